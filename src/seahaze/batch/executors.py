"""Where the scenes of a batch render: in this process, in local worker processes, or as
tasks on a Dask cluster. Each executor yields ``(scene name, SceneDone or exception)``."""

from __future__ import annotations

import contextlib
import os
import signal
import threading
import time
import uuid
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..cpus import render_threads, usable_cpus
from ..dataset.layout import Layout
from ..dataset.writer import write_scene
from ..interrupts import STOP_SIGNALS, WAIT_STEP_S, stoppable
from ..render.engine import SceneRender, render_scene
from ..spec import SceneSpec

# Reaching a scheduler lives in its own module; the names stay importable from here.
from .dask_connect import DASK_CONNECT_TIMEOUT_S as DASK_CONNECT_TIMEOUT_S
from .dask_connect import connect_dask as connect_dask
from .plan import SceneJob


@dataclass
class SceneDone:
    """A scene rendered and written: its name and wall-clock seconds per pass."""

    name: str
    timings: dict[str, float]


def render_job(
    name: str, spec_data: dict[str, Any], root: str, frame: int | None = None
) -> SceneDone:
    """Render one scene of a batch and write its files: the task a worker process or a Dask
    worker runs.

    The spec travels as plain JSON data and is validated again here, so a worker with another
    pydantic build still renders exactly the planned scene. The render selects the Mitsuba
    variant in the worker itself (Mitsuba and drjit state is per process); only the small
    :class:`SceneDone` travels back. ``frame``: the frame of a sequence this job renders.
    """
    start = time.perf_counter()
    scene = render_scene(SceneSpec.model_validate(spec_data), name, frame=frame)
    write_scene(Layout(Path(root)), scene)
    scene.timings["total"] = time.perf_counter() - start
    return SceneDone(name, scene.timings)


Outcome = tuple[str, "SceneDone | BaseException"]


class _InProcess:
    """Scenes rendered one after another in this process (``--workers 1``), drjit's pool at
    ``threads`` threads (None: the CPUs this process may use) while they render.

    Each scene's files are written on a second thread while the next scene renders (PNG and
    EXR compression release the GIL), and its outcome is given once they are all written, so
    a scene is never recorded done before its files are complete. Stopped during a render, the
    previous scene's files are finished but it is not recorded: a resumed batch renders it
    again (the same bytes)."""

    def __init__(
        self,
        jobs: Sequence[SceneJob],
        root: Path,
        note: Callable[[str], None],
        tick: Callable[[], None] | None = None,
        threads: int | None = None,
    ):
        self.jobs, self.root, self.note, self.tick = jobs, root, note, tick
        self.threads = threads
        self._stop = False
        self._signals = STOP_SIGNALS

    def results(self) -> Iterator[Outcome]:
        signalled = threading.Event()
        # A background job ignores Ctrl-C (SIGINT is SIG_IGN): only SIGTERM stops its renders.
        ignored = signal.getsignal(signal.SIGINT) is signal.SIG_IGN
        self._signals = (signal.SIGTERM,) if ignored else STOP_SIGNALS
        restore = _flag_ignored_sigint(signalled)
        writing: _Writing | None = None
        try:
            # Threads matched to the CPUs this process may use: drjit's default is every core
            # of the machine, and its kernels wait for their slowest thread.
            with render_threads(self.threads), ThreadPoolExecutor(1) as writer:
                for job in self.jobs:
                    if self._stop:
                        break
                    start = time.perf_counter()
                    rendered = self._render(job, signalled)
                    if writing is not None:  # the previous scene, written meanwhile
                        yield writing.outcome()
                        writing = None
                    if isinstance(rendered, Exception):
                        yield job.name, rendered
                    elif not self._stop:  # a stop while the previous scene was recorded
                        write = writer.submit(write_scene, Layout(self.root), rendered)
                        rendered_s = time.perf_counter() - start
                        writing = _Writing(job.name, rendered.timings, rendered_s, write)
                if writing is not None:
                    yield writing.outcome()
        finally:
            restore()

    def _render(self, job: SceneJob, signalled: threading.Event) -> SceneRender | Exception:
        for _attempt in range(3):
            signalled.clear()
            try:
                with stoppable(self.tick, self._signals):
                    scene = render_scene(job.spec, job.name, self.note, job.frame)
            except Exception as err:  # a scene's failure is recorded, not raised
                return err
            # Files are written only after the whole scene rendered, so a render cut short
            # by an ignored SIGINT never reaches the folder.
            if not signalled.is_set():
                return scene
            self.note(f"{job.name}: SIGINT (ignored) may have cut a render short; again")
        return RuntimeError("repeated SIGINT while rendering; rerun to render this scene")

    def cancel(self) -> None:
        self._stop = True

    def abort(self) -> None:
        self._stop = True

    def close(self) -> None:
        pass


