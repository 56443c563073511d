"""Whitecaps: the coverage law, the foam reflectance, and a foam field that covers the law's
fraction of the world area at the breaking crests."""

from __future__ import annotations

import math
import warnings
from dataclasses import replace

import numpy as np
import pytest

from seahaze.ocean import FlatSurface, OceanParams, OceanSurface, make_surface
from seahaze.ocean.base import invert_horizontal_displacement
from seahaze.ocean.whitecaps import (
    COUNTED_FOAM_REFLECTANCE,
    FOAM_AGE_DECAY,
    FOAM_REFLECTANCE,
    FRESH_FOAM_REFLECTANCE,
    RESIDUAL_FOAM_WIDTH,
    FoamField,
    foam_fraction,
    whitecap_albedo,
    whitecap_coverage,
)


def _surface(model: str, u10: float, **kw: object) -> OceanSurface:
    params = replace(OceanParams(model=model, wind_speed=u10, fetch_km=200.0, seed=3), **kw)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return make_surface(params)


def test_coverage_follows_monahan_and_omuircheartaigh() -> None:
    """W = 3.84e-6 U10^3.41 (Monahan & O'Muircheartaigh 1980): about 1 % at 10 m/s and 4 % at
    15 m/s."""
    assert whitecap_coverage(10.0) == pytest.approx(0.00987, rel=2e-3)
    assert whitecap_coverage(15.0) == pytest.approx(0.0394, rel=2e-3)
    winds = np.array([3.0, 5.0, 8.0, 12.0, 20.0])
    np.testing.assert_allclose(whitecap_coverage(winds), 3.84e-6 * winds**3.41, rtol=1e-12)
    # Doubling the wind multiplies the coverage by 2^3.41 = 10.6.
    assert whitecap_coverage(16.0) / whitecap_coverage(8.0) == pytest.approx(2.0**3.41)
    assert whitecap_coverage(0.0) == 0.0
    assert whitecap_coverage(-3.0) == 0.0
    assert whitecap_coverage(60.0) == 1.0  # clipped far outside the fitted range


def test_foam_reflectance_is_koepke_effective_value() -> None:
    """Koepke (1984): effective whitecap reflectance 0.22 in the visible, from fresh foam of
    0.55 (Whitlock et al. 1982) times an efficiency factor of about 0.4."""
    assert pytest.approx(0.22) == FOAM_REFLECTANCE
    assert pytest.approx(0.55) == FRESH_FOAM_REFLECTANCE
    assert pytest.approx(0.4) == FOAM_REFLECTANCE / FRESH_FOAM_REFLECTANCE
    assert whitecap_albedo(10.0) == pytest.approx(0.22 * 3.84e-6 * 10.0**3.41)


@pytest.mark.parametrize("model", ["fft", "gerstner"])
@pytest.mark.parametrize("u10", [8.0, 12.0, 15.0])
def test_foam_covers_the_law_fraction_of_the_world_area(model: str, u10: float) -> None:
    """Foam fraction averaged over uniformly spread world points (rest positions found by
    inverting the choppy map), at another place and time than the calibration: within a
    factor of 2 of W(U10) (measured: 0.86-1.1 x); the whole foam alone is W, the residual foam
    around it adds its ramp's mean, ``W·RESIDUAL_FOAM_WIDTH/2``."""
    surface = _surface(model, u10, time_s=23.0)
    foam = FoamField(surface, u10)
    side = 20.0 * surface.peak_wavelength_m
    x, y = np.random.default_rng(5).uniform(3000.0, 3000.0 + side, (2, 60_000))
    x0, y0 = invert_horizontal_displacement(surface, x, y)
    fraction = foam(x0, y0)
    law = whitecap_coverage(u10)
    assert law / 2.0 < float(np.mean(fraction)) < 2.0 * law
    assert law / 2.0 < float(np.mean(fraction > 0.5)) < 2.0 * law
    assert foam.mean_fraction == pytest.approx(law * (1.0 + 0.5 * RESIDUAL_FOAM_WIDTH))
    assert float(np.mean(fraction)) == pytest.approx(foam.mean_fraction, rel=0.1)


