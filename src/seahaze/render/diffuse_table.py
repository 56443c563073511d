"""The diffuse light of a horizontally homogeneous haze slab, tabulated once per level.

The ``physical`` mode splits the light scattered toward the camera at a point of the haze into
two parts. *Single scattering* of the sun and sky (light that reached the point straight from
the emitter) is computed per pixel with shadow rays (:mod:`seahaze.render.physical`). Everything
else — light scattered two or more times, and light reflected by the sea — is the *diffuse
field*. In a slab that is horizontally homogeneous it depends only on height and direction, so
it is computed here once per level by plane-parallel Monte Carlo and looked up per pixel.

Method
    Photons leave the emitter (directions and weights from the scene's own emitter sampling, so
    the sky model is exactly Mitsuba's), enter the slab top, and are followed with analog free
    paths (extinction ``σ``), Henyey–Greenstein scattering with weight ``×albedo``, and the sea
    BSDF at ``z = 0`` (sampled in Mitsuba in importance mode, so the boundary is the same
    material the camera sees). The first flight from the emitter is *not* tallied: it is the
    direct light the integrator handles. Every later flight is tallied with the track-length
    estimator into height × direction bins, which gives the directional fluence
    ``Φ_b(z) = ∫_b L dω`` (W m⁻²) of the diffuse field. The in-scattered radiance per metre toward
    a direction ``ω`` is then ``J(z, ω) = σ_s Σ_b p(ω_b · ω) Φ_b(z)`` with bin-averaged phase
    values (rows renormalised so the discrete phase function integrates to one).

    The first flight is split: the part that reaches the sea is reflected there with weight
    ``exp(−τ/|μ|)``, the rest scatters at a point drawn from the truncated exponential — so thin
    haze (``τ ≈ 0.3`` at 4 km) is not starved of samples.

Assumptions (see docs/physics.md)
    The slab is horizontally unbounded, the sea is flat with the microfacet roughness of the
    sea material (resolved waves are ignored), vessels neither shadow nor reflect the diffuse
    field, the sky is symmetric about the sun's vertical plane (azimuths are folded).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..haze import hg_phase, hg_sample_cos, rotate_directions

SeaReflection = Callable[[np.ndarray, np.random.Generator], tuple[np.ndarray, np.ndarray]]
"""(downward travel directions (m, 3), rng) → (reflected directions (m, 3), RGB weights (m, 3))."""

WEIGHT_FLOOR = 1.0e-4
"""Russian roulette below this fraction of the mean source photon weight."""
MAX_FLIGHTS = 4000


@dataclass(frozen=True)
class TableGrid:
    """Bins of the table: heights over ``[0, top]``, ``μ = cos`` zenith over ``[−1, 1]`` and the
    azimuth from the sun folded into ``[0, π]``. Values sit at bin centres."""

    n_z: int = 32
    n_mu: int = 48
    n_phi: int = 24

    @property
    def n_dir(self) -> int:
        return self.n_mu * self.n_phi


DEFAULT_GRID = TableGrid()


@dataclass
class DiffuseTable:
    """In-scattered radiance per metre of the diffuse field, ``J[z, μ, φ, rgb]`` (W m⁻³ sr⁻¹)."""

    values: np.ndarray
    top_m: float
    sun_azimuth_rad: float
    photons: int
    flights: int

    def lookup(self, z: np.ndarray, directions: np.ndarray) -> np.ndarray:
        """Nearest-bin values for heights (m) and travel directions (n, 3) — for tests."""
        n_z, n_mu, n_phi, _ = self.values.shape
        iz = np.clip((np.asarray(z) / self.top_m * n_z).astype(int), 0, n_z - 1)
        imu, iphi = direction_bins(directions, self.sun_azimuth_rad, n_mu, n_phi)
        return self.values[iz, imu, iphi]


def direction_bins(
    d: np.ndarray, sun_azimuth: float, n_mu: int, n_phi: int
) -> tuple[np.ndarray, np.ndarray]:
    """(μ bin, folded azimuth bin) of unit travel directions ``d`` (n, 3)."""
    mu_bin = np.clip(((d[:, 2] + 1.0) * 0.5 * n_mu).astype(np.int64), 0, n_mu - 1)
    # Azimuth from the sun wrapped into [-π, π), then folded into [0, π].
    phi = np.abs((np.arctan2(d[:, 1], d[:, 0]) - sun_azimuth + np.pi) % (2.0 * np.pi) - np.pi)
    phi_bin = np.clip((phi / np.pi * n_phi).astype(np.int64), 0, n_phi - 1)
    return mu_bin, phi_bin


def _bin_directions(grid: TableGrid, sub: int, mirror: bool) -> np.ndarray:
    """Unit vectors (sun azimuth 0) of ``sub × sub`` stratified points in every direction bin,
    shape (n_mu, n_phi, points, 3); with ``mirror`` the points at ``−φ`` are added."""
    offsets = (np.arange(sub) + 0.5) / sub
    mu = (-1.0 + 2.0 * (np.arange(grid.n_mu)[:, None] + offsets[None, :]) / grid.n_mu).ravel()
    phi = (np.pi * (np.arange(grid.n_phi)[:, None] + offsets[None, :]) / grid.n_phi).ravel()
    mu = mu.reshape(grid.n_mu, sub)[:, None, :, None]
    phi = phi.reshape(grid.n_phi, sub)[None, :, None, :]
    phis = np.concatenate([phi, -phi], axis=-1) if mirror else phi
    s = np.sqrt(1.0 - mu**2)
    v = np.stack(np.broadcast_arrays(s * np.cos(phis), s * np.sin(phis), mu + 0 * phis), axis=-1)
    return v.reshape(grid.n_mu, grid.n_phi, -1, 3)


@lru_cache(maxsize=8)
def phase_matrix(g: float, grid: TableGrid = DEFAULT_GRID, sub: int = 4) -> np.ndarray:
    """``P[node, bin]``: the HG phase value (1/sr) from direction bin ``bin`` into the centre of
    bin ``node``, averaged over the bin (and its mirror azimuth), rows summing to 1 over the
    bins' solid angles. Depends only on ``g`` and the grid, so it is cached across levels."""
    centres = _bin_directions(grid, 1, mirror=False).reshape(grid.n_dir, 3)
    points = _bin_directions(grid, sub, mirror=True).reshape(grid.n_dir, -1, 3)
    p = np.empty((grid.n_dir, grid.n_dir))
    for j in range(grid.n_dir):
        p[:, j] = hg_phase(centres @ points[j].T, g).mean(axis=1)
    solid_angle = 4.0 * np.pi / grid.n_dir
    return p / (p.sum(axis=1, keepdims=True) * solid_angle)


