"""Pixel sums that are the same bytes from run to run: no pixel's samples straddle two of drjit's
thread blocks (seahaze.render.sample_blocks), checked against drjit's launch rule and by
rendering at several thread counts."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from conftest import load_flat_scene, small_spec
from seahaze.cpus import render_threads
from seahaze.render.sample_blocks import (
    BLOCK_LANES,
    WIDEST_PACKET_LANES,
    plain_layout,
    sample_layout,
)
from seahaze.render.wavefront import render_film


def _drjit_blocks(size: int, threads: int, packet: int) -> list[tuple[int, int]]:
    """The lanes [start, end) of each block drjit-core 1.5 launches a kernel of ``size`` lanes
    in, on ``threads`` threads with SIMD packets of ``packet`` lanes (LLVMThreadState::launch)."""
    packets = -(-size // packet)
    if threads <= 1:
        block = size
    elif packets <= threads:
        block = packet
    elif size <= BLOCK_LANES * threads * 2:
        block = -(-packets // (2 * threads)) * packet
    else:
        block = BLOCK_LANES
    return [(start, min(start + block, size)) for start in range(0, size, block)]


def _first_and_last_lanes(layout) -> tuple[np.ndarray, np.ndarray]:
    """Each pixel's first and last sample's lane under ``layout``, from its documented
    definition (sample by sample: lane ``s·P + i`` of the block; else ``shift + i·spp + s``)."""
    pixel = np.arange(layout.n_pixels)
    block = pixel // layout.pixels_per_block
    within = pixel - block * layout.pixels_per_block
    start = block * layout.block_lanes
    if layout.sample_major:
        first = start + within
        return first, first + (layout.spp - 1) * layout.pixels_per_block
    shifts = np.array([layout.shift(b) for b in range(int(block[-1]) + 1)])
    first = start + shifts[block] + within * layout.spp
    return first, first + layout.spp - 1


def _all_lanes(layout) -> np.ndarray:
    """Every sample's lane, (pixels, spp), from the layout's documented definition."""
    first, _ = _first_and_last_lanes(layout)
    step = layout.pixels_per_block if layout.sample_major else 1
    return first[:, None] + step * np.arange(layout.spp)[None, :]


CASES = list(
    itertools.product(
        [1, 7, 144, 2304, 57_600],  # pixels: 1, a row, 16×9, 64×36, 320×180
        [1, 3, 16, 25, 30, 42, 64, 1000, 2025, 4096],  # samples per pixel
        [1, 2, 3, 16],  # threads
    )
)


@pytest.mark.parametrize("lane_groups", [False, True], ids=["by-sample", "by-lane"])
def test_no_pixel_straddles_a_block_of_drjits_launch(lane_groups):
    for n_pixels, spp, threads in CASES:
        layout = sample_layout(n_pixels, spp, threads, lane_groups=lane_groups)
        first, last = _first_and_last_lanes(layout)
        assert last.max() < layout.lanes
        assert layout.padding == layout.lanes - n_pixels * spp >= 0
        if n_pixels * spp <= 200_000:  # every sample its own lane
            lanes = _all_lanes(layout)
            assert len(np.unique(lanes)) == lanes.size
        for packet in (4, 8, WIDEST_PACKET_LANES):
            bounds = np.array([end for _, end in _drjit_blocks(layout.lanes, threads, packet)])
            # The block a pixel's first and last sample fall in: the same for every pixel.
            assert np.array_equal(
                np.searchsorted(bounds, first, side="right"),
                np.searchsorted(bounds, last, side="right"),
            ), (n_pixels, spp, threads, packet)
        if lane_groups:
            # Mitsuba's multijitter stratifies lanes k·spp … k·spp + spp − 1 together.
            assert np.all(first % spp == 0) and np.all(last == first + spp - 1)
        elif spp <= 1024:
            # A pixel's samples lie P ≥ 16 lanes apart: no packet holds two of them, so its
            # sum is its samples added one after another, at any packet width.
            assert layout.sample_major and layout.pixels_per_block >= WIDEST_PACKET_LANES


def test_the_padding_stays_small_and_powers_of_two_need_none():
    # The default scene's 42 samples: 390 pixels per block of 16,384 lanes (4 lanes padding)
    # by sample; 389 by lane, where the blocks' shifts take up to 40 more.
    layout = sample_layout(1280 * 720, 42, 2)
    assert layout.pixels_per_block == 390 and BLOCK_LANES - 390 * 42 == 4
    assert layout.padding / layout.lanes < 0.001
    by_lane = sample_layout(1280 * 720, 42, 2, lane_groups=True)
    assert by_lane.pixels_per_block == 389 and by_lane.padding / by_lane.lanes < 0.003
    for spp in (1, 2, 4, 16, 64, 1024):
        layout = sample_layout(1280 * 720, spp, 4, lane_groups=True)
        assert layout.padding == 0  # Mitsuba's own order
        assert np.array_equal(_first_and_last_lanes(layout)[0], np.arange(1280 * 720) * spp)
        # By sample, whole blocks but the last, whose rows stop short at its last pixel.
        assert sample_layout(1280 * 720, spp, 4).padding < BLOCK_LANES
    # No block holds a pixel of more samples than its lanes: the plain layout, whose pixels
    # straddle anyway.
    assert sample_layout(10, BLOCK_LANES + 1, 4) == plain_layout(10, BLOCK_LANES + 1)


@pytest.mark.parametrize("lane_groups", [False, True], ids=["by-sample", "by-lane"])
def test_every_sample_keeps_its_lane_whatever_the_thread_count(lane_groups):
    # Only the padding at the end depends on the threads: a sampler that draws by lane takes
    # the same numbers on any machine, and a small image is padded, not laid out anew.
    for n_pixels, spp in itertools.product([7, 2304, 9216, 57_600], [3, 25, 42, 64]):
        layouts = [sample_layout(n_pixels, spp, t, lane_groups=lane_groups) for t in (1, 2, 16)]
        lanes = [_all_lanes(layout) for layout in layouts]
        assert all(np.array_equal(x, lanes[0]) for x in lanes[1:]), (n_pixels, spp)
        # More than 2·16 blocks of B lanes at 16 threads: drjit's fourth rule.
        assert layouts[-1].lanes > 2 * 16 * BLOCK_LANES


@pytest.mark.parametrize("bad", [(0, 4, 2), (10, 0, 2), (10, 4, 0)])
def test_counts_below_one_are_refused(bad):
    with pytest.raises(ValueError, match="at least 1"):
        sample_layout(*bad)


def _spread_integrator():
    """Radiance 2^(24u) of one uniform draw u per sample: values over seven decades, so the
    order of a pixel's additions shows in its last bits."""
    import drjit as dr
    import mitsuba as mi

    class Spread(mi.SamplingIntegrator):
        def sample(self, scene, sampler, ray, medium=None, active=True):
            return mi.Spectrum(dr.exp2(24.0 * sampler.next_1d())), mi.Bool(True), []

        def aov_names(self):
            return []

    return Spread(mi.Properties())


