"""Dataset batches: many scenes, resumable, atomic, locked, parallel (local processes or Dask).

A batch is planned before anything is rendered: every scene file (a *template*) gives one scene,
or with ``count`` (``seahaze render --scenes N``) N scenes named ``<template>_00000`` …, scene
``i`` drawing its camera heading, sun, sea state and vessel layout from the template's
``variation:`` ranges with a seed derived from (master seed, template name, ``i``). Each scene is
then rendered by :func:`seahaze.pipeline.render_scene`, unchanged, in this process, in local
worker processes or as Dask tasks; only this (the coordinating) process writes ``dataset.json``.

Safety, in the order :func:`run_batch` does it:

1. a lock file ``OUT/.seahaze.lock`` (``fcntl.flock``, holding pid and host) refuses a second
   process on the same folder; a lock left by a killed process is taken over with a message;
2. temporary files a killed run left (``.<name>.tmp<pid>``) are removed;
3. the plan is compared with the folder's manifest: another config is refused unless ``force``;
4. ``dataset.json`` lists every planned scene in plan order with its state (``pending``,
   ``done``, ``failed``) and is rewritten atomically after each scene, so a crash, SIGKILL or
   Ctrl-C loses at most the scenes in flight and the same command later renders only what is
   missing. Files are written atomically (temporary name, then rename) and carry no timestamps,
   so a resumed batch ends byte-identical to an uninterrupted one whatever the worker count;
5. a write error (full disk, I/O error) stops the batch, keeps finished scenes ``done`` and
   reports it; another failure marks only its scene ``failed`` and the batch goes on.

Timing goes only to the progress display and the optional JSON-lines log, never into the dataset.
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import re
import signal
import socket
import sys
import threading
import time
import uuid
import zlib
from collections import Counter
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any, Literal

import numpy as np

from . import __version__
from .dataset import (
    CLEAN,
    Layout,
    data_yaml_text,
    level_entries,
    manifest,
    write_coco,
    write_json,
    write_text,
)
from .pipeline import DatasetError, SceneResult, render_scene
from .spec import SceneSpec
from .vessels import CLASS_NAMES
from .visibility import level_name

BATCH_SEED_STREAM = 11
"""Stream of :class:`numpy.random.SeedSequence` that derives scene seeds from the master seed."""
VARIATION_SEED_STREAM = 12
"""Stream that derives, from a scene seed, one generator per varied quantity."""
MAX_SEED = 2**31 - 1
"""Largest ``render.seed`` the schema accepts."""
LOCK_NAME = ".seahaze.lock"
"""Lock file inside the dataset folder; present only while a batch runs (or after a crash)."""
FATAL_ERRNOS = frozenset(
    {
        errno.ENOSPC,
        errno.EDQUOT,
        errno.EIO,
        errno.EROFS,
        errno.EFBIG,
        errno.EACCES,
        errno.EPERM,
        errno.ESTALE,
    }
)
"""Errors of the output storage: every later scene would hit them too, so the batch stops."""

DASK_CONNECT_TIMEOUT_S = 15
"""How long to try reaching a Dask scheduler before giving up."""

EXIT_OK = 0
EXIT_FAILED = 1
EXIT_REFUSED = 2
EXIT_WRITE_ERROR = 3
EXIT_INTERRUPTED = 130

_TMP_FILE = re.compile(r"^\..+\.tmp\d+$")  # imaging.atomic_target's temporary names
_TARGET = {
    "camera_heading_deg": ("camera", "heading_deg"),
    "sun_elevation_deg": ("sun", "elevation_deg"),
    "sun_azimuth_deg": ("sun", "azimuth_deg"),
    "wind_speed": ("sea", "wind_speed"),
    "sea_direction_deg": ("sea", "direction_deg"),
}
"""Each ``variation`` range and the spec field it sets; the order fixes each one's stream."""


class BatchRefusedError(Exception):
    """The batch cannot start (folder locked, other config, bad plan); the message is for the user.

    Nothing in the dataset folder has been changed when this is raised.
    """


class DatasetLockedError(BatchRefusedError):
    """Another seahaze process holds the dataset folder's lock."""


class ConfigChangedError(BatchRefusedError):
    """The folder holds a dataset made with another configuration (and ``force`` is off)."""


class BatchFailedError(RuntimeError):
    """Raised by :func:`seahaze.pipeline.render_dataset` when a batch did not complete."""

    def __init__(self, report: BatchReport):
        self.report = report
        super().__init__(report.message)


# --------------------------------------------------------------------------------------------
# Planning: templates → scenes with their own seeds and varied parameters


@dataclass(frozen=True)
class SceneJob:
    """One scene of a batch: its name, its fully resolved spec and where it came from."""

    name: str
    spec: SceneSpec
    template: str
    index: int | None = None

    def images(self) -> int:
        """Images this scene writes: clean plus one per level."""
        return 1 + len(self.spec.haze.levels)

    def entry(self, status: str) -> dict[str, Any]:
        """This scene's record in ``dataset.json``."""
        return {
            "status": status,
            "seed": self.spec.render.seed,
            "template": self.template,
            "index": self.index,
            "config": self.spec.model_dump(mode="json", by_alias=True),
        }


