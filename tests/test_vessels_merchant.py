"""Bulk carrier and tanker gear (issue #32): cranes between the hatches, coamings and covers,
the aft house's height, windows and bridge wings, the tanker's catwalk, manifold and hose
cranes, the lifeboat; the caller's random stream as it was before the gear was added."""

from __future__ import annotations

from itertools import pairwise

import numpy as np
import pytest

from conftest import assert_parts_within_reported_size
from seahaze.vessels import build_vessel
from seahaze.vessels.bulk_tanker import bulk_holds
from seahaze.vessels.model import VesselModel

SEEDS = tuple(range(6))
SUPRAMAX_M = 190.0
"""A Handymax/Supramax bulk carrier's length overall (190-200 m)."""
AFRAMAX_M = 245.0
"""An Aframax tanker's length overall (about 245 m)."""


@pytest.fixture(scope="module")
def ships() -> dict[tuple[str, int], VesselModel]:
    """Supramax bulk carriers and Aframax tankers for a few seeds, built once."""
    return {
        (kind, seed): build_vessel(kind, length, np.random.default_rng(seed))
        for kind, length in (("bulk_carrier", SUPRAMAX_M), ("tanker", AFRAMAX_M))
        for seed in SEEDS
    }


def _bodies(model: VesselModel, name: str) -> list:
    """The disjoint bodies of part ``name``."""
    return model.part(name).mesh.split(only_watertight=False)


def _deck_z(model: VesselModel, x: float) -> float:
    """Deck-edge height (m) of the hull at x: its stations' tops interpolated (the last two
    vertices of the hull loft are its end caps' centres)."""
    v = np.asarray(model.part("hull").mesh.vertices)[:-2]
    stations = np.unique(v[:, 0])
    tops = [v[v[:, 0] == s, 2].max() for s in stations]
    return float(np.interp(x, stations, tops))


def _house(model: VesselModel) -> tuple[float, float, float]:
    """The accommodation's aft and forward x and its wheelhouse roof z (m): the tallest
    superstructure body's top, the longest one's ends."""
    bodies = _bodies(model, "superstructure")
    tiers = max(bodies, key=lambda b: np.ptp(b.bounds[:, 0]))
    top = max(b.bounds[1, 2] for b in bodies)
    return float(tiers.bounds[0, 0]), float(tiers.bounds[1, 0]), float(top)


def _pedestals(model: VesselModel, name: str, least_radius: float) -> list:
    """The pedestals of the cranes of part ``name``: the upright bodies standing on the deck
    at least ``least_radius`` in radius and 5 m tall."""
    found = []
    for body in _bodies(model, name):
        (x0, _, z0), (x1, _, z1) = body.bounds
        deck = _deck_z(model, 0.5 * (x0 + x1))
        if x1 - x0 > 2.0 * least_radius * 0.95 and z0 < deck and z1 - z0 > 5.0:
            found.append(body)
    return found


def test_a_supramaxs_cranes_stand_on_the_centreline_between_its_hatches(ships) -> None:
    geared = 0
    for seed in SEEDS:
        model = ships[("bulk_carrier", seed)]
        covers = sorted((b.bounds for b in _bodies(model, "hatch_covers")), key=lambda b: b[0, 0])
        assert len(covers) == 5, seed  # five holds (Wikipedia "Handymax")
        if "cranes" not in model.part_names:
            continue
        geared += 1
        pedestals = _pedestals(model, "cranes", 1.3)
        assert len(pedestals) == 4, seed  # four cranes
        gaps = [(a[1, 0], b[0, 0]) for a, b in pairwise(covers)]
        for pedestal in pedestals:
            (x0, y0, _), (x1, y1, _) = pedestal.bounds
            assert abs(y0 + y1) < 0.01, seed  # on the centreline
            assert any(a < x0 and x1 < b for a, b in gaps), (seed, x0, x1)  # between hatches
        # Jibs and all: inside the hull's beam and length, over the covers, under the top of
        # the radar mast.
        (cx0, cy0, _), (cx1, cy1, cz1) = model.part("cranes").mesh.bounds
        assert max(abs(cy0), abs(cy1)) < 0.5 * model.beam_m - 5.0
        assert -0.5 * model.length_m < cx0 and cx1 < 0.5 * model.length_m
        assert cz1 > max(c[1, 2] for c in covers) + 5.0, seed
        assert cz1 <= model.part("radar_mast").mesh.bounds[1, 2], seed
    assert geared >= 4  # nine in ten under 215 m


