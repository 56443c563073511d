"""The ``reference`` mode's medium for haze that varies across the sea (FieldMedium).

* Its density in the render kernel equals :meth:`NonUniformHaze.density_at` (numpy, float64)
  at random points of the view: patches, a bank, a fog layer and a drifted field.
* Its majorant bounds the density everywhere (delta tracking is unbiased only then) and is
  the field's own bound, not much above the densest point.
* End to end: Mitsuba's ``volpath`` through it, with nothing scattering, gives each sky
  pixel the transmittance of an independent quadrature of the field over the pixel's area,
  within the binomial noise of the estimate.
* And scattering: a field of density ratio 1 is the homogeneous slab, so ``volpath`` through it
  renders what it renders through Mitsuba's own ``homogeneous`` medium (phase function,
  albedo and extinction all taken from the level).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import simpson

from conftest import small_spec
from seahaze.camera import Camera
from seahaze.fog_layer import fog_layer_medium
from seahaze.haze_field import Bank, Drift, HazeField, Patches
from seahaze.medium import HomogeneousSlab
from seahaze.nonuniform import NonUniformHaze

pytestmark = pytest.mark.usefixtures("mitsuba_variant")

SLAB = HomogeneousSlab(top=300.0, albedo=0.998, g=0.75)
FOG = fog_layer_medium(40.0, 10.0, 0.2, 300.0, 12.0, 0.998, 0.85)
PATCHES = Patches(250.0, 3.0, 50.0, 20.0, seed=12345)
BANK = Bank(1000.0, 20.0, 60.0, 0.15, (30.0, -40.0))
MEDIA = {
    "patches": NonUniformHaze(SLAB, HazeField(PATCHES), 0.8),
    "bank": NonUniformHaze(SLAB, HazeField(bank=BANK), 1.3),
    "fog layer, patches and bank, drifted": NonUniformHaze(
        FOG, HazeField(PATCHES, BANK, Drift(6.0, 200.0, 37.0)), 0.9
    ),
}


def _kernel_density(medium: NonUniformHaze, points: np.ndarray) -> np.ndarray:
    import mitsuba as mi

    from seahaze.render.field_medium import FieldMedium

    box = FieldMedium(medium, np.array([-9e3, -9e3, medium.bottom]), np.array([9e3, 9e3, 300]))
    p = mi.Point3f(*(mi.Float(points[:, k].astype(np.float32)) for k in range(3)))
    return np.asarray(box.density(p), np.float64), box.peak


def _points(n: int, reach: float, rng: np.random.Generator) -> np.ndarray:
    return np.stack(
        [
            rng.uniform(-reach, reach, n),
            rng.uniform(-reach, reach, n),
            rng.uniform(-60.0, 300.0, n),
        ],
        axis=1,
    )


@pytest.mark.parametrize("name", list(MEDIA))
def test_the_kernels_density_is_the_fields(name: str) -> None:
    medium = MEDIA[name]
    points = _points(50_000, 8000.0, np.random.default_rng(7))
    want = medium.density_at(points[:, 0], points[:, 1], points[:, 2])
    got, _ = _kernel_density(medium, points)
    # float32 positions: a lattice coordinate of up to ~400 carries 3e-5 of a cell, which
    # the noise's slope (up to ln R per cell) turns into ~1e-4 of the density.
    np.testing.assert_allclose(got, want, rtol=2e-4, atol=1e-7)
    assert want.max() > 2.0 * want.min() or name == "bank"


@pytest.mark.parametrize("name", list(MEDIA))
def test_the_float64_kernels_density_is_numpys(name: str) -> None:
    """The render's medium evaluates its density at points in a drjit kernel
    (``field_quadrature.kernel_density``, what the diffuse ratios' sums read): numpy's, in
    float64, so to rounding, in the shape of its points."""
    from seahaze.render.field_quadrature import with_kernel_quadrature

    medium = MEDIA[name]
    kernel = with_kernel_quadrature(medium)
    assert kernel.point_density is not None and medium.point_density is None
    points = _points(50_000, 8000.0, np.random.default_rng(9)).reshape(250, 200, 3)
    want = medium.density_at(points[..., 0], points[..., 1], points[..., 2])
    got = kernel.density_at(points[..., 0], points[..., 1], points[..., 2])
    assert got.shape == want.shape
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-15)
    assert np.ptp(want) > 0.5


@pytest.mark.parametrize("name", list(MEDIA))
def test_the_majorant_bounds_the_density_closely(name: str) -> None:
    medium = MEDIA[name]
    points = _points(400_000, 8000.0, np.random.default_rng(11))
    density = medium.density_at(points[:, 0], points[:, 1], points[:, 2])
    _, peak = _kernel_density(medium, points[:8])
    assert density.max() < peak
    # The bound is reached where the noise is extreme; fractal noise rarely is, so the
    # densest of 400,000 points lies within a factor 2 of it, not far below.
    assert density.max() > 0.5 * peak


@pytest.mark.slow
def test_volpath_through_the_field_gives_each_pixel_its_transmittance() -> None:
    # The sky through patchy haze with nothing scattering (albedo 0): a pixel's level over
    # its clean value is the transmittance of its rays through the field (the sky is an
    # emitter at infinity; volpath's delta tracking is unbiased), which an independent
    # quadrature gives: Simpson's rule along 4 x 4 rays spread over the pixel (the film's box
    # filter). The camera looks up so that the rays leave through the haze top inside the box.
    from seahaze.render.engine import render_scene
    from seahaze.scene_medium import scene_haze_medium
    from seahaze.world import frame_camera

    spp = 256
    spec = small_spec(
        camera={"resolution": [24, 14], "pitch_deg": 24.0, "fov_deg": 40.0, "height_m": 12.0},
        haze={
            "levels": [2000.0],
            "albedo": 0.0,
            "patches": {
                "correlation_m": 300,
                "anisotropy": 2,
                "vertical_m": 40,
                "density_ratio": 20,
            },
        },
        render={"mode": "reference", "spp": spp, "seed": 5},
    )
    scene = render_scene(spec, "field_transmittance")
    (level,) = scene.levels
    camera = frame_camera(spec, None)
    medium = scene_haze_medium(spec, camera)
    sigma = 3.912 / 2000.0
    measured = level.radiance[..., 1].astype(np.float64) / scene.clean[..., 1]
    want = _pixel_transmittance(camera, medium, sigma, sub=4)
    sky = ~np.isfinite(scene.geometry.distance_m)
    assert sky.sum() > 0.8 * sky.size
    se = np.sqrt(want * (1.0 - want) / spp)
    z = (measured - want)[sky] / se[sky]
    # Per pixel: the binomial noise of spp escapes (a few pixels beyond 4 se of 300+).
    assert np.mean(np.abs(z) > 4.0) < 0.01, z
    # Over the image: the mean error within 4 standard errors of a mean of the pixels.
    assert abs(z.mean()) * np.sqrt(z.size) < 4.0, z.mean()
    # Not a uniform haze: the pixels' optical depths differ by more than the noise.
    tau = -np.log(want[sky])
    assert tau.max() > 1.5 * tau.min()


def _pixel_transmittance(camera: Camera, medium, sigma: float, sub: int) -> np.ndarray:
    """The mean over ``sub``² rays spread over each pixel of ``exp(−σ ∫ρ ds)`` from the
    camera to the haze top, by Simpson's rule on 2000 steps (under a metre)."""
    v, u = np.mgrid[0 : camera.height, 0 : camera.width]
    offsets = (np.arange(sub) + 0.5) / sub
    out = np.zeros(u.shape)
    origin = camera.origin
    for oy in offsets:
        for ox in offsets:
            d = camera.ray_directions(u + ox, v + oy).reshape(-1, 3)
            end = (medium.top_m - origin[2]) / d[:, 2]
            s = np.linspace(0.0, 1.0, 2001)[None, :] * end[:, None]
            p = origin + s[..., None] * d[:, None, :]
            rho = medium.density_at(p[..., 0], p[..., 1], p[..., 2])
            length = simpson(rho, x=s, axis=1)
            out += np.exp(-sigma * length).reshape(u.shape)
    return out / sub**2


@pytest.mark.slow
def test_a_uniform_field_scatters_as_the_homogeneous_medium() -> None:
    # Patches of density ratio 1 modulate by exp(0) = 1: the same haze as the plain slab, but
    # rendered through FieldMedium. Sky and sea means agree within their noise;
    # when the medium's phase function was a Python override that volpath never called, it
    # scattered isotropically: 42 % darker at 300 m, 5-14 % off and redder at 1000 m.
    from seahaze.render.engine import render_scene

    flat = {"correlation_m": 300, "anisotropy": 2, "vertical_m": 40, "density_ratio": 1.0}
    images = {}
    for name, extra in (("slab", {}), ("field", {"patches": flat})):
        spec = small_spec(
            camera={"resolution": [32, 18], "pitch_deg": 2.0, "height_m": 15.0},
            haze={"levels": [300.0, 1000.0], **extra},
            render={"mode": "reference", "spp": 512, "seed": 5},
        )
        scene = render_scene(spec, "field_scattering")
        assert scene.meta["haze"]["medium"]["kind"] == (
            "NonUniformHaze" if extra else "HomogeneousSlab"
        )
        images[name] = [lv.radiance.astype(np.float64).mean(axis=-1) for lv in scene.levels]
    sky = ~np.isfinite(scene.geometry.distance_m)
    assert 0.2 < sky.mean() < 0.8
    for slab, field in zip(images["slab"], images["field"], strict=True):
        for region in (sky, ~sky):
            # Two renders of the same image: per pixel the difference is noise alone (the
            # image's structure cancels), so its scatter gives the mean's standard error.
            diff = (field - slab)[region]
            se = diff.std(ddof=1) / np.sqrt(diff.size)
            # (Standard errors here 1.6-2.7 % of the mean: the sun's glint on the sea.)
            assert abs(diff.mean()) < 4.0 * se + 0.01 * slab[region].mean(), (diff.mean(), se)


def test_the_levels_phase_function_is_the_one_volpath_reads() -> None:
    # volpath reads the medium's phase function through the C++ base class, not a Python
    # override: the level's g must reach that object (test above for its effect).
    import mitsuba as mi

    from seahaze.render.field_medium import FieldMedium

    medium = MEDIA["patches"]
    box = FieldMedium(medium, np.array([-9e3, -9e3, -60.0]), np.array([9e3, 9e3, 300.0]))
    phase = box.phase_function()
    assert "HGPhaseFunction" in str(phase) and f"{medium.g}" in str(phase)
    params = mi.traverse(box)
    for name, value in medium.mitsuba_level(np.array([1e-3, 2e-3, 3e-3]), 0.9, 0.85).items():
        params[name] = value
    params.update()
    assert "0.85" in str(box.phase_function())
    assert np.allclose(np.asarray(box.sigma_t).ravel(), [1e-3, 2e-3, 3e-3])
    assert np.allclose(np.asarray(box.albedo), 0.9)
