"""Reduced lengths through haze that varies across the sea, in one drjit kernel.

The exact per-pixel optical depths of a patchy or banked haze (the ``transmission/`` maps,
``meta``, ``asm`` and the ``physical`` mode's pixel ratios) are integrals of the field along
each pixel's ray, ``ℓ = ∫ c ρ_v(z) m(x, y, z) ds`` (:mod:`seahaze.nonuniform`). This module
evaluates them with the quadrature :class:`seahaze.nonuniform.NonUniformHaze` plans — the same
panels (no longer than the field's scales allow), three Gauss–Legendre nodes per panel, the
same field (:mod:`seahaze.render.field_medium`'s, the lattice hash and seeds of
:mod:`seahaze.haze_field`) — but in float64 in a single drjit kernel: each ray loops over its
own panels (a symbolic loop), so the rays need neither grouping by panel count nor
temporaries per point. numpy evaluates the same sums one array pass per operation.

The field's parameters that vary between scenes of a batch — the drift travelled, the seed —
are kernel parameters, not literals: the kernel compiles once per kind of field.

``tests/test_nonuniform.py`` holds it to Simpson's rule on 0.1 m steps within 1e-4, as it
holds the numpy sum; ``scripts/bench_pixel_density.py`` measures what it costs.

Import this module only once a Mitsuba variant is set.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import drjit as dr
import mitsuba as mi
import numpy as np

from ..medium import HazeMedium, drjit_ops
from ..nonuniform import GAUSS_NODES, GAUSS_WEIGHTS, NonUniformHaze
from .field_medium import field_modulation

SEED_MASK = 0xFFFFFFFFFFFFFFFF
"""The lattice hash's seeds are taken modulo 2⁶⁴ (:func:`seahaze.haze_field.lattice_value`)."""


def with_kernel_quadrature(medium: HazeMedium) -> HazeMedium:
    """``medium`` with its reduced lengths integrated by :func:`kernel_path_lengths` and its
    density at points evaluated by :func:`kernel_density` when it varies across the sea (a
    fresh cache of path lengths); any other medium as it is."""
    if not isinstance(medium, NonUniformHaze) or medium.quadrature is not None:
        return medium
    return replace(
        medium,
        quadrature=kernel_path_lengths,
        point_density=kernel_density,
        _lengths_cache={},
    )


def kernel_path_lengths(
    medium: NonUniformHaze,
    origins: np.ndarray,
    directions: np.ndarray,
    enter: np.ndarray,
    length: np.ndarray,
    panels: np.ndarray,
) -> np.ndarray:
    """``∫ c ρ_v m ds`` (m, (N,) float64) along each ray ``origins + s·directions`` ((N, 3),
    world frame, unit directions) over ``s`` from ``enter`` to ``enter + length`` (m, (N,)),
    in ``panels`` (N,) equal panels of three Gauss–Legendre nodes each (0 panels: 0)."""
    n = len(directions)
    if n == 0:
        return np.zeros(0)
    float64 = mi.Float64
    o = mi.Point3d(*(np.ascontiguousarray(origins[:, k], np.float64) for k in range(3)))
    d = mi.Vector3d(*(np.ascontiguousarray(directions[:, k], np.float64) for k in range(3)))
    count = mi.UInt32(np.asarray(panels, np.uint32))
    width = float64(np.asarray(length, np.float64) / np.where(panels > 0, panels, 1))
    start = float64(np.asarray(enter, np.float64))
    travelled, seed = _field_parameters(medium)
    ops = drjit_ops()
    # Half the nodes and weights: a panel of width w maps [-1, 1] onto [-w/2, w/2].
    halves = [(0.5 * x, 0.5 * w) for x, w in zip(GAUSS_NODES, GAUSS_WEIGHTS, strict=True)]

    def unfinished(i: Any, total: Any) -> Any:
        return i < count

    def one_panel(i: Any, total: Any) -> tuple[Any, Any]:
        centre = start + (float64(i) + 0.5) * width
        for node, weight in halves:
            p = dr.fma(d, dr.fma(width, float(node), centre), o)
            rho = medium.profile.density(p.z, ops)
            rho *= field_modulation(medium.field, p, travelled, seed)
            total = dr.fma(float(weight) * width, rho, total)
        return i + 1, total

    _, total = dr.while_loop((dr.zeros(mi.UInt32, n), dr.zeros(float64, n)), unfinished, one_panel)
    return medium.scale * np.asarray(total, np.float64)


def kernel_density(
    medium: NonUniformHaze, x: np.ndarray, y: np.ndarray, z: np.ndarray
) -> np.ndarray:
    """:meth:`seahaze.nonuniform.NonUniformHaze.density_at` — ``c ρ_v(z) m(x, y, z)`` at
    world points ``x``, ``y``, ``z`` (m, arrays of one shape), float64 — in one drjit kernel
    (a :class:`seahaze.nonuniform.PointDensity`): the same formulas and lattice hash, without
    numpy's pass over the points per operation (the diffuse ratios' ray sums read millions
    of points per frame)."""
    shape = np.shape(x)
    p = mi.Point3d(*(np.ascontiguousarray(np.ravel(c), np.float64) for c in (x, y, z)))
    if dr.width(p) == 0:
        return np.zeros(shape)
    travelled, seed = _field_parameters(medium)
    rho = medium.profile.density(p.z, drjit_ops())
    rho *= field_modulation(medium.field, p, travelled, seed)
    return medium.scale * np.asarray(rho, np.float64).reshape(shape)


def _field_parameters(medium: NonUniformHaze) -> tuple[Any, Any]:
    """The field's kernel parameters: the drift travelled (m) and the patches' seed (None
    without patches)."""
    drift = medium.field.drift
    travelled = dr.opaque(mi.Float64, drift.speed_m_s * drift.time_s)
    patches = medium.field.patches
    seed = None if patches is None else dr.opaque(mi.UInt64, patches.seed & SEED_MASK)
    return travelled, seed
