"""Vessel motion through a sequence: courses, encounters and the no-collision check.

A vessel's pose in the scene (YAML or sampler) is its pose at the *reference time*, the middle
of the sequence, so the vessels a scene puts in view stay near there. From it each vessel
sails at its constant speed through the water (m/s) and rate of turn (deg/s,
counter-clockwise positive): on a straight line, or on a circle of radius ``v / r``. The sea
has no current, so speed through the water is speed over ground.

An ``encounter`` moves the second vessel under way so that it passes the first at the
reference time at a drawn closest point of approach (CPA) no less than half the sum of the two
footprint diagonals plus 15..60 m: two straight courses at that CPA never meet. With
``encounters: n`` the 3rd and 4th vessels under way meet the same way, and so on for ``n``
pairs. A sampled vessel of an encounter that has to give way (below) leaves it: its and its
partner's ``encounter`` become None. Then every
frame is checked: a sampled vessel whose course meets an earlier one's, or passes over the
camera (or meets the own ship of a ``ship`` platform, which sails from the camera's place at
mid-sequence), gives way (a new heading drawn from :data:`seahaze.seeds.Stream.MOTION`, then
also a new distance on its bearing); explicit
vessels whose courses meet are an error naming both and the time.

Frame ``i`` is at ``i / fps`` seconds after the first frame; the sea is at ``sea.time_s`` plus
that (its waves advance by their dispersion relation, :mod:`seahaze.ocean`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from . import vessels
from .seeds import Stream, stream_rng
from .spec import SceneSpec, SequenceSpec

CPA_MARGIN_M = (15.0, 60.0)
"""Range of the clearance (m) an encounter adds to the two hulls' half-diagonals at the CPA."""
CROSSING_ANGLE_DEG = (60.0, 120.0)
"""Range of the angle between two crossing courses (deg)."""
COURSE_JITTER_DEG = 10.0
"""Largest deviation (deg) of a head-on or overtaking course from (anti)parallel."""
OVERTAKEN_SPEED_FRACTION = 0.6
"""An overtaken vessel sails at most this fraction of its overtaker's speed."""
GIVE_WAY_TRIES = 24
"""Courses a sampled vessel tries before its course is declared impossible."""
GIVE_WAY_SCALE = (0.7, 1.4)
"""Range of the factor on its distance a sampled vessel may move by to give way."""


class MotionError(ValueError):
    """Courses that cannot be sailed: two explicit vessels meet, or an encounter is impossible."""


@dataclass(frozen=True)
class Course:
    """One vessel's course: its pose at ``t_ref_s`` and constant speed and rate of turn."""

    placement: vessels.Placement
    """Pose (midships x, y in m, heading in deg) at the reference time."""
    speed_m_s: float
    turn_rate_deg_s: float = 0.0
    t_ref_s: float = 0.0
    """Reference time after the first frame (s): the middle of the sequence."""
    encounter: str | None = None
    """The encounter this vessel is in (``crossing``, ``head_on``, ``overtaking``), if any."""

    def pose(self, t_s: float) -> tuple[float, float, float]:
        """Midships ``(x, y)`` (m) and heading (deg) at time ``t_s`` after the first frame."""
        p, dt = self.placement, t_s - self.t_ref_s
        h0 = math.radians(p.heading_deg)
        rate = math.radians(self.turn_rate_deg_s)
        if abs(rate) < 1e-12:
            s = self.speed_m_s * dt
            return p.x + s * math.cos(h0), p.y + s * math.sin(h0), p.heading_deg
        h = h0 + rate * dt
        radius = self.speed_m_s / rate
        x = p.x + radius * (math.sin(h) - math.sin(h0))
        y = p.y - radius * (math.cos(h) - math.cos(h0))
        return x, y, math.degrees(h) % 360.0

    def placement_at(
        self, t_s: float, camera_heading_deg: float, camera_xy: tuple[float, float] = (0.0, 0.0)
    ) -> vessels.Placement:
        """The vessel's :class:`~seahaze.vessels.Placement` at ``t_s`` (distance and bearing
        from the camera at ``camera_xy`` (m) recomputed; bearing relative to
        ``camera_heading_deg``; the course's rate of turn, for its wake)."""
        x, y, heading = self.pose(t_s)
        dx, dy = x - camera_xy[0], y - camera_xy[1]
        bearing = (math.degrees(math.atan2(dy, dx)) - camera_heading_deg + 180.0) % 360.0 - 180.0
        return replace(
            self.placement,
            x=x,
            y=y,
            heading_deg=heading,
            distance_m=math.hypot(dx, dy),
            bearing_deg=bearing,
            turn_rate_deg_s=self.turn_rate_deg_s,
        )


def frame_times(sequence: SequenceSpec) -> np.ndarray:
    """Time (s) of every frame after the first."""
    return np.arange(sequence.frames, dtype=np.float64) / sequence.fps


def _diagonal(p: vessels.Placement) -> float:
    beam = p.beam_m if p.beam_m is not None else vessels.get_class(p.kind).max_beam_m(p.length_m)
    return math.hypot(p.length_m, beam)


