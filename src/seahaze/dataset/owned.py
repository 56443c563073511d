"""Files a seahaze tool created in a folder that may hold other files too.

``seahaze export`` and the detector runs of ``seahaze metric`` write into folders the user
names. They never overwrite or delete a file they did not create: each keeps the list of its
files in ``FOLDER/.seahaze-owned.json`` and, before writing anything, refuses when a file it is
about to write exists and is not on that list. The list is written before the files (with the
union of the old and the new files), so an interrupted run still knows what it wrote.
"""

from __future__ import annotations

import json
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..fileio import write_json

RECORD_NAME = ".seahaze-owned.json"
RECORD_FORMAT = "seahaze-owned/1"


class ForeignFileError(Exception):
    """A file seahaze would write exists and was not created by seahaze; nothing was written."""


@dataclass
class OwnedFiles:
    """The files (relative paths) seahaze created in ``root``, and what created them."""

    root: Path
    files: set[str] = field(default_factory=set)
    info: dict[str, Any] = field(default_factory=dict)

    @property
    def record(self) -> Path:
        return self.root / RECORD_NAME

    @classmethod
    def open(cls, root: Path) -> OwnedFiles:
        """The record of ``root`` (an empty one where there is none). Raises
        :class:`ForeignFileError` for a record seahaze cannot read."""
        owned = cls(root)
        if not owned.record.exists():
            return owned
        try:
            data = json.loads(owned.record.read_text(encoding="utf-8"))
            if not (isinstance(data, dict) and data.get("format") == RECORD_FORMAT):
                raise ValueError("not a seahaze record")
            files = {str(f) for f in data["files"]}
        except (OSError, ValueError, KeyError, TypeError) as err:
            raise ForeignFileError(
                f"{owned.record}: cannot read seahaze's list of its files ({err}); "
                "choose another output folder"
            ) from None
        info = {k: v for k, v in data.items() if k not in ("format", "files")}
        return cls(root, files, info)

    def check(self, relative: Iterable[str]) -> None:
        """Raise :class:`ForeignFileError` naming the first of ``relative`` that exists in the
        folder without being seahaze's (and how many there are)."""
        foreign = sorted(
            rel for rel in relative if rel not in self.files and _exists(self.root / rel)
        )
        if foreign:
            more = f" (and {len(foreign) - 1} more)" if len(foreign) > 1 else ""
            raise ForeignFileError(
                f"{self.root / foreign[0]}{more} exists and was not written by seahaze; "
                "it is never overwritten: move it or choose another output folder"
            )

    def claim(self, relative: Iterable[str], info: dict[str, Any]) -> set[str]:
        """Record ``relative`` as seahaze's before writing them (keeping the files recorded
        before, which may still be on disk); returns those earlier files no longer wanted."""
        wanted = set(relative)
        stale = self.files - wanted
        self.info = dict(info)
        self._write(self.files | wanted)
        self.files |= wanted
        return stale

    def release(self, relative: Iterable[str]) -> None:
        """Delete files of ours that are no longer wanted and drop them from the record."""
        gone = set(relative) & self.files
        for rel in sorted(gone):
            (self.root / rel).unlink(missing_ok=True)
        self.files -= gone
        self._write(self.files)

    def _write(self, files: set[str]) -> None:
        write_json(self.record, {"format": RECORD_FORMAT, **self.info, "files": sorted(files)})


def _exists(path: Path) -> bool:
    """Whether ``path`` exists, a broken symbolic link included."""
    return path.exists() or path.is_symlink()
