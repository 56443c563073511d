"""Each pixel's diffuse light in haze that varies across the sea, over its equivalent profile's.

``physical`` renders haze that varies across the sea as each pixel's equivalent profile
(:mod:`seahaze.render.pixel_density`) and reads the diffuse field — everything but the sun's
single scattering — from tables traced in the horizontally homogeneous profile. Where the
field's own diffuse light is known (a bank's, :mod:`seahaze.render.bank_diffuse`; patches',
:mod:`seahaze.render.patch_diffuse`), this module gives each pixel's camera segment its
``diffuse_air`` ratio per level: the diffuse in-scattering along the pixel-centre ray through
the field over the same in the pixel's equivalent profile,

    diffuse_air = Σ_i e^{−τ_i} σ ρ_i J(x_i, −ω) Δ_i
                / Σ_i e^{−r τ_v,i} σ r ρ_v,i J_v(z_i, −ω) Δ_i,

over :data:`RAY_POINTS` points of the ray (cells growing quadratically from the camera), with
``τ`` the field's optical depth from the camera, ``τ_v`` the profile's, ``r`` the pixel's
``view`` ratio and ``J = ϖ Σ_b p(ω_b·ω) Φ_b`` the in-scattered radiance of a directional
fluence ``Φ``: the field's at the point (:class:`FieldLight`), the profile's at its height.
The kernels scale the tables' light on the camera segment by it (``PixelRatios.diffuse_air``).
The sum is taken on a grid of at most :data:`RATIO_GRID_PIXELS` pixels and interpolated to the
pixels between, within the image's segments (the ratio changes slowly across a surface, and
jumps at a silhouette).

The segments after a surface get a ``diffuse_bounce`` ratio of the same kind, averaged over
the directions they leave in, each direction's sums weighted by how much it sends toward the
camera: on the sea, :data:`BOUNCE_RAYS` of the sea's own reflection samples for the pixel's
incidence (the rough lobe and the water body reflect light from every elevation: the mirrored
ray alone put a bank's sea 4–7 % bright); on a hull, as many cosine-weighted directions about
the side that faces the camera. Each such ray's equivalent profile is the one the kernels'
later segments use: the profile times the ray's own density ratio in a bank
(:mod:`seahaze.render.segment_ratio`), times the pixel's ``bounce`` ratio otherwise.

The ratios carry the field tracer's photon noise (docs/benchmarks.md states it per region).

Import this module only once a Mitsuba variant is set.
"""

from __future__ import annotations

import math
from typing import Any, Protocol

import numpy as np

from ..medium import NUMPY
from ..nonuniform import RAY_REACH_M, NonUniformHaze
from .passes import GeometryPass
from .photon_tracer import SeaReflectance
from .pixel_density import ray_ratio
from .segment_smooth import SEA_SEGMENT, segments, smooth_within_segments

RAY_POINTS = 160
"""Points of a ray's sums."""
BOUNCE_POINTS = 48
"""Points of each of a sea pixel's reflected rays."""
BOUNCE_RAYS = 32
"""Reflected rays per sea pixel (the sea's own samples for the pixel's incidence)."""
SEA_STRIDE = 2
"""The sea's ``diffuse_bounce`` is summed on every this-many-th row and column of the ratios'
grid and interpolated within the sea between (its rays are most of the ratios' time)."""
BOUNCE_CHUNK = 2048
"""Sea points whose reflected rays are summed at once (their points are held in memory)."""
RATIO_GRID_PIXELS = 160 * 90
"""Most pixels whose ratios are summed (every ``n``-th row and column)."""
SMOOTHING_CELLS = 4
"""Radius of the box filter (in cells of the ratios' grid, within each segment of the image)
over the summed ratios. Neighbouring rays cross the same few cells of a field's tracer at
nearby points, so the cells' photon noise runs in bands across the sky (a bank's strip: a few
grid rows apart and 1–2 % deep in 8-bit values at 2^18 photons); this radius (1/40 of the
grid's width) flattens them, and the ratio itself changes little over it (it is an integral
along each ray of a field that changes over hundreds of metres)."""
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
"""Rec. 709 luminance: one ratio per level scales all three channels."""


