"""Wind-blown foam streaks: the lines of foam a gale draws along the wind (Beaufort 7 and up).

From force 7 the sea's descriptions change character: "foam from breaking waves begins to be
blown in streaks along the direction of the wind" (7), "foam is blown in well-marked streaks
along the direction of the wind" (8), "dense streaks of foam" (9) (WMO-No. 558, *Manual on
Marine Meteorological Services*, Beaufort scale; the Met Office's sea criteria). The streaks
are the whitecaps' foam gathered into windrows: long lines parallel to the wind, a few metres
to tens of metres apart, into which the surface convergence of wind-driven Langmuir
circulation sweeps floating foam (Langmuir 1938, *Science* 87, 119–123; Leibovich 1983, "The
form and dynamics of Langmuir circulations", *Annu. Rev. Fluid Mech.* 15, 391–427: windrows
within about 15° of the wind, spaced from metres to hundreds of metres, the smallest
shortest-lived). :mod:`seahaze.ocean.whitecaps` puts the whitecaps on the breaking crests;
this module is the streaks between them, a fraction ``s(x, y)`` (0–1) of the surface at each
point covered by streak foam.

The pattern (world frame, metres; ``u`` along the wind, ``v`` across it)
    Across the wind the sea is cut into cells of :data:`SPACING_M`; each cell ``k`` may hold one
    line, jittered within it, of its own width (:data:`WIDTH_M` times 0.5–1.5), with a
    Gaussian cross-profile ``exp(−((v − c_k)/w_k)²)``. The lines meander: ``v`` is shifted by
    :data:`MEANDER_M` times 1-D value noise in ``u`` over :data:`MEANDER_LENGTH_M`, and its
    edges are ragged: ``v`` wanders by :data:`EDGE_WANDER_M` more, 2-D noise over a few metres.
    Along the wind each line is broken into streaks: it is present where its own 1-D value
    noise over :data:`SEGMENT_LENGTH_M` is positive (half its length, by the noise's symmetry),
    faded in and out over :data:`SEGMENT_FADE` of the noise's range, at a ``u`` that wanders by
    :data:`END_WANDER_M` across the line's width, so a streak frays out. Each line has its own
    foam density (:data:`BRIGHTNESS`), and floating foam is fibrous, flecked and holed, not a
    smooth band: the streak is multiplied by ``(1 + clip(g·n, −1, 1))/2``, ``n`` the sum of two
    octaves of 2-D value noise stretched along the wind (:data:`LACE_M`,
    :data:`FINE_LACE_M`), ``g`` :data:`LACE_CONTRAST`, read at a ``v`` of its own that wanders
    by :data:`FIBRE_WANDER_M`: the fibres converge, part and cross the streak. A share of the
    lines, drawn per line from the seed, is present at all: :func:`line_share`, which sets the
    coverage. The noise is the lattice hash of :mod:`seahaze.haze_field` (the same everywhere,
    in any order); the wanders take their own seeds, so each leaves the noise it moves
    symmetric about 0 and the means below hold.

Coverage
    The streaks' mean coverage is ``C = line_share · ½ · √π·w̄/S · 0.7 · ½`` (``w̄`` the mean
    width, ``S`` the cells' spacing, the share of cells holding a line; half of each line
    present, the lines' mean density 0.7, the lace's mean ½; neighbours rarely overlap, which
    the quadrature of ``tests/test_streaks.py`` bounds). It is 0 below force 7's lower wind,
    :data:`ONSET_M_S`, and grows linearly to the whitecap law's ``W`` at force 8's,
    :data:`FULL_M_S`, then follows ``W`` up to the pattern's most (:data:`MAX_LINE_SHARE` of
    the cells holding a line, :data:`MOST_COVERAGE`): streak foam as much as the whitecaps'
    own. The shares are a visual choice, not a measurement: the Beaufort criteria name the
    streaks but give no area, and photographic whitecap coverage counts the bright young foam,
    not the streaks (Callaghan, de Leeuw, Cohen & O'Dowd 2008, *Geophys. Res. Lett.* 35,
    L23609, separate the two stages).
    The streaks' foam is aged foam: its reflectance is Koepke's effective whitecap reflectance,
    :data:`~seahaze.ocean.whitecaps.FOAM_REFLECTANCE` (0.22), fresh foam having faded.

The render reads ``s`` at every shading point (:mod:`seahaze.render.streak_texture`, the
same formulas in drjit), not per mesh vertex: the sea mesh's vertices, 0.3–1 m apart near the
camera and coarser beyond, blur lines a few decimetres wide into bands (docs/ocean.md).

In a sequence the streaks drift downwind with the surface current (:data:`DRIFT_FRACTION`),
while the waves, much faster, pass under them.

Limits: the streaks do not age or re-form within a sequence, do not follow the wave orbital
motion, and their spacing does not grow with the mixed layer's depth or the wind's duration.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..haze_field import lattice_value, value_noise
from .whitecaps import FOAM_REFLECTANCE, whitecap_coverage

ONSET_M_S = 13.9
"""Wind (m/s at 10 m) at which streaks begin: force 7's lower limit."""
FULL_M_S = 17.2
"""Wind at which the streaks' coverage reaches the whitecaps' ``W``: force 8's lower limit."""
SPACING_M = 5.0
"""Distance between neighbouring cells across the wind, each holding at most one line (m)."""
WIDTH_M = 1.2
"""Mean width scale ``w̄`` of a line's Gaussian cross-profile (m)."""
MAX_LINE_SHARE = 0.6
"""The largest share of the cells that hold a line: so many missing keep the lines' spacing
irregular (1 to several cells) at the strongest winds."""
LACE_M = (8.0, 0.35)
"""Lattice steps (m) along and across the wind of the noise that breaks a streak into the
fibres and gaps of floating foam: long along the wind, so that the flecks read as threads
drawn out by it (at 2.5 m along and as wide as a line, seen along the wind from a bridge, they
stacked into the rungs of a ladder)."""
FINE_LACE_M = (2.0, 0.15)
"""Lattice steps (m) of the lace's finer octave: flecks narrower than a fibre, too narrow
across the wind to line up into rungs."""
FINE_LACE_SHARE = 0.4
"""Weight of the finer octave in the lace (the coarser one has the rest)."""
LACE_CONTRAST = 1.6
"""Gain on the lace before it is clipped to [−1, 1]: foam threads on dark water, not grey
bands (two octaves summed vary less than one)."""
FIBRE_WANDER_M = 0.6
"""How far the lace's fibres wander across the wind (m), each stretch on its own: they
converge, part and cross their streak instead of running beside one another the length of
it (drawn along the line's own meander, they read as pairs of rails)."""
FIBRE_WANDER_SCALE_M = (6.0, 1.5)
"""Lattice steps (m) along and across the wind of the fibres' wander."""
EDGE_WANDER_M = 0.3
"""How far a streak's edge wanders across the wind (m): ragged, not a smooth Gaussian band."""
EDGE_WANDER_SCALE_M = (4.0, 1.0)
"""Lattice steps (m) along and across the wind of the edges' wander."""
END_WANDER_M = 3.0
"""How far a streak's end wanders along the wind across its width (m): it frays out instead
of stopping on a straight line across the wind."""
END_WANDER_SCALE_M = (5.0, 0.8)
"""Lattice steps (m) along and across the wind of the ends' wander."""
BRIGHTNESS = (0.4, 0.6)
"""A line's foam density: ``a + b·h`` for its hashed ``h`` in [0, 1) (mean 0.7)."""
MEANDER_M = 1.5
"""Amplitude of the lines' sideways wander (m)."""
MEANDER_LENGTH_M = 40.0
"""Length along the wind over which a line wanders (m: the lattice step of its noise)."""
SEGMENT_LENGTH_M = 25.0
"""Length along the wind of the noise that breaks a line into streaks (m)."""
SEGMENT_FADE = 0.3
"""Range of the segment noise over which a streak fades in and out."""
JITTER = 0.6
"""How far a line may sit from its cell's centre, as a share of the spacing (±half)."""
STREAK_REFLECTANCE = FOAM_REFLECTANCE
"""Visible reflectance of streak foam (Lambertian): Koepke's effective whitecap reflectance."""
DRIFT_FRACTION = 0.03
"""The streaks drift downwind with the wind-driven surface current, about 3 % of ``U10`` (Wu
1983, "Sea-surface drift currents induced by wind and waves", *J. Phys. Oceanogr.* 13,
1441–1451): in a sequence the waves pass under them."""
SEED_SALT = 0x5EA5F0A4
"""Added to the sea's seed: the streaks' noise is unrelated to any other of the scene."""

