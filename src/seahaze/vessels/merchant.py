"""Large merchant ships: container ship and passenger (ro-pax) ferry; the bulk carrier and
tanker builders are :mod:`seahaze.vessels.bulk_tanker`'s, named here too.

Every builder receives principal dimensions already sampled inside the class ranges (see
:mod:`seahaze.vessels.library`) and samples the remaining proportions from ``rng`` inside
the ranges written next to each draw. Metres throughout.

Proportions follow common naval-architecture practice for these types:

- bridge visibility: SOLAS V/22.1.1 requires that the sea surface is visible from the
  conning position no more than two ship lengths or 500 m (the lesser) ahead of the bow;
  container stacks forward of an aft bridge are capped by that sight line below.
- ISO 668 containers: 40 ft (12.19 m) and 20 ft (6.058 m) long, 2.44 m wide, 2.59 m
  (8 ft 6 in) high, stacked in bays of one 40 ft or two 20 ft boxes, rows across the ship and
  tiers up; each box is painted in its own line's livery.
- deck heights of accommodation: about 2.8 m per deck.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np

from seahaze.vessels.accommodation import LIFEBOAT_ORANGE
from seahaze.vessels.bulk_tanker import build_bulk_carrier, build_tanker
from seahaze.vessels.cargo_hull import DECK_HEIGHT_M, boot_top, foremast, merchant_hull
from seahaze.vessels.geometry import HullForm, box, boxes
from seahaze.vessels.materials import (
    ANTIFOULING_REDS,
    CONTAINER_COLOURS,
    DECK_PAINTS,
    FUNNEL_PAINTS,
    HULL_PAINTS_CARGO,
    SUPERSTRUCTURE_WHITES,
    WINDOW_GLASS,
    Material,
    pick_material,
)
from seahaze.vessels.model import VesselPart
from seahaze.vessels.parts import EMBED_M, PartSet, PrincipalDims, deck_range, min_half_beam, u
from seahaze.vessels.railings import (
    RAIL_INSET_M,
    add_house_rails,
    deck_edge_path,
    guard_rail,
    roof_edge_path,
)

__all__ = [
    "build_bulk_carrier",
    "build_container_ship",
    "build_passenger_ferry",
    "build_tanker",
]

CONTAINER_LENGTH_M = 12.19
CONTAINER_WIDTH_M = 2.44
CONTAINER_HEIGHT_M = 2.59
CONTAINER_20FT_LENGTH_M = 6.058
Corner = tuple[float, float, float]
"""A box's corner (x, y, z), m."""
TWENTY_FOOT_SHARE = 0.25
"""Share of a bay's slots holding two 20 ft boxes instead of one 40 ft: on deck most boxes are
40 ft, as most of the world's fleet of boxes is (in TEU, 40 ft units carry about two thirds
of the trade)."""
LINE_SHARE_RANGE = (0.3, 0.7)
"""Share of a ship's boxes in its operating line's own livery (drawn per ship): a liner
carries mostly its own line's boxes among leased and partners' ones."""
CONTAINER_GAP_M = (0.06, 0.02, 0.076)
"""Gaps between neighbouring boxes: across rows (m), between tiers (the corner castings'
clearance, so no two boxes share a vertex), and between the two 20 ft boxes of a 40 ft slot
(ISO 668's 3 in)."""


def _sight_line_limit(
    eye_x: float, eye_z: float, bow_x: float, length: float
) -> Callable[[float], float]:
    """Highest allowed top (m) at ``x`` so the sea is visible min(2L, 500 m) ahead (SOLAS)."""
    sea_x = bow_x + min(2.0 * length, 500.0)

    def limit(x: float) -> float:
        return eye_z * (sea_x - x) / (sea_x - eye_x)

    return limit


