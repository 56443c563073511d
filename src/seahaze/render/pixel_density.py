"""The ``physical`` mode in haze that varies across the sea: each pixel's equivalent profile.

The ``physical`` estimators work in reduced length and reduced height, where a haze that varies
with height alone is a homogeneous slab (:mod:`seahaze.medium`). A haze with patches or a bank
(:class:`seahaze.nonuniform.NonUniformHaze`, density ``c · ρ_v(z) · m(x, y, z)``) is not of that
kind. This module renders it with the *pixel's equivalent profile*: every camera path of a
pixel sees the vertical profile ``ρ_v`` scaled by the pixel's density ratios (all exact
integrals of the field, :class:`PixelRatios`):

``view``
    ``ℓ_field / ℓ_profile`` of the pixel-centre ray up to its surface (or :data:`RAY_REACH_M`
    for the sky): the path's segments (the camera's, and the later ones from the surfaces it
    meets) are the profile's scaled by it. So the camera segment's transmittance at the
    pixel's centre is the field's own, ``e^{−σ ℓ}`` exactly (the ``transmission/`` maps), and
    its in-scattering is the field's wherever the source varies little along the ray:
    ``∫ T σ ρ J ds = J (1 − e^{−σ ℓ})`` for a constant ``J``, wherever the haze lies.
``sun_air``
    The haze's depth toward the sun in the field over the profile's, at points along the
    camera ray (:data:`AIR_POINTS` over its first :data:`AIR_REACH_M`, weighted by the density
    there): how much a patch above the haze in view shades it from the sun. The sun's depth
    toward every point a path scatters at is the profile's scaled by it.
``sun_surface``
    The same ratio at the surface the pixel's ray meets (the sky's: ``sun_air``): the rays
    from a surface toward the sun and the sky see the column above it, scaled by it.

What the scaled profile still misses is where along a ray the haze lies (beyond the sun's
depth): the heights the diffuse tables are read at, and the later segments, which see the
pixel's ratios rather than their own. docs/physics.md ("The physical mode in haze that varies
across the sea") measures what it costs per region against the ``reference`` mode, which
path-traces the field.

Inside a pixel the ratios are the centre ray's: a sample that meets the sky beside a vessel's
edge uses the vessel's (a pixel's width of silhouette). The sun ratios are integrated on a
grid of at most :data:`SUN_GRID_PIXELS` pixels and spread to the pixels around each (the
field's depth toward the sun changes little from one pixel to the next).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..medium import NUMPY, drjit_ops
from ..nonuniform import RAY_REACH_M, NonUniformHaze
from .passes import GeometryPass

AIR_REACH_M = 2000.0
"""How far along a camera ray the points of its ``sun_air`` ratio reach (m): where the sun's
single scattering of the levels from 1000 m up is gathered (at 300 m the sun's light hardly
reaches the haze near the sea)."""
AIR_POINTS = 8
"""Points along a camera ray (midpoints of equal steps) at which its ``sun_air`` ratio is
integrated."""
SUN_GRID_PIXELS = 320 * 180
"""Most pixels whose sun ratios are integrated (every ``n``-th row and column)."""

SMALLEST_RATIO = 1e-6
"""The least ratio a kernel reads: a reduced distance is divided by it."""
SMALLEST_PROFILE_LENGTH_M = 1e-6
"""Below this reduced length in the profile (m) a ray meets no haze worth a ratio: 1 there."""


@dataclass(frozen=True)
class PixelRatios:
    """A frame's per-pixel density ratios (module docstring), each (H, W) float64."""

    view: np.ndarray
    sun_air: np.ndarray
    sun_surface: np.ndarray


