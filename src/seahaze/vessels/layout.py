"""Placing vessels on the sea around a camera: explicit lists, random layouts, and the
vessel-frame → world transform.

Placement frame
---------------
- World: right-handed, **Z up**, sea level z = 0, camera at the world origin (x = y = 0).
- Azimuths (``camera_heading_deg``, a vessel's ``heading_deg``) are measured in the
  horizontal plane **counter-clockwise from world +X**, in degrees (0° = +X, 90° = +Y).
- ``bearing_deg`` is relative to the camera heading, **positive to the left**
  (counter-clockwise seen from above): azimuth ``az = camera_heading_deg + bearing_deg``.
- Position: ``x = d·cos(az)``, ``y = d·sin(az)`` with ``d = distance_m`` (horizontal range from
  the camera to the vessel's midships origin).
- ``heading_deg`` is the world azimuth the bow points to (same convention as the camera
  heading). A vessel with heading = camera heading + 180° comes toward the camera.

Footprints and overlap
----------------------
Each vessel occupies an oriented rectangle ``length × max_beam`` (``max_beam`` = the class's
largest beam/length ratio × length, so the check holds whatever beam ``build_vessel`` later
samples; a user mesh uses its real beam), grown by ``min_separation_m / 2`` on every side.
Two vessels overlap when their grown rectangles intersect (separating-axis test). A rectangle
may not contain the camera.

Overlap in the image (``max_image_overlap``)
--------------------------------------------
Traffic keeps vessels apart on the water, and a camera sees them apart too: two sampled vessels
at one range seldom hide each other. With ``max_image_overlap`` set, a candidate is also
rejected when its **bearing interval** (the angles, seen from the camera, that its footprint
rectangle spans) overlaps an accepted vessel's by more than that fraction of the narrower of
the two — the horizontal overlap of their boxes in the image, the hull's height aside. 0 keeps
every pair side by side in the image; None (the default) leaves the rule out.

Distance distributions (``distance_range_m = (d_min, d_max)``)
--------------------------------------------------------------
- ``"uniform"``: d uniform in [d_min, d_max] (equal count per metre of range).
- ``"log"``: log d uniform (equal count per octave: many near, fewer far; suits detector
  training where near and far objects should both be frequent).
- ``"linear_depth"``: pdf ∝ d, i.e. uniform per unit *sea area* inside the sector — what a
  homogeneous traffic density looks like from the camera (most vessels far away).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from seahaze.vessels.library import CLASS_NAMES, get_class, length_problem
from seahaze.vessels.materials import Material
from seahaze.vessels.model import VesselModel

__all__ = [
    "DISTRIBUTIONS",
    "ExplicitVessel",
    "LayoutError",
    "PlacedPart",
    "Placement",
    "footprint_corners",
    "footprints_overlap",
    "place_explicit",
    "place_on_sea",
    "sample_distance",
    "sample_layout",
    "vessel_attitude",
    "vessel_to_world_matrix",
]

DISTRIBUTIONS = ("log", "uniform", "linear_depth")
# Sea surface callbacks take world x, y as 1-D float arrays (metres) and return arrays (or
# scalars that broadcast): the same signature as ``OceanSurface.height`` in seahaze.ocean.
HeightFn = Callable[[np.ndarray, np.ndarray], np.ndarray | float]
SlopeFn = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray | float, np.ndarray | float]]


class LayoutError(ValueError):
    """A layout cannot be made (overlap in an explicit list, or no room after many tries)."""


@dataclass(frozen=True)
class ExplicitVessel:
    """One vessel of an explicit layout (see the module docstring for the frame).

    ``length_m`` None: sampled uniformly inside the class range by :func:`place_explicit`.
    ``beam_m``: the real beam of a user mesh (see :class:`Placement`); its ``length_m`` is then
    required and need not lie inside the class range, since the user sized the model.
    """

    kind: str
    distance_m: float
    bearing_deg: float
    heading_deg: float
    length_m: float | None = None
    beam_m: float | None = None


@dataclass(frozen=True)
class Placement:
    """Where a vessel sits: world position (m) of its midships origin, bow azimuth (deg),
    and the length to build it with (``build_vessel(kind, length_m, rng)``).

    ``beam_m`` is set for a user mesh, whose beam is known before layout; the footprint then
    uses it instead of the class's largest beam at that length. ``turn_rate_deg_s`` is the rate
    of turn (deg/s, counter-clockwise positive) of the course a sequence frame's vessel sails
    (:meth:`seahaze.motion.Course.placement_at`; its wake follows the arc); 0 for a still.
    """

    kind: str
    x: float
    y: float
    heading_deg: float
    length_m: float
    distance_m: float
    bearing_deg: float
    beam_m: float | None = None
    turn_rate_deg_s: float = 0.0


class PlacedPart(NamedTuple):
    """A part in world coordinates, ready for a renderer (float32 vertices, uint32 faces)."""

    name: str
    vertices: np.ndarray
    faces: np.ndarray
    material: Material


LAYOUT_RESTARTS = 50
"""Whole layouts drawn at most under the image-overlap rule before :func:`sample_layout` gives
up (1 without the rule)."""


# --------------------------------------------------------------------------- footprints
def _footprint_beam(placement: Placement) -> float:
    if placement.beam_m is not None:
        return placement.beam_m
    return get_class(placement.kind).max_beam_m(placement.length_m)


def footprint_corners(placement: Placement, margin_m: float = 0.0) -> np.ndarray:
    """(4, 2) world xy corners of the placement's rectangle grown by ``margin_m`` per side."""
    half_l = 0.5 * placement.length_m + margin_m
    half_b = 0.5 * _footprint_beam(placement) + margin_m
    h = np.radians(placement.heading_deg)
    fwd = np.array([np.cos(h), np.sin(h)])
    port = np.array([-np.sin(h), np.cos(h)])
    centre = np.array([placement.x, placement.y])
    signs = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]], dtype=np.float64)
    return centre + signs[:, :1] * half_l * fwd + signs[:, 1:] * half_b * port


