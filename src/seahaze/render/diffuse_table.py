"""The diffuse light of a horizontally homogeneous haze, tabulated once per level.

The ``physical`` mode splits the light scattered toward the camera at a point of the haze into
two parts. *Single scattering* of the sun and sky (light that reached the point straight from
the emitter) is computed per pixel with shadow rays (:mod:`seahaze.render.physical`). Everything
else — light scattered two or more times, and light reflected by the sea — is the *diffuse
field*. In a haze that is horizontally homogeneous it depends only on height and direction, so
it is computed here once per level by plane-parallel Monte Carlo and looked up per pixel. A
medium whose density varies with height is traced as the homogeneous slab it is in reduced
height (:mod:`seahaze.medium`), and looked up there.

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
    haze (``τ ≈ 0.3`` at 4 km) is not starved of samples. The photons are traced by a compiled
    drjit kernel, every level of a scene in one launch (:mod:`seahaze.render.photon_tracer`);
    ``tests/reference_tracer.py`` is an independent numpy version it is tested against.

Assumptions (see docs/physics.md)
    The slab is horizontally unbounded, the sea is flat with the microfacet roughness of the
    sea material (resolved waves are ignored), vessels neither shadow nor reflect the diffuse
    field, and the sky is symmetric about the sun's vertical plane (azimuths are folded) unless
    the grid says it is not (:attr:`TableGrid.folded`: a broken-cloud sky).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..haze import hg_phase
from ..medium import HazeMedium
from .photon_tracer import SeaReflectance, Slab, downward_photons, trace_fluence


@dataclass(frozen=True)
class TableGrid:
    """Bins of the table: heights over ``[0, top]``, ``μ = cos`` zenith over ``[−1, 1]`` and the
    azimuth from the sun folded into ``[0, π]`` — or, with ``folded`` False, over ``[−π, π)``
    for a sky that is not symmetric about the sun's vertical plane. Values sit at bin
    centres."""

    n_z: int = 32
    n_mu: int = 48
    n_phi: int = 24
    folded: bool = True

    @property
    def n_dir(self) -> int:
        return self.n_mu * self.n_phi


DEFAULT_GRID = TableGrid()

UNFOLDED_GRID = TableGrid(n_phi=2 * DEFAULT_GRID.n_phi, folded=False)
"""The grid of a sky with no mirror symmetry (broken cloud): the whole circle of azimuths at
the default grid's bin width."""


@dataclass
class DiffuseTable:
    """In-scattered radiance per metre of the diffuse field, ``J[z, μ, φ, rgb]`` (W m⁻³ sr⁻¹)."""

    values: np.ndarray
    top_m: float
    sun_azimuth_rad: float
    photons: int
    folded: bool = True

    def lookup(self, z: np.ndarray, directions: np.ndarray) -> np.ndarray:
        """Nearest-bin values for heights (m) and travel directions (n, 3) — for tests."""
        n_z, n_mu, n_phi, _ = self.values.shape
        iz = np.clip((np.asarray(z) / self.top_m * n_z).astype(int), 0, n_z - 1)
        imu, iphi = direction_bins(directions, self.sun_azimuth_rad, n_mu, n_phi, self.folded)
        return self.values[iz, imu, iphi]


def direction_bins(
    d: np.ndarray, sun_azimuth: float, n_mu: int, n_phi: int, folded: bool = True
) -> tuple[np.ndarray, np.ndarray]:
    """(μ bin, azimuth bin) of unit travel directions ``d`` (n, 3); the azimuth from the sun
    folded into ``[0, π]``, or with ``folded`` False over ``[−π, π)``."""
    mu_bin = np.clip(((d[:, 2] + 1.0) * 0.5 * n_mu).astype(np.int64), 0, n_mu - 1)
    # Azimuth from the sun wrapped into [-π, π), then folded into [0, π].
    signed = (np.arctan2(d[:, 1], d[:, 0]) - sun_azimuth + np.pi) % (2.0 * np.pi) - np.pi
    fraction = np.abs(signed) / np.pi if folded else (signed + np.pi) / (2.0 * np.pi)
    phi_bin = np.clip((fraction * n_phi).astype(np.int64), 0, n_phi - 1)
    return mu_bin, phi_bin


