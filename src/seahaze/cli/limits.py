"""The limits that protect a ``seahaze render`` user, and the job's time and memory estimate.

Hard limits (exit 2 before anything starts, docs/limits.md): at most :data:`MAX_SCENES` scenes
in a batch, at most :data:`MAX_WORKERS` local workers (and no more than the machine has cores),
and at most ``2^32`` samples in one image (Mitsuba's limit per render: ``width × height × spp``).
A job estimated at :data:`CONFIRM_SECONDS` or more, or needing more than
:data:`CONFIRM_MEMORY_FRACTION` of the machine's memory for one scene, starts only with
``--yes``; the message gives the estimate.

The estimate is the cost model of ``scripts/measure_cost_model.py`` (render time) and
``scripts/measure_estimates.py`` (memory, compilation, start-up), measured on the project's
2-vCPU machine with the ``llvm_ad_rgb`` variant (docs/limits.md, "The estimate")::

    core-seconds per scene = setup(sea quality) + pixels · (images · write)
                             + pixels · spp · clean
                             + Σ_levels [ fixed(mode, V) + pixels · spp · per_sample(mode, V) ]
    wall time = start-up + compilation + Σ_scenes serial + render / cores

except in ``physical``, whose one pass gives the clean image and every level: its render part is
``pixels · spp · (pass + (levels − 1) · level) + photons / 2^17 · Σ_levels table(V)``, the tables
timed at 2^17 photons and traced with ``EstimatorSettings.photons_for(pixels · spp)``
(:mod:`seahaze.render.estimator`).

Compilation: drjit compiles a render's kernels on first use and keeps them in its cache
(``~/.drjit``); kernels bake in the image size and sample count. The estimate counts a full
compilation for a kind of render (variant, mode, level count) this machine has not rendered,
a partial one for a known kind at a new size or sample count, and none for a render it has
made before: :class:`KernelRecord` remembers them in seahaze's state folder.

Memory: ``base(mode) + pixels · (per_pixel(mode) + images · per_image(mode))`` for one scene;
scenes rendered at once (``--workers``) add up.

``V``-dependent constants are interpolated in log V between 50, 300 and 4000 m (held beyond).
On a GPU (``cuda_ad_rgb``) the estimate is an upper bound.
"""

from __future__ import annotations

import contextlib
import itertools
import json
import math
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

from .. import __version__
from ..cpus import usable_cpus
from ..fileio import write_json
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
ANNOUNCE_COMPILE_SECONDS = 10.0
"""A job that will compile kernels for this many seconds or more says so before it starts."""
CONFIRM_MEMORY_FRACTION = 0.8
"""A scene estimated to need more than this share of the machine's memory needs ``--yes``."""

# measured by scripts/measure_cost_model.py (docs/benchmarks.md, "Cost model"); CPU seconds
SETUP_CORE_S = {"low": 1.79, "medium": 1.94, "high": 3.41}
CLEAN_CORE_S = 6.56e-07
WRITE_CORE_S = 5.97e-07
PHYSICAL_PASS_CORE_S = 1.27e-06
PHYSICAL_LEVEL_CORE_S = 0.0
PHYSICAL_TABLE_S = {50.0: 0.57, 300.0: 0.26, 4000.0: 0.21}
REFERENCE_CORE_S = {50.0: 9.69e-06, 300.0: 6.56e-06, 4000.0: 3.11e-06}
ASM_LEVEL_S = {50.0: 1.31, 300.0: 0.91, 4000.0: 0.67}

# measured on this 2-vCPU machine with the path lengths of scenes/patchy.yaml and
# scenes/fogbank.yaml at 320×180 in the render's drjit kernel (0.16 s for 1.5e7 points and
# 0.22 s for 6.9e6; docs/limits.md); wall seconds on this machine's one core of throughput
FIELD_POINT_S = 1.7e-08
"""One evaluation of a varying haze's density (the patches' noise and the bank)."""
FIELD_RAY_M = 3200.0
"""Mean length (m) of a pixel's ray that the quadrature covers, in horizontal scales."""
FIELD_BYTES = 0.3 * 2**30
"""Memory of the quadrature's rays and its cached path lengths (measured: patches 0.25 GiB
above uniform haze at 1280×720, docs/benchmarks.md, "What the physical mode's equivalent
profiles cost")."""

BANK_PHOTON_S = 1.2e-06
"""Wall seconds per photon and level of a fog bank's own diffuse field in ``physical``: its
strip traced and the ratios' grid summed (0.7–1.7 s per level for 2^20 photons on this
machine, the first of a process compiling the strip's kernel; docs/benchmarks.md, "How close
is physical in a fog bank?")."""