def footprints_overlap(a: np.ndarray, b: np.ndarray) -> bool:
    """Separating-axis test for two convex quadrilaterals given as (4, 2) corner arrays."""
    for poly in (a, b):
        edges = np.roll(poly, -1, axis=0) - poly
        for ex, ey in edges:
            axis = np.array([-ey, ex])
            pa, pb = a @ axis, b @ axis
            if pa.max() < pb.min() or pb.max() < pa.min():
                return False
    return True


def bearing_interval(corners: np.ndarray) -> tuple[float, float]:
    """The interval of azimuths (rad, counter-clockwise from +x) that a footprint's (4, 2)
    world corners span as seen from the camera at the origin; unwrapped around its first
    corner, so an interval across ±π stays one interval."""
    angles = np.arctan2(corners[:, 1], corners[:, 0])
    unwrapped = angles[0] + np.angle(np.exp(1j * (angles - angles[0])))
    return float(unwrapped.min()), float(unwrapped.max())


def image_overlap(a: tuple[float, float], b: tuple[float, float]) -> float:
    """How much two bearing intervals overlap, as a fraction (0–1) of the narrower one; both
    are taken around ``a`` (an overlap across ±π counts)."""
    shift = 2.0 * np.pi * np.round((0.5 * (a[0] + a[1]) - 0.5 * (b[0] + b[1])) / (2.0 * np.pi))
    lo, hi = max(a[0], b[0] + shift), min(a[1], b[1] + shift)
    narrower = min(a[1] - a[0], b[1] - b[0])
    if narrower <= 0.0:
        return 0.0
    return float(np.clip((hi - lo) / narrower, 0.0, 1.0))


def _contains_origin(corners: np.ndarray) -> bool:
    """True if the convex quad (counter-clockwise or clockwise) contains the camera (0, 0)."""
    edges = np.roll(corners, -1, axis=0) - corners
    cross = edges[:, 0] * (-corners[:, 1]) - edges[:, 1] * (-corners[:, 0])
    return bool(np.all(cross >= 0) or np.all(cross <= 0))