class _TrackTally:
    """Track-length tally of photon flights into height × direction bins, RGB.

    A flight from height ``z_a`` to ``z_b`` with weight ``w`` and vertical cosine ``μ`` spends
    ``|[z_a, z_b] ∩ bin| / |μ|`` metres in each height bin. With ``A_b(z) = |[0, z] ∩ bin_b|`` the
    contribution is ``(w/|μ|)(A_b(z_hi) − A_b(z_lo))``, and ``A`` of many heights accumulates in
    O(n) as a count of full bins below (a reversed cumulative sum) plus the partial bin.
    """

    def __init__(self, grid: TableGrid, top: float, sun_azimuth: float):
        self.grid, self.top, self.sun_azimuth = grid, top, sun_azimuth
        self.dz = top / grid.n_z
        shape = (grid.n_z * grid.n_dir, 3)
        self.full = np.zeros(shape)
        self.partial = np.zeros(shape)
        self.flat = np.zeros(shape)

    def add(self, z0: np.ndarray, z1: np.ndarray, d: np.ndarray, w: np.ndarray) -> None:
        """Tally flights from ``z0`` to ``z1`` along travel directions ``d`` with weights ``w``."""
        g = self.grid
        mu_bin, phi_bin = direction_bins(d, self.sun_azimuth, g.n_mu, g.n_phi)
        dir_bin = mu_bin * g.n_phi + phi_bin
        # |μ| is floored only against division by zero: a flight within 1e-6 of horizontal has
        # probability ~1e-6 and its length in the bin is underestimated at worst.
        mu = np.abs(d[:, 2])
        c = w / np.maximum(mu, 1e-6)[:, None]
        # The upper end adds A_b(z_hi), the lower end subtracts A_b(z_lo): both ends in one
        # bincount per accumulator, over flat (bin, channel) indices.
        z = np.clip(np.concatenate([np.maximum(z0, z1), np.minimum(z0, z1)]), 0.0, self.top)
        zb = np.minimum((z / self.dz).astype(np.int64), g.n_z - 1)
        key = (zb * g.n_dir + np.concatenate([dir_bin, dir_bin]))[:, None] * 3 + np.arange(3)
        signed = np.concatenate([c, -c])
        frac = (z - zb * self.dz)[:, None]
        size = self.full.size
        self.full += np.bincount(key.ravel(), signed.ravel(), size).reshape(self.full.shape)
        self.partial += np.bincount(key.ravel(), (signed * frac).ravel(), size).reshape(
            self.partial.shape
        )

    def fluence(self) -> np.ndarray:
        """Directional fluence ``Φ[z, dir, rgb]`` (W m⁻²), the track length per bin height."""
        g = self.grid
        full = self.full.reshape(g.n_z, g.n_dir, 3)
        # Bins strictly below a height's bin are covered in full: sum over the bins above them.
        above = np.cumsum(full[::-1], axis=0)[::-1]
        below_full = np.zeros_like(full)
        below_full[:-1] = above[1:]
        length = self.dz * below_full + self.partial.reshape(g.n_z, g.n_dir, 3)
        return length / self.dz


def _boundary_distance(z: np.ndarray, dz: np.ndarray, top: float) -> np.ndarray:
    """Distance along a flight to the slab top (going up) or the sea at z = 0 (going down)."""
    with np.errstate(divide="ignore"):
        return np.where(dz > 0, (top - z) / dz, np.where(dz < 0, -z / dz, np.inf))


