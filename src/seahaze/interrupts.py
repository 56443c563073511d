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
watcher reads it. A render that returns to Python within :data:`GRACE_S` raises its
KeyboardInterrupt as usual and everything unwinds normally. One that does not (it is inside
a kernel) is stopped hard: the watcher runs the registered cleanups (:func:`on_hard_stop`,
e.g. the dataset lock), says so and ends the process with exit code 130. Nothing of the
render is lost that a rerun cannot redo: files are written only after a render returns, and
the batch records a scene only when its files are complete. A second signal stops at once.

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
import time
from collections.abc import Callable, Iterator

WAIT_STEP_S = 0.1
"""How often the watcher wakes to call ``tick``; also how often the batch's local executors
look for finished scenes."""
GRACE_S = 1.0
"""After a signal, how long the main thread has to unwind by itself before the process is
stopped hard (it is then inside a kernel that cannot be cancelled)."""
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
def stoppable(tick: Callable[[], None] | None = None) -> Iterator[None]:
    """Make the block (a render on the main thread) stop within :data:`GRACE_S` of SIGINT or
    SIGTERM (see the module docstring); ``tick`` is called every :data:`WAIT_STEP_S` meanwhile.

    Only the main thread can receive Python's signals; elsewhere (a Dask worker's thread)
    the block runs as it is, without ticks. SIGTERM without a Python handler of its own
    raises KeyboardInterrupt here, like Ctrl-C."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    reader, writer = socket.socketpair()
    reader.setblocking(False)
    writer.setblocking(False)
    previous = signal.set_wakeup_fd(writer.fileno(), warn_on_full_buffer=False)
    previous_term = signal.getsignal(signal.SIGTERM)
    if previous_term in (signal.SIG_DFL, None):
        signal.signal(signal.SIGTERM, _raise_interrupt)
    done = threading.Event()
    watcher = threading.Thread(
        target=_watch, args=(reader, done, tick), name="seahaze-signal-watch", daemon=True
    )
    watcher.start()
    try:
        yield
    finally:
        done.set()
        signal.set_wakeup_fd(previous)
        if previous_term in (signal.SIG_DFL, None):
            signal.signal(signal.SIGTERM, signal.SIG_DFL)
        watcher.join()
        reader.close()
        writer.close()


def _raise_interrupt(_signum: int, _frame: object) -> None:
    raise KeyboardInterrupt


def _watch(reader: socket.socket, done: threading.Event, tick: Callable[[], None] | None) -> None:
    """The watcher: tick, and after a stop signal give the main thread :data:`GRACE_S` to
    leave the block before stopping the process."""
    signalled_at: float | None = None
    while not done.is_set():
        ready, _, _ = select.select([reader], [], [], WAIT_STEP_S)
        if ready and _stop_signals_in(reader):
            if signalled_at is not None:  # a second signal: the user insists
                _hard_stop()
            signalled_at = time.monotonic()
        overdue = signalled_at is not None and time.monotonic() - signalled_at >= GRACE_S
        if overdue and not done.is_set():
            _hard_stop()
        if tick is not None and not done.is_set():
            with contextlib.suppress(Exception):  # progress must never break a render
                tick()


def _stop_signals_in(reader: socket.socket) -> bool:
    """Whether the bytes waiting on the wakeup fd name a stop signal (other handled signals
    write their numbers too)."""
    try:
        data = reader.recv(64)
    except BlockingIOError:
        return False
    return any(number in data for number in STOP_SIGNALS)


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
