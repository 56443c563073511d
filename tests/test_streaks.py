"""Wind-blown foam streaks (seahaze.ocean.streaks, issue #32: streaks from force 7).

* Their coverage, integrated over a wide stretch of sea, is the one the module states: none
  below force 7, the whitecap law's ``W`` from force 8 up to the pattern's most.
* They run along the wind: the pattern changes far more slowly along it than across it.
* The render kernel's texture is the numpy definition, and the sea's BSDF and plane model take
  the streaks from force 7 only.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from conftest import small_spec
from seahaze.ocean.streaks import (
    FULL_M_S,
    MEANDER_LENGTH_M,
    MEANDER_M,
    MOST_COVERAGE,
    ONSET_M_S,
    STREAK_REFLECTANCE,
    FoamStreaks,
    noise_1d,
    streak_coverage,
    with_streaks,
)
from seahaze.ocean.whitecaps import whitecap_coverage


def _stretch(streaks: FoamStreaks, across_m: float = 3000.0) -> float:
    """The mean of the streaks' fraction over a stretch ``across_m`` wide across the wind and
    1500 m along it: 0.3 m steps across (a line's Gaussian profile has a standard deviation of
    0.42 m and more, which a sum at that step integrates to far better than 1e-6), 5 m along."""
    az = math.radians(streaks.toward_deg)
    v = np.arange(0.0, across_m, 0.3)
    u = np.arange(0.0, 1500.0, 5.0)
    uu, vv = np.meshgrid(u, v, indexing="ij")
    x = uu * math.cos(az) - vv * math.sin(az)
    y = uu * math.sin(az) + vv * math.cos(az)
    return float(streaks.fraction(x, y).mean())


@pytest.mark.parametrize("wind", [12.0, 15.5, 17.2, 19.0])
def test_the_streaks_cover_what_the_module_states(wind):
    want = streak_coverage(wind)
    got = _stretch(FoamStreaks(wind, 35.0, 11))
    if wind <= ONSET_M_S:
        assert want == 0.0 and got == 0.0
    else:
        # 500 lines across the stretch, each present or not by its hash: a few per cent.
        assert got == pytest.approx(want, rel=0.08)


def test_the_coverage_law_of_the_streaks():
    assert streak_coverage(ONSET_M_S) == 0.0
    assert streak_coverage(FULL_M_S) == pytest.approx(
        min(whitecap_coverage(FULL_M_S), MOST_COVERAGE)
    )
    halfway = 0.5 * (ONSET_M_S + FULL_M_S)
    assert streak_coverage(halfway) == pytest.approx(0.5 * whitecap_coverage(halfway))
    winds = np.linspace(10.0, 30.0, 81)
    coverage = [streak_coverage(w) for w in winds]
    assert np.all(np.diff(coverage) >= 0.0) and max(coverage) == pytest.approx(MOST_COVERAGE)


def test_streaks_run_along_the_wind():
    streaks = FoamStreaks(19.0, 35.0, 4)
    az = math.radians(streaks.toward_deg)
    along = np.array([math.cos(az), math.sin(az)])
    across = np.array([-math.sin(az), math.cos(az)])
    rng = np.random.default_rng(2)
    p = rng.uniform(-500.0, 500.0, (20000, 2))

    def change(direction: np.ndarray, lag: float) -> float:
        a = streaks.fraction(p[:, 0], p[:, 1])
        q = p + lag * direction
        return float(np.mean(np.abs(a - streaks.fraction(q[:, 0], q[:, 1]))))

    # A metre across the wind leaves a line; a metre along it stays on it.
    assert change(across, 1.0) > 3.0 * change(along, 1.0)


def test_the_fibres_do_not_run_along_the_lines_meander():
    # A force-8 sea once showed pairs of rails: the lace was read along each line's meander,
    # so its fibres ran beside one another the length of a streak. Following a line's meander
    # 2 m downwind from points inside streaks, the fraction was then 0.68 correlated with
    # itself; the fibres now wander on their own and cross the streak (0.48 here).
    streaks = FoamStreaks(19.0, 0.0, 4)
    rng = np.random.default_rng(3)
    u, v = rng.uniform(0.0, 5000.0, (2, 400_000))
    before = streaks.fraction(u, v)
    inside = before > 0.25
    u, v, before = u[inside], v[inside], before[inside]
    assert len(u) > 10_000

    def meander(along: np.ndarray) -> np.ndarray:
        return MEANDER_M * noise_1d(
            along / MEANDER_LENGTH_M, np.zeros_like(along), streaks.noise_seed
        )

    after = streaks.fraction(u + 2.0, v + meander(u + 2.0) - meander(u))
    assert np.corrcoef(before, after)[0, 1] < 0.58


def test_streaks_drift_downwind_with_the_surface_current():
    # Wu (1983): the wind-driven surface drift is about 3 % of U10; 12.5 s at 16 m/s is 6 m.
    still, later = FoamStreaks(16.0, 120.0, 8), FoamStreaks(16.0, 120.0, 8, time_s=12.5)
    az = math.radians(120.0)
    rng = np.random.default_rng(9)
    x, y = rng.uniform(-300.0, 300.0, (2, 5000))
    moved = later.fraction(x + 6.0 * math.cos(az), y + 6.0 * math.sin(az))
    assert np.allclose(moved, still.fraction(x, y), atol=1e-9)
    assert not np.allclose(later.fraction(x, y), still.fraction(x, y), atol=1e-3)


def test_streaks_add_to_the_seas_mean_foam():
    streaks = FoamStreaks(19.0, 0.0, 1)
    coverage, reflectance = with_streaks(0.1, 0.2, streaks)
    added = 0.9 * streaks.coverage
    assert coverage == pytest.approx(0.1 + added)
    assert reflectance == pytest.approx((0.1 * 0.2 + added * STREAK_REFLECTANCE) / coverage)
    assert with_streaks(0.1, 0.2, FoamStreaks(12.0, 0.0, 1)) == (0.1, 0.2)


@pytest.mark.usefixtures("mitsuba_variant")
def test_the_kernels_streaks_are_the_numpy_ones():
    import drjit as dr
    import mitsuba as mi

    from seahaze.render.streak_texture import streak_texture

    streaks = FoamStreaks(18.0, -50.0, 987654321, time_s=37.0)  # drifted 20 m
    texture = streak_texture(streaks)
    rng = np.random.default_rng(5)
    # The near sea, where streaks are resolved; positions as the kernel holds them (float32).
    xy = rng.uniform(-300.0, 300.0, (50000, 2)).astype(np.float32)
    si = dr.zeros(mi.SurfaceInteraction3f, len(xy))
    si.p = mi.Point3f(mi.Float(xy[:, 0]), mi.Float(xy[:, 1]), mi.Float(0.0))
    si.shape = mi.ShapePtr(mi.load_dict({"type": "rectangle"}))
    got = np.asarray(texture.eval_1(si), np.float64)
    want = streaks.fraction(xy[:, 0].astype(np.float64), xy[:, 1].astype(np.float64))
    # float32 arithmetic on coordinates of a few hundred metres: ~3e-5 m, on lace 0.4 m long.
    assert np.max(np.abs(got - want)) < 5e-4
    assert np.mean(np.abs(got - want)) < 1e-5
    assert want.max() > 0.5  # the points meet the streaks
    # A sample with no shape (the photon tracer's sea samples) reads no streak.
    si.shape = mi.ShapePtr(None)
    assert np.all(np.asarray(texture.eval_1(si)) == 0.0)


@pytest.mark.usefixtures("mitsuba_variant")
@pytest.mark.parametrize("beaufort", [6, 8])
def test_the_sea_takes_streaks_from_force_7(beaufort):
    from seahaze.render.engine import open_session
    from seahaze.world import wind_speed

    sea = {"beaufort": beaufort, "quality": "low", "seed": 3}
    spec = small_spec(sea=sea, haze={"levels": [2000]})
    session = open_session(spec)
    loaded, geometry = session.loaded, session.geometry
    streaks = FoamStreaks(wind_speed(spec), spec.sea.direction_deg, 0)
    want = with_streaks(geometry.sea_foam_coverage, geometry.sea_foam_reflectance, streaks)
    assert (loaded.sea_foam_coverage, loaded.sea_foam_reflectance) == pytest.approx(want)
    # Force 8 adds the streaks to the plane model of the sea; force 6 has none.
    assert (loaded.sea_foam_coverage > geometry.sea_foam_coverage) == (beaufort == 8)
    bsdf = str(loaded.scene.shapes()[0].bsdf()) + "".join(
        str(s.bsdf()) for s in loaded.scene.shapes()
    )
    assert ("FoamStreakTexture" in bsdf) == (beaufort == 8)


def test_the_shipped_gale_has_streaks_and_a_shutter():
    from pathlib import Path

    from seahaze.render.scene import sea_streaks
    from seahaze.sceneio import parse_scene_text

    path = Path(__file__).resolve().parents[1] / "scenes" / "gale.yaml"
    spec = parse_scene_text(path.read_text(), str(path))
    streaks = sea_streaks(spec)
    assert streaks is not None and streaks.coverage == pytest.approx(MOST_COVERAGE)
    assert spec.render.camera_model.shutter_s > 0.0 and spec.sequence is not None
