"""Running a planned batch into a dataset folder: locked, resumable, atomic.

Safety, in the order :func:`run_batch` does it:

0. a folder seahaze did not make (a file, other files, another program's ``dataset.json``) is
   refused before anything is written into it, ``force`` or not;
1. a lock file ``OUT/.seahaze.lock`` (:class:`~seahaze.batch.lock.DatasetLock`) refuses a second
   process on the same folder; a lock left by a killed process is taken over with a message;
2. temporary files a killed run left (``.<name>.tmp<pid>``) are removed;
3. the plan is compared with the folder's manifest: another config is refused unless ``force``
   (which then deletes only files the old manifest lists); a damaged manifest of seahaze's is
   refused unless ``force`` (which keeps it as ``dataset.json.damaged`` and renders every
   scene); images or labels in the level folders that are not the dataset's are refused (the
   COCO files are built from every one of them); a scene marked done is kept only if each of
   its files is there and intact (header and end read), else it is rendered again;
4. ``dataset.json`` lists every planned scene in plan order with its state (``pending``,
   ``done``, ``failed``) and is rewritten atomically after each scene, so a crash, SIGKILL or
   Ctrl-C loses at most the scenes in flight and the same command later renders only what is
   missing. Files are written atomically and carry no timestamps, so a resumed batch ends
   byte-identical to an uninterrupted one whatever the worker count;
5. a write error (full disk, I/O error) stops the batch, keeps finished scenes ``done`` and
   reports it; another failure marks only its scene ``failed`` and the batch goes on.

Only this (the coordinating) process writes ``dataset.json``. Timing goes only to the progress
display and the optional JSON-lines log, never into the dataset.
"""

from __future__ import annotations

import contextlib
import errno
import signal
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from .. import __version__
from ..dataset import Layout, data_yaml_text, level_entries, manifest, split_list_text
from ..dataset.card import remove_card, write_card
from ..dataset.splits import SPLIT_NAMES
from ..dataset.tracks import write_tracks
from ..fileio import write_json, write_text
from ..interrupts import on_hard_stop
from ..metric.errors import MetricInputError
from ..metric.ground_truth import write_coco
from ..vessels import CLASS_NAMES
from ..visibility import CLEAN_LEVEL, is_level_name, level_name
from .dask_connect import DASK_WAIT_S
from .errors import ConfigChangedError, DamagedManifestError, ForeignFolderError
from .executors import SceneDone, connect_dask, start_executor
from .folder import (
    comparable,
    damaged_message,
    describe_error,
    differences,
    inspect_folder,
    keep_damaged,
    prune,
    recorded_digest,
    remove_temporaries,
    scene_digest,
    scene_file_problem,
    stray_files,
    with_current_defaults,
)
from .lock import DatasetLock
from .plan import BatchPlan, SceneJob
from .progress import Reporter
from .report import BatchReport

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


@dataclass(frozen=True)
class BatchOptions:
    """How a batch runs (none of it changes what it renders)."""

    workers: int = 1
    executor: Literal["local", "dask"] = "local"
    scheduler: str | None = None
    dask_wait: float = DASK_WAIT_S
    """Seconds to wait for a first worker of a Dask scheduler that has none."""
    force: bool = False
    threads: int | None = None
    """drjit threads of the local renders, shared by the workers (None: the CPUs this process
    may use, :func:`seahaze.cpus.usable_cpus`); a Dask worker keeps its own."""


def run_batch(
    plan: BatchPlan,
    root: Path,
    options: BatchOptions | None = None,
    reporter: Reporter | None = None,
) -> BatchReport:
    """Render the planned scenes that ``root`` does not hold yet; see the module docstring.

    Raises :class:`~seahaze.batch.errors.DatasetLockedError` or
    :class:`~seahaze.batch.errors.ConfigChangedError` (nothing changed in the folder) and
    :class:`~seahaze.batch.errors.BatchRefusedError` for a Dask scheduler that cannot be
    reached. A storage error that prevents even starting (no permission to create ``root``)
    propagates as ``OSError``. Every other outcome is in the returned report.
    """
    options = options or BatchOptions()
    reporter = reporter or Reporter(quiet=True)
    root = Path(root).resolve()
    inspect_folder(root)  # a folder seahaze did not make is refused before the lock is made
    # Reach the cluster before touching the folder: a refusal leaves everything as it was.
    client = None
    if options.executor == "dask":
        client = connect_dask(options.scheduler or "", wait_s=options.dask_wait, note=reporter.warn)
    try:
        root.mkdir(parents=True, exist_ok=True)
        with DatasetLock(root, reporter.warn) as lock, on_hard_stop(lock.remove_file):
            started = time.perf_counter()
            ledger = open_ledger(plan, root, options.force, reporter)
            stop = render_pending(ledger, options, client, reporter)
            return finish(ledger, stop, time.perf_counter() - started, reporter)
    finally:
        if client is not None:
            with contextlib.suppress(Exception):
                client.close()


