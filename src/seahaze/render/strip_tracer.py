"""The diffuse field of a fog bank: photons traced through a strip across its edge, compiled.

A bank (:class:`seahaze.haze_field.Bank`) varies along one horizontal axis, its normal: the
density is ``c ρ_v(z) m(s)`` with ``s`` the metres past its edge and ``m`` the logistic step
of :func:`seahaze.render.field_medium.bank_step`. Its diffuse field therefore depends on ``s``,
the height ``z`` and the direction, and this module tallies it in cells of a strip
(:class:`Strip`) as the directional fluence ``Φ[s, z, dir]`` (W m⁻²), the diffuse tables'
quantity (:mod:`seahaze.render.diffuse_table`) with one more axis. The same photons are traced
through the bank's vertical profile alone (``ρ_v``, the horizontally homogeneous haze the
tables hold) into the same cells (every :data:`PROFILE_STRIDE`-th photon): what
:mod:`seahaze.render.bank_diffuse` takes of it is its mean across the strip, which pools every
cell of a height. A photon draws the same random numbers in both.

Method (the tables' physics, :mod:`seahaze.render.diffuse_table`, with these differences):

* Photons enter the strip's top at a uniformly random ``s`` over the strip widened by
  :attr:`Strip.margin_m` on each side, carrying the source's horizontal irradiance times that
  span (power per metre of edge), and leave at twice the margin.
* Free paths by delta tracking against the densest point of either field (``σ max ρ_v`` times
  the larger of ``c max(1, r)`` and 1): a tentative collision is real with probability
  density over that bound. The first flight of a sun
  photon is direct light (the kernels' shadow rays): it is not tallied, and it is not split.
* Track lengths are tallied at ``photon_tracer.TRACK_POINTS`` stratified points of every
  flight, each scoring ``w ℓ / n`` into its cell and direction bin: the track-length
  estimator's expectation with far less noise than one point per tentative collision.
* Tallies are integers in fixed point, per-thread copies summed at the end (as the tables'
  tracer: the same bytes whatever the thread order).

Import this module only once a Mitsuba variant is set.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np

from ..medium import HazeMedium, drjit_ops
from . import jit_haze
from .field_medium import bank_step, profile_bound
from .photon_tracer import (
    FIXED_POINT,
    MAX_FLIGHTS,
    TRACK_PACKET,
    SeaReflectance,
    SeaTables,
    downward_photons,
    flight_bins,
    russian_roulette,
    scatter_or_reflect,
    track_points,
)

PROFILE_STRIDE = 1
"""Every this-many-th photon is traced through the profile too. Only the profile's mean across
the strip is used (it is horizontally uniform, and pools forty-odd cells), but its noise is
common to every pixel's ratio: with one photon in 8, one render's region error at 1000 m
scattered 1.5–1.7× more (sixteen strip seeds, the same render; the same at 300 m), for 0.8
against 1.0 s per level at 2^20 photons."""


@dataclass(frozen=True)
class Strip:
    """The strip's cells and the bank in it: ``n_s`` cells of distance ``s`` past the edge over
    ``[s_lo, s_hi)``, ``n_z`` of height over ``[0, top_m)``, and direction bins of ``n_mu``
    ``μ = cos`` zenith over ``[−1, 1]`` × ``n_phi`` azimuths from the bank's normal over
    ``[−π, π)``."""

    s_lo: float
    s_hi: float
    n_s: int
    top_m: float
    n_z: int
    n_mu: int
    n_phi: int
    toward_deg: float
    """World azimuth of the bank's normal (into the bank), deg."""
    edge_m: float
    near_ratio: float
    scale: float
    """``c``: the field's density scale."""
    margin_m: float

    @property
    def n_dir(self) -> int:
        return self.n_mu * self.n_phi

    @property
    def cells(self) -> int:
        return self.n_s * self.n_z * self.n_dir


@dataclass(frozen=True)
class StripFluence:
    """Directional fluence ``[level, s, z, dir, rgb]`` (W m⁻²) of the bank's diffuse field and
    of its vertical profile's (the same photons)."""

    bank: np.ndarray
    profile: np.ndarray