def bin_directions(grid: TableGrid, sub: int, mirror: bool) -> np.ndarray:
    """Unit vectors (sun azimuth 0) of ``sub × sub`` stratified points in every direction bin,
    shape (n_mu, n_phi, points, 3); with ``mirror`` the points at ``−φ`` are added."""
    offsets = (np.arange(sub) + 0.5) / sub
    mu = (-1.0 + 2.0 * (np.arange(grid.n_mu)[:, None] + offsets[None, :]) / grid.n_mu).ravel()
    cells = (np.arange(grid.n_phi)[:, None] + offsets[None, :]) / grid.n_phi
    phi = (np.pi * cells if grid.folded else 2.0 * np.pi * cells - np.pi).ravel()
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
    centres = bin_directions(grid, 1, mirror=False).reshape(grid.n_dir, 3)
    points = bin_directions(grid, sub, mirror=grid.folded).reshape(grid.n_dir, -1, 3)
    p = np.empty((grid.n_dir, grid.n_dir))
    for j in range(grid.n_dir):
        p[:, j] = hg_phase(centres @ points[j].T, g).mean(axis=1)
    solid_angle = 4.0 * np.pi / grid.n_dir
    return p / (p.sum(axis=1, keepdims=True) * solid_angle)


Photons = tuple[np.ndarray, np.ndarray]
"""Downward travel directions (n, 3) and horizontal irradiance weights (n, 3), in W m⁻², that
sum to the source's irradiance on a horizontal plane above the haze."""


def build_tables(
    sun: Photons,
    sky: Photons,
    sea: SeaReflectance,
    sigmas: Sequence[float],
    medium: HazeMedium,
    sun_azimuth_rad: float,
    seed: int,
    grid: TableGrid = DEFAULT_GRID,
) -> list[DiffuseTable]:
    """Tabulate the diffuse field of ``medium`` (its single-scattering albedo and ``g``) for
    every extinction in ``sigmas`` (1/m, each > 0) from the same source photons (see the
    module docstring). A medium whose density varies with height is traced as the homogeneous
    slab it is in reduced height (:mod:`seahaze.medium`): the table spans ``0 ≤ h ≤ H``.

    The first flight of ``sun`` photons is direct light (the integrator's shadow rays) and is
    not tallied; ``sky`` photons are tallied from the moment they enter, so the table also
    holds the single scattering of skylight, which is smooth and needs no shadow rays. Photon
    ``i`` of every extinction draws the same random numbers (correlated table noise across
    levels, as the camera paths are).
    """
    top_m, albedo, g = medium.reduced_top_m, medium.albedo, medium.g
    sigmas = [float(x) for x in sigmas]
    if any(x <= 0.0 for x in sigmas):
        raise ValueError(f"the diffuse table needs haze (sigma > 0), got {sigmas}")
    sun, sky = downward_photons(*sun), downward_photons(*sky)
    slab = Slab(top_m, albedo, g, sun_azimuth_rad, grid.n_z, grid.n_mu, grid.n_phi, grid.folded)
    fluence = trace_fluence(sun, sky, sea, sigmas, slab, seed)
    p = phase_matrix(float(g), grid)
    photons = len(sun[0]) + len(sky[0])
    return [
        DiffuseTable(
            _in_scattered(phi, p, sigma, albedo, grid), top_m, sun_azimuth_rad, photons, grid.folded
        )
        for phi, sigma in zip(fluence, sigmas, strict=True)
    ]


def _in_scattered(
    fluence: np.ndarray, p: np.ndarray, sigma: float, albedo: float, grid: TableGrid
) -> np.ndarray:
    """``J = σ_s P Φ`` as (n_z, n_mu, n_phi, 3) float32 from the fluence (n_z, n_dir, 3)."""
    n_z, n_dir, _ = fluence.shape
    # One BLAS product over all heights and channels (an einsum here took 60 % of the build).
    stacked = fluence.transpose(1, 0, 2).reshape(n_dir, n_z * 3)
    j = albedo * sigma * (p @ stacked).reshape(n_dir, n_z, 3).transpose(1, 0, 2)
    values = j.reshape(grid.n_z, grid.n_mu, grid.n_phi, 3).astype(np.float32)
    return np.maximum(values, 0.0)
