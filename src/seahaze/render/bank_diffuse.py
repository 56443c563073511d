"""A fog bank's own diffuse light on the camera segment, in the ``physical`` mode.

``physical`` renders haze that varies across the sea as each pixel's equivalent profile
(:mod:`seahaze.render.pixel_density`), and reads the diffuse field — everything but the sun's
single scattering — from tables traced in the horizontally homogeneous profile. A bank is not
that: the light inside it and beside it is the bank's, shaped by its edge over kilometres (the
transport mean free path of a fog with ``g ≈ 0.85`` is ``1 / (σ (1 − g))``, 1.7 km at 1 km
visibility). The equivalent profile left the bank's sky 6 % dark at 1000 m and every region
13–19 % dark at 300 m (docs/physics.md, "Haze that varies across the sea in the physical
mode").

This module gives each pixel its camera segment's ``diffuse_air`` ratio per level: the diffuse
in-scattering along the pixel-centre ray through the bank over the same in the pixel's
equivalent profile,

    diffuse_air = Σ_i e^{−τ_i} σ ρ_i J_bank(s_i, z_i, −ω) Δ_i
                / Σ_i e^{−r τ_v,i} σ r ρ_v,i J_profile(z_i, −ω) Δ_i,

over :data:`RAY_POINTS` points of the ray (cells growing quadratically from the camera), with
``τ`` the field's optical depth from the camera, ``τ_v`` the profile's, ``r`` the pixel's
``view`` ratio and ``J = ϖ Σ_b p(ω_b·ω) Φ_b`` the in-scattered radiance of the directional
fluence ``Φ`` of :mod:`seahaze.render.strip_tracer` (the bank's per cell of distance past the
edge and height; the profile's averaged over the strip, where it is horizontally uniform). The
kernels scale the tables' light on the camera segment by it (``PixelRatios.diffuse_air``). The
sum is taken on a grid of at most :data:`RATIO_GRID_PIXELS` pixels and interpolated to the
pixels between, within the image's segments (the ratio changes slowly across a surface, and
jumps at a silhouette).

The segments after a surface get a ``diffuse_bounce`` ratio of the same kind, averaged over
the directions they leave in, each direction's sums weighted by how much it sends toward the
camera: on the sea, :data:`BOUNCE_RAYS` of the sea's own reflection samples for the pixel's
incidence (the rough lobe and the water body reflect light from every elevation: the mirrored
ray alone put the sea 4–7 % bright); on a hull, as many cosine-weighted directions about the
side that faces the camera. Each such ray's equivalent profile is the profile times its own
density ratio, as the kernels' later segments measure it (:mod:`seahaze.render.segment_ratio`).

The ratios carry the strip's photon noise: the tables' horizontally uniform field is one mean
over forty-odd cells, the bank's is not (docs/benchmarks.md, "How close is physical in a fog
bank?", states it per region).

Import this module only once a Mitsuba variant is set.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..medium import NUMPY
from ..nonuniform import RAY_REACH_M, NonUniformHaze
from .diffuse_table import TableGrid, phase_matrix
from .passes import GeometryPass
from .photon_sources import emitter_photons
from .photon_tracer import SeaReflectance
from .pixel_density import ray_ratio
from .segment_smooth import SEA_SEGMENT, segments, smooth_within_segments
from .strip_tracer import Strip, StripFluence, trace_strip

CELL_M = 120.0
"""Width of the strip's cells across the edge (m): the edge's own scale, ``edge_m``, is tens
of metres, but the diffuse field varies over the transport mean free path (km)."""
BEHIND_M = 1500.0
"""The strip starts this far behind the camera or the edge, whichever is nearer the thin side."""
AHEAD_M = 3000.0
"""…and ends this far past the edge or the camera, whichever lies deeper in the bank. Beyond
both ends the field is taken as the last cell's (plane-parallel far from the edge)."""
MARGIN_M = 3000.0
"""Photons enter over the strip widened by this on each side (:class:`Strip`)."""
GRID = TableGrid(n_z=12, n_mu=24, n_phi=24, folded=False)
"""Heights and directions of the strip's cells (azimuths from the bank's normal)."""
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
over the summed ratios. Neighbouring rays cross the same few strip cells at nearby points, so
the cells' photon noise runs in bands across the sky, a few grid rows apart and 1–2 % deep
in 8-bit values at 2^18 photons; this radius (1/40 of the grid's width) flattens them, and
the ratio itself changes little over it (it is an integral along each ray of a field that
changes over hundreds of metres)."""
_LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
"""Rec. 709 luminance: one ratio per level scales all three channels."""


def bank_strip(medium: NonUniformHaze, camera_xy: tuple[float, float]) -> Strip:
    """The strip of ``medium``'s bank (its field a bank alone) seen from a camera at world
    ``camera_xy`` (m): from :data:`BEHIND_M` behind the camera or the edge to
    :data:`AHEAD_M` past the other, in cells of about :data:`CELL_M`."""
    bank = medium.field.bank
    if bank is None:
        raise ValueError("bank_strip needs a field with a bank")
    x, y = medium.field.drift.shifted(np.float64(camera_xy[0]), np.float64(camera_xy[1]))
    camera = float(bank.beyond(x, y))
    lo, hi = min(camera, 0.0) - BEHIND_M, max(camera, 0.0) + AHEAD_M
    n_s = max(1, round((hi - lo) / CELL_M))
    return Strip(
        lo,
        hi,
        n_s,
        medium.profile.top,
        GRID.n_z,
        GRID.n_mu,
        GRID.n_phi,
        bank.toward_deg,
        bank.edge_m,
        bank.near_ratio,
        medium.scale,
        MARGIN_M,
    )


def trace_bank(
    medium: NonUniformHaze,
    sun: Any,
    sky: Any,
    sea: SeaReflectance,
    sigma: np.ndarray,
    camera_xy: tuple[float, float],
    photons: int,
    seed: int,
) -> tuple[Strip, StripFluence]:
    """The bank's and its profile's diffuse fields (:func:`trace_strip`) at levels of
    (green) extinction ``sigma`` (L,) in 1/m, lit by the Mitsuba emitters ``sun`` and ``sky``
    (``photons`` per level, half from each) over the sea ``sea``. Levels are traced one after
    the other (one kernel: the lanes of all levels at once would need gigabytes)."""
    strip = bank_strip(medium, camera_xy)
    top = medium.profile.top
    sources = [emitter_photons(e, photons // 2, seed + i, top) for i, e in enumerate((sun, sky))]
    traced = [trace_strip(*sources, sea, [float(k)], medium.profile, strip, seed) for k in sigma]
    bank = np.concatenate([t.bank for t in traced])
    profile = np.concatenate([t.profile for t in traced])
    return strip, StripFluence(bank, profile)


def diffuse_ratios(
    medium: NonUniformHaze,
    geometry: GeometryPass,
    view: np.ndarray,
    strip: Strip,
    fluence: StripFluence,
    sigma: np.ndarray,
    sea: SeaReflectance,
) -> tuple[np.ndarray, np.ndarray]:
    """(L, H, W) each pixel's ``diffuse_air`` and ``diffuse_bounce`` ratios (module docstring)
    at levels of (green) extinction ``sigma`` (L,) in 1/m, from the strip's fluences, the
    pixels' ``view`` ratios (H, W) and the sea's reflection samples; summed on a grid and
    spread within the image's segments (:func:`spread_within_segments`)."""
    height, width = view.shape
    step = max(1, math.ceil(math.sqrt(height * width / RATIO_GRID_PIXELS)))
    rows, cols = np.arange(0, height, step), np.arange(0, width, step)
    dirs = geometry.directions[rows][:, cols].reshape(-1, 3).astype(np.float64)
    distance = geometry.distance_m[rows][:, cols].reshape(-1).astype(np.float64)
    origin = np.asarray(geometry.origin, np.float64)
    sources = SourceTables.of(strip, fluence, medium.profile.g)
    starts = np.broadcast_to(origin, dirs.shape)
    r = view[rows][:, cols].reshape(-1)
    true, equivalent = ray_sums(
        medium, sources, sigma, starts, dirs, _reach(medium, starts, dirs, distance), r
    )
    air = _quotient(true, equivalent)
    shape = (len(sigma), len(rows), len(cols))
    labels = segments(geometry.instance, geometry.distance_m)
    grid_labels = labels[::step, ::step]
    bounce = np.ones_like(air)
    on_vessel = grid_labels.reshape(-1) >= 0
    if on_vessel.any():
        points = origin + distance[on_vessel, None] * dirs[on_vessel]
        bounce[:, on_vessel] = hull_bounce_ratios(medium, sources, sigma, points, dirs[on_vessel])
    on_sea = grid_labels.reshape(-1) == SEA_SEGMENT
    if on_sea.any():
        # On every SEA_STRIDE-th grid row and column, interpolated within the sea between.
        sparse = np.zeros(shape[1:], bool)
        sparse[::SEA_STRIDE, ::SEA_STRIDE] = True
        sparse = sparse.reshape(-1) & on_sea
        points = origin + distance[sparse, None] * dirs[sparse]
        bounce[:, sparse] = sea_bounce_ratios(medium, sources, sigma, points, dirs[sparse], sea)
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
    sources: SourceTables,
    sigma: np.ndarray,
    points: np.ndarray,
    dirs: np.ndarray,
    sea: SeaReflectance,
) -> np.ndarray:
    """(L, N) the ``diffuse_bounce`` ratio of sea ``points`` (N, 3) seen along camera
    directions ``dirs`` (N, 3): the diffuse in-scattering along :data:`BOUNCE_RAYS` of the
    sea's reflected directions (its own samples for that incidence, each weighted by its
    luminance) through the bank, over the same along each in its own equivalent profile."""
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
                )
                for i in parts
            ],
            axis=1,
        )
    wo, weight = reflected_directions(sea, dirs)
    n, k = wo.shape[:2]
    starts = np.repeat(points, k, axis=0)
    starts[:, 2] = np.maximum(starts[:, 2], 0.0)
    travel = wo.reshape(-1, 3)
    reach = _reach(medium, starts, travel, np.full(len(travel), np.inf))
    own = ray_ratio(medium, starts, travel, reach)
    true, equivalent = ray_sums(medium, sources, sigma, starts, travel, reach, own, BOUNCE_POINTS)
    w = weight.reshape(1, n, k)
    return _quotient(
        (true.reshape(-1, n, k) * w).sum(axis=2), (equivalent.reshape(-1, n, k) * w).sum(axis=2)
    )


