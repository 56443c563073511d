"""Long renders that stop when asked, without leaving the main thread.

drjit compiles and runs a kernel without returning to Python, for minutes at large sizes or
sample counts, and Python runs signal handlers only in the main thread between bytecodes: a
render ignores Ctrl-C and SIGTERM until its kernel ends (12 minutes at 2000 spp at 1280×720
on a 2-vCPU machine). Rendering on a second thread while the main one waits would let the
signal through, but then drjit and Mitsuba are driven from two threads, and that crashed
(segmentation faults in a test-suite worker in two of five full runs).

So the render stays on the main thread and :func:`stoppable` adds a watcher thread. Python's
C-level signal handler writes the signal's number to a *wakeup fd*
(:func:`signal.set_wakeup_fd`) the moment the signal arrives, even inside a kernel; the
watcher reads it and stops the process at once: it runs the registered cleanups
(:func:`on_hard_stop`, e.g. the dataset lock), says so and exits with code 130. No
KeyboardInterrupt is raised inside the render: one raised while drjit traces a kernel comes
out as a RuntimeError, a failed scene instead of a stop. Nothing is lost that a rerun cannot
redo: a render writes no file (files are written after it returns), and the batch records a
scene only when its files are complete, so the interrupted scene stays ``pending``.

The watcher also calls a ``tick`` every :data:`WAIT_STEP_S` (the batch's heartbeat and bar
clock), which the busy main thread cannot.
"""

from __future__ import annotations

import contextlib
import os
import select
import signal
import socket
import sys
import threading
from collections.abc import Callable, Iterator

WAIT_STEP_S = 0.1
"""How often the watcher wakes to call ``tick``; also how often the batch's local executors
look for finished scenes."""
EXIT_INTERRUPTED = 130
"""Exit code of an interrupted command (128 + SIGINT), as shells report Ctrl-C."""
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)

_cleanups: list[Callable[[], None]] = []
_cleanups_lock = threading.Lock()


@contextlib.contextmanager
def on_hard_stop(cleanup: Callable[[], None]) -> Iterator[None]:
    """Run ``cleanup`` (from the watcher thread) if a hard stop ends the process inside this
    block. Cleanups must be quick and safe to run while the main thread is inside a render,
    such as removing the dataset's lock file."""
    with _cleanups_lock:
        _cleanups.append(cleanup)
    try:
        yield
    finally:
        with _cleanups_lock:
            _cleanups.remove(cleanup)


@contextlib.contextmanager
def stoppable(
    tick: Callable[[], None] | None = None, signals: tuple[int, ...] = STOP_SIGNALS
) -> Iterator[None]:
    """Make the block (a render on the main thread, which writes nothing) end the process on
    any of ``signals`` within :data:`WAIT_STEP_S` (see the module docstring); ``tick`` is
    called every :data:`WAIT_STEP_S` meanwhile.

    Only the main thread can receive Python's signals; elsewhere (a Dask worker's thread)
    the block runs as it is, without ticks. A signal whose handler is ``SIG_IGN`` (a
    background job's SIGINT) stays ignored."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    reader, writer = socket.socketpair()
    reader.setblocking(False)
    writer.setblocking(False)
    previous = signal.set_wakeup_fd(writer.fileno(), warn_on_full_buffer=False)
    # A Python handler that does nothing: the C-level handler still writes the wakeup fd, and
    # no KeyboardInterrupt is raised inside the render (drjit turns one raised while it traces
    # a kernel into a RuntimeError, which would fail the scene instead of stopping).
    handlers = {
        signum: signal.signal(signum, _noted)
        for signum in signals
        if signal.getsignal(signum) is not signal.SIG_IGN
    }
    done = threading.Event()
    watcher = threading.Thread(
        target=_watch,
        args=(reader, done, tick, tuple(handlers)),
        name="seahaze-signal-watch",
        daemon=True,
    )
    watcher.start()
    try:
        yield
    finally:
        done.set()
        signal.set_wakeup_fd(previous)
        for signum, handler in handlers.items():
            signal.signal(signum, handler)
        watcher.join()
        reader.close()
        writer.close()


def _noted(_signum: int, _frame: object) -> None:
    """The Python side of a stop signal during a render: the watcher acts on it."""


def _watch(
    reader: socket.socket,
    done: threading.Event,
    tick: Callable[[], None] | None,
    signals: tuple[int, ...],
) -> None:
    """The watcher: tick, and stop the process when one of ``signals`` arrives."""
    while not done.is_set():
        ready, _, _ = select.select([reader], [], [], WAIT_STEP_S)
        if ready and _stop_signals_in(reader, signals) and not done.is_set():
            _hard_stop()
        if tick is not None and not done.is_set():
            with contextlib.suppress(Exception):  # progress must never break a render
                tick()


def _stop_signals_in(reader: socket.socket, signals: tuple[int, ...]) -> bool:
    """Whether the bytes waiting on the wakeup fd name one of ``signals`` (other handled
    signals write their numbers too)."""
    try:
        data = reader.recv(64)
    except BlockingIOError:
        return False
    return any(number in data for number in signals)


def _hard_stop() -> None:
    """Run the cleanups, say so, and end the process with :data:`EXIT_INTERRUPTED`."""
    with _cleanups_lock:
        cleanups = list(_cleanups)
    for cleanup in reversed(cleanups):
        with contextlib.suppress(Exception):
            cleanup()
    with contextlib.suppress(Exception):
        sys.stdout.flush()
        print("seahaze: interrupted (the render was stopped; rerun to resume)", file=sys.stderr)
        sys.stderr.flush()
    os._exit(EXIT_INTERRUPTED)