LINE_COVERAGE = (
    math.sqrt(math.pi) * WIDTH_M / SPACING_M * (BRIGHTNESS[0] + 0.5 * BRIGHTNESS[1]) * 0.5
)
"""Mean coverage of full lines, every one present and unbroken: ``√π w̄ / S`` (the widths'
factor 0.5–1.5 averages 1) times the lines' mean density and the lace's mean, ½ (the noise is
symmetric about 0)."""
MOST_COVERAGE = 0.5 * LINE_COVERAGE * MAX_LINE_SHARE
"""The pattern's most coverage: :data:`MAX_LINE_SHARE` of the lines present, each broken into
streaks over half its length."""


def streak_coverage(wind_speed: float) -> float:
    """The streaks' mean coverage (fraction, 0–1) at wind ``U10`` (m/s; module docstring)."""
    if wind_speed <= ONSET_M_S:
        return 0.0
    ramp = min(1.0, (wind_speed - ONSET_M_S) / (FULL_M_S - ONSET_M_S))
    return min(ramp * whitecap_coverage(wind_speed), MOST_COVERAGE)


def line_share(wind_speed: float) -> float:
    """The share of lines present at wind ``U10``, which gives :func:`streak_coverage`."""
    return streak_coverage(wind_speed) / (0.5 * LINE_COVERAGE)


