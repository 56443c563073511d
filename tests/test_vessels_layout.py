"""Layouts: placement frame, overlap rejection, sampler reproducibility and place_on_sea."""

from __future__ import annotations

import numpy as np
import pytest

from seahaze.vessels import (
    CLASS_NAMES,
    VESSEL_CLASSES,
    ExplicitVessel,
    LayoutError,
    Placement,
    build_vessel,
    min_air_draft_m,
    place_explicit,
    place_on_sea,
    sample_layout,
)
from seahaze.vessels.layout import (
    bearing_interval,
    footprint_corners,
    image_overlap,
    sample_distance,
)

try:  # hypothesis is a test extra; the seed-loop property tests below run without it
    from hypothesis import given, settings
    from hypothesis import strategies as st
except ImportError:  # pragma: no cover
    given = None

WEIGHTS = {"container_ship": 1, "tanker": 1, "tug": 2, "sailboat": 2, "buoy": 1, "speedboat": 2}


# ------------------------------------------------------------- independent overlap check
def _segments_cross(p1, p2, q1, q2) -> bool:
    def orient(a, b, c):
        return np.sign((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))

    return (orient(p1, p2, q1) != orient(p1, p2, q2)) and (orient(q1, q2, p1) != orient(q1, q2, p2))


def _inside(point, quad) -> bool:
    signs = [
        np.sign(
            (quad[(i + 1) % 4][0] - quad[i][0]) * (point[1] - quad[i][1])
            - (quad[(i + 1) % 4][1] - quad[i][1]) * (point[0] - quad[i][0])
        )
        for i in range(4)
    ]
    return all(s >= 0 for s in signs) or all(s <= 0 for s in signs)


def quads_intersect(a: np.ndarray, b: np.ndarray) -> bool:
    """Edge-crossing + containment test (a different method from the library's SAT)."""
    for i in range(4):
        for j in range(4):
            if _segments_cross(a[i], a[(i + 1) % 4], b[j], b[(j + 1) % 4]):
                return True
    return _inside(a[0], b) or _inside(b[0], a)


def assert_no_overlap(placements: list[Placement], separation: float) -> None:
    quads = [footprint_corners(p, 0.5 * separation) for p in placements]
    for i in range(len(quads)):
        assert not _inside((0.0, 0.0), quads[i]), f"{placements[i]} covers the camera"
        for j in range(i):
            assert not quads_intersect(quads[i], quads[j]), (placements[i], placements[j])


# ---------------------------------------------------------------------------- explicit
def test_explicit_positions_follow_the_documented_frame() -> None:
    rng = np.random.default_rng(0)
    ahead, left = place_explicit(
        [
            ExplicitVessel("tug", 500.0, 0.0, 90.0, 30.0),
            ExplicitVessel("buoy", 300.0, 30.0, 0.0, 2.0),
        ],
        camera_heading_deg=0.0,
        rng=rng,
    )
    assert (ahead.x, ahead.y) == pytest.approx((500.0, 0.0))
    assert left.y > 0  # positive bearing = to the left (counter-clockwise)
    assert np.hypot(left.x, left.y) == pytest.approx(300.0)
    assert np.degrees(np.arctan2(left.y, left.x)) == pytest.approx(30.0)
    (north,) = place_explicit([ExplicitVessel("tug", 500.0, 0.0, 0.0, 30.0)], 90.0, rng)
    assert (north.x, north.y) == pytest.approx((0.0, 500.0), abs=1e-9)


def test_explicit_accepts_mappings_and_samples_missing_lengths_reproducibly() -> None:
    items = [{"kind": "tanker", "distance_m": 2000.0, "bearing_deg": -5.0, "heading_deg": 10.0}]
    a = place_explicit(items, 0.0, np.random.default_rng(3))
    b = place_explicit(items, 0.0, np.random.default_rng(3))
    assert a == b
    lo, hi = VESSEL_CLASSES["tanker"].length_range_m
    assert lo <= a[0].length_m <= hi


def test_explicit_overlap_is_rejected_naming_both_vessels() -> None:
    items = [
        ExplicitVessel("container_ship", 1000.0, 0.0, 90.0, 300.0),
        ExplicitVessel("tug", 1000.0, 0.5, 0.0, 30.0),  # ~9 m to the left: on top of it
    ]
    with pytest.raises(LayoutError, match=r"#0 container_ship.*#1 tug.*overlap"):
        place_explicit(items, 0.0, np.random.default_rng(0))


