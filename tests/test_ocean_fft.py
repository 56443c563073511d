"""Physics checks of the Tessendorf FFT ocean."""

from __future__ import annotations

import math
import warnings
from dataclasses import replace

import numpy as np
import pytest
from scipy import integrate

from seahaze.ocean import (
    ChoppinessClampedWarning,
    FFTCascade,
    FFTOcean,
    OceanParams,
    make_surface,
)
from seahaze.ocean.fft import (
    DXX,
    DXY,
    DYY,
    HEIGHT,
    MIN_STRETCH,
    cascade_layout,
    fft_choppiness_limit,
    smallest_eigenvalue,
)
from seahaze.ocean.mesh import build_sea_mesh

G = 9.81


def _resolved_band_variance(params: OceanParams, n_cascades: int) -> float:
    """Variance (m²) of the continuous spectrum over the band the FFT patches resolve.

    Patch 0 carries the disc ``|k| < k_1``, patch ``i`` the annulus ``k_i <= |k| < k_(i+1)``
    and the last patch everything above ``k_(n-1)`` inside its square lattice
    ``max(|kx|, |ky|) < (N/2 - 1/2)·dk`` (the Nyquist row/column is empty). Because
    ``∫ D dtheta = 1``, the disc and annuli are the 1-D integral of ``S(omega)`` up to
    ``omega(k_(n-1))``; the square part is integrated numerically in polar coordinates.
    """
    spectrum = params.sea_spectrum()
    largest = params.patch_size_m or 8.0 * spectrum.peak_wavelength
    size_last, k_low, _ = cascade_layout(largest, params.fft_resolution, n_cascades)[-1]
    inner = spectrum.variance(0.0, math.sqrt(G * k_low)) if k_low > 0.0 else 0.0
    half_width = (params.fft_resolution / 2 - 0.5) * 2.0 * math.pi / size_last
    theta = np.linspace(-math.pi, math.pi, 721)
    k_edge = half_width / np.maximum(np.abs(np.cos(theta)), np.abs(np.sin(theta)))
    k_start = max(k_low, 1e-3 * spectrum.peak_wavenumber)
    u = np.linspace(0.0, 1.0, 2001)
    kk = k_start * (k_edge[:, None] / k_start) ** u[None, :]  # geometric in k
    tt = np.broadcast_to(theta[:, None], kk.shape)
    psi = spectrum.wavenumber_spectrum(kk * np.cos(tt), kk * np.sin(tt))
    radial = integrate.trapezoid(psi * kk, kk, axis=1)
    return inner + float(integrate.trapezoid(radial, theta))


@pytest.mark.parametrize("spectrum", ["jonswap", "pierson_moskowitz"])
def test_height_variance_matches_spectrum(spectrum: str) -> None:
    """Mean grid variance over 24 seeds vs the spectrum integrated over the resolved band
    (N = 256, largest patch 16 peak wavelengths, smaller patches down to 0.25 m spacing)."""
    params = OceanParams(spectrum=spectrum, wind_speed=10.0, fetch_km=30.0, choppiness=0.0)
    params = replace(params, patch_size_m=16.0 * params.sea_spectrum().peak_wavelength)
    oceans = [FFTOcean.from_params(replace(params, seed=s)) for s in range(24)]
    variances = [ocean.height_variance for ocean in oceans]
    band = _resolved_band_variance(params, len(oceans[0].cascades))
    assert np.mean(variances) == pytest.approx(band, rel=0.05)
    # The resolved band holds (almost) the whole spectrum.
    assert band == pytest.approx(params.sea_spectrum().variance(), rel=0.02)


@pytest.mark.parametrize(
    ("spectrum", "wind", "fetch_km", "expected_peak"),
    [
        # Hasselmann et al. (1973): omega_p = 22 (g^2 / (U10 F))^(1/3), fetch-limited.
        ("jonswap", 10.0, 20.0, 22.0 * (G * G / (10.0 * 20e3)) ** (1.0 / 3.0)),
        ("jonswap", 15.0, 50.0, 22.0 * (G * G / (15.0 * 50e3)) ** (1.0 / 3.0)),
        # Pierson & Moskowitz (1964): omega_p = 0.877 g / U19.5, U19.5 = 1.026 U10.
        ("pierson_moskowitz", 10.0, 100.0, 0.877 * G / (1.026 * 10.0)),
        ("pierson_moskowitz", 4.0, 100.0, 0.877 * G / (1.026 * 4.0)),
    ],
)
def test_periodogram_peak_matches_spectrum(
    spectrum: str, wind: float, fetch_km: float, expected_peak: float
) -> None:
    """Energy of the generated field binned by omega(k) (bins of width omega_p/10, 8 seeds,
    one patch of 16 expected peak wavelengths sampled through ``displacement``)."""
    wavelength = 2.0 * math.pi * G / expected_peak**2
    params = OceanParams(
        spectrum=spectrum,
        wind_speed=wind,
        fetch_km=fetch_km,
        choppiness=0.0,
        fft_cascades=1,
        patch_size_m=16.0 * wavelength,
    )
    n = params.fft_resolution
    coords = np.arange(n) * (params.patch_size_m / n)
    x, y = np.meshgrid(coords, coords, indexing="xy")
    k1 = 2.0 * math.pi * np.fft.fftfreq(n, d=params.patch_size_m / n)
    omega = np.sqrt(G * np.hypot(*np.meshgrid(k1, k1, indexing="xy")))
    bin_width = expected_peak / 10.0
    edges = np.arange(0.0, 4.0 * expected_peak, bin_width)
    energy = np.zeros(len(edges) - 1)
    for seed in range(8):
        h = make_surface(replace(params, seed=seed)).displacement(x, y)[2]
        power = np.abs(np.fft.fft2(h) / n**2) ** 2
        energy += np.histogram(omega.ravel(), edges, weights=power.ravel())[0]
    peak_bin = int(np.argmax(energy))
    found = 0.5 * (edges[peak_bin] + edges[peak_bin + 1])
    assert abs(found - expected_peak) <= bin_width


