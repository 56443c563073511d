"""Deck gear of bulk carriers and tankers (issue #32): what makes the two read as what they
are forward of the house (:mod:`seahaze.vessels.accommodation`).

- a bulk carrier's hatch coamings with their stays, hatch covers with their panel joints
  (fore-aft folding on handy sizes, side-rolling with their stowage rails on larger ships), deck
  cranes with a house, cab and box-girder jib, stowed on a jib rest or topped up;
- a tanker's pipe deck (cargo lines on stools under a catwalk with rails), tank hatches and
  vent risers, a midship manifold with its drip trays; the windlasses on the forecastle.

Helpers take their dimensions as arguments and draw their own variety from the ``rng`` they are
given (the builders pass a generator seeded by the vessel's dimensions,
:func:`seahaze.vessels.parts.detail_rng`, never the caller's). Metres; vessel frame x forward,
y port, z up, waterline z = 0.

Proportions (typical published values, not design data):

- Hatch covers: steel covers opening fore and aft on handy-sized bulk carriers, sideways
  (side-rolling, stowed on a steel frame between coaming and rail) from Panamax up
  (handybulk.com, "Cement" / bulk carrier notes); coamings about 2 m high with stays every
  2.5-3 m.
- Deck cranes of Handymax/Supramax bulk carriers: four of about 30 t SWL (Wikipedia
  "Handymax"), pedestal about 3-3.6 m across, jib about 25-28 m (outreach ~26 m); at sea the
  jibs lie in jib rests (cradles) a few metres above the hatch covers, fore-aft.
- Tanker manifold: the cargo manifold at midships with its flanges about 3-4.6 m inboard of the
  side over a drip tray (OCIMF "Recommendations for Oil Tanker Manifolds", 4.6 m on large
  tankers); hose-handling cranes beside it (handybulk.com "Tanker operations").
"""

from __future__ import annotations

from collections.abc import Callable
from itertools import pairwise

import numpy as np

from seahaze.vessels.geometry import (
    HullForm,
    box,
    boxes,
    convex_body,
    cylinder_between,
    tapered_block,
    vertical_cylinder,
)
from seahaze.vessels.materials import FUNNEL_PAINTS, Material
from seahaze.vessels.parts import EMBED_M, PartSet, deck_at, deck_range, min_half_beam, u

__all__ = [
    "SEAM_DARK",
    "add_deck_crane",
    "add_hatches",
    "add_manifold",
    "add_pipe_deck",
    "add_windlasses",
]

SEAM_DARK = FUNNEL_PAINTS[0]
"""The dark of joints between hatch-cover panels (black paint, 30/255 sRGB)."""


