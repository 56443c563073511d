"""Procedural vessel library: watertight parts, declared dimension ranges, frame conventions."""

from __future__ import annotations

import numpy as np
import pytest

from seahaze.vessels import CLASS_NAMES, VESSEL_CLASSES, build_vessel, class_id
from seahaze.vessels.model import VesselModel
from seahaze.world import wind_off_bow

SHIP_KINDS = [k for k in CLASS_NAMES if k != "buoy"]
SEEDS = (0, 1, 2, 3)


@pytest.fixture(scope="module")
def built() -> dict[tuple[str, int], VesselModel]:
    """Every class for a few seeds, built once for the whole module (keeps the suite fast)."""
    return {
        (kind, seed): build_vessel(kind, None, np.random.default_rng(seed))
        for kind in CLASS_NAMES
        for seed in SEEDS
    }


def test_class_names_are_the_stable_yolo_order() -> None:
    # Appending is allowed; reordering would silently relabel every dataset.
    assert CLASS_NAMES[:9] == (
        "container_ship",
        "bulk_carrier",
        "tanker",
        "passenger_ferry",
        "fishing_boat",
        "tug",
        "sailboat",
        "speedboat",
        "buoy",
    )
    assert tuple(VESSEL_CLASSES) == CLASS_NAMES
    assert [class_id(k) for k in CLASS_NAMES] == list(range(len(CLASS_NAMES)))


def test_every_class_documents_ranges_and_sources() -> None:
    for vc in VESSEL_CLASSES.values():
        lo, hi = vc.length_range_m
        assert 0 < lo < hi
        assert 0 < vc.beam_ratio_range[0] <= vc.beam_ratio_range[1]
        assert vc.description and vc.source


@pytest.mark.parametrize("kind", CLASS_NAMES)
def test_every_part_is_watertight_with_positive_volume(built, kind: str) -> None:
    for seed in SEEDS:
        model = built[(kind, seed)]
        assert model.parts
        for part in model.parts:
            mesh = part.mesh
            assert mesh.is_watertight, f"{kind} seed {seed}: {part.name} not watertight"
            assert mesh.is_winding_consistent, f"{kind} seed {seed}: {part.name} winding"
            assert mesh.volume > 0, f"{kind} seed {seed}: {part.name} volume {mesh.volume}"
            assert all(0.0 <= c <= 1.0 for c in part.material.rgb)
            assert 0.0 <= part.material.roughness <= 1.0


@pytest.mark.parametrize("kind", CLASS_NAMES)
def test_dimensions_lie_in_the_declared_ranges(built, kind: str) -> None:
    vc = VESSEL_CLASSES[kind]
    for seed in SEEDS:
        model = built[(kind, seed)]
        lo, hi = vc.length_range_m
        assert lo <= model.length_m <= hi
        ratio = model.beam_m / model.length_m
        assert vc.beam_ratio_range[0] - 1e-9 <= ratio <= vc.beam_ratio_range[1] + 1e-9
        (x0, y0, _), (x1, y1, _) = model.bounds()
        # The mesh really has the stated length and beam (buoy floats are 20-gons: ~1 % less).
        assert x1 - x0 == pytest.approx(model.length_m, rel=0.015)
        assert y1 - y0 == pytest.approx(model.beam_m, rel=0.015, abs=0.05)
        # Frame: origin at midships on the centreline.
        assert (x0 + x1) / 2 == pytest.approx(0.0, abs=0.01 * model.length_m)
        assert (y0 + y1) / 2 == pytest.approx(0.0, abs=0.01 * model.beam_m)


def test_given_length_is_built_exactly() -> None:
    model = build_vessel("tanker", 250.0, np.random.default_rng(5))
    assert model.length_m == 250.0
    (x0, _, _), (x1, _, _) = model.bounds()
    assert x1 - x0 == pytest.approx(250.0, rel=1e-3)


