"""Small working vessels: fishing boat (trawler / seiner) and harbour tug (the leisure craft,
sailing yacht and speedboat, are in :mod:`seahaze.vessels.leisure`).

Builders receive principal dimensions sampled inside the class ranges (see
:mod:`seahaze.vessels.library`) and draw the rest from ``rng`` inside the ranges written
next to each draw (the tug's and fishing boat's added details from a generator seeded by their
dimensions, so that ``rng`` sees the draws it always saw). Metres throughout; vessel frame
x forward, y port, z up, waterline z = 0.
"""

from __future__ import annotations

import numpy as np

from seahaze.vessels.fishing_gear import add_stern_gantry, add_trawl_doors
from seahaze.vessels.geometry import (
    HullForm,
    box,
    cylinder_between,
    loft_hull,
    vertical_cylinder,
)
from seahaze.vessels.materials import (
    ANTIFOULING_REDS,
    FUNNEL_PAINTS,
    HULL_PAINTS_CARGO,
    HULL_PAINTS_SMALL,
    MACHINERY_PAINTS,
    SUPERSTRUCTURE_WHITES,
    WINDOW_GLASS,
    Material,
    material_from_srgb8,
    pick_material,
)
from seahaze.vessels.model import VesselPart
from seahaze.vessels.parts import (
    EMBED_M,
    PartSet,
    PrincipalDims,
    deck_at,
    deck_range,
    min_half_beam,
    u,
)
from seahaze.vessels.railings import RAIL_INSET_M, add_house_rails, deck_edge_path, guard_rail

__all__ = ["build_fishing_boat", "build_tug"]

BLACK_RUBBER = material_from_srgb8("fender_rubber", (25, 25, 25), 0.8)

RUST = material_from_srgb8("rust", (118, 62, 36), 0.85)
"""Rust bleeding from scuppers, hawse pipes and plate seams on working steel hulls."""

NET_COLOURS = (
    material_from_srgb8("net_green", (45, 95, 60), 0.85),
    material_from_srgb8("net_orange", (200, 95, 40), 0.85),
    material_from_srgb8("net_blue", (40, 70, 130), 0.85),
)
"""Trawl netting wound on a drum: polyethylene twine, usually green, orange or blue (matt;
the roughness one of render.fleet.ROUGHNESS_CLASSES, as every built-in material's is)."""


def _detail_rng(d: PrincipalDims) -> np.random.Generator:
    """A generator for a builder's details (fenders, gear, rust), seeded by the vessel's
    principal dimensions, themselves drawn from the caller's ``rng``: deterministic for a seed,
    and drawing nothing from ``rng``, so the vessels built after this one in a scene draw what
    they drew before these details existed."""
    dims = np.array([d.length, d.beam, d.depth, d.draft], np.float64)
    return np.random.default_rng(np.frombuffer(dims.tobytes(), np.uint32))


