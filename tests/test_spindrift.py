"""A gale's spindrift (seahaze.ocean.spindrift, issue #32: spray at force 8).

* Its opacity follows the Beaufort bounds: none below force 8, full from force 9.
* Its source is the young half of the whitecaps' counted area: its world-area mean is
  ``W·Y/2``, by a quadrature of the field weighted by the surface's Jacobian.
* The veil it spreads keeps that mean (the same quadrature) and lies downwind of its crests.
* The sea mesh and the plane model of the sea take it at force 8 and are untouched below.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from seahaze import ocean
from seahaze.ocean.spindrift import (
    FULL_M_S,
    MOST_OPACITY,
    ONSET_M_S,
    REACH_TRAILS,
    SPRAY_REFLECTANCE,
    TAP_SPACING_M,
    TAP_WEIGHTS,
    TRAIL_M,
    YOUNG_SHARE,
    Spindrift,
    mean_source,
    spindrift_opacity,
)
from seahaze.ocean.whitecaps import layer_over


@pytest.fixture(scope="module")
def gale():
    """A force-8 FFT sea, its whitecaps and their spindrift blowing toward 30°."""
    params = ocean.ocean_params_for_beaufort(8, seed=3)
    surface = ocean.make_surface(params)
    foam = ocean.FoamField(surface, params.wind_speed)
    return surface, foam, Spindrift(foam, 30.0)


def _world_mean(surface, values_of) -> float:
    """World-area mean of a field over 8 × 8 peak wavelengths of ``surface`` (the largest
    patch; a 512 × 512 grid of rest positions, 3 m apart, each standing for ``J`` of the world:
    the whitecaps' own weighting)."""
    side = 8.0 * surface.peak_wavelength_m
    nodes = (np.arange(512) + 0.5) * (side / 512)
    x, y = (a.ravel() for a in np.meshgrid(nodes, nodes))
    jacobian = surface.jacobian(x, y)
    return float(np.sum(values_of(x, y) * jacobian) / np.sum(jacobian))


def test_the_opacity_follows_the_beaufort_bounds():
    assert spindrift_opacity(ONSET_M_S) == 0.0 and spindrift_opacity(15.5) == 0.0
    assert spindrift_opacity(0.5 * (ONSET_M_S + FULL_M_S)) == pytest.approx(0.5 * MOST_OPACITY)
    assert spindrift_opacity(FULL_M_S) == pytest.approx(MOST_OPACITY)
    assert spindrift_opacity(32.0) == pytest.approx(MOST_OPACITY)
    # WMO: force 8 is 17.2-20.7 m/s, force 9 from 20.8 m/s.
    assert (ONSET_M_S, FULL_M_S) == (17.2, 20.8)


def test_the_source_is_the_young_half_of_the_whitecaps(gale):
    surface, foam, spindrift = gale
    want = mean_source(foam.coverage)
    assert want == pytest.approx(foam.coverage * YOUNG_SHARE / 2.0)
    got = _world_mean(surface, spindrift.source)
    # The field's quantile table is itself a sample of the surface: 0.94-0.97 of W·Y/2 measured
    # with this grid and with random points.
    assert got == pytest.approx(want, rel=0.08)


def test_the_veil_keeps_the_sources_mean(gale):
    surface, foam, spindrift = gale
    assert spindrift.mean_veil == pytest.approx(
        spindrift.opacity * mean_source(foam.coverage) * TAP_WEIGHTS.sum()
    )
    # The taps' weights sum as the geometric series of the exponential's midpoint samples.
    step = TAP_SPACING_M / TRAIL_M
    series = step * math.exp(-step / 2) * (1.0 - math.exp(-REACH_TRAILS)) / (1.0 - math.exp(-step))
    assert TAP_WEIGHTS.sum() == pytest.approx(series, rel=1e-12)
    assert _world_mean(surface, spindrift.veil) == pytest.approx(spindrift.mean_veil, rel=0.05)


def test_the_veil_lies_downwind_of_its_crests(gale):
    surface, foam, spindrift = gale
    side = 8.0 * surface.peak_wavelength_m
    x, y = np.random.default_rng(5).uniform(0.0, side, (2, 200_000))
    crest = spindrift.source(x, y) > 0.5
    assert crest.sum() > 200
    x, y = x[crest], y[crest]
    for toward in (30.0, 210.0):
        veil = Spindrift(foam, toward)
        ux, uy = math.cos(math.radians(toward)), math.sin(math.radians(toward))
        downwind = veil.veil(x + 3.0 * ux, y + 3.0 * uy).mean()
        upwind = veil.veil(x - 3.0 * ux, y - 3.0 * uy).mean()
        # 3 m behind a crest its own spray, thinned by e^-0.75; 3 m before it, only the spray
        # of the crest's own upwind part (a gale's whitecaps are metres long) and of others.
        assert downwind > 1.5 * upwind
        assert downwind > 0.3 * veil.opacity


def test_a_veil_hides_what_it_covers():
    fraction, albedo = layer_over(
        np.array([0.0, 0.5, 1.0]), np.array([0.0, 0.1, 0.55]), 0.4, SPRAY_REFLECTANCE
    )
    # The surface shows through 1 - v, the veil reflects v·R_s on top.
    assert np.allclose(fraction, [0.4, 0.7, 1.0])
    assert np.allclose(albedo, [0.4 * SPRAY_REFLECTANCE, 0.06 + 0.4 * SPRAY_REFLECTANCE, 0.55])


@pytest.mark.parametrize("force", [7, 8])
def test_the_sea_takes_spindrift_from_force_8(force):
    from conftest import small_spec
    from seahaze.camera import Camera
    from seahaze.world import build_sea, sea_whitecaps

    spec = small_spec(sea={"beaufort": force, "quality": "low", "seed": 3})
    camera = Camera.from_spec(spec.camera)
    sea = build_sea(spec, camera)
    foam = sea_whitecaps(spec, sea.surface)
    spindrift = Spindrift(foam, spec.sea.direction_deg)
    assert spindrift.present == (force == 8)
    # The plane model of the sea: the whitecaps' mean albedo seen through the veil's mean,
    # drawn as a share of fresh foam.
    albedo = layer_over(foam.mean_fraction, foam.albedo, spindrift.mean_veil, SPRAY_REFLECTANCE)[1]
    assert sea.foam_reflectance == ocean.FRESH_FOAM_REFLECTANCE
    assert sea.foam_coverage * sea.foam_reflectance == pytest.approx(albedo, rel=1e-12)
    if force == 7:  # no spindrift: the whitecaps' own albedo, to the bit
        assert sea.foam_coverage == foam.albedo / ocean.FRESH_FOAM_REFLECTANCE
    # The mesh: the same sea with and without the veil (force 7: the same bytes).
    common = {
        "camera_xy": (camera.x_m, camera.y_m),
        "camera_height_m": camera.height_m,
        "quality": "low",
        "foam": foam,
        "view": (math.radians(camera.heading_deg), camera.view_azimuth_half_width()),
    }
    veiled = ocean.build_sea_mesh_data(sea.surface, spindrift=spindrift, **common).foam
    bare = ocean.build_sea_mesh_data(sea.surface, **common).foam
    assert np.array_equal(veiled, sea.mesh.attributes["foam"])
    if force == 7:
        assert np.array_equal(veiled, bare)
        return
    # The veil only adds: every vertex at least as foamy, many more so.
    assert np.all(veiled >= bare - 1e-6) and np.mean(veiled > bare + 0.01) > 0.005