def _describe(index: int, p: Placement) -> str:
    return (
        f"#{index} {p.kind} (L {p.length_m:.0f} m at {p.distance_m:.0f} m, bearing "
        f"{p.bearing_deg:.1f}°)"
    )


# --------------------------------------------------------------------------- explicit
def _field(item: Any, name: str, default: Any = ...) -> Any:
    getter = item.get if isinstance(item, Mapping) else lambda key, d: getattr(item, key, d)
    value = getter(name, default)
    if value is ...:
        raise ValueError(f"layout item {item!r} has no {name!r}")
    return value


def _placement(
    kind: str,
    distance_m: float,
    bearing_deg: float,
    heading_deg: float,
    length_m: float,
    camera_heading_deg: float,
    beam_m: float | None = None,
) -> Placement:
    az = np.radians(camera_heading_deg + bearing_deg)
    return Placement(
        kind=kind,
        x=float(distance_m * np.cos(az)),
        y=float(distance_m * np.sin(az)),
        heading_deg=float(heading_deg % 360.0),
        length_m=float(length_m),
        distance_m=float(distance_m),
        bearing_deg=float(bearing_deg),
        beam_m=None if beam_m is None else float(beam_m),
    )


def _sample_length(kind: str, rng: np.random.Generator) -> float:
    lo, hi = get_class(kind).length_range_m
    return float(rng.uniform(lo, hi))


def place_explicit(
    items: Sequence[Any],
    camera_heading_deg: float,
    rng: np.random.Generator,
    *,
    min_separation_m: float = 0.0,
) -> list[Placement]:
    """Turn explicit (kind, distance_m, bearing_deg, heading_deg, length_m) items into
    placements, in order.

    Items may be :class:`ExplicitVessel`, any object with those attributes, or mappings.
    A missing/None ``length_m`` is sampled from ``rng`` inside the class range; a given one
    must lie inside it, except for a user mesh (an item with ``beam_m``). Raises
    :class:`LayoutError` (a ValueError) naming the two vessels if any footprints overlap (with
    ``min_separation_m``), or naming a vessel that covers the camera; ValueError for unknown
    kinds, out-of-range lengths or non-positive distances.
    """
    placements: list[Placement] = []
    for item in items:
        kind = str(_field(item, "kind"))
        get_class(kind)  # an unknown kind fails here, naming the allowed ones
        distance = float(_field(item, "distance_m"))
        if distance <= 0.0:
            raise ValueError(f"{kind}: distance_m must be > 0, got {distance:g}")
        length = _field(item, "length_m", None)
        beam = _field(item, "beam_m", None)
        if beam is not None and length is None:
            raise ValueError(f"{kind}: a user mesh (beam_m given) needs its length_m")
        if length is None:
            length = _sample_length(kind, rng)
        problem = None if beam is not None else length_problem(kind, float(length))
        if problem is not None:
            raise ValueError(problem)
        placements.append(
            _placement(
                kind,
                distance,
                float(_field(item, "bearing_deg")),
                float(_field(item, "heading_deg")),
                float(length),
                camera_heading_deg,
                beam,
            )
        )
    margin = 0.5 * max(min_separation_m, 0.0)
    corners = [footprint_corners(p, margin) for p in placements]
    for i, p in enumerate(placements):
        if _contains_origin(corners[i]):
            raise LayoutError(f"vessel {_describe(i, p)} covers the camera position")
        for j in range(i):
            if footprints_overlap(corners[i], corners[j]):
                raise LayoutError(
                    f"vessels {_describe(j, placements[j])} and {_describe(i, p)} overlap "
                    f"(minimum separation {min_separation_m:g} m)"
                )
    return placements


