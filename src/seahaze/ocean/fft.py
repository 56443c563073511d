"""Tessendorf FFT ocean: periodic height fields with choppy horizontal displacement.

Model (Tessendorf 2001, "Simulating Ocean Water", §3–4)
    On a periodic patch of side ``L`` with ``N×N`` samples the elevation is the Fourier sum

        h(x, t) = Σ_k h̃(k, t)·exp(i·k·x),   k = 2·pi·(n, m)/L,   -N/2 < n, m < N/2,

    with ``h̃(k, t) = h̃0(k)·exp(-i·omega·t) + conj(h̃0(-k))·exp(+i·omega·t)`` and
    ``omega² = g·|k|`` (deep water), so each mode travels toward ``+k`` and the field is real.
    The amplitudes are Gaussian, ``h̃0 = sqrt(Psi(k)·dk²/2)·(xi_r + i·xi_i)/sqrt(2)``,
    ``xi ~ N(0, 1)``, ``dk = 2·pi/L``, so the expected variance is ``Σ_k Psi(k)·dk²`` — the
    Riemann sum of the directional wavenumber spectrum ``Psi`` over the resolved band. (We
    use ``exp(-i·omega·t)`` with ``exp(+i·k·x)`` so that waves travel along ``k``; Tessendorf's
    printed sign convention moves the ``h̃0(k)`` component toward ``-k``.)

    Horizontal "choppy" displacement (Tessendorf 2001, eq. 29), ``x → x + lambda·D(x, t)`` with

        D(x, t) = Σ_k i·(k/|k|)·h̃(k, t)·exp(i·k·x),

    which for a single wave ``h = A·cos(k·x - omega·t)`` gives ``D = -A·k̂·sin(k·x - omega·t)``:
    a Gerstner (trochoidal) wave with steepness ``lambda``, sharp crests and flat troughs (the
    sign is chosen so that positive ``lambda`` sharpens the crests). The surface folds where the
    Jacobian ``J = (1 + lambda·Dxx)(1 + lambda·Dyy) - lambda²·Dxy²`` is ≤ 0; ``J`` is a quadratic
    in ``lambda``; the clamp keeps both eigenvalues of the (symmetric) Jacobian matrix above
    :data:`MIN_STRETCH` everywhere (see :meth:`FFTOcean.max_choppiness`).

Patch sizes (cascades)
    The largest patch is ``L0 = 8·lambda_p`` (``lambda_p = 2·pi·g/omega_p²``, the peak
    wavelength): with ``N = 256`` its grid spacing is ``lambda_p/32`` and it resolves
    wavelengths from ``8·lambda_p`` down to ``lambda_p/16`` (``lambda_p/8`` when smaller patches
    follow). Smaller patches of side
    ``L_i = L0/r^i``, ``r = ((1 + sqrt 5)/2)³ ≈ 4.236`` (irrational, hence incommensurate with
    ``L0``), carry the wavenumbers above half of the previous patch's Nyquist wavenumber
    ``pi·N/L_(i-1)``. Each wavenumber belongs to exactly one patch, so the variances add up,
    and the sum of patches with incommensurate periods never repeats exactly. By default there
    are as many patches (1–4) as are needed for the finest grid spacing to reach
    ``fft_min_wavelength_m/2`` (0.25 m), and no patch carries waves shorter than
    ``fft_min_wavelength_m`` (0.5 m): a fixed absolute cut-off, so that a rougher sea also
    resolves a larger slope variance; the unresolved rest is microfacet roughness
    (:mod:`seahaze.ocean.cox_munk`). Without the cut a calm sea's single patch reached
    centimetre waves and resolved more slope variance than Cox–Munk's total (1 m/s: 0.0101 vs
    0.0081).

Sampling
    Fields are sampled with periodic bilinear interpolation (``displacement``, ``normal``), or
    through a per-patch low-pass pyramid (``displacement_filtered``: level ``l`` keeps exactly
    the modes ``|n_x|, |n_y| < N/2^(l+1)``, an alias-free band limit) for meshes whose vertex
    spacing is coarser than the patch grid.

Choppiness clamp
    The bound on ``lambda`` (:meth:`FFTOcean.max_choppiness`) is exact for one patch and
    conservative for several (Weyl's inequality: the worst points of the patches are assumed to
    coincide), typically by a factor 1.3–2 with four patches.
"""

