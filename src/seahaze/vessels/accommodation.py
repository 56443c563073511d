"""The aft house of bulk carriers and tankers (issue #32): a poop in the hull's paint, tiers
of accommodation with rows of windows on the front and the sides, a wheelhouse glazed at the
front and sides with bridge wings out to the ship's side, scanners on the radar mast, a
coloured band round the funnel, a freefall lifeboat on the stern or davit boats beside the
house.

Helpers take their dimensions as arguments and draw their own variety from the ``rng`` they are
given (the builders pass a generator seeded by the vessel's dimensions,
:func:`seahaze.vessels.parts.detail_rng`, never the caller's). Metres; vessel frame x forward,
y port, z up, waterline z = 0.

Proportions (typical published values, not design data):

- SOLAS V/22: the bridge wings reach the ship's side (the side must be visible from them).
- IMO MSC/Circ.982: wheelhouse front windows, sill at most 1.0 m, head at least 2.0 m above
  the bridge deck.
- SOLAS III/31 and the LSA Code 4.7: a freefall lifeboat on a launching ramp at the stern,
  bow down at 30-35°; boats for the crews of these ships are about 6.5-10 m long, 2.9-3.3 m
  wide and 3 m high (the size of a 25-30 person boat is about 8.5 × 3 × 3.2 m).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

from seahaze.vessels.geometry import (
    HullForm,
    box,
    boxes,
    convex_body,
    loft_hull,
    prism_from_outline,
    tapered_block,
)
from seahaze.vessels.materials import Material, material_from_srgb8
from seahaze.vessels.parts import EMBED_M, PartSet, deck_at, deck_range, min_half_beam, u
from seahaze.vessels.railings import RAIL_INSET_M, add_house_rails, guard_rail, stern_edge_path

__all__ = [
    "LIFEBOAT_ORANGE",
    "AftHouse",
    "add_aft_house",
    "add_davit_lifeboats",
    "add_freefall_lifeboat",
    "add_funnel_band",
    "add_poop_rails",
    "add_radar_scanners",
]

LIFEBOAT_ORANGE = material_from_srgb8("lifeboat_orange", (235, 100, 20), 0.5)
"""SOLAS international orange of lifeboats and rescue boats."""

Corner = tuple[float, float, float]


@dataclass(frozen=True)
class AftHouse:
    """Where an aft house stands (m): its ends, half-width, the deck under it, the poop's front
    and its height over the main deck, the roof of its tiers, the wheelhouse roof and how far
    out the bridge wings reach."""

    x_aft: float
    x_fwd: float
    half_width: float
    z_deck: float
    x_poop: float
    poop_height: float
    z_roof: float
    z_top: float
    wing_y: float


def _window_rows(
    x0: float, x1: float, half_width: float, z0s: list[float], pitch: float, width: float
) -> tuple[list[Corner], list[Corner]]:
    """Side windows: a box ``width`` long every ``pitch`` from ``x0`` to ``x1`` per sill
    height in ``z0s``, 1.1 m tall, through the house and 5 cm proud of both sides."""
    lower, upper = [], []
    count = max(1, int((x1 - x0) // pitch))
    for z0 in z0s:
        for k in range(count):
            xc = x0 + (k + 0.5) * (x1 - x0) / count
            lower.append((xc - 0.5 * width, -half_width - 0.05, z0))
            upper.append((xc + 0.5 * width, half_width + 0.05, z0 + 1.1))
    return lower, upper


def add_aft_house(
    parts: PartSet,
    form: HullForm,
    rng: np.random.Generator,
    *,
    x_aft: float,
    x_fwd: float,
    half_width: float,
    n_decks: int,
    deck_height: float,
    wheelhouse_length: float,
    paint: Material,
    hull_paint: Material,
    glass: Material,
) -> AftHouse:
    """The aft house of a bulk carrier or tanker: a poop one deck high in the hull's paint
    from the transom to just forward of the house, ``n_decks`` tiers of accommodation (the
    poop's the first) with rows of windows on the front and both sides (sills 1.0 m above each
    deck, windows 1.0-1.2 m wide every 2.2-3.4 m), a wheelhouse on top glazed at the front and
    sides, and bridge wings out to the ship's side (SOLAS V/22)."""
    z_deck, _ = deck_range(form, x_aft, x_fwd)
    z_roof = z_deck + n_decks * deck_height
    x_poop = x_fwd + u(rng, 0.5, 2.0)
    parts.add(
        "poop",
        loft_hull(
            form,
            z_low=lambda x: form.deck_z(x) - 0.3,
            z_high=lambda x: form.deck_z(x) + deck_height,
            inflate=0.01,
            x_range=(-form.half_length + 0.02, x_poop),
            n_stations=12,
            n_vertical=3,
        ),
        hull_paint,
    )
    parts.add(
        "superstructure", tapered_block(x_aft, x_fwd, half_width, z_deck - EMBED_M, z_roof), paint
    )
    sills = [z_deck + k * deck_height + 1.0 for k in range(1, n_decks)]
    front_pitch, front_w = u(rng, 2.2, 3.0), u(rng, 1.0, 1.2)
    columns = max(2, int(1.7 * half_width // front_pitch))
    lower: list[Corner] = []
    upper: list[Corner] = []
    for z0 in sills:
        for k in range(columns):
            yc = (k - 0.5 * (columns - 1)) * front_pitch
            lower.append((x_fwd - 0.2, yc - 0.5 * front_w, z0))
            upper.append((x_fwd + 0.05, yc + 0.5 * front_w, z0 + 1.1))
    side = _window_rows(x_aft + 1.5, x_fwd - 1.5, half_width, sills, u(rng, 2.4, 3.4), 1.0)
    lower += side[0]
    upper += side[1]

    wh_h = 1.1 * deck_height
    wh_x0, wh_x1 = x_fwd - wheelhouse_length, x_fwd + 0.5
    parts.add(
        "superstructure",
        tapered_block(wh_x0, wh_x1, half_width, z_roof - EMBED_M, z_roof + wh_h),
        paint,
    )
    # Glazing: the front band (IMO MSC/Circ.982: sill 1.0 m, head 2.0 m or more) and a band
    # along the sides' forward part; 5 cm proud.
    sill, head = z_roof + 1.0, z_roof + wh_h - 0.4
    lower += [(wh_x1 - 0.3, -(half_width - 0.3), sill), (wh_x0 + 1.0, -half_width - 0.05, sill)]
    upper += [(wh_x1 + 0.05, half_width - 0.3, head), (wh_x1 - 0.6, half_width + 0.05, head)]
    parts.add("windows", boxes(np.array(lower), np.array(upper)), glass)
    # Bridge wings: a deck with a solid bulwark, 2-3 m fore-aft at the wheelhouse front,
    # reaching the ship's greatest half-breadth (the hull may narrow under them aft).
    wing_y = 0.5 * form.beam - 0.02
    wing_len = u(rng, 2.0, 3.0)
    for s in (-1.0, 1.0):
        parts.add(
            "bridge_wings",
            box(
                wh_x1 - wing_len,
                wh_x1,
                s * (half_width - 0.2),
                s * wing_y,
                z_roof - 0.35,
                z_roof + 1.2,
            ),
            paint,
        )
    # A guard rail (ICLL Reg. 25, seahaze.vessels.railings) round the wheelhouse top (the
    # compass deck); the poop's: add_poop_rails, once the stern's lifeboat is placed.
    add_house_rails(
        parts, (x_aft, wh_x0), half_width, None, (wh_x0, wh_x1), half_width, z_roof + wh_h
    )
    return AftHouse(
        x_aft, x_fwd, half_width, z_deck, x_poop, deck_height, z_roof, z_roof + wh_h, wing_y
    )


def add_poop_rails(
    parts: PartSet, form: HullForm, house: AftHouse, paint: Material, gap_half_width: float
) -> None:
    """Guard rails round the poop deck aft of the house (the mooring deck; ICLL Reg. 25,
    :mod:`seahaze.vessels.railings`), open across the transom over ``gap_half_width`` (m)
    either side of the centreline where a freefall lifeboat's ramp runs out over the stern
    (0: closed)."""
    path = stern_edge_path(form, house.x_aft - 0.5, RAIL_INSET_M, rise=house.poop_height)
    if gap_half_width > 0.0:
        port = path[path[:, 1] >= gap_half_width]
        starboard = path[path[:, 1] <= -gap_half_width]
        runs = [run for run in (port, starboard) if len(run) >= 2]
    else:
        runs = [path]
    for run in runs:
        parts.add("railings", guard_rail(run), paint)


def add_funnel_band(
    parts: PartSet,
    x: float,
    half_length: float,
    half_width: float,
    z0: float,
    z1: float,
    rake: float,
    paint: Material,
    rng: np.random.Generator,
) -> None:
    """A company band round a funnel (:meth:`PartSet.add_funnel`'s casing from ``z0`` to
    ``z1``, its top ``rake`` aft): 12-20 % of its height, starting 45-60 % up, 3 % proud."""
    lo = u(rng, 0.45, 0.6)
    hi = lo + u(rng, 0.12, 0.2)
    scale_lo, scale_hi = 1.0 - 0.08 * lo, 1.0 - 0.08 * hi
    parts.add(
        "funnel_band",
        prism_from_outline(
            x - rake * lo,
            0.0,
            1.03 * half_length * scale_lo,
            1.03 * half_width * scale_lo,
            z0 + lo * (z1 - z0),
            z0 + hi * (z1 - z0),
            rake=rake * (hi - lo),
            top_scale=scale_hi / scale_lo,
        ),
        paint,
    )


def add_radar_scanners(
    parts: PartSet, x: float, z_base: float, height: float, paint: Material
) -> None:
    """A platform on the radar mast and two open-array scanners across the ship: S-band
    (about 3.9 m long) on the platform, X-band (about 2.4 m) higher up."""
    z = z_base + 0.55 * height
    parts.add("radar", box(x - 0.8, x + 0.8, -1.0, 1.0, z - 0.15, z), paint)
    parts.add("radar", box(x - 0.15, x + 0.15, -1.95, 1.95, z + 0.5, z + 0.75), paint)
    z = z_base + 0.9 * height
    parts.add("radar", box(x - 0.12, x + 0.12, -1.2, 1.2, z, z + 0.2), paint)


def _boat_body(p0: np.ndarray, axis: np.ndarray, up: np.ndarray, length: float) -> trimesh.Trimesh:
    """A closed lifeboat body ``length`` long from its bow at ``p0`` along ``axis`` (unit), its
    keel on that line, its canopy toward ``up`` (unit, normal to ``axis``): about 0.35 L wide
    and 0.37 L high, pointed at the bow, blunt at the stern."""
    w, h = 0.35 * length, 0.37 * length
    y = np.array([0.0, 1.0, 0.0])
    points = []
    for t, half, n in (
        (0.0, 0.08, 0.45),
        (0.12, 0.3, 0.0),
        (0.2, 0.5, 0.45),
        (0.92, 0.3, 0.0),
        (1.0, 0.45, 0.45),
        (0.25, 0.32, 1.0),
        (0.85, 0.32, 1.0),
    ):
        for s in (-1.0, 1.0):
            points.append(p0 + t * length * axis + s * half * w * y + n * h * up)
    return convex_body(np.array(points))


def add_freefall_lifeboat(
    parts: PartSet,
    form: HullForm,
    house: AftHouse,
    frame_paint: Material,
    rng: np.random.Generator,
) -> float:
    """A freefall lifeboat on its launching ramp at the stern, bow down aft at 30-35°: the
    boat about 4.5 % L long (6.5-9.8 m), its ramp on two legs standing on the poop. Returns
    the ramp's half-width (m) where it runs out over the transom."""
    length = float(np.clip(0.045 * form.length, 6.5, 9.8))
    a = np.radians(u(rng, 30.0, 35.0))
    axis = np.array([np.cos(a), 0.0, np.sin(a)])
    up = np.array([-np.sin(a), 0.0, np.cos(a)])
    half = 0.22 * length
    ramp = np.array(
        [
            t * axis + n * up + s * half * np.array([0.0, 1.0, 0.0])
            for t in (-0.25, length + 0.3)
            for n in (-0.45, -0.05)
            for s in (-1.0, 1.0)
        ]
    )
    boat = _boat_body(np.zeros(3), axis, up, length)
    # The aftmost point of boat or ramp 0.3 m inside the transom.
    x_lo = -form.half_length + 0.3 - min(float(ramp[:, 0].min()), float(boat.bounds[0, 0]))
    bow = np.array([x_lo, 0.0, deck_at(form, x_lo) + house.poop_height + 1.2])
    boat.apply_translation(bow)
    parts.add("lifeboats", boat, LIFEBOAT_ORANGE)
    parts.add("lifeboat_ramp", convex_body(ramp + bow), frame_paint)
    for t in (0.1 * length, 0.85 * length):
        foot = bow + t * axis - 0.3 * up
        z_floor = deck_at(form, float(foot[0])) + house.poop_height
        for s in (-1.0, 1.0):
            parts.add(
                "lifeboat_ramp",
                box(
                    foot[0] - 0.2,
                    foot[0] + 0.2,
                    s * (half - 0.4),
                    s * half,
                    z_floor - EMBED_M,
                    foot[2],
                ),
                frame_paint,
            )
    return half


def add_davit_lifeboats(
    parts: PartSet,
    form: HullForm,
    house: AftHouse,
    deck_height: float,
    frame_paint: Material,
) -> bool:
    """Two lifeboats hung in davits beside the house, one a side, on the third deck: the older
    layout (davit-launched boats). False, building nothing, where the house leaves no room
    for them inside the ship's side."""
    length = float(np.clip(0.045 * form.length, 6.5, 9.0))
    w, h = 0.35 * length, 0.37 * length
    xc = house.x_aft + 0.5 * (house.x_fwd - house.x_aft)
    x0 = xc - 0.5 * length
    y_out = min_half_beam(form, x0, x0 + length) - 0.3
    y_in = y_out - w
    if y_in < house.half_width + 0.3:
        return False
    z = house.z_deck + 2.0 * deck_height + 0.4
    for s in (-1.0, 1.0):
        p0 = np.array([x0, s * 0.5 * (y_in + y_out), z])
        parts.add(
            "lifeboats",
            _boat_body(p0, np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0]), length),
            LIFEBOAT_ORANGE,
        )
        for xd in (x0 + 0.2 * length, x0 + 0.8 * length):
            parts.add(
                "davits",
                box(
                    xd - 0.2,
                    xd + 0.2,
                    s * (house.half_width - 0.1),
                    s * (y_out - 0.3 * w),
                    z + h,
                    z + h + 0.35,
                ),
                frame_paint,
            )
    return True
