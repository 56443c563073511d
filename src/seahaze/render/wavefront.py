"""Mitsuba's render loop for seahaze's cameras, with the image size out of the kernel.

Mitsuba's ``SamplingIntegrator::render`` (the loop behind ``mi.render``) and its ``perspective``
sensor write the film's width and height, their reciprocals and the ray-differential scale into
the kernel as constants, so every new image size compiles the camera pass again: the largest
kernels seahaze has, seconds to tens of seconds of LLVM time each on a small machine
(docs/benchmarks.md, "What does a new image size or sample count compile?"). :func:`render_film`
is that loop for what seahaze renders (one pass of ``spp`` samples per pixel, a pinhole camera,
a box-filtered RGB film) with those numbers passed as opaque values. Every image of up to
256×256 pixels, and above that every image size whose pixel count lies in the same octave,
shares one compiled kernel (the per-thread sums' length is the one size left in it:
:func:`pixel_sum_capacity`).

The samples are summed into each pixel by drjit's scatter-add into per-thread copies of the
image, as in Mitsuba's film, but laid out among the kernel's lanes so that no pixel's samples
are split between two of the threads' blocks (:mod:`seahaze.render.sample_blocks`): on the CPU
the same seed gives the same bytes from run to run and whatever the thread count. Where that
layout keeps Mitsuba's (a sample count that divides drjit's blocks, or an image of one block)
the samples are Mitsuba's own, and the images equal ``mi.render``'s to the rounding of each
pixel's sum (its film orders the additions by its own rules;
``tests/test_wavefront.py``). On a GPU the adds are atomic and their order varies in the last
bits (docs/limits.md, "Reproducibility").

Mitsuba's samplers write the sample count into the kernel too (``multijitter`` permutes within a
grid of that many cells); the ``physical`` mode's integrators draw instead from
:mod:`seahaze.render.stratified`, the same sampler with the count as a parameter.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .sample_blocks import SampleLayout, plain_layout, sample_layout


def render_film(
    scene: Any, sensor: Any, integrator: Any, spp: int, seed: int, *, stratified: bool = False
) -> np.ndarray:
    """Linear radiance and the integrator's AOVs, (H, W, 3 + AOVs) float32, of ``sensor``
    (whose film is ``hdrfilm`` with a box filter, without alpha) rendered with ``integrator``
    at ``spp`` samples per pixel from ``seed``.

    ``stratified``: draw from :class:`~seahaze.render.stratified.StratifiedSampler` (the same
    numbers as Mitsuba's ``multijitter``, with the count out of the kernel) instead of the
    sensor's sampler; for integrators written in Python, which only ask it for ``next_1d``
    and ``next_2d`` (Mitsuba's own integrators need one of its samplers).

    Each pixel's value is the mean of its samples' weighted radiance, as the film's
    development gives it for a box filter (every sample has weight 1 in its own pixel).
    """
    import drjit as dr
    import mitsuba as mi

    film = sensor.film()
    if not film.rfilter().is_box_filter() or film.sample_border():
        raise ValueError("render_film takes a box-filtered film without a sampled border")
    if sensor.needs_aperture_sample():
        raise ValueError("render_film takes a pinhole sensor (no aperture sample)")
    if sensor.shutter_open_time() > 0.0:
        raise ValueError("render_film takes a sensor with an instantaneous shutter")
    width, height = (int(v) for v in film.crop_size())
    n_pixels = width * height
    sampler = None if stratified else sensor.sampler().clone()
    layout = _layout(n_pixels, spp, sampler)
    pixel, sample, summed = _lane_samples(layout)
    if stratified:
        from .stratified import StratifiedSampler

        sampler = StratifiedSampler.seeded(spp, seed, pixel * dr.opaque(mi.UInt32, spp) + sample)
    else:
        sampler.set_sample_count(spp)
        sampler.set_samples_per_wavefront(spp)
        sampler.seed(dr.opaque(mi.UInt32, seed), layout.lanes)

    row = pixel // dr.opaque(mi.UInt32, width)
    position = mi.Point2f(mi.Float(pixel - row * dr.opaque(mi.UInt32, width)), mi.Float(row))
    film_scale = mi.Point2f(dr.opaque(mi.Float, 1.0 / width), dr.opaque(mi.Float, 1.0 / height))
    on_film = (position + sampler.next_2d()) * film_scale
    ray = _pinhole_rays(sensor, on_film, film_scale, spp)
    spectrum, _valid, aovs = integrator.sample(scene, sampler, ray, sensor.get_medium(), summed)
    if len(aovs) != len(integrator.aov_names()):
        raise ValueError("render_film takes integrators whose sample() returns their AOVs only")
    # An RGB variant's rays carry weight 1: the radiance is the sample's value.
    channels = [spectrum.x, spectrum.y, spectrum.z, *aovs]

    capacity = pixel_sum_capacity(n_pixels)
    sums = [dr.zeros(mi.Float, capacity) for _ in channels]
    for total, value in zip(sums, channels, strict=True):
        dr.scatter_reduce(dr.ReduceOp.Add, total, value, pixel, summed)
    # Compile and run the pass here, in drjit's eval and sync, which let go of Python's lock.
    # Reading a scatter's target (the division below, numpy's copy) would do both holding it,
    # and seahaze.interrupts' watcher thread, which ends the process on Ctrl-C during a
    # render, could not run until the pass had been compiled and run.
    dr.eval(sums)
    dr.sync_thread()
    # Divided as the film's development divides by its weights (drjit's division, whose
    # rounding under fast math is not numpy's).
    count = dr.opaque(mi.Float, spp)
    means = [total / count for total in sums]
    dr.eval(means)
    dr.sync_thread()
    # Channels stacked as rows, then transposed in one blocked copy: numpy's stack along the
    # last axis writes each value with the channels' stride, several times slower.
    rows = np.stack([np.array(mean, dtype=np.float32)[:n_pixels] for mean in means])
    return np.ascontiguousarray(rows.T).reshape(height, width, len(channels))


def _layout(n_pixels: int, spp: int, sampler: Any) -> SampleLayout:
    """The lanes of the render's samples: whole pixels in each of drjit's blocks on the CPU
    (:func:`~seahaze.render.sample_blocks.sample_layout`; a Mitsuba ``sampler`` draws by
    lane, seahaze's, None here, by sample), the plain layout on a GPU, whose adds are atomic
    whatever the layout."""
    import drjit as dr
    import mitsuba as mi

    if not mi.variant().startswith("llvm"):
        return plain_layout(n_pixels, spp)
    return sample_layout(n_pixels, spp, dr.thread_count(), lane_groups=sampler is not None)


def _lane_samples(layout: SampleLayout) -> tuple[Any, Any, Any]:
    """Each lane's pixel and sample index under ``layout`` and whether it is summed (not
    padding: a padding lane is pixel 0's, and the integrator is asked for it inactive). The
    layout's numbers are opaque: every layout shares the kernel."""
    import drjit as dr
    import mitsuba as mi

    spp = dr.opaque(mi.UInt32, layout.spp)
    block_lanes = dr.opaque(mi.UInt32, layout.block_lanes)
    samples_per_block = dr.opaque(mi.UInt32, layout.pixels_per_block * layout.spp)
    lane = dr.arange(mi.UInt32, layout.lanes)
    block = lane // block_lanes
    # SampleLayout.shift in the kernel; lanes before it wrap to large offsets (padding).
    shift = (
        block * dr.opaque(mi.UInt32, layout.shift_step) % dr.opaque(mi.UInt32, layout.shift_modulus)
    )
    offset = lane - block * block_lanes - shift
    pixel = block * dr.opaque(mi.UInt32, layout.pixels_per_block) + offset // spp
    summed = (offset < samples_per_block) & (pixel < dr.opaque(mi.UInt32, layout.n_pixels))
    return dr.select(summed, pixel, 0), offset % spp, summed


SMALLEST_SUM_CAPACITY = 1 << 16
"""Fewest pixels the per-thread sums of :func:`render_film` hold (a 256×256 image)."""


def pixel_sum_capacity(n_pixels: int) -> int:
    """Length of the pixel sums for an image of ``n_pixels``: on the CPU drjit sums into one
    private copy of the target per thread ("expand" mode, as Mitsuba's film does) and writes
    the target's length into the kernel, so every image whose sums have one length shares the
    kernel. Rounded up to a power of two, and at least :data:`SMALLEST_SUM_CAPACITY`: small
    images (previews, tests, CI datasets) then share one kernel whatever their size, at the
    cost of summing into copies of at most 256 KiB per channel and thread."""
    return max(SMALLEST_SUM_CAPACITY, 1 << (n_pixels - 1).bit_length())


def _pinhole_rays(sensor: Any, on_film: Any, pixel_size: Any, spp: int) -> Any:
    """The ray differentials of Mitsuba's ``perspective`` sensor through film positions
    ``on_film`` (in [0, 1]², pixels ``pixel_size`` apart: the film's scale), computed as its
    ``sample_ray_differential`` does but without the film's size as a constant: that method
    scales the principal-point offset (0 here) by the film's size and so bakes it into the
    kernel.
    """
    import drjit as dr
    import mitsuba as mi

    # The sensor's camera-to-sample transform stores its inverse: this is the sensor's own
    # sample-to-camera matrix, not a recomputed one.
    sample_to_camera = sensor.projection_transform().inverse()
    to_world = sensor.world_transform()
    near_p = mi.Vector3f(sample_to_camera @ mi.Point3f(on_film.x, on_film.y, 0.0))
    origin = sample_to_camera @ mi.Point3f(0.0)
    # Offsets, not points: Vectors, which the camera's to-world transform does not translate.
    dx = mi.Vector3f(sample_to_camera @ mi.Point3f(pixel_size.x, 0.0, 0.0) - origin)
    dy = mi.Vector3f(sample_to_camera @ mi.Point3f(0.0, pixel_size.y, 0.0) - origin)
    d = dr.normalize(near_p)
    inv_z = dr.rcp(d.z)
    near_t = dr.opaque(mi.Float, sensor.near_clip()) * inv_z
    far_t = dr.opaque(mi.Float, sensor.far_clip()) * inv_z
    ray = mi.RayDifferential3f()
    ray.time = mi.Float(sensor.shutter_open())
    ray.d = to_world @ d
    ray.o = to_world.translation() + ray.d * near_t
    ray.maxt = far_t - near_t
    ray.o_x = ray.o_y = ray.o
    ray.d_x = to_world @ dr.normalize(near_p + dx)
    ray.d_y = to_world @ dr.normalize(near_p + dy)
    ray.has_differentials = True
    ray.scale_differential(dr.opaque(mi.Float, 1.0 / np.sqrt(np.float32(spp))))
    return ray
