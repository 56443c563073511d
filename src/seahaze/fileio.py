"""The files seahaze writes and reads: PNG, OpenEXR, text and JSON, every write atomic.

A file is written under a temporary name beside its target and renamed onto it when complete,
so an interrupted or failed write never leaves a truncated file under the final name (and the
temporary file is removed). Nothing written carries a timestamp: the same data give the same
bytes. EXR files hold linear radiance (or distance) unscaled, float32: maps that vary smoothly
(distance, transmittance) ZIP-compressed, radiance uncompressed (below).
"""

from __future__ import annotations

import functools
import json
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from .cpus import usable_cpus


@contextmanager
def atomic_target(path: Path) -> Iterator[Path]:
    """A temporary path beside ``path`` to write to; renamed onto ``path`` when the block ends.

    An interrupted or failed write leaves no truncated file under the final name.
    """
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp{os.getpid()}")
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


PNG_COMPRESS_LEVEL = 4
"""zlib level of the PNGs. Pillow's default, 6, spends about 2.7 times as long for files about
2 % smaller: rendered images carry grain that deflate's longer searches barely shrink
(docs/benchmarks.md, "What do a scene's files cost to write?")."""


def write_png(path: str | Path, image8: np.ndarray) -> None:
    """Write an 8-bit RGB PNG atomically (temporary file, then rename), zlib level
    :data:`PNG_COMPRESS_LEVEL`."""
    from PIL import Image

    with atomic_target(Path(path)) as tmp:
        Image.fromarray(image8, mode="RGB").save(
            tmp, format="PNG", compress_level=PNG_COMPRESS_LEVEL
        )


def write_exr(path: str | Path, channels: dict[str, np.ndarray], compress: bool = True) -> None:
    """Write float32 channels (each (H, W)) to an OpenEXR file atomically, ZIP-compressed, or
    uncompressed with ``compress=False``."""
    import OpenEXR

    _use_exr_threads(OpenEXR)
    compression = OpenEXR.ZIP_COMPRESSION if compress else OpenEXR.NO_COMPRESSION
    header = {"compression": compression, "type": OpenEXR.scanlineimage}
    data = {
        name: np.ascontiguousarray(values, dtype=np.float32) for name, values in channels.items()
    }
    with atomic_target(Path(path)) as tmp, OpenEXR.File(header, data) as exr:
        try:
            exr.write(str(tmp))
        except RuntimeError as err:
            # OpenEXR reports a failed write (full disk, quota, I/O error) as RuntimeError;
            # as an OSError the batch stops on it like on any other write error.
            raise _exr_write_error(Path(path), err) from err


@functools.cache
def _use_exr_threads(openexr: Any) -> None:
    """Let OpenEXR compress a file's blocks on every CPU of the process (its default is none:
    ZIP took 0.23 s for a 1280×720 RGB file on one thread, 0.12 s on two). The bytes do not
    change: each block is compressed alone."""
    openexr.set_global_thread_count(usable_cpus())


def _exr_write_error(path: Path, err: RuntimeError) -> OSError:
    """The OSError of a failed EXR write: ENOSPC when the disk is full, else EIO."""
    import errno

    code = errno.EIO
    try:
        stats = os.statvfs(path.parent)
        if stats.f_bavail * stats.f_frsize < (1 << 20):
            code = errno.ENOSPC
    except OSError:
        pass
    return OSError(code, f"{os.strerror(code)} (OpenEXR: {str(err).strip()})", str(path))


def write_rgb_exr(path: str | Path, radiance: np.ndarray) -> None:
    """Linear RGB radiance (H, W, 3) as an uncompressed EXR with channels R, G, B.

    A rendered radiance's low mantissa bits are Monte Carlo noise, which no lossless coder
    shrinks: ZIP made these files about a tenth smaller at about fourteen times the time of
    writing them uncompressed (docs/benchmarks.md, "What do a scene's files cost to write?").
    """
    channels = {"R": radiance[..., 0], "G": radiance[..., 1], "B": radiance[..., 2]}
    write_exr(path, channels, compress=False)


def read_exr(path: str | Path) -> dict[str, np.ndarray]:
    """All channels of an EXR file as float arrays (an RGB layer comes back as one (H, W, 3)
    ``RGB``)."""
    import OpenEXR

    with OpenEXR.File(str(path)) as exr:
        return {name: np.array(ch.pixels) for name, ch in exr.channels().items()}


def write_text(path: Path, text: str) -> None:
    """Write a UTF-8 text file atomically."""
    with atomic_target(path) as tmp:
        tmp.write_text(text, encoding="utf-8")


def write_json(path: Path, data: Any) -> None:
    """Write JSON atomically, keys in their given order, 2-space indent, no NaN or infinity."""
    write_text(path, json.dumps(data, indent=2, sort_keys=False, allow_nan=False) + "\n")


# Cheap checks of finished files: a resumed batch verifies what it skips (docs/batches.md).
# Each reads a file's header and, for PNG and EXR, enough of its end to see that it is complete;
# each returns None for a good file and a short reason otherwise.

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
_PNG_IEND = b"\x00\x00\x00\x00IEND\xaeB`\x82"
EXR_MAGIC = b"\x76\x2f\x31\x01"
_EXR_LINES_PER_CHUNK = {0: 1, 1: 1, 2: 1, 3: 16, 4: 32, 5: 16, 6: 32, 7: 32, 8: 32, 9: 256}
"""OpenEXR compression code → scanlines per chunk (NO, RLE, ZIPS, ZIP, PIZ, PXR24, B44, B44A,
DWAA, DWAB)."""


