"""The diffuse field of drifting patches: photons traced through a box of the field, compiled.

Patches (:class:`seahaze.haze_field.Patches`) vary in all three dimensions, so their diffuse
field is a function of position and direction. Tallied in as many cells as the strip of a
bank (:mod:`seahaze.render.strip_tracer`) holds, a box of them would leave a few photons per
cell and direction. What the patches change, though, is mostly how much light reaches a point
from above and from the sun's side, far less the light's angular shape within those: this
module tallies the field's fluence ``Φ_G(x, y, z)`` per cell of a box around the camera in a
few direction groups ``G`` (:attr:`Box.n_band` bands of ``μ`` × :attr:`Box.n_sector` sectors
of azimuth), and the horizontally homogeneous profile's directional fluence ``Φ_v(z, dir)``
per height and direction bin (the diffuse tables' quantity,
:mod:`seahaze.render.diffuse_table`). :mod:`seahaze.render.patch_diffuse` takes the field's
diffuse light as the profile's, each group's share scaled by the ratio of the two at each
cell, ``Φ_G(x, y, z) / Φ_v,G(z)``.

Method (the tables' physics with these differences, as the strip's):

* The box is **periodic** horizontally: a photon that leaves one side enters the opposite one
  (the field read where it really is, at the wrapped position). Patches are statistically the
  same everywhere, so no photon is spent in margins around the box, and the seam, where the
  field on one side does not continue the field on the other, lies at the box's edge, far
  (several mean free paths) from the haze a camera ray sees.
* Photons enter the box's top at a uniformly random point carrying the source's horizontal
  irradiance times the box's area; free paths by delta tracking against the density's bound
  (the field's ``σ c √R max ρ_v``, the profile's ``σ max ρ_v``); the first flight of a sun
  photon is direct light (the kernels' shadow rays), not tallied; the luminance of its track
  length tallied at ``photon_tracer.TRACK_POINTS`` stratified points of every flight (all
  that :mod:`seahaze.render.patch_diffuse` reads, one integer per cell).
* The same source photons are traced through the field and through the profile alone, each
  in a kernel of its own and against its own bound: the profile's lanes never evaluate the
  field, nor take the field's null collisions (about ``c √R`` per real one, 5 in patches of
  ratio 30). Their random numbers then differ, which costs nothing measurable: the profile's
  fluence is summed over all the box's columns, its noise far below a cell's. Without
  patches the two bounds are the same, and so are the two tallies, to the integer.
* Tallies are integers in fixed point, per-thread copies summed at the end: the same bytes
  whatever the thread order.

Import this module only once a Mitsuba variant is set.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from types import SimpleNamespace

import drjit as dr
import mitsuba as mi
import numpy as np

from ..haze_field import HazeField
from ..medium import HazeMedium, drjit_ops
from . import jit_haze
from .diffuse_ratios import LUMINANCE
from .field_medium import field_bound, field_modulation, profile_bound
from .photon_tracer import (
    FIXED_POINT,
    MAX_FLIGHTS,
    SeaReflectance,
    SeaTables,
    downward_photons,
    flight_bins,
    russian_roulette,
    scatter_or_reflect,
    track_points,
)


@dataclass(frozen=True)
class Box:
    """The box's cells: ``n_xy`` × ``n_xy`` columns over the square of side ``side_m`` whose
    lower corner is world ``(x0, y0)``, ``n_z`` heights over ``[0, top_m)``; the profile's
    direction bins, ``n_mu`` ``μ = cos`` zenith over ``[−1, 1]`` × ``n_phi`` azimuths from
    world +x over ``[−π, π)``."""

    x0: float
    y0: float
    side_m: float
    n_xy: int
    top_m: float
    n_z: int
    n_mu: int
    n_phi: int
    n_band: int = 1
    """The field's μ bands: ``n_mu`` must be a multiple of it."""
    n_sector: int = 1
    """The field's azimuth sectors: ``n_phi`` must be a multiple of it."""
    sector_start: int = 0
    """The azimuth bin at which the first sector begins (the sectors turn with it)."""

    @property
    def n_light(self) -> int:
        """The field's direction groups: μ bands × azimuth sectors."""
        return self.n_band * self.n_sector

    def groups(self) -> np.ndarray:
        """(n_dir,) the direction group of each of the profile's direction bins."""
        mu, phi = np.divmod(np.arange(self.n_dir), self.n_phi)
        band = mu // (self.n_mu // self.n_band)
        turned = (phi - self.sector_start) % self.n_phi
        return band * self.n_sector + turned // (self.n_phi // self.n_sector)

    @property
    def n_dir(self) -> int:
        return self.n_mu * self.n_phi

    @property
    def field_cells(self) -> int:
        return self.n_xy * self.n_xy * self.n_z * self.n_light

    @property
    def profile_cells(self) -> int:
        return self.n_z * self.n_dir

    @property
    def toward_deg(self) -> float:
        """World azimuth from which the profile's direction bins count (deg)."""
        return 0.0