from __future__ import annotations

import functools
import math
import warnings
from collections.abc import Sequence
from dataclasses import replace

import numpy as np
from scipy import fft as sfft

from .base import (
    MIN_STRETCH,
    ChoppinessClampedWarning,
    OceanParams,
    height_at,
    unit_normals_from_tangents,
)
from .periodic import sample_periodic_bilinear, sample_pyramid
from .spectra import GRAVITY, SeaSpectrum, deep_water_omega

PATCH_PEAK_WAVELENGTHS = 8.0
"""Side of the largest FFT patch in peak wavelengths."""

CASCADE_SIZE_RATIO = ((1.0 + math.sqrt(5.0)) / 2.0) ** 3
"""Ratio between the sides of successive FFT patches (golden ratio cubed, ≈ 4.236)."""

CASCADE_SPLIT_FRACTION = 0.5
"""Patch ``i`` carries wavenumbers below this fraction of its Nyquist wavenumber ``pi·N/L_i``;
the next (smaller) patch carries the rest."""

# Field order of FFTCascade.fields().
HEIGHT, DISP_X, DISP_Y, SLOPE_X, SLOPE_Y, DXX, DYY, DXY = range(8)
N_FIELDS = 8


class FFTCascade:
    """One periodic ``N×N`` patch of side ``size_m`` with initial amplitudes ``h0``.

    Arrays are indexed ``[iy, ix]``; sample ``(iy, ix)`` sits at ``(ix, iy)·size_m/N`` and
    mode ``(iy, ix)`` has wavenumber ``2·pi·(fftfreq(N)·N)[(ix, iy)]/size_m``.
    """

    def __init__(self, size_m: float, h0: np.ndarray, gravity: float = GRAVITY) -> None:
        h0 = np.asarray(h0, dtype=complex)
        if h0.ndim != 2 or h0.shape[0] != h0.shape[1]:
            raise ValueError("h0 must be a square 2-D array")
        self.size_m = float(size_m)
        self.resolution = h0.shape[0]
        self.gravity = gravity
        self.h0 = h0
        k1 = 2.0 * math.pi * np.fft.fftfreq(self.resolution, d=self.size_m / self.resolution)
        self.kx, self.ky = np.meshgrid(k1, k1, indexing="xy")
        self.k = np.hypot(self.kx, self.ky)
        self.omega = deep_water_omega(self.k, gravity)
        self._h0_minus_conj = np.conj(_reflect_modes(h0))

    @property
    def dk(self) -> float:
        """Wavenumber spacing ``2·pi/L`` (rad/m)."""
        return 2.0 * math.pi / self.size_m

    @property
    def spacing_m(self) -> float:
        """Grid spacing ``L/N`` (m)."""
        return self.size_m / self.resolution

    @classmethod
    def from_spectrum(
        cls,
        spectrum: SeaSpectrum,
        size_m: float,
        resolution: int,
        rng: np.random.Generator,
        k_low: float = 0.0,
        k_high: float = math.inf,
    ) -> FFTCascade:
        """Draw Gaussian amplitudes for the modes with ``k_low <= |k| < k_high``.

        Modes on the Nyquist row/column (index ``-N/2``) and ``k = 0`` are left empty. Exactly
        ``2·N²`` standard normals are drawn from ``rng``, whatever the band.
        """
        rms = _mode_rms_amplitude(spectrum, size_m, resolution, k_low, k_high)
        xi = rng.standard_normal((2, resolution, resolution))
        h0 = rms * (xi[0] + 1j * xi[1]) / math.sqrt(2.0)
        return cls(size_m, h0, spectrum.gravity)

    @property
    def expected_variance(self) -> float:
        """Expected elevation variance ``Σ (|h̃0(k)|² + |h̃0(-k)|²)`` (m²) of this realisation's
        amplitudes (its ensemble mean is ``Σ Psi·dk²``)."""
        return float(np.sum(np.abs(self.h0) ** 2 + np.abs(self._h0_minus_conj) ** 2))

    def height_spectrum(self, time_s: float) -> np.ndarray:
        """``h̃(k, t) = h̃0(k)·e^(-i·omega·t) + conj(h̃0(-k))·e^(+i·omega·t)`` (m)."""
        phase = np.exp(-1j * self.omega * time_s)
        return self.h0 * phase + self._h0_minus_conj * np.conj(phase)

    def field_spectra(self, time_s: float) -> np.ndarray:
        """Half (``rfft``-layout) spectra ``(8, N, N/2 + 1)`` of the fields of :meth:`fields`."""
        half = self.resolution // 2 + 1
        h = self.height_spectrum(time_s)[:, :half]
        kx, ky = self.kx[:, :half], self.ky[:, :half]
        k = self.k[:, :half]
        inv_k = np.divide(1.0, k, out=np.zeros_like(k), where=k > 0.0)
        return np.stack(
            [
                h,
                1j * kx * inv_k * h,
                1j * ky * inv_k * h,
                1j * kx * h,
                1j * ky * h,
                -kx * kx * inv_k * h,
                -ky * ky * inv_k * h,
                -kx * ky * inv_k * h,
            ]
        )

    def fields(self, time_s: float) -> np.ndarray:
        """Grid fields at time ``time_s``, shape ``(8, N, N)``: height (m), choppy displacement
        ``D`` x/y (m, per unit lambda), slopes ``dh/dx``, ``dh/dy``, and the derivatives
        ``dDx/dx``, ``dDy/dy``, ``dDx/dy`` (per unit lambda)."""
        n = self.resolution
        return sfft.irfft2(self.field_spectra(time_s), s=(n, n), axes=(-2, -1)) * float(n * n)

    def displacement_pyramid(self, time_s: float) -> list[np.ndarray]:
        """Low-pass "mip" levels of (height, Dx, Dy): level ``l`` is a ``(3, M, M)`` grid,
        ``M = N/2^l``, holding exactly the modes with ``|n_x|, |n_y| < M/2`` (wavelengths longer
        than ``2·L/M`` along the axes) — an alias-free band limit, not an average. The last
        level (``M = 2``) holds nothing."""
        spectra = self.field_spectra(time_s)[:3]
        levels = []
        m = self.resolution
        while m >= 2:
            levels.append(_truncated_field(spectra, self.resolution, m))
            m //= 2
        return levels


