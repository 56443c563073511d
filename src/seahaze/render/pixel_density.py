"""The ``physical`` mode in haze that varies across the sea: each pixel's equivalent profile.

The ``physical`` estimators work in reduced length and reduced height, where a haze that varies
with height alone is a homogeneous slab (:mod:`seahaze.medium`). A haze with patches or a bank
(:class:`seahaze.nonuniform.NonUniformHaze`, density ``c · ρ_v(z) · m(x, y, z)``) is not of that
kind. This module renders it with the *pixel's equivalent profile*: every camera path of a
pixel sees the vertical profile ``ρ_v`` scaled by the pixel's density ratios (all exact
integrals of the field, :class:`PixelRatios`):

``view``
    ``ℓ_field / ℓ_profile`` of the pixel-centre ray up to its surface (or :data:`RAY_REACH_M`
    for the sky): the camera segment is the profile's scaled by it. So its transmittance at
    the pixel's centre is the field's own, ``e^{−σ ℓ}`` exactly (the ``transmission/`` maps),
    and its in-scattering is the field's wherever the source varies little along the ray:
    ``∫ T σ ρ J ds = J (1 − e^{−σ ℓ})`` for a constant ``J``, wherever the haze lies.
``sun_air`` (one per level)
    How much the haze above the camera ray shades it from the sun: the ratio ``r`` for which
    the profile's depths toward the sun times ``r`` give the field's mean transmittance toward
    the sun over :data:`AIR_POINTS` points of the ray, weighted by the light each scatters
    toward the camera at that level. The sun's depth toward every point the camera segment
    scatters at is the profile's scaled by it.
``sun_surface``
    The field's depth toward the sun over the profile's at the surface the pixel's ray meets:
    the rays from the surface toward the sun and the sky, and the sun's depths along the
    later segments, are the profile's scaled by it.
``bounce``
    The later segments' ratio: on the sea, that of the camera ray mirrored in a flat sea (where
    the light the sea reflects comes from); on a vessel, ``sun_surface``.
``sun_bounce`` (one per level)
    How much the haze above the later segments shades them from the sun: on the sea, the
    ``sun_air`` ratio of the mirrored ray (its points weighted by the light each scatters
    toward the sea point); on a vessel, ``sun_surface``. A sea under thin haze that mirrors a
    bank sees the bank lit by the sun through the bank, not through the thin column above
    the sea point.

``diffuse_air`` and ``diffuse_bounce`` (one per level, optional)
    Factors on the diffuse field (the tables' light) of the camera segment and of the later
    segments: the field's diffuse in-scattering along the ray over the equivalent
    profile's. :func:`pixel_ratios` leaves them None (the tables as they are); the renderer
    sets them in a bank alone from the bank's own diffuse field
    (:mod:`seahaze.render.bank_diffuse`).

The aureole a surface samples around the sun travels through the column above the surface
(``sun_surface``), not along the later segments' ratios: its directions lie around the sun.

What the scaled profile still misses is where along a ray the haze lies and how the diffuse
field answers the haze around each point: the tables are the profile's. docs/physics.md ("Haze
that varies across the sea in the physical mode") measures what that costs per region against
the ``reference`` mode, which path-traces the field: dense patches shield their own inside
(too bright at thick levels). A bank, which puts a ray's haze beyond its edge and lets the
horizon's light reach its face, gets the diffuse ratios of its own field.

Inside a pixel the ratios are the centre ray's: a sample that meets the sky beside a vessel's
edge uses the vessel's (a pixel's width of silhouette). The sun ratios are integrated on a
grid of at most :data:`SUN_GRID_PIXELS` pixels and spread to the pixels around each, as are
the bounce ratios (both change little from one pixel to the next).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..medium import NUMPY
from ..nonuniform import RAY_REACH_M, NonUniformHaze
from .passes import GeometryPass
from .transmission import ray_reach

AIR_REACH_M = 6000.0
"""How far along a camera ray the points of its ``sun_air`` ratios reach (m): the clearest
graded level's haze scatters most of its light within it."""
AIR_POINTS = 24
"""Points along a camera ray at which its ``sun_air`` ratios are integrated: midpoints of
cells that grow quadratically with distance (the thickest level's light comes from the first
tens of metres, the clearest level's from kilometres)."""
SUN_RATIO_NEWTON_STEPS = 12
"""Most Newton steps of a level's ``sun_air`` ratio (quadratic convergence from a close start:
most levels stop at :data:`SUN_RATIO_TOLERANCE` well before)."""
SUN_RATIO_TOLERANCE = 1e-12
"""The logarithm of the mean transmittance toward the sun, matched to this on every ray (a
relative 1e-12 of the transmittance) stops the Newton steps."""
SUN_GRID_PIXELS = 320 * 180
"""Most pixels whose sun and bounce ratios are integrated (every ``n``-th row and column)."""