@dataclass(frozen=True)
class BatchPlan:
    """Every scene of a batch in its canonical order, plus what the manifest's config records."""

    jobs: tuple[SceneJob, ...]
    levels: tuple[float, ...]
    threshold: str
    count: int | None = None
    master_seeds: dict[str, int] = field(default_factory=dict)

    def config(self) -> dict[str, Any]:
        """The manifest's ``config``: dataset-wide settings and, for ``--scenes``, the batch."""
        first = self.jobs[0].spec
        batch = (
            None
            if self.count is None
            else {"scenes_per_template": self.count, "master_seeds": dict(self.master_seeds)}
        )
        return {
            "threshold": self.threshold,
            "mode": first.render.mode,
            "spp": first.render.spp,
            "resolution": list(first.camera.resolution),
            "batch": batch,
        }


def scene_seed(master: int, template: str, index: int) -> int:
    """Seed of scene ``index`` of ``template``: a function of (master seed, template name, index).

    The template name enters through CRC-32 (stable across runs, unlike ``hash``) so two
    templates in one batch draw independent scenes, and adding a template leaves the others'
    scenes unchanged.
    """
    name_key = zlib.crc32(template.encode("utf-8"))
    state = np.random.SeedSequence([master, BATCH_SEED_STREAM, name_key, index]).generate_state(1)
    return int(state[0]) & MAX_SEED


def vary_scene(spec: SceneSpec, seed: int) -> SceneSpec:
    """The scene of a batch with seed ``seed``: ``spec`` with its ``variation`` ranges sampled.

    Every varied quantity has its own random stream, so adding a range to a template does not
    change the values drawn for the others. Values are rounded to 1e-3 (they stay inside their
    ranges, whose ends the schema holds to at most three decimals' worth of meaning).
    """
    variation = spec.variation
    data = spec.model_dump(mode="json", by_alias=True)
    data["render"]["seed"] = seed
    for k, key in enumerate(_TARGET):
        bounds = getattr(variation, key)
        if bounds is None:
            continue
        rng = np.random.default_rng(np.random.SeedSequence([seed, VARIATION_SEED_STREAM, k]))
        low, high = bounds
        value = min(max(round(float(rng.uniform(low, high)), 3), low), high)
        section, name = _TARGET[key]
        data[section][name] = value
        if key == "wind_speed":
            data["sea"]["beaufort"] = None  # a Beaufort force would override the drawn wind
    if variation.resample_sea:
        data["sea"]["seed"] = None  # derived from the scene's render.seed (geometry.py)
    if variation.resample_layout and data["vessels"].get("sample") is not None:
        data["vessels"]["sample"]["seed"] = None
    return SceneSpec.model_validate(data)


def plan_scenes(
    templates: Sequence[tuple[SceneSpec, str]],
    count: int | None = None,
    master_seed: int | None = None,
) -> BatchPlan:
    """The scenes of a batch, in canonical order: templates in the given order, then index.

    ``count`` None: one scene per template, as written. ``count`` N: N scenes per template named
    ``<template>_<i>`` (5 digits or more), each with :func:`scene_seed` of the master seed
    (``master_seed``, else the template's ``render.seed``) and :func:`vary_scene` applied.
    Raises :class:`~seahaze.pipeline.DatasetError` for scenes that cannot share one dataset.
    """
    if not templates:
        raise DatasetError("no scene to render")
    if count is not None and count < 1:
        raise DatasetError(f"the number of scenes must be >= 1, got {count}")
    first, first_name = templates[0]
    for spec, name in templates[1:]:
        if (
            list(spec.haze.levels) != list(first.haze.levels)
            or spec.haze.threshold != first.haze.threshold
        ):
            raise DatasetError(
                f"scene '{name}' has other haze levels or threshold than '{first_name}'; "
                "pass --vis to use the same levels"
            )
    jobs: list[SceneJob] = []
    seeds: dict[str, int] = {}
    if count is None:
        jobs = [SceneJob(name, spec, name) for spec, name in templates]
    else:
        width = max(5, len(str(count - 1)))
        for spec, name in templates:
            master = spec.render.seed if master_seed is None else master_seed
            seeds[name] = master
            for i in range(count):
                seed = scene_seed(master, name, i)
                jobs.append(SceneJob(f"{name}_{i:0{width}d}", vary_scene(spec, seed), name, i))
    counts = Counter(job.name for job in jobs)
    duplicates = sorted(name for name, n in counts.items() if n > 1)
    if duplicates:
        raise DatasetError(
            f"two scenes share the name(s) {duplicates[:5]}; set 'name:' in the YAML"
        )
    return BatchPlan(tuple(jobs), tuple(first.haze.levels), str(first.haze.threshold), count, seeds)


# --------------------------------------------------------------------------------------------
# The lock


