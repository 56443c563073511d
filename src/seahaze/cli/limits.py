"""The limits that protect a ``seahaze render`` user, and the job's time and memory estimate.

Hard limits (exit 2 before anything starts, docs/limits.md): at most :data:`MAX_SCENES` scenes
in a batch, at most :data:`MAX_WORKERS` local workers (and no more than the machine has cores),
and at most ``2^32`` samples in one image (Mitsuba's limit per render: ``width × height × spp``).
A job estimated at :data:`CONFIRM_SECONDS` or more, or needing more than
:data:`CONFIRM_MEMORY_FRACTION` of the machine's memory for one scene, starts only with
``--yes``; the message gives the estimate.

The estimate is the cost model of ``scripts/measure_cost_model.py``, measured on the project's
2-vCPU machine with the ``llvm_ad_rgb`` variant (docs/benchmarks.md, "Cost model")::

    core-seconds per scene = setup(sea quality) + pixels · (images · write)
                             + pixels · spp · clean
                             + Σ_levels [ fixed(mode, V) + pixels · spp · per_sample(mode, V) ]
    wall time = Σ_scenes serial + render / cores    (setup and writes are serial)

except in ``physical``, whose one pass gives the clean image and every level: its render part is
``pixels · spp · (pass + (levels − 1) · level) + photons / 2^17 · Σ_levels table(V)``, the tables
timed at 2^17 photons and traced with ``EstimatorSettings.photons_for(pixels · spp)``
(:mod:`seahaze.render.estimator`).

``V``-dependent constants are interpolated in log V between 50, 300 and 4000 m (held beyond).
On a GPU (``cuda_ad_rgb``) the estimate is an upper bound.
"""

from __future__ import annotations

import itertools
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass

from ..fileio import cores
from ..spec import SceneSpec

MAX_SCENES = 10_000
"""Most scenes in one batch folder. The manifest lists every scene with its full config and is
rewritten after each one (a 10,000-scene manifest is about 40 MB); split larger datasets over
several folders."""
MAX_WORKERS = 64
"""Most local worker processes (and never more than 4 per core: each renders with
cores/workers threads, so more only adds processes)."""
MAX_SAMPLES_PER_IMAGE = 2**32 - 1
"""Mitsuba renders one image in one pass of at most 2^32 samples (width × height × spp)."""
CONFIRM_SECONDS = 3600.0
"""A job estimated at this many seconds or more needs ``--yes``."""
ANNOUNCE_SECONDS = 300.0
"""A job estimated at this many seconds or more prints its estimate before it starts."""
CONFIRM_MEMORY_FRACTION = 0.8
"""A scene estimated to need more than this share of the machine's memory needs ``--yes``."""

# measured by scripts/measure_cost_model.py (docs/benchmarks.md, "Cost model"); CPU seconds
SETUP_CORE_S = {"low": 1.07, "medium": 1.21, "high": 2.44}
CLEAN_CORE_S = 4.21e-07
WRITE_CORE_S = 4.54e-07
PHYSICAL_PASS_CORE_S = 6.88e-07
PHYSICAL_LEVEL_CORE_S = 1.11e-08
PHYSICAL_TABLE_S = {50.0: 0.28, 300.0: 0.14, 4000.0: 0.07}
REFERENCE_CORE_S = {50.0: 6.18e-06, 300.0: 4.21e-06, 4000.0: 2.03e-06}
ASM_LEVEL_S = {50.0: 0.81, 300.0: 0.64, 4000.0: 0.51}

VALIDATED_FROM_M = {"physical": 100.0}
"""Thinnest visibility (m) down to which the mode is within 3 % of converged ``reference``
renders in every region (docs/physics.md, "Validated range"; docs/benchmarks.md): ``physical``
from 100 m (measured at 100, 200, 300, 1000 and 4000 m). ``reference`` is the unbiased yardstick
at every level; ``asm`` is an approximation that is never within 3 % (5–17 % at 300–4000 m)."""

BYTES_PER_PIXEL_IMAGE = 12
"""Linear float32 RGB held per image until the scene is written."""
BYTES_PER_PIXEL_SCENE = 64
"""Geometry pass, film and exposure buffers per pixel, besides the images (rounded up)."""
BASE_BYTES = 2 << 30
"""Mitsuba, the sea mesh and its acceleration structure: about 1–2 GB."""


class LimitError(ValueError):
    """A job beyond a hard limit; the message is one line for the user."""


@dataclass(frozen=True)
class Estimate:
    """What a job will cost on this machine."""

    seconds: float
    """Wall-clock seconds for every scene still to render."""
    scene_bytes: int
    """Peak memory of one scene (the largest)."""
    scenes: int

    def describe(self) -> str:
        return (
            f"{self.scenes} scene(s), about {format_duration(self.seconds)} on "
            f"{cores()} core(s) and {self.scene_bytes / 2**30:.1f} GiB per scene "
            "(cost model: docs/limits.md)"
        )


def max_workers() -> int:
    """Most local workers on this machine: 4 per core, at most :data:`MAX_WORKERS`."""
    return min(MAX_WORKERS, 4 * cores())


def total_memory() -> int:
    """Bytes of memory of this machine (0 when unknown)."""
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):
        return 0


