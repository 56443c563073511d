"""seahaze's multi-jittered sampler against Mitsuba's ``multijitter``: the same numbers, and one
kernel for every sample count."""

from __future__ import annotations

import numpy as np
import pytest

pytestmark = pytest.mark.usefixtures("mitsuba_variant")

PIXELS = 37


def _draws(sampler, count: int = 6) -> list[np.ndarray]:
    """``count`` draws alternating next_2d and next_1d, as arrays."""
    out = []
    for k in range(count):
        if k % 2:
            out.append(np.array(sampler.next_1d()))
        else:
            point = sampler.next_2d()
            out += [np.array(point.x), np.array(point.y)]
    return out


def _mitsuba(spp: int, seed: int):
    import mitsuba as mi

    sampler = mi.load_dict({"type": "multijitter", "sample_count": spp})
    sampler.set_sample_count(spp)
    sampler.set_samples_per_wavefront(spp)
    sampler.seed(seed, PIXELS * spp)
    return sampler


@pytest.mark.parametrize("spp", [1, 2, 4, 6, 9, 12, 30, 42])
def test_the_same_numbers_as_mitsubas_multijitter(spp):
    from seahaze.render.stratified import StratifiedSampler

    ours = _draws(StratifiedSampler.seeded(spp, 5, PIXELS * spp))
    theirs = _draws(_mitsuba(spp, 5))
    for a, b in zip(ours, theirs, strict=True):
        np.testing.assert_array_equal(a, b)
    # Stratified: each pixel's first 1D draw puts one sample in each of its spp strata.
    strata = np.floor(ours[2].reshape(PIXELS, spp) * spp).astype(int)
    assert all(sorted(row) == list(range(spp)) for row in strata)


def _kernel_hashes(draw) -> set[str]:
    import drjit as dr

    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        dr.kernel_history()  # empties it
        dr.eval(draw())
        return {str(k["hash"]) for k in dr.kernel_history()}
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)


def test_one_kernel_for_every_sample_count():
    from seahaze.render.stratified import StratifiedSampler

    def ours(spp):
        sampler = StratifiedSampler.seeded(spp, 3, PIXELS * spp)
        return lambda: (sampler.next_2d(), sampler.next_1d())

    def theirs(spp):
        sampler = _mitsuba(spp, 3)
        return lambda: (sampler.next_2d(), sampler.next_1d())

    assert _kernel_hashes(ours(6)) == _kernel_hashes(ours(30))
    assert _kernel_hashes(theirs(6)) != _kernel_hashes(theirs(30))  # what this module is for


def test_a_count_that_does_not_fill_mitsubas_grid_is_refused():
    from seahaze.render.stratified import StratifiedSampler, grid_of

    assert grid_of(30) == (6, 5) and grid_of(32) == (7, 5)
    with pytest.raises(ValueError, match="7 x 5 grid"):
        StratifiedSampler.seeded(32, 0, PIXELS * 32)