def build_container_ship(d: PrincipalDims, rng: np.random.Generator) -> list[VesselPart]:
    """Cellular container ship: long hull, tiers of ISO boxes, tall accommodation + funnel.

    Bridge aft (feeder to Panamax) or, for ships over 280 m, often forward at ~1/3 L from the
    bow with the funnel aft (typical of ULCVs since ~2010).
    """
    form = merchant_hull(d, rng, fullness=0.0)
    hull = pick_material(HULL_PAINTS_CARGO, rng)
    white = pick_material(SUPERSTRUCTURE_WHITES, rng)
    funnel = pick_material(FUNNEL_PAINTS, rng)
    soot = FUNNEL_PAINTS[0]
    parts = PartSet()
    parts.add_hull(
        form,
        hull,
        bottom=pick_material(ANTIFOULING_REDS, rng),
        boot_top_z=boot_top(d),
        deck=pick_material(DECK_PAINTS, rng),
    )

    length, beam = d.length, d.beam
    coaming = u(rng, 1.5, 2.2)
    # On-deck tiers grow with size: 3-4 on a 100 m feeder, 8-9 on a 400 m ULCV.
    max_tiers = int(np.clip(round(4 + (length - 100.0) / 60.0 + rng.integers(-1, 1)), 3, 10))
    stack_top = float(form.deck_z(np.array([0.0]))[0]) + coaming + max_tiers * CONTAINER_HEIGHT_M

    bridge_forward = length > 280.0 and rng.random() < 0.6
    house_len = max(10.0, u(rng, 0.04, 0.055) * length)
    if bridge_forward:
        x_fwd = form.half_length - u(rng, 0.3, 0.36) * length
    else:
        x_fwd = -form.half_length + u(rng, 0.06, 0.25) * length + house_len
    x_aft = x_fwd - house_len
    z_deck, _ = deck_range(form, x_aft, x_fwd)
    bridge_floor = stack_top + u(rng, 2.5, 5.0)
    n_decks = max(2, int(np.ceil((bridge_floor - z_deck) / DECK_HEIGHT_M)))
    half_w = min(u(rng, 0.28, 0.4) * beam, min_half_beam(form, x_aft, x_fwd) - 0.5)
    z_roof, z_top, wheelhouse = parts.add_accommodation(
        form,
        x_aft,
        x_fwd,
        half_w,
        n_decks,
        DECK_HEIGHT_M,
        wing_half_width=0.5 * beam,
        wheelhouse_length=u(rng, 0.5, 0.8) * house_len,
        paint=white,
        glass=WINDOW_GLASS[0],
    )
    # Guard rails round the compass deck (the wheelhouse top, as wide as the wings) and the
    # house roof aft of the wheelhouse.
    add_house_rails(parts, (x_aft, wheelhouse[0]), half_w, z_roof, wheelhouse, 0.5 * beam, z_top)
    parts.add_mast(
        x_fwd - 0.4 * house_len,
        0.0,
        z_top,
        u(rng, 4.0, 8.0),
        0.35,
        white,
        yard_half_width=2.5,
        name="radar_mast",
    )

    keep_out = [(x_aft - 1.0, x_fwd + 1.0)]
    if bridge_forward:
        f_len = u(rng, 0.025, 0.035) * length
        f_x = -form.half_length + u(rng, 0.12, 0.16) * length
        f_z0, _ = deck_range(form, f_x - f_len, f_x + f_len)
        parts.add_funnel(
            f_x,
            0.0,
            f_len,
            u(rng, 0.12, 0.2) * beam,
            f_z0,
            stack_top + u(rng, 3.0, 8.0),
            rake=u(rng, 0.5, 2.0),
            paint=funnel,
            top=soot,
        )
        keep_out.append((f_x - f_len - 2.0, f_x + f_len + 2.0))
    else:
        f_half = u(rng, 0.15, 0.22) * house_len
        parts.add_funnel(
            x_aft + f_half + 0.5,
            0.0,
            f_half,
            u(rng, 0.1, 0.16) * beam,
            z_roof,
            z_top + u(rng, 2.0, 6.0),
            rake=u(rng, 0.5, 2.0),
            paint=funnel,
            top=soot,
        )

    eye_z = z_top - 1.0 + 1.7
    sight = _sight_line_limit(x_fwd, eye_z, form.half_length, length)
    _add_container_stacks(parts, form, rng, coaming, max_tiers, keep_out, sight)
    foremast(parts, form, white, rng)
    return parts.to_parts()


