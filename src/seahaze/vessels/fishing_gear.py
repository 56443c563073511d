"""A stern trawler's gear at the stern: the A-frame gantry and the trawl doors hung from it.

Proportions are typical values, not design data: the gantry from the FAO Fisheries Technical
Paper 267 drawings of 20-40 m stern trawlers; the doors (otter boards) hung at the stern
quarters outside the hull, where a stern trawler stows them with its gear aboard, their size a
visual choice in proportion to the boat (below). Metres; vessel frame x forward, y port, z up,
waterline z = 0.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from seahaze.vessels.geometry import HullForm, box, cylinder_between
from seahaze.vessels.materials import Material
from seahaze.vessels.parts import EMBED_M, PartSet, deck_at, min_half_beam, u

__all__ = ["DOOR_LENGTH_RATIO", "Gantry", "add_stern_gantry", "add_trawl_doors"]

DOOR_LENGTH_RATIO = 0.1
"""A trawl door's length over the boat's (clipped to 1.5-3.5 m): a 25 m trawler's doors are
2.5 m long and 1.4 m high, about 3.4 m² (a visual choice, not a cited size)."""
DOOR_HEIGHT_RATIO = 0.55
"""A door's height over its length (a visual choice: an oblong plate)."""
DOOR_THICKNESS_M = 0.12
"""Thickness of a door's body (m): a steel plate with its frame and shoe."""


@dataclass(frozen=True)
class Gantry:
    """Where a stern gantry's legs stand (m): their station and the deck's height there, what
    the trawl doors hang beside."""

    x_legs: float
    z_deck: float


def add_stern_gantry(
    parts: PartSet, form: HullForm, rng: np.random.Generator, paint: Material
) -> Gantry:
    """Stern A-frame gantry for the trawl doors and net: two legs at the sides of the stern,
    raked aft a little, joined by a top beam with a hanging block. On 20-40 m stern trawlers it
    stands about 4-8 m above the deck (FAO FTP 267 drawings); legs about 1 % L thick."""
    length = form.length
    xg = -form.half_length + u(rng, 0.03, 0.06) * length
    zg = deck_at(form, xg)
    top = zg + u(rng, 0.12, 0.2) * length + 1.5
    half = min_half_beam(form, xg - 0.5, xg + 0.5)
    r = max(0.12, 0.01 * length)
    rake = min(0.1 * (top - zg), xg + form.half_length - r - 0.05)
    x_top = xg - max(rake, 0.0)
    for side in (-1.0, 1.0):
        parts.add(
            "gantry",
            cylinder_between(
                (xg, side * (0.85 * half - r), zg - EMBED_M), (x_top, side * 0.6 * half, top), r
            ),
            paint,
        )
    parts.add(
        "gantry",
        cylinder_between((x_top, -0.6 * half - r, top), (x_top, 0.6 * half + r, top), r),
        paint,
    )
    # Forward braces from the top of each leg down to the deck: with the legs they make the
    # "A" that shows from the side.
    x_foot = min(xg + 0.35 * (top - zg), form.half_length)
    z_foot = deck_at(form, x_foot)
    for side in (-1.0, 1.0):
        parts.add(
            "gantry",
            cylinder_between(
                (x_foot, side * (0.8 * half - r), z_foot - EMBED_M),
                (x_top, side * 0.6 * half, top - r),
                0.8 * r,
            ),
            paint,
        )
    # Hanging block (the net's sheave) under the top beam.
    s = max(0.25, 0.6 * r + 0.1)
    parts.add("gantry", box(x_top - 0.9 * r, x_top + 0.9 * r, -s, s, top - 2.2 * s, top), paint)
    return Gantry(xg, zg)


def add_trawl_doors(parts: PartSet, form: HullForm, gantry: Gantry, paint: Material) -> None:
    """The two trawl doors stowed at the stern: hung from the gantry, one at each quarter,
    upright and fore-aft against the outside of the hull, their top 0.8 m over the deck (at
    a bulwark's height). Their size follows the boat (:data:`DOOR_LENGTH_RATIO`); no random
    draws, so the vessels after this one are built as before."""
    length = float(np.clip(DOOR_LENGTH_RATIO * form.length, 1.5, 3.5))
    height = DOOR_HEIGHT_RATIO * length
    x0 = max(gantry.x_legs - 0.3 * length, -form.half_length + 0.1)
    x1 = x0 + length
    z1 = gantry.z_deck + 0.8
    z0 = max(z1 - height, 0.3)
    # Outside the hull over the door's whole height and length (the topsides flare out).
    xs, zs = np.meshgrid(np.linspace(x0, x1, 5), np.linspace(z0, z1, 5))
    inside = float(form.half_width(xs, zs).max()) + 0.05
    for side in (-1.0, 1.0):
        y0, y1 = sorted((side * inside, side * (inside + DOOR_THICKNESS_M)))
        parts.add("trawl_doors", box(x0, x1, y0, y1, z0, z1), paint)
