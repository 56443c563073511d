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

Dither (``render.dither``, docs/benchmarks.md "Why are the PNGs dithered?"): rounding to the
nearest code turns a smooth hazy sky, whose render noise is a tenth of a code, into bands one
code apart, which a contrast stretch shows. With a dither seed each value gets triangular noise
of ±1 code (the sum of two uniform ones) before rounding: the mean of many pixels is the float
value and the noise's power is the same at every value, so the gradient survives as its local
mean under an even grain (uniform noise of one code, random rounding, left faint stripes of
finer grain where values lie near a code). Values clipped to black or white stay so (a sun
glint stays 255); within one code of them the clip pulls the mean inward by up to 1/8 code.
The decision is made in linear values against a table of thresholds
(:func:`srgb8_dither_thresholds`), like the nearest code, so it needs no per-pixel power and the
bytes depend on nothing but the input and the seed; the noise is the raw PCG64 stream of the
seed (numpy guarantees its bit generators' streams, not its distributions').
Files are written by :mod:`seahaze.fileio`.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from typing import Any

import numpy as np

from .seeds import dither_seed

AUTO_KEY = 0.6
"""Linear display value of the clean horizon sky under ``exposure: auto``."""
HORIZON_BAND_DEG = 10.0
SKY_HIGHLIGHT_QUANTILE = 0.98
"""Under ``exposure: auto`` at most the brightest 2 % of the sky's pixels are brighter than
white: a sky brighter above than at its horizon (the Belt of Venus over the Earth's shadow
at dusk, the glow over a low sun) lowers the exposure rather than burn out."""
SRGB_LINEAR_KNEE = 0.04045
"""Encoded value below which the sRGB transfer function is linear (IEC 61966-2-1:1999)."""
_BIN_COUNT = 4096
"""Bins of the linear range [0, 1] in the code lookup; each holds at most one code bound
(the closest bounds, at black, are 1/(255·12.92) ≈ 3.0e-4 apart, a bin 2.4e-4 wide)."""
DITHER_STEPS = 256
"""Thresholds per code step of the dither: each uniform part of its noise is one byte, so the
noise moves in steps of 1/256 code."""
REC709_LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
"""Luminance weights of linear sRGB / Rec. 709 primaries (ITU-R BT.709-6)."""


def luminance(rgb: np.ndarray) -> np.ndarray:
    """Relative luminance Y of linear sRGB radiance (..., 3)."""
    return np.asarray(rgb, dtype=np.float64) @ REC709_LUMINANCE


def auto_exposure(clean: np.ndarray, distance_m: np.ndarray, elevation_deg: np.ndarray) -> float:
    """Exposure factor for a scene from its clean radiance, distance and pixel elevations: the
    horizon sky's median luminance at :data:`AUTO_KEY` (without sky, the mean at 0.18), lowered
    where more than the sky's brightest 2 % would then be brighter than white
    (:data:`SKY_HIGHLIGHT_QUANTILE`)."""
    y = luminance(clean)
    sky = np.isinf(distance_m)
    horizon_sky = sky & (elevation_deg < HORIZON_BAND_DEG)
    if horizon_sky.sum() >= 4:
        reference, key = float(np.median(y[horizon_sky])), AUTO_KEY
    else:
        reference, key = float(np.mean(y)), 0.18
    if not (reference > 0 and np.isfinite(reference)):
        return 1.0
    exposure = key / reference
    if sky.sum() >= 4:
        highlight = float(np.quantile(y[sky], SKY_HIGHLIGHT_QUANTILE))
        if highlight > 0 and np.isfinite(highlight):
            exposure = min(exposure, 1.0 / highlight)
    return exposure


def srgb_decode(encoded: np.ndarray) -> np.ndarray:
    """Linear value of sRGB-encoded values in [0, 1]: the IEC 61966-2-1:1999 transfer function,
    ``V/12.92`` up to :data:`SRGB_LINEAR_KNEE`, ``((V + 0.055)/1.055)^2.4`` above."""
    v = np.asarray(encoded, dtype=np.float64)
    return np.where(v <= SRGB_LINEAR_KNEE, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)


def _float32_at_or_above(exact: np.ndarray) -> np.ndarray:
    """The smallest float32 at or above each float64 value: a float32 value reaches it exactly
    when it reaches the exact value, so codes decided against it are those of the float64
    encoding."""
    bounds = exact.astype(np.float32)
    below = bounds < exact
    bounds[below] = np.nextafter(bounds[below], np.float32(np.inf))
    return bounds


def _code_lookup(bounds: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For each of :data:`_BIN_COUNT` equal bins of [0, 1]: the code at the bin's start (how
    many of the 255 ascending ``bounds`` lie at or below it) and the one bound inside the bin
    (``inf`` if none)."""
    starts = np.arange(_BIN_COUNT, dtype=np.float32) / np.float32(_BIN_COUNT)
    first_code = np.searchsorted(bounds, starts, side="right")
    padded = np.append(bounds, np.float32(np.inf))
    return first_code.astype(np.uint8), padded[first_code]


@functools.cache
def srgb8_bounds() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The linear bounds between 8-bit sRGB codes and a lookup of them.

    Returns ``(bounds, first_code, next_bound)``: ``bounds[k]`` (255 float32 values) is the
    smallest float32 whose encoding reaches ``(k + 0.5)/255``, where rounding goes from code
    ``k`` to ``k + 1``; for each of :data:`_BIN_COUNT` equal bins of [0, 1], ``first_code`` is
    the code at the bin's start and ``next_bound`` the one bound inside the bin (``inf`` if
    none).
    """
    bounds = _float32_at_or_above(srgb_decode((np.arange(255) + 0.5) / 255.0))
    return (bounds, *_code_lookup(bounds))