def _renders(spp: int, resolution: tuple[int, int], stratified: bool, threads: list[int]):
    """render_film of the spread integrator at each thread count (a scene with the haze box
    draws from Mitsuba's ``independent`` sampler, which draws by lane)."""
    spec = small_spec(camera={"resolution": list(resolution)})
    loaded, _ = load_flat_scene(spec, haze_box=not stratified)
    scene, integrator = loaded.scene, _spread_integrator()
    images = []
    for count in threads:
        with render_threads(count):
            images.append(
                render_film(scene, scene.sensors()[0], integrator, spp, 5, stratified=stratified)
            )
    return images


@pytest.mark.usefixtures("mitsuba_variant")
@pytest.mark.parametrize(
    ("spp", "resolution"), [(42, (128, 72)), (25, (64, 36)), (42, (16, 9))], ids=str
)
def test_seahazes_sampler_gives_the_same_bytes_at_every_thread_count(spp, resolution):
    # 128×72 at 42 samples: 23 block ends fell inside a pixel before, and two renders differed
    # in 24 of these 27,648 values; at 2 to 16 threads each block goes to whichever is free.
    one, *more = _renders(spp, resolution, True, [1, 2, 4, 7, 16, 2])
    for image in more:
        np.testing.assert_array_equal(image, one)