@pytest.mark.parametrize("mode", [(3, 0), (5, 7), (-20, 11), (0, -40)])
def test_single_mode_advances_with_deep_water_dispersion(mode: tuple[int, int]) -> None:
    size, n, dt = 100.0, 128, 0.05
    h0 = np.zeros((n, n), complex)
    h0[mode[1] % n, mode[0] % n] = 0.3 * np.exp(0.4j)
    cascade = FFTCascade(size, h0)
    k = 2.0 * math.pi * math.hypot(*mode) / size
    phases = []
    for t in (1.3, 1.3 + dt):
        h = cascade.fields(t)[HEIGHT]
        coefficient = np.fft.fft2(h)[mode[1] % n, mode[0] % n] / n**2
        phases.append(np.angle(coefficient))
    omega_measured = -np.angle(np.exp(1j * (phases[1] - phases[0]))) / dt
    assert omega_measured == pytest.approx(math.sqrt(G * k), rel=1e-9)


def test_single_mode_travels_along_k() -> None:
    """A crest moves toward +k at the phase speed omega/k."""
    size, n = 64.0, 64
    k = 2.0 * math.pi * 4 / size  # wavelength 16 m along +x
    h0 = np.zeros((n, n), complex)
    h0[0, 4] = 0.5 * np.exp(-1j * k * 4.0)  # h = cos(k (x - 4) - omega t): crest at x = 4
    cascade = FFTCascade(size, h0)
    c = math.sqrt(G / k)
    dt = 2.0 / c  # the crest should move by 2 m
    x = np.linspace(0.0, 16.0, 4001)
    za = FFTOcean([cascade], 0.0, time_s=0.0).displacement(x, np.zeros_like(x))[2]
    zb = FFTOcean([cascade], 0.0, time_s=dt).displacement(x, np.zeros_like(x))[2]
    assert x[np.argmax(za)] == pytest.approx(4.0, abs=0.05)
    assert x[np.argmax(zb)] - x[np.argmax(za)] == pytest.approx(2.0, abs=0.05)


def test_choppiness_clamped_with_warning() -> None:
    params = OceanParams(wind_speed=12.0, choppiness=20.0, seed=3)
    with pytest.warns(ChoppinessClampedWarning, match="clamped"):
        surface = make_surface(params)
    assert isinstance(surface, FFTOcean)
    assert 0.0 < surface.choppiness < 20.0
    assert surface.choppiness == pytest.approx(surface.choppiness_limit)
    rng = np.random.default_rng(0)
    size = surface.cascades[0].size_m
    x, y = rng.uniform(0.0, size, (2, 400_000))
    assert surface.jacobian(x, y).min() > 0.0
    # A single patch is clamped exactly: the smallest principal stretch of the horizontal map
    # over the grid nodes (which bound the bilinear interpolant) equals the margin.
    with pytest.warns(ChoppinessClampedWarning):
        one = make_surface(replace(params, fft_cascades=1))
    grids = one.cascades[0].fields(one.time_s)
    stretch = 1.0 + one.choppiness * smallest_eigenvalue(grids[DXX], grids[DYY], grids[DXY])
    assert stretch.min() == pytest.approx(MIN_STRETCH, rel=1e-9)


def test_moderate_choppiness_not_clamped() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error", ChoppinessClampedWarning)
        surface = make_surface(OceanParams(wind_speed=8.0, choppiness=0.5))
    assert surface.choppiness == 0.5


def test_sequence_choppiness_limit_is_safe_for_every_frame() -> None:
    params = OceanParams(wind_speed=10.0, choppiness=0.0, seed=5)
    times = [0.0, 0.5, 1.0, 2.0]
    limit = fft_choppiness_limit(params, times)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ChoppinessClampedWarning)
        for t in times:
            make_surface(replace(params, choppiness=limit * 0.999, time_s=t))


