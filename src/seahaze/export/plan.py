"""What an export writes, as a plan made before anything is written: dataset files to place,
small texts, and files built from the dataset's contents (the Parquet shards of ``hf``)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

Builder = Callable[[Path], None]
"""Writes one built file to the path it is given (a temporary name beside its target)."""


@dataclass
class ExportPlan:
    """Every file of an export: dataset files to place (target → source), texts to write and
    files to build (target → builder)."""

    placed: dict[str, Path] = field(default_factory=dict)
    texts: dict[str, str] = field(default_factory=dict)
    built: dict[str, Builder] = field(default_factory=dict)
    pairs: int = 0
    kind: str = ""
    """What the built files are, for the summary line (``Parquet``)."""

    def targets(self) -> list[str]:
        """Every relative path the export writes."""
        return [*self.placed, *self.texts, *self.built]
