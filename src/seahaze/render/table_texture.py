"""The diffuse-field tables as the ``physical`` integrator reads them, one texel per lookup.

:mod:`seahaze.render.diffuse_table` traces ``J[z, μ, φ, rgb]`` per level on a coarse grid. The
integrator looks every level up at every in-scattering point of every segment, so the lookup
is a large part of a level's cost, and the layout is chosen for it:

* **Height** is upsampled :data:`Z_UPSAMPLE` times by linear interpolation once per scene and
  then read at the nearest fine bin — within an eighth of a traced bin of linear interpolation,
  at half the memory reads.
* **Direction** is filtered stochastically: of the four texels that bilinear interpolation in
  (``μ``, folded azimuth from the sun) would blend, a segment reads one, each with probability
  its bilinear weight, so the expected value is the bilinear one (stochastic texture filtering:
  Pharr, Wronski, Salvi & Fajardo (2024), Filtering after shading with stochastic texture
  filtering, Proc. ACM Comput. Graph. Interact. Tech. 7(1)). The choice is made once per
  segment from one uniform number and serves every level and height; the pixel's samples
  average it out. A lookup reads a quarter of the memory, and the levels' noise does not
  change measurably (docs/benchmarks.md, "Design measurements").
* **Memory order** ``(μ, φ, z, level, rgba)``: every level's value of one texel sits in one run
  of memory (a segment looks all levels up in the same direction), and RGB is padded to four
  floats so that one packet gather reads a texel (faster than one scalar gather per channel
  with the levels far apart, the images bit-identical: docs/benchmarks.md, "Design
  measurements").
"""

from __future__ import annotations

from typing import Any

import numpy as np

from . import jit_haze

Z_UPSAMPLE = 4
"""Height bins of the integrator's tables per bin of the traced ones."""


def upsampled_tables(tables: np.ndarray, n_levels: int) -> np.ndarray:
    """Tables (n_z, n_mu, n_phi, 3L) as (n_mu, n_phi, n_z × Z_UPSAMPLE, L, 4) float32, linearly
    interpolated in height at the fine bins' centres (clamped at the ends, like a texture), RGB
    padded with a zero."""
    n_z = tables.shape[0]
    fine = (np.arange(n_z * Z_UPSAMPLE) + 0.5) / Z_UPSAMPLE - 0.5  # in coarse texel units
    low = np.clip(np.floor(fine), 0, n_z - 1).astype(int)
    high = np.clip(low + 1, 0, n_z - 1)
    f = np.clip(fine - low, 0.0, 1.0).astype(np.float32)[:, None, None, None]
    values = np.asarray(tables, np.float32)
    up = (1.0 - f) * values[low] + f * values[high]
    per_level = up.reshape(n_z * Z_UPSAMPLE, *tables.shape[1:3], n_levels, 3)
    packed = np.zeros((*tables.shape[1:3], n_z * Z_UPSAMPLE, n_levels, 4), np.float32)
    packed[..., :3] = per_level.transpose(1, 2, 0, 3, 4)
    return packed


def _linear_taps(u: Any, n: int, periodic: bool = False) -> list[tuple[Any, Any]]:
    """The two texels and weights of linear interpolation at coordinate ``u`` in ``[0, 1]`` of
    an ``n``-texel axis with clamped edges, or wrapped ones if ``periodic`` (texel centres at
    ``(i + 0.5)/n``, as drjit's textures)."""
    import drjit as dr
    import mitsuba as mi

    x = u * n - 0.5
    i0 = dr.floor(x)
    f = x - i0
    if periodic:  # an unfolded azimuth: the last texel's neighbour is the first
        low = mi.UInt32(dr.select(i0 < 0.0, i0 + n, dr.minimum(i0, n - 1)))
        high = mi.UInt32(dr.select(i0 + 1.0 >= n, i0 + 1.0 - n, dr.maximum(i0 + 1.0, 0.0)))
        return [(low, 1.0 - f), (high, f)]
    low = mi.UInt32(dr.clip(i0, 0, n - 1))
    high = mi.UInt32(dr.clip(i0 + 1.0, 0, n - 1))
    return [(low, 1.0 - f), (high, f)]


class TableTexture:
    """Every level's table of one pass, uploaded for the integrator's kernel."""

    def __init__(self, tables: np.ndarray, n_levels: int, folded: bool = True) -> None:
        """``tables`` (n_z, n_mu, n_phi, 3L): channels ``3k..3k+2`` are level ``k``'s RGB;
        ``folded``: their azimuths folded about the sun's vertical plane, or not
        (:class:`seahaze.render.diffuse_table.TableGrid`)."""
        fine = upsampled_tables(tables, n_levels)
        self.n_levels, self.folded = n_levels, folded
        self.grid = fine.shape[0:3]  # (n_mu, n_phi, n_z fine)
        self.values = jit_haze.owned_floats(fine)

    def toward(self, travel: Any, cos_sun: Any, sin_sun: Any, u: Any) -> Any:
        """A function ``(level, z / top) → RGB``: the diffuse in-scattering toward unit travel
        direction ``travel`` at a relative height in the slab (see the module docstring);
        ``cos_sun``, ``sin_sun``: of the sun's azimuth; ``u``: a uniform number in [0, 1)
        that picks the texel (stochastic bilinear filtering, module docstring)."""
        import drjit as dr
        import mitsuba as mi

        n_mu, n_phi, n_z = self.grid
        phi = jit_haze.azimuth_fraction(travel.x, travel.y, cos_sun, sin_sun, self.folded)
        i_mu, u = _pick_tap(_linear_taps((travel.z + 1.0) * 0.5, n_mu), u)
        i_phi, _ = _pick_tap(_linear_taps(phi, n_phi, not self.folded), u)
        offset = (i_mu * n_phi + i_phi) * n_z

        def lookup(level: int, height: Any) -> Any:
            iz = mi.UInt32(dr.clip(dr.floor(height * n_z), 0, n_z - 1))
            rgba = dr.gather(mi.Vector4f, self.values, (offset + iz) * self.n_levels + level)
            return mi.Color3f(rgba.x, rgba.y, rgba.z)

        return lookup


def _pick_tap(taps: list[tuple[Any, Any]], u: Any) -> tuple[Any, Any]:
    """One of linear interpolation's two texels, each with probability its weight, chosen by
    uniform ``u``, and ``u`` rescaled to [0, 1) within the choice (for the next axis)."""
    import drjit as dr

    (low, w_low), (high, _) = taps
    first = u < w_low
    rest = dr.select(first, u / w_low, (u - w_low) / (1.0 - w_low))
    return dr.select(first, low, high), dr.clip(rest, 0.0, 0.99999994)
