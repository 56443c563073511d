"""Leisure craft: sailing yacht (sloop) and speedboat (small working vessels are in
:mod:`seahaze.vessels.smallcraft`).

Builders receive principal dimensions sampled inside the class ranges (see
:mod:`seahaze.vessels.library`) and draw the rest from ``rng`` inside the ranges written next
to each draw. Metres throughout; vessel frame x forward, y port, z up, waterline z = 0.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from seahaze.vessels.geometry import (
    HullForm,
    box,
    cambered_sail,
    convex_body,
    cylinder_between,
    tapered_block,
)
from seahaze.vessels.materials import (
    ANTIFOULING_REDS,
    FUNNEL_PAINTS,
    HULL_PAINTS_SMALL,
    MACHINERY_PAINTS,
    SAIL_CLOTH,
    SUPERSTRUCTURE_WHITES,
    WINDOW_GLASS,
    Material,
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

__all__ = ["build_sailboat", "build_speedboat"]


def build_sailboat(d: PrincipalDims, rng: np.random.Generator) -> list[VesselPart]:
    """Sailing yacht (sloop): low hull with counter stern, coachroof, fin keel and rudder,
    mast about 1.2-1.45 L above deck, mainsail + jib set (75 %) or stowed on the boom."""
    length, beam = d.length, d.beam
    form = HullForm(
        length=length,
        beam=beam,
        draft=d.draft,
        freeboard=d.freeboard,
        sheer_fwd=u(rng, 0.1, 0.25) * d.depth,
        sheer_aft=u(rng, 0.0, 0.05) * d.depth,
        entrance_exponent=u(rng, 1.5, 2.0),
        transom_width=u(rng, 0.55, 0.9),
        stem_rake=u(rng, 0.02, 0.1),
        stem_exponent=1.0,
        stern_cutup=u(rng, 0.3, 0.4),
        transom_immersion=u(rng, -0.6, -0.1),
        section_exponent=2.0,
        bow_flare=0.15,
        topside_flare=0.08,
    )
    hull = HULL_PAINTS_SMALL[0] if rng.random() < 0.75 else pick_material(HULL_PAINTS_SMALL, rng)
    deck_white = pick_material(SUPERSTRUCTURE_WHITES, rng)
    antifouling = pick_material(ANTIFOULING_REDS, rng)
    glass = WINDOW_GLASS[0]
    parts = PartSet()
    parts.add_hull(form, hull, bottom=antifouling, boot_top_z=0.08)

    # Coachroof.
    xa, xf = -u(rng, 0.05, 0.15) * length, u(rng, 0.12, 0.22) * length
    z0, _ = deck_range(form, xa, xf)
    hw = u(rng, 0.55, 0.7) * min_half_beam(form, xa, xf)
    ch = float(np.clip(u(rng, 0.05, 0.07) * length, 0.4, 1.5))
    parts.add_block(
        "superstructure",
        deck_white,
        xa,
        xf,
        hw,
        z0 - EMBED_M,
        z0 + ch,
        front_rake=0.6 * ch,
        top_inset=0.1 * hw,
    )
    parts.add_window_band(
        xa + 0.3 * (xf - xa), xf - ch, 0.95 * hw, z0 + 0.35 * ch, z0 + 0.7 * ch, glass, proud=0.02
    )

    # Fin keel and spade rudder: below the water, they set the draft the mesh reports.
    total_draft = max(d.draft + 0.3, u(rng, 0.13, 0.19) * length)
    chord_top, chord_bot = 0.14 * length, 0.08 * length
    thick = max(0.04, 0.012 * length)
    keel_pts = (
        [(0.06 * length - chord_top, s * thick, -0.7 * d.draft) for s in (-1, 1)]
        + [(0.06 * length, s * thick, -0.7 * d.draft) for s in (-1, 1)]
        + [(0.04 * length - chord_bot, s * 0.6 * thick, -total_draft) for s in (-1, 1)]
        + [(0.04 * length, s * 0.6 * thick, -total_draft) for s in (-1, 1)]
    )
    parts.add("keel", convex_body(keel_pts), antifouling)
    xr = -0.38 * length
    zr = float(form.keel_z(np.array([xr]))[0])
    rudder_pts = [
        (xr + dx, s * 0.6 * thick, z)
        for dx in (-0.04 * length, 0.02 * length)
        for s in (-1, 1)
        for z in (zr + 0.1, -0.6 * total_draft)
    ]
    parts.add("keel", convex_body(rudder_pts), antifouling)

    # Rig.
    x_mast = u(rng, 0.02, 0.12) * length
    deck_m = deck_at(form, x_mast)
    mast_h = u(rng, 1.2, 1.45) * length
    mast_r = max(0.05, 0.008 * length)
    spar = pick_material((MACHINERY_PAINTS[1], MACHINERY_PAINTS[2]), rng)
    parts.add_mast(x_mast, 0.0, deck_m, mast_h, mast_r, spar, yard_half_width=0.12 * beam)
    boom_z = deck_m + min(1.2, 0.1 * length) + ch * 0.5
    boom_len = min(u(rng, 0.33, 0.42) * length, x_mast + 0.45 * length)
    # Without a wind the sails are set at random (the draws as they always were).
    side = 1.0 if rng.random() < 0.5 else -1.0
    max_angle = np.degrees(np.arcsin(min(1.0, 0.4 * beam / boom_len)))
    angle = np.radians(u(rng, 0.0, min(25.0, max_angle))) * side
    sails_set = rng.random() < 0.75
    if d.wind_from_deg is not None:
        side, angle, sails_set = _trim(d.wind_from_deg)
    clew = (x_mast - boom_len * np.cos(angle), boom_len * np.sin(angle), boom_z)
    tack = (x_mast - mast_r, 0.0, boom_z)
    parts.add("boom", cylinder_between(tack, clew, 0.7 * mast_r), spar)
    if sails_set:
        cloth = pick_material(SAIL_CLOTH, rng)
        head = (x_mast - mast_r, 0.0, deck_m + 0.97 * mast_h)
        leeward = (0.0, side, 0.0)
        parts.add("sail_main", cambered_sail(tack, head, clew, MAIN_CAMBER, leeward), cloth)
        jib_tack = (
            form.half_length - 0.03 * length,
            0.0,
            deck_at(form, form.half_length - 0.03 * length) + 0.3,
        )
        jib_head = (x_mast + mast_r, 0.0, deck_m + u(rng, 0.75, 0.9) * mast_h)
        jib_x = x_mast - u(rng, 0.0, 0.1) * length
        if d.wind_from_deg is None:
            jib_reach = u(rng, 0.15, 0.4) * beam
        else:  # sheeted like the main, its foot swung to leeward, at most to the rail's lead
            swung = (jib_tack[0] - jib_x) * abs(np.sin(angle))
            jib_reach = float(np.clip(swung, 0.15 * beam, 0.6 * beam))
        jib_clew = (jib_x, side * jib_reach, deck_m + 0.6)
        jib = cambered_sail(jib_tack, jib_head, jib_clew, JIB_CAMBER, leeward)
        parts.add("sail_jib", jib, cloth)
    else:
        # A stowed sail's cover is a closed body of heavy canvas: opaque.
        cover = replace(pick_material(FUNNEL_PAINTS[1:2] + SAIL_CLOTH[2:], rng), transmittance=0.0)
        parts.add("sail_cover", cylinder_between(tack, clew, 2.5 * mast_r), cover)
    return parts.to_parts()


MAIN_CAMBER = 0.10
"""Depth of a set mainsail's belly at mid-chord, a share of the chord (the sailmaker's
"draft"): trimmed cruising mainsails carry some 8-12 %."""
JIB_CAMBER = 0.12
"""The same for the jib: headsails are cut fuller, some 10-15 %."""

NO_GO_DEG = 40.0
"""A sloop cannot sail closer to the wind than about this many degrees off the bow (the "no-go
zone"): pointing closer, it motors with its sails furled."""


def _trim(wind_from_deg: float) -> tuple[float, float, bool]:
    """How a sloop with the wind ``wind_from_deg`` off its bow (positive: from port) sets its
    mainsail: the side its boom swings to (+1 port, −1 starboard: always to leeward), the
    boom's angle off the centreline (rad, signed like the side) and whether the sails are set
    at all (not inside :data:`NO_GO_DEG`). The boom goes out to about half the wind's angle off
    the bow, the usual trim from close-hauled (about 20°) through a beam reach (45°) to a run
    (85°, the most a boom swings before the shrouds); the true wind stands in for the apparent
    wind, which a moving boat sees further forward."""
    off_bow = abs(wind_from_deg)
    side = -1.0 if wind_from_deg > 0.0 else 1.0
    if off_bow < NO_GO_DEG:
        return side, side * np.radians(5.0), False
    return side, side * np.radians(min(0.5 * off_bow, 85.0)), True


def build_speedboat(d: PrincipalDims, rng: np.random.Generator) -> list[VesselPart]:
    """Planing motorboat: deep-V hull with a long raked bow and full-width transom; cuddy
    cabin, centre console with T-top, or open runabout with a windscreen; outboard engines."""
    length, beam = d.length, d.beam
    form = HullForm(
        length=length,
        beam=beam,
        draft=d.draft,
        freeboard=d.freeboard,
        sheer_fwd=u(rng, 0.15, 0.35) * d.depth,
        entrance_exponent=u(rng, 1.3, 1.8),
        transom_width=u(rng, 0.85, 0.98),
        stem_rake=u(rng, 0.15, 0.25),
        stem_exponent=1.8,
        stern_cutup=0.05,
        transom_immersion=u(rng, 0.85, 1.0),
        section_exponent=u(rng, 1.0, 1.4),
        bow_flare=0.15,
        topside_flare=u(rng, 0.08, 0.15),
    )
    hull = pick_material(HULL_PAINTS_SMALL, rng)
    white = pick_material(SUPERSTRUCTURE_WHITES, rng)
    glass = WINDOW_GLASS[0]
    parts = PartSet()
    parts.add_hull(
        form,
        hull,
        bottom=pick_material(HULL_PAINTS_SMALL + ANTIFOULING_REDS, rng),
        boot_top_z=u(rng, 0.05, 0.2),
    )
    style = ("cuddy", "console", "open")[int(rng.integers(3))]
    if style == "cuddy":
        xa, xf = -u(rng, 0.0, 0.1) * length, u(rng, 0.2, 0.3) * length
        z0, _ = deck_range(form, xa, xf)
        hw = 0.75 * min_half_beam(form, xa, xf)
        h = float(np.clip(u(rng, 0.06, 0.08) * length, 0.4, 1.1))
        parts.add_block(
            "superstructure",
            white,
            xa,
            xf,
            hw,
            z0 - EMBED_M,
            z0 + h,
            front_rake=0.7 * (xf - xa),
            top_inset=0.15 * hw,
        )
        _windscreen(parts, xa + 0.3 * (xf - xa), z0 + h, hw * 0.9, glass)
    elif style == "console":
        xa, xf = -u(rng, 0.03, 0.08) * length, u(rng, 0.02, 0.06) * length
        z0, _ = deck_range(form, xa, xf)
        hw = 0.25 * beam
        parts.add_block("superstructure", white, xa, xf, hw, z0 - EMBED_M, z0 + 1.1, front_rake=0.3)
        _windscreen(parts, xf - 0.2, z0 + 1.1, hw, glass)
        roof_z = z0 + u(rng, 2.1, 2.4)
        rx0, rx1 = xa - 0.1 * length, xf + 0.02 * length
        rhw = min(0.38 * beam, min_half_beam(form, rx0, rx1) - 0.1)
        for x in (rx0 + 0.2, rx1 - 0.2):
            for s in (-1.0, 1.0):
                parts.add(
                    "t_top",
                    cylinder_between(
                        (x, s * 0.8 * rhw, z0 - EMBED_M), (x, s * 0.8 * rhw, roof_z), 0.04
                    ),
                    white,
                )
        parts.add("t_top", box(rx0, rx1, -rhw, rhw, roof_z, roof_z + 0.12), white)
    else:
        xw = u(rng, 0.05, 0.15) * length
        _windscreen(parts, xw, deck_at(form, xw), 0.8 * min_half_beam(form, xw - 0.5, xw), glass)
    if length < 12.0 and rng.random() < 0.7:
        engine = pick_material(
            (MACHINERY_PAINTS[1], MACHINERY_PAINTS[2], *ANTIFOULING_REDS[2:]), rng
        )
        count = 1 if length < 7.0 else 2
        zt = deck_at(form, -form.half_length)
        for i in range(count):
            # Mounted on the transom inside the overall length (LOA includes the engines).
            engine_body = tapered_block(
                -form.half_length,
                -form.half_length + 0.55,
                0.22,
                zt - 0.9,
                zt + 0.45,
                aft_rake=0.15,
            )
            engine_body.apply_translation([0.0, (i - 0.5 * (count - 1)) * 0.35 * beam, 0.0])
            parts.add("outboards", engine_body, engine)
    return parts.to_parts()


def _windscreen(parts: PartSet, x: float, z: float, half_width: float, glass: Material) -> None:
    """Raked windscreen: a thin dark plate leaning aft from (x, z) up 0.5 m."""
    pts = [(x, s * half_width, z - 0.05) for s in (-1, 1)]
    pts += [(x - 0.35, s * 0.9 * half_width, z + 0.5) for s in (-1, 1)]
    pts += [(px - 0.04, py, pz) for px, py, pz in pts]
    parts.add("windows", convex_body(pts), glass)