@dataclass
class SceneLedger:
    """The state of every planned scene of a locked batch, and the manifest it makes."""

    plan: BatchPlan
    layout: Layout
    status: dict[str, str]
    """Scene name → ``pending``, ``done`` or ``failed``, in plan order."""
    done_before: int = 0
    """Scenes already done when the batch started."""
    errors: dict[str, str] = field(default_factory=dict)
    rendered: list[str] = field(default_factory=list)
    """Scenes rendered by this run, in the order they finished."""
    digests: dict[str, str] = field(default_factory=dict)
    """Scene name → the content hash of its files (``files_sha256``) of the done scenes."""

    @property
    def jobs(self) -> dict[str, SceneJob]:
        return {job.name: job for job in self.plan.jobs}

    @property
    def levels(self) -> list[dict[str, Any]]:
        return level_entries(list(self.plan.levels), self.plan.threshold)

    def manifest(self) -> dict[str, Any]:
        """``dataset.json`` for the current states, scenes in plan order (never finish order)."""
        scenes = {}
        for job in self.plan.jobs:
            scenes[job.name] = job.entry(self.status[job.name])
            if job.name in self.errors:
                scenes[job.name]["error"] = self.errors[job.name]
            if self.status[job.name] == "done" and job.name in self.digests:
                scenes[job.name]["files_sha256"] = self.digests[job.name]
        return manifest(self.plan.config(), self.levels, CLASS_NAMES, scenes)

    def write_manifest(self) -> None:
        """Write ``dataset.json`` atomically."""
        write_json(self.layout.manifest, self.manifest())

    def done(self) -> int:
        return sum(s == "done" for s in self.status.values())

    def digest_of(self, job: SceneJob) -> str:
        """The content hash of ``job``'s files as they are now (OSError when unreadable)."""
        levels = [level_name(v) for v in job.spec.haze.levels]
        visible = job.spec.labels.write_visible
        return scene_digest(self.layout, job.name, levels, job.spec.render.write_exr, visible)