@dataclass(frozen=True)
class FoamStreaks:
    """The streaks of a wind (module docstring): ``wind_speed`` (m/s at 10 m), blowing toward
    ``toward_deg`` (the waves' direction, counter-clockwise from +x), seeded by ``seed``, at
    ``time_s`` seconds into a sequence (they have drifted :attr:`drift_m` downwind)."""

    wind_speed: float
    toward_deg: float
    seed: int
    time_s: float = 0.0

    @property
    def drift_m(self) -> float:
        """How far the streaks have drifted downwind (m): :data:`DRIFT_FRACTION` of the wind
        times :attr:`time_s`."""
        return DRIFT_FRACTION * self.wind_speed * self.time_s

    @property
    def present(self) -> bool:
        """Whether the wind draws any streaks."""
        return line_share(self.wind_speed) > 0.0

    @property
    def coverage(self) -> float:
        return streak_coverage(self.wind_speed)

    @property
    def noise_seed(self) -> int:
        return (self.seed + SEED_SALT) & 0xFFFFFFFFFFFFFFFF

    def fraction(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """``s``: the fraction of the surface at world points ``(x, y)`` (m) covered by streak
        foam, float64 in [0, 1]."""
        az = math.radians(self.toward_deg)
        x, y = np.asarray(x, np.float64), np.asarray(y, np.float64)
        u = x * math.cos(az) + y * math.sin(az) - self.drift_m
        across = -x * math.sin(az) + y * math.cos(az)
        seed = self.noise_seed
        z = np.zeros_like(u)

        def wander(scale: tuple[float, float], salt: int) -> np.ndarray:
            return value_noise(u / scale[0], across / scale[1], z, seed + salt)

        v = across + MEANDER_M * noise_1d(u / MEANDER_LENGTH_M, z, seed)
        v = v + EDGE_WANDER_M * wander(EDGE_WANDER_SCALE_M, 4)
        u_ends = u + END_WANDER_M * wander(END_WANDER_SCALE_M, 6)
        share = line_share(self.wind_speed)
        cell = np.floor(v / SPACING_M)
        lines = _LineHashes(cell, seed)
        total = np.zeros_like(u)
        for offset in (-1.0, 0.0, 1.0):  # a jittered line may reach into a neighbour's cell
            k = cell + offset
            centre = (k + 0.5 + JITTER * (lines.of(k, 1) - 0.5)) * SPACING_M
            width = WIDTH_M * (0.5 + lines.of(k, 2))
            profile = np.exp(-(((v - centre) / width) ** 2))
            segment = noise_1d(u_ends / SEGMENT_LENGTH_M, k, seed + 1)
            along = np.clip(segment / SEGMENT_FADE + 0.5, 0.0, 1.0)
            present = lines.of(k, 3) < share
            density = BRIGHTNESS[0] + BRIGHTNESS[1] * lines.of(k, 4)
            total = np.maximum(total, np.where(present, density * profile * along, 0.0))
        fibre_v = across + FIBRE_WANDER_M * wander(FIBRE_WANDER_SCALE_M, 3)
        coarse = value_noise(u / LACE_M[0], fibre_v / LACE_M[1], z, seed + 2)
        fine = value_noise(u / FINE_LACE_M[0], fibre_v / FINE_LACE_M[1], z, seed + 5)
        lace = (1.0 - FINE_LACE_SHARE) * coarse + FINE_LACE_SHARE * fine
        return total * 0.5 * (1.0 + np.clip(LACE_CONTRAST * lace, -1.0, 1.0))


class _LineHashes:
    """:func:`hash_01` of every line the points of ``cell`` (their lines' indices) may reach,
    hashed once per line and channel instead of once per point: the same values."""

    def __init__(self, cell: np.ndarray, seed: int) -> None:
        tabulate = cell.size > 0 and bool(np.all(np.isfinite(cell)))
        low, high = (cell.min() - 1.0, cell.max() + 1.0) if tabulate else (0.0, 0.0)
        # Points spread over more lines than there are points (a sparse sample of a wide sea)
        # are hashed one by one, as the table would be larger than the work it saves.
        self._first = low if tabulate and high - low < cell.size else None
        self._lines = np.arange(low, high + 1.0) if self._first is not None else None
        self._seed = seed
        self._tables: dict[int, np.ndarray] = {}

    def of(self, k: np.ndarray, channel: int) -> np.ndarray:
        """:func:`hash_01` of lines ``k`` and ``channel``."""
        if self._first is None:
            return hash_01(k, channel, self._seed)
        if channel not in self._tables:
            self._tables[channel] = hash_01(self._lines, channel, self._seed)
        return self._tables[channel][(k - self._first).astype(np.intp)]


def hash_01(k: np.ndarray, channel: int, seed: int) -> np.ndarray:
    """A value in [0, 1) per integer line ``k`` and ``channel``: the lattice hash of
    :func:`seahaze.haze_field.lattice_value` at ``(k, channel, 0)``, mapped from [−1, 1]."""
    k = np.asarray(k, np.float64).astype(np.int64)
    return 0.5 * (lattice_value(k, np.full_like(k, channel), np.zeros_like(k), seed) + 1.0)


def noise_1d(t: np.ndarray, k: np.ndarray, seed: int) -> np.ndarray:
    """1-D value noise in [−1, 1] along ``t`` (lattice steps), one independent curve per
    integer ``k``: hashed lattice values blended with the quintic fade."""
    t = np.asarray(t, np.float64)
    base = np.floor(t)
    f = t - base
    fade = f * f * f * (f * (f * 6.0 - 15.0) + 10.0)
    i = base.astype(np.int64)
    line = np.broadcast_to(np.asarray(k, np.float64), t.shape).astype(np.int64)
    zero = np.zeros_like(i)
    a = lattice_value(i, line, zero, seed)
    b = lattice_value(i + 1, line, zero, seed)
    return a + fade * (b - a)


def with_streaks(
    coverage: float, reflectance: float, streaks: FoamStreaks | None
) -> tuple[float, float]:
    """The sea's mean foam ``coverage`` (0–1) and its mean ``reflectance`` with ``streaks``
    laid over it (None: as they are): the streaks cover their share of what the whitecaps
    leave, ``F + (1 − F)·C``, and the mean reflectance is the area-weighted one."""
    if streaks is None or not streaks.present:
        return coverage, reflectance
    added = (1.0 - coverage) * streaks.coverage
    total = coverage + added
    return total, (coverage * reflectance + added * STREAK_REFLECTANCE) / total