@pytest.mark.parametrize("kind", CLASS_NAMES)
def test_waterline_and_draft(built, kind: str) -> None:
    for seed in SEEDS:
        model = built[(kind, seed)]
        (_, _, z0), (_, _, z1) = model.bounds()
        assert z0 == pytest.approx(-model.draft_m)
        assert model.draft_m > 0 and model.air_draft_m > 0
        assert z1 == pytest.approx(model.air_draft_m)
        # The body straddles the waterline: something below and above z = 0.
        hull = model.part("hull" if kind != "buoy" else "float").mesh
        assert hull.bounds[0, 2] < 0 < hull.bounds[1, 2]


def test_air_drafts_are_plausible(built) -> None:
    # Neopanamax air draft limit is 57.91 m (ACP); the largest ULCVs reach ~70 m.
    for (kind, _seed), model in built.items():
        assert model.air_draft_m < 80.0, kind
        assert model.air_draft_m < 2.0 * model.length_m + 5.0, kind
    ferry = [m for (k, _), m in built.items() if k == "container_ship"]
    assert all(m.air_draft_m > 15.0 for m in ferry)


def _hull_half_beam_near(model: VesselModel, x_frac: float) -> float:
    """Largest |y| of hull vertices within ±3 % L of x = x_frac·L (stations are dense there)."""
    vertices = np.asarray(model.part("hull").mesh.vertices)
    x = x_frac * model.length_m
    band = np.abs(vertices[:, 0] - x) < 0.03 * model.length_m
    assert band.any()
    return float(np.abs(vertices[band, 1]).max())


@pytest.mark.parametrize("kind", SHIP_KINDS)
def test_bow_points_to_positive_x(built, kind: str) -> None:
    for seed in SEEDS:
        model = built[(kind, seed)]
        mid = _hull_half_beam_near(model, 0.0)
        bow = _hull_half_beam_near(model, 0.45)  # 0.95 L from the stern
        stern = _hull_half_beam_near(model, -0.45)
        assert bow < 0.85 * mid, f"{kind} seed {seed}: bow not narrower than midships"
        assert bow < stern, f"{kind} seed {seed}: transom should be wider than the bow"
        # The stem is a point: the very tip of the hull is nearly on the centreline.
        vertices = np.asarray(model.part("hull").mesh.vertices)
        tip = vertices[vertices[:, 0] > 0.499 * model.length_m]
        assert np.abs(tip[:, 1]).max() < 0.1 * model.beam_m


@pytest.mark.parametrize("kind", SHIP_KINDS)
def test_deck_rises_toward_the_bow(built, kind: str) -> None:
    # Sheer / forecastle: the hull is higher at the bow than amidships.
    for seed in SEEDS:
        vertices = np.asarray(built[(kind, seed)].part("hull").mesh.vertices)
        length = built[(kind, seed)].length_m
        top_mid = vertices[np.abs(vertices[:, 0]) < 0.05 * length, 2].max()
        top_bow = vertices[vertices[:, 0] > 0.4 * length, 2].max()
        assert top_bow > top_mid


def test_same_seed_same_vessel_and_different_seed_differs() -> None:
    a = build_vessel("container_ship", None, np.random.default_rng(11))
    b = build_vessel("container_ship", None, np.random.default_rng(11))
    c = build_vessel("container_ship", None, np.random.default_rng(12))
    assert a.part_names == b.part_names
    for pa, pb in zip(a.parts, b.parts, strict=True):
        np.testing.assert_array_equal(pa.mesh.vertices, pb.mesh.vertices)
        assert pa.material == pb.material
    assert a.length_m != c.length_m


def test_container_ship_carries_containers_and_a_bridge_above_them(built) -> None:
    for seed in SEEDS:
        model = built[("container_ship", seed)]
        stacks = [p for p in model.parts if p.name.startswith("containers_")]
        assert stacks
        stack_top = max(p.mesh.bounds[1, 2] for p in stacks)
        assert model.part("superstructure").mesh.bounds[1, 2] > stack_top