def open_ledger(plan: BatchPlan, root: Path, force: bool, reporter: Reporter) -> SceneLedger:
    """Check the folder against the plan, clean it up, and find the scenes still to render.

    Raises :class:`ConfigChangedError` (nothing changed) for a folder made with another config
    unless ``force``. Writes ``data.yaml`` and the manifest of the planned scenes.
    """
    ledger = SceneLedger(plan, Layout(root), {job.name: "pending" for job in plan.jobs})
    planned = ledger.manifest()
    state = inspect_folder(root)
    if state.damaged and not force:
        raise DamagedManifestError(damaged_message(root, state.damaged))
    existing = with_current_defaults(state.manifest) if state.manifest is not None else None
    changes = differences(existing, planned) if existing is not None else []
    if changes and not force:
        shown = "\n  ".join(changes[:6])
        more = f"\n  … and {len(changes) - 6} more" if len(changes) > 6 else ""
        raise ConfigChangedError(
            f"{root} holds a dataset made with another configuration:\n  {shown}{more}"
            "\nRerun with --force to re-render what changed (unchanged scenes are kept, "
            "files of scenes and levels no longer configured are deleted), or choose "
            "another --out."
        )
    # Refusals come before any change to the folder.
    _refuse_strays_and_blocked(plan, ledger, existing)
    # From here on the folder is ours and its config is the planned one.
    written_by = (existing or {}).get("seahaze_version")
    if written_by and written_by != __version__:
        reporter.warn(
            f"{root} was written by seahaze {written_by}, this is {__version__}: "
            "scenes rendered now may differ from those already done"
        )
    removed = remove_temporaries(root)
    if removed:
        reporter.note(f"removed {removed} temporary file(s) left by an interrupted run")
    level_names = [entry["name"] for entry in ledger.levels]
    if state.damaged:
        kept = keep_damaged(ledger.layout.manifest)
        reporter.warn(
            f"--force: {ledger.layout.manifest} was damaged ({state.damaged}); kept as "
            f"{kept.name}, every scene is rendered again, no file was deleted"
        )
    if changes:
        assert existing is not None
        pruned = prune(root, existing, set(ledger.status), {CLEAN_LEVEL, *level_names})
        reporter.warn(
            f"--force: the configuration changed ({len(changes)} difference(s)); deleted "
            f"{pruned} file(s) of scenes or levels no longer configured"
        )
    _mark_done_scenes(ledger, (existing or {}).get("scenes") or {}, planned["scenes"], reporter)
    pending = len(plan.jobs) - ledger.done_before
    if ledger.done_before and pending:
        reporter.note(
            f"resuming: {ledger.done_before} of {len(plan.jobs)} scenes already done, "
            f"{pending} to render"
        )
    write_split_files(ledger, existing, level_names)
    ledger.write_manifest()
    if pending:
        # COCO, track files and the card describe every scene: stale until the last is done.
        sequences = {job.sequence for job in plan.jobs if job.sequence is not None}
        for level in [CLEAN_LEVEL, *level_names]:
            ledger.layout.coco(level).unlink(missing_ok=True)
            ledger.layout.coco_visible(level).unlink(missing_ok=True)
            for seq in sorted(sequences):
                ledger.layout.mot_gt(level, seq).unlink(missing_ok=True)
                ledger.layout.mot_seqinfo(level, seq).unlink(missing_ok=True)
        remove_card(root)
    return ledger


def _refuse_strays_and_blocked(
    plan: BatchPlan, ledger: SceneLedger, existing: dict[str, Any] | None
) -> None:
    """Refuse images and labels in level folders that are neither planned nor listed by the
    folder's manifest (the COCO writer reads every one), and a folder where a planned file
    goes. Files the old manifest lists are the dataset's: ``--force`` may prune them."""
    root = ledger.layout.root
    old = existing or {}
    scenes = {*ledger.status, *(old.get("scenes") or {})}
    levels = {
        CLEAN_LEVEL,
        *(e["name"] for e in ledger.levels),
        *(e["name"] for e in old.get("levels", [])),
    }
    strays = stray_files(root, scenes, levels)
    if strays:
        more = f" and {len(strays) - 1} more" if len(strays) > 1 else ""
        raise ForeignFolderError(
            f"{root} holds files that are not this dataset's: {strays[0]}{more}. The COCO "
            "files are built from every image and label in the level folders: move them out "
            "of the folder (or delete them) and rerun"
        )
    # The COCO writer takes every level-named folder under images/ as a level.
    planned = {CLEAN_LEVEL, *(e["name"] for e in ledger.levels)}
    listed = {e["name"] for e in old.get("levels", [])}
    images = root / "images"
    for folder in sorted(images.iterdir()) if images.is_dir() else ():
        if folder.name in planned or not is_level_name(folder.name) or not folder.is_dir():
            continue
        kept = [
            p
            for p in sorted(folder.iterdir())
            if not (folder.name in listed and p.suffix == ".png" and p.stem in scenes)
        ]
        if kept or folder.name not in listed:
            what = kept[0].relative_to(root) if kept else folder.relative_to(root)
            raise ForeignFolderError(
                f"{root} holds {what}, in a level folder that is not this dataset's level "
                f"and that seahaze did not write; the COCO files are built from every level "
                "folder in images/: move it out of the folder and rerun"
            )
    for job in plan.jobs:
        levels_of_job = [level_name(v) for v in job.spec.haze.levels]
        exr, visible = job.spec.render.write_exr, job.spec.labels.write_visible
        for path in ledger.layout.scene_files(job.name, levels_of_job, exr, visible):
            if path.exists() and not path.is_file():
                raise ForeignFolderError(
                    f"{path} is not a file, but seahaze writes one there: move it out of the "
                    "folder and rerun"
                )


