"""drjit versions of the phase-function formulas of :mod:`seahaze.haze`, for the kernels.

The Henyey–Greenstein phase function, its sampling and the frame it rotates in, written with
drjit operations so that they trace into the ``physical`` mode's compiled kernels (a Python
branch on ``g`` would bake it in); ``tests/test_jit_haze.py`` holds them to the numpy
originals. The medium's own formulas (where the haze is, optical depths) are written once for
both array libraries in :mod:`seahaze.medium`. Also the one rule for data those kernels read
(:func:`owned_floats`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..haze import FOUR_PI


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


def azimuth_fraction(x: Any, y: Any, cos_sun: Any, sin_sun: Any, folded: bool = True) -> Any:
    """Where horizontal direction ``(x, y)`` lies on a table's azimuth axis, in ``[0, 1]``:
    folded (:func:`folded_azimuth` over ``π``) for a sky symmetric about the sun's vertical
    plane; else the signed azimuth from the sun, ``[−π, π)`` mapped onto ``[0, 1)`` (the sun
    at ½), for a sky that is not (broken cloud). As
    :func:`seahaze.render.diffuse_table.direction_bins`."""
    import drjit as dr

    if folded:
        return folded_azimuth(x, y, cos_sun, sin_sun) / dr.pi
    along = x * cos_sun + y * sin_sun
    across = y * cos_sun - x * sin_sun
    return (dr.atan2(across, along) + dr.pi) * (0.5 / dr.pi)


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