def _truncated_field(half_spectra: np.ndarray, n: int, m: int) -> np.ndarray:
    """Inverse FFT on an ``m×m`` grid of the modes ``|n_x|, |n_y| < m/2`` of ``n×n`` half
    spectra ``(F, n, n/2 + 1)``."""
    keep = m // 2 - 1  # highest |index| kept
    out = np.zeros((half_spectra.shape[0], m, m // 2 + 1), dtype=complex)
    out[:, : keep + 1, : keep + 1] = half_spectra[:, : keep + 1, : keep + 1]
    if keep > 0:
        out[:, m - keep :, : keep + 1] = half_spectra[:, n - keep :, : keep + 1]
    return sfft.irfft2(out, s=(m, m), axes=(-2, -1)) * float(m * m)


@functools.lru_cache(maxsize=16)
def _mode_rms_amplitude(
    spectrum: SeaSpectrum, size_m: float, resolution: int, k_low: float, k_high: float
) -> np.ndarray:
    """``sqrt(Psi(k)·dk²/2)`` (m) on the FFT grid, 0 outside the band (cached, read-only)."""
    k1 = 2.0 * math.pi * np.fft.fftfreq(resolution, d=size_m / resolution)
    kx, ky = np.meshgrid(k1, k1, indexing="xy")
    k = np.hypot(kx, ky)
    band = (k >= k_low) & (k < k_high) & (k > 0.0)
    nyquist = resolution // 2
    band[nyquist, :] = False
    band[:, nyquist] = False
    dk = 2.0 * math.pi / size_m
    psi = np.where(band, spectrum.wavenumber_spectrum(kx, ky), 0.0)
    rms = np.sqrt(psi * dk * dk / 2.0)
    rms.setflags(write=False)
    return rms


def _reflect_modes(a: np.ndarray) -> np.ndarray:
    """``a(-k)`` on an FFT-ordered grid: index ``i`` → ``(-i) mod N`` on both axes."""
    return np.roll(np.flip(a, axis=(0, 1)), 1, axis=(0, 1))


def _pyramid_mode_weight(cascade: FFTCascade, spacing_m: float) -> np.ndarray:
    """Weight ``(N, N)`` of every mode of ``cascade`` in :func:`sample_pyramid` at the level
    :meth:`FFTOcean.displacement_filtered` picks for vertex spacing ``spacing_m`` (m)."""
    n = cascade.resolution
    n_levels = round(math.log2(n))  # levels M = N, N/2, ..., 2
    last = n_levels - 1
    level = math.log2(max(spacing_m, 1e-12) / cascade.spacing_m) + 0.5
    level = min(max(level, 0.0), float(last))
    lower = min(math.floor(level), max(last - 1, 0))
    frac = level - lower
    index = np.abs(np.fft.fftfreq(n) * n)
    reach = np.maximum(index[None, :], index[:, None])  # max(|n_x|, |n_y|)

    def kept(lv: int) -> np.ndarray:
        return (reach <= n // 2 ** (lv + 1) - 1).astype(float)

    if lower + 1 <= last:
        return (1.0 - frac) * kept(lower) + frac * kept(lower + 1)
    return kept(lower)


def default_patch_size(spectrum: SeaSpectrum) -> float:
    """Side of the largest FFT patch: ``PATCH_PEAK_WAVELENGTHS`` peak wavelengths (m)."""
    return PATCH_PEAK_WAVELENGTHS * spectrum.peak_wavelength


def automatic_cascade_count(
    largest_size_m: float, resolution: int, min_wavelength_m: float, max_cascades: int = 4
) -> int:
    """Fewest patches (1 to ``max_cascades``) whose finest grid spacing
    ``L0/(N·r^(n-1))`` is at most ``min_wavelength_m/2``."""
    ratio = largest_size_m / (resolution * 0.5 * min_wavelength_m)
    if ratio <= 1.0:
        return 1
    return int(min(max_cascades, 1 + math.ceil(math.log(ratio) / math.log(CASCADE_SIZE_RATIO))))


def cascade_layout(
    largest_size_m: float, resolution: int, cascades: int
) -> list[tuple[float, float, float]]:
    """``(size_m, k_low, k_high)`` of every patch: sides shrink by :data:`CASCADE_SIZE_RATIO`,
    patch ``i`` carries ``k_low <= |k| < k_high`` with boundaries at
    ``CASCADE_SPLIT_FRACTION·pi·N/L_i``; the smallest patch is limited by its own square
    Nyquist band only."""
    sizes = [largest_size_m / CASCADE_SIZE_RATIO**i for i in range(cascades)]
    splits = [CASCADE_SPLIT_FRACTION * math.pi * resolution / size for size in sizes[:-1]]
    lows = [0.0, *splits]
    highs = [*splits, math.inf]
    return list(zip(sizes, lows, highs, strict=True))


class FFTOcean:
    """Sum of Tessendorf FFT patches, sampled with periodic bilinear interpolation."""

    def __init__(
        self,
        cascades: Sequence[FFTCascade],
        choppiness: float,
        time_s: float = 0.0,
        peak_wavelength_m: float = math.nan,
        warn: bool = True,
    ) -> None:
        if not cascades:
            raise ValueError("at least one cascade is needed")
        self.cascades = list(cascades)
        self.time_s = float(time_s)
        self.peak_wavelength_m = float(peak_wavelength_m)
        self.requested_choppiness = float(choppiness)
        self._grids = [c.fields(self.time_s) for c in self.cascades]
        self._pyramids: list[list[np.ndarray]] | None = None
        self._power: tuple[float, list[tuple[np.ndarray, np.ndarray]]] | None = None
        self._choppiness_limit: float | None = None
        self.choppiness = self.requested_choppiness
        if self.requested_choppiness > 0.0:
            self.choppiness = min(self.requested_choppiness, self.choppiness_limit)
        if self.choppiness < self.requested_choppiness and warn:
            warnings.warn(
                f"FFT ocean choppiness {self.requested_choppiness:.3g} folds the surface "
                f"(principal stretch < {MIN_STRETCH}, Jacobian -> 0); clamped to "
                f"{self.choppiness:.3g} "
                f"at t = {self.time_s:g} s",
                ChoppinessClampedWarning,
                stacklevel=2,
            )

    @classmethod
    def from_params(cls, params: OceanParams) -> FFTOcean:
        """Build the patches for ``params`` (deterministic in ``params.seed``)."""
        spectrum = params.sea_spectrum()
        largest = params.patch_size_m or default_patch_size(spectrum)
        n_cascades = params.fft_cascades or automatic_cascade_count(
            largest, params.fft_resolution, params.fft_min_wavelength_m
        )
        rng = np.random.default_rng(params.seed)
        # Waves shorter than fft_min_wavelength_m are microfacet roughness, also when the grid
        # could carry them (at low wind one patch of 8 peak wavelengths reaches centimetres,
        # and the resolved slope variance would exceed Cox-Munk's total).
        k_cut = 2.0 * math.pi / params.fft_min_wavelength_m
        cascades = [
            FFTCascade.from_spectrum(
                spectrum, size, params.fft_resolution, rng, min(k_lo, k_cut), min(k_hi, k_cut)
            )
            for size, k_lo, k_hi in cascade_layout(largest, params.fft_resolution, n_cascades)
        ]
        return cls(cascades, params.choppiness, params.time_s, spectrum.peak_wavelength)

    @property
    def choppiness_limit(self) -> float:
        """Largest unfolded choppiness at this time (:meth:`max_choppiness`, cached)."""
        if self._choppiness_limit is None:
            self._choppiness_limit = self.max_choppiness()
        return self._choppiness_limit

    def at_time(self, time_s: float, choppiness: float | None = None) -> FFTOcean:
        """The same realisation at another time (no new random draws)."""
        lam = self.requested_choppiness if choppiness is None else choppiness
        return FFTOcean(self.cascades, lam, time_s, self.peak_wavelength_m)

    # ----------------------------------------------------------------------------- statistics

    @property
    def significant_wave_height_m(self) -> float:
        """``4·sqrt(Σ expected variance)`` (m) of this realisation's amplitudes."""
        return 4.0 * math.sqrt(sum(c.expected_variance for c in self.cascades))

    @property
    def height_variance(self) -> float:
        """Spatial variance of the elevation (m²): sum over patches of the grid variance
        (exact by Parseval; cross terms between incommensurate patches average to zero)."""
        return float(sum(np.mean(g[HEIGHT] ** 2) for g in self._grids))

    @property
    def mean_square_slope(self) -> float:
        """Spatial mean of ``|grad h|²`` over the patches (dimensionless)."""
        return float(sum(np.mean(g[SLOPE_X] ** 2 + g[SLOPE_Y] ** 2) for g in self._grids))

    def resolved_moments(self, spacing_m: float = 0.0) -> tuple[float, float]:
        """``(height variance (m²), mean square slope)`` of the band-limited surface that a mesh
        of vertex spacing ``spacing_m`` (m) samples through :meth:`displacement_filtered`.

        Each mode of each patch is weighted exactly as the trilinear pyramid lookup weights it
        at that spacing (``(1 - f)`` from level ``l``, ``f`` from level ``l + 1``, 0 where a level
        drops it), so the result is ``Σ w²·|h̃(k, t)|²`` and ``Σ w²·k²·|h̃(k, t)|²`` (Parseval).
        ``spacing_m = 0`` gives :attr:`height_variance` and :attr:`mean_square_slope`: every
        wave the generator holds. The microfacets must carry the rest of Cox–Munk's slope
        variance (:func:`seahaze.ocean.cox_munk.slope_budget`).
        """
        variance = 0.0
        mss = 0.0
        for cascade, (power, k_squared) in zip(self.cascades, self._mode_power(), strict=True):
            weight = _pyramid_mode_weight(cascade, spacing_m)
            variance += float(np.sum(weight**2 * power))
            mss += float(np.sum(weight**2 * k_squared * power))
        return variance, mss

    def _mode_power(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """Per cascade, ``|h̃(k, t)|²`` at this surface's time and ``k²``: computed once, as a
        sea mesh's roughness asks :meth:`resolved_moments` for dozens of spacings."""
        if self._power is None or self._power[0] != self.time_s:
            spectra = [(np.abs(c.height_spectrum(self.time_s)) ** 2, c.k**2) for c in self.cascades]
            self._power = (self.time_s, spectra)
        return self._power[1]

    def mean_square_slope_filtered(self, spacing_m: float) -> float:
        """Mean square slope (dimensionless) of :meth:`displacement_filtered` at vertex spacing
        ``spacing_m`` (m): the part of the slope variance a mesh that fine resolves."""
        return self.resolved_moments(spacing_m)[1]

    # ----------------------------------------------------------------------------- sampling

    def _sum_fields(self, fields: Sequence[int], x: np.ndarray, y: np.ndarray) -> np.ndarray:
        total = None
        for cascade, grids in zip(self.cascades, self._grids, strict=True):
            values = sample_periodic_bilinear(grids[list(fields)], cascade.size_m, x, y)
            total = values if total is None else total + values
        assert total is not None
        return total

    def displacement(
        self, x: np.ndarray, y: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(lambda·Dx, lambda·Dy, h)`` (m) at rest positions (x, y) (m)."""
        h, dx, dy = self._sum_fields((HEIGHT, DISP_X, DISP_Y), x, y)
        return self.choppiness * dx, self.choppiness * dy, h

    def displacement_filtered(
        self, x: np.ndarray, y: np.ndarray, spacing_m: np.ndarray | float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Displacement band-limited for a mesh of local vertex spacing ``spacing_m`` (m).

        Each patch is sampled from its low-pass pyramid at the fractional level
        ``log2(spacing/dx) + 1/2`` (``dx`` the patch's grid spacing), so the kept band ends
        between 2 and 4 mesh spacings; a patch whose waves are all shorter drops out.
        """
        x = np.asarray(x, dtype=float)
        y = np.asarray(y, dtype=float)
        spacing = np.broadcast_to(np.asarray(spacing_m, dtype=float), x.shape).ravel()
        if self._pyramids is None:
            self._pyramids = [c.displacement_pyramid(self.time_s) for c in self.cascades]
        total = np.zeros((3, x.size))
        for cascade, pyramid in zip(self.cascades, self._pyramids, strict=True):
            level = np.log2(np.maximum(spacing, 1e-12) / cascade.spacing_m) + 0.5
            total += sample_pyramid(pyramid, cascade.size_m, x, y, level)
        h, dx, dy = (a.reshape(x.shape) for a in total)
        return self.choppiness * dx, self.choppiness * dy, h

    def height(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Elevation (m) above world position (x, y): the rest position is found with four
        fixed-point iterations (:func:`seahaze.ocean.base.invert_horizontal_displacement`)."""
        if self.choppiness == 0.0:
            return self._sum_fields((HEIGHT,), x, y)[0]
        return height_at(self, x, y)

    def normal(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Unit normals ``(..., 3)`` of the displaced surface at rest positions (x, y)."""
        lam = self.choppiness
        sx, sy, dxx, dyy, dxy = self._sum_fields((SLOPE_X, SLOPE_Y, DXX, DYY, DXY), x, y)
        return unit_normals_from_tangents(
            1.0 + lam * dxx, lam * dxy, sx, lam * dxy, 1.0 + lam * dyy, sy
        )

    def jacobian(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Horizontal Jacobian ``det(d(x + lambda·D)/dx)`` at rest positions (x, y)."""
        dxx, dyy, dxy = self._sum_fields((DXX, DYY, DXY), x, y)
        lam = self.choppiness
        return (1.0 + lam * dxx) * (1.0 + lam * dyy) - lam * lam * dxy * dxy

    def patch_jacobian(self, index: int = 0, choppiness: float | None = None) -> np.ndarray:
        """Horizontal Jacobian ``(N, N)`` of patch ``index`` alone on its grid nodes, with
        ``choppiness`` (default: the surface's): the breaking indicator of the waves that patch
        carries (:mod:`seahaze.ocean.whitecaps`)."""
        lam = self.choppiness if choppiness is None else float(choppiness)
        g = self._grids[index]
        return (1.0 + lam * g[DXX]) * (1.0 + lam * g[DYY]) - (lam * g[DXY]) ** 2

    # ----------------------------------------------------------------------------- folding

    def max_choppiness(self) -> float:
        """Largest ``lambda`` that keeps every principal stretch >= :data:`MIN_STRETCH`.

        The horizontal Jacobian matrix is ``I + lambda·A`` with the symmetric
        ``A = [[Dxx, Dxy], [Dxy, Dyy]]`` (``D`` is a gradient field), so the surface folds
        where ``1 + lambda·mu_min(A) <= 0`` (``mu_min``: smallest eigenvalue). ``mu_min`` is
        concave, hence (i) between grid nodes the bilinearly interpolated ``A`` is never worse
        than the worst node, and (ii) for a sum of patches ``mu_min(Σ A_i) >= Σ min mu_min(A_i)``
        (Weyl). The bound ``lambda <= (1 - MIN_STRETCH)/(-Σ_i min_nodes mu_min(A_i))`` is exact
        for one patch and slightly conservative for several (their worst points need not
        coincide). ``inf`` if no patch can fold.
        """
        worst = 0.0
        for grids in self._grids:
            worst += float(np.min(smallest_eigenvalue(grids[DXX], grids[DYY], grids[DXY])))
        if worst >= 0.0:
            return math.inf
        return (1.0 - MIN_STRETCH) / -worst


def smallest_eigenvalue(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Smallest eigenvalue of the symmetric 2×2 matrices ``[[a, c], [c, b]]``."""
    return 0.5 * (a + b) - np.hypot(0.5 * (a - b), c)


def fft_choppiness_limit(params: OceanParams, times_s: Sequence[float]) -> float:
    """Largest choppiness that keeps the FFT surface of ``params`` unfolded at all ``times_s``;
    pass it as ``choppiness`` to keep a sequence's lambda constant from frame to frame."""
    ocean = FFTOcean.from_params(replace(params, choppiness=0.0))
    return min(ocean.at_time(t, choppiness=0.0).choppiness_limit for t in times_s)
