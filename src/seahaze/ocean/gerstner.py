"""Gerstner (trochoidal) wave sum with components sampled from a directional spectrum.

Model (Gerstner 1802; Fournier & Reeves 1986; Tessendorf 2001, §3.1)
    For rest position ``x0`` and components ``i`` with wavenumber vector ``k_i``
    (``|k_i| = omega_i²/g``), amplitude ``A_i``, phase ``phi_i = k_i·x0 - omega_i·t + phi0_i``:

        x = x0 - Σ Q_i·A_i·k̂_i·sin(phi_i),      z = Σ A_i·cos(phi_i).

    All components share the steepness ``Q_i = lambda`` (the ``choppiness``), which makes this
    exactly the FFT model's choppy displacement restricted to a few modes.

Sampling the spectrum
    The band ``[omega_lo, min(r·omega_p, omega_min_wl)]`` (``omega_lo`` where the spectrum's
    cumulative energy reaches 0.1 %, ``r = gerstner_max_frequency_ratio``, ``omega_min_wl`` the
    frequency of the shortest wave the generators carry, ``fft_min_wavelength_m``; it only acts
    below about 2.4 m/s, where ``lambda_p/9`` is shorter than 0.5 m) is split into
    ``gerstner_frequencies`` bins of equal energy; in each bin one frequency is drawn by inverse
    CDF at a jittered quantile. For each frequency ``gerstner_directions`` directions are
    drawn the same way from ``D(theta; omega)``. Every component therefore carries the same
    energy ``m0_band/M`` (``M`` components), i.e. ``A_i = sqrt(2·m0_band/M)`` — a stratified
    Monte-Carlo estimate of ``A² /2 = S(omega, theta)·d omega·d theta``.

Loop limit
    The horizontal Jacobian is ``det(I - Σ w_i·cos(phi_i)·k̂_i k̂_iᵀ)`` with
    ``w_i = Q_i·k_i·A_i``. The matrix sum has norm at most ``Σ w_i``, so ``Σ Q_i·k_i·A_i <= 1``
    guarantees ``J >= 0`` (no loops), with equality only if every crest coincides along one
    direction. ``lambda`` is clamped to ``(1 - MIN_STRETCH)/Σ k_i·A_i`` (every principal stretch
    stays >= ``MIN_STRETCH`` = 0.05, so ``J > 0`` strictly) with a
    :class:`ChoppinessClampedWarning`.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from .base import (
    MIN_STRETCH,
    ChoppinessClampedWarning,
    OceanParams,
    height_at,
    lowpass_weight,
    unit_normals_from_tangents,
)
from .spectra import SeaSpectrum, deep_water_omega, deep_water_wavenumber

CHUNK = 32768
"""Points evaluated per matrix product (bounds memory at about 16 MB per temporary)."""

LOW_ENERGY_QUANTILE = 1e-3
"""Fraction of the spectrum's energy left out below the lowest sampled frequency."""


