"""Checks of the Gerstner wave sum."""

from __future__ import annotations

import math
import warnings
from dataclasses import replace

import numpy as np
import pytest

from seahaze.ocean import ChoppinessClampedWarning, GerstnerOcean, OceanParams, make_surface
from seahaze.ocean.base import MIN_STRETCH

G = 9.81


def _grid(surface: GerstnerOcean, periods: float = 3.0, n: int = 500) -> tuple[np.ndarray, ...]:
    coords = np.linspace(0.0, periods * surface.peak_wavelength_m, n)
    return np.meshgrid(coords, coords)


@pytest.mark.parametrize(("frequencies", "directions"), [(16, 4), (4, 1), (1, 1)])
def test_no_loops_at_maximum_steepness(frequencies: int, directions: int) -> None:
    params = OceanParams(
        model="gerstner",
        wind_speed=12.0,
        choppiness=50.0,
        seed=4,
        gerstner_frequencies=frequencies,
        gerstner_directions=directions,
    )
    with pytest.warns(ChoppinessClampedWarning, match="loop limit"):
        surface = make_surface(params)
    assert isinstance(surface, GerstnerOcean)
    steepness_sum = surface.choppiness * np.sum(surface.k * surface.amplitude)
    assert steepness_sum == pytest.approx(1.0 - MIN_STRETCH)
    assert steepness_sum <= 1.0
    x, y = _grid(surface)
    assert surface.jacobian(x, y).min() > 0.0


def test_single_wave_at_the_limit_is_a_sharp_trochoid() -> None:
    """One wave at the limit: the crest is a near-cusp (Jacobian = MIN_STRETCH at the crest)."""
    omega, amplitude = 1.2, 0.5
    k = omega**2 / G
    q = (1.0 - MIN_STRETCH) / (k * amplitude)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ChoppinessClampedWarning)
        wave = GerstnerOcean(
            np.array([omega]), np.array([0.0]), np.array([amplitude]), np.array([0.0]), choppiness=q
        )
    x = np.linspace(-math.pi / k, math.pi / k, 20001)
    jac = wave.jacobian(x, np.zeros_like(x))
    assert jac.min() == pytest.approx(MIN_STRETCH, rel=1e-6)
    assert abs(x[np.argmin(jac)]) < 1e-3  # at the crest (phase 0)


def test_sampled_components_reproduce_band_energy_and_dispersion() -> None:
    params = OceanParams(model="gerstner", wind_speed=10.0, fetch_km=50.0, choppiness=0.0)
    surface = make_surface(params)
    spectrum = params.sea_spectrum()
    band = spectrum.variance(0.0, params.gerstner_max_frequency_ratio * spectrum.peak_omega)
    # Components carry 99.9 % of the band (the lowest 0.1 % is dropped).
    assert surface.significant_wave_height_m == pytest.approx(
        4.0 * math.sqrt(0.999 * band), rel=1e-3
    )
    np.testing.assert_allclose(surface.omega**2, G * surface.k)
    assert surface.omega.size == params.gerstner_frequencies * params.gerstner_directions
    # Frequencies cluster around the spectral peak, directions around the mean direction.
    assert np.median(surface.omega) == pytest.approx(spectrum.peak_omega, rel=0.2)
    assert abs(np.angle(np.mean(np.exp(1j * surface.direction)))) < 0.1
    # Spatial variance of the generated elevation matches the component energy.
    rng = np.random.default_rng(0)
    x, y = rng.uniform(-5e4, 5e4, (2, 20_000))
    z = surface.displacement(x, y)[2]
    assert np.var(z) == pytest.approx(np.sum(surface.amplitude**2) / 2.0, rel=0.05)


def test_seed_determinism() -> None:
    params = OceanParams(model="gerstner", wind_speed=8.0, seed=9)
    x = np.linspace(0.0, 100.0, 50)
    a = make_surface(params).displacement(x, x)
    b = make_surface(params).displacement(x, x)
    c = make_surface(replace(params, seed=10)).displacement(x, x)
    np.testing.assert_array_equal(np.stack(a), np.stack(b))
    assert not np.allclose(a[2], c[2])


def test_height_inverts_displacement_and_normals_are_unit() -> None:
    surface = make_surface(OceanParams(model="gerstner", wind_speed=10.0, choppiness=0.8))
    rng = np.random.default_rng(1)
    x0, y0 = rng.uniform(-100.0, 100.0, (2, 3000))
    dx, dy, dz = surface.displacement(x0, y0)
    assert np.abs(dx).max() > 0.05
    assert np.abs(surface.height(x0 + dx, y0 + dy) - dz).max() < 0.02 * dz.std() + 1e-3
    n = surface.normal(x0, y0)
    np.testing.assert_allclose(np.linalg.norm(n, axis=-1), 1.0, rtol=1e-12)
    assert np.all(n[:, 2] > 0.0)


def test_filtered_displacement_drops_short_components() -> None:
    surface = make_surface(OceanParams(model="gerstner", wind_speed=10.0, choppiness=0.0))
    x = np.linspace(0.0, 500.0, 1000)
    y = np.zeros_like(x)
    np.testing.assert_allclose(
        np.stack(surface.displacement_filtered(x, y, 1e-3)), np.stack(surface.displacement(x, y))
    )
    shortest = 2.0 * math.pi / surface.k.max()
    coarse = surface.displacement_filtered(x, y, 1.01 * shortest / 2.0 * 2.0)
    assert np.std(coarse[2]) < np.std(surface.displacement(x, y)[2])
    flat = surface.displacement_filtered(x, y, 1e6)
    assert np.abs(np.stack(flat)).max() == 0.0