@functools.cache
def srgb8_dither_thresholds() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The lookups of the dithered encoding.

    Returns ``(first_code, next_bound, thresholds)``: the code lookup (as in
    :func:`srgb8_bounds`) of the codes' own values, the smallest float32 whose encoding reaches
    ``k/255`` for k = 1..255, which gives each value the code ``k`` at or below its encoding;
    and ``thresholds``, 256 × :data:`DITHER_STEPS` float32 values flattened, where
    ``thresholds[k, i]`` is the smallest float32 whose encoding reaches
    ``(k + (i + 1)/DITHER_STEPS)/255``: a value of code ``k`` plus a noise of ``d`` whole codes
    and ``1 - (i + 1)/DITHER_STEPS`` rounds down to ``k + d + 1`` from ``thresholds[k, i]`` on.
    Row 255 is ``inf``: white has no code above it.
    """
    floors = _float32_at_or_above(srgb_decode(np.arange(1, 256) / 255.0))
    first_code, next_bound = _code_lookup(floors)
    steps = np.arange(1, DITHER_STEPS + 1) / DITHER_STEPS
    exact = srgb_decode((np.arange(255)[:, None] + steps[None, :]) / 255.0)
    thresholds = np.full((256, DITHER_STEPS), np.inf, dtype=np.float32)
    thresholds[:255] = _float32_at_or_above(exact)
    return first_code, next_bound, thresholds.ravel()


def dither_noise(seed: np.random.SeedSequence, count: int) -> np.ndarray:
    """``count`` noise bytes (uint8) of ``seed``: the little-endian bytes of its raw PCG64
    stream, the same on every platform and numpy version."""
    words = np.random.PCG64(seed).random_raw((count + 7) // 8)
    return words.astype("<u8").view(np.uint8)[:count]


def _lookup(linear: np.ndarray, first_code: np.ndarray, next_bound: np.ndarray) -> np.ndarray:
    """The code of each value of ``linear`` in [0, 1] by a :func:`_code_lookup` table."""
    bins = np.minimum((linear * _BIN_COUNT).astype(np.int32), _BIN_COUNT - 1)
    codes = first_code[bins]
    codes += linear >= next_bound[bins]
    return codes


def to_srgb8(
    radiance: np.ndarray, exposure: float, dither: np.random.SeedSequence | None = None
) -> np.ndarray:
    """Exposed, clipped and sRGB-encoded 8-bit image (H, W, 3) uint8.

    Without ``dither`` each value's code is the nearest to its encoding; with it (a seed of
    :func:`seahaze.seeds.dither_seed`) the nearest to its encoding plus triangular noise of ±1
    code, so that local means follow the float image (module docstring).
    """
    linear = np.nan_to_num(np.asarray(radiance, dtype=np.float32) * np.float32(exposure), nan=0.0)
    np.clip(linear, 0.0, 1.0, out=linear)
    if dither is None:
        _, first_code, next_bound = srgb8_bounds()
        return _lookup(linear, first_code, next_bound)
    return _dithered(linear, dither)


def _dithered(linear: np.ndarray, dither: np.random.SeedSequence) -> np.ndarray:
    """The dithered codes of ``linear`` (clipped to [0, 1]).

    A value at code position ``k + f`` (``k`` its code at or below, ``0 <= f < 1``) with noise
    ``n`` gets ``floor(k + f + n + 1/2)``. The noise is ``(a + b + 1)/256 - 1`` for two noise
    bytes ``a`` and ``b``: triangular on (-1, 1), mean 0. So ``n + 1/2 = m/256`` with
    ``m = a + b - 127``, whole codes ``d = m // 256`` and a part ``t = m % 256``, and the code is
    ``k + d``, plus one where ``f >= 1 - t/256``: a threshold of the table, compared in linear
    values.
    """
    first_code, next_bound, thresholds = srgb8_dither_thresholds()
    noise = dither_noise(dither, 2 * linear.size).reshape(*linear.shape, 2)
    m = noise[..., 0].astype(np.int16) + noise[..., 1] - 127
    codes = _lookup(linear, first_code, next_bound).astype(np.int16)
    index = codes.astype(np.int32) * DITHER_STEPS + (DITHER_STEPS - 1 - (m & 255))
    codes += (m >> 8) + (linear >= thresholds[index])
    np.clip(codes, 0, 255, out=codes)
    # Clipped values are black or white, not a gradient: no grain on a sun glint.
    codes[linear <= 0.0] = 0
    codes[linear >= 1.0] = 255
    return codes.astype(np.uint8)


def dither_meta(dither: str, seed: int) -> dict[str, Any]:
    """``meta``'s record of how the scene's PNGs are quantised (in its ``render`` entry):
    ``render.dither`` and, when it is on, the seed of :func:`seahaze.seeds.dither_seed`, so
    ``to_srgb8(exr, exposure, dither_seed(dither_seed, scene, level))`` gives the PNG's
    pixels (the EXR undenoised; denoising off)."""
    return {"dither": dither, "dither_seed": seed} if dither == "on" else {"dither": dither}


def png_dither(
    render_meta: Mapping[str, Any], scene: str, level: str
) -> np.random.SeedSequence | None:
    """The dither of the PNG of image ``level`` of ``scene`` by ``meta``'s ``render`` record
    (:func:`dither_meta`): its seed when dithering is on, else None (the nearest code; also a
    render whose meta does not say, as every render before the dither did)."""
    if render_meta.get("dither") != "on":
        return None
    return dither_seed(int(render_meta["dither_seed"]), scene, level)
