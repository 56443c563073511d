"""What a batch did, and the command's exit status for it."""

from __future__ import annotations

from dataclasses import dataclass, field

EXIT_OK = 0
EXIT_FAILED = 1
EXIT_REFUSED = 2
EXIT_WRITE_ERROR = 3
EXIT_INTERRUPTED = 130


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

    @property
    def exit_code(self) -> int:
        """The command's exit status for this outcome."""
        return {
            "complete": EXIT_OK,
            "failed": EXIT_FAILED,
            "write_error": EXIT_WRITE_ERROR,
            "interrupted": EXIT_INTERRUPTED,
        }[self.outcome]
