"""drjit versions of the haze formulas of :mod:`seahaze.haze`, for the traced integrator.

The same formulas as the numpy ones, written with drjit operations so that they trace into the
``physical`` mode's compiled kernel; ``tests/test_jit_haze.py`` holds them to the numpy
originals. Arguments are drjit arrays (or Python floats where noted).
"""

from __future__ import annotations

from typing import Any

from ..haze import FOUR_PI

FLAT_DZ = 1e-7
"""A ray with ``|d_z|`` below this is horizontal for the slab (float32 directions)."""


def slab_interval(oz: Any, dz: Any, bottom: Any, top: Any) -> tuple[Any, Any]:
    """Ray parameters ``[enter, leave]`` (``enter ≥ 0``) of ``o + s·d`` inside the slab
    ``bottom ≤ z ≤ top``; as :func:`seahaze.haze.slab_interval`."""
    import drjit as dr

    inv = dr.rcp(dz)
    s_bottom = (bottom - oz) * inv
    s_top = (top - oz) * inv
    flat = dr.abs(dz) < FLAT_DZ
    inside = (oz >= bottom) & (oz <= top)
    inf = dr.inf
    enter = dr.select(flat, dr.select(inside, 0.0, inf), dr.minimum(s_bottom, s_top))
    leave = dr.select(flat, dr.select(inside, inf, -inf), dr.maximum(s_bottom, s_top))
    return dr.maximum(enter, 0.0), leave


def hg_phase(cos_theta: Any, g: Any) -> Any:
    """Henyey–Greenstein phase function (1/sr); as :func:`seahaze.haze.hg_phase`."""
    import drjit as dr

    denom = 1.0 + g * g - 2.0 * g * cos_theta
    return (1.0 - g * g) / (FOUR_PI * denom * dr.sqrt(denom))