def write_split_files(
    ledger: SceneLedger,
    existing: dict[str, Any] | None,
    level_names: list[str],
) -> None:
    """Write ``data.yaml`` and, with a split, each split's image list; delete the lists of
    splits the folder's previous config had and this one has not. A split that got no scene
    has share 0 in ``plan.split`` and no list (the plan's split line says so)."""
    layout, split = ledger.layout, ledger.plan.split
    fractions = split.as_dict() if split else {}
    names = [name for name in SPLIT_NAMES if fractions.get(name, 0) > 0]
    write_text(layout.data_yaml, data_yaml_text(layout.root, level_names, CLASS_NAMES, names))
    members: dict[str, list[str]] = {name: [] for name in names}
    for job in ledger.plan.jobs:
        if job.split is not None:
            members[job.split].append(job.name)
    for name, scenes in members.items():
        write_text(layout.split_list(name), split_list_text(scenes))
    before = ((existing or {}).get("config") or {}).get("split") or {}
    for name in SPLIT_NAMES:
        if before.get(name, 0) > 0 and name not in members:
            layout.split_list(name).unlink(missing_ok=True)


def _without_split(entry: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in entry.items() if k != "split"}


def _mark_done_scenes(
    ledger: SceneLedger,
    old_scenes: dict[str, Any],
    planned_scenes: dict[str, Any],
    reporter: Reporter,
) -> None:
    """Mark ``done`` the scenes the folder holds, finished, with the planned config, and
    whose files are the ones seahaze wrote: intact, and with the content hash recorded when
    they were written (a file swapped with another scene's has its size and header right).
    A record without a hash (made before seahaze kept one) gets the hash of the files now."""
    for job in ledger.plan.jobs:
        old = old_scenes.get(job.name) or {}
        # A scene's split is bookkeeping, not rendering: a new split keeps its files.
        same = _without_split(comparable(old)) == _without_split(
            comparable(planned_scenes[job.name])
        )
        if not (same and old.get("status") == "done"):
            continue
        levels = [level_name(v) for v in job.spec.haze.levels]
        exr, size = job.spec.render.write_exr, job.spec.camera.resolution
        visible = job.spec.labels.write_visible
        problem = scene_file_problem(ledger.layout, job.name, levels, exr, size, visible)
        if problem is None:
            problem, digest = _content_problem(ledger, job, old)
        if problem is None:
            ledger.status[job.name] = "done"
            ledger.digests[job.name] = digest
        else:
            reporter.warn(f"scene {job.name} is marked done but {problem}: rendering it again")
    ledger.done_before = ledger.done()


def _content_problem(
    ledger: SceneLedger, job: SceneJob, old: dict[str, Any]
) -> tuple[str | None, str]:
    """Whether a finished scene's files still hash to what its record says: (problem or
    None, their hash now)."""
    try:
        digest = ledger.digest_of(job)
    except OSError as err:
        return f"a file of it cannot be read ({err.strerror or err})", ""
    recorded = recorded_digest(old)
    if "files_sha256" in old and recorded is None:
        return "its record's files_sha256 is not a SHA-256", digest
    if recorded is not None and recorded != digest:
        return "its files are not the ones seahaze wrote (their content hash differs)", digest
    return None, digest


Stop = tuple[str, str]
"""Why a batch stopped early: (outcome, reason), outcome ``write_error`` or ``interrupted``."""


def render_pending(
    ledger: SceneLedger, options: BatchOptions, client: Any, reporter: Reporter
) -> Stop | None:
    """Render the pending scenes, recording each as it finishes; stop on storage errors."""
    jobs = ledger.jobs
    pending = [jobs[name] for name, status in ledger.status.items() if status != "done"]
    reporter.start(
        planned=len(jobs),
        done_before=ledger.done_before,
        to_render=len(pending),
        executor=options.executor,
        workers=options.workers,
        root=str(ledger.layout.root),
    )
    if not pending:
        return None
    stop: Stop | None = None
    runner: Any = None
    restore_sigterm = _sigterm_raises_interrupt()
    try:
        runner = start_executor(
            pending,
            ledger.layout.root,
            options.workers,
            client,
            reporter.pass_note,
            reporter.heartbeat,
            options.threads,
        )
        for name, outcome in runner.results():
            stopping = stop is None
            stop = _record(ledger, jobs[name], outcome, stop, reporter)
            if stopping and stop is not None:
                runner.cancel()  # let running scenes finish, start no more
    except KeyboardInterrupt:
        stop = ("interrupted", "interrupted")
        if runner is not None:
            runner.abort()
    finally:
        if runner is not None:
            with contextlib.suppress(Exception):
                runner.close()
        restore_sigterm()
    return stop