def pixel_ratios(
    medium: NonUniformHaze, geometry: GeometryPass, sun_direction: np.ndarray
) -> PixelRatios:
    """The :class:`PixelRatios` of ``geometry``'s pixels in ``medium`` lit from the unit
    ``sun_direction`` (toward the sun, world frame)."""
    view = pixel_density_ratio(medium, geometry)
    if sun_direction[2] <= 0.0:  # a sun below the horizon lights no haze: no depth to scale
        return PixelRatios(view, view, view)
    height, width = view.shape
    step = max(1, math.ceil(math.sqrt(height * width / SUN_GRID_PIXELS)))
    rows, cols = np.arange(0, height, step), np.arange(0, width, step)
    dirs = geometry.directions[rows][:, cols].astype(np.float64)
    dist = np.minimum(geometry.distance_m[rows][:, cols].astype(np.float64), RAY_REACH_M)
    origin = geometry.origin.astype(np.float64)
    # Along the ray: midpoints of equal steps over its first AIR_REACH_M (or up to its surface).
    reach = np.minimum(dist, AIR_REACH_M)[..., None]
    s = (np.arange(AIR_POINTS) + 0.5) / AIR_POINTS * reach
    air = origin + s[..., None] * dirs[..., None, :]
    surface = origin + dist[..., None] * dirs
    points = np.concatenate([air.reshape(-1, 3), surface.reshape(-1, 3)])
    field_depth, profile_depth = sun_depths(medium, points, sun_direction)
    n_air = air.shape[0] * air.shape[1] * AIR_POINTS
    weight = medium.density_at(air[..., 0], air[..., 1], air[..., 2])
    field_air = np.sum(weight * field_depth[:n_air].reshape(air.shape[:-1]), axis=-1)
    profile_air = np.sum(weight * profile_depth[:n_air].reshape(air.shape[:-1]), axis=-1)
    sun_air = _ratio(field_air, profile_air)
    sun_surface = _ratio(field_depth[n_air:], profile_depth[n_air:]).reshape(dist.shape)
    sun_surface = np.where(np.isfinite(geometry.distance_m[rows][:, cols]), sun_surface, sun_air)
    spread = lambda grid: np.repeat(np.repeat(grid, step, 0), step, 1)[:height, :width]  # noqa: E731
    return PixelRatios(view, spread(sun_air), spread(sun_surface))


def _ratio(field: np.ndarray, profile: np.ndarray) -> np.ndarray:
    """``field / profile``, 1 where the profile has (almost) no haze."""
    thin = profile < SMALLEST_PROFILE_LENGTH_M
    return np.where(thin, 1.0, field / np.where(thin, 1.0, profile))


