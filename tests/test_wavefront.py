"""seahaze's render loop against Mitsuba's: the same images to the rounding of the pixels' sums,
the AOVs in Mitsuba's order, and one compiled kernel for every small image size and for the sizes
of one octave of pixels above them."""

from __future__ import annotations

import gc

import numpy as np
import pytest

from conftest import box_vessel, load_flat_scene, small_spec
from seahaze.render.wavefront import pixel_sum_capacity, render_film

pytestmark = pytest.mark.usefixtures("mitsuba_variant")

VESSEL = box_vessel(0, (300.0, 0.0, 4.0), (40.0, 8.0, 8.0))


def _scene(resolution: tuple[int, int], haze_box: bool):
    spec = small_spec(camera={"resolution": list(resolution), "pitch_deg": -2.0})
    loaded, _ = load_flat_scene(spec, vessels=[VESSEL], haze_box=haze_box)
    return loaded.scene


@pytest.mark.parametrize("spp", [3, 4])
@pytest.mark.parametrize("haze_box", [True, False], ids=["volpath-independent", "multijitter"])
def test_render_film_equals_mitsuba_render(spp, haze_box):
    # The same samples, the same rays: equal to the rounding of the pixels' sums, whose order
    # of additions Mitsuba's film chooses by its own rules (one ulp of a pixel's value).
    import mitsuba as mi

    scene = _scene((64, 36), haze_box)
    sensor, integrator = scene.sensors()[0], scene.integrator()
    ours = render_film(scene, sensor, integrator, spp, 7)
    theirs = np.array(mi.render(scene, spp=spp, seed=7), dtype=np.float32)
    assert ours.shape == theirs.shape == (36, 64, 3)
    assert ours.mean() > 0.0
    np.testing.assert_allclose(ours, theirs, rtol=4e-7, atol=1e-12)


def test_render_film_keeps_the_integrators_aovs_in_mitsubas_order():
    import drjit as dr
    import mitsuba as mi

    class RayAOVs(mi.SamplingIntegrator):
        """Radiance 1 on a hit; AOVs: the ray's height component and the hit's distance."""

        def sample(self, scene, sampler, ray, medium=None, active=True):
            si = scene.ray_intersect(mi.Ray3f(ray))
            hit = si.is_valid()
            jitter = sampler.next_1d()  # a per-sample value, so the mean is a real mean
            value = dr.select(hit, 1.0, 0.0) + 0.0 * jitter
            return mi.Spectrum(value), mi.Bool(True), [ray.d.z, dr.select(hit, si.t, 0.0)]

        def aov_names(self):
            return ["dz", "t"]

    scene = _scene((64, 36), False)
    integrator = RayAOVs(mi.Properties())
    ours = render_film(scene, scene.sensors()[0], integrator, 4, 3)
    theirs = np.array(mi.render(scene, spp=4, seed=3, integrator=integrator), dtype=np.float32)
    assert ours.shape == theirs.shape == (36, 64, 5)
    np.testing.assert_allclose(ours, theirs, rtol=4e-7, atol=1e-12)
    # Looking 2 degrees down: rays rise at the top of the film and fall at the bottom, where
    # they meet the flat sea (z = 0) at the camera's height over their downward slope.
    assert ours[0, :, 3].min() > 0.0 > ours[-1, :, 3].max()
    height_m = small_spec().camera.height_m
    np.testing.assert_allclose(ours[-1, :, 4], height_m / -ours[-1, :, 3], rtol=0.01)


def _large_kernels(size: tuple[int, int]) -> set[str]:
    """The hashes of the kernels of more than 1,000 operations that a render at ``size``
    launched. The scene is freed before returning: Mitsuba numbers the live plugins the
    kernels call into, and those numbers are in the kernels too."""
    import drjit as dr

    scene = _scene(size, False)
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        dr.kernel_history()  # empties it
        render_film(scene, scene.sensors()[0], scene.integrator(), 4, 1)
        return {str(k["hash"]) for k in dr.kernel_history() if k.get("operation_count", 0) > 1000}
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
        del scene
        gc.collect()


def test_small_image_sizes_share_the_compiled_kernel():
    # 64×36 = 2304 and 200×100 = 20,000 pixels: two octaves apart, both under the smallest
    # capacity of the sums. The kernels' hashes are their source's, so the test holds whether
    # or not the cache already had them.
    first, second = _large_kernels((64, 36)), _large_kernels((200, 100))
    assert first, "the render launched no large kernel"
    assert first == second


def test_the_pixel_sums_hold_every_pixel_in_one_length_per_octave():
    # The length is the kernel's one size: every small image gets the smallest, a larger one
    # its pixel count rounded up to a power of two (never fewer than its pixels).
    assert pixel_sum_capacity(1) == pixel_sum_capacity(256 * 256) == 1 << 16
    assert pixel_sum_capacity(256 * 256 + 1) == pixel_sum_capacity(384 * 216) == 1 << 17
    assert pixel_sum_capacity(1280 * 720) == pixel_sum_capacity(1024 * 1024) == 1 << 20
    for n in (3, 4097, 65_535, 65_537, 1_000_001, 3840 * 2160):
        capacity = pixel_sum_capacity(n)
        assert capacity >= n and capacity & (capacity - 1) == 0
        assert capacity == 1 << 16 or capacity < 2 * n


def test_render_film_refuses_a_film_it_does_not_sum_like_mitsuba():
    import mitsuba as mi

    scene = _scene((64, 36), False)
    sensor = mi.load_dict(
        {
            "type": "perspective",
            "film": {"type": "hdrfilm", "width": 8, "height": 8, "rfilter": {"type": "gaussian"}},
        }
    )
    with pytest.raises(ValueError, match="box-filtered"):
        render_film(scene, sensor, scene.integrator(), 1, 0)
