"""Parameters and the common interface of seahaze's procedural ocean surfaces.

Coordinates: world metres, Z up, mean sea level at ``z = 0``. A surface maps an undisplaced
(Lagrangian) horizontal position ``(x0, y0)`` to the displaced point
``(x0 + dx, y0 + dy, dz)``. Azimuths are measured in the XY plane, 0 = +x, counter-clockwise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, Protocol, runtime_checkable

import numpy as np

from .spectra import (
    SPREADING_S_MAX,
    SeaSpectrum,
    SpectrumName,
    SpreadingName,
)

ModelName = Literal["flat", "gerstner", "fft"]

MIN_WIND_SPEED = 0.2
"""Below this wind speed (m/s at 10 m; Beaufort 0, "sea like a mirror") every model is flat."""


MIN_STRETCH = 0.05
"""Choppiness is clamped so that both principal stretches of the horizontal map
``x0 -> x0 + (dx, dy)`` stay at least this large, hence the Jacobian stays > 0."""


class ChoppinessClampedWarning(UserWarning):
    """The requested horizontal choppiness would fold the surface and was reduced."""


@dataclass(frozen=True)
class OceanParams:
    """Sea-state and generator parameters (all SI).

    Attributes:
        model: ``"flat"``, ``"gerstner"`` (sum of trochoidal waves) or ``"fft"`` (Tessendorf).
        spectrum: ``"jonswap"``, ``"pierson_moskowitz"`` or ``"phillips"``.
        wind_speed: wind speed at 10 m (m/s).
        fetch_km: fetch (km), JONSWAP only.
        direction_deg: direction the waves travel toward (deg), azimuth in the XY plane,
            0 = +x, counter-clockwise positive.
        choppiness: horizontal displacement scale lambda (dimensionless; Tessendorf 2001,
            eq. 29; for Gerstner waves the steepness ``Q`` of every component). Reduced, with a
            :class:`ChoppinessClampedWarning`, if the surface would fold.
        gamma: JONSWAP peak enhancement; ``None`` (default): from the sea state
            (:func:`seahaze.ocean.spectra.jonswap_gamma`, 1 for a fully developed sea).
        seed: seed of the ``numpy.random.Generator`` that draws amplitudes and phases.
        time_s: time (s); every component advances its phase by ``omega(k)·t``.
        spreading: ``"cos2s"`` (Mitsuyasu/Goda frequency-dependent exponent) or ``"cos2"``.
        spreading_s_max: peak cos-2s exponent (10 for wind waves, Goda 2010).
        patch_size_m: FFT: side of the largest periodic patch (m); ``None`` = 8 peak wavelengths.
        fft_resolution: FFT: grid points per side of every patch (power of two).
        fft_cascades: FFT: number of patches of incommensurate sizes (1–4); ``None`` = as few
            as give a finest grid spacing <= ``fft_min_wavelength_m/2``.
        fft_min_wavelength_m: FFT: shortest wavelength the patches carry (m); with
            ``fft_cascades`` ``None`` patches are added until the finest grid resolves it.
            Shorter waves belong to the BSDF roughness.
        gerstner_frequencies: Gerstner: number of equal-energy frequency bins.
        gerstner_directions: Gerstner: components per frequency bin (equal-energy directions).
        gerstner_max_frequency_ratio: Gerstner: highest frequency sampled, in units of omega_p.
    """

    model: ModelName = "fft"
    spectrum: SpectrumName = "jonswap"
    wind_speed: float = 6.0
    fetch_km: float = 100.0
    direction_deg: float = 0.0
    choppiness: float = 0.8
    gamma: float | None = None
    seed: int = 0
    time_s: float = 0.0
    spreading: SpreadingName = "cos2s"
    spreading_s_max: float = SPREADING_S_MAX
    patch_size_m: float | None = None
    fft_resolution: int = 256
    fft_cascades: int | None = None
    fft_min_wavelength_m: float = 0.5
    gerstner_frequencies: int = 16
    gerstner_directions: int = 4
    gerstner_max_frequency_ratio: float = 3.0

    def __post_init__(self) -> None:
        if self.model not in ("flat", "gerstner", "fft"):
            raise ValueError(f"unknown ocean model {self.model!r}")
        if self.spectrum not in ("jonswap", "pierson_moskowitz", "phillips"):
            raise ValueError(f"unknown spectrum {self.spectrum!r}")
        if self.spreading not in ("cos2s", "cos2"):
            raise ValueError(f"unknown spreading {self.spreading!r}")
        if self.wind_speed < 0.0 or self.fetch_km <= 0.0 or self.choppiness < 0.0:
            raise ValueError("wind_speed and choppiness must be >= 0 and fetch_km > 0")
        n = self.fft_resolution
        if n < 16 or n & (n - 1):
            raise ValueError("fft_resolution must be a power of two >= 16")
        if self.fft_cascades is not None and not 1 <= self.fft_cascades <= 4:
            raise ValueError("fft_cascades must be None or in 1..4")
        if self.fft_min_wavelength_m <= 0.0:
            raise ValueError("fft_min_wavelength_m must be > 0")

    @property
    def direction_rad(self) -> float:
        """Mean wave direction (rad)."""
        return math.radians(self.direction_deg)

    def sea_spectrum(self) -> SeaSpectrum:
        """The directional spectrum these parameters describe."""
        return SeaSpectrum(
            name=self.spectrum,
            wind_speed=self.wind_speed,
            fetch_km=self.fetch_km,
            gamma=self.gamma,
            mean_direction=self.direction_rad,
            spreading=self.spreading,
            s_max=self.spreading_s_max,
        )

    @property
    def is_calm(self) -> bool:
        """True when the sea is flat (model ``"flat"`` or wind below :data:`MIN_WIND_SPEED`)."""
        return self.model == "flat" or self.wind_speed < MIN_WIND_SPEED


@runtime_checkable
class OceanSurface(Protocol):
    """A displaced sea surface, vectorised over arrays of horizontal positions (m)."""

    @property
    def peak_wavelength_m(self) -> float:
        """Wavelength of the spectral peak (m); ``inf`` for a flat sea."""
        ...

    @property
    def significant_wave_height_m(self) -> float:
        """Expected Hs = 4·sqrt(m0) of the represented band (m)."""
        ...

    @property
    def mean_square_slope(self) -> float:
        """Mean square slope ``<(dz/dx)² + (dz/dy)²>`` resolved by the geometry."""
        ...

    def displacement(
        self, x: np.ndarray, y: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Displacement ``(dx, dy, dz)`` (m) of the surface point with rest position (x, y)."""
        ...

    def displacement_filtered(
        self, x: np.ndarray, y: np.ndarray, spacing_m: np.ndarray | float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Displacement band-limited for a mesh with local vertex spacing ``spacing_m`` (m):
        waves longer than about 4 spacings are kept, shorter than 2 spacings removed."""
        ...

    def height(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Elevation (m) of the surface above the world horizontal position (x, y)."""
        ...

    def normal(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Unit normals ``(..., 3)`` at the displaced points of rest positions (x, y)."""
        ...


def invert_horizontal_displacement(
    surface: OceanSurface, x: np.ndarray, y: np.ndarray, iterations: int = 4
) -> tuple[np.ndarray, np.ndarray]:
    """Rest position ``(x0, y0)`` whose displaced point lies above world position (x, y).

    Solves ``x0 + dx(x0, y0) = x`` by the fixed-point iteration ``x0 ← x - dx(x0)`` starting at
    ``x0 = x``. The map is a contraction where ``lambda·|grad D| < 1``, which the choppiness
    clamp guarantees (Jacobian > 0); the error shrinks by about ``lambda·k·A`` per iteration
    (typically 0.1–0.5), so four iterations leave a residual well below 1 % of the horizontal
    displacement.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    x0, y0 = x.copy(), y.copy()
    for _ in range(iterations):
        dx, dy, _ = surface.displacement(x0, y0)
        x0 = x - dx
        y0 = y - dy
    return x0, y0


def height_at(
    surface: OceanSurface, x: np.ndarray, y: np.ndarray, iterations: int = 4
) -> np.ndarray:
    """Elevation above world position (x, y) of a surface with horizontal displacement, via
    :func:`invert_horizontal_displacement` (``iterations`` fixed-point steps)."""
    x0, y0 = invert_horizontal_displacement(surface, x, y, iterations)
    return surface.displacement(x0, y0)[2]


def smoothstep(t: np.ndarray) -> np.ndarray:
    """``3t² - 2t³`` of ``t`` clipped to [0, 1]: a ramp from 0 to 1 with zero slope at both ends."""
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def lowpass_weight(wavelength_m: np.ndarray, spacing_m: np.ndarray | float) -> np.ndarray:
    """Weight of a wave of wavelength ``wavelength_m`` on a mesh of vertex spacing
    ``spacing_m``: 1 at >= 4 spacings, 0 at <= 2 spacings (the sampling limit), smoothstep in
    ``log2(wavelength/spacing)`` between."""
    ratio = np.asarray(wavelength_m, dtype=float) / np.maximum(spacing_m, 1e-12)
    return smoothstep(np.log2(np.maximum(ratio, 1e-12)) - 1.0)


def cell_samples(
    x: np.ndarray,
    y: np.ndarray,
    azimuth_rad: np.ndarray,
    radial_m: np.ndarray,
    tangential_m: np.ndarray,
    count: int,
) -> tuple[np.ndarray, np.ndarray]:
    """``count × count`` stratified points ``(n, count²)`` in each of ``n`` cells centred on
    (x, y) (m): ``radial_m`` long along the azimuth ``azimuth_rad`` and ``tangential_m`` across it
    (a polar mesh vertex's footprint), for averaging a field over the cell."""
    offsets = (np.arange(count) + 0.5) / count - 0.5
    a, b = (o.ravel() for o in np.meshgrid(offsets, offsets))
    c, s = np.cos(azimuth_rad)[:, None], np.sin(azimuth_rad)[:, None]
    along = radial_m[:, None] * a[None, :]
    across = tangential_m[:, None] * b[None, :]
    return x[:, None] + along * c - across * s, y[:, None] + along * s + across * c


def unit_normals_from_tangents(
    dx_dx0: np.ndarray,
    dy_dx0: np.ndarray,
    dz_dx0: np.ndarray,
    dx_dy0: np.ndarray,
    dy_dy0: np.ndarray,
    dz_dy0: np.ndarray,
) -> np.ndarray:
    """Unit normal ``T_x0 × T_y0`` (shape ``(..., 3)``) of a surface from its two tangents
    ``T_x0 = dP/dx0`` and ``T_y0 = dP/dy0``; points up where the surface does not fold."""
    nx = dy_dx0 * dz_dy0 - dz_dx0 * dy_dy0
    ny = dz_dx0 * dx_dy0 - dx_dx0 * dz_dy0
    nz = dx_dx0 * dy_dy0 - dy_dx0 * dx_dy0
    n = np.stack([nx, ny, nz], axis=-1)
    return n / np.linalg.norm(n, axis=-1, keepdims=True)


class FlatSurface:
    """A calm, flat sea at ``z = 0``."""

    peak_wavelength_m: float = math.inf
    significant_wave_height_m: float = 0.0
    mean_square_slope: float = 0.0
    choppiness: float = 0.0

    def mean_square_slope_filtered(self, spacing_m: float) -> float:
        """No resolved slopes."""
        return 0.0

    def resolved_moments(self, spacing_m: float = 0.0) -> tuple[float, float]:
        """No resolved waves."""
        return 0.0, 0.0

    def jacobian(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """1: a flat sea never breaks."""
        return np.ones(np.broadcast(np.asarray(x), np.asarray(y)).shape)

    def displacement(
        self, x: np.ndarray, y: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Zero displacement."""
        z = np.zeros(np.broadcast(np.asarray(x), np.asarray(y)).shape)
        return z, z.copy(), z.copy()

    def displacement_filtered(
        self, x: np.ndarray, y: np.ndarray, spacing_m: np.ndarray | float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Zero displacement."""
        return self.displacement(x, y)

    def height(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Zero elevation."""
        return np.zeros(np.broadcast(np.asarray(x), np.asarray(y)).shape)

    def normal(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """``(0, 0, 1)`` everywhere."""
        shape = np.broadcast(np.asarray(x), np.asarray(y)).shape
        n = np.zeros((*shape, 3))
        n[..., 2] = 1.0
        return n