def _record(
    ledger: SceneLedger,
    job: SceneJob,
    outcome: SceneDone | BaseException,
    stop: Stop | None,
    reporter: Reporter,
) -> Stop | None:
    """Record one finished scene and rewrite the manifest; returns the batch's stop reason."""
    root = ledger.layout.root
    if isinstance(outcome, BaseException):
        if _is_storage_error(outcome, root):
            return stop or ("write_error", f"cannot write scene {job.name}: {outcome}")
        ledger.errors[job.name] = describe_error(outcome)
        ledger.status[job.name] = "failed"
        reporter.scene_failed(job, ledger.errors[job.name])
    else:
        ledger.status[job.name] = "done"
        ledger.errors.pop(job.name, None)
        ledger.rendered.append(job.name)
        try:
            ledger.digests[job.name] = ledger.digest_of(job)
        except OSError as err:  # the files just written cannot be read back
            return stop or ("write_error", f"cannot read back scene {job.name}: {err}")
        reporter.scene_done(job, outcome.timings.get("total", 0.0), outcome.timings)
    try:
        ledger.write_manifest()
    except OSError as err:
        return stop or ("write_error", f"cannot write {ledger.layout.manifest}: {err}")
    return stop


def finish(
    ledger: SceneLedger, stop: Stop | None, seconds: float, reporter: Reporter
) -> BatchReport:
    """Write the last manifest (and the COCO files when every scene is done); the report."""
    coco_error = None
    try:
        ledger.write_manifest()
        if all(s == "done" for s in ledger.status.values()):
            write_coco(ledger.layout.root)
            write_tracks(ledger.layout.root)
            if not write_card(ledger.layout.root):
                reporter.warn(
                    f"{ledger.layout.card} was not written by seahaze: kept, no dataset card"
                )
    except OSError as err:
        if stop is None or stop[0] != "write_error":
            stop = ("write_error", f"cannot write the manifest or COCO files: {err}")
    except MetricInputError as err:  # a file appeared in a level folder during the run
        coco_error = str(err)
    jobs, total = ledger.jobs, len(ledger.status)
    report = BatchReport(
        "complete",
        total,
        ledger.done(),
        ledger.done_before,
        len(ledger.rendered),
        sum(jobs[name].images() for name in ledger.rendered),
        seconds,
        dict(ledger.errors),
    )
    if stop is not None and stop[0] == "write_error":
        report.outcome = "write_error"
        report.message = (
            f"{stop[1]}; stopped with {report.done} of {total} scenes done (kept). "
            "Fix the storage (free space, permissions) and rerun the same command to resume."
        )
    elif stop is not None:
        report.outcome = "interrupted"
        report.message = (
            f"interrupted with {report.done} of {total} scenes done; rerun the same command "
            f"to render the other {total - report.done}"
        )
    elif coco_error:
        report.outcome = "failed"
        report.message = (
            f"every scene is done but the COCO files cannot be written: {coco_error}; move "
            "the files seahaze did not write out of the folder and rerun the same command"
        )
    elif ledger.errors:
        report.outcome = "failed"
        report.message = (
            f"{len(ledger.errors)} of {total} scenes failed "
            f"({', '.join(sorted(ledger.errors)[:5])}); rerun the same command to retry them"
        )
    reporter.end(report)
    return report


def _is_storage_error(err: BaseException, root: Path) -> bool:
    if not isinstance(err, OSError):
        return False
    if err.errno in FATAL_ERRNOS:
        return True
    filename = getattr(err, "filename", None)
    return bool(filename) and Path(str(filename)).resolve().is_relative_to(root)


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