@pytest.mark.parametrize("model", ["fft", "gerstner"])
def test_foam_sits_where_the_surface_breaks(model: str) -> None:
    """Foam marks the compressed crests: low Jacobian and high elevation."""
    surface = _surface(model, 15.0)
    foam = FoamField(surface, 15.0)
    x, y = np.random.default_rng(1).uniform(0.0, 10.0 * surface.peak_wavelength_m, (2, 50_000))
    f = foam(x, y)
    jac = foam.breaking_jacobian(x, y)
    height = surface.displacement(x, y)[2]
    assert np.all(jac[f > 0.5] < foam.jacobian_threshold + 1e-9)
    assert np.all(jac[f == 0.0] >= foam.jacobian_threshold)
    assert np.average(height, weights=f) > 1.0 * np.std(height)  # on the crests
    assert np.mean(jac[f > 0.5]) < np.mean(jac) - 0.1


def test_foam_is_bounded_soft_edged_and_deterministic() -> None:
    surface = _surface("fft", 12.0)
    x, y = np.random.default_rng(2).uniform(-500.0, 500.0, (2, 40_000))
    a = FoamField(surface, 12.0)(x, y)
    assert a.min() >= 0.0 and a.max() <= 1.0
    partial = np.mean((a > 0.02) & (a < 0.98))
    assert 0.1 * np.mean(a) < partial  # edges ramp, the field is not a binary mask
    b = FoamField(_surface("fft", 12.0), 12.0)(x, y)
    assert a.tobytes() == b.tobytes()
    c = FoamField(_surface("fft", 12.0, seed=4), 12.0)(x, y)
    assert not np.array_equal(a, c)
    np.testing.assert_array_equal(foam_fraction(surface, x[:10], y[:10], 12.0), a[:10])
    # Along a fine line the foam albedo the image shows changes gradually: no step of 1 cm is
    # as large as the counted whitecap's edge (0.059), which a hard edge would jump by (the
    # residual foam's ramp carries the field from there to 0; measured 0.034).
    line = np.linspace(0.0, 200.0, 20_001)
    fraction, reflectance = FoamField(surface, 12.0).foam_and_reflectance(line, 0.0 * line)
    assert np.max(np.abs(np.diff(fraction * reflectance))) < 0.05


def test_zero_choppiness_still_places_foam_on_crests() -> None:
    surface = _surface("fft", 15.0, choppiness=0.0)
    foam = FoamField(surface, 15.0)
    x, y = np.random.default_rng(3).uniform(0.0, 2000.0, (2, 80_000))
    f = foam(x, y)
    # No horizontal displacement: rest area = world area.
    assert np.mean(f) == pytest.approx(foam.mean_fraction, rel=0.3)
    assert np.mean(f >= 1.0) == pytest.approx(whitecap_coverage(15.0), rel=0.3)
    height = surface.displacement(x, y)[2]
    assert np.average(height, weights=f) > np.std(height)


def test_flat_sea_and_calm_wind_have_no_foam() -> None:
    x = np.linspace(0.0, 100.0, 11)
    flat = FoamField(FlatSurface(), 12.0)
    np.testing.assert_array_equal(flat(x, x), 0.0)
    assert flat.mean_fraction == pytest.approx(whitecap_coverage(12.0) * 1.25)
    calm = FoamField(_surface("fft", 6.0), 0.0)
    np.testing.assert_array_equal(calm(x, x), 0.0)
    assert math.isinf(calm.jacobian_threshold)