PATCH_PHOTON_S = 2.0e-06
"""The same for patches alone: their box traced (the profile at every level, the field at
levels a factor 2 apart) and the ratios' grid summed (at 1280×720, 2^20 photons per level:
the 11 graded levels' boxes about 15 s, denser levels longer, and the sums about 8 s;
docs/benchmarks.md, "What the physical mode's equivalent profiles cost")."""

VALIDATED_FROM_M = {"physical": 100.0}
"""Thinnest visibility (m) down to which the mode is within 3 % of converged ``reference``
renders in every region (docs/physics.md, "Validated range"; docs/benchmarks.md): ``physical``
from 100 m (measured at 100, 200, 300, 1000 and 4000 m). ``reference`` is the unbiased yardstick
at every level; ``asm`` is an approximation that is never within 3 % (5–17 % at 300–4000 m)."""

PATCHES_VALIDATED_FROM_M = {"physical": 300.0}
"""The same for patches alone (``haze.patches``): ``physical`` gives them the diffuse light of
their own field (``render/patch_diffuse.py``); for strong patches (density ratio 30) every
region, sea and vessels in dense and thin haze apart, within 3 % of the ``reference`` at 300,
1000 and 4000 m (the mean of sixteen renders; the sea's thin part at 300 m, 87 pixels near
the horizon, −2.75 ± 0.69 % against a reference of its own rows; one render's region error
scatters about the mean by 1.0–2.3 %, 1σ: the box's photon noise; docs/physics.md, "Drifting
patches' own diffuse field"). Not measured below 300 m."""
PATCHES_WITH_BANK_VALIDATED_FROM_M = {"physical": 1000.0}
"""Patches with a bank, within 3.5 %: neither field's tracer covers both, so they keep the
tables' diffuse light, as patches alone were before theirs (1.6–3.4 % bright at 1000 m, 7–14 %
at 300 m)."""
BANK_VALIDATED_FROM_M = {"physical": 300.0}
"""The same in a fog bank (``haze.bank``), within 3 %: ``physical`` gives a bank the diffuse
light of its own field, traced through a strip across its edge (``render/bank_diffuse.py``);
every region of two banks within 2.8 % of the ``reference`` at 300, 1000 and 4000 m (the mean
of four renders; one render's region error scatters about it by 0.4–2.8 % at 1000–4000 m and
1.1–3.5 % at 300 m, 1σ: the bank's photon noise; docs/physics.md, "A fog bank's own diffuse
field"). Not measured below 300 m."""

# measured by scripts/measure_estimates.py (docs/limits.md, "The estimate"); bytes, wall seconds
BASE_BYTES = {"physical": 6.34e08, "reference": 5.03e08, "asm": 4.68e08}
"""Mitsuba, drjit, the sea mesh and its acceleration structure (resident bytes)."""
BYTES_PER_PIXEL = {"physical": 159.0, "reference": 396.0, "asm": 415.0}
"""Geometry pass, film and buffers per pixel, besides the images."""
BYTES_PER_PIXEL_IMAGE = {"physical": 81.0, "reference": 11.0, "asm": 9.0}
"""Per pixel and image (clean or level): its film channels, the linear image held until the
scene is written, and its encoding."""
STARTUP_S = 2.7
"""Wall seconds before the first scene: Python, Mitsuba and the variant."""
COMPILE_S = {"physical": 17.0, "reference": 3.7, "asm": 5.3}
"""Wall seconds compiling a kind of render this machine has not rendered."""
RECOMPILE_S = {"physical": 17.0, "reference": 3.7, "asm": 2.5}
"""Wall seconds compiling a known kind of render at a new image size or sample count."""
KERNEL_RECORD_NAME = "kernels.json"
"""The file in seahaze's state folder that lists the renders this machine has compiled."""
MAX_KERNEL_RECORDS = 4096
"""Most renders the record keeps (the oldest are forgotten first)."""


class LimitError(ValueError):
    """A job beyond a hard limit; the message is one line for the user."""


