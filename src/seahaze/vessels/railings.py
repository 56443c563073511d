"""Guard rails along exposed deck edges: stanchions about 1.5 m apart carrying three courses up
to 1 m above the deck, as the International Convention on Load Lines requires.

ICLL 1966/1988, Annex I, Regulation 25 (Protection of the crew): guard rails or bulwarks round
all exposed decks, at least 1 m high; on superstructure and freeboard decks at least three
courses, the opening below the lowest not over 230 mm and the other courses not over 380 mm
apart; stanchions about 1.5 m apart. Small craft codes ask the same heights (e.g. the UK MCA
small vessel code, section 22.2: 1000 mm, 230 mm, 380 mm).

The bars are a few centimetres thick (a 42 mm top rail, 27 mm courses, 50 mm stanchions): a
sixth to a third of a pixel at 200 m in a 1280×720 frame of 60°, so what a camera sees of them
is a faint line over a deck edge that otherwise ends flat against the sky, as railings read in
photographs of ships. All dimensions in metres, in the vessel frame (x forward, y port, z up).
"""

from __future__ import annotations

import numpy as np
import trimesh
from numpy.typing import NDArray

from seahaze.vessels.geometry import HullForm, concatenate
from seahaze.vessels.parts import PartSet

__all__ = [
    "COURSE_HEIGHTS_M",
    "COURSE_SIZES_M",
    "RAIL_INSET_M",
    "STANCHION_SIZE_M",
    "STANCHION_SPACING_M",
    "add_house_rails",
    "deck_edge_path",
    "guard_rail",
    "roof_edge_path",
    "stern_edge_path",
]

FloatArray = NDArray[np.float64]

COURSE_HEIGHTS_M = (0.235, 0.615, 1.0)
"""Centre heights of the three courses above the deck (m): the top rail at 1 m, the lowest
leaving 0.22 m below it (≤ 0.23), the clear gaps between courses 0.355 and 0.351 m (≤ 0.38)."""
COURSE_SIZES_M = (0.027, 0.027, 0.042)
"""Thickness of each course's square bar (m): 1 in. pipe for the courses, 1 1/4 in. (42.4 mm)
for the top rail."""
STANCHION_SIZE_M = 0.05
"""Side of a stanchion's triangular section (m)."""
STANCHION_SPACING_M = 1.5
"""Greatest distance between neighbouring stanchions along the deck edge (m)."""
COURSE_TOLERANCE_M = 0.01
"""Farthest a course strays from the deck edge's path where it runs straight across a bend
the path's points resolve (m): about a third of a course's thickness."""
RAIL_INSET_M = 0.15
"""How far inside a roof's or deck's edge the builders stand a guard rail's stanchions (m)."""


def guard_rail(path: FloatArray) -> trimesh.Trimesh:
    """A guard rail along ``path``, (n, 3) points on the deck edge (x, y, deck height) in
    order: a stanchion at each end and as many between as keep them at most
    ``STANCHION_SPACING_M`` apart along the path, and the courses following the deck's
    height. One mesh of closed bars (each watertight, none sharing a vertex)."""
    path = np.asarray(path, np.float64)
    if path.ndim != 2 or path.shape[1] != 3 or len(path) < 2:
        raise ValueError(f"a guard rail needs (n >= 2, 3) points, got shape {path.shape}")
    # Repeated points (a path closed on itself at the stem) would make bars of no direction.
    keep = np.concatenate([[True], np.linalg.norm(np.diff(path, axis=0), axis=1) > 1e-6])
    path = path[keep]
    if len(path) < 2:
        raise ValueError("a guard rail's path has no length")
    bars = [_stanchions(path)]
    # The courses run straight where the edge does: a bar per bend, not per point.
    corners = path[_bends(path, COURSE_TOLERANCE_M)]
    for height, size in zip(COURSE_HEIGHTS_M, COURSE_SIZES_M, strict=True):
        lifted = corners + np.array([0.0, 0.0, height])
        bars.append(_bars(lifted[:-1], lifted[1:], size))
    return concatenate(bars)