def _read_ends(path: Path, head: int, tail: int) -> tuple[bytes, bytes, int]:
    with open(path, "rb") as handle:
        size = os.fstat(handle.fileno()).st_size
        first = handle.read(head)
        handle.seek(max(size - tail, 0))
        last = handle.read(tail)
    return first, last, size


def check_png(path: Path, size: tuple[int, int]) -> str | None:
    """Whether ``path`` is a complete 8-bit RGB PNG of ``size`` (width, height)."""
    try:
        head, tail, length = _read_ends(path, 33, 12)
    except OSError as err:
        return f"cannot be read ({err.strerror or err})"
    if length == 0:
        return "is empty"
    if head[:8] != PNG_SIGNATURE or head[12:16] != b"IHDR":
        return "is not a PNG"
    width, height = int.from_bytes(head[16:20], "big"), int.from_bytes(head[20:24], "big")
    if (width, height) != tuple(size):
        return f"is {width}x{height}, not {size[0]}x{size[1]}"
    if head[24] != 8 or head[25] != 2:
        return "is not 8-bit RGB"
    if tail != _PNG_IEND:
        return "is truncated"
    return None


def check_exr(path: Path, size: tuple[int, int], channels: set[str]) -> str | None:
    """Whether ``path`` is a complete scanline OpenEXR of ``size`` with exactly ``channels``:
    the header is parsed and the last chunk must end where the file ends."""
    try:
        with open(path, "rb") as handle:
            length = os.fstat(handle.fileno()).st_size
            if length == 0:
                return "is empty"
            return _check_exr(handle, length, size, channels)
    except OSError as err:
        return f"cannot be read ({err.strerror or err})"


def _check_exr(handle: Any, length: int, size: tuple[int, int], channels: set[str]) -> str | None:
    import struct

    head = handle.read(min(length, 1 << 16))
    if head[:4] != EXR_MAGIC:
        return "is not an OpenEXR file"
    if head[5] & 0x1A:  # tiled (0x200), deep (0x800) or multi-part (0x1000): not seahaze's
        return "is not a single-part scanline OpenEXR file"
    pos, attrs = 8, {}
    while True:
        end = head.find(b"\x00", pos)
        if end < 0:
            return "has a truncated header"
        name = head[pos:end].decode("latin-1")
        pos = end + 1
        if not name:
            break
        end = head.find(b"\x00", pos)
        if end < 0 or end + 5 > len(head):
            return "has a truncated header"
        kind = head[pos:end].decode("latin-1")
        (n,) = struct.unpack_from("<i", head, end + 1)
        pos = end + 5
        if n < 0 or pos + n > len(head):
            return "has a truncated header"
        attrs[name] = (kind, head[pos : pos + n])
        pos += n
    try:
        xmin, ymin, xmax, ymax = struct.unpack("<4i", attrs["dataWindow"][1])
        compression = attrs["compression"][1][0]
        chlist = attrs["channels"][1]
    except (KeyError, IndexError, struct.error):
        return "has an incomplete header"
    width, height = xmax - xmin + 1, ymax - ymin + 1
    if (width, height) != tuple(size):
        return f"is {width}x{height}, not {size[0]}x{size[1]}"
    found, at = set(), 0
    while at < len(chlist) and chlist[at] != 0:  # name, then 16 bytes of type and sampling
        end = chlist.find(b"\x00", at)
        if end < 0:
            return "has a damaged channel list"
        found.add(chlist[at:end].decode("latin-1"))
        at = end + 17
    if found != channels:
        return f"has channels {sorted(found)}, not {sorted(channels)}"
    lines = _EXR_LINES_PER_CHUNK.get(compression)
    if lines is None:
        return f"has unknown compression {compression}"
    chunks = -(-height // lines)
    handle.seek(pos)
    table = handle.read(8 * chunks)
    if len(table) < 8 * chunks:
        return "is truncated"
    offsets = struct.unpack(f"<{chunks}Q", table)
    last = max(offsets)
    if min(offsets) < pos + 8 * chunks or last + 8 > length:
        return "is truncated"
    handle.seek(last)
    _y, data_size = struct.unpack("<2i", handle.read(8))
    if last + 8 + data_size != length:
        return "is truncated"
    return None


def json_depth(data: Any, limit: int) -> int:
    """Nesting depth of a parsed JSON document (a scalar is 1), without recursion, so a
    hostile file cannot exhaust the stack; the walk stops once ``limit`` is passed (the result
    is then ``limit + 1``)."""
    deepest, stack = 0, [(data, 1)]
    while stack and deepest <= limit:
        item, depth = stack.pop()
        deepest = max(deepest, depth)
        if isinstance(item, dict):
            stack += [(v, depth + 1) for v in item.values()]
        elif isinstance(item, list):
            stack += [(v, depth + 1) for v in item]
    return min(deepest, limit + 1)


def check_json(path: Path) -> str | None:
    """Whether ``path`` holds a JSON object (the meta files; at most a few kB)."""
    try:
        data = json.loads(Path(path).read_bytes())
    except OSError as err:
        return f"cannot be read ({err.strerror or err})"
    except (ValueError, RecursionError):
        return "is not valid JSON"
    return None if isinstance(data, dict) else "is not a JSON object"
