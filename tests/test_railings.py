"""Guard rails (issue #32: working boats and ferries without railings looked like toys): the
bars a rail is built of meet the Load Line convention's figures (ICLL 1966/1988 Annex I,
Reg. 25: at least 1 m high, the opening under the lowest course at most 230 mm, the courses at
most 380 mm apart, stanchions about 1.5 m apart), measured on the meshes, and they stand on
the decks of the tug, the fishing boat and the ferry."""

from __future__ import annotations

from itertools import pairwise

import numpy as np
import pytest

from seahaze.vessels.geometry import HullForm
from seahaze.vessels.library import build_vessel
from seahaze.vessels.railings import deck_edge_path, guard_rail, roof_edge_path

REG25_HEIGHT_M = 1.0
REG25_LOWEST_OPENING_M = 0.23
REG25_COURSE_GAP_M = 0.38
REG25_STANCHION_SPACING_M = 1.5


def _bodies(mesh):
    """The rail's closed bars, each as its (min, max) corners."""
    return [body.bounds for body in mesh.split(only_watertight=True)]


def _feet(mesh) -> np.ndarray:
    """(x, y) of each upright bar's axis: the mean of its vertices (a prism's corners sit
    evenly round it)."""
    uprights = [b for b in mesh.split(only_watertight=True) if np.ptp(b.vertices[:, 2]) > 0.5]
    return np.array([b.vertices[:, :2].mean(axis=0) for b in uprights])


def test_a_roof_rail_meets_the_load_line_figures():
    z_roof = 7.0
    rail = guard_rail(roof_edge_path(-6.0, 2.0, 2.5, z_roof))
    assert rail.is_watertight and rail.volume > 0
    bodies = _bodies(rail)
    upright = [b for b in bodies if b[1][2] - b[0][2] > 0.5]
    lying = [b for b in bodies if b[1][2] - b[0][2] < 0.1]
    assert len(upright) + len(lying) == len(bodies)
    # Courses: the bars' heights at the aft end (one bar per course there).
    aft = sorted((b[0][2] - z_roof, b[1][2] - z_roof) for b in lying if b[1][1] - b[0][1] > 4.0)
    assert len(aft) == 3
    assert aft[0][0] <= REG25_LOWEST_OPENING_M
    gaps = [upper[0] - lower[1] for lower, upper in pairwise(aft)]
    assert max(gaps) <= REG25_COURSE_GAP_M
    assert aft[-1][1] >= REG25_HEIGHT_M
    # Stanchions: from the deck to the top rail, at most 1.5 m apart along the 21 m edge
    # (8 + 5 + 8), both ends included.
    feet = _feet(rail)
    assert all(b[0][2] <= z_roof and b[1][2] >= z_roof + REG25_HEIGHT_M for b in upright)
    arc = _arc_positions(feet, roof_edge_path(-6.0, 2.0, 2.5, z_roof)[:, :2])
    assert arc[0] == pytest.approx(0.0, abs=1e-9) and arc[-1] == pytest.approx(21.0)
    assert np.diff(arc).max() <= REG25_STANCHION_SPACING_M + 1e-9
    assert len(upright) == 15  # ceil(21 / 1.5) + 1: no more than the spacing needs


def _arc_positions(points: np.ndarray, path: np.ndarray) -> np.ndarray:
    """Each point's distance along the polyline ``path`` (the points lie on it), sorted."""
    steps = np.linalg.norm(np.diff(path, axis=0), axis=1)
    start = np.concatenate([[0.0], np.cumsum(steps)])
    positions = []
    for p in points:
        for k in range(len(steps)):
            a, b = path[k], path[k + 1]
            t = np.dot(p - a, b - a) / steps[k] ** 2
            if -1e-9 <= t <= 1 + 1e-9 and np.linalg.norm(a + t * (b - a) - p) < 1e-6:
                positions.append(start[k] + t * steps[k])
                break
        else:
            raise AssertionError(f"stanchion at {p} is off the path")
    return np.sort(positions)


def test_a_deck_edge_rail_follows_the_sheer_and_stays_inside_the_side():
    form = HullForm(
        length=24.0,
        beam=6.5,
        draft=2.2,
        freeboard=1.4,
        sheer_fwd=1.2,
        forecastle_height=1.8,
        forecastle_length=5.0,
    )
    path = deck_edge_path(form, 7.5, 0.15)
    rail = guard_rail(path)
    assert rail.is_watertight
    for lower, upper in _bodies(rail):
        x, y = 0.5 * (lower[0] + upper[0]), 0.5 * (lower[1] + upper[1])
        # Inside the deck edge (the hull's own half-breadth there, less the inset, and the
        # bar's half thickness).
        assert abs(y) <= form.deck_half_beam(np.array([x]))[0] - 0.15 + 0.05
        if upper[2] - lower[2] > 0.5:  # a stanchion: its foot on the deck where it stands
            # (the path is sampled every metre and followed straight between: 5 mm at most)
            assert lower[2] == pytest.approx(form.deck_z(np.array([x]))[0] - 0.02, abs=5e-3)
    # The top rail rides 1 m over the deck all along, sheer and forecastle included: the
    # highest point over each stanchion's foot.
    tops = rail.vertices[rail.vertices[:, 2] > 0.0]
    deck = form.deck_z(tops[:, 0])
    assert (tops[:, 2] - deck).max() == pytest.approx(1.0 + 0.021, abs=0.03)


@pytest.mark.parametrize(
    "kind", ["tug", "fishing_boat", "passenger_ferry", "bulk_carrier", "tanker", "container_ship"]
)
def test_working_boats_ferries_and_aft_houses_carry_rails_on_their_decks(kind):
    rng = np.random.default_rng(11)
    for _ in range(6):
        vessel = build_vessel(kind, None, rng)
        parts = {part.name: part for part in vessel.parts}
        assert "railings" in parts, kind
        rails = parts["railings"].mesh
        hull = parts["hull"].mesh
        # Within the hull's length and beam, and no higher than a metre over the highest deck
        # (the house's roof, or a forecastle's top).
        house_top = max(parts["superstructure"].mesh.bounds[1][2], hull.bounds[1][2])
        reach = np.abs(hull.bounds[:, :2]).max(axis=0)
        assert (np.abs(rails.bounds[:, :2]) <= reach + 0.05).all()
        assert rails.bounds[1][2] <= house_top + REG25_HEIGHT_M + 0.05
        assert parts["railings"].material == parts["superstructure"].material


def test_the_poop_rail_leaves_the_freefall_boat_its_way_off_the_stern():
    rng = np.random.default_rng(5)
    ramps = 0
    for _ in range(8):
        parts = {part.name: part for part in build_vessel("tanker", None, rng).parts}
        if "lifeboat_ramp" not in parts:
            continue
        ramps += 1
        # The boat's path off the ramp: aft of the ramp, as wide as it.
        ramp = parts["lifeboat_ramp"].mesh.bounds
        for lower, upper in _bodies(parts["railings"].mesh):
            aft_of_ramp = lower[0] < ramp[0][0]
            across_it = lower[1] < ramp[1][1] and upper[1] > ramp[0][1]
            assert not (aft_of_ramp and across_it), (lower, upper, ramp)
    assert ramps >= 4  # most ships carry a freefall boat