class DatasetLock:
    """An exclusive lock on a dataset folder: ``OUT/.seahaze.lock`` under ``fcntl.flock``.

    The kernel drops a flock when its process dies, however it dies, so a lock file left by a
    killed run is free and is taken over (with a message naming the old pid). The file holds the
    pid and host of its owner so a refused process can say who holds it. It is removed on exit.
    """

    def __init__(self, root: Path, warn: Callable[[str], None] = lambda _msg: None):
        self.path = root / LOCK_NAME
        self.warn = warn
        self._fd: int | None = None

    def __enter__(self) -> DatasetLock:
        import fcntl

        while True:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = _read_fd(fd).strip() or "unknown process"
                os.close(fd)
                raise DatasetLockedError(
                    f"{self.path.parent} is in use by another seahaze process ({holder}); "
                    f"wait for it to finish or stop it (lock file {self.path})"
                ) from None
            # The previous owner unlinks the file when it finishes: if that happened between our
            # open and flock, we hold a lock on a deleted file and must start over.
            try:
                same = os.stat(self.path).st_ino == os.fstat(fd).st_ino
            except FileNotFoundError:
                same = False
            if same:
                break
            os.close(fd)
        previous = _read_fd(fd).strip()
        me = f"pid {os.getpid()} on {socket.gethostname()}"
        if previous and previous != me:
            self.warn(f"taking over the lock left by {previous}, which no longer runs")
        os.ftruncate(fd, 0)
        os.pwrite(fd, (me + "\n").encode(), 0)
        self._fd = fd
        return self

    def __exit__(self, *exc: object) -> None:
        if self._fd is not None:
            with contextlib.suppress(OSError):
                self.path.unlink()
            os.close(self._fd)
            self._fd = None


def _read_fd(fd: int) -> str:
    try:
        return os.pread(fd, 4096, 0).decode("utf-8", "replace")
    except OSError:
        return ""


# --------------------------------------------------------------------------------------------
# Progress: console (bar or lines) and a JSON-lines log


class Reporter:
    """Progress of a batch: a bar (or one line per scene when stderr is not a terminal), the
    per-pass messages of in-process renders, and an optional JSON-lines log for batch systems.

    Per-pass messages of in-process renders go into the bar's label on a terminal, and are
    printed otherwise only when a single scene renders (many scenes get one line each).
    ``quiet`` silences the bar and messages but not warnings; ``notes`` receives every message
    instead of the console. Log lines carry ``time`` (Unix seconds) and ``event``: ``start``,
    ``scene_done`` (with per-pass seconds), ``scene_failed``, ``end``. The log is appended to,
    so a resumed batch continues the same file.
    """

    def __init__(
        self,
        *,
        quiet: bool = False,
        log: Path | None = None,
        stream: IO[str] | None = None,
        bar: bool | None = None,
        notes: Callable[[str], None] | None = None,
    ):
        self.quiet = quiet
        self._notes = notes
        self.stream = stream or sys.stderr
        self.use_bar = (not quiet) and (self.stream.isatty() if bar is None else bar)
        self._log = open(log, "a", encoding="utf-8", buffering=1) if log else None  # noqa: SIM115
        self._bar: Any = None
        self._start = time.perf_counter()
        self._planned = self._done = self._images = self._failed = 0
        self._done_before = self._to_render = 0

    def _event(self, event: str, **data: Any) -> None:
        if self._log is not None:
            record = {"time": round(time.time(), 3), "event": event, **data}
            try:
                self._log.write(json.dumps(record, allow_nan=False) + "\n")
            except (OSError, ValueError) as err:
                # The log is for people watching; losing it must not stop the dataset.
                self._log = None
                self.warn(f"cannot write the --log file any more ({err}); continuing without")

    def _print(self, message: str) -> None:
        if self._bar is not None:
            self._bar.write(message, file=self.stream)
        else:
            print(message, file=self.stream, flush=True)

    def note(self, message: str) -> None:
        """An informational message (per-pass timings of in-process renders, resume notes)."""
        if self._notes is not None:
            self._notes(message)
        elif not self.quiet:
            self._print(f"[seahaze] {message}")

    def pass_note(self, message: str) -> None:
        """Progress inside one scene (a pass finished), from in-process renders."""
        if self._notes is not None:
            self._notes(message)
        elif self._bar is not None:
            self._bar.set_description_str(message[:60], refresh=True)
        elif not self.quiet and self._to_render <= 1:
            self._print(f"[seahaze] {message}")

    def warn(self, message: str) -> None:
        """A message that is shown even with ``quiet`` (lock takeover, re-rendered scenes)."""
        self._print(f"seahaze: warning: {message}")

    def start(self, *, planned: int, done_before: int, to_render: int, **info: Any) -> None:
        """The batch starts: ``planned`` scenes, ``done_before`` of them already done."""
        self._planned, self._done_before, self._to_render = planned, done_before, to_render
        self._done = done_before
        self._start = time.perf_counter()
        self._event("start", planned=planned, done_before=done_before, to_render=to_render, **info)
        if self.use_bar and to_render:
            from tqdm import tqdm

            self._bar = tqdm(
                total=planned,
                initial=done_before,
                unit="scene",
                desc="scenes",
                file=self.stream,
                dynamic_ncols=True,
                smoothing=0.1,
            )

    def _rates(self) -> tuple[float, str]:
        elapsed = max(time.perf_counter() - self._start, 1e-9)
        finished = self._done + self._failed - self._done_before
        images_per_s = self._images / elapsed
        left = self._to_render - finished
        eta = "?" if finished == 0 else _hms(elapsed / finished * left)
        return images_per_s, eta

    def scene_done(self, job: SceneJob, seconds: float, timings: dict[str, float]) -> None:
        """One scene finished and is recorded ``done`` in the manifest."""
        self._done += 1
        self._images += job.images()
        images_per_s, eta = self._rates()
        self._event(
            "scene_done",
            scene=job.name,
            seconds=round(seconds, 3),
            images=job.images(),
            timings={k: round(v, 3) for k, v in timings.items()},
            done=self._done,
            planned=self._planned,
            images_per_s=round(images_per_s, 4),
        )
        self._advance(images_per_s, eta, f"{job.name} ({seconds:.1f} s)")

    def scene_failed(self, job: SceneJob, error: str) -> None:
        """One scene failed and is recorded ``failed``; the batch goes on."""
        self._failed += 1
        images_per_s, eta = self._rates()
        self._event("scene_failed", scene=job.name, error=error)
        self.warn(f"scene {job.name} failed: {error}")
        self._advance(images_per_s, eta, f"{job.name} FAILED")

    def _advance(self, images_per_s: float, eta: str, what: str) -> None:
        if self._bar is not None:
            self._bar.set_description_str("scenes", refresh=False)
            self._bar.update(1)
            failed = f", {self._failed} failed" if self._failed else ""
            self._bar.set_postfix_str(f"{images_per_s:.2f} img/s{failed}", refresh=True)
        elif not self.quiet:
            failed = f", {self._failed} failed" if self._failed else ""
            self._print(
                f"[seahaze] {self._done + self._failed}/{self._planned} scenes{failed}, "
                f"{images_per_s:.2f} images/s, ETA {eta}: {what}"
            )

    def end(self, report: BatchReport) -> None:
        """The batch ended (complete, failed, stopped or interrupted)."""
        if self._bar is not None:
            self._bar.close()
            self._bar = None
        self._event(
            "end",
            outcome=report.outcome,
            planned=report.planned,
            done=report.done,
            rendered=report.rendered,
            failed=sorted(report.failed),
            images=report.images,
            seconds=round(report.seconds, 3),
            message=report.message,
        )

    def close(self) -> None:
        """Close the bar and the log file."""
        if self._bar is not None:
            self._bar.close()
            self._bar = None
        if self._log is not None:
            self._log.close()
            self._log = None


