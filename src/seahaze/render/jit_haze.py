"""drjit versions of the haze formulas of :mod:`seahaze.haze`, for the traced integrator.

The same formulas as the numpy ones, written with drjit operations so that they trace into the
``physical`` mode's compiled kernels; ``tests/test_jit_haze.py`` holds them to the numpy
originals. Arguments are drjit arrays (or Python floats where noted). Also the one rule for
data those kernels read (:func:`owned_floats`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..haze import FOUR_PI

TINY_OPTICAL_DEPTH = 1e-3
"""Below this, ``1 − e^{−τ}`` is evaluated as ``τ (1 − τ/2)`` (float32 cancellation)."""
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


def hg_sample_cos(u: Any, g: Any) -> Any:
    """Cosine of a scattering angle drawn from the HG phase function for uniform ``u``; as
    :func:`seahaze.haze.hg_sample_cos`. ``g`` may be an opaque drjit value (no recompilation
    for another ``g``): the isotropic case is a select, not a Python branch."""
    import drjit as dr

    sq = (1.0 - g * g) / (1.0 - g + 2.0 * g * u)
    anisotropic = dr.clip((1.0 + g * g - sq * sq) / (2.0 * g), -1.0, 1.0)
    return dr.select(dr.abs(g) < 1e-3, 1.0 - 2.0 * u, anisotropic)


def rotate_directions(d: tuple[Any, Any, Any], cos_theta: Any, phi: Any) -> tuple[Any, Any, Any]:
    """Unit vectors at angle ``acos(cos_theta)`` from the unit vector ``d`` (components), azimuth
    ``phi``; as :func:`seahaze.haze.rotate_directions` (the same orthonormal frame)."""
    import drjit as dr

    dx, dy, dz = d
    sin_theta = dr.sqrt(dr.maximum(0.0, 1.0 - cos_theta * cos_theta))
    sign = dr.select(dz >= 0.0, 1.0, -1.0)
    a = -1.0 / (sign + dz)
    b = dx * dy * a
    tx, ty, tz = 1.0 + sign * dx * dx * a, sign * b, -sign * dx
    sx, sy, sz = b, sign + dy * dy * a, -dy
    sin_phi, cos_phi = dr.sincos(phi)
    cp, sp = sin_theta * cos_phi, sin_theta * sin_phi
    ox = cp * tx + sp * sx + cos_theta * dx
    oy = cp * ty + sp * sy + cos_theta * dy
    oz = cp * tz + sp * sz + cos_theta * dz
    norm = dr.rsqrt(ox * ox + oy * oy + oz * oz)
    return ox * norm, oy * norm, oz * norm


def folded_azimuth(x: Any, y: Any, cos_sun: Any, sin_sun: Any) -> Any:
    """Azimuth (rad, in ``[0, π]``) of horizontal direction ``(x, y)`` from the sun's azimuth
    (given by its cosine and sine), folded: the sky is symmetric about the sun's vertical
    plane. The direction turned into the sun's frame, one ``atan2``; as the azimuth bins of
    :func:`seahaze.render.diffuse_table.direction_bins`."""
    import drjit as dr

    along = x * cos_sun + y * sin_sun
    across = dr.abs(y * cos_sun - x * sin_sun)
    return dr.atan2(across, along)


def owned_floats(values: np.ndarray) -> Any:
    """``values`` as an evaluated drjit Float array in drjit's own memory. An array made
    straight from numpy may keep numpy's buffer, whose alignment depends on where numpy put it;
    drjit compiles packet gathers only from an aligned source, so the kernel (and its hash)
    would change from one scene to the next and be compiled again."""
    import mitsuba as mi

    return _owned(mi.Float, np.ascontiguousarray(values, np.float32).ravel())


def owned_indices(values: np.ndarray) -> Any:
    """``values`` as an evaluated drjit UInt32 array in drjit's own memory, at least two long
    (a one-element array would be a scalar, another kernel): :func:`owned_floats` for the
    indices of a gather; a one-element ``values`` is repeated."""
    import mitsuba as mi

    values = np.ascontiguousarray(values, np.uint32).ravel()
    return _owned(mi.UInt32, np.repeat(values, 2) if len(values) == 1 else values)


def _owned(array_type: Any, values: np.ndarray) -> Any:
    """``array_type`` of ``values``, computed (hence a fresh, aligned allocation) and
    evaluated."""
    import drjit as dr

    array = array_type(values) + dr.opaque(array_type, 0)
    dr.eval(array)
    return array


def padded_floats(values: np.ndarray) -> Any:
    """:func:`owned_floats` of ``values`` plus one trailing zero: per-level parameters read by
    index. drjit treats a one-element array as a scalar, a different kernel from the one for
    several levels; the padding keeps one kernel for every level count."""
    return owned_floats(np.append(np.asarray(values, np.float32), np.float32(0.0)))


def sun_scattered_fraction(
    sigma: Any, near: Any, e_start: Any, climb: Any, inv_climb: Any, length: Any
) -> Any:
    """``σ ∫₀^ℓ e^{−(τ₀ + σ c s)} ds``: per unit of the sun's source, the light scattered
    toward a segment's start by its first ``length`` metres, each point's light attenuated on
    its way from the sun and on to the start. At distance ``s`` the two paths have optical
    depth ``τ₀ + σ c s``: ``τ₀ = e_start`` toward the sun from the start (``near`` =
    ``e^{−τ₀}``), plus ``σ s`` back to the start, less ``σ s d_z / μ_sun`` toward the sun
    (``c = climb = 1 − d_z / μ_sun``, negative where the segment climbs more steeply than the
    sun). In closed form ``(near − e^{−(τ₀ + σ c ℓ)}) / c``, by its series where ``σ c ℓ``
    is too small for float32. ``inv_climb`` = ``1 / c``, computed once for every level;
    ``sigma`` may be RGB."""
    import drjit as dr

    x = sigma * climb * length
    far = dr.exp(-dr.maximum(e_start + x, 0.0))  # τ at the end is >= 0: never overflows
    series = sigma * near * length * (1.0 - 0.5 * x)
    return dr.select(dr.abs(x) < TINY_OPTICAL_DEPTH, series, (near - far) * inv_climb)
