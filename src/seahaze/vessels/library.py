"""Procedural vessel library: class registry, dimension ranges with sources, ``build_vessel``.

The class list covers the object classes used by maritime detectors (the Singapore Maritime
Dataset labels ferry, buoy, vessel/ship, speed boat, boat, sail boat; the merchant "vessel"
class is split here into container ship, bulk carrier and tanker because their silhouettes
differ most) plus a navigation buoy. :data:`CLASS_NAMES` order is the YOLO class id order:
**append new classes at the end, never reorder**.

Ranges (L = length overall, B = beam, D = hull depth keel→main deck at midships, T = draft).
B/L, D/L are ratios; T/D spans ballast → laden condition:

================  ===========  ===========  ===========  =========  ============================
class             L (m)        B/L          D/L          T/D        sources (typical values)
================  ===========  ===========  ===========  =========  ============================
container_ship    100 – 400    0.11 – 0.17  0.07 – 0.09  0.45–0.6   [1] [2] [3]: feeder ~100-200
                                                                    m; Panamax 294.1 × 32.3 m,
                                                                    T 12.0 m; New Panamax 366 ×
                                                                    51.25 m, T 15.2 m; ULCV ~400
                                                                    × 59-61 m (Emma Maersk 397 ×
                                                                    56 m)
bulk_carrier      100 – 330    0.14 – 0.18  0.08 – 0.095 0.4–0.75   [4] [5]: Handysize ~130-180
                                                                    m, Panamax ~225 × 32.3 m,
                                                                    Capesize ~280-300 × 45 m
tanker            100 – 340    0.15 – 0.19  0.085 – 0.1  0.4–0.75   [6] [7] [8]: coastal ~100-
                                                                    205 m, MR ~183 × 32 m,
                                                                    Aframax ~245 × 34-44 m,
                                                                    Suezmax ~275-285 × 45-48 m,
                                                                    VLCC ~330 × 58-60 m
passenger_ferry   30 – 220     0.13 – 0.25  0.07 – 0.11  0.3–0.45   [9]: harbour ferries 30-60
                                                                    m (B/L ~0.25), ro-pax 150-
                                                                    220 m (B/L ~0.14-0.16)
fishing_boat      10 – 45      0.22 – 0.33  0.11 – 0.17  0.55–0.75  [10] [11]: coastal boats
                                                                    10-24 m, trawlers 24-45 m,
                                                                    L/B ≈ 3-4.5
tug               20 – 40      0.33 – 0.50  0.14 – 0.20  0.6–0.8    [12] [13]: Damen ASD 2111
                                                                    21 × 11 m, 2411 24.5 × 11.3
                                                                    m, 2810 28 × 10 m, 2913 29 ×
                                                                    13 m, 3212 32.7 × 12.8 m
sailboat          6 – 25       0.25 – 0.37  0.07 – 0.11  0.3–0.45   [14]: production sloops
                                                                    (e.g. 7.3 × 2.7 m to 20 × 5
                                                                    m); T/D is the canoe body,
                                                                    the fin keel adds 0.13-0.19
                                                                    L total draft
speedboat         5 – 15       0.25 – 0.42  0.11 – 0.17  0.25–0.45  [15]: runabouts and centre
                                                                    consoles 5-15 m
buoy              1.0 – 3.0    1.0          0.5 – 0.8    0.4–0.6    [16] [17] [18]: L = float
                  (diameter)                (float h/L)             diameter; Φ1.2-3.0 m series
================  ===========  ===========  ===========  =========  ============================

Sources (typical published values; checked for plausibility, not design data):

1. Wikipedia, "Container ship" — size categories (small feeder … ULCV) and dimensions.
2. MAN Energy Solutions, "Propulsion Trends in Container Vessels" — average ship particulars
   as a function of size (TEU).
3. Panama Canal Authority (ACP), "Vessel Requirements" — Panamax 294.13 × 32.31 m, T 12.04 m,
   air draft 57.91 m; Neopanamax 366 × 51.25 m, T 15.2 m.
4. MAN Energy Solutions, "Propulsion Trends in Bulk Carriers" — bulk carrier sizes and
   classes (small, Handysize, Handymax, Panamax, Capesize, VLBC).
5. Wikipedia, "Bulk carrier" — size categories.
6. MAN Energy Solutions, "Propulsion Trends in Tankers".
7. Wikipedia, "Oil tanker" — AFRA size classes (GP, MR, LR1, LR2, VLCC, ULCC) with L/B/T.
8. Rodrigue & Notteboom, "Port Economics, Management and Policy", "Tanker sizes and classes".
9. Wikipedia, "Ferry" and "Roll-on/roll-off" (ro-pax); e.g. Staten Island ferries ~94 × 21 m,
   Color Line Color Fantasy 224 × 35 m.
10. FAO Fisheries Technical Paper 267, "Definition and classification of fishery vessel
    types"; FAO fishing vessel type fact sheets.
11. Wikipedia, "Fishing trawler".
12. Damen Shipyards, ASD Tug product range data sheets (2111, 2411, 2810, 2913, 3212).
13. Wikipedia, "Tugboat".
14. ISO 8666:2020 "Small craft — Principal data" (definitions of LH, BH, draught); published
    specifications of production sailing yachts.
15. Wikipedia, "Motorboat"; published specifications of production runabouts / centre consoles.
16. IALA R1001, "The IALA Maritime Buoyage System" (mark shapes, colours, topmarks).
17. IALA Guideline G1006, "Plastic buoys" (float sizes in service).
18. Trinity House, "Navigation buoys" (Type 2 buoys ~3 m diameter); Chinese general buoy
    specification series Φ0.6/1.2/1.5/1.8/2.4/3.0 m with focal heights ~2-5 m.

Lengths are sampled uniformly in the class range when not given; every other proportion is
sampled uniformly inside the documented range from the caller's ``rng`` (deterministic).

Speeds through the water (knots; 1 kn = 1852/3600 m/s), typical service or operating speeds,
used for the vessel's wake (:mod:`seahaze.ocean.wake`); :func:`sample_speed_m_s` draws
uniformly inside the range:

================  ==========  ===============================================================
class             speed (kn)  sources (typical values)
================  ==========  ===============================================================
container_ship    16 – 24     [2]: design speeds about 19-25 kn (feeder to ULCV); slow
                              steaming since 2009 at 16-18 kn
bulk_carrier      12 – 15     [4]: design speeds about 13.5-15 kn, eco service 12-14 kn
tanker            12 – 16     [6]: design speeds about 14-15.5 kn
passenger_ferry   12 – 25     [9]: harbour ferries 12-16 kn; ro-pax 18-25 kn (Color Fantasy
                              22 kn service)
fishing_boat      3 – 12      [10]: trawling/hauling 3-5 kn, steaming 9-12 kn
tug               6 – 13      [12]: Damen ASD 2411-3212 free-running 12-13 kn; harbour
                              manoeuvring slower
sailboat          3 – 9       [14]: displacement hull speed ``1.34·sqrt(LWL/ft)`` kn, 6-12 kn
                              for 6-25 m; cruising under sail about 4-8 kn
speedboat         15 – 40     [15]: planing runabouts/centre consoles cruise 20-35 kn, top
                              speeds about 40-50 kn
buoy              0           moored: no speed through the water (tidal current is ignored)
================  ==========  ===============================================================
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from seahaze.vessels.buoy import build_buoy
from seahaze.vessels.leisure import build_sailboat, build_speedboat
from seahaze.vessels.merchant import (
    build_bulk_carrier,
    build_container_ship,
    build_passenger_ferry,
    build_tanker,
)
from seahaze.vessels.model import VesselModel, VesselPart
from seahaze.vessels.parts import PrincipalDims
from seahaze.vessels.smallcraft import build_fishing_boat, build_tug

__all__ = [
    "CLASS_NAMES",
    "KNOT_M_S",
    "VESSEL_CLASSES",
    "VesselClass",
    "build_vessel",
    "class_id",
    "get_class",
    "sample_dimensions",
    "sample_speed_m_s",
    "speed_problem",
]

KNOT_M_S = 1852.0 / 3600.0
"""One knot in m/s (international nautical mile of 1852 m per hour)."""

Builder = Callable[[PrincipalDims, np.random.Generator], list[VesselPart]]

# YOLO class ids: index in this tuple. Append only.
CLASS_NAMES: tuple[str, ...] = (
    "container_ship",
    "bulk_carrier",
    "tanker",
    "passenger_ferry",
    "fishing_boat",
    "tug",
    "sailboat",
    "speedboat",
    "buoy",
)


@dataclass(frozen=True)
class VesselClass:
    """Documented dimension ranges of one class (see the module table for sources).

    ``length_range_m``: overall length (for ``buoy``: float diameter), metres.
    ``beam_ratio_range``: beam / length. ``depth_ratio_range``: hull depth / length.
    ``draft_fraction_range``: draft / depth (ballast → laden).
    ``service_speed_kn``: typical speed through the water under way (knots; module table).
    """

    name: str
    length_range_m: tuple[float, float]
    beam_ratio_range: tuple[float, float]
    depth_ratio_range: tuple[float, float]
    draft_fraction_range: tuple[float, float]
    description: str
    source: str
    builder: Builder = field(repr=False, compare=False)
    service_speed_kn: tuple[float, float] = (0.0, 0.0)

    @property
    def service_speed_range_m_s(self) -> tuple[float, float]:
        """:attr:`service_speed_kn` in m/s."""
        lo, hi = self.service_speed_kn
        return lo * KNOT_M_S, hi * KNOT_M_S

    @property
    def class_id(self) -> int:
        """YOLO class id: the index of the class in :data:`CLASS_NAMES`."""
        return CLASS_NAMES.index(self.name)

    def max_beam_m(self, length_m: float) -> float:
        """Largest beam (m) this class can have at ``length_m`` (for layout footprints)."""
        return self.beam_ratio_range[1] * length_m


def _vessel_class(
    name: str,
    length: tuple[float, float],
    beam_ratio: tuple[float, float],
    depth_ratio: tuple[float, float],
    draft_fraction: tuple[float, float],
    description: str,
    source: str,
    builder: Builder,
    speed_kn: tuple[float, float] = (0.0, 0.0),
) -> VesselClass:
    return VesselClass(
        name,
        length,
        beam_ratio,
        depth_ratio,
        draft_fraction,
        description,
        source,
        builder,
        speed_kn,
    )


VESSEL_CLASSES: dict[str, VesselClass] = {
    c.name: c
    for c in (
        _vessel_class(
            "container_ship",
            (100.0, 400.0),
            (0.11, 0.17),
            (0.07, 0.09),
            (0.45, 0.6),
            "Cellular container ship, feeder to ULCV: stacks of ISO containers, tall "
            "accommodation aft or (large ships) forward, funnel.",
            "Wikipedia 'Container ship' size categories; MAN ES 'Propulsion Trends in "
            "Container Vessels'; ACP 'Vessel Requirements' (Panamax/Neopanamax limits)",
            build_container_ship,
            (16.0, 24.0),
        ),
        _vessel_class(
            "bulk_carrier",
            (100.0, 330.0),
            (0.14, 0.18),
            (0.08, 0.095),
            (0.4, 0.75),
            "Dry bulk carrier, Handysize to Capesize: raised hatch covers, aft house and "
            "funnel, deck cranes on geared ships.",
            "MAN ES 'Propulsion Trends in Bulk Carriers'; Wikipedia 'Bulk carrier'",
            build_bulk_carrier,
            (12.0, 15.0),
        ),
        _vessel_class(
            "tanker",
            (100.0, 340.0),
            (0.15, 0.19),
            (0.085, 0.1),
            (0.4, 0.75),
            "Oil / product tanker, coastal to VLCC: low flush deck with pipe rack, aft house "
            "and funnel, manifold cranes.",
            "MAN ES 'Propulsion Trends in Tankers'; Wikipedia 'Oil tanker' AFRA classes; "
            "Port Economics, Management and Policy 'Tanker sizes and classes'",
            build_tanker,
            (12.0, 16.0),
        ),
        _vessel_class(
            "passenger_ferry",
            (30.0, 220.0),
            (0.13, 0.25),
            (0.07, 0.11),
            (0.3, 0.45),
            "Passenger / ro-pax ferry: multi-tier white superstructure with window bands, "
            "bridge forward on the top tier, funnels aft.",
            "Wikipedia 'Ferry', 'Roll-on/roll-off' (ro-pax); published ferry particulars",
            build_passenger_ferry,
            (12.0, 25.0),
        ),
        _vessel_class(
            "fishing_boat",
            (10.0, 45.0),
            (0.22, 0.33),
            (0.11, 0.17),
            (0.55, 0.75),
            "Trawler / seiner / longliner: strong sheer, wheelhouse, mast, stern gantry.",
            "FAO Fisheries Technical Paper 267 (fishery vessel types); Wikipedia 'Fishing trawler'",
            build_fishing_boat,
            (3.0, 12.0),
        ),
        _vessel_class(
            "tug",
            (20.0, 40.0),
            (0.33, 0.5),
            (0.14, 0.2),
            (0.6, 0.8),
            "Harbour / ASD tug: beamy, high bow, heavy fender, tall all-round wheelhouse.",
            "Damen ASD Tug data sheets (2111, 2411, 2810, 2913, 3212); Wikipedia 'Tugboat'",
            build_tug,
            (6.0, 13.0),
        ),
        _vessel_class(
            "sailboat",
            (6.0, 25.0),
            (0.25, 0.37),
            (0.07, 0.11),
            (0.3, 0.45),
            "Sailing yacht (sloop): low hull, coachroof, tall mast, mainsail and jib.",
            "ISO 8666 principal data definitions; production sailing-yacht specifications",
            build_sailboat,
            (3.0, 9.0),
        ),
        _vessel_class(
            "speedboat",
            (5.0, 15.0),
            (0.25, 0.42),
            (0.11, 0.17),
            (0.25, 0.45),
            "Planing motorboat: deep-V hull, raked bow, cuddy / console / open layout, outboards.",
            "Wikipedia 'Motorboat'; production runabout / centre-console specifications",
            build_speedboat,
            (15.0, 40.0),
        ),
        _vessel_class(
            "buoy",
            (1.0, 3.0),
            (1.0, 1.0),
            (0.5, 0.8),
            (0.4, 0.6),
            "IALA navigation buoy (lateral, cardinal, isolated danger, safe water, special); "
            "length = float diameter, depth = float height.",
            "IALA R1001 Maritime Buoyage System; IALA G1006 Plastic buoys; Trinity House "
            "buoy types; Chinese buoy standard series Φ1.2-3.0 m",
            build_buoy,
            (0.0, 0.0),
        ),
    )
}

assert tuple(VESSEL_CLASSES) == CLASS_NAMES, "registry and YOLO id order must match"


def class_id(kind: str) -> int:
    """YOLO class id of ``kind`` (ValueError listing the allowed kinds if unknown)."""
    return get_class(kind).class_id


MIN_AIR_DRAFT_RATIO: dict[str, float] = {
    "container_ship": 0.12,
    "bulk_carrier": 0.10,
    "tanker": 0.10,
    "passenger_ferry": 0.16,
    "fishing_boat": 0.32,
    "tug": 0.30,
    "sailboat": 1.25,
    "speedboat": 0.10,
    "buoy": 1.25,
}
"""Least height above the waterline (the top of mast, funnel or stack: the top of a label's
box) per metre of length that each class's builder gives, over its whole length range. A
floor read off the builders themselves (90 vessels a class: 30 seeds at the shortest, middle
and longest length; tests/test_vessels_library.py checks it still holds), so a layout can
place a vessel where it is sure to look at least so tall (:func:`min_air_draft_m`)."""


def min_air_draft_m(kind: str, length_m: float) -> float:
    """The least height (m) above the waterline a ``kind`` vessel ``length_m`` long is built
    with (:data:`MIN_AIR_DRAFT_RATIO`)."""
    get_class(kind)  # ValueError listing the allowed kinds
    return MIN_AIR_DRAFT_RATIO[kind] * length_m


def get_class(kind: str) -> VesselClass:
    """The :class:`VesselClass` of ``kind`` (ValueError listing the allowed kinds if unknown)."""
    try:
        return VESSEL_CLASSES[kind]
    except KeyError:
        raise ValueError(
            f"unknown vessel kind {kind!r}; allowed kinds: {', '.join(CLASS_NAMES)}"
        ) from None


def length_problem(kind: str, length_m: float) -> str | None:
    """Why ``length_m`` does not fit the class ``kind`` (None when it lies in its range)."""
    lo, hi = get_class(kind).length_range_m
    if lo <= float(length_m) <= hi:
        return None
    return f"{kind} length {float(length_m):g} m is outside the {kind} range [{lo:g}, {hi:g}] m"


def speed_problem(kind: str, speed_kn: float) -> str | None:
    """Why ``speed_kn`` (knots through the water) does not fit the class ``kind``: faster than
    the top of its service-speed range (None when ``0 <= speed_kn <= top``; 0 is stopped)."""
    top = get_class(kind).service_speed_kn[1]
    if 0.0 <= float(speed_kn) <= top:
        return None
    if top == 0.0:
        return f"a {kind} is moored: speed {float(speed_kn):g} kn; allowed: 0"
    return (
        f"{kind} speed {float(speed_kn):g} kn is outside the {kind} range; allowed: 0 (stopped) "
        f"to {top:g} kn"
    )


def _checked_length(
    vessel_class: VesselClass, length_m: float | None, rng: np.random.Generator
) -> float:
    if length_m is None:
        return float(rng.uniform(*vessel_class.length_range_m))
    problem = length_problem(vessel_class.name, length_m)
    if problem is not None:
        raise ValueError(problem)
    return float(length_m)


def sample_dimensions(kind: str, length_m: float | None, rng: np.random.Generator) -> PrincipalDims:
    """Length (given or uniform in range), then B/L, D/L, T/D uniform in their ranges."""
    vc = get_class(kind)
    length = _checked_length(vc, length_m, rng)
    beam = length * float(rng.uniform(*vc.beam_ratio_range))
    depth = length * float(rng.uniform(*vc.depth_ratio_range))
    draft = depth * float(rng.uniform(*vc.draft_fraction_range))
    return PrincipalDims(kind, length, beam, depth, draft)


def sample_speed_m_s(kind: str, rng: np.random.Generator) -> float:
    """Speed through the water (m/s) drawn uniformly in the class's service-speed range
    (:attr:`VesselClass.service_speed_kn`); 0 for a buoy. Uses one draw of ``rng``."""
    lo, hi = get_class(kind).service_speed_range_m_s
    return float(rng.uniform(lo, hi))


def build_vessel(
    kind: str,
    length_m: float | None,
    rng: np.random.Generator,
    wind_from_deg: float | None = None,
) -> VesselModel:
    """Build a procedural vessel of class ``kind`` in the vessel frame (metres).

    ``length_m`` None samples the length uniformly inside the class range; all other
    proportions, layout choices and colours come from ``rng`` (same seed → same vessel).
    ``wind_from_deg``: where the wind comes from, degrees off the bow (positive to port); a
    sailboat trims its sails to it (None: at random). Raises ValueError for an unknown kind
    (listing the allowed kinds) or a length outside the class range (stating the range).
    """
    dims = replace(sample_dimensions(kind, length_m, rng), wind_from_deg=wind_from_deg)
    parts = get_class(kind).builder(dims, rng)
    model = VesselModel(kind, dims.length, dims.beam, dims.draft, 0.0, parts, dims.draft)
    lo, hi = model.bounds()
    # Report what the geometry really reaches (fin keels, masts), not the nominal values.
    model.draft_m = float(-lo[2])
    model.air_draft_m = float(hi[2])
    return model


MODEL_CACHE_SIZE = 64
"""Most procedural vessel models :func:`build_vessel_reused` keeps (least recently used
dropped first): a few sequences' fleets at about 0.2 MB of vertices and faces each."""
_MODEL_CACHE: OrderedDict[tuple[str, float | None, float | None, str], tuple[VesselModel, dict]] = (
    OrderedDict()
)


