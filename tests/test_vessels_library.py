"""Procedural vessel library: watertight parts, declared dimension ranges, frame conventions."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import assert_parts_within_reported_size
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
    """Every opaque part is a closed body; a translucent one (a sail) is a single open sheet
    (tests/test_sails.py)."""
    for seed in SEEDS:
        model = built[(kind, seed)]
        assert model.parts
        for part in model.parts:
            mesh = part.mesh
            if part.material.transmittance > 0.0:
                assert mesh.euler_number == 1 and mesh.area > 0.0, f"{kind}: {part.name}"
                continue
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


# --------------------------------------------------------------- tug and fishing boat details
CRAFT_SEEDS = tuple(range(8))


@pytest.fixture(scope="module")
def craft() -> dict[tuple[str, int], VesselModel]:
    """Tugs and fishing boats for more seeds than ``built`` (their gear is drawn at random)."""
    return {
        (kind, seed): build_vessel(kind, None, np.random.default_rng(seed))
        for kind in ("tug", "fishing_boat")
        for seed in CRAFT_SEEDS
    }


def _hull_half_width(model: VesselModel, x: float, z: float) -> float:
    """Half-breadth (m) of the hull surface at (x, z), read off the hull loft's station loops
    (its last two vertices are the end caps' centres): each station's port side interpolated
    in z, then the two stations around x interpolated in x."""
    v = np.asarray(model.part("hull").mesh.vertices)[:-2]
    stations = np.unique(v[:, 0])
    i = int(np.clip(np.searchsorted(stations, x), 1, len(stations) - 1))

    def at(xs: float) -> float:
        loop = v[(v[:, 0] == xs) & (v[:, 1] > 0.0)]
        order = np.argsort(loop[:, 2])
        return float(np.interp(z, loop[order, 2], loop[order, 1]))

    x0, x1 = stations[i - 1], stations[i]
    t = float(np.clip((x - x0) / (x1 - x0), 0.0, 1.0))
    return (1.0 - t) * at(x0) + t * at(x1)


def _hull_deck_z(model: VesselModel, x: float) -> float:
    """Deck-edge height (m) of the hull at x: its stations' tops interpolated."""
    v = np.asarray(model.part("hull").mesh.vertices)[:-2]
    stations = np.unique(v[:, 0])
    tops = [v[v[:, 0] == s, 2].max() for s in stations]
    return float(np.interp(x, stations, tops))


def _hull_deck_z_bounds(model: VesselModel, x: float) -> tuple[float, float]:
    """Lower and higher deck-edge height (m) of the two hull stations either side of x (the
    deck between them lies between the two, even on a forecastle's short ramp)."""
    v = np.asarray(model.part("hull").mesh.vertices)[:-2]
    stations = np.unique(v[:, 0])
    i = int(np.clip(np.searchsorted(stations, x), 1, len(stations) - 1))
    tops = (v[v[:, 0] == stations[i - 1], 2].max(), v[v[:, 0] == stations[i], 2].max())
    return float(min(tops)), float(max(tops))


def _bodies(model: VesselModel, name: str) -> list:
    """The disjoint bodies of part ``name``."""
    return model.part(name).mesh.split(only_watertight=False)


def test_a_tugs_rubber_fenders_ring_the_sheer_and_cover_the_bow(craft) -> None:
    for seed in CRAFT_SEEDS:
        model = craft[("tug", seed)]
        half_l = 0.5 * model.length_m
        v = np.asarray(model.part("fender").mesh.vertices)
        # Every fender vertex stands 0.2-0.45 m proud of the hull (the D-fender 0.25-0.45 m,
        # the bow block 85 % of it; 3 cm for reading the curved bow off its stations): on the
        # hull's outline, not inside it or off it.
        # (Leaving out the end caps' centres, on the centreline.)
        side = v[(np.abs(v[:, 0]) < 0.45 * model.length_m) & (np.abs(v[:, 1]) > 0.1)]
        offsets = [abs(y) - _hull_half_width(model, x, z) for x, y, z in side]
        assert min(offsets) >= 0.2 and max(offsets) <= 0.48, (seed, min(offsets), max(offsets))
        # Along the whole midbody the fender's top follows the sheer, 5 cm under the deck edge.
        mid = v[np.abs(v[:, 0]) < 0.3 * model.length_m]
        xs = np.unique(mid[:, 0])
        assert len(xs) >= 8 and np.ptp(xs) > 0.5 * model.length_m, seed
        for x in xs:
            top = mid[mid[:, 0] == x, 2].max()
            lo, hi = _hull_deck_z_bounds(model, x)
            assert lo - 0.08 <= top <= hi - 0.02, (seed, x)
        # The bow carries rubber from the deck down to 0.4 m above the water.
        bow = v[v[:, 0] > half_l - 0.1 * model.length_m]
        assert bow[:, 2].min() == pytest.approx(0.4, abs=0.01), seed
        assert _hull_deck_z(model, 0.45 * model.length_m) > 2.5


def test_a_tugs_tyres_hang_against_its_sides_inside_the_beam(craft) -> None:
    for seed in CRAFT_SEEDS:
        model = craft[("tug", seed)]
        tyres = _bodies(model, "tyres")
        port = [t for t in tyres if t.bounds[0, 1] > 0.0]
        assert len(port) >= 5 and len(tyres) == 2 * len(port), seed
        for tyre in tyres:
            (x0, y0, z0), (x1, y1, z1) = tyre.bounds
            # Truck tyres 1.0-1.2 m across (decagons: 0.95 of that across the flats), their
            # centres above the water (where the freeboard is low they dip into it).
            assert 0.95 <= z1 - z0 <= 1.2 + 1e-9 and 0.95 <= x1 - x0 <= 1.2 + 1e-9
            assert z0 >= -0.25 and z0 + z1 > 0.0
            inner, outer = min(abs(y0), abs(y1)), max(abs(y0), abs(y1))
            hull = _hull_half_width(model, 0.5 * (x0 + x1), 0.5 * (z0 + z1))
            assert inner <= hull <= outer, seed  # resting against the hull
            assert outer <= 0.5 * model.beam_m, seed  # inside the D-fender's line
            assert -0.5 * model.length_m < x0 and x1 < 0.5 * model.length_m


def test_a_tugs_wheelhouse_is_glazed_all_round_and_set_forward(craft) -> None:
    for seed in CRAFT_SEEDS:
        model = craft[("tug", seed)]
        house = max(_bodies(model, "superstructure"), key=lambda b: b.bounds[1, 2])
        (hx0, hy0, hz0), (hx1, hy1, hz1) = house.bounds
        assert 0.5 * (hx0 + hx1) > 0.0, seed  # forward of midships
        glazing = max(_bodies(model, "windows"), key=lambda b: b.bounds[1, 2])
        (gx0, gy0, gz0), (gx1, gy1, gz1) = glazing.bounds
        # Proud of the wheelhouse's front, back and both sides: windows all round, at least
        # 1.0 m tall (IMO MSC/Circ.982: sill at most 1.0 m, head at least 2.0 m up).
        assert gx0 < hx0 and gx1 > hx1 and gy0 < hy0 and gy1 > hy1, seed
        assert gz1 - gz0 >= 1.0 and hz0 < gz0 < gz1 < hz1, seed


def test_a_tugs_afterdeck_carries_a_towing_winch_and_bitt(craft) -> None:
    for seed in CRAFT_SEEDS:
        model = craft[("tug", seed)]
        house_aft = model.part("superstructure").mesh.bounds[0, 0]
        for name in ("towing_winch", "towing_bitt"):
            (x0, y0, z0), (x1, y1, z1) = model.part(name).mesh.bounds
            assert -0.5 * model.length_m < x0 and x1 < house_aft, (seed, name)
            deck = _hull_deck_z(model, 0.5 * (x0 + x1))
            assert z0 <= deck < deck + 1.0 <= z1, (seed, name)  # standing on the deck
            assert max(abs(y0), abs(y1)) < 0.5 * model.beam_m
        # The winch's drum lies across the ship, between its two cheeks.
        winch = _bodies(model, "towing_winch")
        drums = [b for b in winch if np.ptp(b.bounds[:, 1]) > 1.5 * np.ptp(b.bounds[:, 0])]
        assert len(drums) == 1 and len(winch) == 3, seed


def test_a_fishing_boats_gantry_stands_at_its_stern(craft) -> None:
    with_gantry = 0
    for seed in CRAFT_SEEDS:
        model = craft[("fishing_boat", seed)]
        if "gantry" not in model.part_names:
            continue
        with_gantry += 1
        (x0, y0, _), (x1, y1, z1) = model.part("gantry").mesh.bounds
        # Within the hull's length, over the last ~13 % of it, at least 3 m above the deck.
        assert -0.5 * model.length_m <= x0 and x1 < -0.37 * model.length_m + 0.6, seed
        assert z1 > _hull_deck_z(model, x0) + 3.0, seed
        assert max(abs(y0), abs(y1)) < 0.5 * model.beam_m
        # An "A" from the side: a leg and a brace meet at the top, apart at the deck.
        legs = [b for b in _bodies(model, "gantry") if b.bounds[1, 1] > 0.0 > b.bounds[0, 1]]
        assert legs  # the top beam, across the ship
        feet = np.asarray(model.part("gantry").mesh.vertices)
        low = feet[feet[:, 2] < _hull_deck_z(model, x0) + 0.2]
        assert np.ptp(low[:, 0]) > 1.0, seed
    assert with_gantry >= 4


def test_a_fishing_boats_net_drum_stands_on_its_open_deck(craft) -> None:
    drums = 0
    for seed in CRAFT_SEEDS:
        model = craft[("fishing_boat", seed)]
        if "net_drum" not in model.part_names:
            continue
        drums += 1
        (x0, y0, z0), (x1, y1, _) = model.part("net_drum").mesh.bounds
        assert y1 - y0 > x1 - x0, seed  # its axis across the ship
        assert max(abs(y0), abs(y1)) < 0.5 * model.beam_m
        assert -0.5 * model.length_m < x0 and x1 < 0.5 * model.length_m
        assert z0 > _hull_deck_z(model, 0.5 * (x0 + x1)), seed
        for house in _bodies(model, "superstructure"):  # clear of the deckhouse
            assert x1 < house.bounds[0, 0] or x0 > house.bounds[1, 0], seed
    assert drums >= 5


def test_a_fishing_boats_rust_streaks_lie_on_its_topsides(craft) -> None:
    for seed in CRAFT_SEEDS:
        model = craft[("fishing_boat", seed)]
        v = np.asarray(model.part("rust").mesh.vertices)
        for x, y, z in v[np.abs(v[:, 1]) > 0.1]:  # not the end caps' centres
            hull = _hull_half_width(model, x, z)
            # A few mm proud; 2 cm either way for reading the hull off its stations.
            assert hull - 0.02 <= abs(y) <= hull + 0.03, (seed, x, z, abs(y) - hull)
            assert 0.3 <= z <= _hull_deck_z_bounds(model, x)[1], (seed, x, z)


@pytest.mark.parametrize("kind", ["tug", "fishing_boat"])
def test_every_part_lies_inside_the_reported_length_beam_and_air_draft(craft, kind) -> None:
    for seed in CRAFT_SEEDS:
        model = craft[(kind, seed)]
        assert_parts_within_reported_size(model, seed)


@pytest.mark.parametrize(("kind", "most_faces"), [("tug", 9000), ("fishing_boat", 7000)])
def test_small_craft_are_deterministic_and_light(craft, kind: str, most_faces: int) -> None:
    for seed in CRAFT_SEEDS[:3]:
        again = build_vessel(kind, None, np.random.default_rng(seed))
        model = craft[(kind, seed)]
        assert again.part_names == model.part_names
        for a, b in zip(again.parts, model.parts, strict=True):
            np.testing.assert_array_equal(a.mesh.vertices, b.mesh.vertices)
            assert a.material == b.material
        # A scene renders many vessels: a few thousand triangles each.
        assert sum(len(p.mesh.faces) for p in model.parts) < most_faces
    other = craft[(kind, 1)]
    assert other.part_names != craft[(kind, 0)].part_names or not np.array_equal(
        other.part("hull").mesh.vertices, craft[(kind, 0)].part("hull").mesh.vertices
    )
