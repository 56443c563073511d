"""A long render the main thread can leave when a signal comes.

drjit compiles and runs a kernel without returning to Python, for minutes at large sizes or
sample counts, and Python runs signal handlers only in the main thread between bytecodes: a
render called from the main thread ignores Ctrl-C and SIGTERM until its kernel ends (12
minutes at 2000 spp at 1280×720 on a 2-vCPU machine). :func:`run_interruptibly` runs it in a
thread of its own while the main thread waits in short steps, so the signal's
KeyboardInterrupt comes within :data:`WAIT_STEP_S`.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any, TypeVar

T = TypeVar("T")

_abandoned = threading.Event()
"""Set when a render was left running in its thread by an interrupt (see
:func:`run_interruptibly`)."""

WAIT_STEP_S = 0.1
"""How often the main thread wakes while a render runs: the longest a signal waits."""


def run_interruptibly(render: Callable[[], T], tick: Callable[[], None] | None = None) -> T:
    """``render()`` in a thread of its own, while this thread waits in short steps; its
    result, or its exception raised here. ``tick`` is called at every step (progress).

    A signal's KeyboardInterrupt (or any exception) raised while waiting leaves the render
    running: it cannot be stopped. The caller must write nothing of it (write files only after
    a render returned), and the ``seahaze`` command exits without waiting for it
    (:func:`render_abandoned`, ``seahaze.cli.entry``).
    """
    outcome: dict[str, Any] = {}

    def target() -> None:
        try:
            outcome["value"] = render()
        except BaseException as err:  # handed to the waiting thread, which raises it
            outcome["error"] = err

    thread = threading.Thread(target=target, name="seahaze-render", daemon=True)
    thread.start()
    try:
        while thread.is_alive():
            thread.join(WAIT_STEP_S)
            if tick is not None:
                tick()
    except BaseException:
        _abandoned.set()
        raise
    if "error" in outcome:
        raise outcome["error"]
    return outcome["value"]


def render_abandoned() -> bool:
    """Whether an interrupt left a render running in its thread: the process should exit
    without waiting for it (``os._exit`` after flushing its output)."""
    return _abandoned.is_set()