def build_vessel_reused(
    kind: str,
    length_m: float | None,
    rng: np.random.Generator,
    wind_from_deg: float | None = None,
) -> VesselModel:
    """:func:`build_vessel`, reusing the model built before from the same inputs.

    A model depends on the class, the length, the wind and the generator's state and nothing
    else (the library code is fixed within a process), so those are the key; a hit also moves
    ``rng`` on to the state the build left it in, so the vessels built after it draw what they
    would have. The frames of a sequence build the same fleet (same seed, kinds and lengths),
    so every frame after the first reuses its models (a sailboat's only while its heading, and
    so its trim, holds). The model is shared: callers must not change it
    (:func:`seahaze.vessels.place_on_sea` copies the vertices it moves).
    """
    key = (kind, length_m, wind_from_deg, repr(rng.bit_generator.state))
    hit = _MODEL_CACHE.get(key)
    if hit is not None:
        _MODEL_CACHE.move_to_end(key)
        rng.bit_generator.state = hit[1]
        return hit[0]
    model = build_vessel(kind, length_m, rng, wind_from_deg)
    _MODEL_CACHE[key] = (model, rng.bit_generator.state)
    while len(_MODEL_CACHE) > MODEL_CACHE_SIZE:
        _MODEL_CACHE.popitem(last=False)
    return model


def clear_model_cache() -> None:
    """Forget every model :func:`build_vessel_reused` kept."""
    _MODEL_CACHE.clear()
