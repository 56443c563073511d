"""An independent numpy implementation of the diffuse-field photon tracer, for tests.

The same physics as :mod:`seahaze.render.photon_tracer` (analog flights, the split first sun
flight, HG scattering, the sea, Russian roulette, the track-length tally), written wavefront-style
in float64 numpy with its own random numbers, so the compiled tracer is checked against a
separate program rather than against itself. It keeps its own slab (flights to the top and to
the sea at z = 0) on purpose, rather than asking :mod:`seahaze.medium`: a shared formula would
be checked against itself.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from seahaze.haze import hg_sample_cos, rotate_directions
from seahaze.render.diffuse_table import DEFAULT_GRID, TableGrid, direction_bins

SeaReflection = Callable[[np.ndarray, np.random.Generator], tuple[np.ndarray, np.ndarray]]
WEIGHT_FLOOR = 1.0e-4
MAX_FLIGHTS = 4000


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
        mu_bin, phi_bin = direction_bins(d, self.sun_azimuth, g.n_mu, g.n_phi, g.folded)
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


def reference_fluence(
    sun: tuple[np.ndarray, np.ndarray],
    sky: tuple[np.ndarray, np.ndarray],
    sea_reflection: SeaReflection,
    sigma: float,
    albedo: float,
    g: float,
    top_m: float,
    sun_azimuth_rad: float,
    seed: int,
    grid: TableGrid = DEFAULT_GRID,
) -> np.ndarray:
    """Directional fluence ``Φ[z, dir, rgb]`` of the diffuse field (numpy reference)."""
    if sigma <= 0.0:
        raise ValueError(f"the diffuse table needs haze (sigma > 0), got {sigma}")
    rng = np.random.default_rng(seed)
    tally = _TrackTally(grid, top_m, sun_azimuth_rad)
    d, w = sun
    sky_d, sky_w = sky
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

    return tally.fluence()