def trace_strip(
    sun: tuple[np.ndarray, np.ndarray],
    sky: tuple[np.ndarray, np.ndarray],
    sea: SeaReflectance,
    sigmas: Sequence[float],
    profile: HazeMedium,
    strip: Strip,
    seed: int,
    profile_stride: int = PROFILE_STRIDE,
) -> StripFluence:
    """The bank's and its profile's diffuse fields at every extinction in ``sigmas`` (1/m per
    unit density, each > 0) of ``profile``'s optics (albedo, ``g``) in ``strip``'s cells, from
    the source photons ``sun`` and ``sky`` (downward travel directions and horizontal
    irradiance weights, numpy, as :func:`seahaze.render.photon_sources.emitter_photons`);
    every ``profile_stride``-th photon is traced through the profile too."""
    sun_d, sun_w = downward_photons(*sun)
    sky_d, sky_w = downward_photons(*sky)
    d_all, w_all = np.concatenate([sun_d, sky_d]), np.concatenate([sun_w, sky_w])
    n_photons, n_sun, n_levels = len(d_all), len(sun_d), len(sigmas)
    shape = (n_levels, strip.n_s, strip.n_z, strip.n_dir, 3)
    scale = float(w_all.max(axis=1).mean()) if n_photons else 0.0
    if n_photons == 0 or scale <= 0.0 or n_levels == 0:
        return StripFluence(np.zeros(shape), np.zeros(shape))
    span = strip.s_hi - strip.s_lo + 2.0 * strip.margin_m

    # Lane = (level, family, photon): every photon in the bank, every profile_stride-th in
    # the profile (weighted up by the stride). The counts are opaque: one kernel for any scene.
    n_profile = -(-n_photons // profile_stride)
    per_level = n_photons + n_profile
    index = dr.arange(mi.UInt32, n_levels * per_level)
    photons_op, per_level_op = dr.opaque(mi.UInt32, n_photons), dr.opaque(mi.UInt32, per_level)
    level = index // per_level_op
    rest = index - level * per_level_op
    family = dr.select(rest < photons_op, 0, 1)  # 0: the bank, 1: its profile alone
    photon = dr.select(family == 0, rest, (rest - photons_op) * profile_stride)
    weight = dr.select(
        family == 0,
        dr.opaque(mi.Float, 1.0 / scale),
        dr.opaque(mi.Float, n_photons / n_profile / scale),
    )
    d = tuple(dr.gather(mi.Float, jit_haze.owned_floats(d_all[:, i]), photon) for i in range(3))
    w = tuple(
        dr.gather(mi.Float, jit_haze.owned_floats(w_all[:, i]), photon) * weight for i in range(3)
    )
    direct = photon < dr.opaque(mi.UInt32, n_sun)
    rng = mi.PCG32(dr.width(index))
    # Stream = photon: a photon draws the same numbers in both families and at every level.
    rng.seed(dr.opaque(mi.UInt64, seed) + mi.UInt64(photon), mi.UInt64(photon))

    p = _StripParams(strip, profile, span)
    sigma = dr.gather(mi.Float, jit_haze.padded_floats(np.asarray(sigmas)), level)
    majorant = sigma * p.bound
    s = p.launch_lo + rng.next_float32() * p.span
    z = dr.full(mi.Float, 1.0, dr.width(index)) * p.top
    tables = SeaTables(sea)
    tally = dr.zeros(mi.Int64, 2 * n_levels * strip.cells * TRACK_PACKET)
    base = (level * 2 + family) * strip.cells
    active = dr.max(w) > 0.0
    flights = dr.zeros(mi.UInt32, dr.width(index))
    ops = drjit_ops()

    def cond(s, z, dx, dy, dz, wr, wg, wb, direct, active, flights, rng):
        return active

    def body(s, z, dx, dy, dz, wr, wg, wb, direct, active, flights, rng):
        d, w = (dx, dy, dz), (wr, wg, wb)
        u = [rng.next_float32() for _ in range(7)]
        free = -dr.log(dr.maximum(1.0 - u[0], 1e-30)) / majorant
        wall = dr.select(dz > 0, (p.top - z) / dz, dr.select(dz < 0, -z / dz, dr.inf))
        step = dr.minimum(free, wall)
        along = dx * p.cos_n + dy * p.sin_n
        _tally(tally, base, s, z, along, d, w, step, u[6], active & ~direct, p)
        s_end = dr.fma(step, along, s)
        z_end = dr.clip(dr.fma(step, dz, z), 0.0, p.top)
        collide = free < wall
        bank = p.scale * bank_step(s_end, p.half_inverse_edge, p.near)
        density = profile.density(z_end, ops) * dr.select(family == 0, bank, 1.0)
        real = collide & (u[1] * p.bound < density)
        at_sea = ~collide & (dz < 0)
        d, w = scatter_or_reflect(d, w, u[2:5], real, at_sea, p.albedo, p.g, tables)
        z = dr.select(at_sea, 0.0, z_end)
        direct &= ~(real | at_sea)
        inside = (s_end > p.leave_lo) & (s_end < p.leave_hi)
        active &= (collide | at_sea) & inside
        w, survive = russian_roulette(w, u[5])
        flights += 1
        active &= survive & (d[2] != 0.0) & (flights < MAX_FLIGHTS)
        return (s_end, z, *d, *w, direct, active, flights, rng)

    dr.while_loop((s, z, *d, *w, direct, active, flights, rng), cond, body)
    dr.eval(tally)
    dr.sync_thread()  # wait with Python's lock let go: Ctrl-C's watcher (seahaze.interrupts)
    sums = np.array(tally).reshape(n_levels, 2, strip.n_s, strip.n_z, strip.n_dir, TRACK_PACKET)
    ds, dz_cell = (strip.s_hi - strip.s_lo) / strip.n_s, strip.top_m / strip.n_z
    # Fixed point → metres of track × weight; per cell volume (per metre of edge) → fluence.
    fluence = sums[..., :3].astype(np.float64) * (scale * span / (FIXED_POINT * ds * dz_cell))
    return StripFluence(fluence[:, 0], fluence[:, 1])


class _StripParams:
    """The strip's and medium's scalars as opaque drjit values (kernel inputs, not literals:
    another bank or frame reuses the kernel)."""

    def __init__(self, strip: Strip, profile: HazeMedium, span: float):
        opaque = lambda v: dr.opaque(mi.Float, float(v))  # noqa: E731
        az = math.radians(strip.toward_deg)
        self.strip = strip
        self.cos_n, self.sin_n = opaque(math.cos(az)), opaque(math.sin(az))
        self.top = opaque(strip.top_m)
        self.scale = opaque(strip.scale)
        # The densest point of either family: the bank's c·max m or the profile's 1, times ρ_v.
        densest = max(strip.scale * max(1.0, strip.near_ratio), 1.0) * profile_bound(profile)
        self.bound = opaque(densest)
        self.half_inverse_edge = opaque(0.5 / strip.edge_m)
        self.near = opaque(strip.near_ratio)
        self.albedo, self.g = opaque(profile.albedo), opaque(profile.g)
        self.span = opaque(span)
        self.launch_lo = opaque(strip.s_lo - strip.margin_m)
        self.leave_lo = opaque(strip.s_lo - 2.0 * strip.margin_m)
        self.leave_hi = opaque(strip.s_hi + 2.0 * strip.margin_m)
        self.s_lo = opaque(strip.s_lo)
        self.inv_ds = opaque(strip.n_s / (strip.s_hi - strip.s_lo))
        self.inv_dz = opaque(strip.n_z / strip.top_m)


def _tally(tally, base, s, z, along, d, w, step, u, active, p: _StripParams) -> None:
    """Track length ``w ℓ`` of the flight from ``(s, z)`` along ``d`` (``along``: its component
    on the bank's normal) for ``step`` metres, at ``photon_tracer.TRACK_POINTS`` points
    stratified with the offset ``u``, into each point's cell and direction bin (points outside
    the strip's ``s`` range score nothing)."""
    strip = p.strip
    dz = d[2]
    mu_bin, phi_bin = flight_bins(d, strip.n_mu, strip.n_phi, p.cos_n, p.sin_n)
    dir_bin = mu_bin * strip.n_phi + phi_bin
    packet, points = track_points(w, step, u)
    for t in points:
        cs = (dr.fma(t, along, s) - p.s_lo) * p.inv_ds
        cz = dr.clip(dr.fma(t, dz, z), 0.0, p.top) * p.inv_dz
        inside = active & (cs >= 0.0) & (cs < strip.n_s)
        i_s = mi.UInt32(dr.clip(mi.Int32(cs), 0, strip.n_s - 1))
        i_z = mi.UInt32(dr.clip(mi.Int32(cz), 0, strip.n_z - 1))
        cell = base + (i_s * strip.n_z + i_z) * strip.n_dir + dir_bin
        dr.scatter_add(tally, packet, cell, inside, mode=dr.ReduceMode.Expand)