def test_explicit_separation_is_enforced() -> None:
    items = [
        ExplicitVessel("buoy", 500.0, 0.0, 0.0, 2.0),
        ExplicitVessel("buoy", 510.0, 0.0, 0.0, 2.0),
    ]
    place_explicit(items, 0.0, np.random.default_rng(0), min_separation_m=5.0)
    with pytest.raises(LayoutError, match="overlap"):
        place_explicit(items, 0.0, np.random.default_rng(0), min_separation_m=20.0)


def test_explicit_vessel_on_top_of_the_camera_is_rejected() -> None:
    with pytest.raises(LayoutError, match="camera"):
        place_explicit(
            [ExplicitVessel("tanker", 50.0, 0.0, 0.0, 300.0)], 0.0, np.random.default_rng(0)
        )


def test_explicit_rejects_unknown_kind_and_bad_length() -> None:
    rng = np.random.default_rng(0)
    with pytest.raises(ValueError, match="allowed kinds"):
        place_explicit([ExplicitVessel("yacht", 100.0, 0.0, 0.0)], 0.0, rng)
    with pytest.raises(ValueError, match=r"\[20, 40\] m"):
        place_explicit([ExplicitVessel("tug", 100.0, 0.0, 0.0, 80.0)], 0.0, rng)


def test_user_mesh_footprint_uses_its_own_beam_and_length() -> None:
    # Two vessels heading along +x, 20 m apart across: a library tug (L 30, largest beam
    # 0.5 L = 15 m) at y = 0 and a user mesh at y = +20 with a given beam. Their rectangles
    # touch when 15/2 + beam/2 >= 20, i.e. for a beam of 25 m or more.
    lateral = np.degrees(np.arctan2(20.0, 1000.0))
    distance = float(np.hypot(1000.0, 20.0))
    tug = ExplicitVessel("tug", 1000.0, 0.0, 0.0, 30.0)
    rng = np.random.default_rng(0)
    narrow = ExplicitVessel("tug", distance, lateral, 0.0, 80.0, beam_m=20.0)
    placements = place_explicit([tug, narrow], 0.0, rng)  # 80 m: outside the tug range, allowed
    assert placements[1].beam_m == 20.0 and placements[1].length_m == 80.0
    corners = footprint_corners(placements[1])
    assert np.ptp(corners[:, 1]) == pytest.approx(20.0) and np.ptp(corners[:, 0]) == 80.0
    wide = ExplicitVessel("tug", distance, lateral, 0.0, 80.0, beam_m=26.0)
    with pytest.raises(LayoutError, match="overlap"):
        place_explicit([tug, wide], 0.0, rng)
    with pytest.raises(ValueError, match="needs its length_m"):
        place_explicit([ExplicitVessel("tug", 500.0, 0.0, 0.0, beam_m=5.0)], 0.0, rng)


# ----------------------------------------------------------------------------- sampler
def _sample(seed: int, **overrides) -> list[Placement]:
    args = dict(
        count=6,
        class_weights=WEIGHTS,
        distance_range_m=(100.0, 4000.0),
        distribution="log",
        bearing_spread_deg=50.0,
        min_separation_m=20.0,
        camera_heading_deg=30.0,
        rng=np.random.default_rng(seed),
    )
    args.update(overrides)
    return sample_layout(**args)


def test_sampled_layout_is_reproducible_from_the_seed() -> None:
    assert _sample(7) == _sample(7)
    assert _sample(7) != _sample(8)


@pytest.mark.parametrize("distribution", ["log", "uniform", "linear_depth"])
def test_sampled_layouts_never_overlap(distribution: str) -> None:
    # Crowded on purpose (narrow sector, short range) so rejections really happen.
    for seed in range(40):
        placements = _sample(
            seed,
            count=8,
            distance_range_m=(150.0, 1500.0),
            distribution=distribution,
            bearing_spread_deg=20.0,
            min_separation_m=30.0,
        )
        assert len(placements) == 8
        assert_no_overlap(placements, 30.0)


