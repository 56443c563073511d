"""Bulk carrier and tanker: the cargo hull (:mod:`seahaze.vessels.cargo_hull`), an aft house
and the deck gear each is known by (:mod:`seahaze.vessels.deck_gear`). Metres; vessel frame x
forward, y port, z up, waterline z = 0.

Every draw from the caller's ``rng`` is one the builders made before their gear was added
(issue #32), in the same order, so the vessels built after one in a scene draw what they always
drew; what was added draws from :func:`seahaze.vessels.parts.detail_rng`, seeded by the
vessel's dimensions. A few of the old draws now decide something else (the house's extra deck,
whether a bulk carrier is geared) or are drawn and left unused (an old hatch's width where a
ship now has fewer holds): each is marked where it is drawn.

Proportions from typical published particulars (not design data):

- Handymax/Supramax bulk carrier (the commonest geared bulk carrier at sea): LOA 190-200 m,
  beam 32.2-32.3 m, depth ~18 m, five holds and four ~30 t cranes between the hatches
  (Wikipedia "Handymax"; shiprope.com "What is a Supramax bulk carrier"); Handysize
  (130-150 m) also five holds, Panamax/Kamsarmax (225-229 m) seven, Capesize (~290 m) nine
  (bulkcarrierguide.com "size range"; mycompassair.com "Vessels": Capesize 290 m, 9 holds,
  gearless). Most Panamax and almost all Capesize bulk carriers are gearless, their covers
  side-rolling; handy sizes have fore-aft folding covers (handybulk.com).
- Aframax tanker: LOA ~243-253 m, beam 41.6-44.2 m, draft ~14 m (Imarex average 243.2 ×
  41.6 × 14.1 m; Wikipedia "Oil tanker"); MR product tanker ~183 × 32 m. A manifold at
  midships with a hose-handling crane (handybulk.com "Tanker operations").
- Accommodation: about 2.8 m a deck (:data:`seahaze.vessels.cargo_hull.DECK_HEIGHT_M`); a
  Supramax's or MR/Aframax tanker's house has the poop and five or six more decks under the
  wheelhouse, whose roof stands about 20-23 m above the main deck; ships under 150 m one deck
  fewer, over 250 m one more (:func:`house_decks`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from seahaze.vessels.accommodation import (
    AftHouse,
    add_aft_house,
    add_davit_lifeboats,
    add_freefall_lifeboat,
    add_funnel_band,
    add_poop_rails,
    add_radar_scanners,
)
from seahaze.vessels.cargo_hull import DECK_HEIGHT_M, boot_top, foremast, merchant_hull
from seahaze.vessels.deck_gear import (
    add_deck_crane,
    add_hatches,
    add_manifold,
    add_pipe_deck,
    add_windlasses,
)
from seahaze.vessels.geometry import HullForm
from seahaze.vessels.materials import (
    ANTIFOULING_REDS,
    DECK_PAINTS,
    FUNNEL_PAINTS,
    HULL_PAINTS_CARGO,
    MACHINERY_PAINTS,
    SUPERSTRUCTURE_WHITES,
    WINDOW_GLASS,
    Material,
    pick_material,
)
from seahaze.vessels.model import VesselPart
from seahaze.vessels.parts import PartSet, PrincipalDims, deck_at, detail_rng, min_half_beam, u

__all__ = ["build_bulk_carrier", "build_tanker", "bulk_holds", "house_decks"]

RADAR_GREY = MACHINERY_PAINTS[2]


def house_decks(length: float, extra_deck: int) -> int:
    """Decks of an aft house under its wheelhouse, the poop's included: five on ships under
    150 m, six to 250 m (Supramax, MR tanker), seven above, plus ``extra_deck`` (0 or 1)."""
    base = 5 if length < 150.0 else 6 if length < 250.0 else 7
    return base + int(extra_deck)


def bulk_holds(length: float) -> int:
    """Holds (and hatches) of a bulk carrier ``length`` m long: four on mini bulkers (under
    125 m), five on Handysize to Ultramax (to 215 m), seven on Panamax/Kamsarmax (to 260 m),
    nine on Capesize."""
    return 4 if length < 125.0 else 5 if length < 215.0 else 7 if length < 260.0 else 9


def _cargo_start(
    d: PrincipalDims,
    rng: np.random.Generator,
    extra: np.random.Generator,
    fullness: float,
) -> tuple[PartSet, HullForm, AftHouse, tuple[Material, Material, Material]]:
    """The shared start of bulk carriers and tankers: the painted cargo hull and the aft house
    with its funnel, radar mast and lifeboat. Returns the parts, the hull form, the house and
    the (hull, superstructure, deck) paints."""
    length, beam = d.length, d.beam
    form = merchant_hull(d, rng, fullness=fullness)
    hull = pick_material(HULL_PAINTS_CARGO, rng)
    white = pick_material(SUPERSTRUCTURE_WHITES, rng)
    deck = pick_material(DECK_PAINTS, rng)
    parts = PartSet()
    parts.add_hull(
        form, hull, bottom=pick_material(ANTIFOULING_REDS, rng), boot_top_z=boot_top(d), deck=deck
    )
    n_decks = house_decks(length, int(rng.integers(0, 2)))  # the old house's extra deck
    funnel = pick_material(FUNNEL_PAINTS, rng)
    x_aft = -form.half_length + u(rng, 0.035, 0.06) * length
    house_len = max(12.0, u(rng, 0.07, 0.1) * length)
    x_fwd = x_aft + house_len
    half_w = min(u(rng, 0.3, 0.4) * beam, min_half_beam(form, x_aft, x_fwd) - 0.5)
    house = add_aft_house(
        parts,
        form,
        extra,
        x_aft=x_aft,
        x_fwd=x_fwd,
        half_width=half_w,
        n_decks=n_decks,
        deck_height=DECK_HEIGHT_M,
        wheelhouse_length=u(rng, 0.35, 0.5) * house_len,
        paint=white,
        hull_paint=hull,
        glass=WINDOW_GLASS[0],
    )
    f_half_len = u(rng, 0.12, 0.18) * house_len
    f_x = x_aft + f_half_len + u(rng, 0.5, 2.0)
    f_half_w = u(rng, 0.12, 0.2) * beam
    f_top = house.z_top + u(rng, 3.0, 7.0)
    rake = u(rng, 0.5, 2.0)
    parts.add_funnel(
        f_x, 0.0, f_half_len, f_half_w, house.z_roof, f_top, rake=rake, paint=funnel,
        top=FUNNEL_PAINTS[0],
    )  # fmt: skip
    band = pick_material([p for p in FUNNEL_PAINTS if p.name != funnel.name], extra)
    add_funnel_band(parts, f_x, f_half_len, f_half_w, house.z_roof, f_top, rake, band, extra)
    mast_x, mast_h = x_fwd - 0.3 * house_len, u(rng, 4.0, 7.0)
    parts.add_mast(
        mast_x, 0.0, house.z_top, mast_h, 0.3, white, yard_half_width=2.0, name="radar_mast"
    )
    add_radar_scanners(parts, mast_x, house.z_top, mast_h, RADAR_GREY)
    # Freefall lifeboats on most ships built since about 2006; davit boats on older ones.
    davits = extra.random() < 0.2 and add_davit_lifeboats(parts, form, house, DECK_HEIGHT_M, white)
    # A freefall boat slides off its ramp over the transom: the poop's rail leaves it a gap
    # with 0.5 m to spare either side.
    gap = 0.0 if davits else add_freefall_lifeboat(parts, form, house, white, extra) + 0.5
    add_poop_rails(parts, form, house, white, gap)
    return parts, form, house, (hull, white, deck)


def _crane_params(
    source: np.random.Generator, length: float
) -> tuple[Material, float, float, float, float, float]:
    """A bulk carrier's crane paint, pedestal height (8-11 m) and radius (1.3-1.8 m), jib length
    (10-13 % L, 15-32 m), direction and old elevation draw, as the builder always drew them."""
    paint = pick_material(MACHINERY_PAINTS, source)
    ped_h, ped_r = u(source, 8.0, 11.0), u(source, 1.3, 1.8)
    jib = float(np.clip(u(source, 0.1, 0.13) * length, 15.0, 32.0))
    direction = 1.0 if source.random() < 0.5 else -1.0
    return paint, ped_h, ped_r, jib, direction, u(source, 10.0, 35.0)


def build_bulk_carrier(d: PrincipalDims, rng: np.random.Generator) -> list[VesselPart]:
    """Bulk carrier: bluff hull with a forecastle and foremast, windlasses, a row of raised
    hatch coamings with covers (five holds on handy sizes, seven on Panamax, nine on Capesize),
    and on geared ships (nine in ten from 125 to 215 m, fewer smaller and larger) four deck
    cranes (three on four holds) on the centreline between the hatches, their jibs fore-aft,
    stowed on jib rests or topped up; the aft house of :func:`_cargo_start`."""
    extra = detail_rng(d)
    length, beam = d.length, d.beam
    parts, form, house, (hull, white, deck) = _cargo_start(d, rng, extra, fullness=1.0)
    cover_frac = u(rng, 0.65, 0.75)
    cover_paint = hull if rng.random() < 0.5 else deck
    cover_h = u(rng, 1.8, 2.6) + 0.006 * length  # coaming + cover: ~2.5 m small, ~4 m Capesize
    old_holds = int(np.clip(round(length / 33.0), 4, 9))
    widths = [u(rng, 0.25, 0.31) for _ in range(old_holds)]  # all drawn; some unused now
    gear_draw = rng.random() if length < 235.0 else 1.0
    crane = _crane_params(rng, length) if gear_draw < 0.6 else None  # the old geared ships'
    foremast(parts, form, white, rng)
    # The caller's rng is done with: everything below draws from extra.

    n_holds = bulk_holds(length)
    widths += [u(extra, 0.25, 0.31) for _ in range(n_holds - len(widths))]
    x_first = max(house.x_fwd + 0.025 * length, house.x_poop + 1.5)
    x_last = form.half_length - form.forecastle_length - 0.02 * length
    pitch = (x_last - x_first) / n_holds
    cover_len = cover_frac * pitch
    centres = [x_first + (i + 0.5) * pitch for i in range(n_holds)]
    hatches = []
    for xc, frac in zip(centres, widths, strict=False):
        x0, x1 = xc - 0.5 * cover_len, xc + 0.5 * cover_len
        hatches.append((x0, x1, min(frac * beam, min_half_beam(form, x0, x1) - 1.0)))
    covers = add_hatches(
        parts,
        form,
        hatches,
        coaming_height=0.62 * cover_h,
        cover_height=0.38 * cover_h,
        coaming_paint=hull,
        cover_paint=cover_paint,
        side_rolling=length >= 215.0,
    )
    add_windlasses(parts, form, pick_material(MACHINERY_PAINTS, extra), extra)

    # Geared: many mini bulkers are not (bulkcarrierguide.com), nine in ten handy sizes are,
    # a few Panamaxes; Capesizes never (gear_draw is 1 from 235 m).
    geared = gear_draw < (0.4 if length < 125.0 else 0.9 if length < 215.0 else 0.3)
    if not geared:
        return parts.to_parts()
    paint, ped_h, ped_r, jib, direction, _ = crane or _crane_params(extra, length)
    jib = min(jib, 0.85 * pitch)
    n_gaps = n_holds - 1
    gaps = sorted({round(float(g)) for g in np.linspace(0, n_gaps - 1, min(n_gaps, 4))})
    stowed = extra.random() < 0.65
    top_z = house.z_top + 3.0  # a topped jib's head stays under the radar mast's top (4-7 m)

    def rest_on(x: float) -> float:
        for c0, c1, z_top in covers:
            if c0 <= x <= c1:
                return z_top
        return deck_at(form, x)

    rest_h = u(extra, 2.5, 4.5)
    elevation = u(extra, 25.0, 40.0)
    for i in gaps:
        xc = 0.5 * (centres[i] + centres[i + 1])
        z0 = deck_at(form, xc)
        heel_z = z0 + ped_h + 0.45 * (2.2 * ped_r + 0.6)
        cap = np.degrees(np.arcsin(np.clip((top_z - heel_z) / jib, 0.0, 1.0)))
        add_deck_crane(
            parts,
            x=xc,
            y=0.0,
            z_deck=z0,
            pedestal_height=ped_h,
            pedestal_radius=ped_r,
            jib_length=jib,
            direction=direction,
            paint=paint,
            glass=WINDOW_GLASS[0],
            elevation_deg=None if stowed else float(min(elevation, cap)),
            rest_on=rest_on,
            rest_height=rest_h,
        )
    return parts.to_parts()


def build_tanker(d: PrincipalDims, rng: np.random.Generator) -> list[VesselPart]:
    """Oil / product tanker: long low deck between a poop and a forecastle with its foremast
    and windlasses; cargo lines on the centreline under a catwalk from poop to forecastle, tank
    hatches and vent risers; the midship manifold across the ship with a hose-handling crane
    either side of it; the aft house of :func:`_cargo_start`."""
    extra = detail_rng(d)
    length, beam = d.length, d.beam
    parts, form, house, (_hull, white, deck) = _cargo_start(d, rng, extra, fullness=0.7)
    bundle_hw = max(1.0, u(rng, 0.04, 0.06) * beam)
    pipes_top = u(rng, 1.2, 2.0)
    catwalk_h = u(rng, 2.4, 3.0)
    crane_paint = pick_material(MACHINERY_PAINTS, rng)
    xm = u(rng, -0.05, 0.05) * length
    hose_cranes = [(u(rng, 6.0, 8.0), u(rng, 12.0, 18.0), u(rng, 15.0, 35.0)) for _ in range(2)]
    foremast(parts, form, white, rng)
    # The caller's rng is done with: everything below draws from extra.

    x0 = house.x_poop - 0.3
    # Up to the foot of the forecastle's ramp (HullForm.deck_z: 1.5 % L, at most 0.3 of it).
    ramp = min(0.015 * length, 0.3 * form.forecastle_length)
    x1 = form.half_length - form.forecastle_length - ramp - 0.5
    add_pipe_deck(
        parts,
        form,
        x0,
        x1,
        bundle_half_width=bundle_hw,
        pipes_top=pipes_top,
        catwalk_height=catwalk_h,
        pipe_paint=deck,
        catwalk_paint=white,
        rng=extra,
    )
    x_a, x_b = add_manifold(parts, form, xm, paint=deck, rng=extra)
    add_windlasses(parts, form, crane_paint, extra)
    stowed = extra.random() < 0.5
    rest_on: Callable[[float], float] = lambda x: deck_at(form, x)  # noqa: E731
    for side, (ped_h, jib, elevation) in zip((-1.0, 1.0), hose_cranes, strict=True):
        xc = (x_b + 2.5) if side > 0 else (x_a - 2.5)
        add_deck_crane(
            parts,
            x=xc,
            y=side * 0.3 * beam,
            z_deck=deck_at(form, xc),
            pedestal_height=ped_h,
            pedestal_radius=0.9,
            jib_length=jib,
            direction=side,
            paint=crane_paint,
            glass=WINDOW_GLASS[0],
            elevation_deg=None if stowed else elevation,
            rest_on=rest_on,
            rest_height=u(extra, 3.5, 5.0),
            name="hose_cranes",
        )
    return parts.to_parts()
