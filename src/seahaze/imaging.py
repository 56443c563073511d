"""Linear radiance to display images, and the image file formats seahaze writes.

Exposure: one linear factor per scene, chosen from the clean image and applied unchanged to every
level, so pixel values are comparable across levels (a brighter hazy level is brighter haze, not
a different exposure). ``auto`` maps the median luminance of the clean image's sky within 10° of
the horizon to :data:`AUTO_KEY` (a bright, unclipped horizon); without such sky pixels it maps the
mean luminance to 0.18. Values above 1 after exposure clip (sun glints); the sRGB transfer
function is IEC 61966-2-1 via colour-science. EXR files hold the linear radiance unscaled.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np

AUTO_KEY = 0.6
"""Linear display value of the clean horizon sky under ``exposure: auto``."""
HORIZON_BAND_DEG = 10.0
REC709_LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
"""Luminance weights of linear sRGB / Rec. 709 primaries (ITU-R BT.709-6)."""


def luminance(rgb: np.ndarray) -> np.ndarray:
    """Relative luminance Y of linear sRGB radiance (..., 3)."""
    return np.asarray(rgb, dtype=np.float64) @ REC709_LUMINANCE


def auto_exposure(clean: np.ndarray, distance_m: np.ndarray, elevation_deg: np.ndarray) -> float:
    """Exposure factor for a scene from its clean radiance, distance and pixel elevations."""
    y = luminance(clean)
    horizon_sky = np.isinf(distance_m) & (elevation_deg < HORIZON_BAND_DEG)
    if horizon_sky.sum() >= 4:
        reference, key = float(np.median(y[horizon_sky])), AUTO_KEY
    else:
        reference, key = float(np.mean(y)), 0.18
    return key / reference if reference > 0 and np.isfinite(reference) else 1.0


def to_srgb8(radiance: np.ndarray, exposure: float) -> np.ndarray:
    """Exposed, clipped and sRGB-encoded 8-bit image (H, W, 3) uint8."""
    import colour

    linear = np.clip(np.nan_to_num(radiance * exposure, nan=0.0, posinf=1.0), 0.0, 1.0)
    encoded = colour.cctf_encoding(linear, function="sRGB")
    return np.round(encoded * 255.0).astype(np.uint8)


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
    """All channels of an EXR file as float arrays (an RGB layer comes back as one (H, W, 3) "
    "'RGB')."""
    import OpenEXR

    with OpenEXR.File(str(path)) as exr:
        return {name: np.array(ch.pixels) for name, ch in exr.channels().items()}
