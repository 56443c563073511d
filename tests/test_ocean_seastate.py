"""Sea-state consistency: the generated surfaces carry the Hs, peak period and slope variance of
the spectrum they sample, at every wind speed of the documented range.

Hs is measured as ``4·std(eta)`` of the world-space elevation (``height``, choppy surfaces
included) over many independent points and seeds; the peak period from a measured spectrum
(FFT: the periodogram of the largest patch mapped to frequency with ``omega = sqrt(g k)``;
Gerstner: the frequency spectrum of elevation time series at fixed points, as a wave buoy
measures it), smoothed with a Gaussian of ``0.05·omega_p``.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import replace

import numpy as np
import pytest

from seahaze.ocean import FFTOcean, GerstnerOcean, OceanParams, make_surface
from seahaze.ocean.cox_munk import mean_square_slope, slope_budget

G = 9.81
WINDS = (3.0, 7.0, 12.0, 15.0)
SEAS = (("pierson_moskowitz", 100.0), ("jonswap", 20.0), ("jonswap", 120.0))
FFT_SEEDS = range(8)
GERSTNER_SEEDS = range(32)  # 16 frequencies per seed: many seeds for a smooth spectrum


def _smoothed_peak(omega: np.ndarray, density: np.ndarray, omega_p: float) -> float:
    """Frequency (rad/s) of the maximum of ``density`` smoothed with a Gaussian of
    ``0.05·omega_p`` (only between ``0.3`` and ``3`` nominal peak frequencies)."""
    sigma = 0.05 * omega_p
    kernel = np.exp(-0.5 * ((omega[:, None] - omega[None, :]) / sigma) ** 2)
    smooth = kernel @ density
    window = (omega > 0.3 * omega_p) & (omega < 3.0 * omega_p)
    return float(omega[np.argmax(np.where(window, smooth, 0.0))])


def _measure_fft(params: OceanParams) -> tuple[float, float]:
    """``(Hs, Tp)`` measured from FFT surfaces (m, s)."""
    omega_p = params.sea_spectrum().peak_omega
    edges = np.arange(0.25 * omega_p, 3.0 * omega_p, omega_p / 100.0)
    energy = np.zeros(len(edges) - 1)
    variances = []
    for seed in FFT_SEEDS:
        surface = make_surface(replace(params, seed=seed))
        assert isinstance(surface, FFTOcean)
        patch = surface.cascades[0]
        n, size = patch.resolution, patch.size_m
        x, y = np.random.default_rng(100 + seed).uniform(0.0, 4.0 * size, (2, 20_000))
        variances.append(np.var(surface.height(x, y)))
        nodes = np.arange(n) * (size / n)
        h = surface.displacement(*np.meshgrid(nodes, nodes))[2]
        power = np.abs(np.fft.fft2(h) / n**2) ** 2
        k1 = 2.0 * math.pi * np.fft.fftfreq(n, d=size / n)
        omega = np.sqrt(G * np.hypot(*np.meshgrid(k1, k1)))
        energy += np.histogram(omega.ravel(), edges, weights=power.ravel())[0]
    centres = 0.5 * (edges[1:] + edges[:-1])
    peak = _smoothed_peak(centres, energy, omega_p)
    return 4.0 * math.sqrt(float(np.mean(variances))), 2.0 * math.pi / peak


def _measure_gerstner(params: OceanParams) -> tuple[float, float]:
    """``(Hs, Tp)`` from elevation time series at 16 fixed rest positions (a Lagrangian buoy),
    1024 samples of ``Tp/8``."""
    omega_p = params.sea_spectrum().peak_omega
    dt, n_t = (2.0 * math.pi / omega_p) / 8.0, 1024
    omega = 2.0 * math.pi * np.fft.rfftfreq(n_t, dt)
    psd = np.zeros_like(omega)
    variances = []
    for seed in GERSTNER_SEEDS:
        surface = make_surface(replace(params, seed=seed))
        assert isinstance(surface, GerstnerOcean)
        reach = 50.0 * surface.peak_wavelength_m
        x, y = np.random.default_rng(100 + seed).uniform(-reach, reach, (2, 16))
        series = surface.elevation_series(x, y, np.arange(n_t) * dt)
        variances.append(np.var(series))
        spectrum = np.fft.rfft(series * np.hanning(n_t), axis=1)
        psd += np.mean(np.abs(spectrum) ** 2, axis=0)
    peak = _smoothed_peak(omega, psd, omega_p)
    return 4.0 * math.sqrt(float(np.mean(variances))), 2.0 * math.pi / peak


@pytest.mark.parametrize("model", ["fft", "gerstner"])
@pytest.mark.parametrize(("spectrum", "fetch_km"), SEAS)
@pytest.mark.parametrize("u10", WINDS)
def test_measured_hs_and_peak_period_match_the_spectrum(
    model: str, spectrum: str, fetch_km: float, u10: float
) -> None:
    """Hs and Tp measured from the generated field within 10 % of the spectrum's own
    (``Hs = 4 sqrt(m0)``, ``Tp = 2 pi/omega_p``); default choppiness 0.8."""
    params = OceanParams(model=model, spectrum=spectrum, wind_speed=u10, fetch_km=fetch_km)
    target = params.sea_spectrum()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a clamped choppiness does not change heights
        measure = _measure_fft if model == "fft" else _measure_gerstner
        hs, tp = measure(params)
    assert hs == pytest.approx(target.significant_wave_height, rel=0.10)
    assert tp == pytest.approx(target.peak_period, rel=0.10)


def test_gerstner_elevation_series_is_the_displacement_over_time() -> None:
    surface = make_surface(OceanParams(model="gerstner", wind_speed=8.0, seed=3))
    assert isinstance(surface, GerstnerOcean)
    x, y = np.array([0.0, 13.0, -40.0]), np.array([5.0, -7.0, 22.0])
    times = np.array([0.0, 1.7, 9.3])
    series = surface.elevation_series(x, y, times)
    for j, t in enumerate(times):
        np.testing.assert_allclose(series[:, j], surface.at_time(t).displacement(x, y)[2])


def test_fft_resolved_moments_match_the_sampled_pyramid() -> None:
    """At spacings where the pyramid level is an integer the filtered field at that level's
    grid nodes is exact: its variance equals ``resolved_moments``; spacing 0 gives everything."""
    params = OceanParams(wind_speed=9.0, fetch_km=60.0, choppiness=0.0, fft_cascades=1, seed=4)
    surface = make_surface(params)
    assert isinstance(surface, FFTOcean)
    assert surface.resolved_moments(0.0) == pytest.approx(
        (surface.height_variance, surface.mean_square_slope), rel=1e-9
    )
    patch = surface.cascades[0]
    for level in (1, 2, 3):
        spacing = patch.spacing_m * 2.0 ** (level - 0.5)
        m = patch.resolution // 2**level
        nodes = np.arange(m) * (patch.size_m / m)
        x, y = np.meshgrid(nodes, nodes)
        h = surface.displacement_filtered(x, y, spacing)[2]
        variance, mss = surface.resolved_moments(spacing)
        assert np.mean(h**2) == pytest.approx(variance, rel=1e-9)
        assert mss < surface.mean_square_slope


@pytest.mark.parametrize("model", ["fft", "gerstner"])
@pytest.mark.parametrize(
    ("spectrum", "fetch_km"), [("pierson_moskowitz", 100.0), ("jonswap", 20.0)]
)
def test_resolved_and_sub_grid_slopes_add_up_to_cox_munk(
    model: str, spectrum: str, fetch_km: float
) -> None:
    """At every wind of the documented range (1-25 m/s) the generator resolves less slope
    variance than Cox & Munk's (1954) total ``0.003 + 5.12e-3 U``, so the microfacets carry
    a non-negative rest and ``resolved + sub_grid = total`` exactly, at every mesh spacing."""
    for u10 in (1.0, 2.0, 3.0, 5.0, 7.0, 10.0, 12.0, 15.0, 20.0, 25.0):
        params = OceanParams(
            model=model, spectrum=spectrum, wind_speed=u10, fetch_km=fetch_km, seed=1
        )
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            surface = make_surface(params)
        previous = math.inf
        for spacing in (0.0, 0.5, 2.0, 8.0, 32.0):
            budget = slope_budget(u10, surface, spacing)
            assert budget.total == pytest.approx(mean_square_slope(u10))
            assert 0.0 <= budget.resolved < budget.total - 0.003
            assert budget.closes
            assert budget.resolved + budget.sub_grid == pytest.approx(budget.total, rel=1e-12)
            assert budget.alpha == pytest.approx(math.sqrt(budget.total - budget.resolved))
            assert budget.resolved <= previous  # coarser meshes resolve less
            previous = budget.resolved
        assert slope_budget(u10, surface, 1e5).resolved == pytest.approx(0.0, abs=1e-12)