def _add_container_stacks(
    parts: PartSet,
    form: HullForm,
    rng: np.random.Generator,
    coaming: float,
    max_tiers: int,
    keep_out: list[tuple[float, float]],
    sight_limit: Callable[[float], float],
) -> None:
    """Fill the deck with 40 ft bays of containers: rows across, tiers up, box by box.

    A bay holds one or two stacks across (two on a wide ship, split at the centreline); a
    stack's rows have their own heights (a row one tier short now and then) and each slot is
    one 40 ft box or two 20 ft boxes, each painted in the ship's line's livery (a share drawn
    in :data:`LINE_SHARE_RANGE`) or another from :data:`CONTAINER_COLOURS`, so from afar the
    deck reads as the patchwork of colours real ships carry. Bays are separated by
    lashing-bridge gaps.
    """
    x_front = form.half_length - form.forecastle_length - 2.0
    x_end = -form.half_length + 0.05 * form.length
    gap = u(rng, 0.8, 1.4)
    row_pitch = CONTAINER_WIDTH_M + CONTAINER_GAP_M[0]
    livery = _Livery(pick_material(CONTAINER_COLOURS, rng, jitter=0.0), u(rng, *LINE_SHARE_RANGE))
    by_colour: dict[str, tuple[Material, list[Corner], list[Corner]]] = {}
    x1 = x_front
    while x1 - CONTAINER_LENGTH_M > x_end:
        x0 = x1 - CONTAINER_LENGTH_M
        bay = (x0, x1)
        blocked = [a for a, b in keep_out if bay[1] > a and bay[0] < b]
        if blocked:
            x1 = min(blocked) - gap  # restart the bay grid right behind the obstacle
            continue
        x1 = x0 - gap
        half_avail = min_half_beam(form, *bay) - 0.5
        rows = int(2.0 * half_avail // row_pitch)
        if rows < 1:
            continue
        width = rows * row_pitch
        z_base = deck_range(form, *bay)[1] + coaming
        blocks = (
            [(-0.5 * width, -0.15), (0.15, 0.5 * width)]
            if rows >= 6
            else [(-0.5 * width, 0.5 * width)]
        )
        for y0, y1 in blocks:
            if rng.random() < 0.06:
                continue  # an empty stack, common on partly loaded ships
            tiers = max_tiers - int(rng.choice(3, p=(0.5, 0.35, 0.15)))
            allowed = int((sight_limit(bay[1]) - z_base) // CONTAINER_HEIGHT_M)
            tiers = min(tiers, allowed)
            if tiers < 1:
                continue
            for colour, lower, upper in _stack(bay, (y0, y1), z_base, tiers, livery, rng):
                entry = by_colour.setdefault(colour.name, (colour, [], []))
                entry[1].append(lower)
                entry[2].append(upper)
        # Hatch cover under the stacks (also visible where a stack is missing).
        z_deck = deck_range(form, *bay)[0]
        parts.add(
            "hatch_covers",
            box(x0 - 0.2, bay[1] + 0.2, -0.5 * width, 0.5 * width, z_deck - EMBED_M, z_base - 0.6),
            DECK_PAINTS[2],
        )
    for name, (colour, lower, upper) in sorted(by_colour.items()):
        parts.add(f"containers_{name.removeprefix('container_')}", boxes(lower, upper), colour)


@dataclass(frozen=True)
class _Livery:
    """A ship's container colours: its operating line's ``own`` livery for a ``share`` of its
    boxes, any of :data:`CONTAINER_COLOURS` for the rest."""

    own: Material
    share: float

    def pick(self, rng: np.random.Generator) -> Material:
        """One box's colour."""
        if rng.random() < self.share:
            return self.own
        return pick_material(CONTAINER_COLOURS, rng, jitter=0.0)


def _stack(
    bay: tuple[float, float],
    across: tuple[float, float],
    z_base: float,
    tiers: int,
    livery: _Livery,
    rng: np.random.Generator,
) -> Iterator[tuple[Material, Corner, Corner]]:
    """The boxes of one stack, ``bay`` along the ship and ``across`` it (m), from ``z_base`` up
    ``tiers`` tiers: row by row (a row one tier short now and then), tier by tier, slot by slot
    (:func:`_slot_boxes`), each with its colour and lower and upper corners."""
    y0, y1 = across
    row_pitch = CONTAINER_WIDTH_M + CONTAINER_GAP_M[0]
    for row in range(max(1, int((y1 - y0 + CONTAINER_GAP_M[0]) // row_pitch))):
        ya = y0 + row * row_pitch
        row_tiers = tiers - int(rng.random() < 0.2)
        for tier in range(row_tiers):
            za = z_base + tier * CONTAINER_HEIGHT_M
            # The bottom tier sits 0.5 m into the coaming: no sky under the stack.
            bottom = za - 0.5 if tier == 0 else za
            top = za + CONTAINER_HEIGHT_M - CONTAINER_GAP_M[1]
            for xa, xb in _slot_boxes(bay, rng):
                colour = livery.pick(rng)
                yield colour, (xa, ya, bottom), (xb, ya + CONTAINER_WIDTH_M, top)


def _slot_boxes(bay: tuple[float, float], rng: np.random.Generator) -> list[tuple[float, float]]:
    """The boxes of one 40 ft slot along the ship: one 40 ft box, or (a share
    :data:`TWENTY_FOOT_SHARE` of slots) two 20 ft boxes with ISO 668's gap between them."""
    x0, x1 = bay
    if rng.random() >= TWENTY_FOOT_SHARE:
        return [(x0, x1)]
    return [(x0, x0 + CONTAINER_20FT_LENGTH_M), (x1 - CONTAINER_20FT_LENGTH_M, x1)]


def build_passenger_ferry(d: PrincipalDims, rng: np.random.Generator) -> list[VesselPart]:
    """Passenger / ro-pax ferry: high white superstructure over most of the length in stepped
    tiers with window bands, bridge at the front of the top tier, one or two funnels aft,
    lifeboats along the sides on larger ships."""
    length, beam = d.length, d.beam
    form = HullForm(
        length=length,
        beam=beam,
        draft=d.draft,
        freeboard=d.freeboard,
        sheer_fwd=u(rng, 0.05, 0.15) * d.depth,
        parallel_fwd=u(rng, 0.0, 0.2),
        parallel_aft=u(rng, 0.1, 0.3),
        entrance_exponent=u(rng, 1.8, 2.4),
        bow_roundness=u(rng, 1.1, 1.4),
        transom_width=u(rng, 0.85, 0.95),
        stem_rake=u(rng, 0.05, 0.09),
        stem_exponent=0.6,
        stern_cutup=0.1,
        transom_immersion=u(rng, 0.0, 0.3),
        section_exponent=4.0,
        bow_flare=u(rng, 0.25, 0.35),
    )
    white = pick_material(SUPERSTRUCTURE_WHITES, rng)
    hull = white if rng.random() < 0.6 else pick_material(HULL_PAINTS_CARGO, rng)
    stripe = pick_material(HULL_PAINTS_CARGO + ANTIFOULING_REDS, rng)
    glass = WINDOW_GLASS[0]
    parts = PartSet()
    parts.add_hull(form, hull, bottom=stripe, boot_top_z=u(rng, 0.6, 0.45 * d.freeboard + 0.6))

    n_tiers = int(np.clip(round(length / 35.0 + u(rng, 0.0, 1.5)), 1, 7))
    tier_h = u(rng, 2.7, 3.1)
    x_aft = -form.half_length + u(rng, 0.04, 0.12) * length
    x_fwd = form.half_length - u(rng, 0.12, 0.2) * length
    step_aft = u(rng, 0.0, 0.03) * length
    step_fwd = u(rng, 0.005, 0.02) * length
    z = deck_range(form, x_aft, x_fwd)[0]
    narrow = 1.0
    for k in range(n_tiers):
        xa, xf = x_aft + k * step_aft, x_fwd - k * step_fwd
        hw = narrow * (min_half_beam(form, xa, xf) - 0.15)
        rake = 0.35 * tier_h
        parts.add_block(
            "superstructure", white, xa, xf, hw, z - EMBED_M, z + tier_h, front_rake=rake
        )
        parts.add_window_band(xa + 0.5, xf - rake - 0.5, hw, z + 0.9, z + 2.0, glass)
        if k == 1 and length > 60.0 and rng.random() < 0.7:
            _add_lifeboats(parts, xa, xf, hw, z, 0.5 * beam, rng)
        z += tier_h
        narrow *= 0.97
        if k < n_tiers - 1 and step_aft > 1.5:
            # The open deck this tier's roof leaves aft of the next tier: railed round its end.
            end = roof_edge_path(xa + RAIL_INSET_M, xa + step_aft, hw - RAIL_INSET_M, z)
            parts.add("railings", guard_rail(end), white)
    # The open foredeck forward of the superstructure, railed along the hull's deck edge.
    parts.add("railings", guard_rail(deck_edge_path(form, x_fwd + 1.0, RAIL_INSET_M)), white)
    top_aft, top_fwd = x_aft + (n_tiers - 1) * step_aft, x_fwd - (n_tiers - 1) * step_fwd
    bridge_len = max(3.0, u(rng, 0.03, 0.05) * length)
    bx1 = top_fwd - 0.35 * tier_h - 0.3
    wing = min(0.5 * beam, min_half_beam(form, bx1 - bridge_len, bx1))
    parts.add_block(
        "superstructure",
        white,
        bx1 - bridge_len,
        bx1,
        wing,
        z - EMBED_M,
        z + tier_h,
        front_rake=0.5,
    )
    parts.add(
        "windows",
        box(bx1 - 0.8, bx1 + 0.05, -(wing - 0.3), wing - 0.3, z + 0.9, z + tier_h - 0.4),
        glass,
    )
    z_top = z + tier_h
    # The sun deck: the top tier's roof aft of the bridge, railed round its sides and end.
    sun_deck_aft, sun_deck_fwd = top_aft + RAIL_INSET_M, bx1 - bridge_len - 0.3
    if sun_deck_fwd - sun_deck_aft > 2.0:
        sun_deck = roof_edge_path(sun_deck_aft, sun_deck_fwd, hw - RAIL_INSET_M, z)
        parts.add("railings", guard_rail(sun_deck), white)
    parts.add_mast(
        bx1 - 0.5 * bridge_len,
        0.0,
        z_top,
        u(rng, 3.0, 6.0),
        0.2,
        white,
        yard_half_width=1.5,
        name="radar_mast",
    )

    funnel = pick_material(FUNNEL_PAINTS, rng)
    f_half_len = float(np.clip(u(rng, 0.03, 0.05) * length, 0.6, 8.0))
    f_height = float(np.clip(u(rng, 0.03, 0.05) * length, 1.5, 10.0))
    fx = top_aft + f_half_len + u(rng, 0.5, 0.1 * length)
    twin = length > 90.0 and rng.random() < 0.5
    ys = (-0.22 * beam, 0.22 * beam) if twin else (0.0,)
    for y in ys:
        parts.add_funnel(
            fx,
            y,
            f_half_len,
            u(rng, 0.06, 0.1) * beam,
            z - tier_h,
            z + f_height,
            rake=u(rng, 0.3, 1.5),
            paint=funnel,
            top=FUNNEL_PAINTS[0],
        )
    return parts.to_parts()


def _add_lifeboats(
    parts: PartSet,
    xa: float,
    xf: float,
    hw: float,
    z: float,
    half_beam: float,
    rng: np.random.Generator,
) -> None:
    """SOLAS lifeboats (international orange) hung along both sides, inside the beam."""
    boat_len = u(rng, 7.0, 9.0)
    count = int(np.clip((xf - xa) // (boat_len * 2.5), 1, 4))
    y_out = min(half_beam - 0.05, hw + 1.2)
    y_in = y_out - 2.6
    start = xa + 0.2 * (xf - xa)
    for i in range(count):
        x0 = start + i * boat_len * 1.6
        for side in (-1.0, 1.0):
            ya, yb = sorted((side * y_in, side * y_out))
            parts.add(
                "lifeboats", box(x0, x0 + boat_len, ya, yb, z + 0.3, z + 2.7), LIFEBOAT_ORANGE
            )