# --------------------------------------------------------------------------- sampler
def sample_distance(
    distance_range_m: tuple[float, float], distribution: str, rng: np.random.Generator
) -> float:
    """One range sample (m) from ``distribution`` (see the module docstring)."""
    d_min, d_max = (float(v) for v in distance_range_m)
    if not 0.0 < d_min <= d_max:
        raise ValueError(f"distance_range_m must satisfy 0 < min <= max, got {distance_range_m}")
    r = float(rng.random())
    if distribution == "uniform":
        return d_min + r * (d_max - d_min)
    if distribution == "log":
        return float(np.exp(np.log(d_min) + r * (np.log(d_max) - np.log(d_min))))
    if distribution == "linear_depth":
        return float(np.sqrt(d_min**2 + r * (d_max**2 - d_min**2)))
    raise ValueError(
        f"unknown distance distribution {distribution!r}; use one of {', '.join(DISTRIBUTIONS)}"
    )


def _normalised_weights(class_weights: Mapping[str, float]) -> tuple[list[str], np.ndarray]:
    kinds = list(class_weights)
    for kind in kinds:
        get_class(kind)  # ValueError listing the allowed kinds
    weights = np.array([float(class_weights[k]) for k in kinds])
    if len(kinds) == 0 or np.any(weights < 0) or weights.sum() <= 0:
        raise ValueError(
            f"class_weights must name classes from {', '.join(CLASS_NAMES)} with weights >= 0 "
            f"and a positive sum, got {dict(class_weights)}"
        )
    return kinds, weights / weights.sum()


def _bearing_half_range(
    bearing_spread_deg: float, horizontal_fov_deg: float | None, length_m: float, distance_m: float
) -> float:
    """Half-width (deg) of the bearing interval that keeps the vessel inside the view.

    The vessel's angular half-size is taken broadside (worst case, atan(L/2 / d)); if it is
    wider than the field of view the vessel is centred (half-width 0).
    """
    half = 0.5 * bearing_spread_deg
    if horizontal_fov_deg is not None:
        angular = np.degrees(np.arctan2(0.5 * length_m, distance_m))
        half = min(half, 0.5 * horizontal_fov_deg - angular)
    return max(half, 0.0)