Photons = tuple[np.ndarray, np.ndarray]
"""Downward travel directions (n, 3) and horizontal irradiance weights (n, 3), in W m⁻², that
sum to the source's irradiance on a horizontal plane above the haze."""


def build_diffuse_table(
    sun: Photons,
    sky: Photons,
    sea_reflection: SeaReflection,
    sigma: float,
    albedo: float,
    g: float,
    top_m: float,
    sun_azimuth_rad: float,
    seed: int,
    grid: TableGrid = DEFAULT_GRID,
) -> DiffuseTable:
    """Tabulate the diffuse field of a slab ``0 ≤ z ≤ top_m`` (see the module docstring).

    The first flight of ``sun`` photons is direct light (the integrator's shadow rays) and is
    not tallied; ``sky`` photons are tallied from the moment they enter, so the table also
    holds the single scattering of skylight, which is smooth and needs no shadow rays.
    """
    if sigma <= 0.0:
        raise ValueError(f"the diffuse table needs haze (sigma > 0), got {sigma}")
    rng = np.random.default_rng(seed)
    tally = _TrackTally(grid, top_m, sun_azimuth_rad)
    d, w = _downward(*sun)
    sky_d, sky_w = _downward(*sky)
    weights = np.concatenate([w, sky_w])
    floor = WEIGHT_FLOOR * float(weights.max(axis=1).mean()) if len(weights) else 0.0

    # First flight of the sun (direct light, not tallied), split into the part that reaches
    # the sea and the part that scatters on the way down.
    path_to_sea = top_m / -d[:, 2]
    t_sea = np.exp(-sigma * path_to_sea)
    refl_d, refl_w = sea_reflection(d, rng)
    u = rng.random(len(d))
    s = -np.log1p(-u * (1.0 - t_sea)) / sigma
    scat_z = top_m + s * d[:, 2]
    scat_d = rotate_directions(
        d, hg_sample_cos(rng.random(len(d)), g), 2 * np.pi * rng.random(len(d))
    )
    z = np.concatenate([np.zeros(len(d)), scat_z, np.full(len(sky_d), float(top_m))])
    d = np.concatenate([refl_d, scat_d, sky_d])
    w = np.concatenate([w * t_sea[:, None] * refl_w, w * (1.0 - t_sea)[:, None] * albedo, sky_w])

    flights = 0
    while len(z) and flights < MAX_FLIGHTS:
        flights += 1
        free = -np.log1p(-rng.random(len(z))) / sigma
        boundary = _boundary_distance(z, d[:, 2], top_m)
        step = np.minimum(free, boundary)
        z_end = np.clip(z + step * d[:, 2], 0.0, top_m)
        tally.add(z, z_end, d, w)
        collide = free < boundary
        at_sea = ~collide & (d[:, 2] < 0)
        # Collisions scatter; the sea reflects; flights through the top leave for good.
        n_c = int(collide.sum())
        new_d = rotate_directions(
            d[collide], hg_sample_cos(rng.random(n_c), g), 2 * np.pi * rng.random(n_c)
        )
        sea_d, sea_w = sea_reflection(d[at_sea], rng) if at_sea.any() else (d[at_sea], w[at_sea])
        z = np.concatenate([z_end[collide], np.zeros(int(at_sea.sum()))])
        d = np.concatenate([new_d, sea_d])
        w = np.concatenate([w[collide] * albedo, w[at_sea] * sea_w])
        # Russian roulette keeps the expectation: survivors below the floor are lifted to it.
        wmax = w.max(axis=1) if len(w) else np.zeros(0)
        low = wmax < floor
        survive = ~low | (rng.random(len(w)) * floor < wmax)
        w = np.where((low & survive)[:, None], w * (floor / np.maximum(wmax, 1e-300))[:, None], w)
        z, d, w = z[survive], d[survive], w[survive]
        ok = d[:, 2] != 0.0  # a photon exactly horizontal cannot leave: vanishingly rare
        z, d, w = z[ok], d[ok], w[ok]

    fluence = tally.fluence()  # (n_z, n_dir, 3)
    p = phase_matrix(float(g), grid)
    # One BLAS product over all heights and channels (an einsum here took 60 % of the build).
    n_z, n_dir, _ = fluence.shape
    stacked = fluence.transpose(1, 0, 2).reshape(n_dir, n_z * 3)
    j = albedo * sigma * (p @ stacked).reshape(n_dir, n_z, 3).transpose(1, 0, 2)
    values = j.reshape(grid.n_z, grid.n_mu, grid.n_phi, 3).astype(np.float32)
    return DiffuseTable(np.maximum(values, 0.0), top_m, sun_azimuth_rad, len(weights), flights)


def _downward(d: np.ndarray, w: np.ndarray) -> Photons:
    """The photons that travel down and carry energy (the sky below the horizon has none)."""
    d = np.asarray(d, dtype=np.float64)
    w = np.asarray(w, dtype=np.float64)
    keep = (d[:, 2] < -1e-6) & (w.max(axis=1) > 0)
    return d[keep], w[keep]
