"""The diffuse-field photon tracer of :mod:`seahaze.render.diffuse_table`, compiled with drjit.

Every level's photons are traced in one kernel: a lane is one photon of one level, its
extinction gathered from the level's ``σ``, so eleven levels cost one launch and the kernel is
the same for every scene (no value is baked into it). The physics is the numpy description in
:mod:`seahaze.render.diffuse_table`; what is specific to the compiled version:

* **Lanes.** Per level, one lane per sun photon that reaches the sea on its first flight, one
  per sun photon that scatters on the way down (the first flight is split, as described there),
  and one per sky photon.
* **Random numbers.** One PCG32 stream per photon (``seed``, photon index), shared by that
  photon's lanes at every level; five draws per flight.
* **Deterministic tallies.** Track lengths are summed as integers: every contribution is
  rounded to a fixed point of :data:`FIXED_POINT` units per (normalised) photon weight, and
  integer addition does not depend on the order in which threads add. Floating-point sums
  would make the table — and every image — differ in its last bits from run to run. The
  rounding error is below 1e-9 of a photon's weight.
* **Packet scatters.** Each tally cell holds eight integers (the full-bin and partial-bin sums of
  R, G, B, each padded to four), added by one packet scatter into per-thread copies of the
  tally (drjit's ``ReduceMode.Expand``), which are summed at the end — exact for integers, and
  several times faster than eight atomic additions on a CPU.
* **Few transcendental functions per flight.** Azimuths are rotations by the direction's own
  horizontal cosine and sine (the sea) or by the sun's (the tally's folded azimuth), not
  ``atan2``/``cos``/``sin`` round trips, and a sea sample (direction, weight) is one packet
  gather of eight floats, read only by photons at the sea; faint photons end by Russian
  roulette (:data:`WEIGHT_FLOOR`). What each of these saved is in docs/benchmarks.md, "Design
  measurements".
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from . import jit_haze

FIXED_POINT = float(2**30)
"""Tally units per unit of normalised photon weight (a photon weighs about one)."""
WEIGHT_FLOOR = 1.0e-2
"""Russian roulette below this fraction of the mean source photon weight (unbiased: a survivor
is lifted to the floor). Photons this faint are mostly sky photons after a sea reflection:
the floor changes the tables far less than their own noise (docs/benchmarks.md, "Design
measurements")."""
MAX_FLIGHTS = 4000
MU_FLOOR = 1.0e-6
"""|μ| floor of the track-length division: a flight within 1e-6 of horizontal has probability
~1e-6 and its length in the bin is underestimated at worst."""
_DRAWS = 5
CELL = 8
"""Integers per tally cell: full-bin R, G, B, pad, partial-bin R, G, B, pad (a packet)."""


@dataclass(frozen=True)
class SeaReflectance:
    """The sea's BSDF pre-sampled for photons: per incidence bin (``μ`` of the arriving travel
    direction, ``n_mu`` equal bins over (0, 1]) ``per_bin`` outgoing travel directions in the
    plane of incidence (arriving from −x) with their RGB weights (importance transport)."""

    wo: np.ndarray
    """(n_mu, per_bin, 3) unit outgoing travel directions, z > 0."""
    weight: np.ndarray
    """(n_mu, per_bin, 3) RGB weights (BSDF × cos / pdf); zero where a sample failed."""

    @classmethod
    def black(cls) -> SeaReflectance:
        """A sea that reflects nothing."""
        return cls(np.array([[[0.0, 0.0, 1.0]]]), np.zeros((1, 1, 3)))

    @property
    def n_mu(self) -> int:
        return self.wo.shape[0]

    @property
    def per_bin(self) -> int:
        return self.wo.shape[1]

    def reflect(self, d: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """Reflected travel directions and RGB weights for downward travel directions ``d``
        (numpy; the tracer does the same in drjit). A photon takes a random pre-drawn outgoing
        direction of its incidence bin, rotated to its own azimuth — exact for an isotropic
        BSDF up to the binning of the incidence angle."""
        return self.samples(d, rng.integers(0, self.per_bin, len(d)))

    def samples(self, d: np.ndarray, pick: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Outgoing travel directions and RGB weights (``pick``'s shape, then 3) of the
        pre-drawn samples ``pick`` ((N,) or (N, K) indices) of the incidence bins of downward
        travel directions ``d`` (N, 3), rotated to each direction's azimuth (numpy)."""
        mu_bin = np.clip((-d[:, 2] * self.n_mu).astype(np.int64), 0, self.n_mu - 1)
        mu_bin = mu_bin.reshape(-1, *([1] * (pick.ndim - 1)))
        wo = self.wo[mu_bin, pick]
        azimuth = np.arctan2(d[:, 1], d[:, 0]).reshape(mu_bin.shape)
        c, s = np.cos(azimuth), np.sin(azimuth)
        out = np.stack(
            [c * wo[..., 0] - s * wo[..., 1], s * wo[..., 0] + c * wo[..., 1], wo[..., 2]], -1
        )
        return out, self.weight[mu_bin, pick]


@dataclass(frozen=True)
class Slab:
    """The slab a table is traced in, and the bins it is tallied into."""

    top_m: float
    albedo: float
    g: float
    sun_azimuth_rad: float
    n_z: int
    n_mu: int
    n_phi: int
    folded: bool = True
    """Azimuths folded about the sun's vertical plane (``n_phi`` bins over ``[0, π]``), or not
    (over ``[−π, π)``: a sky that is not symmetric)."""

    @property
    def n_dir(self) -> int:
        return self.n_mu * self.n_phi


def trace_fluence(
    sun: tuple[np.ndarray, np.ndarray],
    sky: tuple[np.ndarray, np.ndarray],
    sea: SeaReflectance,
    sigmas: Sequence[float],
    slab: Slab,
    seed: int,
) -> np.ndarray:
    """Directional fluence ``Φ[level, z, dir, rgb]`` (W m⁻²) of the diffuse field of every
    extinction in ``sigmas`` (1/m, each > 0), from the same source photons (downward travel
    directions and horizontal irradiance weights, numpy) with independent random numbers."""
    import drjit as dr
    import mitsuba as mi

    # An empty source becomes one photon of zero weight (inactive from the start), so every
    # gather below has data to read.
    sun_d, sun_w = _nonempty(*sun)
    sky_d, sky_w = _nonempty(*sky)
    n_sun, n_sky, n_levels = len(sun_d), len(sky_d), len(sigmas)
    weights = np.concatenate([sun_w, sky_w])
    scale = float(weights.max(axis=1).mean()) if len(weights) else 1.0
    per_level = 2 * n_sun + n_sky
    lanes = n_levels * per_level
    cells = n_levels * slab.n_z * slab.n_dir
    if lanes == 0 or scale <= 0.0:
        return np.zeros((n_levels, slab.n_z, slab.n_dir, 3))

    # Per lane: level, kind (0 sun to the sea, 1 sun scattering, 2 sky) and source photon,
    # computed in the kernel from the lane index and opaque counts. Arrays made from numpy
    # would be loaded at their numpy address's alignment, which is part of the kernel's hash:
    # the same kernel would be compiled again for another scene.
    index = dr.arange(mi.UInt32, lanes)
    n_sun_op, per_level_op = dr.opaque(mi.UInt32, n_sun), dr.opaque(mi.UInt32, per_level)
    level = index // per_level_op
    lane = index - level * per_level_op
    kind = dr.select(lane < n_sun_op, 0, dr.select(lane < 2 * n_sun_op, 1, 2))
    source = dr.select(kind == 2, lane - 2 * n_sun_op, lane % dr.maximum(n_sun_op, 1))
    from_sky = kind == 2

    def column(sun_values: np.ndarray, sky_values: np.ndarray, i: int) -> mi.Float:
        a = dr.gather(mi.Float, mi.Float(sun_values[:, i]), source, ~from_sky)
        b = dr.gather(mi.Float, mi.Float(sky_values[:, i]), source, from_sky)
        return dr.select(from_sky, b, a)

    d = tuple(column(sun_d, sky_d, i) for i in range(3))
    w = tuple(column(sun_w / scale, sky_w / scale, i) for i in range(3))
    # A kernel input, not a literal, and never a one-element array (jit_haze.padded_floats).
    sigma = dr.gather(mi.Float, jit_haze.padded_floats(sigmas), level)
    # Stream = photon index, the same at every level: photon i of each level draws the same
    # random numbers (correlated table noise across levels, and a level's table does not
    # depend on which other levels are traced with it).
    photon = mi.UInt64(lane)
    rng = mi.PCG32(lanes)  # the constructor would add the lane index: seed explicitly
    rng.seed(dr.opaque(mi.UInt64, seed) + photon, photon)
    tables = SeaTables(sea)
    params = _Params(slab)

    z, d, w = _first_flight(kind, d, w, sigma, rng, tables, params)
    tally = dr.zeros(mi.Int64, cells * CELL)
    base = level * (slab.n_z * slab.n_dir)
    active = dr.full(mi.Bool, True, lanes) & (dr.max(w) > 0.0)
    flights = dr.zeros(mi.UInt32, lanes)

    def cond(z, dx, dy, dz, wr, wg, wb, active, flights, rng):
        return active

    def body(z, dx, dy, dz, wr, wg, wb, active, flights, rng):
        d, w = (dx, dy, dz), (wr, wg, wb)
        u = [rng.next_float32() for _ in range(_DRAWS)]
        free = -dr.log(dr.maximum(1.0 - u[0], 1e-30)) / sigma
        boundary = dr.select(dz > 0, (params.top - z) / dz, dr.select(dz < 0, -z / dz, dr.inf))
        step = dr.minimum(free, boundary)
        z_end = dr.clip(z + step * dz, 0.0, params.top)
        _tally(tally, base, z, z_end, d, w, active, params)
        collide = free < boundary
        at_sea = ~collide & (dz < 0)
        cos_t = jit_haze.hg_sample_cos(u[1], params.g)
        scattered = jit_haze.rotate_directions(d, cos_t, 2.0 * dr.pi * u[2])
        reflected, sea_w = tables.reflect(d, u[3], at_sea)
        d = tuple(dr.select(collide, a, b) for a, b in zip(scattered, reflected, strict=True))
        w = tuple(
            dr.select(collide, c * params.albedo, c * s) for c, s in zip(w, sea_w, strict=True)
        )
        z = dr.select(collide, z_end, 0.0)
        active &= collide | at_sea
        w, survive = russian_roulette(w, u[4])
        flights += 1
        # A photon exactly horizontal cannot leave: vanishingly rare.
        active &= survive & (d[2] != 0.0) & (flights < MAX_FLIGHTS)
        return (z, *d, *w, active, flights, rng)

    dr.while_loop((z, *d, *w, active, flights, rng), cond, body)
    dr.eval(tally)
    dr.sync_thread()  # wait with Python's lock let go: Ctrl-C's watcher (seahaze.interrupts)
    sums = np.array(tally).reshape(n_levels, slab.n_z, slab.n_dir, CELL)
    return _fluence(sums[..., 0:3], sums[..., 4:7], slab) * scale


def russian_roulette(w: tuple, u: object) -> tuple[tuple, object]:
    """Photon weights ``w`` (R, G, B drjit Floats, normalised) after Russian roulette with
    uniform ``u``, and whether each photon survives: a photon below :data:`WEIGHT_FLOOR`
    survives with probability weight / floor and is lifted to the floor (the expectation is
    kept)."""
    import drjit as dr

    wmax = dr.maximum(dr.maximum(w[0], w[1]), w[2])
    low = wmax < WEIGHT_FLOOR
    survive = ~low | (u * WEIGHT_FLOOR < wmax)
    lift = WEIGHT_FLOOR / dr.maximum(wmax, 1e-30)
    return tuple(dr.select(low & survive, c * lift, c) for c in w), survive


def scatter_or_reflect(d, w, u, real, at_sea, albedo, g, tables: SeaTables) -> tuple[tuple, tuple]:
    """Travel directions and weights after a flight that ended in a real collision (``real``:
    scattered by the Henyey–Greenstein phase of ``g``, the weight times ``albedo``), at the
    sea (``at_sea``: one of the sea's pre-drawn samples) or in neither (unchanged); ``u``:
    three uniform numbers (the cosine, the azimuth, the sea's sample). The step the field
    tracers (a bank's strip, patches' box) share."""
    import drjit as dr

    cos_t = jit_haze.hg_sample_cos(u[0], g)
    scattered = jit_haze.rotate_directions(d, cos_t, 2.0 * dr.pi * u[1])
    reflected, sea_w = tables.reflect(d, u[2], at_sea)
    d = tuple(
        dr.select(real, a, dr.select(at_sea, b, c))
        for a, b, c in zip(scattered, reflected, d, strict=True)
    )
    w = tuple(
        dr.select(real, c * albedo, dr.select(at_sea, c * k, c))
        for c, k in zip(w, sea_w, strict=True)
    )
    return d, w


TRACK_POINTS = 4
"""Stratified points per flight at which the field tracers (a bank's strip, patches' box)
tally its track length: the track-length estimator's expectation with far less noise than
one point per tentative collision."""
TRACK_PACKET = 4
"""Integers per cell of a bank's strip tallies: R, G, B and a pad (one packet scatter; the
patches' box tallies one integer of luminance)."""


def track_points(w, step, u) -> tuple[object, list]:
    """What each of :data:`TRACK_POINTS` points of a flight of ``step`` metres scores (``w ℓ /
    n`` in fixed point: for weights ``w`` of R, G, B a packet of them and a pad, for a single
    weight one integer) and the points' distances along the flight, stratified with the offset
    ``u`` (drjit; the field tracers' tally step)."""
    import drjit as dr
    import mitsuba as mi

    piece = step * (1.0 / TRACK_POINTS)
    score = [mi.Int64(dr.round(c * piece * FIXED_POINT)) for c in w]
    packet = score[0] if len(score) == 1 else mi.ArrayXi64([*score, mi.Int64(0)])
    return packet, [(k + u) * piece for k in range(TRACK_POINTS)]


def flight_bins(d, n_mu: int, n_phi: int, cos_ref, sin_ref) -> tuple[object, object]:
    """The ``μ`` bin (``n_mu`` over ``[−1, 1]``) and azimuth bin (``n_phi`` over ``[−π, π)``
    from the azimuth whose cosine and sine are ``cos_ref``, ``sin_ref``) of travel directions
    ``d`` (drjit UInt32s; the field tracers' direction bins)."""
    import drjit as dr
    import mitsuba as mi

    dx, dy, dz = d
    mu_bin = mi.UInt32(dr.clip(mi.Int32((dz + 1.0) * 0.5 * n_mu), 0, n_mu - 1))
    phi = jit_haze.azimuth_fraction(dx, dy, cos_ref, sin_ref, folded=False)
    phi_bin = mi.UInt32(dr.clip(mi.Int32(phi * n_phi), 0, n_phi - 1))
    return mu_bin, phi_bin


def downward_photons(d: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Of source photons (travel directions (n, 3), weights (n, 3)), those that travel down
    and carry energy (the sky below the horizon has none), as float64."""
    d = np.asarray(d, dtype=np.float64)
    w = np.asarray(w, dtype=np.float64)
    keep = (d[:, 2] < -1e-6) & (w.max(axis=1) > 0)
    return d[keep], w[keep]


def _nonempty(d: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    if len(d):
        return d, w
    return np.array([[0.0, 0.0, -1.0]]), np.zeros((1, 3))


@dataclass(frozen=True)
class _Params:
    """Scalars of the slab as opaque drjit values, so they are kernel inputs, not literals."""

    top: object
    albedo: object
    g: object
    cos_sun: object
    sin_sun: object
    dz_bin: object
    slab: Slab

    def __init__(self, slab: Slab) -> None:
        import drjit as dr
        import mitsuba as mi

        object.__setattr__(self, "top", dr.opaque(mi.Float, slab.top_m))
        object.__setattr__(self, "albedo", dr.opaque(mi.Float, slab.albedo))
        object.__setattr__(self, "g", dr.opaque(mi.Float, slab.g))
        object.__setattr__(self, "cos_sun", dr.opaque(mi.Float, np.cos(slab.sun_azimuth_rad)))
        object.__setattr__(self, "sin_sun", dr.opaque(mi.Float, np.sin(slab.sun_azimuth_rad)))
        object.__setattr__(self, "dz_bin", dr.opaque(mi.Float, slab.top_m / slab.n_z))
        object.__setattr__(self, "slab", slab)


class SeaTables:
    """:class:`SeaReflectance` uploaded for gathers in the kernel."""

    def __init__(self, sea: SeaReflectance) -> None:
        self.n_mu, self.per_bin = sea.n_mu, sea.per_bin
        # One sample per packet of eight floats (direction, weight, padding): one gather.
        packed = np.zeros((sea.n_mu * sea.per_bin, 8), np.float32)
        packed[:, 0:3] = sea.wo.reshape(-1, 3)
        packed[:, 3:6] = sea.weight.reshape(-1, 3)
        self.samples = jit_haze.owned_floats(packed)

    def reflect(self, d, u, active=True):
        """Reflected travel direction and RGB weight for downward travel direction ``d`` (read
        only where ``active``: zero elsewhere)."""
        import drjit as dr
        import mitsuba as mi

        dx, dy, dz = d
        mu_bin = mi.UInt32(dr.clip(mi.Int32(-dz * self.n_mu), 0, self.n_mu - 1))
        pick = dr.minimum(mi.UInt32(u * self.per_bin), self.per_bin - 1)
        index = mu_bin * self.per_bin + pick
        sample = dr.gather(mi.ArrayXf, self.samples, index, active, shape=(8, dr.width(index)))
        wo = [sample[i] for i in range(3)]
        weight = tuple(sample[i] for i in range(3, 6))
        # The photon's azimuth as its horizontal direction's cosine and sine (no trigonometry;
        # a vertical photon keeps azimuth 0).
        rho = dr.sqrt(dx * dx + dy * dy)
        inv = dr.select(rho > 0.0, dr.rcp(rho), 0.0)
        c, s = dr.select(rho > 0.0, dx * inv, 1.0), dy * inv
        out = (c * wo[0] - s * wo[1], s * wo[0] + c * wo[1], wo[2])
        return out, weight


def _first_flight(kind, d, w, sigma, rng, tables: SeaTables, params: _Params):
    """Start state after the untallied first flight: sun photons reflected at the sea (kind 0)
    with weight ``exp(−τ/|μ|)``, sun photons scattered on the way down (kind 1) at a point from
    the truncated exponential with weight ``(1 − exp(−τ/|μ|))·albedo``, sky photons (kind 2)
    entering at the top."""
    import drjit as dr

    u = [rng.next_float32() for _ in range(4)]
    top = params.top
    t_sea = dr.exp(-sigma * top / -d[2])
    reflected, sea_w = tables.reflect(d, u[0])
    s = -dr.log(dr.maximum(1.0 - u[1] * (1.0 - t_sea), 1e-30)) / sigma
    cos_t = jit_haze.hg_sample_cos(u[2], params.g)
    scattered = jit_haze.rotate_directions(d, cos_t, 2.0 * dr.pi * u[3])
    to_sea, scatters = kind == 0, kind == 1
    z = dr.select(to_sea, 0.0, dr.select(scatters, top + s * d[2], top))
    new_d = tuple(
        dr.select(to_sea, r, dr.select(scatters, sc, c))
        for r, sc, c in zip(reflected, scattered, d, strict=True)
    )
    new_w = tuple(
        dr.select(to_sea, c * t_sea * sw, dr.select(scatters, c * (1.0 - t_sea) * params.albedo, c))
        for c, sw in zip(w, sea_w, strict=True)
    )
    return z, new_d, new_w


def _tally(tally, base, z0, z1, d, w, active, params: _Params) -> None:
    """Track-length tally of flights from ``z0`` to ``z1``: ``(w/|μ|)(A_b(z_hi) − A_b(z_lo))``
    with ``A_b(z) = |[0, z] ∩ bin_b|``, accumulated as full-bin counts and partial lengths (see
    :func:`_fluence`) in fixed point, one packet of :data:`CELL` integers per flight end."""
    import drjit as dr
    import mitsuba as mi

    slab = params.slab
    dx, dy, dz = d
    mu_bin = mi.UInt32(dr.clip(mi.Int32((dz + 1.0) * 0.5 * slab.n_mu), 0, slab.n_mu - 1))
    phi = jit_haze.azimuth_fraction(dx, dy, params.cos_sun, params.sin_sun, slab.folded)
    phi_bin = mi.UInt32(dr.clip(mi.Int32(phi * slab.n_phi), 0, slab.n_phi - 1))
    dir_bin = mu_bin * slab.n_phi + phi_bin
    inv_mu = 1.0 / dr.maximum(dr.abs(dz), MU_FLOOR)
    for end, sign in ((dr.maximum(z0, z1), 1.0), (dr.minimum(z0, z1), -1.0)):
        zc = dr.clip(end, 0.0, params.top)
        zb = mi.UInt32(dr.minimum(mi.Int32(zc / params.dz_bin), slab.n_z - 1))
        frac = dr.clip(zc / params.dz_bin - mi.Float(zb), 0.0, 1.0)
        cell = base + zb * slab.n_dir + dir_bin
        c = [sign * w[ch] * inv_mu * FIXED_POINT for ch in range(3)]
        zero = mi.Int64(0)
        packet = [mi.Int64(dr.round(x)) for x in c] + [zero]
        packet += [mi.Int64(dr.round(x * frac)) for x in c] + [zero]
        # Per-thread copies, no atomics: exact and order-independent for integers.
        dr.scatter_add(tally, mi.ArrayXi64(packet), cell, active, mode=dr.ReduceMode.Expand)


def _fluence(full: np.ndarray, partial: np.ndarray, slab: Slab) -> np.ndarray:
    """``Φ[level, z, dir, rgb]`` from the tallies (level, z, dir, rgb): bins strictly below a
    height's bin are covered in full (a reversed cumulative sum), its own bin in part."""
    full_len = full.astype(np.float64) / FIXED_POINT
    part_len = partial.astype(np.float64) / FIXED_POINT
    above = np.cumsum(full_len[:, ::-1], axis=1)[:, ::-1]
    below = np.zeros_like(full_len)
    below[:, :-1] = above[:, 1:]
    # Track length per bin height: dz × (full bins) + dz × (partial fraction), over dz.
    return below + part_len