SMALLEST_RATIO = 1e-6
"""The least ratio a kernel reads: a reduced distance is divided by it."""
SMALLEST_PROFILE_LENGTH_M = 1e-6
"""Below this reduced length in the profile (m) a ray meets no haze worth a ratio: 1 there."""


@dataclass(frozen=True)
class PixelRatios:
    """A frame's per-pixel density ratios (module docstring), float64."""

    view: np.ndarray
    """(H, W)."""
    sun_air: np.ndarray
    """(L, H, W): one per level."""
    sun_surface: np.ndarray
    """(H, W)."""
    bounce: np.ndarray
    """(H, W)."""
    sun_bounce: np.ndarray
    """(L, H, W): one per level."""
    diffuse_air: np.ndarray | None = None
    """(L, H, W) or None: per level, the camera segment's diffuse in-scattering in the field
    over that in the pixel's equivalent profile; None: 1."""
    diffuse_bounce: np.ndarray | None = None
    """(L, H, W) or None: the same along the later segments."""

    def levels(self, part: slice) -> PixelRatios:
        """The ratios of the levels ``part`` of those they were computed for."""
        pick = lambda a: None if a is None else a[part]  # noqa: E731
        return PixelRatios(
            self.view,
            self.sun_air[part],
            self.sun_surface,
            self.bounce,
            self.sun_bounce[part],
            pick(self.diffuse_air),
            pick(self.diffuse_bounce),
        )


def pixel_ratios(
    medium: NonUniformHaze,
    geometry: GeometryPass,
    sun_direction: np.ndarray,
    sigma: np.ndarray,
    sea: np.ndarray | None = None,
) -> PixelRatios:
    """The :class:`PixelRatios` of ``geometry``'s pixels in ``medium`` lit from the unit
    ``sun_direction`` (toward the sun, world frame), for levels of (green) extinction
    ``sigma`` (L,) in 1/m; ``sea``: (H, W) the pixels whose surface is the sea (None: every
    surface pixel that is no vessel, from ``geometry.instance``)."""
    view = pixel_density_ratio(medium, geometry)
    sigma = np.asarray(sigma, np.float64)
    if sun_direction[2] <= 0.0:  # a sun below the horizon lights no haze: no depth to scale
        per_level = np.stack([view] * len(sigma))
        return PixelRatios(view, per_level, view, view, per_level)
    height, width = view.shape
    step = max(1, math.ceil(math.sqrt(height * width / SUN_GRID_PIXELS)))
    rows, cols = np.arange(0, height, step), np.arange(0, width, step)
    dirs = geometry.directions[rows][:, cols].astype(np.float64)
    dist_m = geometry.distance_m[rows][:, cols].astype(np.float64)
    dist = np.minimum(dist_m, RAY_REACH_M)
    origin = geometry.origin.astype(np.float64)
    surface = origin + dist[..., None] * dirs
    field_depth, profile_depth = sun_depths(medium, surface.reshape(-1, 3), sun_direction)
    sun_surface = _ratio(field_depth, profile_depth).reshape(dist.shape)
    sky = ~np.isfinite(dist_m)
    sun_surface = np.where(sky, view[rows][:, cols], sun_surface)
    # Along the ray, up to AIR_REACH_M or its surface.
    reach = np.minimum(dist, AIR_REACH_M)
    sun_air = air_sun_ratios(medium, origin, dirs, reach, sun_direction, sigma)
    if sea is None:
        sea = np.isfinite(geometry.distance_m) & (geometry.instance < 0)
    on_sea = sea[rows][:, cols]
    bounce = sun_surface.copy()
    sun_bounce = np.stack([sun_surface] * len(sigma))
    if on_sea.any():
        bounce[on_sea] = mirror_ratio(medium, surface[on_sea], dirs[on_sea])
        up = dirs[on_sea] * np.array([1.0, 1.0, -1.0])
        mirrored = np.minimum(mirror_reach(medium, surface[on_sea], up), AIR_REACH_M)
        sun_bounce[:, on_sea] = air_sun_ratios(
            medium, surface[on_sea], up, mirrored, sun_direction, sigma
        )

    def spread(grid: np.ndarray) -> np.ndarray:
        return np.repeat(np.repeat(grid, step, -2), step, -1)[..., :height, :width]

    return PixelRatios(
        view, spread(sun_air), spread(sun_surface), spread(bounce), spread(sun_bounce)
    )


