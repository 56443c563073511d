"""Wind-sea wave spectra (directional spreading: :mod:`.spreading`; dispersion: :mod:`.dispersion`,
both re-exported here).

Conventions (SI throughout)
    * angular frequency ``omega`` in rad/s, wavenumber ``k`` in rad/m;
    * one-sided frequency spectra ``S(omega)`` in m²·s/rad, so that the elevation variance is
      ``m0 = ∫ S(omega) d omega`` (m²) and the significant wave height ``Hs = 4·sqrt(m0)``;
    * directional spreading ``D(theta; omega)`` in 1/rad, normalised so that
      ``∫_{-pi}^{pi} D d theta = 1``; ``theta`` is the direction the waves travel *toward*,
      an azimuth in the XY plane (0 = +x, counter-clockwise positive, Z up);
    * the directional wavenumber spectrum ``Psi(kx, ky)`` in m⁴/rad² (m² of variance per unit
      area of the (kx, ky) plane), ``m0 = ∬ Psi dkx dky``.

References
    * Pierson, W. J. & Moskowitz, L. (1964). A proposed spectral form for fully developed wind
      seas based on the similarity theory of S. A. Kitaigorodskii. J. Geophys. Res. 69(24),
      5181–5190.
    * Hasselmann, K. et al. (1973). Measurements of wind-wave growth and swell decay during the
      Joint North Sea Wave Project (JONSWAP). Dtsch. Hydrogr. Z. A8(12).
    * Phillips, O. M. (1958). The equilibrium range in the spectrum of wind-generated waves.
      J. Fluid Mech. 4(4), 426–434.
    * Tessendorf, J. (2001). Simulating Ocean Water. SIGGRAPH course notes.
    * Stewart, R. H. (2008). Introduction to Physical Oceanography, ch. 16 (eqs. 16.28–16.35:
      ``U19.5 ≈ 1.026·U10``, ``omega_p = 0.877 g/U19.5``, JONSWAP fetch laws).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy import integrate

from .dispersion import GRAVITY, deep_water_group_velocity, deep_water_omega, deep_water_wavenumber
from .spreading import (
    SPREADING_S_MAX,
    cos2_spreading,
    cos2s_spreading,
    mitsuyasu_spreading_exponent,
)

PHILLIPS_CONSTANT = 8.1e-3
"""Phillips' equilibrium-range constant alpha (dimensionless), as fitted by Pierson & Moskowitz
(1964)."""

PM_BETA = 0.74
"""Pierson–Moskowitz low-frequency cut-off constant beta (dimensionless)."""

U19_5_OVER_U10 = 1.026
"""Ratio of the wind speed at 19.5 m to that at 10 m for a neutral boundary layer with drag
coefficient 1.3e-3 (Stewart 2008, eq. 16.29)."""

JONSWAP_SIGMA_LOW = 0.07
"""JONSWAP peak width for omega <= omega_p (Hasselmann et al. 1973)."""

JONSWAP_SIGMA_HIGH = 0.09
"""JONSWAP peak width for omega > omega_p (Hasselmann et al. 1973)."""

JONSWAP_GAMMA = 3.3
"""Mean JONSWAP peak-enhancement factor (Hasselmann et al. 1973); the default ``gamma`` is
the sea-state dependent :func:`jonswap_gamma` instead."""

JONSWAP_HS_GROWTH = 1.6e-3
"""JONSWAP fetch-limited growth of the significant wave height, ``g·Hs/U10² = 1.6e-3·chi^½``
(from the energy law ``g²·m0/U10⁴ = 1.6e-7·chi``, Hasselmann et al. 1973)."""

SpectrumName = Literal["jonswap", "pierson_moskowitz", "phillips"]
SpreadingName = Literal["cos2s", "cos2"]
ArrayLike = float | np.ndarray


# --------------------------------------------------------------------------------------------
# Wind


def wind_speed_19_5_from_10(u10: float) -> float:
    """Wind speed at 19.5 m (m/s) from the wind speed at 10 m (m/s): ``U19.5 ≈ 1.026·U10``
    (neutral log profile, drag coefficient 1.3e-3; Stewart 2008, eq. 16.29). Pierson & Moskowitz
    (1964) expressed their spectrum with the wind at 19.5 m (the anemometer height of the weather
    ships they used)."""
    return U19_5_OVER_U10 * float(u10)


# --------------------------------------------------------------------------------------------
# Frequency spectra


def pierson_moskowitz(
    omega: ArrayLike,
    u19_5: float,
    alpha: float = PHILLIPS_CONSTANT,
    beta: float = PM_BETA,
    gravity: float = GRAVITY,
) -> np.ndarray:
    """Pierson–Moskowitz spectrum of a fully developed wind sea, ``S(omega)`` in m²·s/rad.

    ``S = alpha·g²/omega⁵ · exp(-beta·(omega_0/omega)⁴)`` with ``omega_0 = g/U19.5``,
    ``alpha = 8.1e-3``, ``beta = 0.74`` (Pierson & Moskowitz 1964). ``u19_5`` is the wind speed
    (m/s) at **19.5 m** above the sea; convert from 10 m with :func:`wind_speed_19_5_from_10`.
    Peak at ``omega_p = (4·beta/5)^(1/4)·g/U19.5 = 0.877·g/U19.5``; ``Hs = 0.21·U19.5²/g``
    (Stewart 2008, eqs. 16.30, 16.33).
    """
    omega = np.asarray(omega, dtype=float)
    if u19_5 <= 0.0:
        return np.zeros_like(omega)
    omega_0 = gravity / u19_5
    return _power_law_with_cutoff(omega, alpha * gravity**2, beta * omega_0**4)


def pierson_moskowitz_peak_frequency(
    u19_5: float, beta: float = PM_BETA, gravity: float = GRAVITY
) -> float:
    """Peak angular frequency (rad/s) of :func:`pierson_moskowitz`:
    ``omega_p = (4·beta/5)^(1/4)·g/U19.5 ≈ 0.877·g/U19.5`` (Stewart 2008, eq. 16.30)."""
    return (0.8 * beta) ** 0.25 * gravity / u19_5


def phillips(
    omega: ArrayLike, u10: float, alpha: float = PHILLIPS_CONSTANT, gravity: float = GRAVITY
) -> np.ndarray:
    """Phillips spectrum in Tessendorf's form, written as a frequency spectrum (m²·s/rad).

    Phillips (1958) derived the saturated equilibrium range ``S = alpha·g²·omega⁻⁵``; Tessendorf
    (2001, eq. 23) cuts it at low wavenumbers with ``exp(-1/(k·L)²)``, ``L = U²/g`` the largest
    wave a wind ``U`` sustains. With ``k = omega²/g`` the cut-off is ``exp(-(g/(U·omega))⁴)``,
    so in frequency form ``S = alpha·g²/omega⁵ · exp(-(g/(U10·omega))⁴)``: the Pierson–Moskowitz
    shape with ``beta = 1`` and the wind at 10 m. Peak at ``omega_p = 0.946·g/U10``,
    ``Hs = 2·sqrt(alpha)·U10²/g ≈ 0.18·U10²/g``. Tessendorf's ``|k̂·ŵ|²`` directional factor is
    provided separately by :func:`cos2_spreading`; ``alpha`` fixes his free amplitude ``A``.
    """
    omega = np.asarray(omega, dtype=float)
    if u10 <= 0.0:
        return np.zeros_like(omega)
    return _power_law_with_cutoff(omega, alpha * gravity**2, (gravity / u10) ** 4)


def phillips_peak_frequency(u10: float, gravity: float = GRAVITY) -> float:
    """Peak angular frequency (rad/s) of :func:`phillips`: ``(4/5)^(1/4)·g/U10``."""
    return 0.8**0.25 * gravity / u10


def jonswap_dimensionless_fetch(u10: float, fetch_km: float, gravity: float = GRAVITY) -> float:
    """Dimensionless fetch ``chi = g·F/U10²`` (F in metres, U10 in m/s)."""
    return gravity * fetch_km * 1.0e3 / (u10 * u10)


def fully_developed_dimensionless_fetch(gravity: float = GRAVITY) -> float:
    """Dimensionless fetch at which the JONSWAP peak frequency reaches the Pierson–Moskowitz
    value (full development): ``22·chi^(-1/3) = 0.877·1.026⁻¹`` → ``chi ≈ 1.70e4``.

    Longer fetches do not lower the peak further (the sea is fully developed), so seahaze caps
    ``chi`` there for the peak frequency. (The energy reaches full development at a slightly
    longer fetch, ``chi ≈ 1.91e4``: :func:`jonswap_significant_wave_height`.)"""
    del gravity  # dimensionless
    pm_peak_u10 = (0.8 * PM_BETA) ** 0.25 / U19_5_OVER_U10  # omega_p·U10/g at full development
    return (22.0 / pm_peak_u10) ** 3


def _capped_fetch(u10: float, fetch_km: float, gravity: float) -> float:
    chi = jonswap_dimensionless_fetch(u10, fetch_km, gravity)
    return min(chi, fully_developed_dimensionless_fetch())


def jonswap_peak_frequency(u10: float, fetch_km: float, gravity: float = GRAVITY) -> float:
    """JONSWAP peak angular frequency (rad/s) from wind and fetch.

    ``omega_p = 22·(g²/(U10·F))^(1/3) = 2·pi·3.5·(g/U10)·chi^(-1/3)`` (Hasselmann et al. 1973:
    ``f_p·U10/g = 3.5·chi^(-0.33)``; Stewart 2008, eq. 16.35), with the dimensionless fetch
    ``chi = g·F/U10²`` capped at full development (:func:`fully_developed_dimensionless_fetch`),
    where it equals the Pierson–Moskowitz peak ``0.877·g/U19.5``. ``fetch_km`` in km, ``u10`` in
    m/s at 10 m.
    """
    chi = _capped_fetch(u10, fetch_km, gravity)
    return 22.0 * (gravity / u10) * chi ** (-1.0 / 3.0)


def jonswap_alpha_fit(u10: float, fetch_km: float, gravity: float = GRAVITY) -> float:
    """JONSWAP's own fit of the equilibrium-range constant, ``alpha = 0.076·chi^(-0.22)``
    (dimensionless; Hasselmann et al. 1973), ``chi = g·F/U10²`` capped at full development.

    Not used to build spectra: with ``gamma = 3.3`` and the peak law it gives 20–30 % more
    ``Hs`` than JONSWAP's energy growth law, and 1.29× the fully developed Pierson–Moskowitz
    ``Hs`` at the cap (see :func:`jonswap_alpha`). Kept as a reference value."""
    return 0.076 * _capped_fetch(u10, fetch_km, gravity) ** (-0.22)


def jonswap_significant_wave_height(u10: float, fetch_km: float, gravity: float = GRAVITY) -> float:
    """Fetch-limited significant wave height (m), capped at the fully developed sea.

    JONSWAP energy growth law ``g²·m0/U10⁴ = 1.6e-7·chi`` (Hasselmann et al. 1973), i.e.
    ``g·Hs/U10² = 1.6e-3·chi^(1/2)`` (also U.S. Army CERC, *Shore Protection Manual*, 1984,
    deep-water fetch-limited growth), ``chi = g·F/U10²`` (F in m, U10 in m/s at 10 m). A wind sea
    cannot exceed full development, so ``Hs`` is capped at the Pierson–Moskowitz value
    ``0.21·U19.5²/g`` (reached at ``chi ≈ 1.91e4``).
    """
    if u10 <= 0.0 or fetch_km <= 0.0:
        return 0.0
    chi = jonswap_dimensionless_fetch(u10, fetch_km, gravity)
    growth = JONSWAP_HS_GROWTH * math.sqrt(chi) * u10 * u10 / gravity
    return min(growth, pierson_moskowitz_significant_wave_height(u10, gravity))


def pierson_moskowitz_significant_wave_height(u10: float, gravity: float = GRAVITY) -> float:
    """``Hs = 4·sqrt(m0)`` (m) of :func:`pierson_moskowitz` for a wind ``u10`` (m/s at 10 m):
    ``m0 = alpha·g²/(4·beta·omega_0⁴)`` in closed form, i.e. ``Hs ≈ 0.21·U19.5²/g``
    (Stewart 2008, eqs. 16.32–16.33)."""
    u19_5 = wind_speed_19_5_from_10(u10)
    if u19_5 <= 0.0:
        return 0.0
    omega_0 = gravity / u19_5
    m0 = PHILLIPS_CONSTANT * gravity**2 / (4.0 * PM_BETA * omega_0**4)
    return 4.0 * math.sqrt(m0)


def jonswap_gamma_for_sea_state(hs_m: float, tp_s: float) -> float:
    """Peak enhancement ``gamma`` of a JONSWAP sea of given ``Hs`` (m) and ``Tp`` (s):
    ``5`` for ``Tp/sqrt(Hs) <= 3.6``, ``exp(5.75 - 1.15·Tp/sqrt(Hs))`` up to 5, ``1`` (the
    Pierson–Moskowitz shape) above (DNV, *Environmental conditions and environmental loads*,
    DNV-RP-C205, 2010, §3.5.5.5; ``Tp`` in s, ``Hs`` in m).

    With the JONSWAP growth laws ``Tp/sqrt(Hs) = 2.28·chi^(1/12)`` (s/m^½), so ``gamma`` falls
    from 5 at short fetch (``chi < 300``) through 3 (``chi ≈ 1e3``) to 1 at full development
    (``Tp/sqrt(Hs) = 4.99`` for Pierson–Moskowitz): a fully developed sea has the
    Pierson–Moskowitz shape, as it should.
    """
    if hs_m <= 0.0:
        return 1.0
    ratio = tp_s / math.sqrt(hs_m)
    if ratio <= 3.6:
        return 5.0
    if ratio >= 5.0:
        return 1.0
    return math.exp(5.75 - 1.15 * ratio)


@functools.lru_cache(maxsize=256)
def jonswap_shape_integral(
    gamma: float,
    sigma_low: float = JONSWAP_SIGMA_LOW,
    sigma_high: float = JONSWAP_SIGMA_HIGH,
) -> float:
    """Dimensionless ``I(gamma) = ∫ u⁻⁵·exp(-5/4·u⁻⁴)·gamma^r(u) du`` (``u = omega/omega_p``),
    so that :func:`jonswap_shape` integrates to ``m0 = alpha·g²·I(gamma)/omega_p⁴``.
    ``I(1) = 1/5`` exactly; DNV-RP-C205's normalising factor is ``A_gamma ≈ 1/(5·I(gamma))``
    ``≈ 1 - 0.287·ln(gamma)``."""

    def integrand(u: float) -> float:
        sigma = sigma_low if u <= 1.0 else sigma_high
        r = math.exp(-((u - 1.0) ** 2) / (2.0 * sigma * sigma))
        return u**-5 * math.exp(-1.25 * u**-4) * gamma**r

    value, _ = integrate.quad(
        integrand, 0.05, 60.0, points=[0.7, 0.9, 1.0, 1.1, 1.5, 3.0], limit=200, epsrel=1e-10
    )
    return float(value)


def jonswap_gamma(u10: float, fetch_km: float, gravity: float = GRAVITY) -> float:
    """Default JONSWAP peak enhancement for a wind ``u10`` (m/s at 10 m) and fetch (km):
    :func:`jonswap_gamma_for_sea_state` of the growth-law ``Hs`` and ``Tp``; exactly 1 once the
    peak has reached full development (there ``Tp/sqrt(Hs) = 4.9996``, DNV's limit of 5 up to
    the rounding of its coefficients), so that a fully developed sea is Pierson–Moskowitz."""
    if jonswap_dimensionless_fetch(u10, fetch_km, gravity) >= fully_developed_dimensionless_fetch():
        return 1.0
    hs = jonswap_significant_wave_height(u10, fetch_km, gravity)
    tp = 2.0 * math.pi / jonswap_peak_frequency(u10, fetch_km, gravity)
    return jonswap_gamma_for_sea_state(hs, tp)


def jonswap_alpha(
    u10: float, fetch_km: float, gamma: float | None = None, gravity: float = GRAVITY
) -> float:
    """Equilibrium-range constant ``alpha`` (dimensionless) that gives the JONSWAP spectrum of
    wind ``u10`` (m/s at 10 m) and fetch (km) the growth-law ``Hs``
    (:func:`jonswap_significant_wave_height`) at the growth-law peak
    (:func:`jonswap_peak_frequency`): ``alpha = (Hs/4)²·omega_p⁴/(g²·I(gamma))``.

    This is how a JONSWAP sea is specified by ``(Hs, Tp, gamma)`` in engineering practice
    (Goda 2010, eq. 2.12; DNV-RP-C205 §3.5.5). JONSWAP's separate fit ``0.076·chi^(-0.22)``
    (:func:`jonswap_alpha_fit`) is not consistent with its own energy law: combined with
    ``gamma = 3.3`` it overshoots ``Hs`` by 20–30 %, and beyond full development it gave
    1.29× the Pierson–Moskowitz ``Hs`` — more than a fully developed sea can hold. ``gamma``
    ``None`` uses :func:`jonswap_gamma`.
    """
    if gamma is None:
        gamma = jonswap_gamma(u10, fetch_km, gravity)
    hs = jonswap_significant_wave_height(u10, fetch_km, gravity)
    omega_p = jonswap_peak_frequency(u10, fetch_km, gravity)
    return (hs / 4.0) ** 2 * omega_p**4 / (gravity**2 * jonswap_shape_integral(float(gamma)))


def jonswap_shape(
    omega: ArrayLike,
    omega_p: float,
    alpha: float,
    gamma: float = JONSWAP_GAMMA,
    sigma_low: float = JONSWAP_SIGMA_LOW,
    sigma_high: float = JONSWAP_SIGMA_HIGH,
    gravity: float = GRAVITY,
) -> np.ndarray:
    """JONSWAP spectral form (m²·s/rad) for a given peak ``omega_p`` (rad/s) and ``alpha``.

    ``S = alpha·g²/omega⁵ · exp(-5/4·(omega_p/omega)⁴) · gamma^r``,
    ``r = exp(-(omega - omega_p)² / (2·sigma²·omega_p²))``, ``sigma = 0.07`` below the peak and
    ``0.09`` above it (Hasselmann et al. 1973). ``gamma = 1`` gives the Pierson–Moskowitz shape.
    """
    omega = np.asarray(omega, dtype=float)
    base = _power_law_with_cutoff(omega, alpha * gravity**2, 1.25 * omega_p**4)
    sigma = np.where(omega <= omega_p, sigma_low, sigma_high)
    r = np.exp(-((omega - omega_p) ** 2) / (2.0 * sigma**2 * omega_p**2))
    return base * gamma**r


def jonswap(
    omega: ArrayLike,
    u10: float,
    fetch_km: float,
    gamma: float | None = None,
    gravity: float = GRAVITY,
) -> np.ndarray:
    """JONSWAP spectrum of a fetch-limited wind sea, ``S(omega)`` in m²·s/rad.

    ``u10``: wind speed (m/s) at 10 m; ``fetch_km``: fetch (km). The sea state follows the
    JONSWAP growth laws of Hasselmann et al. (1973), both capped at full development: peak
    :func:`jonswap_peak_frequency`, ``Hs`` :func:`jonswap_significant_wave_height`; the shape is
    :func:`jonswap_shape` (``sigma`` 0.07/0.09) with ``gamma`` (``None``:
    :func:`jonswap_gamma`, 5 → 1 as the sea develops) and ``alpha`` from :func:`jonswap_alpha`,
    so that ``4·sqrt(∫ S d omega)`` is exactly the growth-law ``Hs``.
    """
    omega = np.asarray(omega, dtype=float)
    if u10 <= 0.0 or fetch_km <= 0.0:
        return np.zeros_like(omega)
    if gamma is None:
        gamma = jonswap_gamma(u10, fetch_km, gravity)
    return jonswap_shape(
        omega,
        jonswap_peak_frequency(u10, fetch_km, gravity),
        jonswap_alpha(u10, fetch_km, gamma, gravity),
        gamma,
        gravity=gravity,
    )


def _power_law_with_cutoff(omega: np.ndarray, scale: float, cutoff: float) -> np.ndarray:
    """``scale·omega⁻⁵·exp(-cutoff/omega⁴)``, 0 where ``omega <= 0``."""
    out = np.zeros_like(omega, dtype=float)
    positive = omega > 0.0
    w = omega[positive]
    out[positive] = scale / w**5 * np.exp(-cutoff / w**4)
    return out


# --------------------------------------------------------------------------------------------
# Moments


def spectral_moment(
    spectrum: Callable[[np.ndarray], np.ndarray],
    order: int = 0,
    omega_min: float = 0.0,
    omega_max: float = math.inf,
    omega_peak: float | None = None,
) -> float:
    """Spectral moment ``m_n = ∫ omega^n·S(omega) d omega`` over ``[omega_min, omega_max]``
    (units m²·(rad/s)^n). ``omega_peak`` (rad/s), if known, helps the adaptive quadrature."""

    def integrand(w: float) -> float:
        return float(w**order * spectrum(np.asarray([w]))[0])

    lo, hi = max(omega_min, 0.0), omega_max
    if omega_peak is not None and math.isinf(hi):
        hi = max(60.0 * omega_peak, lo * 2.0)
    points = None
    if omega_peak is not None and lo < omega_peak < hi:
        factors = (0.7, 0.9, 1.0, 1.1, 1.5, 3.0)
        points = [omega_peak * f for f in factors if lo < omega_peak * f < hi]
    value, _ = integrate.quad(integrand, lo, hi, points=points, limit=200, epsabs=0.0, epsrel=1e-8)
    return float(value)


def significant_wave_height(m0: float) -> float:
    """Spectral significant wave height ``Hs = Hm0 = 4·sqrt(m0)`` (m) from the elevation
    variance ``m0`` (m²)."""
    return 4.0 * math.sqrt(max(m0, 0.0))


# --------------------------------------------------------------------------------------------
# A complete directional sea spectrum


@dataclass(frozen=True)
class SeaSpectrum:
    """A directional wind-sea spectrum ``S(omega)·D(theta; omega)`` ready for sampling.

    Attributes:
        name: spectrum family.
        wind_speed: wind speed at 10 m (m/s).
        fetch_km: fetch (km), used by JONSWAP only.
        gamma: JONSWAP peak enhancement; ``None`` (default) uses the sea-state dependent
            :func:`jonswap_gamma` (DNV-RP-C205), which is 1 for a fully developed sea.
        mean_direction: direction the waves travel toward (rad; 0 = +x, counter-clockwise).
        spreading: ``"cos2s"`` (Mitsuyasu frequency-dependent exponent, peak value ``s_max``) or
            ``"cos2"`` (Tessendorf's cos²).
        s_max: peak cos-2s exponent.
        gravity: g (m/s²).
    """

    name: SpectrumName = "jonswap"
    wind_speed: float = 6.0
    fetch_km: float = 100.0
    gamma: float | None = None
    mean_direction: float = 0.0
    spreading: SpreadingName = "cos2s"
    s_max: float = SPREADING_S_MAX
    gravity: float = GRAVITY

    @property
    def peak_omega(self) -> float:
        """Peak angular frequency of ``S(omega)`` (rad/s)."""
        if self.name == "jonswap":
            return jonswap_peak_frequency(self.wind_speed, self.fetch_km, self.gravity)
        if self.name == "pierson_moskowitz":
            u19_5 = wind_speed_19_5_from_10(self.wind_speed)
            return pierson_moskowitz_peak_frequency(u19_5, gravity=self.gravity)
        if self.name == "phillips":
            return phillips_peak_frequency(self.wind_speed, self.gravity)
        raise ValueError(f"unknown spectrum {self.name!r}")

    @property
    def peak_period(self) -> float:
        """Peak period ``Tp = 2·pi/omega_p`` (s)."""
        return 2.0 * math.pi / self.peak_omega

    @property
    def peak_wavenumber(self) -> float:
        """Wavenumber of the spectral peak (rad/m)."""
        return float(deep_water_wavenumber(self.peak_omega, self.gravity))

    @property
    def peak_wavelength(self) -> float:
        """Wavelength of the spectral peak ``2·pi·g/omega_p²`` (m)."""
        return 2.0 * math.pi / self.peak_wavenumber

    def omega_spectrum(self, omega: ArrayLike) -> np.ndarray:
        """Frequency spectrum ``S(omega)`` (m²·s/rad)."""
        if self.name == "jonswap":
            return jonswap(omega, self.wind_speed, self.fetch_km, self.gamma, gravity=self.gravity)
        if self.name == "pierson_moskowitz":
            u19_5 = wind_speed_19_5_from_10(self.wind_speed)
            return pierson_moskowitz(omega, u19_5, gravity=self.gravity)
        if self.name == "phillips":
            return phillips(omega, self.wind_speed, gravity=self.gravity)
        raise ValueError(f"unknown spectrum {self.name!r}")

    def spreading_function(self, theta: ArrayLike, omega: ArrayLike) -> np.ndarray:
        """Directional spreading ``D(theta; omega)`` (1/rad)."""
        if self.spreading == "cos2":
            return cos2_spreading(theta, self.mean_direction) * np.ones_like(omega, dtype=float)
        if self.spreading == "cos2s":
            s = mitsuyasu_spreading_exponent(omega, self.peak_omega, self.s_max)
            return cos2s_spreading(theta, self.mean_direction, s)
        raise ValueError(f"unknown spreading {self.spreading!r}")

    def wavenumber_spectrum(self, kx: np.ndarray, ky: np.ndarray) -> np.ndarray:
        """Directional wavenumber spectrum ``Psi(kx, ky)`` (m⁴/rad²).

        ``Psi = S(omega(k))·(d omega/dk)·D(theta; omega)/k`` with deep-water dispersion; the
        ``1/k`` is the polar-area Jacobian. Zero at ``k = 0``.
        """
        kx = np.asarray(kx, dtype=float)
        ky = np.asarray(ky, dtype=float)
        k = np.hypot(kx, ky)
        out = np.zeros(np.broadcast(kx, ky).shape)
        positive = k > 0.0
        kp = k[positive]
        omega = deep_water_omega(kp, self.gravity)
        theta = np.arctan2(
            np.broadcast_to(ky, out.shape)[positive], np.broadcast_to(kx, out.shape)[positive]
        )
        s_omega = self.omega_spectrum(omega)
        out[positive] = (
            s_omega
            * deep_water_group_velocity(omega, self.gravity)
            * self.spreading_function(theta, omega)
            / kp
        )
        return out

    def variance(self, omega_min: float = 0.0, omega_max: float = math.inf) -> float:
        """Elevation variance ``m0`` (m²) of the band ``[omega_min, omega_max]`` (rad/s)."""
        return spectral_moment(self.omega_spectrum, 0, omega_min, omega_max, self.peak_omega)

    @property
    def significant_wave_height(self) -> float:
        """``Hs = 4·sqrt(m0)`` (m) of the whole spectrum."""
        return significant_wave_height(self.variance())