@pytest.mark.usefixtures("mitsuba_variant")
def test_mitsubas_sampler_gives_the_same_bytes_at_every_thread_count():
    first, *more = _renders(42, (128, 72), False, [2, 2, 4, 1, 16])
    for image in more:
        np.testing.assert_array_equal(image, first)


@pytest.mark.usefixtures("mitsuba_variant")
def test_every_sample_is_summed_once_into_its_own_pixel():
    # The same draws taken straight from seahaze's sampler, lane = sample, summed in float64:
    # the padding is summed nowhere and each sample lands in its pixel (the mean of 2^(24u)
    # over a pixel's 42 samples is its own: a misplaced sample moves it by percent).
    from seahaze.render.stratified import StratifiedSampler

    width, height, spp = 128, 72, 42
    (image,) = _renders(spp, (width, height), True, [2])
    sampler = StratifiedSampler.seeded(spp, 5, width * height * spp)
    sampler.next_2d()  # the film position, drawn before the integrator's draw
    u = np.array(sampler.next_1d(), dtype=np.float64)
    expected = np.exp2(24.0 * u).reshape(height, width, spp).mean(axis=-1)
    np.testing.assert_allclose(image[..., 0], expected, rtol=2e-6)
    # On the CPU this layout has padding between its blocks' pixels.
    assert sample_layout(width * height, spp, 2).padding > 0


WIDTH_RENDER = """
import ctypes, sys
from pathlib import Path
import drjit as dr
core = ctypes.CDLL(str(next(Path(dr.__file__).parent.glob("libdrjit-core.*"))))
cpu = core["_Z19jit_llvm_target_cpuv"]
features = core["_Z24jit_llvm_target_featuresv"]
cpu.restype = features.restype = ctypes.c_char_p
set_target = core["_Z19jit_llvm_set_targetPKcS0_j"]
set_target.argtypes = [ctypes.c_char_p, ctypes.c_char_p, ctypes.c_uint32]
import mitsuba as mi
mi.set_variant("llvm_ad_rgb")
set_target(cpu(), features(), int(sys.argv[1]))
sys.path.insert(0, sys.argv[3])
import numpy as np
from conftest import load_flat_scene, small_spec
from test_sample_blocks import _spread_integrator
from seahaze.render.wavefront import render_film
loaded, _ = load_flat_scene(small_spec(camera={"resolution": [128, 72]}), haze_box=False)
scene = loaded.scene
image = render_film(scene, scene.sensors()[0], _spread_integrator(), 42, 5, stratified=True)
np.save(sys.argv[2], image)
"""
"""A render at the SIMD packet width ``argv[1]``, set through drjit-core's C API (its Python
API has no setter), saved to ``argv[2]``."""


@pytest.mark.usefixtures("mitsuba_variant")
def test_seahazes_sampler_gives_the_same_bytes_at_every_simd_width(tmp_path, mitsuba_variant):
    # drjit adds a packet's lanes of one pixel together first, in a grouping that follows the
    # packet's width: laid out pixel by pixel, a render at 8 lanes differed from one at 16 in
    # 9,750 of these 27,648 values. Sample by sample, a packet holds one sample of a pixel.
    import subprocess
    import sys
    from pathlib import Path

    if not mitsuba_variant.startswith("llvm"):
        pytest.skip("the packet width is the CPU backend's")
    tests = str(Path(__file__).parent)
    images = []
    for width in (4, 8):
        out = tmp_path / f"width{width}.npy"
        done = subprocess.run(
            [sys.executable, "-c", WIDTH_RENDER, str(width), str(out), tests],
            capture_output=True,
            text=True,
            timeout=300,
        )
        if done.returncode != 0 and "_Z19jit_llvm" in done.stderr:
            pytest.skip("this drjit-core exports no jit_llvm_set_target")
        assert done.returncode == 0, done.stderr
        images.append(np.load(out))
    np.testing.assert_array_equal(images[0], images[1])
    assert images[0].max() > 1.0  # the spread integrator's values, not an empty film
