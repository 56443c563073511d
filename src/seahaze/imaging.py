"""Linear radiance to display images, and the image file formats seahaze writes.

Exposure: one linear factor per scene, chosen from the clean image and applied unchanged to every
level, so pixel values are comparable across levels (a brighter hazy level is brighter haze, not
a different exposure). ``auto`` maps the median luminance of the clean image's sky within 10° of
the horizon to :data:`AUTO_KEY` (a bright, unclipped horizon); without such sky pixels it maps the
mean luminance to 0.18. Values above 1 after exposure clip (sun glints); the sRGB transfer
function is IEC 61966-2-1 via colour-science. Files are written by :mod:`seahaze.fileio`.
"""

from __future__ import annotations

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