def _hms(seconds: float) -> str:
    seconds = round(seconds)
    return f"{seconds // 3600}:{seconds % 3600 // 60:02d}:{seconds % 60:02d}"


# --------------------------------------------------------------------------------------------
# Executors: where the scenes render. Each yields (scene name, SceneResult or exception).


def render_job(name: str, spec_data: dict[str, Any], root: str) -> SceneResult:
    """Render one scene of a batch: the task a worker process or a Dask worker runs.

    The spec travels as plain JSON data and is validated again here, so a worker with another
    pydantic build still renders exactly the planned scene. :func:`render_scene` selects the
    Mitsuba variant in the worker itself (Mitsuba and drjit state is per process).
    """
    start = time.perf_counter()
    result = render_scene(SceneSpec.model_validate(spec_data), name, Path(root))
    result.timings["total"] = time.perf_counter() - start
    return result


Outcome = tuple[str, "SceneResult | BaseException"]


class _InProcess:
    """Scenes rendered one after another in this process (``--workers 1``)."""

    def __init__(self, jobs: Sequence[SceneJob], root: Path, note: Callable[[str], None]):
        self.jobs, self.root, self.note = jobs, root, note
        self._stop = False

    def results(self) -> Iterator[Outcome]:
        signalled = threading.Event()
        restore = _flag_ignored_sigint(signalled)
        try:
            for job in self.jobs:
                if self._stop:
                    return
                yield job.name, self._render(job, signalled)
        finally:
            restore()

    def _render(self, job: SceneJob, signalled: threading.Event) -> SceneResult | Exception:
        for _attempt in range(3):
            signalled.clear()
            start = time.perf_counter()
            try:
                result = render_scene(job.spec, job.name, self.root, self.note)
            except Exception as err:  # a scene's failure is recorded, not raised
                return err
            if not signalled.is_set():
                result.timings["total"] = time.perf_counter() - start
                return result
            self.note(f"{job.name}: SIGINT (ignored) may have cut a render short; again")
        return RuntimeError("repeated SIGINT while rendering; rerun to render this scene")

    def cancel(self) -> None:
        self._stop = True

    def abort(self) -> None:
        self._stop = True

    def close(self) -> None:
        pass


def _flag_ignored_sigint(signalled: threading.Event) -> Callable[[], None]:
    """Where SIGINT is ignored (a background job), note it instead; returns the undo function.

    During a render Mitsuba installs its own SIGINT handler that cancels the render and then
    passes the signal on: to Python's handler (KeyboardInterrupt, nothing is written) or, when
    SIGINT is ignored, to nobody, so the render returns cut short without an error. Noting the
    signal lets the scene be rendered again instead of written incomplete.
    """
    if threading.current_thread() is not threading.main_thread():
        return lambda: None
    if signal.getsignal(signal.SIGINT) is not signal.SIG_IGN:
        return lambda: None
    signal.signal(signal.SIGINT, lambda _signum, _frame: signalled.set())
    return lambda: signal.signal(signal.SIGINT, signal.SIG_IGN)


