"""Sequences (issue 17): moving vessels on an evolving sea, frames as units of work, track labels.

Checks that need no render come first: the schema and the command line, the courses (speeds in
their class's range, encounter geometry, no two hulls ever meeting), heave, pitch and roll
against the surface model at each frame's time. Then one tiny sequence (3 frames, 64×36 px,
1 spp, one level, a low-density sea, two vessels) is rendered once uninterrupted (the
``reference`` fixture) and checked independently: each track's box moves by less than its own
size between frames unless occluded, lies inside the box re-projected from the vessel's
recorded pose, and matches the MOTChallenge and COCO files; a run killed after its first frame
and resumed must end byte-identical to it; the animated preview has one frame per frame (the
MP4 one decoded back against the contact sheets); frames that reuse their vessel models
build the same bytes as frames that build them afresh.
"""

from __future__ import annotations

import itertools
import json
import math
import signal
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from conftest import TINY_SEQUENCE
from seahaze import ocean, vessels
from seahaze.batch import plan_scenes
from seahaze.batch.plan import vary_scene
from seahaze.camera import Camera
from seahaze.cli import main
from seahaze.motion import MotionError, first_conflict, frame_times, plan_courses
from seahaze.sceneio import SceneFileError, load_scene, parse_scene_text
from seahaze.spec import SceneSpec, with_overrides
from seahaze.world import (
    build_geometry,
    build_vessels,
    frame_camera,
    frame_layout,
    layout_vessels,
    ocean_params,
    vessel_speeds,
)

REPO = Path(__file__).resolve().parents[1]

TINY = TINY_SEQUENCE


def _spec(text: str = TINY) -> SceneSpec:
    return parse_scene_text(text, "tiny.yaml")


def _sampled(encounter: str, seed: int, count: int = 5, encounters: int = 1) -> SceneSpec:
    sequence = {"frames": 100, "fps": 10, "encounter": encounter, "encounters": encounters}
    return SceneSpec.model_validate(
        {
            "camera": {"height_m": 15},
            "vessels": {"sample": {"count": count, "distance_m": [200, 3000]}},
            "sequence": sequence,
            "render": {"seed": seed},
        }
    )


# --------------------------------------------------------------------------------------------
# Schema and command line


def test_a_still_scene_records_no_sequence_field():
    data = SceneSpec().model_dump(mode="json", by_alias=True)
    assert "sequence" not in data
    placed = _spec().vessels.placed[0].model_dump(by_alias=True)
    assert "turn_rate_deg_s" not in placed  # unset: a still scene's config is unchanged
    assert _spec().vessels.placed[1].turn_rate_deg_s == 2.0


def test_camera_perspective_varies_within_its_ranges_and_shifts_nothing_else():
    base = {"variation": {"sun_elevation_deg": [10, 50], "wind_speed": [3, 12]}}
    varied = {
        "variation": {
            **base["variation"],
            "camera_height_m": [8, 40],
            "camera_pitch_deg": [-6, 1],
            "camera_fov_deg": [35, 75],
        }
    }
    assert "camera_height_m" not in SceneSpec.model_validate(base).model_dump()["variation"]
    heights = []
    for seed in range(20):
        a = vary_scene(SceneSpec.model_validate(base), seed)
        b = vary_scene(SceneSpec.model_validate(varied), seed)
        assert 8 <= b.camera.height_m <= 40 and -6 <= b.camera.pitch_deg <= 1
        assert 35 <= b.camera.fov_deg <= 75
        # Each varied quantity has its own stream: adding the camera's leaves the sun and wind.
        assert (a.sun.elevation_deg, a.sea.wind_speed) == (b.sun.elevation_deg, b.sea.wind_speed)
        heights.append(b.camera.height_m)
    assert np.ptp(heights) > 10.0


def test_a_sequence_varies_its_mast_only_within_5_to_60_m():
    with pytest.raises(SceneFileError, match=r"variation.camera_height_m \[2, 40\].*5\.\.60 m"):
        parse_scene_text("sequence: {frames: 3}\nvariation: {camera_height_m: [2, 40]}", "s.yaml")


def test_the_encounter_scene_is_a_10_s_sequence_at_10_fps_with_a_crossing(capsys):
    spec, name = load_scene(REPO / "scenes" / "encounter.yaml")
    assert (name, spec.sequence.frames, spec.sequence.fps) == ("encounter", 100, 10.0)
    assert spec.sequence.duration_s == pytest.approx(9.9)  # frame 99 at 9.9 s: 10 s of video
    camera = Camera.from_spec(spec.camera)
    first, speeds = frame_layout(spec, camera, 0)
    last, _ = frame_layout(spec, camera, 99)
    assert all(v > 0 for v in speeds)  # every vessel under way
    # The fishing boat was moved to cross the ferry's course 60..120 deg apart.
    turn = abs((first[1].heading_deg - first[0].heading_deg + 180) % 360 - 180)
    assert 60 <= turn <= 120
    assert math.dist((first[0].x, first[0].y), (last[0].x, last[0].y)) == pytest.approx(
        15 * vessels.KNOT_M_S * 9.9
    )
    assert main(["validate", str(REPO / "scenes" / "encounter.yaml")]) == 0
    placements = layout_vessels(spec, camera)
    courses = plan_courses(spec, placements, vessel_speeds(spec, placements))
    assert [c.encounter for c in courses] == ["crossing", "crossing", None, None, None]


