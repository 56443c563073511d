"""The drjit haze formulas the physical integrator traces agree with the numpy originals."""

from __future__ import annotations

import numpy as np
import pytest

from seahaze import haze
from seahaze.render import jit_haze


@pytest.fixture(scope="module")
def dr_float(mitsuba_variant):
    import mitsuba as mi

    return mi.Float


def test_slab_interval_matches_numpy(dr_float) -> None:
    rng = np.random.default_rng(3)
    oz = rng.uniform(-100.0, 500.0, 4000)
    dz = rng.uniform(-1.0, 1.0, 4000)
    # Horizontal rays inside and outside the slab, and rays straight up and down.
    oz[:4], dz[:4] = [10.0, 400.0, 10.0, 10.0], [0.0, 0.0, 1.0, -1.0]
    enter, leave = jit_haze.slab_interval(dr_float(oz), dr_float(dz), -60.0, 300.0)
    expected_enter, expected_leave = haze.slab_interval(oz, dz, -60.0, 300.0)
    np.testing.assert_allclose(np.array(enter), expected_enter, rtol=1e-5, atol=1e-3)
    np.testing.assert_allclose(np.array(leave), expected_leave, rtol=1e-5, atol=1e-3)


@pytest.mark.parametrize("g", [0.0, 0.75, -0.3])
def test_hg_phase_matches_numpy(dr_float, g: float) -> None:
    cos = np.linspace(-1.0, 1.0, 2001)
    got = np.array(jit_haze.hg_phase(dr_float(cos), g))
    np.testing.assert_allclose(got, haze.hg_phase(cos, g), rtol=2e-5)
    # And the numpy original is a normalised phase function: 2π ∫ p dμ = 1.
    assert abs(2 * np.pi * np.trapezoid(haze.hg_phase(cos, g), cos) - 1.0) < 1e-3


@pytest.mark.parametrize("g", [0.0, 0.75])
def test_hg_sampling_and_rotation_match_numpy(dr_float, g: float) -> None:
    rng = np.random.default_rng(5)
    u = rng.random(5000)
    np.testing.assert_allclose(
        np.array(jit_haze.hg_sample_cos(dr_float(u), g)), haze.hg_sample_cos(u, g), atol=2e-5
    )
    d = rng.normal(size=(5000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    d[0] = [0.0, 0.0, -1.0]  # the frame's singular direction for the other sign
    cos_t, phi = haze.hg_sample_cos(rng.random(5000), g), 2 * np.pi * rng.random(5000)
    expected = haze.rotate_directions(d, cos_t, phi)
    got = jit_haze.rotate_directions(
        tuple(dr_float(d[:, i]) for i in range(3)), dr_float(cos_t), dr_float(phi)
    )
    np.testing.assert_allclose(np.stack([np.array(c) for c in got], axis=1), expected, atol=1e-4)
    # The rotated vector is at the requested angle from d.
    np.testing.assert_allclose(np.sum(expected * d, axis=1), cos_t, atol=1e-9)


def test_sun_scattered_fraction_matches_quadrature(dr_float) -> None:
    """The closed form (and its series for tiny optical depths) against the trapezoid rule on
    the integrand, for segments climbing, descending and flat, in thin and dense haze."""
    rng = np.random.default_rng(11)
    n = 400
    sigma = 3.912 / rng.choice([50.0, 300.0, 1000.0, 4000.0, 1e7], n)
    depth = rng.uniform(0.0, 600.0, n)  # metres toward the sun from the segment's start
    climb = rng.uniform(-1.5, 2.5, n)
    climb[:20] = 0.0  # a segment that keeps its optical depth toward the sun
    climb[20:40] = 1e-6
    length = rng.uniform(0.0, 2000.0, n)
    # A physical segment ends below the slab's top: its depth toward the sun stays >= 0.
    rising = climb < 0.0
    length[rising] = np.minimum(length[rising], depth[rising] / -climb[rising])
    e_start = sigma * depth
    with np.errstate(divide="ignore"):
        inv_climb = 1.0 / climb
    got = jit_haze.sun_scattered_fraction(
        dr_float(sigma),
        dr_float(np.exp(-e_start)),
        dr_float(e_start),
        dr_float(climb),
        dr_float(inv_climb),
        dr_float(length),
    )
    s = np.linspace(0.0, 1.0, 20001)[None, :] * length[:, None]
    integrand = np.exp(-(e_start[:, None] + sigma[:, None] * climb[:, None] * s))
    expected = sigma * np.trapezoid(integrand, s, axis=1)
    np.testing.assert_allclose(np.array(got), expected, rtol=2e-4, atol=1e-9)
