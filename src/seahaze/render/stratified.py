"""Mitsuba's ``multijitter`` sampler with the sample count as a kernel parameter.

The ``physical`` mode draws its camera paths from correlated multi-jittered samples (Kensler,
A. (2013). Correlated Multi-Jittered Sampling. Pixar Technical Memo 13-01): each pixel's
``n = a·b`` samples fill an ``a × b`` grid of strata in every pair of dimensions, in an order
shuffled per pixel and per dimension by Kensler's hash-based permutation. Mitsuba's C++
sampler writes ``n``, ``a``, ``b`` and their reciprocals into the kernel as constants, so every
sample count compiles the render kernels again (docs/benchmarks.md, "What does a new image size
or sample count compile?"). :class:`StratifiedSampler` is the same algorithm — the same
seeding, permutations and jitter, so it draws the same numbers as Mitsuba's sampler
(``tests/test_stratified.py``) — with those counts held as opaque drjit values.

It offers what seahaze's integrators ask of a sampler (``next_1d``, ``next_2d``) and is a
drjit PyTree (``DRJIT_STRUCT``), so it can be the state of a symbolic loop. Its dimension index
is a drjit value too, as in Mitsuba: inside a loop each iteration draws from its own dimensions.
"""

from __future__ import annotations

from typing import Any, ClassVar

import drjit as dr
import mitsuba as mi

_PERMUTE_1D = 0x45FBE943
_PERMUTE_2D = 0x51633E2D
_PERMUTE_X = 0x68BC21EB
_PERMUTE_Y = 0x02E5BE93
"""Mitsuba's multipliers of the per-dimension seed for each permutation it draws."""


def grid_of(spp: int) -> tuple[int, int]:
    """The ``(a, b)`` strata of ``spp`` samples as Mitsuba lays them out: ``b = ⌊√spp⌋`` rows of
    ``a = ⌈spp / b⌉`` columns (``a·b`` may exceed ``spp``: Mitsuba then rounds the count up)."""
    rows = int(dr.sqrt(float(spp)))  # Mitsuba takes the float32 square root
    return (spp + rows - 1) // rows, rows


def permute_kensler(index: Any, count: Any, seed: Any, active: Any = True) -> Any:
    """Kensler's permutation of ``index`` among ``0..count-1`` for ``seed`` (UInt32 arrays;
    ``count`` may be opaque): a hash restricted to the next power of two by its mask, applied
    again while the result falls outside the range (cycle walking), then offset by the seed."""
    w = count - 1
    for shift in (1, 2, 4, 8, 16):
        w |= w >> shift

    def scramble(i: Any) -> Any:
        i = i ^ seed
        i *= 0xE170893D
        i ^= seed >> 16
        i ^= (i & w) >> 4
        i ^= seed >> 8
        i *= 0x0929EB3F
        i ^= seed >> 23
        i ^= (i & w) >> 1
        i *= 1 | seed >> 27
        i *= 0x6935FA69
        i ^= (i & w) >> 11
        i *= 0x74DCB303
        i ^= (i & w) >> 2
        i *= 0x9E501CC3
        i ^= (i & w) >> 2
        i *= 0xC860A3DF
        i &= w
        i ^= i >> 5
        return i

    def walk(pending: Any, i: Any) -> tuple[Any, Any]:
        i = dr.select(pending, scramble(i), i)
        return pending & (i >= count), i

    _, index = dr.while_loop(
        (mi.Bool(active), mi.UInt32(index)),
        lambda pending, _i: dr.detach(pending),
        walk,
        label="kensler permutation",
    )
    return (index + seed) % count


class StratifiedSampler:
    """Correlated multi-jittered samples for a wavefront of ``pixels × spp`` lanes, each pixel's
    samples neighbours (see the module docstring); :meth:`seeded` makes one."""

    DRJIT_STRUCT: ClassVar[dict[str, type]] = {
        "rng": mi.PCG32,
        "permutation_seed": mi.UInt32,
        "sample_index": mi.UInt32,
        "dimension": mi.UInt32,
        "count": mi.UInt32,
        "columns": mi.UInt32,
        "rows": mi.UInt32,
        "inv_count": mi.Float,
        "inv_columns": mi.Float,
        "inv_rows": mi.Float,
    }

    def __init__(self, **fields: Any) -> None:
        for name, kind in self.DRJIT_STRUCT.items():
            setattr(self, name, fields.get(name, kind()))

    @classmethod
    def seeded(cls, spp: int, seed: int, samples: int | Any) -> StratifiedSampler:
        """A sampler of ``spp`` samples per pixel (which Mitsuba's grid must hold exactly:
        :func:`grid_of`) seeded as Mitsuba seeds ``multijitter`` with ``seed`` (its base seed
        0). ``samples``: each lane's sample, ``pixel·spp + index`` (``UInt32``), where Mitsuba's
        sampler would take that lane of its wavefront; or a wavefront size ``n``, lanes
        ``0 … n−1`` drawing samples ``0 … n−1`` as Mitsuba's do."""
        columns, rows = grid_of(spp)
        if columns * rows != spp:
            raise ValueError(f"{spp} samples do not fill a {columns} x {rows} grid")
        lane = dr.arange(mi.UInt32, samples) if isinstance(samples, int) else samples
        seed_value = dr.opaque(mi.UInt32, seed)
        v0, v1 = mi.sample_tea_32(seed_value, lane)
        count = dr.opaque(mi.UInt32, spp)
        first_of_pixel = count * (lane // count)
        permutation_seed, _ = mi.sample_tea_32(dr.opaque(mi.UInt32, 0), first_of_pixel + seed_value)
        rng = mi.PCG32()  # seeded, not constructed with a size: that adds the lane to both
        rng.seed(mi.UInt64(v0), mi.UInt64(v1))
        return cls(
            rng=rng,
            permutation_seed=permutation_seed,
            sample_index=lane % count,
            dimension=dr.opaque(mi.UInt32, 0),
            count=count,
            columns=dr.opaque(mi.UInt32, columns),
            rows=dr.opaque(mi.UInt32, rows),
            inv_count=dr.opaque(mi.Float, 1.0 / spp),
            inv_columns=dr.opaque(mi.Float, 1.0 / columns),
            inv_rows=dr.opaque(mi.Float, 1.0 / rows),
        )

    def _next_dimension(self) -> Any:
        seed = self.permutation_seed + self.dimension
        self.dimension = self.dimension + 1
        return seed

    def next_1d(self, active: Any = True) -> Any:
        """One stratified value in [0, 1) per lane."""
        seed = self._next_dimension()
        p = mi.Float(permute_kensler(self.sample_index, self.count, seed * _PERMUTE_1D, active))
        return (p + self.rng.next_float32(active)) * self.inv_count

    def next_2d(self, active: Any = True) -> Any:
        """One multi-jittered point in [0, 1)² per lane."""
        seed = self._next_dimension()
        s = permute_kensler(self.sample_index, self.count, seed * _PERMUTE_2D, active)
        y = s // self.columns
        x = s - y * self.columns
        sx = permute_kensler(x, self.columns, seed * _PERMUTE_X, active)
        sy = permute_kensler(y, self.rows, seed * _PERMUTE_Y, active)
        jx = self.rng.next_float32(active)
        jy = self.rng.next_float32(active)
        return mi.Point2f(
            (mi.Float(x) + (mi.Float(sy) + jx) * self.inv_rows) * self.inv_columns,
            (mi.Float(y) + (mi.Float(sx) + jy) * self.inv_columns) * self.inv_rows,
        )
