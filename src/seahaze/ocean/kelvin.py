"""Kelvin ship waves: the steady wave field of a hull moving at constant speed in deep water,
solved on a grid in the vessel's frame (heights and slopes in metres, m/m).

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
zero over the last fifth of the wake length :func:`wake_length_m`.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from scipy import fft as sfft

from .base import smoothstep
from .spectra import GRAVITY

KELVIN_HALF_ANGLE_RAD = math.asin(1.0 / 3.0)
"""Half-angle of the Kelvin wedge, ``asin(1/3) = 19.47°`` (rad)."""

BREAKING_SLOPE = 0.44
"""Wave slope above which a crest breaks: ``a·k`` of the steepest Stokes wave
(``H/lambda = 0.142``, Michell 1893)."""

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

WRAP_DECAY = 3.0
"""The damping lowers a wave by ``exp(-WRAP_DECAY)`` over one period of the grid."""

_GAUSS_NODES, _GAUSS_WEIGHTS = np.polynomial.legendre.leggauss(96)


def transverse_wavelength(speed_m_s: float, gravity: float = GRAVITY) -> float:
    """Wavelength (m) of the transverse ship waves, ``2·pi·U²/g`` (the deep-water wave whose
    phase speed equals the ship's speed ``U`` in m/s)."""
    return 2.0 * math.pi * speed_m_s**2 / gravity


def wake_length_m(length_m: float, speed_m_s: float, gravity: float = GRAVITY) -> float:
    """Distance behind midships (m) over which the wave field of a hull ``length_m`` long at
    ``speed_m_s`` is computed: the larger of :data:`WAKE_SHIP_LENGTHS` ship lengths and
    :data:`WAKE_TRANSVERSE_WAVELENGTHS` transverse wavelengths, at most
    :data:`MAX_WAKE_LENGTH_M`."""
    lam0 = transverse_wavelength(speed_m_s, gravity)
    wanted = max(WAKE_SHIP_LENGTHS * length_m, WAKE_TRANSVERSE_WAVELENGTHS * lam0)
    return min(wanted, MAX_WAKE_LENGTH_M)


def hull_shape_transform(k: np.ndarray, half_length: float, power: int) -> np.ndarray:
    """``∫ (1 - s^power)·exp(-i·k·a·s)·a ds`` over ``s in [-1, 1]`` (``a = half_length``), the
    Fourier transform of one factor of the hull shape (real: the shape is even)."""
    s = _GAUSS_NODES
    shape = 1.0 - s**power
    return half_length * (np.cos(np.outer(k, s) * half_length) @ (_GAUSS_WEIGHTS * shape))


@dataclass(frozen=True)
class WaveGrid:
    """The solved wave field of one hull at one speed, in the vessel frame (read-only arrays).

    It depends on the hull and the speed only, not on where the vessel is or where it heads, so
    it is computed once (:func:`wave_grid`) and shared by every frame of a sequence and every
    scene that repeats the vessel.
    """

    wavelength_m: float
    length_behind_m: float
    ahead_m: float
    spacing_m: float
    origin: tuple[float, float]  # (xi, eta) of sample [0, 0] (m)
    height: np.ndarray  # (ny, nx) elevation (m), float32
    slope: np.ndarray  # (ny, nx) |grad zeta|, float32
    breaking_box: tuple[float, float, float, float] | None


@functools.lru_cache(maxsize=16)  # up to 25 MB per hull and speed
def wave_grid(
    speed_m_s: float, length_m: float, beam_m: float, draft_m: float, gravity: float
) -> WaveGrid:
    """The wave field of a hull (waterline length, beam, draft in m) at ``speed_m_s`` (> 0),
    solved (module docstring) on a grid sized for its wavelengths and wake length; cached."""
    u = speed_m_s
    wavelength = transverse_wavelength(u, gravity)
    behind_m = wake_length_m(length_m, u, gravity)
    # Grid: behind, 1.5 wake lengths (the last half only absorbs what the damping leaves);
    # ahead, half the ship plus two transverse wavelengths; across, the wedge of that
    # length plus the beam.
    ahead = 0.5 * length_m + 2.0 * wavelength
    behind = 1.5 * behind_m
    half_width = math.tan(KELVIN_HALF_ANGLE_RAD) * behind + beam_m + wavelength
    extent_x = behind + ahead
    extent_y = 2.0 * half_width
    h = min(wavelength / GRID_POINTS_PER_WAVELENGTH, length_m / GRID_POINTS_PER_LENGTH)
    h = max(h, max(extent_x, extent_y) / MAX_GRID_POINTS)
    nx = sfft.next_fast_len(math.ceil(extent_x / h), real=True)
    ny = sfft.next_fast_len(math.ceil(extent_y / h), real=True)
    origin = (ahead - nx * h, -0.5 * ny * h)
    height, slope = _solve_waves(u, length_m, beam_m, draft_m, gravity, nx, ny, h, origin)
    window = _wake_window(origin[0], nx, h, length_m, wavelength, behind_m)
    height = (height * window).astype(np.float32)
    slope = (slope * window).astype(np.float32)
    height.flags.writeable = False
    slope.flags.writeable = False
    return WaveGrid(
        wavelength, behind_m, ahead, h, origin, height, slope, _steep_box(slope, origin, h)
    )


def _solve_waves(
    u: float,
    length_m: float,
    beam_m: float,
    draft_m: float,
    g: float,
    nx: int,
    ny: int,
    h: float,
    origin: tuple[float, float],
) -> tuple[np.ndarray, np.ndarray]:
    """Height and slope magnitude of the steady ship waves on the (ny, nx) grid (unwindowed).

    The field is real, so its spectrum is Hermitian: only the half with ``k_x >= 0`` is built
    and transformed (``irfft2``), half the work of a full complex transform.
    """
    kx = 2.0 * math.pi * np.fft.rfftfreq(nx, d=h)
    ky = 2.0 * math.pi * np.fft.fftfreq(ny, d=h)
    mu = WRAP_DECAY * u / (2.0 * nx * h)  # amplitude ~ exp(-2·mu·|xi|/U)
    # Samples sit at xi0 + j·h: shift the phase to the grid origin; 1/h² turns the
    # continuous transform into grid values. Both factors separate in kx and ky, and are
    # computed in double precision; the 2-D products below in single precision (half the
    # time), as the transform is: the field's own accuracy is far coarser.
    row = hull_shape_transform(kx, 0.5 * length_m, 4) * np.exp(1j * kx * origin[0])
    col = hull_shape_transform(ky, 0.5 * beam_m, 2) * np.exp(1j * ky * origin[1])
    w2 = (u * kx + 1j * mu) ** 2
    k = np.hypot(kx[None, :], ky[:, None]).astype(np.float32)
    # The displacement is spread evenly over the draft, each layer at depth z radiating with
    # exp(-k·z) (Michell 1898): factor (1 - exp(-k·T))/(k·T).
    kt = k * np.float32(draft_m)
    depth = np.where(kt > 1e-9, -np.expm1(-kt) / np.maximum(kt, np.float32(1e-9)), 1.0)
    resonance = np.float32(g) * k - w2.astype(np.complex64)[None, :]
    top = ((-draft_m / (h * h)) * row * w2).astype(np.complex64)
    spectrum = col.astype(np.complex64)[:, None] * top[None, :] * depth
    spectrum /= resonance
    # Height and both slopes in one single-precision transform of the three spectra: the
    # field's own accuracy (linear theory, grid interpolation) is far coarser than float32.
    stacked = np.empty((3, ny, kx.size), dtype=np.complex64)
    stacked[0] = spectrum
    stacked[1] = spectrum * (1j * kx)[None, :]
    stacked[2] = spectrum * (1j * ky)[:, None]
    height, sx, sy = sfft.irfft2(stacked, s=(ny, nx), workers=-1)
    return height, np.hypot(sx, sy)


def _wake_window(
    xi0: float, nx: int, h: float, length_m: float, wavelength: float, behind_m: float
) -> np.ndarray:
    """1 inside the wake region, smooth to 0 ahead of the bow (beyond one transverse
    wavelength) and over the last fifth of the wake length; a row over xi, broadcast down."""
    xi = xi0 + np.arange(nx) * h
    ahead = smoothstep((0.5 * length_m + wavelength - xi) / wavelength)
    behind = smoothstep((xi + behind_m) / (0.2 * behind_m))
    return (ahead * behind)[None, :]


def _steep_box(
    slope: np.ndarray, origin: tuple[float, float], h: float
) -> tuple[float, float, float, float] | None:
    """``(xi_min, xi_max, eta_min, eta_max)`` (m, vessel frame) of the grid cells whose slope
    can make breaking foam, or None if none can."""
    steep = slope > 0.7 * BREAKING_SLOPE
    if not np.any(steep):
        return None
    rows, cols = np.nonzero(steep)
    xi0, eta0 = origin
    return (
        xi0 + (cols.min() - 1) * h,
        xi0 + (cols.max() + 1) * h,
        eta0 + (rows.min() - 1) * h,
        eta0 + (rows.max() + 1) * h,
    )
