"""Linear radiance to display images, and the image file formats seahaze writes.

Exposure: one linear factor per scene, chosen from the clean image and applied unchanged to every
level, so pixel values are comparable across levels (a brighter hazy level is brighter haze, not
a different exposure). ``auto`` maps the median luminance of the clean image's sky within 10° of
the horizon to :data:`AUTO_KEY` (a bright, unclipped horizon); without such sky pixels it maps the
mean luminance to 0.18. Values above 1 after exposure clip (sun glints). The 8-bit sRGB code of
a value is the IEC 61966-2-1 encoding rounded to the nearest code, found by comparing the
linear value with the linear bounds between codes (:func:`srgb8_bounds`): the same codes as
encoding every pixel (colour-science's ``cctf_encoding``, the tests' reference) at a tenth of
the time, and without importing colour-science, whose plotting import costs ~2 s a process.
Files are written by :mod:`seahaze.fileio`.
"""

from __future__ import annotations

import functools

import numpy as np

AUTO_KEY = 0.6
"""Linear display value of the clean horizon sky under ``exposure: auto``."""
HORIZON_BAND_DEG = 10.0
SRGB_LINEAR_KNEE = 0.04045
"""Encoded value below which the sRGB transfer function is linear (IEC 61966-2-1:1999)."""
_BIN_COUNT = 4096
"""Bins of the linear range [0, 1] in the code lookup; each holds at most one code bound
(the closest bounds, at black, are 1/(255·12.92) ≈ 3.0e-4 apart, a bin 2.4e-4 wide)."""
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


def srgb_decode(encoded: np.ndarray) -> np.ndarray:
    """Linear value of sRGB-encoded values in [0, 1]: the IEC 61966-2-1:1999 transfer function,
    ``V/12.92`` up to :data:`SRGB_LINEAR_KNEE`, ``((V + 0.055)/1.055)^2.4`` above."""
    v = np.asarray(encoded, dtype=np.float64)
    return np.where(v <= SRGB_LINEAR_KNEE, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)


@functools.cache
def srgb8_bounds() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The linear bounds between 8-bit sRGB codes and a lookup of them.

    Returns ``(bounds, first_code, next_bound)``: ``bounds[k]`` (255 float32 values) is the
    smallest float32 whose encoding reaches ``(k + 0.5)/255``, where rounding goes from code
    ``k`` to ``k + 1``; for each of :data:`_BIN_COUNT` equal bins of [0, 1], ``first_code`` is
    the code at the bin's start and ``next_bound`` the one bound inside the bin (``inf`` if
    none).
    """
    exact = srgb_decode((np.arange(255) + 0.5) / 255.0)
    # The smallest float32 at or above each exact bound: a float32 value reaches it exactly
    # when it reaches the exact bound, so the codes are those of the float64 encoding.
    bounds = exact.astype(np.float32)
    below = bounds < exact
    bounds[below] = np.nextafter(bounds[below], np.float32(np.inf))
    starts = np.arange(_BIN_COUNT, dtype=np.float32) / np.float32(_BIN_COUNT)
    first_code = np.searchsorted(bounds, starts, side="right")
    padded = np.append(bounds, np.float32(np.inf))
    return bounds, first_code.astype(np.uint8), padded[first_code]


def to_srgb8(radiance: np.ndarray, exposure: float) -> np.ndarray:
    """Exposed, clipped and sRGB-encoded 8-bit image (H, W, 3) uint8: each value's code is the
    nearest to its encoding (module docstring)."""
    linear = np.nan_to_num(np.asarray(radiance, dtype=np.float32) * np.float32(exposure), nan=0.0)
    np.clip(linear, 0.0, 1.0, out=linear)
    _, first_code, next_bound = srgb8_bounds()
    bins = np.minimum((linear * _BIN_COUNT).astype(np.int32), _BIN_COUNT - 1)
    codes = first_code[bins]
    codes += linear >= next_bound[bins]
    return codes
