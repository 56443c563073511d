"""The sun's disk as the ``physical`` integrator samples it: its axis, the cone it is drawn
in, and its irradiance.

Mitsuba's ``sunsky`` sun is a limb-darkened disk of angular diameter :data:`SUN_APERTURE_DEG`.
Surfaces sample it uniformly in a cone a few float32 steps wider than the disk
(:func:`sun_cone_cos`), weighting each direction by its radiance. The haze's single
scattering needs only the disk's irradiance ``E = ∫_disk L dω`` (W m⁻² per RGB channel, on a
plane facing the sun) and a direction in the disk for the phase function and the shadow ray:
across 0.27° the Henyey–Greenstein phase changes by less than 0.1 % (its peak is tens of
degrees wide), so a direction uniform in the disk carrying ``E`` is the same light as the
limb-darkened disk without evaluating ``sunsky`` for every segment (:func:`disk_irradiance`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

SUN_APERTURE_DEG = 0.5358
"""Angular diameter (deg) of Mitsuba's ``sunsky`` sun disk (its ``sun_aperture`` default)."""
SUN_CONE_ULPS = 4
"""float32 steps (6e-8 each, 0.5 % of the disk's ``1 − cos``) the sampled cone is widened by."""
IRRADIANCE_GRID = 512
"""Points per axis of the stratified grid :func:`disk_irradiance` integrates the disk on."""


def sun_cone_cos() -> float:
    """Cosine of the half-angle of the cone the sun is sampled in: sunsky's disk, widened by
    :data:`SUN_CONE_ULPS` float32 steps so that it holds the whole disk however sunsky rounds
    its own edge (directions outside the disk have no radiance, so a wider cone only wastes a
    few samples; a narrower one would lose the limb). A float32 value, so that the density
    ``1 / (2π (1 − cos))`` is that of the cone the kernel samples."""
    c = np.float32(np.cos(np.radians(0.5 * SUN_APERTURE_DEG)))
    for _ in range(SUN_CONE_ULPS):
        c = np.nextafter(c, np.float32(0.0))
    return float(c)


def sun_axis(sun: Any) -> np.ndarray:
    """Unit direction (3,) toward the centre of the sun of a ``sunsky`` emitter, world frame."""
    import mitsuba as mi

    d = mi.traverse(sun)["sun_direction"]
    axis = np.array([float(d.x[0]), float(d.y[0]), float(d.z[0])])
    return axis / np.linalg.norm(axis)


def disk_irradiance(sun: Any, n: int = IRRADIANCE_GRID) -> np.ndarray:
    """The sun disk's irradiance ``∫ L dω`` (3,) of a sun-only ``sunsky`` emitter: its radiance
    at the centres of an ``n × n`` stratified grid mapped uniformly onto the sampling cone,
    averaged and divided by the cone's density (midpoint rule). The disk's edge falls between
    grid points; at 512² the result is within 0.05 % of a 4-million-sample Monte Carlo
    estimate (default scene's sun: 1.0720 against 1.0725 ± 0.0001 in green)."""
    import drjit as dr
    import mitsuba as mi

    from .jit_haze import owned_floats

    cos_max = sun_cone_cos()
    centres = (np.arange(n, dtype=np.float64) + 0.5) / n
    u, v = np.meshgrid(centres, centres, indexing="ij")
    # The grid in drjit's own memory and the sun's direction opaque: one compiled kernel for
    # every sun (a literal direction, or numpy's buffer alignment, made one per scene).
    grid = mi.Point2f(owned_floats(u), owned_floats(v))
    local = mi.warp.square_to_uniform_cone(grid, cos_max)
    ds = dr.zeros(mi.DirectionSample3f, n * n)
    axis = mi.Vector3f(*(dr.opaque(mi.Float, float(c)) for c in sun_axis(sun)))
    ds.d = mi.Frame3f(axis).to_world(local)
    radiance = sun.eval_direction(dr.zeros(mi.Interaction3f, n * n), ds)
    dr.eval(radiance)  # one kernel for the three channels
    mean = np.array([np.mean(np.asarray(radiance[c], np.float64)) for c in range(3)])
    return mean * 2.0 * np.pi * (1.0 - cos_max)