@dataclass(frozen=True)
class Estimate:
    """What a job will cost on this machine."""

    seconds: float
    """Wall-clock seconds for every scene still to render, compilation included."""
    scene_bytes: int
    """Peak memory of one scene (the largest)."""
    scenes: int
    compile_seconds: float
    """Of :attr:`seconds`, those compiling kernels on first use."""
    peak_bytes: int
    """Peak memory of the job: :attr:`scene_bytes` times the scenes rendered at once, in one
    process plus a scene's images written while the next renders."""

    def describe(self) -> str:
        compiling = (
            f" (of which {format_duration(self.compile_seconds)} compiling kernels on first use)"
            if self.compile_seconds >= 1.0
            else ""
        )
        return (
            f"{self.scenes} scene(s), about {format_duration(self.seconds)}{compiling} on "
            f"{usable_cpus()} core(s) and {self.peak_bytes / 2**30:.1f} GiB "
            "(cost model: docs/limits.md)"
        )

    def record(self) -> dict[str, float | int]:
        """The estimate as plain data (``seahaze render --estimate`` prints it as JSON)."""
        return {
            "scenes": self.scenes,
            "seconds": round(self.seconds, 3),
            "compile_seconds": round(self.compile_seconds, 3),
            "scene_bytes": self.scene_bytes,
            "peak_bytes": self.peak_bytes,
        }


def max_workers() -> int:
    """Most local workers on this machine: 4 per core, at most :data:`MAX_WORKERS`."""
    return min(MAX_WORKERS, 4 * usable_cpus())


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
    serial += varying_haze_seconds(spec)
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
        # A bank alone or patches alone get their own diffuse field, traced per level
        # (render/bank_diffuse, render/patch_diffuse).
        own = settings.bank_photons_for(settings.photons_for(pixels * spp))
        if spec.haze.bank is not None and spec.haze.patches is None:
            tables += len(levels) * own * BANK_PHOTON_S
        if spec.haze.patches is not None and spec.haze.bank is None:
            tables += len(levels) * own * PATCH_PHOTON_S
        return serial, parallel + tables
    parallel = pixels * spp * CLEAN_CORE_S
    # Delta tracking samples at the field's bound: patches whose density spans R cost about
    # sqrt(R) times as many steps (the exact field's majorant; docs/limits.md), in the
    # reference's render and in asm's airlight render alike.
    patches = spec.haze.patches
    majorant = math.sqrt(patches.density_ratio) if patches is not None else 1.0
    for v in levels:
        if mode == "reference":
            per, fixed = _interpolated(REFERENCE_CORE_S, v) * majorant, 0.0
        else:
            airlight = spec.render.airlight_spp / 1024.0
            per, fixed = 0.0, _interpolated(ASM_LEVEL_S, v) * airlight * majorant
        parallel += fixed + pixels * spp * per
    return serial, parallel


def varying_haze_seconds(spec: SceneSpec) -> float:
    """CPU seconds of the optical depths of haze that varies across the sea (``haze.patches``,
    ``haze.bank``): once per scene, three Gauss points per panel of its horizontal scale
    over :data:`FIELD_RAY_M` per pixel (:mod:`seahaze.nonuniform`); 0 for haze that varies
    with height alone."""
    from ..scene_medium import haze_field

    field = haze_field(spec)
    if field is None:
        return 0.0
    horizontal, _ = field.scales_m()
    width, height = spec.camera.resolution
    points = width * height * 3.0 * FIELD_RAY_M / horizontal
    return points * FIELD_POINT_S


def scene_bytes(spec: SceneSpec) -> int:
    """Peak resident memory of one scene: Mitsuba and the sea, the per-pixel buffers, and the
    images (clean and levels) held until they are written."""
    width, height = spec.camera.resolution
    mode = spec.render.mode
    images = len(spec.haze.levels) + 1
    per_pixel = BYTES_PER_PIXEL[mode] + images * BYTES_PER_PIXEL_IMAGE[mode]
    varying = spec.haze.patches is not None or spec.haze.bank is not None
    return int(BASE_BYTES[mode] + width * height * per_pixel + (FIELD_BYTES if varying else 0))


def written_scene_bytes(spec: SceneSpec) -> int:
    """Memory of a rendered scene's images waiting to be written: a batch in one process holds
    the last scene's while the next renders (``seahaze.batch.executors``); measured 0.25 GiB
    more peak for ``scenes/msvd.yaml`` at 640×360, 0.74 GiB at 1280×720."""
    width, height = spec.camera.resolution
    images = len(spec.haze.levels) + 1
    return int(width * height * images * BYTES_PER_PIXEL_IMAGE[spec.render.mode])


def kernel_kind(spec: SceneSpec) -> str:
    """What a render's kernels depend on besides its size and samples: seahaze's version (its
    integrators), the variant, the mode and the number of levels."""
    render = spec.render
    return f"{__version__}/{render.variant}/{render.mode}/{len(spec.haze.levels)}"


def kernel_key(spec: SceneSpec) -> str:
    """:func:`kernel_kind` with the image size and samples per pixel, which kernels bake in."""
    width, height = spec.camera.resolution
    return f"{kernel_kind(spec)}/{width}x{height}/{spec.render.spp}"


