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


def _pixel_starts(layout) -> np.ndarray:
    """Each pixel's first lane under ``layout``, from its documented definition."""
    pixel = np.arange(layout.n_pixels)
    block = pixel // layout.pixels_per_block
    within = pixel - block * layout.pixels_per_block
    shifts = np.array([layout.shift(b) for b in range(int(block[-1]) + 1)])
    return block * layout.block_lanes + shifts[block] + within * layout.spp


CASES = list(
    itertools.product(
        [1, 7, 144, 2304, 9216, 57_600],  # pixels: 1, a row, 16×9, 64×36, 128×72, 320×180
        [1, 3, 4, 16, 25, 30, 36, 42, 64, 100, 1000, 2025, 4096],  # samples per pixel
        [1, 2, 3, 8, 16],  # threads
    )
)


@pytest.mark.parametrize("lane_groups", [False, True], ids=["by-sample", "by-lane"])
def test_no_pixel_straddles_a_block_of_drjits_launch(lane_groups):
    for n_pixels, spp, threads in CASES:
        layout = sample_layout(n_pixels, spp, threads, lane_groups=lane_groups)
        starts = _pixel_starts(layout)
        ends = starts + spp
        # Every sample has its own lane: runs in order, not overlapping, inside the launch.
        assert np.all(starts[1:] >= ends[:-1]) and ends[-1] <= layout.lanes
        assert layout.padding == layout.lanes - n_pixels * spp >= 0
        for packet in (4, 8, WIDEST_PACKET_LANES):
            bounds = np.array([end for _, end in _drjit_blocks(layout.lanes, threads, packet)])
            # The block each pixel's first and last sample fall in: the same for every pixel.
            first = np.searchsorted(bounds, starts, side="right")
            last = np.searchsorted(bounds, ends - 1, side="right")
            assert np.array_equal(first, last), (n_pixels, spp, threads, packet)
        if lane_groups:
            # Mitsuba's multijitter stratifies lanes k·spp … k·spp + spp − 1 together.
            assert np.all(starts % spp == 0), (n_pixels, spp, threads)
        else:
            # Where the plain layout puts it within a packet: drjit's adds group alike.
            plain = np.arange(n_pixels) * spp
            assert np.all(starts % WIDEST_PACKET_LANES == plain % WIDEST_PACKET_LANES)


def test_the_padding_stays_small_and_powers_of_two_need_none():
    # The default scene's 42 samples: 389 pixels per block of 16,384 lanes, 46 lanes padding.
    layout = sample_layout(1280 * 720, 42, 2)
    assert layout.pixels_per_block == 389
    assert BLOCK_LANES - 389 * 42 == 46
    assert layout.padding / layout.lanes < 0.003
    for spp in (1, 2, 4, 16, 64, 1024):
        for lane_groups in (False, True):
            layout = sample_layout(1280 * 720, spp, 4, lane_groups=lane_groups)
            assert layout.padding == 0
            assert np.array_equal(_pixel_starts(layout), np.arange(1280 * 720) * spp)
    # No block holds a pixel of more samples than its lanes: the plain layout, whose pixels
    # straddle anyway.
    assert sample_layout(10, BLOCK_LANES + 1, 4) == plain_layout(10, BLOCK_LANES + 1)


@pytest.mark.parametrize("lane_groups", [False, True], ids=["by-sample", "by-lane"])
def test_every_sample_keeps_its_lane_whatever_the_thread_count(lane_groups):
    # Only the padding at the end depends on the threads: a sampler that draws by lane takes
    # the same numbers on any machine, and a small image is padded, not laid out anew.
    for n_pixels, spp in itertools.product([7, 2304, 9216, 57_600], [3, 25, 42, 64]):
        layouts = [sample_layout(n_pixels, spp, t, lane_groups=lane_groups) for t in (1, 2, 16)]
        starts = [_pixel_starts(layout) for layout in layouts]
        assert all(np.array_equal(s, starts[0]) for s in starts[1:]), (n_pixels, spp)
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