def roof_edge_path(
    x_aft: float, x_fwd: float, half_width: float, z: float, *, closed: bool = False
) -> FloatArray:
    """The edge of a flat roof from ``x_aft`` to ``x_fwd`` (m) and ``half_width`` either side,
    at height ``z``: up the port side from forward, across the aft end, down the starboard
    side; the forward end left to what stands there (a wheelhouse), or ``closed`` across it
    too (a wheelhouse top)."""
    corners = [
        [x_fwd, half_width, z],
        [x_aft, half_width, z],
        [x_aft, -half_width, z],
        [x_fwd, -half_width, z],
    ]
    return np.array(corners + corners[:1] if closed else corners)


def deck_edge_path(form: HullForm, x_aft: float, inset: float, step: float = 1.0) -> FloatArray:
    """The hull's deck edge forward of ``x_aft`` (m), ``inset`` (m) inside the side: from the
    port side at ``x_aft`` round the bow to the starboard side at ``x_aft``, at the deck's
    height, a point every ``step`` metres or closer so the rail follows the sheer and the
    bow's curve."""
    return _round_the_end(form, x_aft, form.half_length - inset, inset, 0.0, step)


def stern_edge_path(
    form: HullForm, x_fwd: float, inset: float, rise: float = 0.0, step: float = 1.0
) -> FloatArray:
    """The hull's deck edge aft of ``x_fwd`` (m), ``inset`` (m) inside the side and ``rise``
    (m) over the deck (a poop's deck a deck height up): from the port side at ``x_fwd`` aft
    along the side, across the transom, and forward along the starboard side to ``x_fwd``, a
    point every ``step`` metres or closer."""
    return _round_the_end(form, x_fwd, -form.half_length + inset, inset, rise, step)


def _round_the_end(
    form: HullForm, x_start: float, x_end: float, inset: float, rise: float, step: float
) -> FloatArray:
    """The deck edge ``inset`` inside the side and ``rise`` over the deck, from the port side
    at ``x_start`` to ``x_end`` (the bow or the stern), across, and back along the starboard
    side, a point every ``step`` metres or closer. Where the two sides meet in one point (a
    stem), it is kept once."""
    count = max(2, int(np.ceil(abs(x_end - x_start) / step)) + 1)
    xs = np.linspace(x_start, x_end, count)
    ys = np.maximum(form.deck_half_beam(xs) - inset, 0.0)
    zs = form.deck_z(xs) + rise
    port = np.column_stack([xs, ys, zs])
    starboard = np.column_stack([xs, -ys, zs])[::-1]
    if np.allclose(port[-1], starboard[0]):
        starboard = starboard[1:]
    return np.vstack([port, starboard])


def add_house_rails(
    parts: PartSet,
    roof_x: tuple[float, float],
    roof_half_width: float,
    roof_z: float | None,
    top_x: tuple[float, float],
    top_half_width: float,
    top_z: float,
) -> None:
    """Guard rails all round a wheelhouse top (``top_x``, aft to forward, inside its rakes;
    ``top_half_width``; at ``top_z``), where the mast stands, and round the house roof aft of
    the wheelhouse (``roof_x``, ``roof_half_width``, at ``roof_z``; None: no such roof),
    painted as the house (the part ``superstructure``)."""
    paint = parts.material_of("superstructure")
    x0, x1 = top_x[0] + RAIL_INSET_M, top_x[1] - RAIL_INSET_M
    if x1 - x0 > 0.5:
        top = roof_edge_path(x0, x1, top_half_width - RAIL_INSET_M, top_z, closed=True)
        parts.add("railings", guard_rail(top), paint)
    x0, x1 = roof_x[0] + RAIL_INSET_M, roof_x[1] - 0.3  # clear of the wheelhouse's aft wall
    if roof_z is not None and x1 - x0 > 0.5:
        roof = roof_edge_path(x0, x1, roof_half_width - RAIL_INSET_M, roof_z)
        parts.add("railings", guard_rail(roof), paint)