def test_the_ship_encounter_scene_sails_and_meets_head_on():
    spec, _ = load_scene(REPO / "scenes" / "ship_encounter.yaml")
    assert (spec.sequence.platform, spec.sequence.frames, spec.sequence.fps) == ("ship", 100, 10.0)
    start, end = frame_camera(spec, 0), frame_camera(spec, 99)
    assert end.x_m - start.x_m == pytest.approx(12 * vessels.KNOT_M_S * 9.9)
    placements, _ = frame_layout(spec, start, 0)
    movers = [p for p in placements if vessels.get_class(p.kind).service_speed_kn[1] > 0]
    turn = abs((movers[1].heading_deg - movers[0].heading_deg + 180) % 360 - 180)
    assert abs(turn - 180) <= 10.0


def test_frames_and_fps_overrides_make_a_sequence():
    spec = with_overrides(SceneSpec(), frames=12, fps=5)
    assert (spec.sequence.frames, spec.sequence.fps) == (12, 5.0)
    assert spec.sequence.duration_s == pytest.approx(11 / 5)
    kept = with_overrides(_spec(), fps=4)
    assert (kept.sequence.frames, kept.sequence.fps) == (3, 4.0)


@pytest.mark.parametrize(
    ("text", "where", "says"),
    [
        ("sequence: {frames: 0}", "tiny.yaml:1: sequence.frames", ">= 1"),
        ("sequence:\n  encounter: sideways", "tiny.yaml:2: sequence.encounter", "'head_on'"),
        ("sequence: {fps: 500}", "tiny.yaml:1: sequence.fps", "<= 120"),
        ("camera: {height_m: 80}\nsequence: {frames: 5}", "tiny.yaml", "allowed: 5..60 m"),
    ],
)
def test_bad_sequence_input_names_file_line_field_and_allowed(text, where, says):
    with pytest.raises(SceneFileError) as err:
        parse_scene_text(text, "tiny.yaml")
    message = str(err.value)
    assert message.startswith(where) and says in message, message