def hull_bounce_ratios(
    medium: NonUniformHaze,
    sources: SourceTables,
    sigma: np.ndarray,
    points: np.ndarray,
    dirs: np.ndarray,
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
    own = ray_ratio(medium, starts, travel, reach)
    true, equivalent = ray_sums(medium, sources, sigma, starts, travel, reach, own, BOUNCE_POINTS)
    return _quotient(true.reshape(-1, n, k).sum(axis=2), equivalent.reshape(-1, n, k).sum(axis=2))


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
    return wo, weight @ _LUMINANCE


def _reach(medium: NonUniformHaze, starts: np.ndarray, dirs: np.ndarray, distance: np.ndarray):
    """How far rays run in the haze: to their surface, the haze's top, or :data:`RAY_REACH_M`."""
    reach = np.minimum(distance, RAY_REACH_M)
    up = dirs[:, 2] > 0.0
    room = np.maximum(medium.profile.top - starts[up, 2], 0.0)
    reach[up] = np.minimum(reach[up], room / dirs[up, 2])
    return reach


def _quotient(true: np.ndarray, equivalent: np.ndarray) -> np.ndarray:
    """``true / equivalent``, 1 where the equivalent profile gives nothing."""
    fine = equivalent > 0.0
    return np.where(fine, true / np.where(fine, equivalent, 1.0), 1.0)


@dataclass(frozen=True)
class SourceTables:
    """Per level, the in-scattered luminance per metre and unit density toward the centre of
    every direction bin (``ϖ Σ_b p Φ_b``; ``σ ρ`` times it is ``J``): the bank's per cell
    ``[L, s·z, dir]`` and the profile's per height ``[L, z, dir]`` (its mean across the
    strip, where it is uniform)."""

    strip: Strip
    bank: np.ndarray
    profile: np.ndarray

    @classmethod
    def of(cls, strip: Strip, fluence: StripFluence, g: float) -> SourceTables:
        grid = TableGrid(strip.n_z, strip.n_mu, strip.n_phi, folded=False)
        phase = phase_matrix(float(g), grid).T  # [bin, node]
        lum = fluence.bank @ _LUMINANCE  # [L, s, z, dir]
        bank = lum.reshape(len(fluence.bank), -1, strip.n_dir) @ phase
        profile = (fluence.profile.mean(axis=1) @ _LUMINANCE) @ phase
        return cls(strip, bank, profile)


def ray_sums(
    medium: NonUniformHaze,
    sources: SourceTables,
    sigma: np.ndarray,
    starts: np.ndarray,
    dirs: np.ndarray,
    reach: np.ndarray,
    ratio: np.ndarray,
    points: int = RAY_POINTS,
) -> tuple[np.ndarray, np.ndarray]:
    """(L, N) each ray's diffuse in-scattering toward its start through the bank,
    ``Σ e^{−τ} ρ J Δ``, and through its equivalent profile (the profile times ``ratio``),
    per unit ``σ ϖ`` — from ``starts`` (N, 3) along unit ``dirs`` (N, 3) over ``reach`` (N,)
    metres, at ``points`` points (cells growing quadratically from the start)."""
    strip = sources.strip
    edges = (np.arange(points + 1) / points) ** 2
    along = 0.5 * (edges[:-1] + edges[1:])[None] * reach[:, None]
    width = np.diff(edges)[None] * reach[:, None]
    p = starts[:, None, :] + along[..., None] * dirs[:, None, :]
    z = np.clip(p[..., 2], 0.0, strip.top_m)
    rho = medium.density_at(p[..., 0], p[..., 1], z) * width
    rho_v = np.asarray(medium.profile.density(z, NUMPY), np.float64) * width
    s_cell, z_cell = _cells(medium, strip, p[..., 0], p[..., 1], z)
    nodes = _nodes(strip, -dirs)
    cell = s_cell * strip.n_z + z_cell
    mass = np.cumsum(rho, 1) - 0.5 * rho
    mass_v = (np.cumsum(rho_v, 1) - 0.5 * rho_v) * ratio[:, None]
    true = np.empty((len(sigma), len(dirs)))
    equivalent = np.empty_like(true)
    for k, level in enumerate(sigma):
        j_bank = sum(w[:, None] * sources.bank[k][cell, n[:, None]] for n, w in nodes)
        j_flat = sum(w[:, None] * sources.profile[k][z_cell, n[:, None]] for n, w in nodes)
        true[k] = np.sum(np.exp(-level * mass) * rho * j_bank, 1)
        equivalent[k] = np.sum(np.exp(-level * mass_v) * rho_v * j_flat, 1) * ratio
    return true, equivalent


def _cells(medium: NonUniformHaze, strip: Strip, x: Any, y: Any, z: Any):
    """The strip cell (distance past the edge, height) of world points; points beyond either
    end of the strip take its end cell."""
    bank = medium.field.bank
    assert bank is not None
    s = bank.beyond(*medium.field.drift.shifted(x, y))
    i_s = np.clip((s - strip.s_lo) * (strip.n_s / (strip.s_hi - strip.s_lo)), 0, strip.n_s - 1)
    i_z = np.clip(z * (strip.n_z / strip.top_m), 0, strip.n_z - 1)
    return i_s.astype(np.int64), i_z.astype(np.int64)


def _nodes(strip: Strip, travel: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """The four direction bins around travel directions (N, 3), as (bin, bilinear weight)
    pairs between the bins' centres in ``μ`` and in the azimuth from the bank's normal (which
    wraps around): the in-scattered light changes smoothly with the ray's direction, not in
    steps of a bin (steps that would show as seams across the sky)."""
    mu = (travel[:, 2] + 1.0) * 0.5 * strip.n_mu - 0.5
    az = math.radians(strip.toward_deg)
    along = travel[:, 0] * math.cos(az) + travel[:, 1] * math.sin(az)
    across = travel[:, 1] * math.cos(az) - travel[:, 0] * math.sin(az)
    phi = (np.arctan2(across, along) + np.pi) / (2.0 * np.pi) * strip.n_phi - 0.5
    mu0 = np.floor(mu)
    mu_w = np.clip(mu - mu0, 0.0, 1.0)
    mu_lo = np.clip(mu0, 0, strip.n_mu - 1).astype(np.int64)
    mu_hi = np.clip(mu0 + 1, 0, strip.n_mu - 1).astype(np.int64)
    phi0 = np.floor(phi)
    phi_w = phi - phi0
    phi_lo = np.mod(phi0, strip.n_phi).astype(np.int64)
    phi_hi = np.mod(phi0 + 1, strip.n_phi).astype(np.int64)
    return [
        (m * strip.n_phi + f, wm * wf)
        for m, wm in ((mu_lo, 1.0 - mu_w), (mu_hi, mu_w))
        for f, wf in ((phi_lo, 1.0 - phi_w), (phi_hi, phi_w))
    ]