if given is not None:

    @settings(max_examples=60, deadline=None)
    @given(
        seed=st.integers(0, 2**32 - 1),
        count=st.integers(1, 8),
        d_min=st.floats(100.0, 800.0),
        span=st.floats(200.0, 3500.0),
        spread=st.floats(5.0, 90.0),
        separation=st.floats(0.0, 100.0),
        heading=st.floats(-180.0, 180.0),
        distribution=st.sampled_from(["log", "uniform", "linear_depth"]),
        kinds=st.lists(st.sampled_from(CLASS_NAMES), min_size=1, max_size=4, unique=True),
    )
    def test_property_sampled_layouts_never_overlap(
        seed, count, d_min, span, spread, separation, heading, distribution, kinds
    ) -> None:
        args = dict(
            count=count,
            class_weights=dict.fromkeys(kinds, 1.0),
            distance_range_m=(d_min, d_min + span),
            distribution=distribution,
            bearing_spread_deg=spread,
            min_separation_m=separation,
            camera_heading_deg=heading,
        )
        try:
            placements = sample_layout(**args, rng=np.random.default_rng(seed))
        except LayoutError:
            return  # a crowded draw may legitimately not fit: the error is the contract
        assert placements == sample_layout(**args, rng=np.random.default_rng(seed))
        assert_no_overlap(placements, separation)


def test_sampled_values_respect_ranges_and_field_of_view() -> None:
    for seed in range(20):
        for p in _sample(seed, horizontal_fov_deg=40.0):
            assert 100.0 <= p.distance_m <= 4000.0
            half_size = np.degrees(np.arctan2(0.5 * p.length_m, p.distance_m))
            assert abs(p.bearing_deg) <= max(20.0 - half_size, 0.0) + 1e-9
            assert abs(p.bearing_deg) <= 25.0
            assert p.kind in WEIGHTS
            lo, hi = VESSEL_CLASSES[p.kind].length_range_m
            assert lo <= p.length_m <= hi
            az = np.radians(30.0 + p.bearing_deg)
            assert (p.x, p.y) == pytest.approx(
                (p.distance_m * np.cos(az), p.distance_m * np.sin(az))
            )


def test_zero_weight_classes_are_never_drawn() -> None:
    for seed in range(10):
        kinds = {p.kind for p in _sample(seed, class_weights={"tug": 1.0, "tanker": 0.0})}
        assert kinds == {"tug"}


@pytest.mark.parametrize(
    ("distribution", "expected_median"),
    [
        ("uniform", 2050.0),
        ("log", np.sqrt(100.0 * 4000.0)),
        ("linear_depth", np.sqrt((100.0**2 + 4000.0**2) / 2)),
    ],
)
def test_distance_distributions_have_the_documented_shape(distribution, expected_median) -> None:
    rng = np.random.default_rng(0)
    d = np.array([sample_distance((100.0, 4000.0), distribution, rng) for _ in range(4000)])
    assert d.min() >= 100.0 and d.max() <= 4000.0
    assert np.median(d) == pytest.approx(expected_median, rel=0.06)


def test_impossible_layout_raises_a_clear_error() -> None:
    with pytest.raises(LayoutError, match="could not place vessel"):
        _sample(
            0,
            count=30,
            class_weights={"container_ship": 1},
            distance_range_m=(600, 700),
            bearing_spread_deg=5.0,
            max_attempts_per_vessel=50,
        )


def test_sampler_argument_errors() -> None:
    with pytest.raises(ValueError, match="distribution"):
        _sample(0, distribution="gaussian")
    with pytest.raises(ValueError, match="allowed kinds"):
        _sample(0, class_weights={"frigate": 1.0})
    with pytest.raises(ValueError, match="positive sum"):
        _sample(0, class_weights={"tug": 0.0})


# --------------------------------------------------------------------------- to world
@pytest.fixture(scope="module")
def tug():
    return build_vessel("tug", 30.0, np.random.default_rng(1))


def test_place_on_sea_puts_the_waterline_at_the_sea_height(tug) -> None:
    placement = Placement("tug", 400.0, -50.0, 0.0, 30.0, 403.1, -7.1)
    placed = place_on_sea(tug, placement, height_fn=lambda x, y: 2.5)
    assert [p.name for p in placed] == tug.part_names
    z_min = min(p.vertices[:, 2].min() for p in placed)
    assert z_min == pytest.approx(2.5 - tug.draft_m, abs=1e-3)
    for part, original in zip(placed, tug.parts, strict=True):
        assert part.vertices.dtype == np.float32 and part.faces.dtype == np.uint32
        np.testing.assert_array_equal(part.faces, original.mesh.faces)
        assert part.material == original.material
    flat = place_on_sea(tug, placement)  # no height_fn: sea level 0
    assert min(p.vertices[:, 2].min() for p in flat) == pytest.approx(-tug.draft_m, abs=1e-3)