@dataclass
class _Writing:
    """A rendered scene whose files a writer thread is writing."""

    name: str
    timings: dict[str, float]
    rendered_s: float
    """Seconds its render took."""
    write: Future[None]

    def outcome(self) -> Outcome:
        """Once its files are written: the scene done, or the write's error. Its ``total`` is
        the batch's time it took: its render and the wait for its files once the next scene
        had rendered (all of the writing for the last scene), so the totals of a batch add up
        to its wall time, start-up and the record kept between scenes aside."""
        waiting = time.perf_counter()
        try:
            self.write.result()
        except Exception as err:  # a scene's failure is recorded, not raised
            return self.name, err
        self.timings["total"] = self.rendered_s + time.perf_counter() - waiting
        return self.name, SceneDone(self.name, self.timings)


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
    from ..render.variant import find_libllvm

    llvm = find_libllvm()
    if llvm:  # drjit reads it when its LLVM backend starts
        os.environ.setdefault("DRJIT_LIBLLVM_PATH", llvm)
    import drjit as dr

    # K workers on N CPUs: N/K threads each, not N each (oversubscription slows all of them).
    dr.set_thread_count(threads)

    def watch() -> None:
        # A SIGKILLed coordinator cannot stop its workers; they notice the new parent and quit.
        while os.getppid() == parent_pid:
            time.sleep(0.5)
        os._exit(1)

    threading.Thread(target=watch, daemon=True, name="seahaze-parent-watch").start()


def threads_per_worker(workers: int, threads: int | None = None) -> int:
    """drjit threads of each of ``workers`` local worker processes: ``threads`` in all (None:
    the CPUs this process may use, affinity and cgroup quota) shared evenly, at least 1."""
    total = threads if threads is not None else usable_cpus()
    return max(1, total // max(1, workers))


class _LocalPool:
    """Scenes rendered in ``workers`` spawned processes (Mitsuba and drjit are not fork-safe),
    ``threads`` drjit threads in all (None: the CPUs this process may use)."""

    def __init__(
        self,
        jobs: Sequence[SceneJob],
        root: Path,
        workers: int,
        tick: Callable[[], None] | None = None,
        threads: int | None = None,
    ):
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        self.tick = tick
        self.executor = ProcessPoolExecutor(
            max_workers=workers,
            mp_context=multiprocessing.get_context("spawn"),
            initializer=_worker_init,
            initargs=(os.getpid(), threads_per_worker(workers, threads)),
        )
        self.futures = {
            self.executor.submit(
                render_job,
                job.name,
                job.spec.model_dump(mode="json", by_alias=True),
                str(root),
                job.frame,
            ): job.name
            for job in jobs
        }

    def results(self) -> Iterator[Outcome]:
        from concurrent.futures import FIRST_COMPLETED, wait

        pending = set(self.futures)
        while pending:
            # Short waits: progress ticks between finished scenes, and a signal is seen at once.
            finished, pending = wait(pending, timeout=WAIT_STEP_S, return_when=FIRST_COMPLETED)
            if self.tick is not None:
                self.tick()
            for future in finished:
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
                job.frame,
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


Executor = _InProcess | _LocalPool | _DaskCluster


def start_executor(
    jobs: Sequence[SceneJob],
    root: Path,
    workers: int,
    client: Any,
    note: Callable[[str], None],
    tick: Callable[[], None] | None = None,
    threads: int | None = None,
) -> Executor:
    """The executor for ``jobs``: the Dask cluster of ``client`` when given, else ``workers``
    local processes (more than one), else this process (``note`` gets its per-pass messages).
    Local executors call ``tick`` every :data:`~seahaze.interrupts.WAIT_STEP_S` while they
    wait (progress between scenes) and render with ``threads`` drjit threads in all (None:
    the CPUs this process may use, :func:`seahaze.cpus.usable_cpus`); a Dask worker keeps
    its own."""
    if client is not None:
        return _DaskCluster(jobs, root, client)
    if workers > 1 and len(jobs) > 1:
        return _LocalPool(jobs, root, min(workers, len(jobs)), tick, threads)
    return _InProcess(jobs, root, note, tick, threads)