def test_containers_are_iso_boxes_in_many_liveries_mostly_the_lines(built) -> None:
    # ISO 668: 40 ft = 12.19 m and 20 ft = 6.058 m long, 2.44 m wide, 2.59 m high (less the
    # 2 cm tier clearance; a bottom tier also reaches 0.5 m down into the hatch coaming).
    for seed in SEEDS:
        stacks = [p for p in built[("container_ship", seed)].parts if p.name.startswith("cont")]
        counts = {}
        for part in stacks:
            corners = np.asarray(part.mesh.vertices).reshape(-1, 8, 3)  # one box per 8 vertices
            extent = corners.max(axis=1) - corners.min(axis=1)
            assert np.all(np.isclose(extent[:, 0], 12.19) | np.isclose(extent[:, 0], 6.058))
            np.testing.assert_allclose(extent[:, 1], 2.44)
            assert np.all(np.isclose(extent[:, 2], 2.57) | np.isclose(extent[:, 2], 3.07))
            counts[part.name] = len(corners)
        total = sum(counts.values())
        assert len(counts) >= 4 and total > 50
        assert max(counts.values()) >= 0.25 * total  # the operating line's own boxes lead


def test_sailboat_has_mast_taller_than_hull_length_and_keel_sets_draft(built) -> None:
    for seed in SEEDS:
        model = built[("sailboat", seed)]
        assert model.part("mast").mesh.bounds[1, 2] > model.length_m
        assert model.part("keel").mesh.bounds[0, 2] == pytest.approx(-model.draft_m)


def test_unknown_kind_lists_allowed_kinds() -> None:
    with pytest.raises(ValueError, match="allowed kinds: container_ship, bulk_carrier"):
        build_vessel("submarine", None, np.random.default_rng(0))


def test_out_of_range_length_states_the_range() -> None:
    with pytest.raises(ValueError, match=r"\[5, 15\] m"):
        build_vessel("speedboat", 40.0, np.random.default_rng(0))


def _boom_angle_deg(model) -> float:
    """The boom's angle off the centreline (deg, positive to port) from its mesh: the line
    from its forward end (at the mast) to its far end."""
    v = np.asarray(model.part("boom").mesh.vertices)
    fwd = v[np.argmax(v[:, 0])]
    aft = v[np.argmax(np.hypot(v[:, 0] - fwd[0], v[:, 1] - fwd[1]))]
    return float(np.degrees(np.arctan2(aft[1] - fwd[1], fwd[0] - aft[0])))


@pytest.mark.parametrize(
    ("wind_from_deg", "boom_deg"),
    [(90.0, -45.0), (-120.0, 60.0), (60.0, -30.0), (180.0, -85.0), (-179.0, 85.0)],
)
def test_a_sailboat_trims_its_boom_to_leeward_by_half_the_winds_angle(wind_from_deg, boom_deg):
    model = build_vessel("sailboat", 12.0, np.random.default_rng(5), wind_from_deg)
    assert "sail_main" in model.part_names and "sail_cover" not in model.part_names
    # The boom's own radius tilts the measured line a little: within 3°.
    assert _boom_angle_deg(model) == pytest.approx(boom_deg, abs=3.0)
    jib = np.asarray(model.part("sail_jib").mesh.vertices)
    assert np.sign(jib[:, 1].sum()) == np.sign(boom_deg)  # the jib to leeward too


def test_a_sailboat_heading_into_the_wind_furls_its_sails() -> None:
    for wind in (0.0, 25.0, -35.0):
        model = build_vessel("sailboat", 12.0, np.random.default_rng(5), wind)
        assert "sail_cover" in model.part_names and "sail_main" not in model.part_names


@pytest.mark.parametrize(
    ("toward", "heading", "expected"),
    [
        (0.0, 0.0, 180.0),
        (0.0, 180.0, 0.0),
        (0.0, 90.0, 90.0),
        (0.0, -90.0, -90.0),
        (30.0, 300.0, -90.0),
    ],
)
def test_the_wind_off_the_bow(toward: float, heading: float, expected: float) -> None:
    # A wind toward +x comes from azimuth 180: dead astern of a bow to +x, ahead of one to -x,
    # on the port beam of a bow to +y (counter-clockwise, port, is positive).
    assert wind_off_bow(toward, heading) == pytest.approx(expected)