def _bends(path: FloatArray, tolerance: float) -> NDArray[np.intp]:
    """Indices of the points of ``path`` a polyline through them alone keeps within
    ``tolerance`` (m) of every point: both ends, and greedily the farthest point each straight
    run can reach."""
    keep = [0]
    while keep[-1] < len(path) - 1:
        start, end = keep[-1], keep[-1] + 1
        while end + 1 < len(path) and _within(path[start : end + 2], tolerance):
            end += 1
        keep.append(end)
    return np.array(keep)


def _within(run: FloatArray, tolerance: float) -> bool:
    """Every point of ``run`` lies within ``tolerance`` of the chord from its first to its
    last point."""
    chord = run[-1] - run[0]
    offsets = run - run[0]
    along = offsets @ chord / max(float(chord @ chord), 1e-12)
    return bool(np.all(np.linalg.norm(offsets - along[:, None] * chord, axis=1) <= tolerance))


def _stanchions(path: FloatArray) -> trimesh.Trimesh:
    """Vertical bars from the deck to the top rail at both ends of ``path`` and evenly between,
    at most ``STANCHION_SPACING_M`` apart along it: triangular prisms of ``STANCHION_SIZE_M``
    across (8 triangles where a box takes 12; at a fraction of a pixel the shape of a bar's
    section does not show, and a ship's rails hold a hundred or more of them)."""
    steps = np.linalg.norm(np.diff(path, axis=0), axis=1)
    arc = np.concatenate([[0.0], np.cumsum(steps)])
    count = int(np.ceil(arc[-1] / STANCHION_SPACING_M)) + 1
    at = np.linspace(0.0, arc[-1], max(count, 2))
    feet = np.column_stack([np.interp(at, arc, path[:, k]) for k in range(3)])
    feet[:, 2] -= 0.02  # set 2 cm into the deck: no seam
    # An equilateral triangle of side STANCHION_SIZE_M round each foot, counter-clockwise
    # seen from above, at the foot and 1.02 m up.
    angles = np.radians([90.0, 210.0, 330.0])
    ring = STANCHION_SIZE_M / np.sqrt(3.0) * np.column_stack([np.cos(angles), np.sin(angles)])
    corners = np.zeros((6, 3))
    corners[:3, :2] = corners[3:, :2] = ring
    corners[3:, 2] = COURSE_HEIGHTS_M[-1] + 0.02
    vertices = feet[:, None, :] + corners[None]
    faces = np.array(
        [[0, 2, 1], [3, 4, 5], [0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4], [2, 0, 3], [2, 3, 5]]
    )
    faces = faces[None] + 6 * np.arange(len(feet))[:, None, None]
    return trimesh.Trimesh(vertices.reshape(-1, 3), faces.reshape(-1, 3), process=False)


_UNIT_BOX = trimesh.creation.box(bounds=np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]]))


def _bars(starts: FloatArray, ends: FloatArray, size: float) -> trimesh.Trimesh:
    """Square bars of side ``size`` from ``starts[i]`` to ``ends[i]`` ((n, 3), m), one face
    level and one upright, each lengthened by half its side at both ends so that bars meeting
    at a corner close it. The segments must not be vertical."""
    along = ends - starts
    length = np.linalg.norm(along, axis=1, keepdims=True)
    tangent = along / length
    side = np.cross([0.0, 0.0, 1.0], tangent)
    side /= np.linalg.norm(side, axis=1, keepdims=True)
    up = np.cross(tangent, side)  # (tangent, side, up) is right-handed, as the unit box's axes
    origin = starts - 0.5 * size * (tangent + side + up)
    corners = np.asarray(_UNIT_BOX.vertices)  # in [0, 1]^3
    frame = np.stack([(length + size) * tangent, size * side, size * up], axis=1)  # (n, 3, 3)
    vertices = origin[:, None, :] + np.einsum("ck,nkj->ncj", corners, frame)
    faces = np.asarray(_UNIT_BOX.faces)[None] + np.arange(len(starts))[:, None, None] * 8
    return trimesh.Trimesh(vertices.reshape(-1, 3), faces.reshape(-1, 3), process=False)