def test_time_evolution_is_consistent() -> None:
    params = OceanParams(wind_speed=9.0, seed=11, time_s=0.0)
    base = FFTOcean.from_params(params)
    x = np.linspace(-50.0, 50.0, 101)
    later = make_surface(replace(params, time_s=2.5))
    np.testing.assert_array_equal(
        np.stack(base.at_time(2.5).displacement(x, x)), np.stack(later.displacement(x, x))
    )
    assert not np.allclose(base.displacement(x, x)[2], later.displacement(x, x)[2])


def test_seed_determinism_of_vertices() -> None:
    params = OceanParams(wind_speed=7.0, seed=42)
    v1, f1 = build_sea_mesh(make_surface(params), camera_height_m=10.0, quality="low")
    v2, f2 = build_sea_mesh(make_surface(params), camera_height_m=10.0, quality="low")
    v3, _ = build_sea_mesh(
        make_surface(replace(params, seed=43)), camera_height_m=10.0, quality="low"
    )
    np.testing.assert_array_equal(v1, v2)
    np.testing.assert_array_equal(f1, f2)
    assert not np.array_equal(v1, v3)


def test_height_inverts_choppy_displacement() -> None:
    surface = make_surface(OceanParams(wind_speed=12.0, choppiness=1.0, seed=2))
    rng = np.random.default_rng(7)
    x0, y0 = rng.uniform(-200.0, 200.0, (2, 2000))
    dx, dy, dz = surface.displacement(x0, y0)
    assert np.abs(dx).max() > 0.1  # the test is not trivial
    h = surface.height(x0 + dx, y0 + dy)
    rms = math.sqrt(np.mean(dz**2))
    assert np.abs(h - dz).max() < 0.02 * rms + 1e-3


def test_single_mode_normals_match_trochoid() -> None:
    """For h = A cos(phi), x = x0 - lambda A sin(phi) the normal is
    (A k sin(phi), 0, 1 - lambda A k cos(phi)) up to normalisation (checked at grid nodes)."""
    size, n, amplitude, lam = 64.0, 64, 0.4, 0.7
    h0 = np.zeros((n, n), complex)
    h0[0, 2] = amplitude / 2.0
    ocean = FFTOcean([FFTCascade(size, h0)], lam, time_s=0.8)
    k = 2.0 * math.pi * 2 / size
    x = np.arange(n) * (size / n)
    phi = k * x - math.sqrt(G * k) * 0.8
    expected = np.stack(
        [amplitude * k * np.sin(phi), np.zeros(n), 1.0 - lam * amplitude * k * np.cos(phi)], axis=-1
    )
    expected /= np.linalg.norm(expected, axis=-1, keepdims=True)
    np.testing.assert_allclose(ocean.normal(x, np.zeros(n)), expected, atol=1e-12)
    dx, _, dz = ocean.displacement(x, np.zeros(n))
    np.testing.assert_allclose(dx, -lam * amplitude * np.sin(phi), atol=1e-12)
    np.testing.assert_allclose(dz, amplitude * np.cos(phi), atol=1e-12)


def test_normals_carry_the_mean_square_slope() -> None:
    """At the grid nodes (where interpolation is exact) the normals' slopes have the mean
    square slope of the spectral field; between nodes bilinear interpolation smooths it."""
    surface = make_surface(OceanParams(wind_speed=10.0, choppiness=0.0, seed=1, fft_cascades=1))
    cascade = surface.cascades[0]
    nodes = np.arange(cascade.resolution) * cascade.spacing_m
    x, y = np.meshgrid(nodes, nodes)
    n = surface.normal(x, y)
    np.testing.assert_allclose(np.linalg.norm(n, axis=-1), 1.0, rtol=1e-12)
    slopes2 = (n[..., 0] ** 2 + n[..., 1] ** 2) / n[..., 2] ** 2
    assert np.mean(slopes2) == pytest.approx(surface.mean_square_slope, rel=1e-9)
    rng = np.random.default_rng(3)
    n_between = surface.normal(*rng.uniform(0.0, cascade.size_m, (2, 100_000)))
    between = np.mean((n_between[:, 0] ** 2 + n_between[:, 1] ** 2) / n_between[:, 2] ** 2)
    assert 0.6 * surface.mean_square_slope < between <= surface.mean_square_slope


def test_waves_travel_toward_direction_deg() -> None:
    params = OceanParams(wind_speed=8.0, direction_deg=90.0, choppiness=0.0, fft_cascades=1)
    total = 0.0j
    for seed in range(8):
        cascade = FFTOcean.from_params(replace(params, seed=seed)).cascades[0]
        energy = np.abs(cascade.h0) ** 2
        total += np.sum(energy * np.exp(1j * np.arctan2(cascade.ky, cascade.kx)))
    assert math.degrees(np.angle(total)) == pytest.approx(90.0, abs=2.0)