@pytest.mark.parametrize("heading", [0.0, 90.0, 215.0])
def test_place_on_sea_rotates_the_bow_to_the_heading(tug, heading: float) -> None:
    placement = Placement("tug", 100.0, 200.0, heading, 30.0, 223.6, 63.4)
    hull = place_on_sea(tug, placement)[tug.part_names.index("hull")]
    bow_index = int(np.argmax(tug.part("hull").mesh.vertices[:, 0]))
    bow = hull.vertices[bow_index, :2] - np.array([100.0, 200.0])
    assert np.linalg.norm(bow) == pytest.approx(15.0, rel=0.02)
    assert np.degrees(np.arctan2(bow[1], bow[0])) % 360 == pytest.approx(heading, abs=0.5)


def test_place_on_sea_follows_the_slope_when_asked(tug) -> None:
    slope = 0.05  # sea surface rising toward +x (a long swell face)
    placement = Placement("tug", 0.0, 100.0, 0.0, 30.0, 100.0, 90.0)
    hull_index = tug.part_names.index("hull")
    bow_index = int(np.argmax(tug.part("hull").mesh.vertices[:, 0]))
    stern_index = int(np.argmin(tug.part("hull").mesh.vertices[:, 0]))

    def height(x: float, y: float) -> float:
        return slope * x

    level = place_on_sea(tug, placement, height)[hull_index].vertices
    pitched = place_on_sea(tug, placement, height, follow_slope=True)[hull_index].vertices
    body = np.asarray(tug.part("hull").mesh.vertices)
    body_rise = body[bow_index, 2] - body[stern_index, 2]
    # Without follow_slope the hull only heaves: bow-stern height difference as built.
    assert level[bow_index, 2] - level[stern_index, 2] == pytest.approx(body_rise, abs=1e-3)
    rise = pitched[bow_index, 2] - pitched[stern_index, 2]
    run = pitched[bow_index, 0] - pitched[stern_index, 0]
    pitch = np.arctan(slope)
    # Bow-up rotation by atan(slope): the body's bow-stern line turns by exactly that angle.
    assert np.arctan2(rise, run) == pytest.approx(pitch + np.arctan2(body_rise, 30.0), abs=2e-3)
    # An analytic slope function gives the same attitude as the finite differences.
    analytic = place_on_sea(
        tug, placement, height, slope_fn=lambda x, y: (slope, 0.0), follow_slope=True
    )[hull_index].vertices
    np.testing.assert_allclose(analytic, pitched, atol=1e-3)