class KernelRecord:
    """The renders this machine has compiled kernels for, kept in seahaze's state folder
    (``$SEAHAZE_STATE_DIR/kernels.json``): a hint for the estimate, never a reason to refuse.
    drjit's own cache may be emptied behind its back; then a render compiles again and takes
    longer than estimated."""

    def __init__(self, keys: Iterable[str] = ()):
        self.keys = list(dict.fromkeys(keys))

    @staticmethod
    def path() -> Path:
        from ..dataset.owned import state_dir

        return state_dir() / KERNEL_RECORD_NAME

    @classmethod
    def load(cls) -> KernelRecord:
        """The record on this machine; empty when missing or unreadable (it is only a hint)."""
        try:
            path = cls.path()
            if path.stat().st_size > 1 << 20:
                return cls()
            data = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError, RecursionError):
            return cls()
        keys = data.get("kernels") if isinstance(data, dict) else None
        if not isinstance(keys, list):
            return cls()
        return cls(k for k in keys if isinstance(k, str) and len(k) < 512)

    def compile_seconds(self, specs: Iterable[SceneSpec]) -> float:
        """Wall seconds the renders of ``specs`` will spend compiling: each kind not compiled
        before costs :data:`COMPILE_S`, each new size or sample count of a known kind
        :data:`RECOMPILE_S`, a render made before nothing."""
        known = set(self.keys)
        kinds = {key.rsplit("/", 2)[0] for key in known}
        seconds = 0.0
        for spec in specs:
            key, kind, mode = kernel_key(spec), kernel_kind(spec), spec.render.mode
            if key in known:
                continue
            seconds += RECOMPILE_S[mode] if kind in kinds else COMPILE_S[mode]
            known.add(key)
            kinds.add(kind)
        return seconds

    def remember(self, specs: Iterable[SceneSpec]) -> None:
        """Add the renders of ``specs`` and write the record (silently skipped when the state
        folder cannot be written: the record only makes estimates better)."""
        added = [kernel_key(spec) for spec in specs]
        self.keys = [k for k in self.keys if k not in added] + list(dict.fromkeys(added))
        self.keys = self.keys[-MAX_KERNEL_RECORDS:]
        with contextlib.suppress(OSError):
            write_json(self.path(), {"format": "seahaze-kernels/1", "kernels": self.keys})


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
            f"{usable_cpus()} core(s); each worker renders with cores/workers threads)"
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


def estimate(
    jobs: Sequence[tuple[SceneSpec, int]],
    kernels: KernelRecord | None = None,
    at_once: int = 1,
) -> Estimate:
    """The time and memory estimate of rendering ``count`` scenes (or frames) like each spec
    (a frame costs what a still scene does), ``at_once`` of them at a time (``--workers``),
    with the compilation ``kernels`` says is still to do (None: the record on this machine)."""
    kernels = KernelRecord.load() if kernels is None else kernels
    serial = parallel = 0.0
    for spec, count in jobs:
        s, p = scene_core_seconds(spec)
        serial, parallel = serial + count * s, parallel + count * p
    scenes = sum(count for _, count in jobs)
    compiling = kernels.compile_seconds(spec for spec, count in jobs if count)
    seconds = (STARTUP_S if scenes else 0.0) + compiling + serial + parallel / usable_cpus()
    peak = max((scene_bytes(spec) for spec, _ in jobs), default=0)
    together = peak * max(min(at_once, scenes), 1)
    if at_once <= 1 and scenes > 1:  # one process: a scene is written while the next renders
        together += max(written_scene_bytes(spec) for spec, _ in jobs)
    return Estimate(seconds, peak, scenes, compiling, together)


def confirmation_needed(job: Estimate, memory: int | None = None) -> str | None:
    """Why the job needs ``--yes`` (None: it does not) on a machine of ``memory`` bytes
    (None: this one)."""
    memory = total_memory() if memory is None else memory
    needed = job.peak_bytes
    if memory and needed > CONFIRM_MEMORY_FRACTION * memory:
        if needed == job.scene_bytes:
            what, verb = "one scene", "needs"
        elif needed < 2 * job.scene_bytes:  # one process: a scene renders, the last is written
            what, verb = "one scene with the last one's images still being written", "needs"
        else:
            what, verb = "the scenes rendered at once", "need"
        return (
            f"{what} {verb} about {needed / 2**30:.1f} GiB of memory and this machine has "
            f"{memory / 2**30:.1f} GiB"
        )
    if job.seconds >= CONFIRM_SECONDS:
        return f"the job takes about {format_duration(job.seconds)}"
    return None
