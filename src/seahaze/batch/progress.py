"""Progress of a batch: a bar or lines on the console, and a JSON-lines log for batch systems."""

from __future__ import annotations

import json
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any

from .plan import SceneJob
from .report import BatchReport

HEARTBEAT_S = 30.0
"""Without a terminal, a progress line (and a ``heartbeat`` log event) at least this often
while scenes render: a batch log never sits silent for minutes."""
BAR_REFRESH_S = 1.0
"""How often the bar on a terminal is redrawn while a scene renders (its clock moves)."""


class Reporter:
    """Progress of a batch: a bar (or one line per scene when stderr is not a terminal), the
    per-pass messages of in-process renders, and an optional JSON-lines log for batch systems.

    Per-pass messages of in-process renders go into the bar's label on a terminal, and are
    printed otherwise only when a single scene renders (many scenes get one line each).
    ``quiet`` silences the bar and messages but not warnings; ``notes`` receives every message
    instead of the console. Log lines carry ``time`` (Unix seconds) and ``event``: ``start``,
    ``scene_done`` (with per-pass seconds), ``scene_failed``, ``heartbeat`` (every
    :data:`HEARTBEAT_S` without news: scenes done and seconds elapsed), ``end``. The log is
    appended to, so a resumed batch continues the same file.
    """

    def __init__(
        self,
        *,
        quiet: bool = False,
        log: Path | None = None,
        stream: IO[str] | None = None,
        bar: bool | None = None,
        notes: Callable[[str], None] | None = None,
        heartbeat_s: float = HEARTBEAT_S,
    ):
        self.quiet = quiet
        self.heartbeat_s = heartbeat_s
        self._notes = notes
        self.stream = stream or sys.stderr
        self.use_bar = (not quiet) and (self.stream.isatty() if bar is None else bar)
        self._log = open(log, "a", encoding="utf-8", buffering=1) if log else None  # noqa: SIM115
        self._bar: Any = None
        self._start = time.perf_counter()
        self._planned = self._done = self._images = self._failed = 0
        self._done_before = self._to_render = 0
        self._last_news = self._last_refresh = time.perf_counter()
        self._stage = ""  # the latest step of an in-process render, for the heartbeat
        # The heartbeat comes from the signal watcher's thread while the main one renders.
        self._lock = threading.RLock()

    def _event(self, event: str, **data: Any) -> None:
        with self._lock:
            self._log_event(event, data)

    def _log_event(self, event: str, data: dict[str, Any]) -> None:
        self._last_news = time.perf_counter()
        if self._log is not None:
            record = {"time": round(time.time(), 3), "event": event, **data}
            try:
                self._log.write(json.dumps(record, allow_nan=False) + "\n")
            except (OSError, ValueError) as err:
                # The log is for people watching; losing it must not stop the dataset.
                self._log = None
                self.warn(f"cannot write the --log file any more ({err}); continuing without")

    def heartbeat(self) -> None:
        """Called often while scenes render: redraw the bar (its clock) on a terminal; else,
        after ``heartbeat_s`` (default :data:`HEARTBEAT_S`) without a line, say how far the
        batch is (and log it). May be called from another thread than the batch's."""
        with self._lock:
            self._heartbeat()

    def _heartbeat(self) -> None:
        now = time.perf_counter()
        if self._bar is not None:
            if now - self._last_refresh >= BAR_REFRESH_S:
                self._last_refresh = now
                self._bar.refresh()
            return
        if now - self._last_news < self.heartbeat_s:
            return
        self._last_news = now
        elapsed = now - self._start
        finished = self._done + self._failed
        stage = {"stage": self._stage} if self._stage else {}
        seconds = round(elapsed, 1)
        self._event("heartbeat", done=self._done, planned=self._planned, seconds=seconds, **stage)
        if not self.quiet:
            doing = f" ({self._stage})" if self._stage else ""
            self._print(
                f"[seahaze] {finished}/{self._planned} scenes, {_hms(elapsed)} elapsed, "
                f"rendering{doing}"
            )

    def _print(self, message: str) -> None:
        with self._lock:
            self._last_news = time.perf_counter()
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
        """Progress inside one scene (a step started or finished), from in-process renders;
        the heartbeat repeats the latest."""
        with self._lock:
            self._stage = message
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
