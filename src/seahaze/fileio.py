"""The files seahaze writes and reads: PNG, OpenEXR, text and JSON, every write atomic.

A file is written under a temporary name beside its target and renamed onto it when complete,
so an interrupted or failed write never leaves a truncated file under the final name (and the
temporary file is removed). Nothing written carries a timestamp: the same data give the same
bytes. EXR files hold linear radiance (or distance) unscaled, float32, ZIP-compressed.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np


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


def write_png(path: str | Path, image8: np.ndarray) -> None:
    """Write an 8-bit RGB PNG atomically (temporary file, then rename)."""
    from PIL import Image

    with atomic_target(Path(path)) as tmp:
        Image.fromarray(image8, mode="RGB").save(tmp, format="PNG")


def write_exr(path: str | Path, channels: dict[str, np.ndarray]) -> None:
    """Write float32 channels (each (H, W)) to an OpenEXR file atomically, ZIP-compressed."""
    import OpenEXR

    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    data = {
        name: np.ascontiguousarray(values, dtype=np.float32) for name, values in channels.items()
    }
    with atomic_target(Path(path)) as tmp, OpenEXR.File(header, data) as exr:
        exr.write(str(tmp))


def write_rgb_exr(path: str | Path, radiance: np.ndarray) -> None:
    """Linear RGB radiance (H, W, 3) as an EXR with channels R, G, B."""
    write_exr(path, {"R": radiance[..., 0], "G": radiance[..., 1], "B": radiance[..., 2]})


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
