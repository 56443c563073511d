"""Issue 14, ground truth without visible noise: the sampling changes and the optional denoiser.

* The sun sampled on its own (a uniform cone over ``sunsky``'s disk) integrates the disk's
  radiance: its mean weight equals a quadrature of the disk within its Monte Carlo error.
* ``stratified_spp`` gives sample counts Mitsuba's ``multijitter`` sampler takes unchanged.
* ``render.denoise``: its values (YAML's bare on/off booleans included) and its override.
* The glint lobe: a wall facing the sea's sun glint keeps its mean and loses most of its noise.
* The denoiser (skipped without ``pyoidn``): deterministic, keeps a flat image's level, lowers
  the noise of a noisy one, and in a tiny scene render it changes the PNG, not the EXR, and
  ``meta`` says what was done.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from pydantic import ValidationError

from conftest import box_vessel, load_flat_scene, small_spec
from seahaze.render import denoise, passes, physical
from seahaze.render.estimator import DEFAULT_SETTINGS, EstimatorSettings
from seahaze.render.sky import sun_and_sky_dicts
from seahaze.spec import with_overrides

pytestmark = pytest.mark.usefixtures("mitsuba_variant")
needs_oidn = pytest.mark.skipif(not denoise.available(), reason="pyoidn is not installed")


def test_sun_cone_sampling_integrates_the_sun_disk() -> None:
    import drjit as dr
    import mitsuba as mi

    from seahaze.medium import HomogeneousSlab
    from seahaze.render.physical import integrator_classes
    from seahaze.render.sun_disk import SUN_APERTURE_DEG, disk_irradiance, sun_axis

    spec = small_spec(sun={"elevation_deg": 28.0, "azimuth_deg": 150.0})
    sun, sky = (mi.load_dict(d) for d in sun_and_sky_dicts(spec))
    camera_pass, _ = integrator_classes()
    medium = HomogeneousSlab(300.0)
    integrator = camera_pass(sun, sky, medium, 1, True, spec.sea.wind_speed, DEFAULT_SETTINGS)
    n = 200_000
    it = dr.zeros(mi.Interaction3f, n)
    it.p = mi.Point3f(0.0, 0.0, 10.0)
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(3, n)
    _ds, weight = integrator.sample_sun(it, sampler.next_2d(), mi.Bool(True))
    green = np.array(weight[1], dtype=np.float64)
    estimate, stderr = green.mean(), green.std() / np.sqrt(n)
    # Midpoint quadrature of the disk's radiance over a polar grid a little wider than it.
    half = np.radians(0.5 * SUN_APERTURE_DEG)
    n_r, n_phi = 300, 128
    r = (np.arange(n_r) + 0.5) / n_r * half * 1.02
    phi = (np.arange(n_phi) + 0.5) / n_phi * 2.0 * np.pi
    rr, pp = np.meshgrid(r, phi, indexing="ij")
    frame = mi.Frame3f(mi.Vector3f(*(float(c) for c in sun_axis(sun))))
    local = mi.Vector3f(
        mi.Float((np.sin(rr) * np.cos(pp)).ravel()),
        mi.Float((np.sin(rr) * np.sin(pp)).ravel()),
        mi.Float(np.cos(rr).ravel()),
    )
    grid = dr.zeros(mi.DirectionSample3f, rr.size)
    grid.d = frame.to_world(local)
    radiance = np.array(sun.eval_direction(dr.zeros(mi.Interaction3f, rr.size), grid)[1])
    area = np.sin(rr) * (r[1] - r[0]) * (2.0 * np.pi / n_phi)
    quadrature = float(np.sum(radiance.reshape(rr.shape) * area))
    assert quadrature > 0.1
    assert abs(estimate - quadrature) <= 4.0 * stderr + 2e-3 * quadrature, (estimate, quadrature)
    # The irradiance the haze's single scattering uses: the same integral on a stratified grid.
    assert disk_irradiance(sun)[1] == pytest.approx(quadrature, rel=2e-3)
    # Every sample lies in the cone and the disk fills all but a thin rim of it.
    assert np.mean(green > 0.0) > 0.97


def test_stratified_spp_is_what_multijitter_takes() -> None:
    import mitsuba as mi

    assert physical.stratified_spp(32) == 30
    assert [physical.stratified_spp(n) for n in (1, 2, 3, 4, 5, 16, 64, 1024)] == [
        1,
        2,
        3,
        4,
        4,
        16,
        64,
        1024,
    ]
    for spp in range(1, 140):
        n = physical.stratified_spp(spp)
        # The grids a × b are at most ⌊√spp⌋ apart: never more than that is given up.
        assert spp - np.sqrt(spp) <= n <= spp
        sampler = mi.load_dict({"type": "multijitter", "sample_count": n})
        assert sampler.sample_count() == n


def test_render_denoise_values_and_override() -> None:
    assert small_spec().render.denoise == "off"
    assert small_spec(render={"denoise": True}).render.denoise == "on"
    assert small_spec(render={"denoise": False}).render.denoise == "off"
    assert small_spec(render={"denoise": "on"}).render.denoise == "on"
    with pytest.raises(ValidationError):
        small_spec(render={"denoise": "yes please"})
    assert with_overrides(small_spec(), denoise="on").render.denoise == "on"
    assert with_overrides(small_spec(render={"denoise": "on"})).render.denoise == "on"


def _noisy_flat(rng: np.random.Generator) -> tuple[np.ndarray, denoise.FeatureBuffers]:
    """A 64×64 grey wall of radiance 0.5 with 20 % Gaussian noise, and its features."""
    truth = np.full((64, 64, 3), 0.5, np.float32)
    noisy = truth * (1.0 + 0.2 * rng.standard_normal(truth.shape)).astype(np.float32)
    albedo = np.full_like(truth, 0.6)
    normal = np.zeros_like(truth)
    normal[..., 2] = 1.0
    return np.maximum(noisy, 0.0), denoise.FeatureBuffers(albedo, normal)


@needs_oidn
def test_denoiser_is_deterministic_and_keeps_the_level() -> None:
    noisy, features = _noisy_flat(np.random.default_rng(4))
    a = denoise.denoise(noisy, features, exposure=1.2)
    b = denoise.denoise(noisy, features, exposure=1.2)
    assert a.dtype == np.float32 and a.shape == noisy.shape
    np.testing.assert_array_equal(a, b)
    # The mean level survives (within 1 %), the noise drops at least 4-fold.
    assert abs(a.mean() / 0.5 - 1.0) < 0.01, a.mean()
    assert np.std(a - 0.5) < 0.25 * np.std(noisy - 0.5), (np.std(a), np.std(noisy))
    # Black stays black to 1e-4 of the wall's level (the network's output is not exactly 0).
    black = denoise.denoise(np.zeros_like(noisy), features, exposure=1.2)
    assert np.all(black >= 0.0) and black.max() < 5e-5, black.max()


@needs_oidn
def test_denoised_scene_writes_denoised_png_and_undenoised_exr(tmp_path) -> None:
    from seahaze import fileio, imaging
    from seahaze.dataset.layout import Layout
    from seahaze.dataset.writer import write_scene
    from seahaze.render.engine import render_scene
    from seahaze.seeds import dither_seed
    from seahaze.visibility import CLEAN_LEVEL

    spec = small_spec(
        render={"spp": 2, "seed": 3, "denoise": "on"},
        haze={"levels": [1000.0]},
        vessels={"placed": [{"class": "tug", "distance_m": 150.0, "bearing_deg": 0.0}]},
    )
    scene = render_scene(spec, "tiny")
    assert scene.clean_denoised is not None and scene.levels[0].denoised is not None
    assert not np.array_equal(scene.clean_denoised, scene.clean)
    render = scene.meta["render"]
    assert render["denoise"] == "on" and render["spp_used"] == 2
    assert render["denoiser"]["version"] == denoise.library_version()
    layout = Layout(tmp_path)
    write_scene(layout, scene)
    from PIL import Image

    png = np.asarray(Image.open(layout.image(CLEAN_LEVEL, "tiny")).convert("RGB"))
    # The PNG is the denoised image, dithered with the image's seed (render.dither's default).
    dither = dither_seed(3, "tiny", CLEAN_LEVEL)
    np.testing.assert_array_equal(
        png, imaging.to_srgb8(scene.clean_denoised, scene.exposure, dither)
    )
    exr = fileio.read_exr(layout.exr(CLEAN_LEVEL, "tiny"))
    rgb = exr["RGB"] if "RGB" in exr else np.stack([exr[c] for c in "RGB"], axis=-1)
    np.testing.assert_array_equal(rgb, scene.clean)
    meta = json.loads(layout.meta("tiny").read_text())
    assert meta["render"]["denoise"] == "on"
    again = render_scene(spec, "tiny")
    np.testing.assert_array_equal(again.clean_denoised, scene.clean_denoised)
    np.testing.assert_array_equal(again.levels[0].denoised, scene.levels[0].denoised)


def _glint_wall_renders(share: float, seeds: range) -> tuple[list[np.ndarray], np.ndarray]:
    """Clean renders of a wall standing on a flat, nearly smooth sea (α 0.05) and facing the
    sun's mirror image in it (sun 30° high behind the camera), the continuation directions
    drawn toward the glint with probability ``share``; and the wall's pixel mask."""
    spec = small_spec(
        camera={"resolution": [48, 27], "fov_deg": 40.0, "pitch_deg": -4.0},
        sun={"elevation_deg": 30.0, "azimuth_deg": 160.0},
    )
    # The face toward the camera (normal −x) sees the glint: x of the sun's direction < 0.
    wall = box_vessel(0, (120.0, 0.0, 8.0), (10.0, 30.0, 16.0))
    loaded, _ = load_flat_scene(spec, [wall], (), haze_box=False)
    mask = passes.render_geometry(loaded).instance == 0
    settings = EstimatorSettings(glint_share=share)
    renderer = physical.PhysicalRenderer(loaded, spec, settings)
    return [renderer.render([], 0.998, 0.75, 16, seed).clean for seed in seeds], mask