def _worker_init(parent_pid: int, threads: int) -> None:
    """Set up a local worker process: own process group, drjit thread count, die with parent."""
    # Ctrl-C at a terminal signals the foreground process group: keep the workers out of it, so
    # the coordinator alone decides (it terminates them). A SIGINT sent to a worker directly
    # raises KeyboardInterrupt (never ignored: see _flag_ignored_sigint) and fails its scene.
    os.setpgrp()
    signal.signal(signal.SIGINT, signal.default_int_handler)
    from .render.variant import find_libllvm

    llvm = find_libllvm()
    if llvm:  # drjit reads it when its LLVM backend starts
        os.environ.setdefault("DRJIT_LIBLLVM_PATH", llvm)
    import drjit as dr

    # K workers on N cores: N/K threads each, not N each (oversubscription slows all of them).
    dr.set_thread_count(threads)

    def watch() -> None:
        # A SIGKILLed coordinator cannot stop its workers; they notice the new parent and quit.
        while os.getppid() == parent_pid:
            time.sleep(0.5)
        os._exit(1)

    threading.Thread(target=watch, daemon=True, name="seahaze-parent-watch").start()


class _LocalPool:
    """Scenes rendered in ``workers`` spawned processes (Mitsuba and drjit are not fork-safe)."""

    def __init__(self, jobs: Sequence[SceneJob], root: Path, workers: int):
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else 1
        self.executor = ProcessPoolExecutor(
            max_workers=workers,
            mp_context=multiprocessing.get_context("spawn"),
            initializer=_worker_init,
            initargs=(os.getpid(), max(1, (cores or 1) // workers)),
        )
        self.futures = {
            self.executor.submit(
                render_job, job.name, job.spec.model_dump(mode="json", by_alias=True), str(root)
            ): job.name
            for job in jobs
        }

    def results(self) -> Iterator[Outcome]:
        from concurrent.futures import as_completed

        for future in as_completed(self.futures):
            if future.cancelled():
                continue
            error = future.exception()
            yield self.futures[future], error if error is not None else future.result()

    def cancel(self) -> None:
        for future in self.futures:
            future.cancel()

    def abort(self) -> None:
        self.cancel()
        # Renders are atomic and deterministic, so killing a worker mid-scene loses nothing
        # but that scene's time; waiting for it could take minutes.
        for process in list(getattr(self.executor, "_processes", {}).values()):
            with contextlib.suppress(Exception):
                process.terminate()

    def close(self) -> None:
        self.executor.shutdown(wait=True, cancel_futures=True)


def connect_dask(scheduler: str) -> Any:
    """A ``distributed.Client`` of the scheduler at ``scheduler``.

    Raises :class:`BatchRefusedError` when dask.distributed is missing or the scheduler cannot
    be reached in :data:`DASK_CONNECT_TIMEOUT_S`.
    """
    try:
        from distributed import Client
    except ImportError:
        raise BatchRefusedError(
            "--executor dask needs dask.distributed: pip install 'dask[distributed]'"
        ) from None
    try:
        return Client(scheduler, timeout=f"{DASK_CONNECT_TIMEOUT_S}s", set_as_default=False)
    except (OSError, TimeoutError, ValueError) as err:
        raise BatchRefusedError(
            f"cannot reach the Dask scheduler at {scheduler!r}: {err}"
        ) from None


class _DaskCluster:
    """Scenes submitted as tasks to an existing Dask distributed scheduler."""

    def __init__(self, jobs: Sequence[SceneJob], root: Path, client: Any):
        self.client = client
        self.futures = {}
        for job in jobs:
            future = self.client.submit(
                render_job,
                job.name,
                job.spec.model_dump(mode="json", by_alias=True),
                str(root),
                key=f"seahaze-{job.name}-{uuid.uuid4().hex[:12]}",  # unique per run
                pure=False,
            )
            self.futures[future.key] = (future, job.name)

    def results(self) -> Iterator[Outcome]:
        from distributed import as_completed

        futures = [f for f, _ in self.futures.values()]
        for future in as_completed(futures, loop=self.client.loop):
            name = self.futures[future.key][1]
            if future.status == "cancelled":
                continue
            if future.status == "error":
                yield name, future.exception()
            else:
                yield name, future.result()

    def cancel(self) -> None:
        pending = [f for f, _ in self.futures.values() if not f.done()]
        if pending:
            self.client.cancel(pending)

    def abort(self) -> None:
        self.cancel()

    def close(self) -> None:
        pass  # the client belongs to run_batch


# --------------------------------------------------------------------------------------------
# The batch


@dataclass(frozen=True)
class BatchOptions:
    """How a batch runs (none of it changes what it renders)."""

    workers: int = 1
    executor: Literal["local", "dask"] = "local"
    scheduler: str | None = None
    force: bool = False


@dataclass
class BatchReport:
    """What a batch did. ``outcome``: ``complete``, ``failed`` (some scenes failed),
    ``write_error`` (stopped by the storage) or ``interrupted``."""

    outcome: str
    planned: int
    done: int
    done_before: int
    rendered: int
    images: int
    seconds: float
    failed: dict[str, str] = field(default_factory=dict)
    message: str = ""
    results: list[SceneResult] = field(default_factory=list)

    @property
    def exit_code(self) -> int:
        """The command's exit status for this outcome."""
        return {
            "complete": EXIT_OK,
            "failed": EXIT_FAILED,
            "write_error": EXIT_WRITE_ERROR,
            "interrupted": EXIT_INTERRUPTED,
        }[self.outcome]


def _is_storage_error(err: BaseException, root: Path) -> bool:
    if not isinstance(err, OSError):
        return False
    if err.errno in FATAL_ERRNOS:
        return True
    filename = getattr(err, "filename", None)
    return bool(filename) and Path(str(filename)).resolve().is_relative_to(root)


def _describe(err: BaseException) -> str:
    text = str(err).strip().splitlines()
    return f"{type(err).__name__}: {text[0] if text else ''}".rstrip(": ")


def _flatten(data: Any, prefix: str = "") -> dict[str, Any]:
    if isinstance(data, dict):
        out: dict[str, Any] = {}
        for key, value in data.items():
            out.update(_flatten(value, f"{prefix}.{key}" if prefix else str(key)))
        return out
    return {prefix: data}


def _with_current_defaults(existing: dict[str, Any]) -> dict[str, Any]:
    """The folder's manifest with each scene's recorded config re-validated by this version's
    schema, so a field added since (at its default, which keeps the old behaviour) is not a
    change. A config that no longer validates is kept as recorded: it differs for real."""
    scenes = existing.get("scenes")
    if not isinstance(scenes, dict):
        return existing
    upgraded = {}
    for name, entry in scenes.items():
        config = entry.get("config") if isinstance(entry, dict) else None
        if isinstance(config, dict):
            try:
                config = SceneSpec.model_validate(config).model_dump(mode="json", by_alias=True)
                entry = {**entry, "config": config}
            except ValueError:
                pass
        upgraded[name] = entry
    return {**existing, "scenes": upgraded}


def _differences(old: dict[str, Any], new: dict[str, Any]) -> list[str]:
    """Human lines for what differs between a folder's manifest and the planned one."""
    lines = []
    for key in ("format", "format_version"):
        if old.get(key) != new[key]:
            return [f"{key} is {old.get(key)!r} there, {new[key]!r} now"]
    for key in ("config", "levels", "classes"):
        a, b = _flatten(old.get(key)), _flatten(new[key])
        for path in sorted(set(a) | set(b)):
            if a.get(path, "(none)") != b.get(path, "(none)"):
                lines.append(
                    f"{path}: {a.get(path, '(none)')!r} there, {b.get(path, '(none)')!r} now"
                )
    old_scenes, new_scenes = old.get("scenes") or {}, new["scenes"]
    gone = [n for n in old_scenes if n not in new_scenes]
    added = [n for n in new_scenes if n not in old_scenes]
    if gone:
        lines.append(f"{len(gone)} scene(s) not in the new config, e.g. {gone[0]}")
    if added:
        lines.append(f"{len(added)} scene(s) not in the folder, e.g. {added[0]}")
    for name, entry in new_scenes.items():
        if name not in old_scenes:
            continue
        a = _flatten({k: v for k, v in old_scenes[name].items() if k not in ("status", "error")})
        b = _flatten({k: v for k, v in entry.items() if k != "status"})
        changed = [p for p in sorted(set(a) | set(b)) if a.get(p, "(none)") != b.get(p, "(none)")]
        if changed:
            p = changed[0]
            more = f" (and {len(changed) - 1} more)" if len(changed) > 1 else ""
            lines.append(
                f"scene {name}: {p} is {a.get(p, '(none)')!r} there, "
                f"{b.get(p, '(none)')!r} now{more}"
            )
    return lines


def _read_manifest(path: Path, force: bool) -> dict[str, Any] | None:
    """The folder's manifest; None where there is none. One that cannot be read is refused,
    or under ``force`` taken as an empty one (so every file not planned is deleted)."""
    if not path.exists():
        return None
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        problem = None if isinstance(data, dict) else "not a seahaze manifest"
    except (OSError, UnicodeDecodeError, ValueError) as err:
        problem = _describe(err)
    if problem is None:
        return data
    if force:
        return {}
    raise ConfigChangedError(
        f"cannot use {path} ({problem}); choose another --out, or --force to replace the dataset"
    )


def _scene_files(layout: Layout, job: SceneJob) -> list[Path]:
    levels = [CLEAN, *(level_name(v) for v in job.spec.haze.levels)]
    files = [layout.meta(job.name), layout.depth(job.name)]
    for level in levels:
        files += [layout.image(level, job.name), layout.label(level, job.name)]
        if job.spec.render.write_exr:
            files.append(layout.exr(level, job.name))
    return files


def _remove_temporaries(root: Path) -> int:
    """Delete temporary files a killed run left behind; returns how many."""
    removed = 0
    for folder, _dirs, files in os.walk(root):
        for name in files:
            if _TMP_FILE.match(name):
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(os.path.join(folder, name))
                    removed += 1
    return removed


def _prune(root: Path, keep_scenes: set[str], keep_levels: set[str]) -> int:
    """Under ``force``: delete files of scenes and levels the new config no longer has."""
    from .metric.dataset import is_level_name

    removed = 0
    for kind in ("images", "labels", "exr"):
        base = root / kind
        if not base.is_dir():
            continue
        for level_dir in base.iterdir():
            if not (level_dir.is_dir() and is_level_name(level_dir.name)):
                continue
            for path in level_dir.iterdir():
                if level_dir.name not in keep_levels or path.stem not in keep_scenes:
                    path.unlink()
                    removed += 1
            if level_dir.name not in keep_levels:
                with contextlib.suppress(OSError):
                    level_dir.rmdir()
    for kind, keep in (("depth", keep_scenes), ("meta", keep_scenes), ("coco", keep_levels)):
        base = root / kind
        for path in base.iterdir() if base.is_dir() else ():
            if path.is_file() and path.stem not in keep:
                path.unlink()
                removed += 1
    return removed


def run_batch(
    plan: BatchPlan,
    root: Path,
    options: BatchOptions | None = None,
    reporter: Reporter | None = None,
) -> BatchReport:
    """Render the planned scenes that ``root`` does not hold yet; see the module docstring.

    Raises :class:`DatasetLockedError` or :class:`ConfigChangedError` (nothing changed in the
    folder) and :class:`BatchRefusedError` for a Dask scheduler that cannot be reached. A
    storage error that prevents even starting (no permission to create ``root``) propagates as
    ``OSError``. Every other outcome is in the returned report.
    """
    options = options or BatchOptions()
    reporter = reporter or Reporter(quiet=True)
    root = Path(root).resolve()
    # Reach the cluster before touching the folder: a refusal leaves everything as it was.
    client = connect_dask(options.scheduler or "") if options.executor == "dask" else None
    try:
        root.mkdir(parents=True, exist_ok=True)
        with DatasetLock(root, reporter.warn):
            batch = _Batch(plan, root, reporter)
            batch.prepare(options.force)
            batch.execute(options, client)
            return batch.finish()
    finally:
        if client is not None:
            with contextlib.suppress(Exception):
                client.close()


class _Batch:
    """The state of one locked batch run: scene states, errors, and the manifest they make."""

    def __init__(self, plan: BatchPlan, root: Path, reporter: Reporter):
        self.plan, self.root, self.reporter = plan, root, reporter
        self.started = time.perf_counter()
        self.layout = Layout(root)
        self.jobs = {job.name: job for job in plan.jobs}
        self.levels = level_entries(list(plan.levels), plan.threshold)
        self.level_dirs = {CLEAN, *(entry["name"] for entry in self.levels)}
        self.status = dict.fromkeys(self.jobs, "pending")
        self.errors: dict[str, str] = {}
        self.stop: tuple[str, str] | None = None  # (outcome, reason) once the batch must stop
        self.report = BatchReport("complete", len(self.jobs), 0, 0, 0, 0, 0.0)

    def manifest(self) -> dict[str, Any]:
        """``dataset.json`` for the current states, scenes in plan order (never finish order)."""
        scenes = {}
        for name, job in self.jobs.items():
            scenes[name] = job.entry(self.status[name])
            if name in self.errors:
                scenes[name]["error"] = self.errors[name]
        return manifest(self.plan.config(), self.levels, CLASS_NAMES, scenes)

    def write_manifest(self) -> None:
        """Write ``dataset.json`` atomically."""
        write_json(self.layout.manifest, self.manifest())

    def prepare(self, force: bool) -> None:
        """Check the folder against the plan, clean it up, and find the scenes still to render."""
        planned = self.manifest()
        existing = _read_manifest(self.layout.manifest, force)
        if existing is not None:
            existing = _with_current_defaults(existing)
        changes = _differences(existing, planned) if existing is not None else []
        if changes and not force:
            shown = "\n  ".join(changes[:6])
            more = f"\n  … and {len(changes) - 6} more" if len(changes) > 6 else ""
            raise ConfigChangedError(
                f"{self.root} holds a dataset made with another configuration:\n  {shown}{more}"
                "\nRerun with --force to re-render what changed (unchanged scenes are kept, "
                "files of scenes and levels no longer configured are deleted), or choose "
                "another --out."
            )
        # From here on the folder is ours and its config is the planned one.
        written_by = (existing or {}).get("seahaze_version")
        if written_by and written_by != __version__:
            self.reporter.warn(
                f"{self.root} was written by seahaze {written_by}, this is {__version__}: "
                "scenes rendered now may differ from those already done"
            )
        removed = _remove_temporaries(self.root)
        if removed:
            self.reporter.note(f"removed {removed} temporary file(s) left by an interrupted run")
        if changes:
            pruned = _prune(self.root, set(self.jobs), self.level_dirs)
            self.reporter.warn(
                f"--force: the configuration changed ({len(changes)} difference(s)); deleted "
                f"{pruned} file(s) of scenes or levels no longer configured"
            )
        old_scenes = (existing or {}).get("scenes") or {}
        for name, job in self.jobs.items():
            old = old_scenes.get(name) or {}
            same = all(old.get(k) == v for k, v in planned["scenes"][name].items() if k != "status")
            if not (same and old.get("status") == "done"):
                continue
            if all(path.exists() for path in _scene_files(self.layout, job)):
                self.status[name] = "done"
            else:
                self.reporter.warn(f"scene {name} is marked done but files are missing: re-render")
        self.report.done_before = sum(s == "done" for s in self.status.values())
        pending = len(self.jobs) - self.report.done_before
        if self.report.done_before and pending:
            self.reporter.note(
                f"resuming: {self.report.done_before} of {len(self.jobs)} scenes already done, "
                f"{pending} to render"
            )
        level_names = [entry["name"] for entry in self.levels]
        write_text(self.layout.data_yaml, data_yaml_text(self.root, level_names, CLASS_NAMES))
        self.write_manifest()
        if pending:
            # COCO files describe every scene of a level: stale until the last scene is done.
            for level in self.level_dirs:
                self.layout.coco(level).unlink(missing_ok=True)

    def execute(self, options: BatchOptions, client: Any) -> None:
        """Render the pending scenes, recording each as it finishes; stop on storage errors."""
        pending = [job for name, job in self.jobs.items() if self.status[name] != "done"]
        self.reporter.start(
            planned=len(self.jobs),
            done_before=self.report.done_before,
            to_render=len(pending),
            executor=options.executor,
            workers=options.workers,
            root=str(self.root),
        )
        if not pending:
            return
        runner: Any = None
        restore_sigterm = _sigterm_raises_interrupt()
        try:
            if client is not None:
                runner = _DaskCluster(pending, self.root, client)
            elif options.workers > 1 and len(pending) > 1:
                runner = _LocalPool(pending, self.root, min(options.workers, len(pending)))
            else:
                runner = _InProcess(pending, self.root, self.reporter.pass_note)
            for name, outcome in runner.results():
                if self._record(self.jobs[name], outcome) and self.stop is not None:
                    runner.cancel()  # let running scenes finish, start no more
        except KeyboardInterrupt:
            self.stop = ("interrupted", "interrupted")
            if runner is not None:
                runner.abort()
        finally:
            if runner is not None:
                with contextlib.suppress(Exception):
                    runner.close()
            restore_sigterm()

    def _record(self, job: SceneJob, outcome: SceneResult | BaseException) -> bool:
        """Record one finished scene; True when this made the batch stop."""
        stopping = self.stop is None
        if isinstance(outcome, BaseException):
            if _is_storage_error(outcome, self.root):
                if self.stop is None:
                    self.stop = ("write_error", f"cannot write scene {job.name}: {outcome}")
                return stopping
            self.errors[job.name] = _describe(outcome)
            self.status[job.name] = "failed"
            self.reporter.scene_failed(job, self.errors[job.name])
        else:
            self.status[job.name] = "done"
            self.errors.pop(job.name, None)
            self.report.results.append(outcome)
            self.report.rendered += 1
            self.report.images += job.images()
            self.reporter.scene_done(job, outcome.timings.get("total", 0.0), outcome.timings)
        try:
            self.write_manifest()
        except OSError as err:
            if self.stop is None:
                self.stop = ("write_error", f"cannot write {self.layout.manifest}: {err}")
        return stopping and self.stop is not None

    def finish(self) -> BatchReport:
        """Write the last manifest (and the COCO files when every scene is done); the report."""
        try:
            self.write_manifest()
            if all(s == "done" for s in self.status.values()):
                write_coco(self.root)
        except OSError as err:
            if self.stop is None or self.stop[0] != "write_error":
                self.stop = ("write_error", f"cannot write the manifest or COCO files: {err}")
        report, total = self.report, len(self.jobs)
        report.done = sum(s == "done" for s in self.status.values())
        report.failed = dict(self.errors)
        report.seconds = time.perf_counter() - self.started
        if self.stop is not None and self.stop[0] == "write_error":
            report.outcome = "write_error"
            report.message = (
                f"{self.stop[1]}; stopped with {report.done} of {total} scenes done (kept). "
                "Fix the storage (free space, permissions) and rerun the same command to resume."
            )
        elif self.stop is not None:
            report.outcome = "interrupted"
            report.message = (
                f"interrupted with {report.done} of {total} scenes done; rerun the same command "
                f"to render the other {total - report.done}"
            )
        elif self.errors:
            report.outcome = "failed"
            report.message = (
                f"{len(self.errors)} of {total} scenes failed "
                f"({', '.join(sorted(self.errors)[:5])}); rerun the same command to retry them"
            )
        self.reporter.end(report)
        return report


def _sigterm_raises_interrupt() -> Callable[[], None]:
    """Make SIGTERM (a batch system at its time limit) stop the batch like Ctrl-C.

    Returns the function that restores the previous handler. Signal handlers can only be set
    from the main thread; elsewhere this does nothing.
    """
    if threading.current_thread() is not threading.main_thread():
        return lambda: None

    def handler(_signum: int, _frame: Any) -> None:
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, handler)
    return lambda: signal.signal(signal.SIGTERM, previous)