def test_hatch_coamings_stand_above_the_deck_under_their_covers(ships) -> None:
    for seed in SEEDS:
        model = ships[("bulk_carrier", seed)]
        coamings = [b for b in _bodies(model, "hatch_coamings") if np.ptp(b.bounds[:, 0]) > 5.0]
        covers = [b.bounds for b in _bodies(model, "hatch_covers")]
        assert len(coamings) == len(covers) == bulk_holds(model.length_m)
        for coaming in coamings:
            (x0, y0, _), (x1, y1, z1) = coaming.bounds
            xc = 0.5 * (x0 + x1)
            # Coamings about 2 m over the deck (1.6-2.3 m here), across about 0.5-0.62 B.
            assert 1.5 < z1 - _deck_z(model, xc) < 2.5, (seed, z1 - _deck_z(model, xc))
            assert 0.45 * model.beam_m < y1 - y0 < 0.65 * model.beam_m
            cover = next(c for c in covers if c[0, 0] < xc < c[1, 0])
            assert cover[0, 2] == pytest.approx(z1, abs=0.1)  # the cover sits on it
            assert 0.8 < cover[1, 2] - z1 < 1.8  # 0.38 of coaming + cover
            assert cover[0, 0] < x0 and x1 < cover[1, 0]  # and overhangs it
    # Handy sizes to Capesize: five, seven and nine holds.
    assert [bulk_holds(length) for length in (110.0, 190.0, 229.0, 290.0)] == [4, 5, 7, 9]


def test_a_capesize_is_gearless_with_nine_hatches() -> None:
    for seed in range(3):
        model = build_vessel("bulk_carrier", 290.0, np.random.default_rng(seed))
        assert "cranes" not in model.part_names
        assert len(_bodies(model, "hatch_covers")) == 9


@pytest.mark.parametrize("kind", ["bulk_carrier", "tanker"])
def test_the_accommodation_stands_about_20_m_over_the_main_deck(ships, kind) -> None:
    # A Supramax's or MR/Aframax tanker's house: the poop and five or six decks of 2.8 m under
    # a 3.1 m wheelhouse, its roof about 20-23 m over the main deck.
    for seed in SEEDS:
        model = ships[(kind, seed)]
        x_aft, x_fwd, top = _house(model)
        height = top - _deck_z(model, 0.5 * (x_aft + x_fwd))
        assert 19.0 < height < 23.5, (kind, seed, height)
        # Windows in rows: one row of sills per deck above the poop on the house front.
        windows = np.asarray(model.part("windows").mesh.vertices)
        front = windows[(np.abs(windows[:, 0] - x_fwd) < 0.3) & (windows[:, 2] < top - 3.5)]
        assert len(np.unique(np.round(front[:, 2], 2))) >= 2 * 5, (kind, seed)  # sill, head


@pytest.mark.parametrize("kind", ["bulk_carrier", "tanker"])
def test_the_bridge_wings_reach_the_ships_side(ships, kind) -> None:
    for seed in SEEDS:
        model = ships[(kind, seed)]
        _, x_fwd, top = _house(model)
        wings = _bodies(model, "bridge_wings")
        assert len(wings) == 2
        for wing in wings:
            (x0, y0, z0), (x1, y1, z1) = wing.bounds
            outer = max(abs(y0), abs(y1))
            assert 0.5 * model.beam_m - 0.3 < outer <= 0.5 * model.beam_m, (kind, seed, outer)
            assert x0 < x_fwd < x1 + 1.0  # at the wheelhouse's front
            assert top - 4.0 < z0 < z1 < top  # on the bridge deck


def test_a_tankers_manifold_and_hose_cranes_stand_at_midships(ships) -> None:
    for seed in SEEDS:
        model = ships[("tanker", seed)]
        (mx0, my0, _), (mx1, my1, _) = model.part("manifold").mesh.bounds
        midships = 0.05 * model.length_m + 1.0
        assert abs(0.5 * (mx0 + mx1)) < midships, seed
        # Across the ship to 3-4.6 m inboard of either side (flanges and drip trays).
        for y in (my0, my1):
            assert 0.5 * model.beam_m - 6.0 < abs(y) <= 0.5 * model.beam_m, (seed, y)
        pedestals = _pedestals(model, "hose_cranes", 0.85)
        assert len(pedestals) == 2, seed
        xs = sorted(0.5 * (p.bounds[0, 0] + p.bounds[1, 0]) for p in pedestals)
        assert xs[0] < mx0 and mx1 < xs[1], seed  # one either side of the manifold
        assert all(abs(x) < midships + 12.0 for x in xs), (seed, xs)
        (_, cy0, _), (_, cy1, _) = model.part("hose_cranes").mesh.bounds
        assert max(abs(cy0), abs(cy1)) < 0.5 * model.beam_m


def test_a_tankers_catwalk_runs_from_poop_to_forecastle_over_its_pipes(ships) -> None:
    for seed in SEEDS:
        model = ships[("tanker", seed)]
        poop = model.part("poop").mesh.bounds
        (x0, _, _), (x1, _, _) = model.part("catwalk").mesh.bounds
        assert x0 == pytest.approx(poop[1, 0], abs=0.5), seed
        assert x1 > 0.35 * model.length_m, seed  # to the forecastle's foot
        # The plank 2.4-3.0 m over the deck (its underside 0.25 m lower), its rails 1 m over
        # it; the posts' feet in the deck.
        walk = np.asarray(model.part("catwalk").mesh.vertices)
        over = walk[:, 2] - [_deck_z(model, x) for x in walk[:, 0]]
        high = over[over > 1.0]
        assert 2.1 < high.min() < 2.8 and high.max() < 4.1, (seed, high.min(), high.max())
        assert over.min() < 0.0
        # The cargo lines on stools under it: their tops 1.2-2.1 m over the deck.
        pipes = np.asarray(model.part("cargo_pipes").mesh.vertices)
        over = pipes[:, 2] - [_deck_z(model, x) for x in pipes[:, 0]]
        assert 1.1 < over.max() < 2.1 and over.min() < 0.0, seed