def air_sun_ratios(
    medium: NonUniformHaze,
    origins: np.ndarray,
    dirs: np.ndarray,
    reach: np.ndarray,
    sun_direction: np.ndarray,
    sigma: np.ndarray,
) -> np.ndarray:
    """(L, ...) each level's sun ratio (:func:`level_sun_ratio`) of the rays from ``origins``
    ((..., 3), or one (3,) for all) along unit ``dirs`` (..., 3) over ``reach`` (...) metres,
    at :data:`AIR_POINTS` points: midpoints of cells growing quadratically from the origin."""
    edges = (np.arange(AIR_POINTS + 1) / AIR_POINTS) ** 2
    s = 0.5 * (edges[:-1] + edges[1:]) * reach[..., None]
    width_m = np.diff(edges) * reach[..., None]
    start = origins if origins.ndim == 1 else origins[..., None, :]
    air = start + s[..., None] * dirs[..., None, :]
    field_depth, profile_depth = sun_depths(medium, air.reshape(-1, 3), sun_direction)
    shape = air.shape[:-1]
    mass = medium.density_at(air[..., 0], air[..., 1], air[..., 2]) * width_m
    return np.stack(
        [
            level_sun_ratio(k, mass, field_depth.reshape(shape), profile_depth.reshape(shape))
            for k in sigma
        ]
    )


def level_sun_ratio(
    sigma: float, mass: np.ndarray, field_depth: np.ndarray, profile_depth: np.ndarray
) -> np.ndarray:
    """One level's ``sun_air`` ratio per ray: the ``r`` for which the profile's depths toward
    the sun, times ``r``, give the same mean transmittance toward the sun as the field's, the
    mean over the ray's points weighted by the light each scatters toward the camera
    (``ρ Δs e^{−σ ℓ}``, ``ℓ`` the reduced length from the camera; ``mass`` = ``ρ Δs``). So a
    field that is the profile times ``r`` gives ``r``. Solved by Newton's method on the
    logarithm of the mean (convex and decreasing in ``r``), from the ratio of the mean depths;
    in logarithms throughout: no underflow at the optical depths of hundreds of a thick
    level."""
    travelled = np.cumsum(mass, axis=-1) - 0.5 * mass
    with np.errstate(divide="ignore"):
        log_w = np.log(mass) - sigma * travelled
    target = _logsumexp(log_w - sigma * field_depth)
    weight = np.exp(log_w - _logsumexp(log_w)[..., None])
    r = _ratio(np.sum(weight * field_depth, -1), np.sum(weight * profile_depth, -1))
    for _ in range(SUN_RATIO_NEWTON_STEPS):
        log_t = log_w - sigma * r[..., None] * profile_depth
        total = _logsumexp(log_t)
        value = total - target
        if not np.any(np.abs(value) > SUN_RATIO_TOLERANCE):
            break  # every ray's mean transmittance matched to the tolerance
        share = np.exp(log_t - total[..., None])
        slope = -sigma * np.sum(share * profile_depth, axis=-1)
        r = np.where(slope < 0.0, r - value / np.where(slope < 0.0, slope, -1.0), r)
        r = np.maximum(r, 0.0)
    return r


def _logsumexp(x: np.ndarray) -> np.ndarray:
    """``ln Σ e^x`` over the last axis, safe for large and ``−∞`` values."""
    top = np.max(x, axis=-1)
    top = np.where(np.isfinite(top), top, 0.0)
    with np.errstate(divide="ignore"):
        return top + np.log(np.sum(np.exp(x - top[..., None]), axis=-1))