def add_hatches(
    parts: PartSet,
    form: HullForm,
    hatches: list[tuple[float, float, float]],
    *,
    coaming_height: float,
    cover_height: float,
    coaming_paint: Material,
    cover_paint: Material,
    side_rolling: bool,
) -> list[tuple[float, float, float]]:
    """Raised hatches, one per ``(x0, x1, half-width)`` of the coaming: the coaming from the
    deck up ``coaming_height`` with stays on both sides every 2.5-2.8 m, the cover 0.25 m
    over it all round and ``cover_height`` high with a cambered top; dark joints split folding
    covers into four panels fore and aft, side-rolling ones in two at the centreline, whose
    stowage rails run out to near the ship's side at both ends. Returns each cover's
    ``(x0, x1, z top)``."""
    covers = []
    for x0, x1, hw in hatches:
        z_low, z_high = deck_range(form, x0, x1)
        z_c = z_high + coaming_height
        z_t = z_c + cover_height
        parts.add("hatch_coamings", box(x0, x1, -hw, hw, z_low - EMBED_M, z_c), coaming_paint)
        count = max(2, int((x1 - x0) // 2.6))
        xs = x0 + (np.arange(count) + 0.5) * (x1 - x0) / count
        lower = [(x - 0.06, s * hw, z_low - EMBED_M) for x in xs for s in (-1.0, 1.0)]
        upper = [(x + 0.06, s * (hw + 0.5), z_c - 0.3) for x in xs for s in (-1.0, 1.0)]
        parts.add("hatch_coamings", boxes(np.array(lower), np.array(upper)), coaming_paint)
        hw_c = hw + 0.25
        inset = 0.12 * hw_c
        parts.add(
            "hatch_covers",
            tapered_block(
                x0 - 0.25,
                x1 + 0.25,
                hw_c,
                z_c - 0.05,
                z_t,
                top_inset=inset,
                front_rake=0.2,
                aft_rake=0.2,
            ),
            cover_paint,
        )
        if side_rolling:
            joints = [(x0 - 0.27, x1 + 0.27, -0.06, 0.06, z_t - 0.3, z_t + 0.03)]
            for xe, s in ((x0 - 0.7, -1.0), (x1 + 0.7, 1.0)):
                y_side = min_half_beam(form, xe - 0.3, xe + 0.3) - 0.6
                for side in (-1.0, 1.0):
                    parts.add(
                        "hatch_coamings",
                        box(
                            xe - 0.2 * s,
                            xe + 0.2 * s,
                            side * hw,
                            side * y_side,
                            z_low - EMBED_M,
                            z_c,
                        ),
                        coaming_paint,
                    )
        else:
            joints = [
                (xj - 0.06, xj + 0.06, -hw_c - 0.03, hw_c + 0.03, z_c, z_t + 0.03)
                for xj in x0 + (x1 - x0) * np.array([0.25, 0.5, 0.75])
            ]
        lo = np.array([(a, c, e) for a, _, c, _, e, _ in joints])
        hi = np.array([(b, d, f) for _, b, _, d, _, f in joints])
        parts.add("hatch_cover_joints", boxes(lo, hi), SEAM_DARK)
        covers.append((x0 - 0.25, x1 + 0.25, z_t))
    return covers


def add_deck_crane(
    parts: PartSet,
    *,
    x: float,
    y: float,
    z_deck: float,
    pedestal_height: float,
    pedestal_radius: float,
    jib_length: float,
    direction: float,
    paint: Material,
    glass: Material,
    elevation_deg: float | None = None,
    rest_on: Callable[[float], float] | None = None,
    rest_height: float = 3.0,
    name: str = "cranes",
) -> tuple[float, float]:
    """A deck crane: pedestal, slewing house (about 3.8 by 3 pedestal radii, 2.2 radii + 0.6 m
    high) with the operator's cab at its front on the port side, a box-girder jib tapering to
    its head, fore-aft (``direction`` +1 forward, -1 aft), and the post on the house the luffing
    wires run from (the wires themselves, a few cm thick, are left out: far under a pixel).

    Topped at ``elevation_deg``; or (None) stowed, its head on a jib rest ``rest_height`` above
    what ``rest_on(x)`` gives (the hatch cover's top or the deck under the head). Returns the
    jib head's (x, z)."""
    r = pedestal_radius
    z_ped = z_deck + pedestal_height
    parts.add(name, vertical_cylinder(x, y, r, z_deck - EMBED_M, z_ped, sections=12), paint)
    hl, hw, hh = 1.9 * r, 1.5 * r, 2.2 * r + 0.6
    parts.add(name, box(x - hl, x + hl, y - hw, y + hw, z_ped - 0.1, z_ped + hh), paint)
    front = x + direction * hl
    cab = (front - direction * 0.3, front + direction * 1.4, y + 0.45 * hw, y + hw, z_ped + 0.4)
    parts.add(name, box(cab[0], cab[1], cab[2], cab[3], cab[4], cab[4] + 2.2), paint)
    parts.add(
        "windows",
        box(
            cab[1] - direction * 0.1,
            cab[1] + direction * 0.05,
            cab[2] + 0.15,
            cab[3] - 0.15,
            cab[4] + 1.0,
            cab[4] + 2.0,
        ),
        glass,
    )
    heel = np.array([x + direction * (hl - 0.2), y, z_ped + 0.45 * hh])
    if elevation_deg is None and rest_on is None:
        raise ValueError("a stowed crane needs rest_on: where its jib rest stands")
    if elevation_deg is None:
        e = 0.0
        for _ in range(3):  # the head's height depends on where it lands: settle it
            head_x = heel[0] + direction * jib_length * np.cos(e)
            target = rest_on(float(head_x)) + rest_height
            e = float(np.arcsin(np.clip((target - heel[2]) / jib_length, -0.35, 0.35)))
    else:
        e = float(np.radians(elevation_deg))
    along = np.array([direction * np.cos(e), 0.0, np.sin(e)])
    normal = np.array([-direction * np.sin(e), 0.0, np.cos(e)])
    head = heel + jib_length * along
    points = []
    for p, half_w, half_h in ((heel, 0.45 * r, 0.5 * r), (head, 0.22 * r, 0.28 * r)):
        for s in (-1.0, 1.0):
            for t in (-1.0, 1.0):
                points.append(p + np.array([0.0, s * half_w, 0.0]) + t * half_h * normal)
    parts.add(name, convex_body(np.array(points)), paint)
    post_x = x - direction * 0.6 * hl
    post_top = z_ped + hh + 1.2 * r + 0.8
    parts.add(
        name,
        box(post_x - 0.25, post_x + 0.25, y - 0.6 * hw, y + 0.6 * hw, z_ped + hh - 0.1, post_top),
        paint,
    )
    if rest_on is not None and elevation_deg is None:
        base = rest_on(float(head[0]))
        top = head[2] - 0.28 * r - 0.05
        if top - base > 0.3:
            parts.add(
                name,
                vertical_cylinder(float(head[0]), y, 0.3, base - EMBED_M, top, sections=8),
                paint,
            )
            parts.add(
                name,
                box(
                    head[0] - 0.4,
                    head[0] + 0.4,
                    y - 0.35 * r - 0.1,
                    y + 0.35 * r + 0.1,
                    top - 0.3,
                    top + 0.05,
                ),
                paint,
            )
    return float(head[0]), float(head[2])


def add_windlasses(
    parts: PartSet, form: HullForm, paint: Material, rng: np.random.Generator
) -> None:
    """Anchor windlasses on the forecastle, one a side: a bed, a chain wheel and a warping drum
    on a shaft across the ship (about 2.6 × 1.6 m bed, 1.2 m drum on a 32 m beam; scaled with
    the beam)."""
    s = float(np.clip(form.beam / 32.0, 0.5, 1.5))
    x = form.half_length - form.forecastle_length * u(rng, 0.45, 0.6)
    z = deck_at(form, x)
    half = min_half_beam(form, x - 1.5 * s, x + 1.5 * s)
    for side in (-1.0, 1.0):
        yc = side * min(0.2 * form.beam, 0.55 * half)
        parts.add(
            "windlass",
            box(x - 1.3 * s, x + 1.3 * s, yc - 0.8 * s, yc + 0.8 * s, z - EMBED_M, z + 0.9 * s),
            paint,
        )
        parts.add(
            "windlass",
            cylinder_between(
                (x, yc - 0.9 * s, z + 1.3 * s), (x, yc + 0.9 * s, z + 1.3 * s), 0.6 * s, sections=12
            ),
            paint,
        )


def add_pipe_deck(
    parts: PartSet,
    form: HullForm,
    x0: float,
    x1: float,
    *,
    bundle_half_width: float,
    pipes_top: float,
    catwalk_height: float,
    pipe_paint: Material,
    catwalk_paint: Material,
    rng: np.random.Generator,
) -> None:
    """A tanker's main deck from ``x0`` to ``x1``: cargo lines fore and aft on the centreline
    (as many as fit ``bundle_half_width``, 0.4-0.9 m across by the beam) on stools every
    6-9 m, their tops ``pipes_top`` above the deck; the catwalk over them, ``catwalk_height``
    up (level with the poop and the forecastle it joins), on posts every 9-12 m that carry its
    railing on up; a tank hatch and a vent riser each side per cargo tank
    (5-7 pairs)."""
    # The lines and the catwalk follow the deck's sheer chord by chord (the deck is convex, so
    # a chord never dips into it).
    stations = np.linspace(x0, x1, 7)
    deck = form.deck_z(stations)

    def over(x: float, height: float) -> float:
        return float(np.interp(x, stations, deck)) + height

    r = float(np.clip(0.009 * form.beam, 0.2, 0.45))
    pitch = 2.0 * r + 0.3
    n = int(np.clip(2.0 * bundle_half_width // pitch, 3, 10))
    ys = (np.arange(n) - 0.5 * (n - 1)) * pitch
    axis = max(pipes_top, 2.0 * r + 0.3) - r
    for y in ys:
        for xa, xb in pairwise(stations):
            parts.add(
                "cargo_pipes",
                cylinder_between((xa, y, over(xa, axis)), (xb, y, over(xb, axis)), r, sections=8),
                pipe_paint,
            )
    xs = np.arange(x0 + 1.0, x1 - 0.5, u(rng, 6.0, 9.0))
    wide = ys[-1] + r + 0.2
    lower = [(x - 0.15, -wide, deck_at(form, x) - EMBED_M) for x in xs]
    upper = [(x + 0.15, wide, over(x, axis) - 0.5 * r) for x in xs]
    parts.add("cargo_pipes", boxes(np.array(lower), np.array(upper)), pipe_paint)

    # The catwalk's plank and its railing: a top rail with its kick plate below read as one
    # 0.25 m band 1 m over the plank (the stanchions and the rail, 3-6 cm bars, would be a
    # tenth of a pixel at 200 m and are left out).
    h = catwalk_height
    for xa, xb in pairwise(stations):
        for y0, y1, z0, z1 in [(-0.6, 0.6, -0.25, 0.0)] + [
            (s * 0.58 - 0.025, s * 0.58 + 0.025, 0.8, 1.05) for s in (-1.0, 1.0)
        ]:
            corners = [(x, y, over(x, h) + z) for x in (xa, xb) for y in (y0, y1) for z in (z0, z1)]
            parts.add("catwalk", convex_body(np.array(corners)), catwalk_paint)
    lower, upper = [], []
    for x in np.arange(x0 + 1.0, x1 - 0.5, u(rng, 9.0, 12.0)):
        for s in (-1.0, 1.0):
            # Posts from the deck up under the plank, and their stanchions on up to the rail.
            lower.append((x - 0.12, s * 0.5 - 0.12, deck_at(form, x) - EMBED_M))
            upper.append((x + 0.12, s * 0.5 + 0.12, over(x, h) + 0.9))
    parts.add("catwalk", boxes(np.array(lower), np.array(upper)), catwalk_paint)

    tanks = int(rng.integers(5, 8))
    lower, upper = [], []
    for k in range(tanks):
        xt = x0 + (k + 0.5) * (x1 - x0) / tanks
        z = deck_at(form, xt)
        half = min_half_beam(form, xt - 1.0, xt + 1.0)
        for s in (-1.0, 1.0):
            yh = s * min(0.28 * form.beam, half - 1.5)
            lower.append((xt - 0.65, yh - 0.65, z - EMBED_M))
            upper.append((xt + 0.65, yh + 0.65, z + 0.9))
            parts.add(
                "tank_fittings",
                vertical_cylinder(
                    xt + 3.0,
                    s * 0.15 * form.beam,
                    0.18,
                    z - EMBED_M,
                    z + u(rng, 2.5, 3.5),
                    sections=8,
                ),
                pipe_paint,
            )
    parts.add("tank_fittings", boxes(np.array(lower), np.array(upper)), pipe_paint)


def add_manifold(
    parts: PartSet,
    form: HullForm,
    x: float,
    *,
    paint: Material,
    rng: np.random.Generator,
) -> tuple[float, float]:
    """The midship cargo manifold centred on ``x``: 3-6 lines 1.8-2.5 m apart across the ship,
    about a metre over the pipe deck, each ending in a valve and a flange 3-4.6 m inboard of
    either side (0.1 B), over a drip tray. Returns the x extent of its drip trays."""
    n = int(rng.integers(3, 7))
    spacing = u(rng, 1.8, 2.5)
    xs = x + (np.arange(n) - 0.5 * (n - 1)) * spacing
    x_a, x_b = float(xs[0] - 1.2), float(xs[-1] + 1.2)
    half = min_half_beam(form, x_a, x_b)
    y_end = half - float(np.clip(0.1 * form.beam, 3.0, 4.6))
    r = float(np.clip(0.008 * form.beam, 0.2, 0.4))
    z_low, z_high = deck_range(form, x_a, x_b)
    zc = z_high + u(rng, 1.0, 1.4)
    for xl in xs:
        parts.add(
            "manifold", cylinder_between((xl, -y_end, zc), (xl, y_end, zc), r, sections=8), paint
        )
        for s in (-1.0, 1.0):
            parts.add(
                "manifold",
                vertical_cylinder(
                    xl, s * (y_end - 1.2), 1.5 * r, zc - 1.2 * r, zc + 1.4 * r + 0.4, sections=8
                ),
                paint,
            )
            parts.add(
                "manifold",
                cylinder_between(
                    (xl, s * (y_end - 0.15), zc), (xl, s * (y_end + 0.1), zc), 1.6 * r, sections=10
                ),
                paint,
            )
    for s in (-1.0, 1.0):
        parts.add(
            "manifold",
            box(
                x_a,
                x_b,
                s * (y_end - 1.8),
                s * min(y_end + 1.2, half - 0.3),
                z_low - EMBED_M,
                z_high + 0.5,
            ),
            paint,
        )
    return x_a, x_b