@dataclass(frozen=True)
class BoxFluence:
    """The luminance of the field's fluence per direction group ``[level, x, y, z, group]``
    (None where only the profile was traced) and of the profile's directional fluence
    ``[level, z, dir]`` (W m⁻², Rec. 709 luminance), from the same source photons."""

    field: np.ndarray | None
    profile: np.ndarray


@dataclass(frozen=True)
class SourcePhotons:
    """The sun's and the sky's photons that travel down and carry energy: travel directions
    ``d`` (n, 3) and weights ``w`` (n, 3) normalised by ``scale`` (W m⁻² per photon of the
    box's area), the first ``n_sun`` the sun's. Made once per frame, read by every level's
    box."""

    d: np.ndarray
    w: np.ndarray
    n_sun: int
    scale: float


def source_photons(
    sun: tuple[np.ndarray, np.ndarray], sky: tuple[np.ndarray, np.ndarray]
) -> SourcePhotons:
    """:class:`SourcePhotons` of the source photons ``sun`` and ``sky`` (travel directions and
    horizontal irradiance weights, numpy, as
    :func:`seahaze.render.photon_sources.emitter_photons`)."""
    sun_d, sun_w = downward_photons(*sun)
    sky_d, sky_w = downward_photons(*sky)
    d, w = np.concatenate([sun_d, sky_d]), np.concatenate([sun_w, sky_w])
    scale = float(w.max(axis=1).mean()) if len(d) else 0.0
    return SourcePhotons(d, w / scale if scale > 0.0 else w, len(sun_d), scale)


def trace_box(
    sources: SourcePhotons,
    sea: SeaReflectance,
    sigmas: Sequence[float],
    profile: HazeMedium,
    field: HazeField,
    scale: float,
    travelled_m: float,
    box: Box,
    seed: int,
    with_field: bool = True,
) -> BoxFluence:
    """The field's (``scale · ρ_v · m``, ``m`` of ``field`` drifted ``travelled_m`` metres)
    and its profile's diffuse fields at every extinction in ``sigmas`` (1/m per unit density,
    each > 0) of ``profile``'s optics in ``box``'s cells, from the ``sources``' photons; the
    profile's alone (``field`` None in the result) unless ``with_field``."""
    n_levels = len(sigmas)
    field_shape = (n_levels, box.n_xy, box.n_xy, box.n_z, box.n_light)
    profile_shape = (n_levels, box.n_z, box.n_dir)
    families = (True, False) if with_field else (False,)
    if len(sources.d) == 0 or sources.scale <= 0.0 or n_levels == 0:
        sums = {f: np.zeros(field_shape if f else profile_shape) for f in families}
    else:
        p = _BoxParams(box, profile, field, scale, travelled_m)
        sums = {
            f: _trace_family(f, sources, sigmas, profile, field, p, sea, seed)
            * (sources.scale * box.side_m**2 / FIXED_POINT)
            for f in families
        }
    cell = box.side_m / box.n_xy
    dz_cell = box.top_m / box.n_z
    # Track length × weight per cell volume → fluence.
    field_fluence = sums[True] / (cell * cell * dz_cell) if with_field else None
    profile_fluence = sums[False] / (box.side_m**2 * dz_cell)
    return BoxFluence(
        None if field_fluence is None else field_fluence.reshape(field_shape),
        profile_fluence.reshape(profile_shape),
    )


