"""Beaufort presets and Cox–Munk roughness."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from seahaze.ocean import (
    BEAUFORT_SCALE,
    FlatSurface,
    beaufort_force_for_wind,
    beaufort_wave_height,
    beaufort_wind_speed,
    beckmann_alpha,
    cox_munk_alpha,
    cox_munk_anisotropic_alpha,
    make_surface,
    mean_square_slope,
    ocean_params_for_beaufort,
    sub_grid_roughness,
)
from seahaze.ocean.cox_munk import mean_square_slope_components


def test_beaufort_table_is_monotone_and_contiguous() -> None:
    forces = [row.force for row in BEAUFORT_SCALE]
    assert forces == list(range(13))
    winds = [beaufort_wind_speed(f) for f in forces]
    heights = [beaufort_wave_height(f) for f in forces]
    assert all(b > a for a, b in itertools.pairwise(winds))
    assert all(b > a for a, b in itertools.pairwise(heights[1:]))
    assert heights[0] == 0.0
    for lower, upper in itertools.pairwise(BEAUFORT_SCALE):
        assert upper.wind_min == pytest.approx(lower.wind_max + 0.1)  # 0.1 m/s resolution
        assert lower.wind_min <= lower.wind_speed <= lower.wind_max
    assert beaufort_wind_speed(4) == pytest.approx(6.7)
    assert beaufort_wave_height(7) == 4.0


@pytest.mark.parametrize("force", range(13))
def test_force_for_nominal_wind_round_trips(force: int) -> None:
    assert beaufort_force_for_wind(beaufort_wind_speed(force)) == force


def test_presets_reach_the_table_height_where_the_sea_can() -> None:
    assert isinstance(make_surface(ocean_params_for_beaufort(0)), FlatSurface)
    for force in (4, 6, 7, 9):
        params = ocean_params_for_beaufort(force)
        hs = params.sea_spectrum().significant_wave_height
        assert hs == pytest.approx(beaufort_wave_height(force), rel=1e-3)
    # Forces 2 and 5: the table height exceeds a fully developed wind sea at the nominal wind
    # (Pierson-Moskowitz Hs = 0.21 U19.5²/g: 0.13 m and 1.96 m), so the preset is fully
    # developed. (Force 5 reached 2.0 m before the JONSWAP spectrum was capped at full
    # development.)
    for force in (2, 5):
        u19_5 = 1.026 * beaufort_wind_speed(force)
        hs = ocean_params_for_beaufort(force).sea_spectrum().significant_wave_height
        assert hs < beaufort_wave_height(force)
        assert hs == pytest.approx(0.21 * u19_5**2 / 9.81, rel=0.015)


def test_rougher_sea_state_has_larger_hs_and_slope_variance() -> None:
    calm = make_surface(ocean_params_for_beaufort(2, seed=1))
    rough = make_surface(ocean_params_for_beaufort(7, seed=1))
    assert rough.significant_wave_height_m > 5.0 * calm.significant_wave_height_m
    assert 4.0 * math.sqrt(rough.height_variance) > 4.0 * math.sqrt(calm.height_variance)
    assert rough.mean_square_slope > 1.2 * calm.mean_square_slope
    # The microfacet part grows with the wind as well.
    assert cox_munk_alpha(beaufort_wind_speed(7)) > cox_munk_alpha(beaufort_wind_speed(2))


def test_cox_munk_mean_square_slope_at_10_m_s() -> None:
    assert mean_square_slope(10.0) == pytest.approx(0.0542, abs=1e-12)
    up, cross = mean_square_slope_components(10.0)
    assert up + cross == pytest.approx(0.0538)  # the component fits sum to ~ the total fit
    assert cox_munk_alpha(10.0) == pytest.approx(math.sqrt(0.0542))


def test_beckmann_alpha_matches_gaussian_slope_statistics() -> None:
    """Mitsuba's Beckmann slope density exp(-(p² + q²)/alpha²)/(pi alpha²) has per-axis
    variance alpha²/2, so the total mean square slope is alpha²."""
    alpha = beckmann_alpha(0.0542)
    p = np.linspace(-2.0, 2.0, 2001)
    pp, qq = np.meshgrid(p, p)
    density = np.exp(-(pp**2 + qq**2) / alpha**2) / (math.pi * alpha**2)
    cell = (p[1] - p[0]) ** 2
    assert np.sum(density) * cell == pytest.approx(1.0, rel=1e-6)
    assert np.sum((pp**2 + qq**2) * density) * cell == pytest.approx(0.0542, rel=1e-6)
    au, av = cox_munk_anisotropic_alpha(10.0)
    up, cross = mean_square_slope_components(10.0)
    assert (au**2 / 2.0, av**2 / 2.0) == pytest.approx((up, cross))


def test_sub_grid_roughness_subtracts_resolved_slopes() -> None:
    total = mean_square_slope(10.0)
    assert sub_grid_roughness(10.0) == pytest.approx(cox_munk_alpha(10.0))
    assert sub_grid_roughness(10.0, 0.02) == pytest.approx(math.sqrt(total - 0.02))
    assert sub_grid_roughness(10.0, 1.0) == pytest.approx(math.sqrt(0.003))
    surface = make_surface(ocean_params_for_beaufort(5, seed=0))
    expected = math.sqrt(total - surface.mean_square_slope)
    assert sub_grid_roughness(10.0, surface) == pytest.approx(expected)


@pytest.mark.parametrize("wind", [3.0, 8.0, 15.0])
def test_mesh_roughness_gives_every_vertex_its_slope_budget(wind: float) -> None:
    """Two Beckmann lobes mixed per vertex carry exactly the microfacet slope variance each
    vertex's budget leaves: Cox–Munk's total less what its band-limited, faded displacement
    resolves (``slope_budget`` at its spacing, times the fade squared). The near lobe is the
    budget at the finest spacing, the far lobe Cox–Munk's full alpha, and the flat far sea
    gets the far lobe alone."""
    from seahaze.ocean import (
        OceanParams,
        build_sea_mesh_data,
        cox_munk_alpha,
        make_surface,
        mesh_roughness,
        slope_budget,
    )

    surface = make_surface(OceanParams(model="fft", wind_speed=wind, fetch_km=50.0, seed=2))
    mesh = build_sea_mesh_data(surface, camera_height_m=12.0, quality="low")
    spacing, fade = mesh.vertex_spacing_m, mesh.vertex_fade
    mix = mesh_roughness(wind, surface, spacing, fade)
    assert mix.alpha_far == pytest.approx(cox_munk_alpha(wind))
    assert mix.alpha_near == pytest.approx(slope_budget(wind, surface, spacing.min()).alpha)
    assert mix.alpha_near < mix.alpha_far
    rng = np.random.default_rng(4)
    for i in rng.choice(np.nonzero(fade > 0.0)[0], 40, replace=False):
        budget = slope_budget(wind, surface, float(spacing[i]))
        expected = budget.total - fade[i] ** 2 * budget.resolved
        assert mix.sub_grid_mean_square_slope()[i] == pytest.approx(expected, rel=0.02)
    np.testing.assert_array_equal(mix.near_weight[fade == 0.0], 0.0)
    assert mix.near_weight.max() == pytest.approx(1.0)
