"""Ship waves and wakes: the Kelvin wave pattern, the bow wave and the turbulent foam wake of
moving vessels, as height and foam fields to add to the sea surface.

Waves (linear potential flow, deep water)
    A hull moving at speed ``U`` is represented by a pressure distribution on the free surface
    that, at rest, would press the water down by the hull's draft: ``p = rho·g·d(xi, eta)``, with
    ``d = T·(1 - s_xi⁴)·(1 - s_eta²)`` over the waterplane (``s_xi = 2·xi/L``,
    ``s_eta = 2·eta/B``; block coefficient 0.53) in the vessel frame (``xi`` toward the bow,
    ``eta`` to port). This is the "pressure ship" of Havelock (1909, *Proc. R. Soc. A* 82,
    276–300; Lamb 1932, *Hydrodynamics*, §§242–256, waves of a travelling pressure). The steady
    linearised free-surface problem is solved exactly in Fourier space,

        zeta_hat(k) = -d_hat(k) · (U·k_x + i·mu)² / (g·|k| - (U·k_x + i·mu)²),

    where the hydrostatic part ``-d`` (the hull's own displacement, hidden inside the hull) has
    been removed, so a vessel at rest makes no waves. Rayleigh's small damping ``mu`` selects
    the waves that trail the ship (the radiation condition). ``d_hat`` is the analytic Fourier
    transform of the hull shape (Gauss–Legendre quadrature), so small hulls need no fine grid.
    Deep-water dispersion puts every free wave on ``g·k = (U·k_x)²``: a wave whose crests run at
    angle ``theta`` to the track has ``k = k0·sec²theta``, ``k0 = g/U²``; stationary phase
    confines the pattern to the Kelvin wedge of half-angle ``asin(1/3) = 19.47°`` (Kelvin 1887;
    Lighthill 1978, *Waves in Fluids*, §3.10), with transverse waves of wavelength
    ``2·pi·U²/g`` along the track and divergent waves toward the cusps. The same solution holds
    the bow wave (the crest that stands at the stem) and the trough along the hull. The
    amplitude scales with the draft, and with length, beam and speed through ``d_hat`` at the
    free-wave wavenumbers, i.e. through the Froude number ``U/sqrt(g·L)``: interference of bow
    and stern systems, humps and hollows of wave making. At large Froude numbers the angle of
    the highest waves shrinks below Kelvin's (Rabaud & Moisy 2013, *Phys. Rev. Lett.* 110,
    214503), which this linear model reproduces; the wedge itself stays 19.47°.

    Approximations: linear (no breaking, no crest sharpening; steep bow waves of fast hulls
    are overestimated), a smooth parametric hull instead of the real lines, deep water, no
    viscosity or interaction with the wind sea, a straight course at constant speed. The field
    is computed on a periodic grid (waves shorter than two grid spacings are dropped; the
    damping is set so that copies wrapped around the grid are below ``e⁻³``) and tapered to
    zero over the last fifth of the wake length :func:`wake_length`.

Breaking (bow wave foam)
    Where the linear wave slope ``|grad zeta|`` exceeds :data:`BREAKING_SLOPE` (0.44, the slope
    amplitude ``a·k`` of the steepest Stokes wave, Michell 1893: ``H/lambda = 0.142``) the
    crest is taken to break and carries foam (a smooth ramp from 70 % of it).

Turbulent foam wake
    The propeller and hull leave a band of white, bubbly water behind the stern. It is centred
    on the track with a half-width ``b(s) = (B/2)·(1 + s/B)^(1/5)`` at distance ``s`` behind the
    stern: self-propelled (momentumless) turbulent wakes widen as the 1/5 power of distance
    (Tennekes & Lumley 1972, *A First Course in Turbulence*, §4.2; Naudascher 1965, *J. Fluid
    Mech.* 22, 625–656) — an approximation for a ship's wake, which is not axisymmetric. Its
    foam fraction is 1 at the stern and decays as ``exp(-s/(U·tau))`` with the water's age
    ``s/U``. The surface stays white while the bubbles the hull and propeller mixed in are still
    rising, so ``tau`` scales with the depth they were mixed to — taken as the hull's draft
    ``T`` (an assumption) — over the rise speed of millimetre air bubbles, about 0.2 m/s (Clift,
    Grace & Weber 1978, *Bubbles, Drops and Particles*, ch. 7): ``tau = T / 0.2 m/s``, at least
    2 s (:func:`wake_foam_decay_s`). A tanker of 12 m draft keeps a white wake for about a
    minute (half a kilometre at 14 kn, two ship lengths), a speedboat of 0.6 m for 3 s (50 m at
    30 kn). Cross profile: ``(1 - (eta/b)²)²``.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy import fft as sfft

from .base import cell_samples, lowpass_weight
from .spectra import GRAVITY

KNOT_M_S = 1852.0 / 3600.0
"""One knot (international nautical mile per hour) in m/s."""

KELVIN_HALF_ANGLE_RAD = math.asin(1.0 / 3.0)
"""Half-angle of the Kelvin wedge, ``asin(1/3) = 19.47°`` (rad)."""

BREAKING_SLOPE = 0.44
"""Wave slope above which a crest breaks: ``a·k`` of the steepest Stokes wave
(``H/lambda = 0.142``, Michell 1893)."""

BUBBLE_RISE_M_S = 0.2
"""Rise speed of millimetre air bubbles in sea water (m/s; Clift, Grace & Weber 1978)."""

MIN_WAKE_FOAM_DECAY_S = 2.0
"""Shortest e-folding age of wake foam (s), for hulls of almost no draft."""

WAKE_SHIP_LENGTHS = 12.0
"""The wake is computed for at least this many ship lengths behind the vessel..."""

WAKE_TRANSVERSE_WAVELENGTHS = 10.0
"""...and at least this many transverse wavelengths ``2·pi·U²/g``..."""

MAX_WAKE_LENGTH_M = 6000.0
"""...but not beyond this distance (m)."""

GRID_POINTS_PER_WAVELENGTH = 12.0
"""Grid points per transverse wavelength (the divergent waves are shorter)..."""

GRID_POINTS_PER_LENGTH = 8.0
"""...and at least this many per ship length (fast small craft make waves of hull scale)."""

MAX_GRID_POINTS = 2048
"""Largest grid along either axis."""

FOAM_CUTOFF = 1.0e-3
"""Turbulent wake foam below this fraction is ignored when finding where a wake has foam."""

MAX_FOAM_SAMPLES = 16
"""Most samples per axis when a mesh vertex's footprint is averaged over the wake foam."""