def test_colliding_courses_are_bad_input_exit_2(tmp_path, capsys):
    scene = tmp_path / "collide.yaml"
    scene.write_text(
        "vessels:\n  placed:\n"
        "    - {class: tug, distance_m: 300, bearing_deg: 0, heading_deg: 90, speed_kn: 10}\n"
        "    - {class: tug, distance_m: 300, bearing_deg: 10, heading_deg: 270, speed_kn: 10}\n"
        "sequence: {frames: 100, fps: 10}\n"
    )
    assert main(["validate", str(scene)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert f"{scene}:5: sequence:" in err and "collide at t = " in err and "allowed:" in err
    assert main(["render", str(scene), "--out", str(tmp_path / "o"), "--res", "64x36"]) == 2


def test_bad_frames_flag_exits_2(tmp_path, capsys):
    scene = REPO / "scenes" / "encounter.yaml"
    assert main(["render", str(scene), "--frames", "0", "--out", str(tmp_path / "o")]) == 2
    assert "--frames 0: must be within 1.." in capsys.readouterr().err


def test_each_frame_is_a_unit_of_work():
    spec = _spec()
    plan = plan_scenes([(spec, "tinyseq")])
    assert [job.name for job in plan.jobs] == ["tinyseq_f0000", "tinyseq_f0001", "tinyseq_f0002"]
    assert [job.frame for job in plan.jobs] == [0, 1, 2]
    entry = plan.jobs[1].entry("pending")
    assert (entry["sequence"], entry["frame"]) == ("tinyseq", 1)
    batch = plan_scenes([(spec, "tinyseq")], count=2)
    assert [job.name for job in batch.jobs][2:4] == ["tinyseq_00000_f0002", "tinyseq_00001_f0000"]
    assert {job.sequence for job in batch.jobs} == {"tinyseq_00000", "tinyseq_00001"}
    # One seed per sequence: its frames share it (the same sea and vessels, moving).
    assert len({job.spec.render.seed for job in batch.jobs[:3]}) == 1
    still = plan_scenes([(SceneSpec(), "still")]).jobs[0].entry("pending")
    assert list(still) == ["status", "seed", "template", "index", "config"]


# --------------------------------------------------------------------------------------------
# Courses: speeds, encounters, no collisions


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_speeds_through_the_water_lie_in_the_class_range(seed):
    spec = _sampled("random", seed, count=6)
    camera = Camera.from_spec(spec.camera)
    placements = layout_vessels(spec, camera)
    courses = plan_courses(spec, placements, vessel_speeds(spec, placements))
    for course in courses:
        lo, hi = vessels.get_class(course.placement.kind).service_speed_range_m_s
        assert lo - 1e-9 <= course.speed_m_s <= hi + 1e-9, course


def _min_gap(a, b, times) -> float:
    return min(math.dist(a.pose(t)[:2], b.pose(t)[:2]) for t in times)


def _movers(courses):
    return [c for c in courses if vessels.get_class(c.placement.kind).service_speed_kn[1] > 0]


def _assert_encounter(a, b, encounter):
    turn = (b.placement.heading_deg - a.placement.heading_deg + 180.0) % 360.0 - 180.0
    if encounter == "head_on":
        assert abs(abs(turn) - 180.0) <= 10.0 + 1e-9
    elif encounter == "crossing":
        assert 60.0 - 1e-9 <= abs(turn) <= 120.0 + 1e-9
    else:
        assert abs(turn) <= 10.0 + 1e-9
        assert a.speed_m_s != pytest.approx(b.speed_m_s)
    # Closest approach at mid-sequence, farther apart than the two hulls' half-diagonals.
    times = np.linspace(0.0, 2 * a.t_ref_s, 401)
    gaps = [math.dist(a.pose(t)[:2], b.pose(t)[:2]) for t in times]
    assert times[int(np.argmin(gaps))] == pytest.approx(a.t_ref_s, abs=0.05)
    half_diagonals = sum(
        0.5
        * math.hypot(
            c.placement.length_m,
            vessels.get_class(c.placement.kind).max_beam_m(c.placement.length_m),
        )
        for c in (a, b)
    )
    assert min(gaps) >= half_diagonals + 15.0 - 1e-6


@pytest.mark.parametrize("encounter", ["crossing", "head_on", "overtaking"])
@pytest.mark.parametrize("seed", [4, 5])
def test_encounters_have_their_geometry_and_pass_clear(encounter, seed):
    spec = _sampled(encounter, seed, count=4)
    camera = Camera.from_spec(spec.camera)
    placements = layout_vessels(spec, camera)
    courses = plan_courses(spec, placements, vessel_speeds(spec, placements))
    # The first two vessels that can move (buoys are moored) meet.
    a, b = _movers(courses)[:2]
    _assert_encounter(a, b, encounter)


@pytest.mark.parametrize("encounter", ["crossing", "head_on"])
def test_several_encounters_pair_the_vessels_under_way(encounter):
    kept = 0
    for seed in range(4, 10):
        spec = _sampled(encounter, seed, count=7, encounters=2)
        camera = Camera.from_spec(spec.camera)
        placements = layout_vessels(spec, camera)
        courses = plan_courses(spec, placements, vessel_speeds(spec, placements))
        assert first_conflict(courses, frame_times(spec.sequence)) is None
        movers = _movers(courses)
        assert all(c.encounter is None for c in courses if c not in movers[:4])
        for a, b in ((movers[0], movers[1]), (movers[2], movers[3])):
            # A pair one of whose vessels had to give way to another pair is no encounter.
            assert a.encounter == b.encounter
            if a.encounter is not None:
                assert a.encounter == encounter
                _assert_encounter(a, b, encounter)
                kept += 1
    assert kept >= 9  # of 12 pairs: giving way is the exception


def test_more_encounters_than_vessels_under_way_is_a_clear_error():
    spec = _sampled("crossing", 4, count=3, encounters=3)
    camera = Camera.from_spec(spec.camera)
    placements = layout_vessels(spec, camera)
    with pytest.raises(MotionError, match=r"3 encounter.*need 6 vessels that can move"):
        plan_courses(spec, placements, vessel_speeds(spec, placements))


@pytest.mark.parametrize("seed", range(6))
def test_no_two_hulls_meet_at_any_frame(seed):
    spec = _sampled("random", seed, count=8)
    camera = Camera.from_spec(spec.camera)
    placements = layout_vessels(spec, camera)
    courses = plan_courses(spec, placements, vessel_speeds(spec, placements))
    times = frame_times(spec.sequence)
    assert first_conflict(courses, times) is None
    # Independently: sample each hull's rectangle densely and check no point of one lies
    # inside another's rectangle at any frame.
    for t in times[::9]:
        rects = []
        for c in courses:
            x, y, h = c.pose(float(t))
            beam = vessels.get_class(c.placement.kind).max_beam_m(c.placement.length_m)
            rects.append((x, y, math.radians(h), c.placement.length_m / 2, beam / 2))
        for i, (xi, yi, hi, li, bi) in enumerate(rects):
            u, v = np.meshgrid(np.linspace(-li, li, 15), np.linspace(-bi, bi, 5))
            px = xi + u * math.cos(hi) - v * math.sin(hi)
            py = yi + u * math.sin(hi) + v * math.cos(hi)
            for j, (xj, yj, hj, lj, bj) in enumerate(rects):
                if i == j:
                    continue
                du, dv = px - xj, py - yj
                along = du * math.cos(hj) + dv * math.sin(hj)
                across = -du * math.sin(hj) + dv * math.cos(hj)
                assert not np.any((np.abs(along) < lj) & (np.abs(across) < bj)), (i, j, t)


def test_explicit_courses_that_meet_raise_naming_both():
    # Two tugs 52 m apart steaming at each other at 10 kn each: they meet after about 4.5 s.
    spec = SceneSpec.model_validate(
        {
            "vessels": {
                "placed": [
                    {
                        "class": "tug",
                        "distance_m": 300,
                        "bearing_deg": 0,
                        "heading_deg": 90,
                        "length_m": 30,
                        "speed_kn": 10,
                    },
                    {
                        "class": "tug",
                        "distance_m": 300,
                        "bearing_deg": 10,
                        "heading_deg": 270,
                        "length_m": 30,
                        "speed_kn": 10,
                    },
                ]
            },
            "sequence": {"frames": 100, "fps": 10},
        }
    )
    placements = layout_vessels(spec, Camera.from_spec(spec.camera))
    with pytest.raises(MotionError, match=r"vessel #0 \(tug\) and vessel #1 \(tug\) collide"):
        plan_courses(spec, placements, vessel_speeds(spec, placements))
    # Ten frames only (0.9 s): they have not met yet.
    short = with_overrides(spec, frames=10)
    assert len(plan_courses(short, placements, vessel_speeds(short, placements))) == 2


def test_a_straight_course_moves_at_its_speed_and_a_turn_turns_at_its_rate():
    spec = _spec()
    camera = Camera.from_spec(spec.camera)
    start, _ = frame_layout(spec, camera, 0)
    end, speeds = frame_layout(spec, camera, 2)  # 1 s later
    ferry = math.dist((start[0].x, start[0].y), (end[0].x, end[0].y))
    assert ferry == pytest.approx(20 * vessels.KNOT_M_S, rel=1e-9)
    assert speeds[0] == pytest.approx(20 * vessels.KNOT_M_S)
    assert (end[1].heading_deg - start[1].heading_deg) % 360 == pytest.approx(2.0)
    # On an arc the chord is a little shorter than the path: 2 r sin(θ/2) for θ = 2°.
    radius = 10 * vessels.KNOT_M_S / math.radians(2.0)
    chord = math.dist((start[1].x, start[1].y), (end[1].x, end[1].y))
    assert chord == pytest.approx(2 * radius * math.sin(math.radians(1.0)), rel=1e-9)
    middle, _ = frame_layout(spec, camera, None)  # the scene as written: mid-sequence poses
    halfway = frame_layout(spec, camera, 1)[0]
    assert (halfway[0].x, halfway[0].y) == pytest.approx((middle[0].x, middle[0].y))


# --------------------------------------------------------------------------------------------
# Riding the waves: heave, pitch and roll against the surface model at each frame's time


def test_vessels_heave_pitch_and_roll_with_the_surface_at_each_frame_time():
    spec = with_overrides(_spec(), frames=21, fps=10)
    camera = Camera.from_spec(spec.camera)
    heaves = []
    for frame in (0, 7, 20):
        t = frame / 10.0
        # An independent surface: the same sea parameters with time_s advanced by t.
        params = ocean_params(spec)
        surface = ocean.make_surface(replace(params, time_s=params.time_s + t))
        placed = build_vessels(spec, camera, ocean.make_surface(ocean_params(spec, t)), frame)
        for v in placed:
            p = v.placement
            z = surface.height(np.array([p.x]), np.array([p.y]))[0]
            assert v.waterline_z == pytest.approx(float(z), abs=1e-9)
            h = math.radians(p.heading_deg)
            half = 0.5 * v.length_m
            bow = surface.height(
                np.array([p.x + half * math.cos(h)]), np.array([p.y + half * math.sin(h)])
            )[0]
            stern = surface.height(
                np.array([p.x - half * math.cos(h)]), np.array([p.y - half * math.sin(h)])
            )[0]
            pitch = math.degrees(math.atan((bow - stern) / v.length_m))
            assert v.pitch_deg == pytest.approx(pitch, abs=1e-9)
        heaves.append([v.waterline_z for v in placed])
    # The sea moves: the heave under each vessel changes between frames.
    assert np.ptp(np.array(heaves), axis=0).min() > 1e-3


@pytest.mark.parametrize("which", ["explicit", "sampled"])
def test_frames_reuse_their_vessel_models_and_build_the_same_bytes(which, monkeypatch):
    from seahaze.vessels import library

    spec = _spec() if which == "explicit" else _sampled("crossing", 4, count=4)
    spec = with_overrides(spec, frames=3).model_copy(
        update={"sea": _spec().sea}  # the low-density sea: the vessels are what is measured
    )
    built = []
    build = library.build_vessel

    def counting(kind, length_m, rng, wind_from_deg=None):
        built.append(kind)
        return build(kind, length_m, rng, wind_from_deg)

    monkeypatch.setattr(library, "build_vessel", counting)

    def frames(fresh: bool = False) -> list:
        out = []
        for frame in range(3):
            if fresh:  # no reuse: each frame builds afresh
                library.clear_model_cache()
            camera = frame_camera(spec, frame)
            geometry = build_geometry(spec, camera, frame)
            fields = [
                (v.kind, v.length_m, v.beam_m, v.air_draft_m, v.hull_draft_m, v.bounds_m)
                for v in geometry.vessels
            ]
            out.append((geometry.digest(), fields))
        return out

    cold = frames(fresh=True)
    n_vessels = len(cold[0][1])
    assert n_vessels >= 2 and len(built) == 3 * n_vessels
    monkeypatch.undo()
    monkeypatch.setattr(library, "build_vessel", counting)
    built.clear()
    library.clear_model_cache()
    warm = frames()
    assert warm == cold  # every mesh, material and dimension bit for bit
    assert len(built) == n_vessels  # the first frame built them, the others reused them
    assert len({digest for digest, _ in warm}) == 3  # the frames do differ (motion, sea)


def test_the_sea_advances_by_its_dispersion_relation():
    spec = with_overrides(_spec(), frames=11, fps=10)
    s0 = ocean.make_surface(ocean_params(spec, 0.0))
    s1 = ocean.make_surface(ocean_params(spec, 1.0))
    later = ocean.make_surface(ocean_params(with_overrides(spec), 1.0))
    x, y = np.linspace(-50, 50, 41), np.full(41, 120.0)
    assert not np.allclose(s0.height(x, y), s1.height(x, y))
    assert np.array_equal(s1.height(x, y), later.height(x, y))  # deterministic in time
    assert ocean_params(spec, 1.0).time_s == pytest.approx(spec.sea.time_s + 1.0)


# --------------------------------------------------------------------------------------------
# A ship platform: the camera sails with the own ship and rides its heave and pitch

SHIP = """\
name: shipseq
camera: {height_m: 15, pitch_deg: -2, fov_deg: 50, resolution: [64, 36]}
sea: {quality: low, seed: 5, wind_speed: 10}
vessels:
  follow_slope: true
  placed:
    - {class: passenger_ferry, distance_m: 400, bearing_deg: 5, heading_deg: 150, length_m: 80,
       speed_kn: 15}
    - {class: tug, distance_m: 250, bearing_deg: -12, heading_deg: 40, length_m: 25, speed_kn: 8}
haze: {levels: [1000]}
sequence: {frames: 3, fps: 1, platform: ship, own_speed_kn: 12, own_length_m: 60}
render: {spp: 1, seed: 3}
"""


def test_the_ship_camera_sails_heaves_and_pitches_with_the_sea():
    spec = _spec(SHIP)
    for frame in range(3):
        camera = frame_camera(spec, frame)
        t = frame - 1.0  # seconds from mid-sequence (t_ref = 1 s at 1 fps)
        # Heading 0 (the camera's): the own ship sails along +x at 12 kn.
        assert (camera.x_m, camera.y_m) == pytest.approx((12 * vessels.KNOT_M_S * t, 0.0))
        params = ocean_params(spec)
        surface = ocean.make_surface(replace(params, time_s=params.time_s + frame))
        z = surface.height(np.array([camera.x_m, camera.x_m + 30, camera.x_m - 30]), np.zeros(3))
        assert camera.height_m == pytest.approx(15.0 + z[0], abs=1e-9)
        pitch = math.degrees(math.atan((z[1] - z[2]) / 60.0))
        assert camera.pitch_deg == pytest.approx(-2.0 + pitch, abs=1e-9)
    # The vessels' distances are measured from the moving camera.
    camera = frame_camera(spec, 2)
    placements, _ = frame_layout(spec, camera, 2)
    for p in placements:
        assert p.distance_m == pytest.approx(math.hypot(p.x - camera.x_m, p.y - camera.y_m))
    assert frame_camera(spec, None) == Camera.from_spec(spec.camera)


def test_a_vessel_may_not_sail_into_the_own_ship():
    # A tug 120 m ahead steaming at the own ship: they meet within 10 s.
    text = SHIP.replace("bearing_deg: -12, heading_deg: 40", "bearing_deg: 0, heading_deg: 180")
    text = text.replace("distance_m: 250", "distance_m: 120").replace("frames: 3", "frames: 20")
    with pytest.raises(SceneFileError, match=r"sequence: .*tug\) sails over the camera \(or into "):
        parse_scene_text(text, "s.yaml")
    with pytest.raises(SceneFileError, match="own_speed_kn and own_heading_deg describe an own"):
        parse_scene_text("sequence: {own_speed_kn: 5}", "s.yaml")


# --------------------------------------------------------------------------------------------
# One rendered sequence, checked independently


@pytest.fixture(scope="module")
def template(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("scenes") / "tinyseq.yaml"
    path.write_text(TINY)
    return path


@pytest.fixture(scope="module")
def reference(template, tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("reference")
    assert main(["render", str(template), "--out", str(out), "--quiet"]) == 0
    return out


def _meta(root: Path, frame: int) -> dict:
    return json.loads((root / "meta" / f"tinyseq_f{frame:04d}.json").read_text())


def _frame_camera(meta: dict, spec: SceneSpec) -> Camera:
    """The frame's camera from its meta alone (a ship platform's moves and pitches)."""
    x, y, z = meta["camera"]["position_m"]
    pitch = meta["camera"]["pitch_used_deg"]
    return replace(Camera.from_spec(spec.camera), x_m=x, y_m=y, height_m=z, pitch_deg=pitch)


def _reprojected_box(vessel: dict, camera: Camera) -> tuple[float, float, float, float]:
    """The image box of the vessel's vessel-frame bounds placed at its recorded pose."""
    pose = vessel["pose"]
    low, high = np.array(pose["bounds_m"])
    corners = np.array(
        [[x, y, z] for x in (low[0], high[0]) for y in (low[1], high[1]) for z in (low[2], high[2])]
    )
    h, p, r = (math.radians(pose[k]) for k in ("heading_deg", "pitch_deg", "roll_deg"))
    rz = np.array([[math.cos(h), -math.sin(h), 0], [math.sin(h), math.cos(h), 0], [0, 0, 1]])
    ry = np.array([[math.cos(p), 0, -math.sin(p)], [0, 1, 0], [math.sin(p), 0, math.cos(p)]])
    rx = np.array([[1, 0, 0], [0, math.cos(r), -math.sin(r)], [0, math.sin(r), math.cos(r)]])
    world = corners @ (rz @ ry @ rx).T + np.array(pose["position_m"])
    u, v, front = camera.project(world)
    assert front.all()
    return u.min(), v.min(), u.max(), v.max()


def _check_tracks(root: Path, name: str, spec: SceneSpec, dt: float) -> None:
    metas = [json.loads((root / "meta" / f"{name}_f{f:04d}.json").read_text()) for f in range(3)]
    boxed = 0
    for meta in metas:
        camera = _frame_camera(meta, spec)
        for vessel in meta["vessels"]:
            if vessel["box_px"] is None:
                continue
            boxed += 1
            x0, y0, x1, y1 = vessel["box_px"]
            u0, v0, u1, v1 = _reprojected_box(vessel, camera)
            assert u0 - 1 <= x0 and x1 <= u1 + 1 and v0 - 1 <= y0 and y1 <= v1 + 1
    assert boxed >= 4
    for before, after in itertools.pairwise(metas):
        for a, b in zip(before["vessels"], after["vessels"], strict=True):
            assert a["track_id"] == b["track_id"]
            step = math.dist(a["pose"]["position_m"][:2], b["pose"]["position_m"][:2])
            assert step == pytest.approx(a["speed_m_s"] * dt, rel=1e-3)


def test_a_ship_platform_sequence_renders_with_tracks_from_the_moving_camera(tmp_path):
    scene = tmp_path / "shipseq.yaml"
    scene.write_text(SHIP)
    out = tmp_path / "out"
    assert main(["render", str(scene), "--out", str(out), "--quiet"]) == 0
    spec = _spec(SHIP)
    _check_tracks(out, "shipseq", spec, 1.0)
    positions = [_meta_of(out, "shipseq", f)["camera"]["position_m"] for f in range(3)]
    assert positions[2][0] - positions[0][0] == pytest.approx(2 * 12 * vessels.KNOT_M_S)
    assert len((out / "mot" / "v1000" / "shipseq" / "gt" / "gt.txt").read_text().splitlines()) >= 4


def _meta_of(root: Path, name: str, frame: int) -> dict:
    return json.loads((root / "meta" / f"{name}_f{frame:04d}.json").read_text())


def test_tracks_are_continuous_and_reproject_from_the_recorded_pose(reference):
    camera = Camera.from_spec(_spec().camera)
    _check_tracks(reference, "tinyseq", _spec(), 0.5)
    metas = [_meta(reference, f) for f in range(3)]
    assert [m["sequence"]["frame"] for m in metas] == [0, 1, 2]
    assert [m["sequence"]["time_s"] for m in metas] == [0.0, 0.5, 1.0]
    boxed = 0
    for meta in metas:
        assert [v["track_id"] for v in meta["vessels"]] == [1, 2]
        assert [v["encounter"] for v in meta["vessels"]] == [None, None]
        for vessel in meta["vessels"]:
            if vessel["box_px"] is None:
                continue
            boxed += 1
            x0, y0, x1, y1 = vessel["box_px"]
            u0, v0, u1, v1 = _reprojected_box(vessel, camera)
            # The labelled pixels lie inside the re-projected hull box (pixel edges: ±1 px).
            assert u0 - 1 <= x0 and x1 <= u1 + 1 and v0 - 1 <= y0 and y1 <= v1 + 1
    assert boxed >= 4
    for before, after in itertools.pairwise(metas):
        for a, b in zip(before["vessels"], after["vessels"], strict=True):
            assert a["track_id"] == b["track_id"]
            if a["box_px"] is None or b["box_px"] is None:
                continue
            if min(a["visible_fraction"], b["visible_fraction"]) < 1.0:
                continue  # occluded: its visible box may jump
            width, height = a["box_px"][2] - a["box_px"][0], a["box_px"][3] - a["box_px"][1]
            moved_x = abs((a["box_px"][0] + a["box_px"][2]) - (b["box_px"][0] + b["box_px"][2])) / 2
            moved_y = abs((a["box_px"][1] + a["box_px"][3]) - (b["box_px"][1] + b["box_px"][3])) / 2
            assert moved_x < width and moved_y < height
            # The pose moved by speed × frame interval (0.5 s) along the ground.
            step = math.dist(a["pose"]["position_m"][:2], b["pose"]["position_m"][:2])
            assert step == pytest.approx(a["speed_m_s"] * 0.5, rel=1e-3)


def test_mot_and_coco_track_files_match_the_frames(reference):
    gt = (reference / "mot" / "v1000" / "tinyseq" / "gt" / "gt.txt").read_text().splitlines()
    metas = [_meta(reference, f) for f in range(3)]
    expected = [
        (m["sequence"]["frame"] + 1, v["track_id"], v["box_px"])
        for m in metas
        for v in m["vessels"]
        if v["box_px"] is not None
    ]
    assert len(gt) == len(expected)
    contrasts = {
        (m["sequence"]["frame"] + 1, v["track_id"]): v["levels"]["v1000"]["apparent_contrast"]
        for m in metas
        for v in m["vessels"]
    }
    for line, (frame, track, box) in zip(gt, expected, strict=True):
        fields = line.split(",")
        # consider = an observer could see it: |apparent contrast| >= 0.02 (Koschmieder).
        contrast = contrasts[(frame, track)]
        assert int(fields[6]) == int(contrast is not None and abs(contrast) >= 0.02)
        assert (int(fields[0]), int(fields[1])) == (frame, track)
        assert float(fields[2]) == pytest.approx(box[0] + 1) and float(fields[4]) == pytest.approx(
            box[2] - box[0]
        )
    info = (reference / "mot" / "v1000" / "tinyseq" / "seqinfo.ini").read_text()
    assert "frameRate=2" in info and "seqLength=3" in info and "imWidth=64" in info
    coco = json.loads((reference / "coco" / "v1000.json").read_text())
    assert coco["videos"] == [{"id": 1, "name": "tinyseq", "fps": 2.0, "frames": 3}]
    assert [img["frame_id"] for img in coco["images"]] == [0, 1, 2]
    tracks = [(a["image_id"], a["track_id"]) for a in coco["annotations"]]
    assert tracks == [(frame, track) for frame, track, _ in expected]


@pytest.mark.slow
def test_sigkill_after_a_frame_then_resume_is_byte_identical(template, reference, tmp_path):
    out = tmp_path / "killed"
    command = [sys.executable, "-m", "seahaze.cli", "render", str(template)]
    command += ["--out", str(out), "--quiet"]
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 300
    try:
        while time.monotonic() < deadline and process.poll() is None:
            manifest = out / "dataset.json"
            if manifest.exists():
                try:
                    scenes = json.loads(manifest.read_text())["scenes"]
                except ValueError:
                    scenes = {}
                if any(s["status"] == "done" for s in scenes.values()):
                    break
            time.sleep(0.02)
        process.send_signal(signal.SIGKILL)
    finally:
        process.kill()
        process.wait()
    statuses = [
        s["status"] for s in json.loads((out / "dataset.json").read_text())["scenes"].values()
    ]
    assert "done" in statuses and "pending" in statuses, statuses
    assert not (out / "mot").exists()  # track files come only when every frame is done
    assert main(["render", str(template), "--out", str(out), "--quiet"]) == 0
    files = sorted(p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file())
    expected = sorted(
        p.relative_to(reference).as_posix() for p in reference.rglob("*") if p.is_file()
    )
    files = [f for f in files if not f.startswith(".")]
    expected = [f for f in expected if not f.startswith(".")]
    assert files == expected
    for name in files:
        a, b = (out / name).read_bytes(), (reference / name).read_bytes()
        if name == "data.yaml":
            a = a.replace(str(out.resolve()).encode(), b"")
            b = b.replace(str(reference.resolve()).encode(), b"")
        assert a == b, name


def test_animated_preview_has_one_frame_per_frame(reference, tmp_path):
    out = tmp_path / "seq.gif"
    args = [
        "preview",
        str(reference),
        "--sequence",
        "tinyseq",
        "--tile-width",
        "64",
        "--columns",
        "2",
    ]
    assert main([*args, "--levels", "clean,v1000", "--out", str(out)]) == 0
    with Image.open(out) as gif:
        assert gif.n_frames == 3
        assert gif.size == (128, 36)
        assert gif.info["duration"] == 500
        assert gif.info["loop"] == 0


def test_mp4_preview_decodes_to_the_frames_contact_sheets(reference, tmp_path):
    imageio = pytest.importorskip("imageio.v2")
    pytest.importorskip("imageio_ffmpeg")
    from seahaze.preview import animation

    out = tmp_path / "seq.mp4"
    args = ["preview", str(reference), "--sequence", "tinyseq", "--tile-width", "64"]
    args += ["--columns", "2", "--levels", "clean,v1000"]
    assert main([*args, "--out", str(out)]) == 0
    sheets, fps = animation(reference, "tinyseq", ["clean", "v1000"], 2, 64)
    reader = imageio.get_reader(out, format="FFMPEG")
    try:
        assert reader.get_meta_data()["fps"] == pytest.approx(fps)
        frames = [np.asarray(frame, np.float64) for frame in reader]
    finally:
        reader.close()
    assert len(frames) == 3 and all(f.shape == (36, 128, 3) for f in frames)
    # Luma (ITU-R 601, as PIL's "L") is coded at full resolution: within 3 levels of 255 on
    # average at CRF 18, and every frame nearest to its own sheet (the vessels move). The
    # chroma is halved both ways (4:2:0), which blurs a 1-spp render's colour noise but keeps
    # each channel's mean (a swapped or mis-ranged channel would shift it by tens of levels).
    luma = [np.asarray(Image.fromarray(f.astype(np.uint8)).convert("L"), float) for f in frames]
    sheet_luma = [np.asarray(sheet.convert("L"), np.float64) for sheet in sheets]
    errors = np.array([[np.abs(f - s).mean() for s in sheet_luma] for f in luma])
    assert errors.diagonal().max() < 3.0, errors
    assert all(row[i] < 0.5 * np.delete(row, i).min() for i, row in enumerate(errors)), errors
    for frame, sheet in zip(frames, sheets, strict=True):
        bias = (frame - np.asarray(sheet, np.float64)).mean(axis=(0, 1))
        assert np.abs(bias).max() < 3.0, bias
    # One encoder thread: the same sheets give the same bytes.
    again = tmp_path / "again.mp4"
    assert main([*args, "--out", str(again)]) == 0
    assert again.read_bytes() == out.read_bytes()
    assert main([*args, "--out", str(tmp_path / "seq.avi")]) == 2
    # Its own MP4 is replaced; a user's video of the same name is not.
    assert main([*args, "--out", str(out)]) == 0 and out.read_bytes() == again.read_bytes()
    (tmp_path / "holiday.mp4").write_bytes(b"\x00\x00\x00\x18ftypmp42 a user's video")
    assert main([*args, "--out", str(tmp_path / "holiday.mp4")]) == 2
    assert (tmp_path / "holiday.mp4").read_bytes().endswith(b"a user's video")


def test_mp4_preview_without_the_video_extra_is_a_one_line_error(
    reference, tmp_path, monkeypatch, capsys
):
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", None)  # import raises ImportError
    out = tmp_path / "seq.mp4"
    assert main(["preview", str(reference), "--sequence", "tinyseq", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "pip install 'seahaze[video]'" in err, err
    assert not out.exists()


def test_a_sequences_frames_share_one_split_so_splits_stay_scene_disjoint() -> None:
    """With --split, every frame of a sequence lands in its sequence's split (frames of one
    sequence in train and test would leak the same vessels and sea into both)."""
    from seahaze.dataset.splits import SplitFractions

    spec, name = load_scene(REPO / "scenes" / "encounter.yaml")
    plan = plan_scenes([(spec, name)], 6, split=SplitFractions.parse("0.5,0.25,0.25"))
    by_sequence: dict[str, set[str]] = {}
    for job in plan.jobs:
        by_sequence.setdefault(job.sequence, set()).add(job.split)
    assert len(by_sequence) == 6
    assert all(len(splits) == 1 for splits in by_sequence.values())
    assert len(set().union(*by_sequence.values())) >= 2  # the splits do differ between sequences