class GerstnerOcean:
    """A sum of Gerstner waves (vectorised; see the module docstring)."""

    def __init__(
        self,
        omega: np.ndarray,
        direction: np.ndarray,
        amplitude: np.ndarray,
        phase: np.ndarray,
        choppiness: float,
        time_s: float = 0.0,
        peak_wavelength_m: float = math.nan,
        gravity: float = 9.81,
        warn: bool = True,
    ) -> None:
        self.omega = np.asarray(omega, dtype=float)
        self.direction = np.asarray(direction, dtype=float)
        self.amplitude = np.asarray(amplitude, dtype=float)
        self.phase = np.asarray(phase, dtype=float)
        self.gravity = float(gravity)
        self.k = deep_water_wavenumber(self.omega, gravity)
        self.time_s = float(time_s)
        self.peak_wavelength_m = float(peak_wavelength_m)
        self.requested_choppiness = float(choppiness)
        self.choppiness_limit = (1.0 - MIN_STRETCH) / float(np.sum(self.k * self.amplitude))
        self.choppiness = min(self.requested_choppiness, self.choppiness_limit)
        if self.choppiness < self.requested_choppiness and warn:
            warnings.warn(
                f"Gerstner choppiness {self.requested_choppiness:.3g} exceeds the loop limit "
                f"sum(Q·k·A) <= 1 - {MIN_STRETCH}; clamped to {self.choppiness:.3g}",
                ChoppinessClampedWarning,
                stacklevel=2,
            )
        self._kx = self.k * np.cos(self.direction)
        self._ky = self.k * np.sin(self.direction)
        self._phase_t = self.phase - self.omega * self.time_s

    @classmethod
    def from_params(cls, params: OceanParams) -> GerstnerOcean:
        """Sample components from ``params``' spectrum (deterministic in ``params.seed``)."""
        spectrum = params.sea_spectrum()
        rng = np.random.default_rng(params.seed)
        omega, direction, amplitude = sample_components(
            spectrum,
            params.gerstner_frequencies,
            params.gerstner_directions,
            params.gerstner_max_frequency_ratio,
            rng,
            max_omega=float(deep_water_omega(2.0 * math.pi / params.fft_min_wavelength_m)),
        )
        phase = rng.uniform(0.0, 2.0 * math.pi, omega.shape)
        return cls(
            omega,
            direction,
            amplitude,
            phase,
            params.choppiness,
            params.time_s,
            spectrum.peak_wavelength,
            spectrum.gravity,
        )

    def at_time(self, time_s: float) -> GerstnerOcean:
        """The same components at another time (no new random draws; same choppiness)."""
        return GerstnerOcean(
            self.omega,
            self.direction,
            self.amplitude,
            self.phase,
            self.choppiness,
            time_s,
            self.peak_wavelength_m,
            self.gravity,
            warn=False,
        )

    # ----------------------------------------------------------------------------- statistics

    @property
    def significant_wave_height_m(self) -> float:
        """``4·sqrt(Σ A_i²/2)`` (m)."""
        return 4.0 * math.sqrt(float(np.sum(self.amplitude**2) / 2.0))

    @property
    def mean_square_slope(self) -> float:
        """``Σ (k_i·A_i)²/2`` (dimensionless), the spatial mean of ``|grad z|²`` for
        ``lambda = 0``."""
        return float(np.sum((self.k * self.amplitude) ** 2) / 2.0)

    def resolved_moments(self, spacing_m: float = 0.0) -> tuple[float, float]:
        """``(height variance (m²), mean square slope)`` of :meth:`displacement_filtered` at
        vertex spacing ``spacing_m`` (m): ``Σ w_i²·A_i²/2`` and ``Σ w_i²·(k_i·A_i)²/2`` with
        ``w_i`` the :func:`~seahaze.ocean.base.lowpass_weight` of component ``i``; spacing 0
        gives every component."""
        weight = np.ones_like(self.k)
        if spacing_m > 0.0:
            weight = lowpass_weight(2.0 * math.pi / self.k, spacing_m)
        variance = float(np.sum((weight * self.amplitude) ** 2) / 2.0)
        mss = float(np.sum((weight * self.k * self.amplitude) ** 2) / 2.0)
        return variance, mss

    def mean_square_slope_filtered(self, spacing_m: float) -> float:
        """Mean square slope resolved by a mesh of vertex spacing ``spacing_m`` (m)."""
        return self.resolved_moments(spacing_m)[1]

    # ----------------------------------------------------------------------------- evaluation

    def _evaluate(
        self,
        x: np.ndarray,
        y: np.ndarray,
        weights: np.ndarray,
        use_sin: np.ndarray,
        spacing_m: np.ndarray | float | None = None,
    ) -> np.ndarray:
        """``Σ_i weights[j, i]·(sin or cos)(phi_i)`` for every point, chunked; returns
        ``(J, *x.shape)``. With ``spacing_m`` every term is also multiplied by the low-pass
        weight of its wavelength for that point's mesh spacing."""
        x = np.asarray(x, dtype=float)
        y = np.asarray(y, dtype=float)
        shape = np.broadcast(x, y).shape
        xf, yf = (a.ravel() for a in np.broadcast_arrays(x, y))
        spacing = None
        if spacing_m is not None:
            spacing = np.broadcast_to(np.asarray(spacing_m, dtype=float), shape).ravel()
        wavelength = 2.0 * math.pi / self.k
        out = np.empty((weights.shape[0], xf.size))
        w_sin = weights * use_sin[:, None]
        w_cos = weights * (~use_sin)[:, None]
        for start in range(0, xf.size, CHUNK):
            sl = slice(start, start + CHUNK)
            phi = np.outer(xf[sl], self._kx) + np.outer(yf[sl], self._ky) + self._phase_t
            sin_phi, cos_phi = np.sin(phi), np.cos(phi)
            if spacing is not None:
                lowpass = lowpass_weight(wavelength[None, :], spacing[sl, None])
                sin_phi *= lowpass
                cos_phi *= lowpass
            out[:, sl] = (sin_phi @ w_sin.T).T + (cos_phi @ w_cos.T).T
        return out.reshape(weights.shape[0], *shape)

    def _displacement_weights(self) -> np.ndarray:
        qa = self.choppiness * self.amplitude
        return np.stack(
            [-qa * np.cos(self.direction), -qa * np.sin(self.direction), self.amplitude]
        )

    def displacement(
        self, x: np.ndarray, y: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(dx, dy, dz)`` (m) at rest positions (x, y) (m)."""
        use_sin = np.array([True, True, False])
        dx, dy, dz = self._evaluate(x, y, self._displacement_weights(), use_sin)
        return dx, dy, dz

    def displacement_filtered(
        self, x: np.ndarray, y: np.ndarray, spacing_m: np.ndarray | float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Displacement with every component weighted by
        :func:`seahaze.ocean.base.lowpass_weight` of its wavelength and the local mesh spacing
        ``spacing_m`` (m)."""
        use_sin = np.array([True, True, False])
        dx, dy, dz = self._evaluate(x, y, self._displacement_weights(), use_sin, spacing_m)
        return dx, dy, dz

    def elevation_series(self, x: np.ndarray, y: np.ndarray, times_s: np.ndarray) -> np.ndarray:
        """Vertical displacement ``dz`` (m) at rest positions (x, y) (1-D, m) for every time of
        ``times_s`` (s), shape ``(len(x), len(times_s))``: the record of a Lagrangian wave buoy
        (``Σ A_i·cos(k_i·x0 - omega_i·t + phi0_i)``; ``self.time_s`` is ignored)."""
        x = np.ravel(np.asarray(x, dtype=float))
        y = np.ravel(np.asarray(y, dtype=float))
        t = np.ravel(np.asarray(times_s, dtype=float))
        spatial = np.outer(x, self._kx) + np.outer(y, self._ky) + self.phase  # (P, C)
        out = np.empty((x.size, t.size))
        for p in range(x.size):  # (T, C) per point keeps memory small
            out[p] = np.cos(spatial[p][None, :] - np.outer(t, self.omega)) @ self.amplitude
        return out

    def _derivatives(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """``d(x, y, z)/d(x0, y0)``: rows dx/dx0, dy/dx0, dz/dx0, dx/dy0, dy/dy0, dz/dy0."""
        c, s = np.cos(self.direction), np.sin(self.direction)
        kqa = self.k * self.choppiness * self.amplitude
        ka = self.k * self.amplitude
        weights = np.stack(
            [-kqa * c * c, -kqa * c * s, -ka * c, -kqa * c * s, -kqa * s * s, -ka * s]
        )
        use_sin = np.array([False, False, True, False, False, True])
        d = self._evaluate(x, y, weights, use_sin)
        d[0] += 1.0
        d[4] += 1.0
        return d

    def jacobian(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Horizontal Jacobian ``det(d(x, y)/d(x0, y0))`` at rest positions (x, y)."""
        d = self._derivatives(x, y)
        return d[0] * d[4] - d[1] * d[3]

    def normal(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Unit normals ``(..., 3)`` at the displaced points of rest positions (x, y)."""
        d = self._derivatives(x, y)
        return unit_normals_from_tangents(d[0], d[1], d[2], d[3], d[4], d[5])

    def height(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Elevation (m) above world position (x, y) (four fixed-point iterations)."""
        return height_at(self, x, y)


def sample_components(
    spectrum: SeaSpectrum,
    n_frequencies: int,
    n_directions: int,
    max_frequency_ratio: float,
    rng: np.random.Generator,
    max_omega: float = math.inf,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Stratified equal-energy components ``(omega (rad/s), direction (rad), amplitude (m))``.

    See the module docstring. Returns ``n_frequencies·n_directions`` components.
    """
    omega_p = spectrum.peak_omega
    top = min(max_frequency_ratio * omega_p, max(max_omega, 1.01 * omega_p))
    grid = np.linspace(0.05 * omega_p, top, 4096)
    cdf = _cumulative(grid, spectrum.omega_spectrum(grid))
    lowest = float(np.interp(LOW_ENERGY_QUANTILE * cdf[-1], cdf, grid))
    band_energy = cdf[-1] - float(np.interp(lowest, grid, cdf))
    u = (np.arange(n_frequencies) + rng.uniform(size=n_frequencies)) / n_frequencies
    u = (1.0 - u) * float(np.interp(lowest, grid, cdf)) + u * cdf[-1]
    omega = np.interp(u, cdf, grid)

    theta_grid = np.linspace(-math.pi, math.pi, 1441)
    directions = np.empty((n_frequencies, n_directions))
    for i, w in enumerate(omega):
        d_cdf = _cumulative(theta_grid, spectrum.spreading_function(theta_grid, w))
        v = (np.arange(n_directions) + rng.uniform(size=n_directions)) / n_directions
        directions[i] = np.interp(v * d_cdf[-1], d_cdf, theta_grid)
    m = n_frequencies * n_directions
    amplitude = np.full(m, math.sqrt(2.0 * band_energy / m))
    return np.repeat(omega, n_directions), directions.ravel(), amplitude


def _cumulative(x: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Cumulative trapezoidal integral of ``f(x)`` starting at 0."""
    steps = 0.5 * (f[1:] + f[:-1]) * np.diff(x)
    return np.concatenate([[0.0], np.cumsum(steps)])