def test_sea_callbacks_receive_arrays_like_an_ocean_surface(tug) -> None:
    calls = []

    def height(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        calls.append((x.shape, y.shape))
        return 0.1 * np.sin(0.05 * x) + 0.0 * y

    placement = Placement("tug", 120.0, 40.0, 30.0, 30.0, 126.5, 18.4)
    placed = place_on_sea(tug, placement, height, follow_slope=True)
    assert calls and all(len(sx) == 1 and sx == sy for sx, sy in calls)
    z_min = min(p.vertices[:, 2].min() for p in placed)
    assert np.isfinite(z_min)


# --------------------------------------------------------------------------- image overlap
def _angles_seen(placement: Placement) -> np.ndarray:
    """The azimuths (deg, 0..360) of a footprint's corners seen from the camera at the origin:
    an independent route to its bearing interval (the tests keep vessels away from 0/360)."""
    corners = footprint_corners(placement)
    return np.degrees(np.arctan2(corners[:, 1], corners[:, 0])) % 360.0


def test_image_overlap_is_the_shared_share_of_the_narrower_interval() -> None:
    assert image_overlap((0.0, 1.0), (0.5, 2.0)) == pytest.approx(0.5)
    assert image_overlap((0.0, 1.0), (0.2, 0.4)) == pytest.approx(1.0)
    assert image_overlap((0.0, 1.0), (1.5, 2.0)) == 0.0
    # Across ±π: (π - 0.2, π + 0.1) and (-π - 0.1, -π + 0.3) share 0.2 rad of the first 0.3.
    a, b = (np.pi - 0.2, np.pi + 0.1), (-np.pi - 0.1, -np.pi + 0.3)
    assert image_overlap(a, b) == pytest.approx(0.2 / 0.3)


def test_bearing_interval_spans_the_footprints_corners() -> None:
    tug = Placement("tug", 0.0, 300.0, 30.0, 30.0, 300.0, 90.0)
    lo, hi = bearing_interval(footprint_corners(tug))
    seen = _angles_seen(tug)
    assert np.degrees(lo) == pytest.approx(seen.min()) and np.degrees(hi) == pytest.approx(
        seen.max()
    )
    # Behind the camera, across ±180°: one short interval around 180°, not a whole circle.
    astern = Placement("tug", -300.0, 0.0, 90.0, 30.0, 300.0, 180.0)
    lo, hi = bearing_interval(footprint_corners(astern))
    assert 0.0 < hi - lo < np.radians(10.0) and abs(0.5 * (lo + hi)) == pytest.approx(
        np.pi, abs=0.05
    )


def _shared(a: Placement, b: Placement) -> float:
    """The share of the narrower corner-angle interval the two share (degrees, no wrap)."""
    sa, sb = _angles_seen(a), _angles_seen(b)
    shared = min(sa.max(), sb.max()) - max(sa.min(), sb.min())
    return max(shared, 0.0) / min(np.ptp(sa), np.ptp(sb))


def test_sampled_vessels_keep_apart_in_the_image_when_asked() -> None:
    crowded = dict(
        count=6, distance_range_m=(200.0, 2000.0), bearing_spread_deg=60.0, camera_heading_deg=90.0
    )
    overlapping = 0
    for seed in range(10):
        free = _sample(seed, **crowded)
        overlapping += sum(_shared(a, b) > 0.1 for i, a in enumerate(free) for b in free[i + 1 :])
        kept = _sample(seed, **crowded, max_image_overlap=0.1)
        assert len(kept) == 6
        assert all(_shared(a, b) <= 0.1 + 1e-9 for i, a in enumerate(kept) for b in kept[i + 1 :])
    assert overlapping > 0  # the rule had work to do: without it these layouts overlap


def test_a_layout_the_overlap_rule_cannot_meet_says_so() -> None:
    with pytest.raises(LayoutError, match="raise max_image_overlap"):
        # Twelve hulls 150-160 m off within 5° cannot all stand side by side in the image.
        _sample(
            1,
            count=12,
            distance_range_m=(150.0, 160.0),
            bearing_spread_deg=5.0,
            max_image_overlap=0.0,
        )


# --------------------------------------------------------------------------- detectable share
@pytest.mark.parametrize("kind", CLASS_NAMES)
def test_every_built_vessel_stands_at_least_its_class_floor(kind: str) -> None:
    # Seeds past the 30 the floor was read from: the floor holds for vessels it never saw.
    lo, hi = VESSEL_CLASSES[kind].length_range_m
    for seed in range(100, 112):
        for length in (lo, 0.5 * (lo + hi), hi):
            model = build_vessel(kind, length, np.random.default_rng(seed))
            assert model.air_draft_m >= min_air_draft_m(kind, model.length_m) - 1e-9


def test_the_detectable_share_stands_near_enough_to_look_tall_enough() -> None:
    mrad = 14.4

    def near(kind: str, length: float) -> float:
        return 1000.0 * min_air_draft_m(kind, length) / mrad

    for seed in range(20):
        placements = _sample(
            seed, count=6, distance_range_m=(150.0, 4000.0), near_enough=near, n_near=3
        )
        for p in placements[:3]:
            # Built as the world builds it: its real height, not the floor, subtends at least so.
            assert 1000.0 * min_air_draft_m(p.kind, p.length_m) / p.distance_m >= mrad - 1e-9
    without = [p for seed in range(20) for p in _sample(seed, distance_range_m=(150.0, 4000.0))]
    small = [
        p for p in without if 1000.0 * min_air_draft_m(p.kind, p.length_m) / p.distance_m < mrad
    ]
    assert small  # without the rule many vessels look smaller than that