def sun_depths(
    medium: NonUniformHaze, points: np.ndarray, sun_direction: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The reduced lengths (m) from world ``points`` (N, 3) toward the sun (unit
    ``sun_direction``, above the horizon) up to the medium's top, in the field and in its
    profile alone (each (N,), float64). The profile's in closed form,
    ``(h(top) − h(z)) / μ_sun``; the field's by composite three-point Gauss–Legendre
    quadrature in the render kernel's arithmetic (:mod:`seahaze.render.field_medium`'s
    field), in panels no longer than the field's scales allow
    (:meth:`NonUniformHaze.panel_length`)."""
    profile = medium.profile
    mu = float(sun_direction[2])
    if mu <= 0.0:
        raise ValueError(f"the sun's depth needs a sun above the horizon, not at z = {mu:g}")
    z = np.minimum(points[:, 2], profile.top)
    reduced_top = profile.reduced_height(np.float64(profile.top), NUMPY)
    profile_depth = (reduced_top - np.asarray(profile.reduced_height(z, NUMPY))) / mu
    length = np.maximum(profile.top - points[:, 2], 0.0) / mu
    panel = float(medium.panel_length(np.array([mu]))[0])
    panels = max(1, math.ceil(float(length.max(initial=0.0)) / panel))
    field_depth = _field_quadrature(medium, points, sun_direction, length, panels)
    return field_depth, profile_depth


def _field_quadrature(
    medium: NonUniformHaze,
    points: np.ndarray,
    direction: np.ndarray,
    length: np.ndarray,
    panels: int,
) -> np.ndarray:
    """``∫₀^L c ρ_v m ds`` from each point along ``direction`` over its ``length`` (m), in
    ``panels`` equal panels of three Gauss–Legendre nodes, evaluated with drjit (one kernel
    launched per node, its position a kernel parameter)."""
    import drjit as dr
    import mitsuba as mi

    from ..nonuniform import GAUSS_NODES, GAUSS_WEIGHTS
    from .field_medium import field_modulation

    drift = medium.field.drift
    travelled = dr.opaque(mi.Float, drift.speed_m_s * drift.time_s)
    o = [mi.Float(points[:, k].astype(np.float32)) for k in range(3)]
    width = mi.Float((length / panels).astype(np.float32))
    d = [dr.opaque(mi.Float, float(c)) for c in direction]  # another sun, the same kernel
    total = dr.zeros(mi.Float, len(points))
    for i in range(panels):
        for node, w in zip(GAUSS_NODES, GAUSS_WEIGHTS, strict=True):
            s = width * dr.opaque(mi.Float, i + 0.5 + 0.5 * node)
            p = mi.Point3f(*(o[k] + d[k] * s for k in range(3)))
            vertical = medium.profile.density(p.z, drjit_ops())
            total += (
                dr.opaque(mi.Float, 0.5 * w)
                * width
                * vertical
                * field_modulation(medium.field, p, travelled)
            )
            dr.eval(total)
    return medium.scale * np.asarray(total, np.float64)


def pixel_density_ratio(medium: NonUniformHaze, geometry: GeometryPass) -> np.ndarray:
    """(H, W) float64 ``r = ℓ_field / ℓ_profile`` of every pixel-centre ray of ``geometry``
    (module docstring), up to its surface or :data:`RAY_REACH_M`; 1 where the profile gives
    the ray no haze."""
    distance = np.minimum(geometry.distance_m.astype(np.float64), RAY_REACH_M)
    field = medium.ray_path_length(geometry.origin, geometry.directions, distance)
    dirs_z = geometry.directions[..., 2].astype(np.float64)
    # The profile without the field's normalisation c: c is part of the ratio.
    profile = medium.profile.path_length(float(geometry.origin[2]), dirs_z, distance)
    thin = profile < SMALLEST_PROFILE_LENGTH_M
    return np.where(thin, 1.0, field / np.where(thin, 1.0, profile))


class PixelRatio:
    """A frame's :class:`PixelRatios` for a kernel: the ratios of the pixel a camera ray
    leaves through, found by projecting a point on the ray back onto the film with the
    scene's own sensor (so exactly the pixel the sample belongs to). The ratios and the film's
    size are kernel parameters: another frame or scene reuses the kernel."""

    def __init__(self, sensor: Any, ratios: PixelRatios):
        """``sensor``: the scene's Mitsuba sensor; ``ratios``: those of its film's pixels."""
        import drjit as dr
        import mitsuba as mi

        from .jit_haze import owned_floats

        height, width = ratios.view.shape
        self.sensor = sensor
        # A ratio of 0 (no haze along the ray) would divide a reduced distance by 0.
        self.ratios = [
            owned_floats(np.maximum(r, SMALLEST_RATIO))
            for r in (ratios.view, ratios.sun_air, ratios.sun_surface)
        ]
        self.width = dr.opaque(mi.UInt32, width)
        self.last_x = dr.opaque(mi.Float, width - 1)
        self.last_y = dr.opaque(mi.Float, height - 1)

    def at(self, ray: Any, active: Any) -> tuple[Any, Any, Any]:
        """The ``view``, ``sun_air`` and ``sun_surface`` ratios of the pixel camera ray
        ``ray`` leaves through (a Float per lane each; 1 where inactive)."""
        import drjit as dr
        import mitsuba as mi

        it = dr.zeros(mi.Interaction3f)
        it.p = ray(1.0)  # any point in front of the camera projects onto the ray's pixel
        ds, _ = self.sensor.sample_direction(it, mi.Point2f(0.5, 0.5), active)
        x = dr.clip(dr.floor(ds.uv.x), 0.0, self.last_x)
        y = dr.clip(dr.floor(ds.uv.y), 0.0, self.last_y)
        inside = active & dr.isfinite(x) & dr.isfinite(y)
        index = dr.select(inside, mi.UInt32(y) * self.width + mi.UInt32(x), 0)
        view, sun_air, sun_surface = (
            dr.select(inside, dr.gather(mi.Float, r, index, inside), 1.0) for r in self.ratios
        )
        return view, sun_air, sun_surface
