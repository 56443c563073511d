"""Per-pixel transmittance, optical depth and effective visibility (issue #31): the maps and
the vessels' entries against an independent numerical integration of the medium's density
along each pixel's ray, and against Beer–Lambert in a homogeneous slab."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad

from seahaze import fileio
from seahaze.dataset.layout import TRANSMISSION_CHANNELS
from seahaze.medium import NUMPY
from seahaze.render.engine import render_scene
from seahaze.render.transmission import SKY_REACH_M
from seahaze.scene_medium import haze_medium
from seahaze.sceneio import load_scene
from seahaze.spec import with_overrides
from seahaze.visibility import extinction_coefficient

SCENES = Path(__file__).resolve().parents[1] / "scenes"


@pytest.fixture(scope="module")
def fog_render():
    """scenes/fog_layer.yaml (camera at 40 m above a 25 m fog top) at 64×36, 1 spp, asm."""
    spec, name = load_scene(SCENES / "fog_layer.yaml")
    spec = with_overrides(spec, resolution=(64, 36), spp=1, mode="asm", levels=[300.0, 4000.0])
    return spec, render_scene(spec, name)


def _integrated_reduced_length(density, z0: float, dz: float, distance: float) -> float:
    """``∫₀ᵈ ρ(z0 + s·dz) ds`` by adaptive quadrature of the density itself, in height for a
    sloping ray (``ds = dz'/dz``), split at the medium's kinks."""
    rho = lambda z: float(density(np.array([z]), NUMPY)[0])  # noqa: E731
    if abs(dz) < 1e-9:
        return rho(z0) * distance
    z1 = z0 + distance * dz
    lo, hi = min(z0, z1), max(z0, z1)
    value, _ = quad(rho, lo, hi, limit=400, epsabs=1e-10, epsrel=1e-10)
    return value / abs(dz)


@pytest.mark.slow
def test_fog_layer_maps_equal_a_numerical_integration(fog_render):
    spec, scene = fog_render
    geo = scene.geometry
    medium = haze_medium(spec.haze, spec.camera.height_m)
    rng = np.random.default_rng(3)
    rows, cols = rng.integers(0, 36, 60), rng.integers(0, 64, 60)
    pixels = [(int(i), int(j)) for i, j in zip(rows, cols, strict=True)]
    pixels += [(0, 0), (0, 63), (35, 32), (18, 32)]  # the top row is sky, the bottom sea
    assert any(not np.isfinite(geo.distance_m[p]) for p in pixels)
    for level in scene.levels:
        maps = level.transmission
        for p in pixels:
            d = float(geo.distance_m[p]) if np.isfinite(geo.distance_m[p]) else SKY_REACH_M
            ell = _integrated_reduced_length(
                medium.density, float(geo.origin[2]), float(geo.directions[p][2]), d
            )
            tau = level.sigma_rgb * ell
            np.testing.assert_allclose(maps.optical_depth[p], tau, rtol=1e-4, atol=1e-7)
            np.testing.assert_allclose(maps.transmittance[p], np.exp(-tau), rtol=1e-4, atol=1e-30)
            # V_eff = −ln ε · d / τ at the level's nominal extinction.
            sigma = extinction_coefficient(level.visibility_m, spec.haze.threshold)
            v_eff = -np.log(0.02) * d / (sigma * ell)
            assert maps.visibility_eff_m[p] == pytest.approx(v_eff, rel=1e-4)


@pytest.mark.slow
def test_in_the_fog_layer_the_view_sees_farther_upward(fog_render):
    """The camera sits above the fog: rays down into it see less than the level's
    visibility, rays up into the thinner haze more."""
    _, scene = fog_render
    v_eff = scene.levels[0].transmission.visibility_eff_m
    nominal = scene.levels[0].visibility_m
    assert v_eff[0].min() > nominal  # the top row: sky, climbing away from the fog
    assert v_eff[-1].max() < nominal  # the bottom row: the sea under the fog


def test_a_homogeneous_slab_is_beer_lambert(dataset):
    """In the default scene's slab (the camera inside it) every surface pixel's optical depth
    is σ times its distance from the depth file (up to the 20 km reach), so ``V_eff`` is the
    level's visibility; the files hold exactly the documented channels."""
    meta = json.loads((dataset / "meta" / "default.json").read_text())
    depth = fileio.read_exr(dataset / "depth" / "default.exr")["Z"]
    surface = np.isfinite(depth)
    for level in meta["levels"]:
        path = dataset / "transmission" / level["name"] / "default.exr"
        assert fileio.check_exr(path, depth.shape[::-1], set(TRANSMISSION_CHANNELS)) is None
        maps = fileio.read_exr(path)
        sigma = np.asarray(level["sigma_rgb_per_m"])
        reach = np.minimum(depth[surface], SKY_REACH_M)  # the far sea: followed for the reach
        tau = maps["tau"][surface]
        np.testing.assert_allclose(tau, reach[:, None] * sigma, rtol=1e-5, atol=1e-7)
        # T in float32: 0 where exp(−τ) underflows (τ > ~103), the optical depth still exact.
        t = np.exp(-maps["tau"].astype(np.float64)).astype(np.float32)
        np.testing.assert_allclose(maps["T"], t, rtol=1e-5, atol=1e-44)
        assert np.all(maps["T"][maps["tau"] > 104] == 0.0)
        np.testing.assert_allclose(maps["V_eff"][surface], level["visibility_m"], rtol=1e-5)
        assert level["visibility_eff_centre_m"] == pytest.approx(level["visibility_m"], rel=1e-5)
        assert not (dataset / "transmission" / "clean").exists()


@pytest.fixture(scope="module")
def slab_render():
    """scenes/default.yaml (camera inside a homogeneous slab) at 64×36, 1 spp, asm."""
    spec, name = load_scene(SCENES / "default.yaml")
    spec = with_overrides(spec, resolution=(64, 36), spp=1, mode="asm", levels=[300.0, 1000.0])
    return spec, render_scene(spec, name)


def test_vessel_entries_follow_their_pixels_and_centre(slab_render):
    """In the slab each vessel's mean and least transmittance are those of ``exp(−σ d)`` over
    the pixels that show it (``d`` its distance in the geometry pass), and the optical depth
    to its centre is σ times the straight distance from the camera."""
    spec, scene = slab_render
    geo = scene.geometry
    checked = 0
    for level in scene.levels:
        sigma = extinction_coefficient(level.visibility_m, spec.haze.threshold)
        for vessel in scene.meta["vessels"]:
            entry = vessel["levels"][level.name]
            x, y, waterline = vessel["position_m"]
            centre = np.array([x, y, waterline + vessel["air_draft_m"] / 2])
            assert entry["optical_depth_centre"] == pytest.approx(
                sigma * np.linalg.norm(centre - geo.origin), rel=1e-6
            )
            shown = geo.instance == vessel["index"]
            if not shown.any():
                assert entry["transmittance_mean"] is None
                continue
            t = np.exp(-sigma * geo.distance_m[shown].astype(np.float64))
            assert entry["transmittance_mean"] == pytest.approx(t.mean(), rel=1e-5)
            assert entry["transmittance_min"] == pytest.approx(t.min(), rel=1e-5)
            checked += 1
    assert checked >= 4


def test_coco_annotations_carry_each_vessels_optics(dataset):
    """Each COCO annotation of a hazy level holds its vessel's distance, transmittance and
    optical depth from meta (the boxed vessels in index order: the label file's lines)."""
    meta = json.loads((dataset / "meta" / "default.json").read_text())
    boxed = sorted((v for v in meta["vessels"] if v["box_px"]), key=lambda v: v["index"])
    for level in meta["levels"]:
        coco = json.loads((dataset / "coco" / f"{level['name']}.json").read_text())
        annotations = coco["annotations"]
        assert len(annotations) == len(boxed) > 0
        for annotation, vessel in zip(annotations, boxed, strict=True):
            entry = vessel["levels"][level["name"]]
            assert annotation["distance_m"] == vessel["distance_m"]
            for key in ("transmittance_mean", "transmittance_min", "optical_depth_centre"):
                assert annotation[key] == entry[key]
            x0, y0, x1, y1 = vessel["box_px"]
            assert annotation["bbox"] == pytest.approx([x0, y0, x1 - x0, y1 - y0], abs=1e-3)
