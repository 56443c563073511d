"""Render passes against analytic answers: Beer–Lambert on an emitter, distance to a plane,
camera model agreement, labels versus projection, and finite output at extreme visibilities."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import box_vessel, load_flat_scene, small_spec
from seahaze.labels import boxes_from_instances
from seahaze.medium import HomogeneousSlab
from seahaze.render import passes
from seahaze.visibility import extinction_coefficient

pytestmark = pytest.mark.usefixtures("mitsuba_variant")


def test_camera_model_matches_mitsuba_rays():
    spec = small_spec(camera={"pitch_deg": -5.0, "heading_deg": 33.0, "fov_deg": 50.0})
    loaded, camera = load_flat_scene(spec)
    geo = passes.render_geometry(loaded)
    ours = camera.pixel_center_directions()
    assert np.allclose(geo.directions, ours, atol=2e-6)
    assert np.allclose(geo.origin, camera.origin, atol=1e-4)


def test_distance_pass_equals_analytic_distance_to_plane():
    spec = small_spec(camera={"height_m": 20.0, "pitch_deg": -10.0})
    loaded, camera = load_flat_scene(spec)
    geo = passes.render_geometry(loaded)
    dz = geo.directions[..., 2].astype(np.float64)
    below = dz < -1e-3
    expected = camera.height_m / -dz[below]
    assert below.sum() > 0.5 * dz.size
    np.testing.assert_allclose(geo.distance_m[below], expected, rtol=1e-4)
    assert np.all(np.isinf(geo.distance_m[dz > 1e-3]))
    assert np.all(geo.instance == -1)


@pytest.mark.parametrize(
    "sigma", [1.0 / 1500.0, np.array([1.0 / 2000.0, 1.0 / 1500.0, 1.0 / 1000.0])]
)
def test_absorbing_medium_gives_beer_lambert_on_the_sky(sigma):
    # Albedo 0: the sky seen through the layer is the clean sky times exp(-sigma_c L), L the
    # path length inside the layer, per channel (a per-channel sigma is a chromatic medium for
    # volpath). The sun is switched off so the sky is the only emitter.
    spec = small_spec(
        camera={"pitch_deg": 25.0, "resolution": [64, 36]},
        sun={"scale": 0.0},
        haze={"albedo": 0.0, "top_m": 300.0},
    )
    loaded, _ = load_flat_scene(spec, visibilities=(20000.0,))
    geo = passes.render_geometry(loaded)
    clean = passes.render_clean(loaded, 16, 1, 0.0, 0.0)
    hazy = passes.render_reference_level(loaded, sigma, 0.0, 0.0, 256, 1, 0)
    sky = np.isinf(geo.distance_m)
    assert sky.mean() > 0.9
    slab = HomogeneousSlab(300.0)
    length = geo.haze_path_length(slab)[sky]
    t = np.exp(-np.asarray(sigma)[None, ...] * length[:, None]) * np.ones((1, 3))
    assert 0.2 < t.mean() < 0.9
    expected = (clean[sky] * t).sum(axis=0)
    np.testing.assert_allclose(hazy[sky].sum(axis=0), expected, rtol=0.01)
    # The ASM composite with no airlight is the same law, per channel.
    asm = passes.asm_level(clean, geo, sigma, np.zeros(3), slab)
    np.testing.assert_allclose(asm[sky].sum(axis=0), expected, rtol=1e-5)


def test_haze_path_length_cases():
    from seahaze.render.passes import GeometryPass

    d = np.array([[[0.0, 0.6, 0.8], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]]], np.float32)
    dist = np.array([[np.inf, 10.0, np.inf]], np.float32)
    geo = GeometryPass(dist, np.full((1, 3), -1), d, np.array([0.0, 0.0, 10.0]))
    slab = HomogeneousSlab(90.0, bottom=-50.0)
    length = geo.haze_path_length(slab)
    assert length[0, 0] == pytest.approx(80.0 / 0.8)  # up to the top
    assert length[0, 1] == pytest.approx(10.0)  # to the surface
    assert np.isinf(length[0, 2])  # horizontal inside the layer: never leaves
    above = GeometryPass(dist, np.full((1, 3), -1), d, np.array([0.0, 0.0, 150.0]))
    length = above.haze_path_length(slab)
    assert length[0, 0] == 0.0 and length[0, 2] == 0.0


def test_labels_agree_with_projected_box_at_160x90():
    spec = small_spec(camera={"resolution": [160, 90], "pitch_deg": -1.0})
    center, size = (600.0, -40.0, 10.0), (60.0, 14.0, 20.0)
    loaded, camera = load_flat_scene(spec, vessels=[box_vessel(0, center, size)])
    geo = passes.render_geometry(loaded)
    (box,) = boxes_from_instances(geo.instance, [0])
    corners = np.array(
        [
            [
                center[0] + sx * size[0] / 2,
                center[1] + sy * size[1] / 2,
                center[2] + sz * size[2] / 2,
            ]
            for sx in (-1, 1)
            for sy in (-1, 1)
            for sz in (-1, 1)
        ]
    )
    u, v, _ = camera.project(corners)
    projected = np.array([u.min(), v.min(), u.max(), v.max()])
    measured = np.array([box.x0, box.y0, box.x1, box.y1])
    assert np.all(np.abs(measured - projected) <= 1.0), (measured, projected)


@pytest.mark.parametrize("visibility", [50.0, 1.0e5])
@pytest.mark.parametrize("mode", ["reference", "asm"])
def test_extreme_visibilities_give_finite_non_negative_images(visibility, mode):
    spec = small_spec(camera={"resolution": [32, 18]})
    loaded, _ = load_flat_scene(
        spec,
        vessels=[box_vessel(0, (300.0, 0.0, 5.0), (40.0, 10.0, 10.0))],
        visibilities=(visibility,),
    )
    sigma = extinction_coefficient(visibility)
    if mode == "reference":
        image = passes.render_reference_level(loaded, sigma, 0.998, 0.75, 2, 3, 0)
    else:
        geo = passes.render_geometry(loaded)
        clean = passes.render_clean(loaded, 2, 3, 0.998, 0.75)
        air = passes.render_airlight(loaded, sigma, 0.998, 0.75, 64, 3, 0)
        image = passes.asm_level(clean, geo, sigma, air.rgb, HomogeneousSlab(300.0))
    assert np.all(np.isfinite(image)) and np.all(image >= 0.0)
    assert image.mean() > 0.0