def test_the_glint_lobe_is_unbiased_and_lowers_a_lit_walls_noise() -> None:
    seeds = range(6)
    guided, mask = _glint_wall_renders(DEFAULT_SETTINGS.glint_share, seeds)
    plain, _ = _glint_wall_renders(0.0, seeds)
    assert mask.sum() > 100
    # Unbiased: the wall's mean radiance, over seeds, agrees with BSDF sampling alone. (With
    # the lights' MIS weights taken against the BSDF's density instead of the mixture's, the
    # wall lost part of its sky light: this fails on it.)
    a = np.array([img[mask].mean(axis=0) for img in guided])
    b = np.array([img[mask].mean(axis=0) for img in plain])
    se = np.hypot(a.std(axis=0, ddof=1), b.std(axis=0, ddof=1)) / np.sqrt(len(seeds))
    assert np.all(np.abs(a.mean(axis=0) - b.mean(axis=0)) <= 4.0 * se + 1e-3 * b.mean(axis=0))
    # The glint is a large part of the wall's light and its noise: per-pixel variance over
    # seeds falls by more than half.
    var_guided = np.mean(np.var(np.array([img[mask] for img in guided]), axis=0, ddof=1))
    var_plain = np.mean(np.var(np.array([img[mask] for img in plain]), axis=0, ddof=1))
    assert var_guided < 0.5 * var_plain, (var_guided, var_plain)