def _moved(p: vessels.Placement, x: float, y: float, heading_deg: float) -> vessels.Placement:
    return replace(p, x=x, y=y, heading_deg=heading_deg % 360.0, distance_m=math.hypot(x, y))


def _speed_range(kind: str) -> tuple[float, float]:
    return vessels.get_class(kind).service_speed_range_m_s


def _encounter(
    kind: str, a: Course, b: Course, rng: np.random.Generator
) -> tuple[Course, Course, str]:
    """Courses ``a`` (kept where it is) and ``b`` (moved) set up for encounter ``kind``."""
    if kind == "random":
        kind = str(rng.choice(["crossing", "head_on", "overtaking"]))
    pa, pb = a.placement, b.placement
    speed_a = a.speed_m_s or float(rng.uniform(*_speed_range(pa.kind)))
    speed_b = b.speed_m_s or float(rng.uniform(*_speed_range(pb.kind)))
    jitter = float(rng.uniform(-COURSE_JITTER_DEG, COURSE_JITTER_DEG))
    if kind == "head_on":
        heading_b = pa.heading_deg + 180.0 + jitter
    elif kind == "crossing":
        side = 1.0 if rng.uniform() < 0.5 else -1.0
        heading_b = pa.heading_deg + side * float(rng.uniform(*CROSSING_ANGLE_DEG))
    else:  # overtaking: the vessel of the faster class comes up from astern
        heading_b = pa.heading_deg + jitter
        top_a, top_b = _speed_range(pa.kind)[1], _speed_range(pb.kind)[1]
        fast, slow = (b, a) if top_b >= top_a else (a, b)
        fast_top = max(top_a, top_b)
        slow_low = _speed_range(slow.placement.kind)[0]
        slow_speed = max(slow_low, OVERTAKEN_SPEED_FRACTION * fast_top)
        if slow_speed >= fast_top:
            raise MotionError(
                f"overtaking: a {slow.placement.kind} sails at least {slow_low:.1f} m/s, a "
                f"{fast.placement.kind} at most {fast_top:.1f} m/s; allowed: two vessels of "
                "which one is faster"
            )
        speed_a, speed_b = (slow_speed, fast_top) if fast is b else (fast_top, slow_speed)
    ha, hb = math.radians(pa.heading_deg), math.radians(heading_b)
    va = np.array([math.cos(ha), math.sin(ha)]) * speed_a
    vr = np.array([math.cos(hb), math.sin(hb)]) * speed_b - va
    norm = float(np.hypot(*vr))
    along = vr / norm if norm > 1e-9 else np.array([math.cos(ha), math.sin(ha)])
    normal = np.array([-along[1], along[0]])
    cpa = 0.5 * (_diagonal(pa) + _diagonal(pb)) + float(rng.uniform(*CPA_MARGIN_M))
    centre = np.array([pa.x, pa.y])
    # The second vessel passes on the side away from the camera, so it stays in front of it.
    near, far = centre - cpa * normal, centre + cpa * normal
    spot = far if np.hypot(*far) >= np.hypot(*near) else near
    moved_b = _moved(pb, float(spot[0]), float(spot[1]), heading_b)
    return (
        replace(a, speed_m_s=speed_a, encounter=kind),
        replace(b, placement=moved_b, speed_m_s=speed_b, encounter=kind),
        kind,
    )


def _corners(course: Course, t_s: float) -> np.ndarray:
    x, y, heading = course.pose(t_s)
    return vessels.footprint_corners(_moved(course.placement, x, y, heading))


def _covers_camera(corners: np.ndarray) -> bool:
    edges = np.roll(corners, -1, axis=0) - corners
    cross = edges[:, 0] * (-corners[:, 1]) - edges[:, 1] * (-corners[:, 0])
    return bool(np.all(cross >= 0) or np.all(cross <= 0))


OWN_SHIP = "own_ship"
"""The ``kind`` of the own ship's placement (a ``ship`` platform; not a vessel class)."""
OWN_BEAM_FRACTION = 1.0 / 6.0
"""The own ship's beam as a fraction of its length (a typical L/B of 6)."""


def own_course(spec: SceneSpec) -> Course | None:
    """The own ship's course (a ``ship`` platform): at the camera's place at mid-sequence,
    sailing at ``own_speed_kn`` on ``own_heading_deg``; None on a shore mast."""
    sequence = spec.sequence
    if sequence is None or sequence.platform != "ship":
        return None
    heading = (
        spec.camera.heading_deg if sequence.own_heading_deg is None else sequence.own_heading_deg
    )
    length = sequence.own_length_m
    placement = vessels.Placement(
        OWN_SHIP, 0.0, 0.0, heading % 360.0, length, 0.0, 0.0, OWN_BEAM_FRACTION * length
    )
    speed = sequence.own_speed_kn * vessels.KNOT_M_S
    return Course(placement, speed, 0.0, 0.5 * sequence.duration_s)