class FieldLight(Protocol):
    """A field's diffuse light and its profile's, as :func:`ray_sums` reads them."""

    def light(self, k: int, x: Any, y: Any, z: Any, travel: np.ndarray) -> tuple[Any, Any]:
        """(N, P) level ``k``'s in-scattered luminance per unit ``σ ρ`` at world points
        ``x``, ``y``, ``z`` (N, P) toward the travel directions ``travel`` (N, 3) of the light
        that reaches each ray's start: the field's, and its profile's at the same heights."""
        ...


def diffuse_ratios(
    medium: NonUniformHaze,
    geometry: GeometryPass,
    view: np.ndarray,
    sources: FieldLight,
    sigma: np.ndarray,
    sea: SeaReflectance,
    later: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """(L, H, W) each pixel's ``diffuse_air`` and ``diffuse_bounce`` ratios (module docstring)
    at levels of (green) extinction ``sigma`` (L,) in 1/m, from the field's light ``sources``
    (:class:`FieldLight`), the pixels' ``view`` ratios (H, W) and the sea's reflection
    samples; the later segments' equivalent profile is the profile times ``later`` (H, W),
    the pixel's ratio for them, or where None each reflected ray's own (as a bank's kernels
    measure it). Summed on a grid and spread within the image's segments
    (:func:`spread_within_segments`)."""
    height, width = view.shape
    step = max(1, math.ceil(math.sqrt(height * width / RATIO_GRID_PIXELS)))
    rows, cols = np.arange(0, height, step), np.arange(0, width, step)
    dirs = geometry.directions[rows][:, cols].reshape(-1, 3).astype(np.float64)
    distance = geometry.distance_m[rows][:, cols].reshape(-1).astype(np.float64)
    origin = np.asarray(geometry.origin, np.float64)
    starts = np.broadcast_to(origin, dirs.shape)
    r = view[rows][:, cols].reshape(-1)
    grid_later = None if later is None else later[rows][:, cols].reshape(-1)
    true, equivalent = ray_sums(
        medium, sources, sigma, starts, dirs, _reach(medium, starts, dirs, distance), r
    )
    air = quotient(true, equivalent)
    shape = (len(sigma), len(rows), len(cols))
    labels = segments(geometry.instance, geometry.distance_m)
    grid_labels = labels[::step, ::step]
    bounce = np.ones_like(air)
    on_vessel = grid_labels.reshape(-1) >= 0
    pick = lambda mask: None if grid_later is None else grid_later[mask]  # noqa: E731
    if on_vessel.any():
        points = origin + distance[on_vessel, None] * dirs[on_vessel]
        bounce[:, on_vessel] = hull_bounce_ratios(
            medium, sources, sigma, points, dirs[on_vessel], pick(on_vessel)
        )
    on_sea = grid_labels.reshape(-1) == SEA_SEGMENT
    if on_sea.any():
        # On every SEA_STRIDE-th grid row and column, interpolated within the sea between.
        sparse = np.zeros(shape[1:], bool)
        sparse[::SEA_STRIDE, ::SEA_STRIDE] = True
        sparse = sparse.reshape(-1) & on_sea
        points = origin + distance[sparse, None] * dirs[sparse]
        bounce[:, sparse] = sea_bounce_ratios(
            medium, sources, sigma, points, dirs[sparse], sea, pick(sparse)
        )
        coarse = bounce.reshape(shape)[:, ::SEA_STRIDE, ::SEA_STRIDE]
        between = spread_within_segments(coarse, grid_labels, SEA_STRIDE).reshape(len(sigma), -1)
        bounce[:, on_sea & ~sparse] = between[:, on_sea & ~sparse]

    def smoothed(ratios: np.ndarray) -> np.ndarray:
        cube = ratios.reshape(shape).transpose(1, 2, 0)
        cube = smooth_within_segments(cube, grid_labels, SMOOTHING_CELLS)
        return cube.transpose(2, 0, 1).astype(np.float64)

    return tuple(spread_within_segments(smoothed(r), labels, step) for r in (air, bounce))


def spread_within_segments(grid: np.ndarray, labels: np.ndarray, step: int) -> np.ndarray:
    """(L, H, W) values at every pixel from ``grid`` (L, h, w), the values at every
    ``step``-th row and column: bilinear between the four grid pixels around each pixel, of
    those in its own segment (``labels`` (H, W): the sky, the sea, each vessel), so a ratio
    never crosses a silhouette; the nearest grid pixel where none of the four is of its
    segment (a vessel narrower than the grid's step)."""
    height, width = labels.shape
    rows, cols = _corners(height, step, grid.shape[1]), _corners(width, step, grid.shape[2])
    grid_labels = labels[::step, ::step]
    total = np.zeros((len(grid), height, width))
    weight = np.zeros((height, width))
    for i, wy in rows:
        for j, wx in cols:
            w = np.outer(wy, wx) * (grid_labels[np.ix_(i, j)] == labels)
            total += w * grid[:, i][:, :, j]
            weight += w
    nearest = np.repeat(np.repeat(grid, step, -2), step, -1)[..., :height, :width]
    found = weight > 0.0
    return np.where(found, total / np.where(found, weight, 1.0), nearest)


def _corners(n: int, step: int, n_grid: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """For pixels ``0 … n−1`` along one axis, the grid index below and above each with its
    linear weight (grid index ``k`` is pixel ``k·step``)."""
    at = np.arange(n) / step
    below = np.minimum(np.floor(at).astype(np.int64), n_grid - 1)
    above = np.minimum(below + 1, n_grid - 1)
    frac = np.clip(at - below, 0.0, 1.0)
    frac = np.where(above == below, 0.0, frac)
    return [(below, 1.0 - frac), (above, frac)]


def sea_bounce_ratios(
    medium: NonUniformHaze,
    sources: FieldLight,
    sigma: np.ndarray,
    points: np.ndarray,
    dirs: np.ndarray,
    sea: SeaReflectance,
    later: np.ndarray | None = None,
) -> np.ndarray:
    """(L, N) the ``diffuse_bounce`` ratio of sea ``points`` (N, 3) seen along camera
    directions ``dirs`` (N, 3): the diffuse in-scattering along :data:`BOUNCE_RAYS` of the
    sea's reflected directions (its own samples for that incidence, each weighted by its
    luminance) through the field, over the same along each in the equivalent profile of the
    later segments (the profile times the point's ``later`` ratio (N,), or where None each
    ray's own)."""
    if len(points) > BOUNCE_CHUNK:
        parts = range(0, len(points), BOUNCE_CHUNK)
        return np.concatenate(
            [
                sea_bounce_ratios(
                    medium,
                    sources,
                    sigma,
                    points[i : i + BOUNCE_CHUNK],
                    dirs[i : i + BOUNCE_CHUNK],
                    sea,
                    None if later is None else later[i : i + BOUNCE_CHUNK],
                )
                for i in parts
            ],
            axis=1,
        )
    if len(points) == 0:  # (e.g. a sea seen on no row or column the sea's grid sums)
        return np.ones((len(sigma), 0))
    wo, weight = reflected_directions(sea, dirs)
    n, k = wo.shape[:2]
    starts = np.repeat(points, k, axis=0)
    starts[:, 2] = np.maximum(starts[:, 2], 0.0)
    travel = wo.reshape(-1, 3)
    reach = _reach(medium, starts, travel, np.full(len(travel), np.inf))
    own = _later_ratio(medium, starts, travel, reach, later, k)
    true, equivalent = ray_sums(medium, sources, sigma, starts, travel, reach, own, BOUNCE_POINTS)
    w = weight.reshape(1, n, k)
    return quotient(
        (true.reshape(-1, n, k) * w).sum(axis=2), (equivalent.reshape(-1, n, k) * w).sum(axis=2)
    )


def hull_bounce_ratios(
    medium: NonUniformHaze,
    sources: FieldLight,
    sigma: np.ndarray,
    points: np.ndarray,
    dirs: np.ndarray,
    later: np.ndarray | None = None,
) -> np.ndarray:
    """(L, N) the ``diffuse_bounce`` ratio of hull ``points`` (N, 3) seen along camera
    directions ``dirs`` (N, 3): as :func:`sea_bounce_ratios`, over :data:`BOUNCE_RAYS`
    cosine-weighted directions about the hull's side that faces the camera (a matte side:
    the geometry pass keeps no normals). Rays that go down end at the sea."""
    travel = hull_directions(dirs)
    n, k = travel.shape[:2]
    starts = np.repeat(points, k, axis=0)
    travel = travel.reshape(-1, 3)
    to_sea = np.where(travel[:, 2] < 0.0, starts[:, 2] / np.maximum(-travel[:, 2], 1e-9), np.inf)
    reach = _reach(medium, starts, travel, to_sea)
    own = _later_ratio(medium, starts, travel, reach, later, k)
    true, equivalent = ray_sums(medium, sources, sigma, starts, travel, reach, own, BOUNCE_POINTS)
    return quotient(true.reshape(-1, n, k).sum(axis=2), equivalent.reshape(-1, n, k).sum(axis=2))


def hull_directions(dirs: np.ndarray) -> np.ndarray:
    """(N, K, 3) :data:`BOUNCE_RAYS` cosine-weighted directions (a stratified spiral) about the
    horizontal normal facing back along each camera direction of ``dirs`` (N, 3)."""
    k = BOUNCE_RAYS
    radius = np.sqrt((np.arange(k) + 0.5) / k)
    angle = np.arange(k) * np.pi * (3.0 - np.sqrt(5.0))  # the golden angle
    a, b = radius * np.cos(angle), radius * np.sin(angle)
    c = np.sqrt(np.maximum(1.0 - radius**2, 0.0))
    horizontal = -dirs[:, :2]
    normal = horizontal / np.maximum(np.linalg.norm(horizontal, axis=1, keepdims=True), 1e-12)
    nx, ny = normal[:, 0:1], normal[:, 1:2]
    # Frame: the normal, the horizontal tangent (−ny, nx) and the vertical.
    up = np.broadcast_to(b, (len(dirs), k))
    return np.stack([c * nx - a * ny, c * ny + a * nx, up], axis=-1)


def reflected_directions(sea: SeaReflectance, dirs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(N, K, 3) travel directions and (N, K) luminance weights of :data:`BOUNCE_RAYS` of the
    sea's reflection samples for camera rays arriving along ``dirs`` (N, 3, downward), each
    rotated to its ray's azimuth (as the photon tracer does)."""
    k = min(BOUNCE_RAYS, sea.per_bin)
    pick = ((np.arange(k) + 0.5) * sea.per_bin / k).astype(np.int64)
    wo, weight = sea.samples(dirs, np.broadcast_to(pick, (len(dirs), k)))
    return wo, weight @ LUMINANCE


def _later_ratio(medium, starts, travel, reach, later: np.ndarray | None, k: int) -> np.ndarray:
    """The equivalent profile's ratio of each of ``k`` rays per point: the point's ``later``
    ratio, or where None each ray's own (:func:`seahaze.render.pixel_density.ray_ratio`)."""
    if later is None:
        return ray_ratio(medium, starts, travel, reach)
    return np.repeat(np.asarray(later, np.float64), k)


def _reach(medium: NonUniformHaze, starts: np.ndarray, dirs: np.ndarray, distance: np.ndarray):
    """How far rays run in the haze: to their surface, the haze's top, or :data:`RAY_REACH_M`."""
    reach = np.minimum(distance, RAY_REACH_M)
    up = dirs[:, 2] > 0.0
    room = np.maximum(medium.profile.top - starts[up, 2], 0.0)
    reach[up] = np.minimum(reach[up], room / dirs[up, 2])
    return reach


def quotient(true: np.ndarray, equivalent: np.ndarray) -> np.ndarray:
    """``true / equivalent``, 1 where the equivalent (the profile's light, a weight) is not
    positive: a ratio that leaves what it scales as it is where there is nothing to scale."""
    fine = equivalent > 0.0
    return np.where(fine, true / np.where(fine, equivalent, 1.0), 1.0)


def ray_sums(
    medium: NonUniformHaze,
    sources: FieldLight,
    sigma: np.ndarray,
    starts: np.ndarray,
    dirs: np.ndarray,
    reach: np.ndarray,
    ratio: np.ndarray,
    points: int = RAY_POINTS,
) -> tuple[np.ndarray, np.ndarray]:
    """(L, N) each ray's diffuse in-scattering toward its start through the field,
    ``Σ e^{−τ} ρ J Δ``, and through its equivalent profile (the profile times ``ratio``),
    per unit ``σ ϖ`` — from ``starts`` (N, 3) along unit ``dirs`` (N, 3) over ``reach`` (N,)
    metres, at ``points`` points (cells growing quadratically from the start), the light
    ``J`` read from ``sources`` (a bank's or patches')."""
    edges = (np.arange(points + 1) / points) ** 2
    along = 0.5 * (edges[:-1] + edges[1:])[None] * reach[:, None]
    width = np.diff(edges)[None] * reach[:, None]
    p = starts[:, None, :] + along[..., None] * dirs[:, None, :]
    z = np.clip(p[..., 2], 0.0, medium.profile.top)
    rho = medium.density_at(p[..., 0], p[..., 1], z) * width
    rho_v = np.asarray(medium.profile.density(z, NUMPY), np.float64) * width
    mass = np.cumsum(rho, 1) - 0.5 * rho
    mass_v = (np.cumsum(rho_v, 1) - 0.5 * rho_v) * ratio[:, None]
    true = np.empty((len(sigma), len(dirs)))
    equivalent = np.empty_like(true)
    for k, level in enumerate(sigma):
        j_true, j_flat = sources.light(k, p[..., 0], p[..., 1], z, -dirs)
        true[k] = np.sum(np.exp(-level * mass) * rho * j_true, 1)
        equivalent[k] = np.sum(np.exp(-level * mass_v) * rho_v * j_flat, 1) * ratio
    return true, equivalent


def light_nodes(grid: Any, travel: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """The four direction bins around travel directions (N, 3), as (bin, bilinear weight)
    pairs between the bins' centres in ``μ`` and in the azimuth from ``grid.toward_deg``
    (which wraps around), of a tracer's ``grid.n_mu`` × ``grid.n_phi`` bins (a bank's strip,
    a patch box): the in-scattered light changes smoothly with the ray's direction, not in
    steps of a bin (steps that would show as seams across the sky)."""
    mu = (travel[:, 2] + 1.0) * 0.5 * grid.n_mu - 0.5
    az = math.radians(grid.toward_deg)
    along = travel[:, 0] * math.cos(az) + travel[:, 1] * math.sin(az)
    across = travel[:, 1] * math.cos(az) - travel[:, 0] * math.sin(az)
    phi = (np.arctan2(across, along) + np.pi) / (2.0 * np.pi) * grid.n_phi - 0.5
    mu0 = np.floor(mu)
    mu_w = np.clip(mu - mu0, 0.0, 1.0)
    mu_lo = np.clip(mu0, 0, grid.n_mu - 1).astype(np.int64)
    mu_hi = np.clip(mu0 + 1, 0, grid.n_mu - 1).astype(np.int64)
    phi0 = np.floor(phi)
    phi_w = phi - phi0
    phi_lo = np.mod(phi0, grid.n_phi).astype(np.int64)
    phi_hi = np.mod(phi0 + 1, grid.n_phi).astype(np.int64)
    return [
        (m * grid.n_phi + f, wm * wf)
        for m, wm in ((mu_lo, 1.0 - mu_w), (mu_hi, mu_w))
        for f, wf in ((phi_lo, 1.0 - phi_w), (phi_hi, phi_w))
    ]
