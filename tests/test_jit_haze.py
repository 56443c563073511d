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
