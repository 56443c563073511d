"""Files a seahaze tool created in a folder that may hold other files too.

``seahaze export`` and the detector runs of ``seahaze metric`` write into folders the user
names. They never overwrite or delete a file they did not create: each keeps the list of its
files in ``FOLDER/.seahaze-owned.json`` and, before writing anything, refuses when a file it is
about to write exists and is not on that list. The list is written before the files (with the
union of the old and the new files), so an interrupted run still knows what it claimed.

The record is data from disk, so it is read as hostile input (anyone who can leave a file in
the folder can write it). A file is seahaze's to overwrite or delete only when all of these
hold:

* the record is one seahaze wrote: each time it writes a record, seahaze keeps the record's
  SHA-256 in its own state folder (:func:`state_dir`), under the folder's resolved path; a
  record whose digest is not there (planted, edited, or written on another machine) is read,
  but none of its files is trusted;
* its recorded path is a plain relative path inside the folder — no absolute path, no ``..``,
  no empty or ``.`` component, at most :data:`MAX_PATH_CHARS` characters — and the folder it
  lies in resolves, after symbolic links, inside the folder seahaze owns;
* the record lists it, with the identity seahaze recorded right after writing it: the device,
  inode, size and modification time of the file itself (``lstat``: a link is its own file);
* the file on disk still has that identity. A file replaced since (another inode), edited
  (another size or time) or never finished (no identity recorded: an interrupted run) is not
  seahaze's any more: it is left alone and reported.

Entries that break these rules are dropped when the record is read and reported in
:attr:`OwnedFiles.ignored`; a record of more than :data:`MAX_ENTRIES` entries is refused.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath
from typing import Any

from ..fileio import write_json, write_text

RECORD_NAME = ".seahaze-owned.json"
RECORD_FORMAT = "seahaze-owned/2"
"""Version 2 records each file's identity; version 1 records (paths only) are read, and their
files count as never finished: nothing of theirs is overwritten or deleted."""
OLD_FORMATS = ("seahaze-owned/1",)
MAX_ENTRIES = 1_000_000
"""Most files one record may list (an export of MSVD's size lists about 30,000)."""
MAX_RECORD_BYTES = 256 << 20
"""Largest record read."""
MAX_PATH_CHARS = 1024
"""Longest relative path a record may list."""

Identity = tuple[int, int, int, int]
"""(device, inode, size, modification time in ns) of a file, as ``lstat`` gives them."""


STATE_ENV = "SEAHAZE_STATE_DIR"
"""Environment variable naming seahaze's state folder (default ``$XDG_STATE_HOME/seahaze`` or
``~/.local/state/seahaze``)."""


def state_dir() -> Path:
    """The folder where seahaze keeps what it must remember between runs: the digests of the
    records of files it wrote into users' folders."""
    explicit = os.environ.get(STATE_ENV)
    if explicit:
        return Path(explicit)
    base = os.environ.get("XDG_STATE_HOME") or str(Path.home() / ".local" / "state")
    return Path(base) / "seahaze"


def _digest_file(root: Path) -> Path:
    """Where the digest of ``root``'s record is kept."""
    key = hashlib.sha256(str(root.resolve()).encode("utf-8", "surrogateescape")).hexdigest()
    return state_dir() / "owned" / f"{key}.sha256"


class ForeignFileError(Exception):
    """A file seahaze would write exists and was not created by seahaze; nothing was written."""


def plain_relative(rel: Any) -> str | None:
    """``rel`` as a normalised relative POSIX path inside a folder, or None where it is not one
    (absolute, ``..``, ``.`` or empty components, backslashes, NUL, too long, not a string)."""
    if not isinstance(rel, str) or not rel or len(rel) > MAX_PATH_CHARS:
        return None
    if "\\" in rel or "\x00" in rel or rel.startswith("/"):
        return None
    parts = rel.split("/")
    if any(part in ("", ".", "..") for part in parts):
        return None
    return str(PurePosixPath(*parts))


def identity(path: Path) -> Identity | None:
    """The identity of the file at ``path`` itself (a link not followed), None if absent."""
    try:
        st = os.lstat(path)
    except OSError:
        return None
    return (st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns)


@dataclass
class OwnedFiles:
    """The files (relative paths) seahaze created in ``root``, with the identity each had when
    seahaze finished writing it (None: claimed, never finished), and what created them."""

    root: Path
    files: dict[str, Identity | None] = field(default_factory=dict)
    info: dict[str, Any] = field(default_factory=dict)
    ignored: list[str] = field(default_factory=list)
    """Why record entries were not trusted (one line each), for the caller to report."""
    folders: dict[str, bool] = field(default_factory=dict, repr=False)
    """Folder → whether it resolves inside the root, for the call in progress (:meth:`check`
    and :meth:`release` start afresh: the folders may have changed since)."""

    @property
    def record(self) -> Path:
        return self.root / RECORD_NAME

    @classmethod
    def open(cls, root: Path) -> OwnedFiles:
        """The record of ``root`` (an empty one where there is none), its unsafe entries
        dropped into :attr:`ignored`. Raises :class:`ForeignFileError` for a record seahaze
        cannot read."""
        owned = cls(Path(root))
        if not owned.record.exists() and not owned.record.is_symlink():
            return owned
        try:
            if owned.record.is_symlink() or not owned.record.is_file():
                raise ValueError("not a regular file")
            if owned.record.stat().st_size > MAX_RECORD_BYTES:
                raise ValueError(f"larger than {MAX_RECORD_BYTES >> 20} MiB")
            raw = owned.record.read_bytes()
            data = json.loads(raw.decode("utf-8"))
            if not isinstance(data, dict) or data.get("format") not in (
                RECORD_FORMAT,
                *OLD_FORMATS,
            ):
                raise ValueError("not a seahaze record")
            entries = _entries(data["files"])
        except (OSError, ValueError, KeyError, TypeError, RecursionError) as err:
            raise ForeignFileError(
                f"{owned.record}: cannot read seahaze's list of its files ({err}); "
                "choose another output folder"
            ) from None
        info = {k: v for k, v in data.items() if k not in ("format", "files")}
        owned.info = info
        if not _written_here(owned.root, raw):
            owned.ignored.append(
                f"{owned.record}: not a record seahaze wrote on this machine (or changed since): "
                "none of the files it lists is overwritten or deleted"
            )
            entries = [(rel, None) for rel, _ in entries]
        for rel, ident in entries:
            clean = plain_relative(rel)
            if clean is None:
                owned.ignored.append(f"{owned.record}: {rel!r} is not a path inside the folder")
            elif clean in owned.files:
                owned.ignored.append(f"{owned.record}: {rel!r} is listed twice")
            else:
                owned.files[clean] = ident
        return owned

    def is_ours(self, rel: str) -> bool:
        """Whether the file at ``rel`` is seahaze's as it stands: listed with an identity,
        still that identity, in a folder that resolves inside the root."""
        recorded = self.files.get(rel)
        if recorded is None or not self._inside(rel):
            return False
        return identity(self.root / rel) == recorded

    def check(self, relative: Iterable[str]) -> None:
        """Raise :class:`ForeignFileError` naming the first of ``relative`` that exists in the
        folder without being seahaze's (and how many there are)."""
        relative = list(relative)
        self.folders.clear()
        foreign = sorted(
            rel for rel in relative if _exists(self.root / rel) and not self.is_ours(rel)
        )
        if foreign:
            more = f" (and {len(foreign) - 1} more)" if len(foreign) > 1 else ""
            raise ForeignFileError(
                f"{self.root / foreign[0]}{more} exists and was not written by seahaze (or was "
                "changed since); it is never overwritten: move it or choose another output folder"
            )
        outside = sorted(rel for rel in relative if not self._inside(rel))
        if outside:
            raise ForeignFileError(
                f"{self.root / outside[0]}: its folder leads outside {self.root} (a symbolic "
                "link); seahaze writes only inside the folder it was given"
            )

    def claim(self, relative: Iterable[str], info: dict[str, Any]) -> set[str]:
        """Record ``relative`` as seahaze's before writing them (keeping the files recorded
        before, which may still be on disk); returns those earlier files no longer wanted.
        Call :meth:`seal` once they are written."""
        wanted = set(relative)
        stale = set(self.files) - wanted
        self.info = dict(info)
        for rel in wanted:
            self.files[rel] = None
        self._write()
        return stale

    def seal(self, relative: Iterable[str]) -> None:
        """Record the identity of each of ``relative`` as written now."""
        for rel in relative:
            self.files[rel] = identity(self.root / rel)
        self._write()

    def release(self, relative: Iterable[str]) -> list[str]:
        """Delete files of ours that are no longer wanted and drop them from the record; a file
        that is not ours as it stands (:meth:`is_ours`) is left alone. Returns what was left
        alone, one line each."""
        kept = []
        self.folders.clear()
        for rel in sorted(set(relative) & set(self.files)):
            path = self.root / rel
            if self.is_ours(rel):
                path.unlink()
            elif _exists(path):
                kept.append(f"{path}: kept, not as seahaze wrote it")
            del self.files[rel]
        self._write()
        return kept

    def _inside(self, rel: str) -> bool:
        """Whether the folder of ``rel`` resolves, links followed, inside the root. Resolved
        once per folder and call: an export's thousands of files share a few folders."""
        folder = str(PurePosixPath(rel).parent)
        if folder not in self.folders:
            self.folders[folder] = _resolves_inside(self.root, folder)
        return self.folders[folder]

    def _write(self) -> None:
        files = {rel: list(ident) if ident else None for rel, ident in sorted(self.files.items())}
        write_json(self.record, {"format": RECORD_FORMAT, **self.info, "files": files})
        digest = hashlib.sha256(self.record.read_bytes()).hexdigest()
        write_text(_digest_file(self.root), digest + "\n")


def _written_here(root: Path, raw: bytes) -> bool:
    """Whether ``raw`` is the record seahaze last wrote for ``root`` on this machine."""
    try:
        kept = _digest_file(root).read_text(encoding="utf-8").strip()
    except (OSError, UnicodeDecodeError):
        return False
    return kept == hashlib.sha256(raw).hexdigest()


def _resolves_inside(root: Path, folder: str) -> bool:
    """Whether ``root/folder`` resolves, links followed, inside ``root`` resolved."""
    inside = root.resolve()
    resolved = (root / folder).resolve()
    return resolved == inside or resolved.is_relative_to(inside)


def _entries(files: Any) -> list[tuple[Any, Identity | None]]:
    """(path, identity) pairs of a record's ``files``: a mapping (version 2) or a list
    (version 1, no identities)."""
    if len(files) > MAX_ENTRIES:
        raise ValueError(f"more than {MAX_ENTRIES} files listed")
    if isinstance(files, list):
        return [(rel, None) for rel in files]
    if not isinstance(files, dict):
        raise TypeError("'files' is neither a mapping nor a list")
    return [(rel, _identity_of(value)) for rel, value in files.items()]


def _identity_of(value: Any) -> Identity | None:
    """A recorded identity, None where it is not four whole numbers."""
    if (
        isinstance(value, list)
        and len(value) == 4
        and all(isinstance(v, int) and not isinstance(v, bool) for v in value)
    ):
        return (value[0], value[1], value[2], value[3])
    return None


def _exists(path: Path) -> bool:
    """Whether ``path`` exists, a broken symbolic link included."""
    return path.exists() or path.is_symlink()