def build_fishing_boat(d: PrincipalDims, rng: np.random.Generator) -> list[VesselPart]:
    """Trawler / seiner: strong sheer, whaleback forecastle, deckhouse with an all-round-windowed
    wheelhouse (forward on trawlers, aft on seiners/longliners), a mast with radar and a derrick
    or raised outrigger booms, a stern A-frame gantry with a net drum forward of it, rust
    streaks down the topsides."""
    length, beam = d.length, d.beam
    # Every draw from ``rng`` is the one this builder always made, in the same order (the
    # vessels built after it draw what they did); what was added draws from ``extra``.
    extra = _detail_rng(d)
    # Most trawlers have a raised forecastle or whaleback over the fore deck (FAO FTP 267).
    draw = rng.random()
    has_forecastle = draw < 0.85
    fc_rng = rng if draw < 0.5 else extra  # the builder drew these from rng below 0.5
    form = HullForm(
        length=length,
        beam=beam,
        draft=d.draft,
        freeboard=d.freeboard,
        sheer_fwd=u(rng, 0.25, 0.45) * d.depth,
        sheer_aft=u(rng, 0.05, 0.1) * d.depth,
        forecastle_height=u(fc_rng, 1.4, 2.0) if has_forecastle else 0.0,
        forecastle_length=u(fc_rng, 0.18, 0.28) * length if has_forecastle else 0.0,
        entrance_exponent=u(rng, 1.6, 2.2),
        bow_roundness=u(rng, 1.0, 1.2),
        transom_width=u(rng, 0.7, 0.9),
        stem_rake=u(rng, 0.05, 0.09),
        stem_exponent=0.7,
        stern_cutup=u(rng, 0.15, 0.2),
        transom_immersion=u(rng, 0.3, 0.6),
        section_exponent=u(rng, 2.5, 3.5),
        bow_flare=0.3,
        topside_flare=0.05,
    )
    hull = pick_material(HULL_PAINTS_CARGO + HULL_PAINTS_SMALL, rng)
    # Working boats' whites are dirtier and more varied than a ferry's: twice the jitter.
    white = pick_material(SUPERSTRUCTURE_WHITES, rng, jitter=0.12)
    glass = WINDOW_GLASS[0]
    parts = PartSet()
    parts.add_hull(form, hull, bottom=pick_material(ANTIFOULING_REDS, rng), boot_top_z=0.25)
    _rust_streaks(parts, form, extra)

    house_len = u(rng, 0.2, 0.28) * length
    trawler = rng.random() < 0.6
    if trawler:  # stern trawler: wheelhouse forward of midships, working deck aft
        x_aft = u(rng, -0.1, 0.05) * length
    else:  # seiner / longliner: wheelhouse aft
        x_aft = -form.half_length + u(rng, 0.06, 0.12) * length
    x_fwd = x_aft + house_len
    z_deck, _ = deck_range(form, x_aft, x_fwd)
    hw = u(rng, 0.65, 0.85) * (min_half_beam(form, x_aft, x_fwd) - 0.1)
    z = z_deck
    lower_roof = None
    if length >= 15.0:  # a lower deckhouse under the wheelhouse on all but small boats
        h = u(rng, 2.0, 2.3)
        parts.add_block("superstructure", white, x_aft, x_fwd, hw, z - EMBED_M, z + h)
        _side_windows(parts, x_aft + 0.8, x_fwd - 0.8, hw, z + h - 1.3, z + h - 0.6, glass, extra)
        z += h
        lower_roof = z
    wh_len = u(rng, 0.5, 0.7) * house_len
    wh_h = u(rng, 2.2, 2.5)  # clear height 2.2-2.5 m: room for a sill at 1.0 m, head at 2.0 m
    parts.add_block(
        "superstructure",
        white,
        x_fwd - wh_len,
        x_fwd,
        0.9 * hw,
        z - EMBED_M,
        z + wh_h,
        front_rake=0.4,
    )
    _wheelhouse_glazing(parts, x_fwd - wh_len, x_fwd, 0.9 * hw, z, wh_h, glass)
    z += wh_h
    add_house_rails(
        parts, (x_aft, x_fwd - wh_len), hw, lower_roof, (x_fwd - wh_len, x_fwd - 0.4), 0.9 * hw, z
    )
    if has_forecastle:  # the forecastle's top: rails round it from its break to the stem
        x_break = form.half_length - form.forecastle_length + 0.5
        parts.add("railings", guard_rail(deck_edge_path(form, x_break, RAIL_INSET_M)), white)
    mast_paint = pick_material(MACHINERY_PAINTS, rng)
    x_mast = x_fwd - 0.5 * wh_len
    mast_h = u(rng, 0.15, 0.3) * length + 1.5
    parts.add_mast(
        x_mast, 0.0, z, mast_h, max(0.08, 0.006 * length), mast_paint, yard_half_width=0.6 * hw
    )
    _radar(parts, x_mast, z + 0.55 * mast_h, min(1.3, 0.8 * hw), mast_paint)

    # Working deck: the stretch of deck the gear stands on (aft of the house on a trawler,
    # forward of it on a seiner).
    if trawler:
        work_aft, work_fwd = -form.half_length + 0.03 * length, x_aft - 0.3
    else:
        work_aft, work_fwd = x_fwd + 0.3, form.half_length - form.forecastle_length - 0.05 * length
    gear = pick_material(MACHINERY_PAINTS, extra)
    draw = rng.random()  # the builder drew the gantry's place and height from rng below 0.6
    gantry = None
    if trawler or draw < 0.5:
        gantry = add_stern_gantry(parts, form, rng if draw < 0.6 else extra, gear)
    elif draw < 0.6:
        rng.uniform(size=2)  # the place and height of a gantry no longer built here
    if work_fwd - work_aft > 0.12 * length:
        # Gallows / derrick mast at the fore end of the working deck; its derrick reaches aft
        # (or forward on a seiner) over the deck: about a third of the length (FAO FTP 267).
        xm = work_fwd - 0.2 if trawler else work_aft + 0.2
        zm = deck_at(form, xm)
        post_h = u(extra, 0.22, 0.32) * length + 1.0
        post_r = max(0.1, 0.008 * length)
        parts.add_mast(xm, 0.0, zm, post_h, post_r, gear, name="derrick")
        if extra.random() < 0.5:  # outrigger booms, raised (stowed) as a V either side
            boom = u(extra, 0.3, 0.45) * length
            half = min_half_beam(form, xm - 0.5, xm + 0.5)
            base_y = 0.3
            reach = float(np.clip((0.95 * half - base_y - post_r) / boom, 0.0, 0.35))
            for side in (-1.0, 1.0):
                tip = (xm, side * (base_y + boom * reach), zm + 1.0 + boom * np.sqrt(1 - reach**2))
                parts.add(
                    "outriggers",
                    cylinder_between((xm, side * base_y, zm + 1.0), tip, 0.7 * post_r),
                    gear,
                )
        else:  # a derrick boom topped up at 30-45° over the working deck
            direction = -1.0 if trawler else 1.0
            span = min(u(extra, 0.25, 0.35) * length, 0.8 * (work_fwd - work_aft))
            angle = np.radians(u(extra, 30.0, 45.0))
            heel = (xm + direction * post_r, 0.0, zm + 1.2)
            head = (
                heel[0] + direction * span * np.cos(angle),
                0.0,
                heel[2] + span * np.sin(angle),
            )
            parts.add("derrick", cylinder_between(heel, head, 0.6 * post_r), gear)
    draw = rng.random()
    if draw < 0.5 and x_aft > -0.2 * length:
        rng.uniform()  # where the builder drew the drum's place
    if draw < 0.9 and work_fwd - work_aft > 0.1 * length:
        # Net drum: on a stern trawler just forward of the gantry; flanges about 2.5-3.5 % L
        # in radius, 0.8-2.2 m across (a 25 m trawler's drum is about 1.5 m across the flanges,
        # FAO FTP 267 drawings), the wound net inside them.
        rd = float(np.clip(u(extra, 0.025, 0.035) * length, 0.4, 1.1))
        xd = work_aft + 0.1 * length + rd if trawler else 0.5 * (work_aft + work_fwd)
        zd = deck_at(form, xd) + rd + 0.3
        half = 0.55 * min_half_beam(form, xd - rd, xd + rd)
        parts.add(
            "net_drum",
            cylinder_between((xd, -half, zd), (xd, half, zd), 0.8 * rd, sections=14),
            pick_material(NET_COLOURS, extra),
        )
        for side in (-1.0, 1.0):
            parts.add(
                "net_drum_frame",
                cylinder_between(
                    (xd, side * half, zd), (xd, side * (half + 0.12), zd), rd, sections=14
                ),
                gear,
            )
            parts.add(
                "net_drum_frame",
                box(
                    xd - 0.3 * rd,
                    xd + 0.3 * rd,
                    side * half,
                    side * (half + 0.1),
                    zd - rd - 0.5,
                    zd,
                ),
                gear,
            )
    if trawler and gantry is not None:
        add_trawl_doors(parts, form, gantry, gear)
    return parts.to_parts()