def _trace_family(
    in_field: bool,
    sources: SourcePhotons,
    sigmas: Sequence[float],
    profile: HazeMedium,
    field: HazeField,
    p: _BoxParams,
    sea: SeaReflectance,
    seed: int,
) -> np.ndarray:
    """The fixed-point luminance tallies ``[level, cell]`` (as float64) of every photon of
    ``sources`` traced through the field (``in_field``) or through the profile alone, each
    family in a kernel of its own against its own bound (a photon's random stream is its
    index)."""
    box = p.box
    d_all, w_all, n_sun = sources.d, sources.w, sources.n_sun
    n_photons, n_levels = len(d_all), len(sigmas)
    index = dr.arange(mi.UInt32, n_levels * n_photons)
    level = index // dr.opaque(mi.UInt32, n_photons)
    photon = index - level * dr.opaque(mi.UInt32, n_photons)
    d = tuple(dr.gather(mi.Float, jit_haze.owned_floats(d_all[:, i]), photon) for i in range(3))
    w = tuple(dr.gather(mi.Float, jit_haze.owned_floats(w_all[:, i]), photon) for i in range(3))
    direct = photon < dr.opaque(mi.UInt32, n_sun)
    rng = mi.PCG32(dr.width(index))
    rng.seed(dr.opaque(mi.UInt64, seed) + mi.UInt64(photon), mi.UInt64(photon))
    sigma = dr.gather(mi.Float, jit_haze.padded_floats(np.asarray(sigmas)), level)
    bound = p.bound if in_field else p.profile_bound
    majorant = sigma * bound
    x = rng.next_float32() * p.side
    y = rng.next_float32() * p.side
    z = dr.full(mi.Float, 1.0, dr.width(index)) * p.top
    tables = SeaTables(sea)
    cells = box.field_cells if in_field else box.profile_cells
    tally = dr.zeros(mi.Int64, n_levels * cells)
    base = level * cells
    active = dr.max(w) > 0.0
    flights = dr.zeros(mi.UInt32, dr.width(index))
    ops = drjit_ops()

    def cond(x, y, z, dx, dy, dz, wr, wg, wb, direct, active, flights, rng):
        return active

    def body(x, y, z, dx, dy, dz, wr, wg, wb, direct, active, flights, rng):
        d, w = (dx, dy, dz), (wr, wg, wb)
        u = [rng.next_float32() for _ in range(7)]
        free = -dr.log(dr.maximum(1.0 - u[0], 1e-30)) / majorant
        wall = dr.select(dz > 0, (p.top - z) / dz, dr.select(dz < 0, -z / dz, dr.inf))
        step = dr.minimum(free, wall)
        _tally(tally, base, in_field, x, y, z, d, w, step, u[6], active & ~direct, p)
        x_end = p.wrap(dr.fma(step, dx, x))
        y_end = p.wrap(dr.fma(step, dy, y))
        z_end = dr.clip(dr.fma(step, dz, z), 0.0, p.top)
        collide = free < wall
        density = profile.density(z_end, ops)
        if in_field:
            world = SimpleNamespace(x=x_end + p.x0, y=y_end + p.y0, z=z_end)
            density = density * p.scale * field_modulation(field, world, p.travelled)
        real = collide & (u[1] * bound < density)
        at_sea = ~collide & (dz < 0)
        d, w = scatter_or_reflect(d, w, u[2:5], real, at_sea, p.albedo, p.g, tables)
        z = dr.select(at_sea, 0.0, z_end)
        direct &= ~(real | at_sea)
        active &= collide | at_sea
        w, survive = russian_roulette(w, u[5])
        flights += 1
        active &= survive & (d[2] != 0.0) & (flights < MAX_FLIGHTS)
        return (x_end, y_end, z, *d, *w, direct, active, flights, rng)

    dr.while_loop((x, y, z, *d, *w, direct, active, flights, rng), cond, body)
    dr.eval(tally)
    dr.sync_thread()  # wait with Python's lock let go: Ctrl-C's watcher (seahaze.interrupts)
    return np.array(tally).astype(np.float64).reshape(n_levels, cells)