def sample_layout(
    count: int,
    class_weights: Mapping[str, float],
    distance_range_m: tuple[float, float],
    distribution: str,
    bearing_spread_deg: float,
    min_separation_m: float,
    camera_heading_deg: float,
    rng: np.random.Generator,
    *,
    horizontal_fov_deg: float | None = None,
    max_attempts_per_vessel: int = 200,
    existing: Sequence[Placement] = (),
    max_image_overlap: float | None = None,
    near_enough: Callable[[str, float], float] | None = None,
    n_near: int = 0,
) -> list[Placement]:
    """Sample ``count`` non-overlapping vessels around the camera (rejection sampling).

    Per vessel, in this order from ``rng``: class (``class_weights``, normalised), length
    (uniform in the class range), distance (``distribution`` over ``distance_range_m``),
    bearing (uniform in ±``bearing_spread_deg``/2, narrowed so the whole vessel stays inside
    ``horizontal_fov_deg`` when given), heading (uniform in [0, 360)). A candidate is
    rejected if its footprint (grown by ``min_separation_m``/2) overlaps an accepted one or
    covers the camera, or overlaps one of the ``existing`` placements (explicit vessels of the
    same scene), or, with ``max_image_overlap``, hides more than that fraction of one of them
    in the image (module docstring); after ``max_attempts_per_vessel`` rejections a
    :class:`LayoutError` says how many vessels fitted. Same ``rng`` state → same layout.

    ``near_enough(kind, length)`` (m), for the first ``n_near`` vessels: the farthest distance
    at which that vessel still looks as large as asked (the sampler's ``detectable``); their
    distance is drawn from ``distribution`` over the range cut there, and a class and length
    whose cut falls short of the range's near end is drawn again.
    """
    if count < 0:
        raise ValueError(f"count must be >= 0, got {count}")
    if bearing_spread_deg < 0:
        raise ValueError(f"bearing_spread_deg must be >= 0, got {bearing_spread_deg}")
    if distribution not in DISTRIBUTIONS:
        raise ValueError(
            f"unknown distance distribution {distribution!r}; use one of {', '.join(DISTRIBUTIONS)}"
        )
    kinds, probs = _normalised_weights(class_weights)
    margin = 0.5 * max(min_separation_m, 0.0)
    # The image rule can corner a layout (a long hull near the camera spans much of the view):
    # then the whole layout is drawn again, from where the generator stands. Without the rule
    # one try, so its layouts draw exactly what they always drew.
    tries = 1 if max_image_overlap is None else LAYOUT_RESTARTS
    for _try in range(tries):
        placements: list[Placement] = []
        corners: list[np.ndarray] = [footprint_corners(p, margin) for p in existing]
        seen = [bearing_interval(footprint_corners(p)) for p in existing]
        for _vessel in range(count):
            for _attempt in range(max_attempts_per_vessel):
                kind = kinds[int(rng.choice(len(kinds), p=probs))]
                length = _sample_length(kind, rng)
                span = distance_range_m
                if near_enough is not None and len(placements) < n_near:
                    span = (span[0], min(span[1], near_enough(kind, length)))
                    if span[1] < span[0]:
                        continue  # too small to look large enough anywhere in the range
                distance = sample_distance(span, distribution, rng)
                half = _bearing_half_range(bearing_spread_deg, horizontal_fov_deg, length, distance)
                bearing = float(rng.uniform(-half, half))
                heading = float(rng.uniform(0.0, 360.0))
                candidate = _placement(kind, distance, bearing, heading, length, camera_heading_deg)
                cand_corners = footprint_corners(candidate, margin)
                if _contains_origin(cand_corners):
                    continue
                if any(footprints_overlap(cand_corners, c) for c in corners):
                    continue
                interval = bearing_interval(footprint_corners(candidate))
                if max_image_overlap is not None and any(
                    image_overlap(interval, other) > max_image_overlap for other in seen
                ):
                    continue
                placements.append(candidate)
                corners.append(cand_corners)
                seen.append(interval)
                break
            else:
                break  # this vessel found no place: the layout failed
        else:
            return placements
    overlap = "" if max_image_overlap is None else f", image overlap {max_image_overlap:g}"
    again = "" if tries == 1 else f" in each of {tries} layouts"
    raise LayoutError(
        f"could not place vessel {len(placements) + 1} of {count} after "
        f"{max_attempts_per_vessel} attempts{again} (distance {distance_range_m} m, bearing spread "
        f"{bearing_spread_deg:g}°, min separation {min_separation_m:g} m{overlap}): widen "
        f"the ranges, lower the count or the separation"
        + ("" if max_image_overlap is None else " or raise max_image_overlap")
    )


# --------------------------------------------------------------------------- to world
def hull_rotation(heading_deg: float, pitch_rad: float, roll_rad: float) -> np.ndarray:
    """The hull frame (x bow, y port, z up) in the world: R = Rz(heading) · Ry(-pitch) ·
    Rx(roll), bow-up pitch and port-up roll positive (radians, heading in degrees)."""
    h = np.radians(heading_deg)
    ch, sh = np.cos(h), np.sin(h)
    cp, sp = np.cos(-pitch_rad), np.sin(-pitch_rad)
    cr, sr = np.cos(roll_rad), np.sin(roll_rad)
    rz = np.array([[ch, -sh, 0.0], [sh, ch, 0.0], [0.0, 0.0, 1.0]])
    ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    return rz @ ry @ rx


