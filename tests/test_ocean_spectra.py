"""Physics checks of the wave spectra, spreading functions and dispersion."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate

from seahaze.ocean import spectra
from seahaze.ocean.spectra import SeaSpectrum

G = 9.81


def _peak_of(spectrum_fn, lo: float, hi: float) -> float:
    omega = np.linspace(lo, hi, 200_001)
    return float(omega[np.argmax(spectrum_fn(omega))])


def test_deep_water_dispersion_round_trip() -> None:
    k = np.array([1e-3, 0.1, 1.0, 10.0])
    omega = spectra.deep_water_omega(k)
    np.testing.assert_allclose(omega**2, G * k)
    np.testing.assert_allclose(spectra.deep_water_wavenumber(omega), k)
    np.testing.assert_allclose(spectra.deep_water_group_velocity(omega), 0.5 * omega / k)


@pytest.mark.parametrize("u10", [3.0, 10.0, 20.0])
def test_pierson_moskowitz_peak_and_hs(u10: float) -> None:
    u19_5 = spectra.wind_speed_19_5_from_10(u10)
    assert u19_5 == pytest.approx(1.026 * u10)
    peak = _peak_of(lambda w: spectra.pierson_moskowitz(w, u19_5), 0.1, 5.0)
    assert peak == pytest.approx(0.877 * G / u19_5, rel=1e-3)  # Stewart (2008) eq. 16.30
    m0, _ = integrate.quad(
        lambda w: spectra.pierson_moskowitz(np.array([w]), u19_5)[0], 0.0, 60.0 * peak, limit=400
    )
    # Stewart (2008) eq. 16.32: m0 = 2.74e-3 U^4/g^2, Hs = 0.21 U19.5^2/g.
    assert m0 == pytest.approx(2.74e-3 * u19_5**4 / G**2, rel=3e-3)
    assert spectra.significant_wave_height(m0) == pytest.approx(0.21 * u19_5**2 / G, rel=5e-3)


def test_jonswap_fetch_laws_and_full_development() -> None:
    u10, fetch_km = 10.0, 20.0
    expected_peak = 22.0 * (G * G / (u10 * fetch_km * 1e3)) ** (1.0 / 3.0)
    assert spectra.jonswap_peak_frequency(u10, fetch_km) == pytest.approx(expected_peak)
    chi = G * fetch_km * 1e3 / u10**2
    assert spectra.jonswap_alpha(u10, fetch_km) == pytest.approx(0.076 * chi**-0.22)
    found = _peak_of(lambda w: spectra.jonswap(w, u10, fetch_km), 0.2, 5.0)
    assert found == pytest.approx(expected_peak, rel=1e-3)
    # Beyond full development the peak sits at the Pierson-Moskowitz frequency.
    pm_peak = 0.877 * G / (1.026 * u10)
    assert spectra.jonswap_peak_frequency(u10, 5000.0) == pytest.approx(pm_peak, rel=2e-3)
    # Longer fetch: lower peak, more energy.
    short = SeaSpectrum("jonswap", wind_speed=u10, fetch_km=10.0)
    long = SeaSpectrum("jonswap", wind_speed=u10, fetch_km=100.0)
    assert long.peak_omega < short.peak_omega
    assert long.significant_wave_height > short.significant_wave_height


def test_jonswap_shape_gamma_one_is_pierson_moskowitz() -> None:
    u19_5 = 12.0
    omega_p = spectra.pierson_moskowitz_peak_frequency(u19_5)
    omega = np.linspace(0.2, 4.0, 500)
    np.testing.assert_allclose(
        spectra.jonswap_shape(omega, omega_p, spectra.PHILLIPS_CONSTANT, gamma=1.0),
        spectra.pierson_moskowitz(omega, u19_5),
        rtol=1e-12,
    )
    # gamma multiplies the peak value exactly.
    ratio = spectra.jonswap_shape(np.array([omega_p]), omega_p, 0.01, gamma=3.3) / (
        spectra.jonswap_shape(np.array([omega_p]), omega_p, 0.01, gamma=1.0)
    )
    assert ratio[0] == pytest.approx(3.3)


def test_phillips_is_tessendorf_cutoff() -> None:
    u10 = 8.0
    k = np.linspace(0.01, 2.0, 50)
    omega = spectra.deep_water_omega(k)
    big_l = u10**2 / G
    # Tessendorf: exp(-1/(kL)^2) cut-off on the Phillips omega^-5 range.
    expected = spectra.PHILLIPS_CONSTANT * G**2 / omega**5 * np.exp(-1.0 / (k * big_l) ** 2)
    np.testing.assert_allclose(spectra.phillips(omega, u10), expected, rtol=1e-12)
    hs = SeaSpectrum("phillips", wind_speed=u10).significant_wave_height
    assert hs == pytest.approx(2.0 * math.sqrt(spectra.PHILLIPS_CONSTANT) * u10**2 / G, rel=1e-4)


@pytest.mark.parametrize("s", [0.3, 1.0, 10.0, 75.0])
def test_cos2s_spreading_is_normalised_and_centred(s: float) -> None:
    theta = np.linspace(-math.pi, math.pi, 200_001)
    d = spectra.cos2s_spreading(theta, 0.7, s)
    assert integrate.trapezoid(d, theta) == pytest.approx(1.0, rel=1e-6)
    assert theta[np.argmax(d)] == pytest.approx(0.7, abs=1e-4)


def test_cos2_spreading_is_normalised_one_sided() -> None:
    theta = np.linspace(-math.pi, math.pi, 200_001)
    d = spectra.cos2_spreading(theta, math.pi / 2)
    assert integrate.trapezoid(d, theta) == pytest.approx(1.0, rel=1e-6)
    assert np.all(d[np.sin(theta) < 0.0] == 0.0)  # nothing travels against the wind


def test_wavenumber_spectrum_integrates_to_m0() -> None:
    spectrum = SeaSpectrum("jonswap", wind_speed=10.0, fetch_km=50.0, mean_direction=1.0)
    kp = spectrum.peak_wavenumber
    k = np.geomspace(0.2 * kp, 200.0 * kp, 3000)
    theta = np.linspace(-math.pi, math.pi, 721)
    kk, tt = np.meshgrid(k, theta, indexing="ij")
    psi = spectrum.wavenumber_spectrum(kk * np.cos(tt), kk * np.sin(tt))
    m0 = integrate.trapezoid(integrate.trapezoid(psi * kk, theta, axis=1), k)
    assert m0 == pytest.approx(spectrum.variance(), rel=2e-3)
    # Energy travels toward the mean direction.
    mean_dir = np.angle(np.sum(psi * kk * np.exp(1j * tt)))
    assert mean_dir == pytest.approx(1.0, abs=1e-3)