class _BoxParams:
    """The box's and medium's scalars as opaque drjit values where another frame changes them
    (the drift), literals where the kernel already bakes in the field (its patches)."""

    def __init__(
        self,
        box: Box,
        profile: HazeMedium,
        field: HazeField,
        scale: float,
        travelled_m: float,
    ):
        opaque = lambda v: dr.opaque(mi.Float, float(v))  # noqa: E731
        self.box = box
        self.side = opaque(box.side_m)
        self.inv_side = opaque(1.0 / box.side_m)
        self.x0, self.y0 = opaque(box.x0), opaque(box.y0)
        self.top = opaque(box.top_m)
        self.scale = opaque(scale)
        self.travelled = opaque(travelled_m)
        self.profile_bound = opaque(profile_bound(profile))
        self.bound = opaque(scale * field_bound(field) * profile_bound(profile))
        self.albedo, self.g = opaque(profile.albedo), opaque(profile.g)
        self.inv_cell = opaque(box.n_xy / box.side_m)
        self.inv_dz = opaque(box.n_z / box.top_m)
        # Each direction bin's group, read from Box.groups: the field's tally files light by
        # the same table the ratios are formed with, not by a second copy of its formula.
        self.groups = mi.UInt32(box.groups().astype(np.uint32))

    def wrap(self, v):
        """A horizontal box coordinate brought back into ``[0, side)`` (periodic box)."""
        return v - dr.floor(v * self.inv_side) * self.side


def luminance(w):
    """The Rec. 709 luminance of drjit weights ``w`` (R, G, B): what the box tallies, since
    :mod:`seahaze.render.patch_diffuse` reads only the luminance of the fluence (one integer
    per cell instead of a packet of four: a quarter of the tallies' memory traffic)."""
    r, g, b = (float(c) for c in LUMINANCE)
    return dr.fma(w[0], r, dr.fma(w[1], g, w[2] * b))


def _tally(tally, base, in_field, x, y, z, d, w, step, u, active, p: _BoxParams) -> None:
    """Track length ``w ℓ`` of the flight from box point ``(x, y, z)`` along ``d`` for
    ``step`` metres, at ``photon_tracer.TRACK_POINTS`` points stratified with the offset
    ``u``: into each point's cell and direction group in the field (``in_field``), each
    point's height and direction bin in the profile."""
    box = p.box
    dx, dy, dz = d
    mu_bin, phi_bin = flight_bins(d, box.n_mu, box.n_phi, 1.0, 0.0)
    dir_bin = mu_bin * box.n_phi + phi_bin
    if in_field:
        group = dr.gather(mi.UInt32, p.groups, dir_bin, active)
    score, points = track_points((luminance(w),), step, u)
    last = box.n_xy - 1
    for t in points:
        cz = dr.clip(dr.fma(t, dz, z), 0.0, p.top) * p.inv_dz
        i_z = mi.UInt32(dr.clip(mi.Int32(cz), 0, box.n_z - 1))
        if in_field:
            i_x = mi.UInt32(dr.clip(mi.Int32(p.wrap(dr.fma(t, dx, x)) * p.inv_cell), 0, last))
            i_y = mi.UInt32(dr.clip(mi.Int32(p.wrap(dr.fma(t, dy, y)) * p.inv_cell), 0, last))
            cell = base + ((i_x * box.n_xy + i_y) * box.n_z + i_z) * box.n_light + group
        else:
            cell = base + i_z * box.n_dir + dir_bin
        dr.scatter_add(tally, score, cell, active, mode=dr.ReduceMode.Expand)