def _rust_streaks(parts: PartSet, form: HullForm, rng: np.random.Generator) -> None:
    """Rust streaks running down the topsides from the deck edge (scuppers, the hawse pipe at
    the bow): 3-7 bands 0.2-0.6 m wide, a third to most of the freeboard long, a few mm proud
    of the hull so they follow its shape (both sides alike)."""
    count = int(rng.integers(3, 8))
    for i in range(count):
        if i == 0:  # hawse pipe: where the anchor chain leaves its streak, near the stem
            x0 = form.half_length - u(rng, 0.08, 0.12) * form.length
        else:
            x0 = u(rng, -0.45, 0.3) * form.length
        width = u(rng, 0.2, 0.6)
        drop = u(rng, 0.35, 0.8)
        z_top = float(form.deck_z(np.array([x0]))[0]) - 0.08
        z_bottom = max(0.35, z_top - drop * z_top)
        if z_top - z_bottom < 0.2:
            continue
        parts.add(
            "rust",
            loft_hull(
                form,
                z_low=lambda x, zb=z_bottom: np.full_like(x, zb),
                z_high=lambda x, zt=z_top: np.full_like(x, zt),
                inflate=0.008,
                x_range=(x0, x0 + width),
                n_stations=3,
                n_vertical=3,
            ),
            RUST,
        )