@pytest.mark.parametrize("kind", ["bulk_carrier", "tanker"])
def test_the_lifeboat_is_orange_at_the_stern_or_beside_the_house(ships, kind) -> None:
    for seed in SEEDS:
        model = ships[(kind, seed)]
        boats = model.part("lifeboats")
        assert boats.material.name == "lifeboat_orange"
        x_aft, x_fwd, _ = _house(model)
        (x0, y0, z0), (x1, y1, _) = boats.mesh.bounds
        assert x1 < x_fwd and -0.5 * model.length_m < x0, (kind, seed)
        assert max(abs(y0), abs(y1)) < 0.5 * model.beam_m
        assert z0 > _deck_z(model, x0) + 1.0  # on the poop or hung above it
        if "lifeboat_ramp" in model.part_names:  # freefall: bow down aft, at the stern
            v = np.asarray(boats.mesh.vertices)
            assert v[np.argmin(v[:, 0]), 2] < v[np.argmax(v[:, 0]), 2], (kind, seed)
            assert x0 < x_aft


def _deck_half_breadth(model: VesselModel, x: float) -> float:
    """Half-breadth (m) of the hull's deck edge at x: its stations' widest points
    interpolated."""
    v = np.asarray(model.part("hull").mesh.vertices)[:-2]
    stations = np.unique(v[:, 0])
    widths = [np.abs(v[v[:, 0] == s, 1]).max() for s in stations]
    return float(np.interp(x, stations, widths))


@pytest.mark.parametrize("kind", ["bulk_carrier", "tanker"])
def test_the_windlasses_stand_on_the_forecastle_inside_its_deck(ships, kind) -> None:
    for seed in SEEDS:
        model = ships[(kind, seed)]
        bodies = _bodies(model, "windlass")
        assert len(bodies) == 4, (kind, seed)  # a bed and a drum a side
        for side in (-1.0, 1.0):
            mine = [b.bounds for b in bodies if side * b.bounds[:, 1].mean() > 0.0]
            (x0, _, z0), (x1, _, _) = np.min(mine, axis=0)[0], np.max(mine, axis=0)[1]
            deck = _deck_z(model, 0.5 * (x0 + x1))
            assert deck > _deck_z(model, 0.0) + 2.0, (kind, seed)  # on the raised forecastle
            assert z0 < deck, (kind, seed)  # its bed in the deck
            inside = min(_deck_half_breadth(model, x) for x in (x0, x1))
            assert max(np.abs(b[:, 1]).max() for b in mine) < inside, (kind, seed)


@pytest.mark.parametrize("kind", ["bulk_carrier", "tanker"])
def test_every_part_lies_inside_the_reported_length_beam_and_air_draft(ships, kind) -> None:
    for seed in SEEDS:
        model = ships[(kind, seed)]
        assert_parts_within_reported_size(model, seed)


# The caller's next draw after each build, as the builders left it before their gear was
# added (commit d536b70): the vessels built after a bulk carrier or tanker in a scene draw what
# they always drew.
NEXT_DRAW = {
    ("bulk_carrier", 190.0, 0): 0.15027946689483906,
    ("bulk_carrier", 190.0, 1): 0.8355692165002742,
    ("bulk_carrier", None, 0): 0.450339366649287,
    ("bulk_carrier", None, 3): 0.5669778744529123,
    ("tanker", 245.0, 0): 0.05202130106440961,
    ("tanker", 245.0, 2): 0.19616991196827194,
    ("tanker", None, 1): 0.2740483886137183,
    ("tanker", None, 3): 0.18028754084309517,
}


@pytest.mark.parametrize(("kind", "length", "seed"), sorted(NEXT_DRAW, key=str))
def test_the_callers_random_stream_is_the_one_it_was(kind, length, seed) -> None:
    rng = np.random.default_rng(seed)
    build_vessel(kind, length, rng)
    assert float(rng.random()) == NEXT_DRAW[(kind, length, seed)]


@pytest.mark.parametrize(("kind", "most_faces"), [("bulk_carrier", 9500), ("tanker", 12000)])
def test_bulk_carriers_and_tankers_are_deterministic_and_light(kind, most_faces) -> None:
    for length, seed in ((100.0, 0), (330.0 if kind == "bulk_carrier" else 340.0, 1), (None, 2)):
        a = build_vessel(kind, length, np.random.default_rng(seed))
        b = build_vessel(kind, length, np.random.default_rng(seed))
        assert a.part_names == b.part_names
        for pa, pb in zip(a.parts, b.parts, strict=True):
            np.testing.assert_array_equal(pa.mesh.vertices, pb.mesh.vertices)
            assert pa.material == pb.material
        # A scene renders many vessels: about ten thousand triangles each at most.
        assert sum(len(p.mesh.faces) for p in a.parts) < most_faces, (length, seed)
