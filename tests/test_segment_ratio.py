"""A later segment's own density ratio through a fog bank (``seahaze.render.segment_ratio``).

* The kernel's ratio of a segment, averaged over its random shift, is the field's reduced
  length over the profile's along it, each integrated independently by Simpson's rule on the
  numpy field: across the edge, from under the thin side up into the bank, up to a surface
  and out of the haze, with the bank drifted and its camera start moved off the origin.
* A single shift lies within one point's share of the truth (16 points), and a segment that
  never leaves the thin side reads its near ratio exactly.
* Only a bank alone is measured this way: patches, or no field, keep the pixel's ratios.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import simpson

from seahaze.haze_field import Bank, Drift, HazeField, Patches
from seahaze.medium import HomogeneousSlab
from seahaze.nonuniform import RAY_REACH_M, NonUniformHaze

pytestmark = pytest.mark.usefixtures("mitsuba_variant")

SLAB = HomogeneousSlab(top=300.0, albedo=0.998, g=0.75)
BANK = Bank(900.0, 75.0, 80.0, 0.2, origin_xy=(40.0, -25.0))
DRIFT = Drift(speed_m_s=4.0, toward_deg=120.0, time_s=30.0)
FIELD = NonUniformHaze(SLAB, HazeField(bank=BANK, drift=DRIFT), 1.07)


def _rays() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Origins on the sea and in the air, directions up steeply and shallowly toward and
    away from the bank, and where each ends (a surface, or ``inf``: out of the haze)."""
    origins = np.array(
        [[40.0, 300.0, 0.0], [0.0, 500.0, 0.0], [10.0, 0.0, 15.0], [5.0, 200.0, 0.0]]
    )
    dirs = np.array([[0.25, 0.96, 0.035], [0.2, 0.9, 0.4], [-0.1, 1.0, 0.002], [0.0, -1.0, 0.05]])
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    t_end = np.array([np.inf, np.inf, 4000.0, np.inf])
    return origins, dirs, t_end


def _kernel_ratios(shift: float) -> np.ndarray:
    import drjit as dr
    import mitsuba as mi

    from seahaze.render.segment_ratio import BankSegments

    origins, dirs, t_end = _rays()
    ray = mi.Ray3f(
        mi.Point3f(*origins.T.astype(np.float32)), mi.Vector3f(*dirs.T.astype(np.float32))
    )
    u = mi.Float(np.full(len(origins), shift, np.float32))
    got = BankSegments(FIELD).ratio(ray, mi.Float(t_end.astype(np.float32)), u, mi.Float(-1.0))
    dr.eval(got)
    return np.asarray(got, np.float64)


def _simpson_ratios() -> np.ndarray:
    origins, dirs, t_end = _rays()
    want = []
    for o, d, end in zip(origins, dirs, t_end, strict=True):
        top = (SLAB.top - o[2]) / d[2]
        length = min(end, top, RAY_REACH_M)
        s = np.linspace(0.0, length, 200_001)
        p = o + s[:, None] * d
        field = simpson(FIELD.density_at(p[:, 0], p[:, 1], p[:, 2]), x=s)
        want.append(field / length)  # the slab's profile: density 1 over the whole stretch
    return np.array(want)


def test_the_mean_over_shifts_is_the_fields_length_over_the_profiles():
    shifts = (np.arange(64) + 0.5) / 64
    mean = np.mean([_kernel_ratios(u) for u in shifts], axis=0)
    want = _simpson_ratios()
    np.testing.assert_allclose(mean, want, rtol=2e-3)
    # The rays differ: some stay mostly in the thin side, some run into the bank.
    assert want.max() > 2.0 * want.min()


def test_one_shift_is_within_a_points_share_and_the_thin_side_reads_its_ratio():
    from seahaze.render.segment_ratio import SEGMENT_POINTS

    want = _simpson_ratios()
    bank_density = FIELD.scale  # m = 1 inside the bank
    for u in (0.05, 0.5, 0.95):
        got = _kernel_ratios(u)
        assert np.all(np.abs(got - want) <= bank_density / SEGMENT_POINTS + 1e-6)
    # Away from the bank (the last ray) every point sees the near side, r · c: one shift
    # is then as good as many.
    np.testing.assert_allclose(want[-1], BANK.near_ratio * FIELD.scale, rtol=1e-3)
    np.testing.assert_allclose(_kernel_ratios(0.3)[-1], want[-1], rtol=1e-4)


def test_only_a_bank_alone_is_measured_along_its_segments():
    from seahaze.render.segment_ratio import BankSegments

    patches = Patches(300.0, 3.0, 60.0, 20.0, seed=5)
    assert BankSegments.suits(FIELD)
    assert not BankSegments.suits(NonUniformHaze(SLAB, HazeField(patches, BANK), 1.0))
    assert not BankSegments.suits(NonUniformHaze(SLAB, HazeField(patches), 1.0))
    assert not BankSegments.suits(SLAB)
    with pytest.raises(ValueError, match="bank alone"):
        BankSegments(NonUniformHaze(SLAB, HazeField(patches), 1.0))