def _radar(parts: PartSet, x: float, z: float, half_span: float, paint: Material) -> None:
    """Open-array radar scanner: a bar across the ship (X-band arrays are 1.2-2.4 m long) on
    a short pedestal at ``z`` up the mast."""
    parts.add("radar", box(x - 0.12, x + 0.12, -half_span, half_span, z, z + 0.18), paint)


def _side_windows(
    parts: PartSet,
    x0: float,
    x1: float,
    half_width: float,
    z0: float,
    z1: float,
    glass: Material,
    rng: np.random.Generator,
) -> None:
    """A row of rectangular windows 0.6-0.8 m wide every 1.6-2.2 m along a deckhouse's sides
    (one box through the house shows on both sides)."""
    pitch = u(rng, 1.6, 2.2)
    width = u(rng, 0.6, 0.8)
    count = int((x1 - x0) // pitch)
    for k in range(count):
        xc = x0 + (k + 0.5) * (x1 - x0) / count
        parts.add(
            "windows",
            box(xc - 0.5 * width, xc + 0.5 * width, -half_width - 0.03, half_width + 0.03, z0, z1),
            glass,
        )


def _wheelhouse_glazing(
    parts: PartSet,
    x0: float,
    x1: float,
    half_width: float,
    z_floor: float,
    height: float,
    glass: Material,
) -> None:
    """Windows all round a wheelhouse block (``x0..x1``, rakes as the block's): sill 1.0 m
    above its floor, head 0.3 m under its roof. IMO MSC/Circ.982 (bridge design) asks for the
    lower edge of the front windows no more than 1.0 m above the deck and the upper edge at
    least 2.0 m: the 1.0-1.3 m tall dark band that makes a wheelhouse read at a distance. The
    band is a box a few cm proud of every face at the sill (the raked faces recede above)."""
    z0, z1 = z_floor + 1.0, z_floor + height - 0.3
    proud = 0.04
    parts.add(
        "windows",
        box(
            x0 - proud,
            x1 + proud,
            -half_width - proud,
            half_width + proud,
            z0,
            z1,
        ),
        glass,
    )


def build_tug(d: PrincipalDims, rng: np.random.Generator) -> list[VesselPart]:
    """Harbour / ASD tug: short beamy hull with high forecastle, heavy black rubber fendering
    (a D-fender along the sheer, a deep block fender round the bow, truck tyres hung along the
    sides), a deckhouse with a tall all-round-windowed wheelhouse on top set forward, a mast
    with radar, twin exhaust stacks with sooty tops, a towing winch and H-bitt on the low open
    afterdeck."""
    length, beam = d.length, d.beam
    # As in the fishing boat: rng's draws as they always were, the added details from extra.
    extra = _detail_rng(d)
    fender = float(np.clip(0.012 * length, 0.25, 0.45))
    form = HullForm(
        length=length,
        beam=beam - 2.0 * fender,
        draft=d.draft,
        freeboard=d.freeboard,
        sheer_fwd=u(rng, 0.25, 0.45) * d.depth,
        sheer_aft=u(rng, 0.0, 0.05) * d.depth,
        forecastle_height=u(rng, 1.4, 2.2),
        forecastle_length=u(rng, 0.4, 0.5) * length,
        parallel_fwd=u(rng, 0.0, 0.1),
        entrance_exponent=u(rng, 2.0, 2.6),
        bow_roundness=u(rng, 1.5, 2.0),
        transom_width=u(rng, 0.8, 0.92),
        stem_rake=u(rng, 0.07, 0.12),
        stem_exponent=0.8,
        stern_cutup=u(rng, 0.2, 0.25),
        transom_immersion=u(rng, 0.3, 0.5),
        section_exponent=2.5,
        bow_flare=0.1,
        topside_flare=0.05,
    )
    hull = pick_material(HULL_PAINTS_CARGO, rng)
    house_paint = pick_material(SUPERSTRUCTURE_WHITES, rng) if rng.random() < 0.7 else hull
    glass = WINDOW_GLASS[0]
    parts = PartSet()
    parts.add_hull(form, hull, bottom=pick_material(ANTIFOULING_REDS, rng), boot_top_z=0.3)
    # D-fender along the sheer, ``fender`` (0.25-0.45 m) proud of the hull: the outer beam.
    fender_h = u(rng, 0.7, 1.1)
    parts.add(
        "fender",
        loft_hull(
            form,
            z_low=lambda x: form.deck_z(x) - fender_h,
            z_high=lambda x: form.deck_z(x) - 0.05,
            inflate=fender,
            n_stations=40,
            n_vertical=4,
        ),
        BLACK_RUBBER,
    )
    # Bow fendering: harbour tugs push with the bow, which carries a deep block of rubber (a
    # cylindrical fender of 0.8-1.2 m over W- or M-block fenders) from the sheer down to
    # about 0.4 m above the waterline over the forward 12-16 % L (Trelleborg / Damen ASD tug
    # fender arrangements). Slightly inside the D-fender, so the beam stays the D-fender's.
    bow_x0 = form.half_length - u(extra, 0.12, 0.16) * length
    parts.add(
        "fender",
        loft_hull(
            form,
            z_low=lambda x: np.full_like(x, 0.4),
            z_high=lambda x: form.deck_z(x) - fender_h + 0.1,
            inflate=0.85 * fender,
            x_range=(bow_x0, form.half_length),
            n_stations=12,
            n_vertical=4,
        ),
        BLACK_RUBBER,
    )
    # Truck tyres hung under the D-fender along the sides (the classic harbour-tug look): about
    # 1.0-1.2 m across and 0.3 m wide (large truck tyres), every 1.4-1.8 m; hung against the
    # hull inside the D-fender's outer line.
    tyre_r = u(extra, 0.5, 0.6)
    pitch = u(extra, 1.4, 1.8)
    thick = min(0.3, fender - 0.03)
    x = -form.half_length + 0.08 * length
    while x < bow_x0 - tyre_r - 0.3:
        # Under the D-fender; where the freeboard is low they dip into the water (their centres
        # stay above it) and hide partly behind the fender, which stands further out; at
        # least 0.3 m of each shows under it.
        z_fender = float(form.deck_z(np.array([x]))[0]) - fender_h
        zc = max(z_fender - 0.6 * tyre_r, 0.6 * tyre_r)
        if zc - tyre_r < z_fender - 0.3:
            hull_y = float(form.half_width(np.array([x]), np.array([zc]))[0])
            for side in (-1.0, 1.0):
                parts.add(
                    "tyres",
                    cylinder_between(
                        (x, side * (hull_y - 0.05), zc),
                        (x, side * (hull_y + thick), zc),
                        tyre_r,
                        sections=10,
                    ),
                    BLACK_RUBBER,
                )
        x += pitch

    x_aft = -u(rng, 0.12, 0.2) * length
    x_fwd = u(rng, 0.12, 0.22) * length
    z_low, z_high = deck_range(form, x_aft, x_fwd)
    hw = u(rng, 0.6, 0.7) * min_half_beam(form, x_aft, x_fwd)
    z_roof = z_high + u(rng, 2.3, 2.8)
    parts.add_block("superstructure", house_paint, x_aft, x_fwd, hw, z_low - EMBED_M, z_roof)
    _side_windows(parts, x_aft + 0.6, x_fwd - 0.6, hw, z_roof - 1.4, z_roof - 0.6, glass, extra)
    # Wheelhouse: set at the forward end of the house and raised on a pedestal so the master
    # sees the bow and the stern (ASD tug general arrangements: wheelhouse deck about 5-7 m
    # over the main deck, glazed all round).
    wh_len = u(rng, 0.14, 0.2) * length
    wh_x1 = x_fwd + 0.3
    wh_z0 = z_roof + u(rng, 0.0, 1.0)
    wh_z1 = wh_z0 + u(rng, 2.3, 2.6)
    wh_hw = u(rng, 0.3, 0.36) * beam
    parts.add_block(
        "superstructure",
        house_paint,
        wh_x1 - wh_len,
        wh_x1,
        wh_hw,
        z_roof - EMBED_M,
        wh_z1,
        front_rake=0.2,
        aft_rake=0.2,
    )
    _wheelhouse_glazing(parts, wh_x1 - wh_len, wh_x1, wh_hw, wh_z0, wh_z1 - wh_z0, glass)
    add_house_rails(
        parts,
        (x_aft, wh_x1 - wh_len),
        hw,
        z_roof,
        (wh_x1 - wh_len + 0.2, wh_x1 - 0.2),
        wh_hw,
        wh_z1,
    )
    mast_paint = pick_material(MACHINERY_PAINTS, extra)
    x_mast = wh_x1 - 0.5 * wh_len
    # Mast 3-5 m over the wheelhouse roof, at least to 0.31 L above the water: the least air
    # draft the library promises for a tug (library.MIN_AIR_DRAFT_RATIO, 0.30 L; Damen ASD
    # 2411-3212 masts top out about 12-16 m up).
    mast_h = max(u(rng, 3.0, 5.0), 0.31 * length - wh_z1)
    parts.add_mast(x_mast, 0.0, wh_z1, mast_h, 0.12, house_paint, yard_half_width=1.2)
    _radar(parts, x_mast, wh_z1 + 0.45 * mast_h, min(1.2, 0.8 * wh_hw), mast_paint)
    funnel = pick_material(FUNNEL_PAINTS, rng)
    xs = x_aft + u(rng, 0.1, 0.2) * (x_fwd - x_aft)
    stack_r = u(rng, 0.25, 0.35)
    for side in (-1.0, 1.0):
        stack_top = z_roof + u(rng, 2.5, 4.0)
        parts.add(
            "funnel",
            vertical_cylinder(xs, side * 0.22 * beam, stack_r, z_roof - EMBED_M, stack_top),
            funnel,
        )
        # Soot: the top 0.4 m of each exhaust stack is black.
        parts.add(
            "funnel_top",
            vertical_cylinder(
                xs, side * 0.22 * beam, stack_r + 0.03, stack_top - 0.4, stack_top + 0.02
            ),
            BLACK_RUBBER,
        )
    # Afterdeck: towing winch (a drum between two cheeks, about 1.2-1.6 m across on a 30 m
    # tug) aft of the house and an H-bitt (towing post) near the stern.
    gear = pick_material(MACHINERY_PAINTS, extra)
    xw = x_aft - u(extra, 0.06, 0.09) * length
    zw = deck_at(form, xw)
    wr = u(extra, 0.02, 0.028) * length
    half = 0.45 * min_half_beam(form, xw - wr, xw + wr)
    parts.add(
        "towing_winch",
        cylinder_between((xw, -half, zw + wr + 0.2), (xw, half, zw + wr + 0.2), wr, sections=12),
        gear,
    )
    for side in (-1.0, 1.0):
        parts.add(
            "towing_winch",
            box(
                xw - 1.2 * wr,
                xw + 1.2 * wr,
                side * half,
                side * (half + 0.15),
                zw - EMBED_M,
                zw + 2 * wr + 0.4,
            ),
            gear,
        )
    xt = -form.half_length + u(extra, 0.08, 0.12) * length
    zt = deck_at(form, xt)
    bitt_h = u(extra, 1.0, 1.4)
    half = 0.35 * min_half_beam(form, xt - 0.3, xt + 0.3)
    for side in (-1.0, 1.0):
        parts.add(
            "towing_bitt",
            vertical_cylinder(xt, side * half, 0.2, zt - EMBED_M, zt + bitt_h),
            funnel,
        )
    parts.add(
        "towing_bitt",
        cylinder_between((xt, -half, zt + 0.7 * bitt_h), (xt, half, zt + 0.7 * bitt_h), 0.15),
        funnel,
    )
    if rng.random() < 0.5:  # towing staple over the aft deck
        xt = -u(rng, 0.3, 0.38) * length
        zt = deck_at(form, xt)
        half = 0.7 * min_half_beam(form, xt - 0.3, xt + 0.3)
        top = zt + u(rng, 1.8, 2.4)
        for side in (-1.0, 1.0):
            parts.add(
                "towing_staple",
                cylinder_between((xt, side * half, zt - EMBED_M), (xt, side * half, top), 0.12),
                funnel,
            )
        parts.add(
            "towing_staple", cylinder_between((xt, -half, top), (xt, half, top), 0.12), funnel
        )
    return parts.to_parts()