WRAP_DECAY = 3.0
"""The damping lowers a wave by ``exp(-WRAP_DECAY)`` over one period of the grid."""

_GAUSS_NODES, _GAUSS_WEIGHTS = np.polynomial.legendre.leggauss(96)


@dataclass(frozen=True)
class MovingVessel:
    """A vessel under way, as seen by the sea.

    Attributes:
        x, y: world position of midships (m).
        heading_deg: world azimuth the bow points to (deg, counter-clockwise from +x).
        speed_m_s: speed through the water (m/s); 0 makes no waves and no wake.
        length_m: waterline length (m).
        beam_m: beam (m).
        draft_m: draft (m).
    """

    x: float
    y: float
    heading_deg: float
    speed_m_s: float
    length_m: float
    beam_m: float
    draft_m: float

    def __post_init__(self) -> None:
        if self.speed_m_s < 0.0 or min(self.length_m, self.beam_m, self.draft_m) <= 0.0:
            raise ValueError("speed must be >= 0 and length, beam, draft > 0")

    @property
    def froude_number(self) -> float:
        """Length Froude number ``U/sqrt(g·L)``."""
        return self.speed_m_s / math.sqrt(GRAVITY * self.length_m)

    def to_vessel_frame(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World (x, y) (m) → ``(xi, eta)``: metres ahead of midships and to port."""
        h = math.radians(self.heading_deg)
        dx = np.asarray(x, dtype=float) - self.x
        dy = np.asarray(y, dtype=float) - self.y
        return dx * math.cos(h) + dy * math.sin(h), -dx * math.sin(h) + dy * math.cos(h)


def wake_foam_decay_s(vessel: MovingVessel) -> float:
    """e-folding age (s) of the turbulent wake's foam: the hull draft over the bubbles' rise
    speed, ``T / 0.2 m/s``, at least :data:`MIN_WAKE_FOAM_DECAY_S` (module docstring)."""
    return max(vessel.draft_m / BUBBLE_RISE_M_S, MIN_WAKE_FOAM_DECAY_S)


def transverse_wavelength(speed_m_s: float, gravity: float = GRAVITY) -> float:
    """Wavelength (m) of the transverse ship waves, ``2·pi·U²/g`` (the deep-water wave whose
    phase speed equals the ship's speed ``U`` in m/s)."""
    return 2.0 * math.pi * speed_m_s**2 / gravity


def wake_length(vessel: MovingVessel, gravity: float = GRAVITY) -> float:
    """Distance behind midships (m) over which the wave field is computed: the larger of
    :data:`WAKE_SHIP_LENGTHS` ship lengths and :data:`WAKE_TRANSVERSE_WAVELENGTHS` transverse
    wavelengths, at most :data:`MAX_WAKE_LENGTH_M`."""
    lam0 = transverse_wavelength(vessel.speed_m_s, gravity)
    wanted = max(WAKE_SHIP_LENGTHS * vessel.length_m, WAKE_TRANSVERSE_WAVELENGTHS * lam0)
    return min(wanted, MAX_WAKE_LENGTH_M)


def _shape_transform(k: np.ndarray, half_length: float, power: int) -> np.ndarray:
    """``∫ (1 - s^power)·exp(-i·k·a·s)·a ds`` over ``s in [-1, 1]`` (``a = half_length``), the
    Fourier transform of one factor of the hull shape (real: the shape is even)."""
    s = _GAUSS_NODES
    shape = 1.0 - s**power
    return half_length * (np.cos(np.outer(k, s) * half_length) @ (_GAUSS_WEIGHTS * shape))


class ShipWaves:
    """The steady wave field of one :class:`MovingVessel` on a grid in its own frame.

    ``height`` and ``slope`` sample it (bilinearly) at world points; zero outside the grid,
    ahead of the bow beyond one transverse wavelength, and beyond :func:`wake_length`.
    """

    def __init__(self, vessel: MovingVessel, gravity: float = GRAVITY) -> None:
        self.vessel = vessel
        self.gravity = gravity
        self.moving = vessel.speed_m_s > 0.0
        if not self.moving:
            return
        u = vessel.speed_m_s
        self.wavelength_m = transverse_wavelength(u, gravity)
        self.length_behind_m = wake_length(vessel, gravity)
        # Grid: behind, 1.5 wake lengths (the last half only absorbs what the damping leaves);
        # ahead, half the ship plus two transverse wavelengths; across, the wedge of that
        # length plus the beam.
        self.ahead_m = 0.5 * vessel.length_m + 2.0 * self.wavelength_m
        behind = 1.5 * self.length_behind_m
        half_width = math.tan(KELVIN_HALF_ANGLE_RAD) * behind + vessel.beam_m + self.wavelength_m
        extent_x = behind + self.ahead_m
        extent_y = 2.0 * half_width
        spacing = min(
            self.wavelength_m / GRID_POINTS_PER_WAVELENGTH, vessel.length_m / GRID_POINTS_PER_LENGTH
        )
        spacing = max(spacing, max(extent_x, extent_y) / MAX_GRID_POINTS)
        nx = sfft.next_fast_len(math.ceil(extent_x / spacing), real=True)
        ny = sfft.next_fast_len(math.ceil(extent_y / spacing), real=True)
        self.spacing_m = spacing
        self.origin = (self.ahead_m - nx * spacing, -0.5 * ny * spacing)  # (xi, eta) of [0, 0]
        self.shape = (ny, nx)
        self._height, self._slope = self._solve(nx, ny, spacing)

    def _solve(self, nx: int, ny: int, h: float) -> tuple[np.ndarray, np.ndarray]:
        v, g = self.vessel, self.gravity
        u = v.speed_m_s
        kx = 2.0 * math.pi * np.fft.fftfreq(nx, d=h)
        ky = 2.0 * math.pi * np.fft.fftfreq(ny, d=h)
        mu = WRAP_DECAY * u / (2.0 * nx * h)  # amplitude ~ exp(-2·mu·|xi|/U)
        d_hat = v.draft_m * np.outer(
            _shape_transform(ky, 0.5 * v.beam_m, 2), _shape_transform(kx, 0.5 * v.length_m, 4)
        )
        k = np.hypot(kx[None, :], ky[:, None])
        # The displacement is spread evenly over the draft, each layer at depth z radiating with
        # exp(-k·z) (Michell 1898): factor (1 - exp(-k·T))/(k·T).
        kt = k * v.draft_m
        d_hat *= np.where(kt > 1e-9, -np.expm1(-kt) / np.maximum(kt, 1e-9), 1.0)
        w = u * kx[None, :] + 1j * mu
        zeta_hat = -d_hat * w * w / (g * k - w * w)
        # Samples sit at xi0 + j·h: shift the phase to the grid origin; 1/h² turns the
        # continuous transform into grid values.
        phase = np.exp(1j * (kx[None, :] * self.origin[0] + ky[:, None] * self.origin[1]))
        spectrum = zeta_hat * phase / (h * h)
        # Height and both slopes in one single-precision transform of the three spectra: the
        # field's own accuracy (linear theory, grid interpolation) is far coarser than float32,
        # and at 2048² this is 6x faster than three double-precision transforms (a scene with
        # three moving vessels spent 5.7 s here).
        stacked = np.stack([spectrum, 1j * kx[None, :] * spectrum, 1j * ky[:, None] * spectrum])
        height, sx, sy = sfft.ifft2(stacked.astype(np.complex64), workers=-1).real
        window = self._window(nx, ny, h)
        slope = np.hypot(sx, sy) * window
        return (height * window).astype(np.float32), slope.astype(np.float32)

    def _window(self, nx: int, ny: int, h: float) -> np.ndarray:
        """1 inside the wake region, smooth to 0 ahead of the bow (beyond one transverse
        wavelength) and over the last fifth of the wake length."""
        xi = self.origin[0] + np.arange(nx) * h
        bow = 0.5 * self.vessel.length_m
        ahead = _smoothstep((bow + self.wavelength_m - xi) / self.wavelength_m)
        taper = 0.2 * self.length_behind_m
        behind = _smoothstep((xi + self.length_behind_m) / taper)
        return np.broadcast_to((ahead * behind)[None, :], (ny, nx))

    def _sample(self, grid: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        xi, eta = self.vessel.to_vessel_frame(x, y)
        u = (xi - self.origin[0]) / self.spacing_m
        v = (eta - self.origin[1]) / self.spacing_m
        ny, nx = self.shape
        inside = (u >= 0.0) & (u <= nx - 1) & (v >= 0.0) & (v <= ny - 1)
        out = np.zeros(np.shape(u))
        if not np.any(inside):
            return out
        ui, vi = u[inside], v[inside]
        i0 = np.minimum(np.floor(ui).astype(np.int64), nx - 2)
        j0 = np.minimum(np.floor(vi).astype(np.int64), ny - 2)
        tu, tv = ui - i0, vi - j0
        top = grid[j0, i0] * (1.0 - tu) + grid[j0, i0 + 1] * tu
        bottom = grid[j0 + 1, i0] * (1.0 - tu) + grid[j0 + 1, i0 + 1] * tu
        out[inside] = top * (1.0 - tv) + bottom * tv
        return out

    def height(
        self, x: np.ndarray, y: np.ndarray, spacing_m: np.ndarray | float | None = None
    ) -> np.ndarray:
        """Wave elevation (m) of this vessel's waves at world points (x, y) (m).

        With a mesh vertex spacing ``spacing_m`` (m) the field is weighted by
        :func:`~seahaze.ocean.base.lowpass_weight` of the transverse wavelength, so a mesh too
        coarse to carry the waves gets none instead of aliases.
        """
        if not self.moving:
            return np.zeros(np.broadcast(np.asarray(x), np.asarray(y)).shape)
        out = self._sample(self._height, *np.broadcast_arrays(x, y))
        if spacing_m is not None:
            out = out * lowpass_weight(self.wavelength_m, spacing_m)
        return out

    def slope(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Wave slope magnitude ``|grad zeta|`` at world points (x, y) (m)."""
        if not self.moving:
            return np.zeros(np.broadcast(np.asarray(x), np.asarray(y)).shape)
        return self._sample(self._slope, *np.broadcast_arrays(x, y))

    def breaking_foam(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Foam fraction (0–1) of breaking ship waves: a smoothstep of the slope from
        ``0.7·BREAKING_SLOPE`` to :data:`BREAKING_SLOPE`."""
        s = self.slope(x, y)
        return _smoothstep((s - 0.7 * BREAKING_SLOPE) / (0.3 * BREAKING_SLOPE))

    def turbulent_foam(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Foam fraction (0–1) of the turbulent wake behind the stern (module docstring)."""
        x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
        v = self.vessel
        if not self.moving:
            return np.zeros(x.shape)
        xi, eta = v.to_vessel_frame(x, y)
        s = -xi - 0.5 * v.length_m  # distance behind the stern
        half_width = 0.5 * v.beam_m * (1.0 + np.maximum(s, 0.0) / v.beam_m) ** 0.2
        across = np.clip(1.0 - (eta / half_width) ** 2, 0.0, 1.0) ** 2
        age = np.maximum(s, 0.0) / v.speed_m_s
        # Ramp in over a tenth of the beam at the stern so the band starts softly.
        start = _smoothstep(s / (0.1 * v.beam_m))
        return start * across * np.exp(-age / wake_foam_decay_s(v))

    def foam(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Foam fraction (0–1): turbulent wake and breaking waves, overlapping as independent
        coverages (``1 - (1 - a)(1 - b)``)."""
        a = self.turbulent_foam(x, y)
        if not self.moving:
            return a
        return 1.0 - (1.0 - a) * (1.0 - self.breaking_foam(x, y))

    @functools.cached_property
    def _breaking_box(self) -> tuple[float, float, float, float] | None:
        """``(xi_min, xi_max, eta_min, eta_max)`` (m, vessel frame) of the grid cells whose
        slope can make breaking foam, or None if none can."""
        steep = self._slope > 0.7 * BREAKING_SLOPE
        if not np.any(steep):
            return None
        rows, cols = np.nonzero(steep)
        h = self.spacing_m
        xi0, eta0 = self.origin
        return (
            xi0 + (cols.min() - 1) * h,
            xi0 + (cols.max() + 1) * h,
            eta0 + (rows.min() - 1) * h,
            eta0 + (rows.max() + 1) * h,
        )

    def foam_region(self, x: np.ndarray, y: np.ndarray, margin_m: np.ndarray | float) -> np.ndarray:
        """True where a point (x, y) (m) lies within ``margin_m`` of a region that can hold this
        vessel's foam: the turbulent wake until its foam is below :data:`FOAM_CUTOFF`, and the
        box of the grid cells steep enough to break."""
        if not self.moving:
            return np.zeros(np.broadcast(np.asarray(x), np.asarray(y)).shape, dtype=bool)
        v = self.vessel
        xi, eta = v.to_vessel_frame(x, y)
        stern = -0.5 * v.length_m
        behind = v.speed_m_s * wake_foam_decay_s(v) * math.log(1.0 / FOAM_CUTOFF)
        half_width = 0.5 * v.beam_m * (1.0 + behind / v.beam_m) ** 0.2
        inside = (
            (xi <= stern + margin_m)
            & (xi >= stern - behind - margin_m)
            & (np.abs(eta) <= half_width + margin_m)
        )
        box = self._breaking_box
        if box is not None:
            inside |= (
                (xi >= box[0] - margin_m)
                & (xi <= box[1] + margin_m)
                & (eta >= box[2] - margin_m)
                & (eta <= box[3] + margin_m)
            )
        return inside

    @property
    def foam_feature_m(self) -> float:
        """Smallest foam feature (m): a quarter of the smaller of the beam (turbulent wake) and
        the transverse wavelength (breaking crests); inf at rest."""
        if not self.moving:
            return math.inf
        return 0.25 * min(self.vessel.beam_m, self.wavelength_m)

    def foam_averaged(
        self,
        x: np.ndarray,
        y: np.ndarray,
        azimuth_rad: np.ndarray,
        radial_m: np.ndarray,
        tangential_m: np.ndarray,
    ) -> np.ndarray:
        """Mean foam fraction over cells centred on world points (x, y) (m), 1-D arrays:
        ``radial_m`` long along the azimuth ``azimuth_rad`` and ``tangential_m`` across it (a
        polar mesh vertex's footprint). Cells larger than :attr:`foam_feature_m` are averaged
        over a grid of up to :data:`MAX_FOAM_SAMPLES`² points, so a wake narrower than the cell
        is neither missed between vertices nor spread over the whole cell at full strength."""
        out = np.zeros(np.shape(x))
        if not self.moving:
            return out
        cell = np.maximum(radial_m, tangential_m)
        index = np.nonzero(self.foam_region(x, y, cell))[0]
        n = np.clip(np.ceil(cell[index] / self.foam_feature_m), 1, MAX_FOAM_SAMPLES).astype(int)
        for count in np.unique(n):
            pick = index[n == count]
            sx, sy = cell_samples(
                x[pick], y[pick], azimuth_rad[pick], radial_m[pick], tangential_m[pick], int(count)
            )
            out[pick] = self.foam(sx, sy).mean(axis=1)
        return out


def _smoothstep(t: np.ndarray) -> np.ndarray:
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


class WakeField:
    """The waves and foam of several moving vessels, to be added to the sea surface.

    Heights add (linear waves superpose); foam fractions combine as independent coverages.
    ``height``/``foam`` take world positions (m); a mesh builder evaluates them at its
    vertices (:func:`seahaze.ocean.mesh.build_sea_mesh_data`, argument ``wakes``).
    """

    def __init__(self, vessels: Sequence[MovingVessel], gravity: float = GRAVITY) -> None:
        self.vessels = list(vessels)
        self.waves = [_ship_waves(v, gravity) for v in self.vessels]

    def height(
        self, x: np.ndarray, y: np.ndarray, spacing_m: np.ndarray | float | None = None
    ) -> np.ndarray:
        """Sum of the vessels' wave elevations (m) at world points (x, y), band-limited for a
        mesh vertex spacing ``spacing_m`` (m) if given (:meth:`ShipWaves.height`)."""
        total = np.zeros(np.broadcast(np.asarray(x), np.asarray(y)).shape)
        for waves in self.waves:
            total += waves.height(x, y, spacing_m)
        return total

    def foam(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Foam fraction (0–1) of all wakes at world points (x, y)."""
        clear = np.ones(np.broadcast(np.asarray(x), np.asarray(y)).shape)
        for waves in self.waves:
            clear *= 1.0 - waves.foam(x, y)
        return 1.0 - clear

    def reach_m(self, center_xy: tuple[float, float]) -> float:
        """Distance (m) from ``center_xy`` within which a mesh should resolve the wakes: per
        moving vessel, its distance plus half its length and the longer of one foam e-folding
        length and two transverse wavelengths behind the stern; 0 if none moves."""
        reach = 0.0
        for waves in self.waves:
            if not waves.moving:
                continue
            v = waves.vessel
            behind = max(v.speed_m_s * wake_foam_decay_s(v), 2.0 * waves.wavelength_m)
            distance = math.hypot(v.x - center_xy[0], v.y - center_xy[1])
            reach = max(reach, distance + 0.5 * v.length_m + behind)
        return reach

    def foam_averaged(
        self,
        x: np.ndarray,
        y: np.ndarray,
        azimuth_rad: np.ndarray,
        radial_m: np.ndarray,
        tangential_m: np.ndarray,
    ) -> np.ndarray:
        """Foam fraction (0–1) of all wakes averaged over polar mesh cells (1-D arrays; see
        :meth:`ShipWaves.foam_averaged`); vessels combine as independent coverages."""
        clear = np.ones(np.shape(x))
        for waves in self.waves:
            clear *= 1.0 - waves.foam_averaged(x, y, azimuth_rad, radial_m, tangential_m)
        return 1.0 - clear


@functools.lru_cache(maxsize=4)  # a few vessels' grids (up to 32 MB each)
def _ship_waves(vessel: MovingVessel, gravity: float) -> ShipWaves:
    return ShipWaves(vessel, gravity)


def wake_height(vessels: Sequence[MovingVessel], x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Elevation (m) of the ship waves of ``vessels`` at world points (x, y) (m)."""
    return WakeField(vessels).height(x, y)


def wake_foam(vessels: Sequence[MovingVessel], x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Foam fraction (0–1) of the wakes of ``vessels`` at world points (x, y) (m)."""
    return WakeField(vessels).foam(x, y)