def mirror_ratio(medium: NonUniformHaze, points: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """``ℓ_field / ℓ_profile`` (N,) of the rays from sea ``points`` (N, 3) along the camera
    rays ``dirs`` (N, 3) mirrored in a flat sea: where the light the sea reflects toward the
    camera travels, up to the medium's top or :data:`RAY_REACH_M`."""
    up = dirs * np.array([1.0, 1.0, -1.0])
    return ray_ratio(medium, points, up, mirror_reach(medium, points, up))


def ray_ratio(
    medium: NonUniformHaze, starts: np.ndarray, dirs: np.ndarray, reach: np.ndarray
) -> np.ndarray:
    """``ℓ_field / ℓ_profile`` (N,) of the rays from ``starts`` (N, 3) along unit ``dirs``
    (N, 3) over ``reach`` (N,) metres (1 where the profile gives them no haze)."""
    _, profile_length = medium.profile.reduced_length(starts[:, 2], dirs[:, 2], reach, NUMPY)
    field_length = medium.lengths_along(starts, dirs, np.zeros(len(starts)), reach)
    return _ratio(field_length, np.asarray(profile_length, np.float64))


def mirror_reach(medium: NonUniformHaze, points: np.ndarray, up: np.ndarray) -> np.ndarray:
    """How far (m) the mirrored rays from ``points`` (N, 3) along ``up`` (N, 3) run in the
    haze: to the medium's top, at most :data:`RAY_REACH_M`."""
    climb = np.maximum(up[:, 2], 1e-9)
    return np.minimum(np.maximum(medium.profile.top - points[:, 2], 0.0) / climb, RAY_REACH_M)


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
    ``(h(top) − h(z)) / μ_sun``; the field's by the transmission maps' quadrature
    (:meth:`NonUniformHaze.lengths_along`, summed by the render's kernel where
    :func:`seahaze.render.engine.open_session` gave the medium it)."""
    profile = medium.profile
    mu = float(sun_direction[2])
    if mu <= 0.0:
        raise ValueError(f"the sun's depth needs a sun above the horizon, not at z = {mu:g}")
    z = np.minimum(points[:, 2], profile.top)
    reduced_top = profile.reduced_height(np.float64(profile.top), NUMPY)
    profile_depth = (reduced_top - np.asarray(profile.reduced_height(z, NUMPY))) / mu
    length = np.maximum(profile.top - points[:, 2], 0.0) / mu
    directions = np.broadcast_to(np.asarray(sun_direction, np.float64), points.shape)
    field_depth = medium.lengths_along(points, directions, np.zeros(len(points)), length)
    return field_depth, profile_depth


def pixel_density_ratio(medium: NonUniformHaze, geometry: GeometryPass) -> np.ndarray:
    """(H, W) float64 ``r = ℓ_field / ℓ_profile`` of every pixel-centre ray of ``geometry``
    (module docstring), up to its surface or :data:`RAY_REACH_M`; 1 where the profile gives
    the ray no haze."""
    # The transmission/ maps' own rays and quadrature (the medium keeps their lengths).
    reach = ray_reach(geometry, medium)
    dirs_z = geometry.directions[..., 2].astype(np.float64)
    # The profile without the field's normalisation c: c is part of the ratio.
    profile = medium.profile.path_length(float(geometry.origin[2]), dirs_z, reach.distance_m)
    return _ratio(reach.reduced_m, profile)


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
        owned = lambda r: owned_floats(np.maximum(r, SMALLEST_RATIO))  # noqa: E731
        self.view, self.surface, self.bounce = (
            owned(r) for r in (ratios.view, ratios.sun_surface, ratios.bounce)
        )
        self.sun_air = [owned(r) for r in ratios.sun_air]
        self.sun_bounce = [owned(r) for r in ratios.sun_bounce]
        self.diffuse_air, self.diffuse_bounce = (
            None if a is None else [owned_floats(r) for r in a]
            for a in (ratios.diffuse_air, ratios.diffuse_bounce)
        )
        self.width = dr.opaque(mi.UInt32, width)
        self.last_x = dr.opaque(mi.Float, width - 1)
        self.last_y = dr.opaque(mi.Float, height - 1)

    def at(self, ray: Any, active: Any) -> tuple:
        """The ``view`` ratio, the levels' ``sun_air`` ratios, the ``sun_surface`` and the
        ``bounce`` ratio, the levels' ``sun_bounce`` ratios and the levels' ``diffuse_air``
        and ``diffuse_bounce`` ratios (None where the frame has none) of the pixel camera ray
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

        def read(array: Any) -> Any:
            return dr.select(inside, dr.gather(mi.Float, array, index, inside), 1.0)

        return (
            read(self.view),
            [read(a) for a in self.sun_air],
            read(self.surface),
            read(self.bounce),
            [read(a) for a in self.sun_bounce],
            None if self.diffuse_air is None else [read(a) for a in self.diffuse_air],
            None if self.diffuse_bounce is None else [read(a) for a in self.diffuse_bounce],
        )