def first_conflict(
    courses: Sequence[Course],
    times: np.ndarray,
    only: int | None = None,
    own: Course | None = None,
) -> tuple[int, int | None, float] | None:
    """The first ``(i, j, t)`` where vessel ``i``'s footprint meets vessel ``j < i``'s (``j``
    None: it covers the camera, or meets the own ship ``own`` of a ``ship`` platform) at frame
    time ``t`` (s); None if the courses never meet.

    ``only``: check only that vessel against those before it. Footprints are the layout's
    rectangles (length × the class's largest beam) without margin.
    """
    radii = [0.5 * _diagonal(c.placement) for c in courses]
    targets = range(len(courses)) if only is None else [only]
    for t in times:
        poses = [c.pose(float(t)) for c in courses]
        own_corners = _corners(own, float(t)) if own is not None else None
        for i in targets:
            corners_i = _corners(courses[i], float(t))
            if own_corners is not None and vessels.footprints_overlap(corners_i, own_corners):
                return i, None, float(t)
            if own_corners is None and _covers_camera(corners_i):
                return i, None, float(t)
            for j in range(i):
                gap = math.hypot(poses[i][0] - poses[j][0], poses[i][1] - poses[j][1])
                if gap > radii[i] + radii[j]:
                    continue  # bounding circles apart: cheaper than the rectangle test
                if vessels.footprints_overlap(corners_i, _corners(courses[j], float(t))):
                    return i, j, float(t)
    return None


def plan_courses(
    spec: SceneSpec,
    placements: Sequence[vessels.Placement],
    speeds: Sequence[float],
) -> list[Course]:
    """Every vessel's course through ``spec.sequence`` (explicit vessels first, as laid out).

    ``placements`` and ``speeds`` (m/s) are the scene's layout and speeds through the water
    (:func:`seahaze.world.layout_vessels`, :func:`seahaze.world.vessel_speeds`). Raises
    :class:`MotionError` when an encounter cannot be set up or courses meet (see the module
    docstring).
    """
    sequence = spec.sequence
    if sequence is None:
        raise ValueError("plan_courses needs a scene with a sequence")
    t_ref = 0.5 * sequence.duration_s
    n_placed = len(spec.vessels.placed)
    turns = [
        (spec.vessels.placed[i].turn_rate_deg_s or 0.0) if i < n_placed else 0.0
        for i in range(len(placements))
    ]
    courses = [
        Course(p, float(v), float(r), t_ref)
        for p, v, r in zip(placements, speeds, turns, strict=True)
    ]
    rng = stream_rng(spec.render.seed, Stream.MOTION)
    partner: dict[int, int] = {}
    if sequence.encounter != "none":
        movers = [i for i, c in enumerate(courses) if _speed_range(c.placement.kind)[1] > 0.0]
        pairs = sequence.encounters
        if len(movers) < 2 * pairs:
            raise MotionError(
                f"{pairs} encounter(s) {sequence.encounter} need {2 * pairs} vessels that can "
                f"move, the scene has {len(movers)}; allowed: encounter none, fewer "
                "encounters, or add vessels"
            )
        for a, b in zip(movers[0 : 2 * pairs : 2], movers[1 : 2 * pairs : 2], strict=True):
            courses[a], courses[b], _ = _encounter(sequence.encounter, courses[a], courses[b], rng)
            partner[a], partner[b] = b, a
    times = frame_times(sequence)
    own = own_course(spec)
    for i in range(len(courses)):
        conflict = first_conflict(courses, times, only=i, own=own)
        tries = 0
        original = courses[i].placement
        while conflict is not None and i >= n_placed and tries < GIVE_WAY_TRIES:
            heading = float(rng.uniform(0.0, 360.0))
            # First a new heading only; then also a new distance on the same bearing (it may
            # sit where an encounter put another vessel, which no heading clears).
            scale = 1.0 if tries < GIVE_WAY_TRIES // 2 else float(rng.uniform(*GIVE_WAY_SCALE))
            x, y = original.x * scale, original.y * scale
            courses[i] = replace(courses[i], placement=_moved(original, x, y, heading))
            conflict = first_conflict(courses, times, only=i, own=own)
            tries += 1
        if conflict is not None:
            raise MotionError(_describe_conflict(courses, conflict))
        if tries and i in partner:  # it gave way: no longer on its encounter's course
            for j in (i, partner[i]):
                courses[j] = replace(courses[j], encounter=None)
    return courses


def _describe_conflict(courses: Sequence[Course], conflict: tuple[int, int | None, float]) -> str:
    i, j, t = conflict
    first = f"vessel #{i} ({courses[i].placement.kind})"
    if j is None:
        return (
            f"{first} sails over the camera (or into the own ship) at t = {t:.1f} s; allowed: "
            "courses clear of it"
        )
    other = f"vessel #{j} ({courses[j].placement.kind})"
    return (
        f"{other} and {first} collide at t = {t:.1f} s; allowed: courses whose hulls never "
        "meet (change a heading, speed_kn or turn_rate_deg_s)"
    )
