"""The lock of a dataset folder: one seahaze process at a time."""

from __future__ import annotations

import contextlib
import os
import socket
from collections.abc import Callable
from pathlib import Path

from .errors import DatasetLockedError

LOCK_NAME = ".seahaze.lock"
"""Lock file inside the dataset folder; present only while a batch runs (or after a crash)."""


class DatasetLock:
    """An exclusive lock on a dataset folder: ``OUT/.seahaze.lock`` under ``fcntl.flock``.

    The kernel drops a flock when its process dies, however it dies, so a lock file left by a
    killed run is free and is taken over (with a message naming the old pid). The file holds the
    pid and host of its owner so a refused process can say who holds it. It is removed on exit.
    """

    def __init__(self, root: Path, warn: Callable[[str], None] = lambda _msg: None):
        self.path = root / LOCK_NAME
        self.warn = warn
        self._fd: int | None = None

    def __enter__(self) -> DatasetLock:
        import fcntl

        while True:
            fd = self._open()
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = _read_fd(fd).strip() or "unknown process"
                os.close(fd)
                raise DatasetLockedError(
                    f"{self.path.parent} is in use by another seahaze process ({holder}); "
                    f"wait for it to finish or stop it (lock file {self.path})"
                ) from None
            # The previous owner unlinks the file when it finishes: if that happened between our
            # open and flock, we hold a lock on a deleted file and must start over.
            try:
                same = os.stat(self.path).st_ino == os.fstat(fd).st_ino
            except FileNotFoundError:
                same = False
            if same:
                break
            os.close(fd)
        previous = _read_fd(fd).strip()
        me = f"pid {os.getpid()} on {socket.gethostname()}"
        if previous and previous != me:
            self.warn(f"taking over the lock left by {previous}, which no longer runs")
        os.ftruncate(fd, 0)
        os.pwrite(fd, (me + "\n").encode(), 0)
        self._fd = fd
        return self

    def _open(self) -> int:
        """The lock file, opened (created if absent). A folder, a link or anything else under
        the lock's name is refused: never followed, truncated or written through."""
        try:
            return os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o644)
        except OSError as err:
            if self.path.is_symlink() or (os.path.lexists(self.path) and not self.path.is_file()):
                kind = "symbolic link" if self.path.is_symlink() else "folder or special file"
                raise DatasetLockedError(
                    f"{self.path} is a {kind}, not seahaze's lock file: remove it to render here"
                ) from None
            raise err

    def remove_file(self) -> None:
        """Remove the lock file (the flock itself ends with the process): what a process
        stopped hard inside a render leaves behind is then nothing."""
        if self._fd is not None:
            with contextlib.suppress(OSError):
                self.path.unlink()

    def __exit__(self, *exc: object) -> None:
        if self._fd is not None:
            self.remove_file()
            os.close(self._fd)
            self._fd = None


def _read_fd(fd: int) -> str:
    try:
        return os.pread(fd, 4096, 0).decode("utf-8", "replace")
    except OSError:
        return ""
