"""A stern trawler's gear (issue #32: a fishing boat should carry its telltale parts): the trawl
doors hang at the stern outside the hull, one each side, sized by the boat; seiners, which set
no trawl, carry none."""

from __future__ import annotations

import numpy as np

from seahaze.vessels.fishing_gear import DOOR_HEIGHT_RATIO, DOOR_LENGTH_RATIO
from seahaze.vessels.library import build_vessel


def _fishing_boats(count: int, seed: int):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        vessel = build_vessel("fishing_boat", None, rng)
        yield vessel, {part.name: part for part in vessel.parts}


def test_trawl_doors_hang_outside_the_stern_quarters():
    doors_seen = 0
    for _, parts in _fishing_boats(24, 3):
        if "trawl_doors" not in parts:
            continue
        doors_seen += 1
        hull = parts["hull"].mesh
        length = hull.bounds[1][0] - hull.bounds[0][0]
        bodies = parts["trawl_doors"].mesh.split(only_watertight=True)
        assert len(bodies) == 2
        ys = sorted(float(body.centroid[1]) for body in bodies)
        assert ys[0] < 0.0 < ys[1]  # one each side
        for body in bodies:
            # Outside the hull: every hull vertex abreast of the door, from its foot up, lies
            # nearer the centreline than the door's inner face.
            (x0, y0, z0), (x1, y1, _) = body.bounds
            v = hull.vertices
            abreast = (v[:, 0] >= x0) & (v[:, 0] <= x1) & (v[:, 2] >= z0)
            assert abreast.sum() >= 4
            assert np.abs(v[abreast, 1]).max() < min(abs(y0), abs(y1))
            # At the stern, aft of the boat's quarter length.
            assert body.bounds[0][0] >= hull.bounds[0][0] - 1e-9
            assert body.bounds[1][0] < hull.bounds[0][0] + 0.25 * length
            door_length = body.bounds[1][0] - body.bounds[0][0]
            want = np.clip(DOOR_LENGTH_RATIO * length, 1.5, 3.5)
            assert abs(door_length - want) < 0.02 * length  # the hull's length over all
            height = body.bounds[1][2] - body.bounds[0][2]
            assert height <= DOOR_HEIGHT_RATIO * door_length + 1e-9
            assert body.bounds[0][2] > 0.0  # clear of the water
    assert doors_seen >= 6  # stern trawlers are six in ten fishing boats


def test_only_boats_with_a_stern_gantry_carry_doors():
    for _, parts in _fishing_boats(24, 4):
        if "trawl_doors" in parts:
            assert "gantry" in parts