def test_sea_mesh_carries_per_vertex_foam() -> None:
    """``build_sea_mesh_data(..., foam=...)`` adds a foam fraction per vertex without moving a
    vertex; far from the camera, where a vertex's cell holds several whitecaps or none, it is
    their local coverage: it varies from cell to cell and its area mean is the law's;
    ``build_sea_mesh`` is unchanged."""
    from seahaze.ocean import build_sea_mesh, build_sea_mesh_data

    surface = _surface("fft", 15.0)
    foam = FoamField(surface, 15.0)
    plain = build_sea_mesh_data(surface, camera_height_m=10.0, quality="low")
    assert plain.foam is None
    mesh = build_sea_mesh_data(surface, camera_height_m=10.0, quality="low", foam=foam)
    np.testing.assert_array_equal(mesh.vertices, plain.vertices)
    vertices, faces = build_sea_mesh(surface, camera_height_m=10.0, quality="low")
    np.testing.assert_array_equal(faces, plain.faces)
    np.testing.assert_array_equal(vertices, plain.vertices)
    assert mesh.foam is not None and mesh.foam.shape == (len(mesh.vertices),)
    assert mesh.foam.dtype == np.float32
    assert mesh.foam.min() >= 0.0 and mesh.foam.max() <= 1.0
    r = np.hypot(mesh.vertices[:, 0], mesh.vertices[:, 1])
    radii = mesh.ring_radii_m
    padded = np.append(radii, 2 * radii[-1] - radii[-2])
    cell = 0.5 * (padded[2:] - padded[:-2]) * radii[1:] * 2 * np.pi / mesh.n_theta
    area = np.concatenate([[0.0], np.repeat(cell, mesh.n_theta)])
    far = r > mesh.fade_end_m
    far_mean = np.sum(mesh.foam[far] * area[far]) / np.sum(area[far])
    # The foam as a share of fresh foam (module docstring, *Rendering*): the field's albedo.
    share = foam.albedo / FRESH_FOAM_REFLECTANCE
    assert far_mean == pytest.approx(share, rel=0.25)
    assert mesh.foam[far].std() > 0.2 * share  # cells with whitecaps, without
    near = r < 0.5 * mesh.fade_start_m
    assert mesh.foam[near].max() > 0.9  # resolved fresh whitecaps near the camera
    # Vertices whose foam albedo reaches half of Koepke's R_eff: a part of the counted W.
    bright = mesh.foam[near] * FRESH_FOAM_REFLECTANCE > 0.5 * FOAM_REFLECTANCE
    assert 0.3 * whitecap_coverage(15.0) < np.mean(bright) < whitecap_coverage(15.0)


def test_koepke_decay_makes_the_counted_whitecaps_effective_reflectance() -> None:
    """Koepke (1984): fresh foam (0.55) decaying exponentially over a whitecap's counted life
    reflects 0.4 of its fresh value on average, ``(1 - e^-k)/k = 0.4``; the life ends about a
    factor 10 below fresh foam (his 0.55 to about 0.055). Checked by an independent
    quadrature."""
    from scipy.integrate import quad

    mean = quad(lambda u: math.exp(-FOAM_AGE_DECAY * u), 0.0, 1.0)[0]
    assert FRESH_FOAM_REFLECTANCE * mean == pytest.approx(FOAM_REFLECTANCE, abs=1e-9)
    assert pytest.approx(0.55 * math.exp(-FOAM_AGE_DECAY)) == COUNTED_FOAM_REFLECTANCE
    assert 8.0 < FRESH_FOAM_REFLECTANCE / COUNTED_FOAM_REFLECTANCE < 10.5
    assert 0.052 < COUNTED_FOAM_REFLECTANCE < 0.065


@pytest.mark.parametrize(("model", "u10"), [("fft", 8.0), ("fft", 15.0), ("gerstner", 12.0)])
def test_the_photographed_whitecaps_are_the_law_and_reflect_koepke(model: str, u10: float) -> None:
    """Monahan's W is photographed coverage: the area brighter than a threshold. The area whose
    foam albedo (fraction × reflectance) reaches Koepke's faintest counted whitecap is exactly
    the whole foam (fraction 1), it covers W of the world (measured 0.90-1.03 W on independent
    points), its mean reflectance is Koepke's 0.22 and it starts at fresh foam on the most
    compressed crest. The residual foam beyond (fraction below 1) is all fainter than the
    threshold, so no photograph counts it."""
    surface = _surface(model, u10, time_s=23.0)
    foam = FoamField(surface, u10)
    side = 20.0 * surface.peak_wavelength_m
    x, y = np.random.default_rng(5).uniform(3000.0, 3000.0 + side, (2, 60_000))
    x0, y0 = invert_horizontal_displacement(surface, x, y)
    fraction, reflectance = foam.foam_and_reflectance(x0, y0)
    np.testing.assert_array_equal(fraction, foam(x0, y0))
    albedo = fraction * reflectance
    counted = albedo >= COUNTED_FOAM_REFLECTANCE * (1.0 - 1e-9)
    whole = fraction >= 1.0
    np.testing.assert_array_equal(counted, whole)
    law = whitecap_coverage(u10)
    assert 0.8 * law < float(np.mean(counted)) < 1.25 * law
    assert float(np.mean(reflectance[counted])) == pytest.approx(FOAM_REFLECTANCE, rel=0.06)
    assert reflectance.max() <= FRESH_FOAM_REFLECTANCE
    assert reflectance[np.argmin(foam.breaking_jacobian(x0, y0))] > 0.5  # the freshest crest
    residual = (fraction > 0.0) & ~whole
    assert np.any(residual)
    assert albedo[residual].max() < COUNTED_FOAM_REFLECTANCE * (1.0 + 1e-9)
    bright = np.sum(fraction[reflectance > 0.4]) / np.sum(fraction)
    assert 0.05 < bright < 0.3  # white cores, grey skirts


