"""The one exception type of :mod:`seahaze.metric` for bad user input."""

from __future__ import annotations

from pathlib import Path


class MetricInputError(ValueError):
    """Input the metric cannot use: missing file, malformed line, bad value, too-short table.

    The message is a single line that names the file (and line, where there is one) and says
    what is allowed, so the CLI can print it as is and exit with code 2.
    """


def located(path: Path | str, message: str, line: int | None = None) -> MetricInputError:
    """A :class:`MetricInputError` whose message starts with ``path[:line]: ``."""
    where = f"{path}:{line}" if line is not None else str(path)
    return MetricInputError(f"{where}: {message}")