def _slopes(
    model: VesselModel, placement: Placement, height_fn: HeightFn | None, slope_fn: SlopeFn | None
) -> tuple[float, float]:
    """Surface slope along the bow direction and toward port (dz per metre).

    With ``slope_fn`` the local gradient is used; otherwise central differences of
    ``height_fn`` across the hull's length and beam, so a long ship averages over short waves
    (it bridges them) instead of following every ripple.
    """
    h = np.radians(placement.heading_deg)
    fwd = np.array([np.cos(h), np.sin(h)])
    port = np.array([-np.sin(h), np.cos(h)])
    if slope_fn is not None:
        gx, gy = slope_fn(np.array([placement.x]), np.array([placement.y]))
        grad = np.array([_scalar(gx), _scalar(gy)])
        return float(grad @ fwd), float(grad @ port)
    if height_fn is None:
        return 0.0, 0.0
    half_l, half_b = 0.5 * model.length_m, 0.5 * model.beam_m
    # Bow, stern, port and starboard points, evaluated in one vectorised call.
    offsets = np.array([half_l * fwd, -half_l * fwd, half_b * port, -half_b * port])
    points = np.array([placement.x, placement.y]) + offsets
    z = _heights(height_fn, points[:, 0], points[:, 1])
    return float((z[0] - z[1]) / (2.0 * half_l)), float((z[2] - z[3]) / (2.0 * half_b))


def _scalar(value: np.ndarray | float) -> float:
    return float(np.asarray(value, dtype=np.float64).reshape(-1)[0])


def _heights(height_fn: HeightFn, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Call ``height_fn`` on 1-D arrays; a constant result is broadcast to every point."""
    z = np.asarray(height_fn(x, y), dtype=np.float64)
    return np.broadcast_to(z, x.shape)


def vessel_attitude(
    model: VesselModel,
    placement: Placement,
    height_fn: HeightFn | None = None,
    slope_fn: SlopeFn | None = None,
    follow_slope: bool = False,
) -> tuple[float, float, float]:
    """Heave (m, the surface height under midships), pitch and roll (rad, bow-up and port-up
    positive; 0 without ``follow_slope``) of a vessel floating at ``placement``."""
    z0 = 0.0
    if height_fn is not None:
        z0 = float(_heights(height_fn, np.array([placement.x]), np.array([placement.y]))[0])
    pitch = roll = 0.0
    if follow_slope:
        along, across = _slopes(model, placement, height_fn, slope_fn)
        pitch, roll = float(np.arctan(along)), float(np.arctan(across))
    return z0, pitch, roll


def vessel_to_world_matrix(
    model: VesselModel,
    placement: Placement,
    height_fn: HeightFn | None = None,
    slope_fn: SlopeFn | None = None,
    follow_slope: bool = False,
) -> np.ndarray:
    """4×4 homogeneous transform from the vessel frame to the world (metres)."""
    z0, pitch, roll = vessel_attitude(model, placement, height_fn, slope_fn, follow_slope)
    matrix = np.eye(4)
    matrix[:3, :3] = hull_rotation(placement.heading_deg, pitch, roll)
    matrix[:3, 3] = (placement.x, placement.y, z0)
    return matrix


def place_on_sea(
    model: VesselModel,
    placement: Placement,
    height_fn: HeightFn | None = None,
    slope_fn: SlopeFn | None = None,
    follow_slope: bool = False,
) -> list[PlacedPart]:
    """Transform every part of ``model`` into the world for ``placement``.

    The vessel frame is rotated about z by ``placement.heading_deg`` (bow → that azimuth) and
    translated so its origin (midships, waterline) sits at ``(x, y, height_fn(x, y))``
    (``height_fn`` None = flat sea at z = 0; e.g. ``surface.height`` of a seahaze.ocean
    surface). With ``follow_slope`` the hull also pitches and rolls to the sea slope
    (``slope_fn(x, y) -> (dz/dx, dz/dy)`` if given, else finite differences of ``height_fn``
    over the hull length and beam). Both callbacks receive 1-D numpy arrays of world x, y (m).
    Returns ``PlacedPart(name, vertices float32 (N, 3), faces uint32 (M, 3), material)``.
    """
    matrix = vessel_to_world_matrix(model, placement, height_fn, slope_fn, follow_slope)
    rot, shift = matrix[:3, :3], matrix[:3, 3]
    placed = []
    for part in model.parts:
        vertices = np.asarray(part.mesh.vertices, dtype=np.float64) @ rot.T + shift
        placed.append(
            PlacedPart(
                part.name,
                vertices.astype(np.float32),
                np.asarray(part.mesh.faces, dtype=np.uint32),
                part.material,
            )
        )
    return placed
