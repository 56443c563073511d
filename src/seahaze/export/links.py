"""Putting a dataset file into an export without copying its pixels.

``auto`` makes a hard link (same bytes, no extra space, survives moving either folder on one
file system), falls back to a symbolic link where hard links are impossible (another file
system, or a file system without them), and copies only where neither works. Every placement is
atomic: made under a temporary name, then renamed onto the target.
"""

from __future__ import annotations

import os
import shutil
from collections import Counter
from pathlib import Path

from ..fileio import atomic_target

LINK_MODES: tuple[str, ...] = ("auto", "hard", "symlink", "copy")
"""``--link`` values; ``auto`` tries them in the order hard, symlink, copy."""

METHOD_NAMES = {"hard": "hard links", "symlink": "symbolic links", "copy": "copies"}


class Placer:
    """Places files by one ``--link`` mode and counts the method each one got."""

    def __init__(self, mode: str) -> None:
        if mode not in LINK_MODES:
            raise ValueError(f"link mode {mode!r}: allowed {', '.join(LINK_MODES)}")
        self.methods = ["hard", "symlink", "copy"] if mode == "auto" else [mode]
        self.used: Counter[str] = Counter()

    def place(self, source: Path, target: Path) -> str:
        """Put ``source`` at ``target`` (replacing a previous placement); returns the method.

        In ``auto`` a method that fails once is not tried again: every file of an export comes
        from one dataset and goes to one folder. Raises ``OSError`` when no method works.
        """
        while True:
            method = self.methods[0]
            try:
                _place(method, source, target)
            except OSError:
                if len(self.methods) == 1:
                    raise
                self.methods.pop(0)
                continue
            self.used[method] += 1
            return method

    def summary(self) -> str:
        """``"hard links: 96"`` (or several methods, in the order tried)."""
        used = [f"{METHOD_NAMES[m]}: {n}" for m, n in self.used.items()]
        return ", ".join(used) or "no files"


def _place(method: str, source: Path, target: Path) -> None:
    with atomic_target(target) as tmp:
        tmp.unlink(missing_ok=True)
        if method == "hard":
            os.link(source, tmp)
        elif method == "symlink":
            # Absolute: the link stays valid wherever the export folder is moved.
            os.symlink(source.resolve(), tmp)
        else:
            shutil.copyfile(source, tmp)