def format_duration(seconds: float) -> str:
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    if seconds < 2 * 86400:
        return f"{seconds / 3600:.1f} h"
    return f"{seconds / 86400:.1f} days"


def _interpolated(table: dict[float, float], visibility_m: float) -> float:
    """``table`` (V → value) at ``visibility_m``, linear in log V, held beyond its ends."""
    points = sorted(table)
    x = math.log(min(max(visibility_m, points[0]), points[-1]))
    for a, b in itertools.pairwise(points):
        if x <= math.log(b):
            t = (x - math.log(a)) / (math.log(b) - math.log(a))
            return table[a] + t * (table[b] - table[a])
    return table[points[-1]]


def scene_core_seconds(spec: SceneSpec) -> tuple[float, float]:
    """CPU seconds one scene costs by the cost model (module docstring): the serial part
    (geometry, scene load, file writes) and the part the renderer spreads over every core."""
    width, height = spec.camera.resolution
    pixels, spp, levels = width * height, spec.render.spp, spec.haze.levels
    serial = SETUP_CORE_S[spec.sea.quality] + pixels * (len(levels) + 1) * WRITE_CORE_S
    mode = spec.render.mode
    if mode == "physical":
        # One pass gives the clean image and every level; each level adds a little to it
        # and its diffuse table.
        from ..render.estimator import settings_from

        settings = settings_from(spec.render.estimator)

        further = max(len(levels) - 1, 0) * PHYSICAL_LEVEL_CORE_S
        parallel = pixels * spp * (PHYSICAL_PASS_CORE_S + further)
        # The tables were timed at the fewest photons; larger passes trace more.
        photons = settings.photons_for(pixels * spp) / settings.min_table_photons
        tables = photons * sum(_interpolated(PHYSICAL_TABLE_S, v) for v in levels)
        return serial, parallel + tables
    parallel = pixels * spp * CLEAN_CORE_S
    for v in levels:
        if mode == "reference":
            per, fixed = _interpolated(REFERENCE_CORE_S, v), 0.0
        else:
            airlight = spec.render.airlight_spp / 1024.0
            per, fixed = 0.0, _interpolated(ASM_LEVEL_S, v) * airlight
        parallel += fixed + pixels * spp * per
    return serial, parallel


def scene_bytes(spec: SceneSpec) -> int:
    """Peak memory of one scene: its images held until written, buffers and Mitsuba."""
    width, height = spec.camera.resolution
    images = len(spec.haze.levels) + 1
    return BASE_BYTES + width * height * (images * BYTES_PER_PIXEL_IMAGE + BYTES_PER_PIXEL_SCENE)


def check_hard_limits(
    templates: Sequence[tuple[str, SceneSpec]], scenes: int, workers: int | None
) -> None:
    """Raise :class:`LimitError` for a job no confirmation makes sensible: ``scenes`` in all
    from ``templates`` (name, spec; variation does not change their size or sample count)."""
    if scenes > MAX_SCENES:
        raise LimitError(
            f"{scenes:,} scenes; a batch folder holds at most {MAX_SCENES:,} (split the "
            "dataset over several --out folders)"
        )
    if workers is not None and not 1 <= workers <= max_workers():
        raise LimitError(
            f"--workers {workers}: must be within 1..{max_workers()} (this machine has "
            f"{cores()} core(s); each worker renders with cores/workers threads)"
        )
    for name, spec in templates:
        width, height = spec.camera.resolution
        samples = width * height * spec.render.spp
        if samples > MAX_SAMPLES_PER_IMAGE:
            most = MAX_SAMPLES_PER_IMAGE // (width * height)
            raise LimitError(
                f"{name}: {width}x{height} at {spec.render.spp} spp is {samples:.2e} samples per "
                f"image; Mitsuba renders at most 2^32 = 4.29e9 in one image: at most {most} spp "
                "at this resolution"
            )


def frames_of(spec: SceneSpec) -> int:
    """Units of work (frames) one scene of ``spec`` makes: its sequence's frames, else 1."""
    return spec.sequence.frames if spec.sequence is not None else 1


def estimate(jobs: Sequence[tuple[SceneSpec, int]]) -> Estimate:
    """The time and memory estimate of rendering ``count`` scenes (or frames) like each spec:
    a frame costs what a still scene does."""
    serial = parallel = 0.0
    for spec, count in jobs:
        s, p = scene_core_seconds(spec)
        serial, parallel = serial + count * s, parallel + count * p
    seconds = serial + parallel / max(cores(), 1)
    peak = max((scene_bytes(spec) for spec, _ in jobs), default=0)
    return Estimate(seconds, peak, sum(count for _, count in jobs))


def confirmation_needed(job: Estimate) -> str | None:
    """Why the job needs ``--yes`` (None: it does not)."""
    memory = total_memory()
    if memory and job.scene_bytes > CONFIRM_MEMORY_FRACTION * memory:
        return (
            f"one scene needs about {job.scene_bytes / 2**30:.0f} GiB of memory and this "
            f"machine has {memory / 2**30:.0f} GiB"
        )
    if job.seconds >= CONFIRM_SECONDS:
        return f"the job takes about {format_duration(job.seconds)}"
    return None
