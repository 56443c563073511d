"""Sampling periodic grids (the FFT ocean's patches): bilinear with wrap-around, and trilinear
across a low-pass pyramid."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def sample_periodic_bilinear(
    grids: np.ndarray, size_m: float, x: np.ndarray, y: np.ndarray
) -> np.ndarray:
    """Bilinear interpolation with wrap-around of periodic grids.

    Args:
        grids: ``(F, N, N)`` fields indexed ``[field, iy, ix]``, sample ``(iy, ix)`` at
            ``(ix, iy)·size_m/N``.
        size_m: period (m).
        x, y: positions (m), any equal shape.

    Returns:
        ``(F, *x.shape)`` interpolated values.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    n = grids.shape[-1]
    flat = grids.reshape(grids.shape[0], n * n)
    u = (x.ravel() / size_m) * n
    v = (y.ravel() / size_m) * n
    u_floor = np.floor(u)
    v_floor = np.floor(v)
    tu = u - u_floor
    tv = v - v_floor
    i0 = u_floor.astype(np.int64) % n
    j0 = v_floor.astype(np.int64) % n
    i1 = (i0 + 1) % n
    j1 = (j0 + 1) % n
    row0 = j0 * n
    row1 = j1 * n
    top = flat[:, row0 + i0] * (1.0 - tu) + flat[:, row0 + i1] * tu
    bottom = flat[:, row1 + i0] * (1.0 - tu) + flat[:, row1 + i1] * tu
    out = top * (1.0 - tv) + bottom * tv
    return out.reshape(grids.shape[0], *x.shape)


def sample_pyramid(
    levels: Sequence[np.ndarray], size_m: float, x: np.ndarray, y: np.ndarray, level: np.ndarray
) -> np.ndarray:
    """Trilinear sampling of a low-pass pyramid (``FFTCascade.displacement_pyramid`` in
    :mod:`seahaze.ocean.fft`): bilinear in space at the two levels around the fractional
    ``level`` (per point, clamped to the available range) and linear between them. Returns
    ``(F, n_points)``."""
    x = np.ravel(x)
    y = np.ravel(y)
    last = len(levels) - 1
    level = np.clip(np.ravel(level), 0.0, float(last))
    lower = np.minimum(np.floor(level).astype(np.int64), max(last - 1, 0))
    frac = level - lower
    out = np.zeros((levels[0].shape[0], x.size))
    for lv in np.unique(lower):
        sel = lower == lv
        a = sample_periodic_bilinear(levels[lv], size_m, x[sel], y[sel])
        if lv + 1 <= last:
            b = sample_periodic_bilinear(levels[lv + 1], size_m, x[sel], y[sel])
            out[:, sel] = a + (b - a) * frac[sel]
        else:
            out[:, sel] = a
    return out