@pytest.mark.parametrize("u10", [8.0, 15.0])
def test_far_field_means_are_the_field_means(u10: float) -> None:
    """What the renderer gives the sea it does not resolve (``mean_fraction``, ``albedo``,
    ``mean_reflectance``) is the field's own world-area mean over independent points (measured
    0.91-0.97 of the fraction and 0.84-0.97 of the albedo), so near and far sea agree; the
    counted whitecaps' share of that albedo is Koepke's ``W·R_eff`` (``whitecap_albedo``), the
    residual foam's a few per cent."""
    surface = _surface("fft", u10, time_s=23.0)
    foam = FoamField(surface, u10)
    side = 20.0 * surface.peak_wavelength_m
    x, y = np.random.default_rng(7).uniform(-4000.0, -4000.0 + side, (2, 60_000))
    x0, y0 = invert_horizontal_displacement(surface, x, y)
    fraction, reflectance = foam.foam_and_reflectance(x0, y0)
    assert float(np.mean(fraction)) == pytest.approx(foam.mean_fraction, rel=0.1)
    assert float(np.mean(fraction * reflectance)) == pytest.approx(foam.albedo, rel=0.2)
    assert foam.mean_reflectance == pytest.approx(foam.albedo / foam.mean_fraction)
    assert 1.0 < foam.albedo / whitecap_albedo(u10) < 1.1


def test_sea_mesh_draws_foam_as_a_share_of_fresh_foam() -> None:
    """Per vertex the field's foam albedo (fraction × reflectance) is kept and drawn as a share
    of fresh foam, ``albedo / 0.55``, the water between: fresh and whole on the resolved
    crests, a small share on the faint residual foam, the field's mean albedo in the far field
    and the sea's mean foam albedo W·R_eff near the camera."""
    from seahaze.ocean import build_sea_mesh_data

    surface = _surface("fft", 15.0)
    foam = FoamField(surface, 15.0)
    mesh = build_sea_mesh_data(surface, camera_height_m=10.0, quality="low", foam=foam)
    assert mesh.foam is not None and mesh.foam_reflectance is not None
    assert mesh.foam_reflectance.dtype == np.float32
    assert np.all(mesh.foam_reflectance == np.float32(FRESH_FOAM_REFLECTANCE))
    r = np.hypot(mesh.vertices[:, 0], mesh.vertices[:, 1])
    far = r > mesh.fade_end_m
    assert float(np.mean(mesh.foam[far])) * FRESH_FOAM_REFLECTANCE == pytest.approx(
        foam.albedo, rel=0.2
    )
    near = r < 0.5 * mesh.fade_start_m
    albedo = mesh.foam[near] * FRESH_FOAM_REFLECTANCE
    assert float(np.mean(albedo)) == pytest.approx(whitecap_albedo(15.0), rel=0.5)
    # The faint foam (albedo below Koepke's faintest counted whitecap) covers at most a tenth.
    faint = (albedo > 0.0) & (albedo < COUNTED_FOAM_REFLECTANCE)
    assert np.any(faint) and mesh.foam[near][faint].max() < 0.11
