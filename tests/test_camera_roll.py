"""Camera roll (issue 17): ``camera.roll_deg``, its variation range and a rigidly mounted ship
camera that rolls and pitches with the own ship.

Checked independently of the camera model: a level camera's basis is exactly the formula it
had before roll existed (so every existing output keeps its bytes); the rendered horizon of a
flat sea tilts with slope ``-tan(roll)`` in pixels (v down), in the geometry pass to half a
pixel and in the clean image's brightness edge; a rolled library vessel's labelled box equals
its visible mesh projected by the rolled camera within 1 px; a rigid mount's camera is the hull
rotation (bow-up pitch, port-up roll from the surface model at the frame's time) applied to the
mast camera; and the boxes of a rendered rigid-mount ship sequence lie inside the vessels'
recorded poses re-projected by each frame's rolled camera.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest

from conftest import load_flat_scene, small_spec
from seahaze import imaging, motion, ocean, vessels
from seahaze.batch.plan import vary_scene
from seahaze.camera import Camera
from seahaze.cli import main
from seahaze.labels import boxes_from_instances
from seahaze.render import passes
from seahaze.render.scene import build_scene
from seahaze.sceneio import SceneFileError, parse_scene_text
from seahaze.spec import CameraSpec, SceneSpec, SequenceSpec
from seahaze.world import build_geometry, frame_camera, ocean_params
from test_annotations import (
    assert_rails_set_no_edge,
    framed_camera,
    framing_parts,
    projected_box,
    thinnest_rod_m,
    visible_points,
)
from test_sequences import SHIP

# --------------------------------------------------------------------------------------------
# Schema, basis and variation (no render)


def _unrolled_basis(heading_deg: float, pitch_deg: float):
    """The camera basis as ``Camera.basis`` computed it before roll existed."""
    h, p = math.radians(heading_deg), math.radians(pitch_deg)
    forward = np.array([math.cos(p) * math.cos(h), math.cos(p) * math.sin(h), math.sin(p)])
    right = np.array([math.sin(h), -math.cos(h), 0.0])
    return forward, right, np.cross(right, forward)


@pytest.mark.parametrize(("heading", "pitch"), [(0.0, -1.5), (37.0, -12.0), (-200.0, 8.0)])
def test_a_level_camera_has_exactly_the_unrolled_basis(heading, pitch):
    camera = Camera(12.0, 60.0, pitch, heading, 64, 36)
    for got, expected in zip(camera.basis(), _unrolled_basis(heading, pitch), strict=True):
        assert np.array_equal(got, expected)  # bit for bit: level outputs keep their bytes
    spec = CameraSpec(pitch_deg=pitch, heading_deg=heading, resolution=(64, 36))
    assert Camera.from_spec(spec) == camera


def test_roll_is_recorded_only_when_set():
    assert "roll_deg" not in SceneSpec().model_dump(mode="json")["camera"]
    assert SceneSpec(camera={"roll_deg": -7.5}).model_dump()["camera"]["roll_deg"] == -7.5
    ship = SequenceSpec(platform="ship")
    assert "camera_mount" not in ship.model_dump()
    assert SequenceSpec(platform="ship", camera_mount="rigid").model_dump()["camera_mount"] == (
        "rigid"
    )
    assert "camera_roll_deg" not in SceneSpec().model_dump()["variation"]


@pytest.mark.parametrize("roll", [12.0, -30.0])
def test_roll_turns_right_side_down_about_the_optical_axis(roll):
    level = Camera(12.0, 50.0, -4.0, 25.0, 64, 36)
    rolled = replace(level, roll_deg=roll)
    f0, r0, u0 = level.basis()
    f, r, u = rolled.basis()
    assert np.array_equal(f, f0)  # the optical axis does not move
    r_rad = math.radians(roll)
    assert r @ u0 == pytest.approx(-math.sin(r_rad)) and u @ r0 == pytest.approx(math.sin(r_rad))
    assert np.allclose(np.cross(r, f), u) and r @ u == pytest.approx(0.0, abs=1e-15)
    # Right side down for a positive roll: the right vector dips below the horizontal.
    assert np.sign(r[2]) == -np.sign(roll)
    back = level.pointing(f, u)
    angles = (back.heading_deg, back.pitch_deg, back.roll_deg)
    assert angles == pytest.approx((25.0, -4.0, roll))


def test_the_camera_roll_varies_within_its_range_and_shifts_nothing_else():
    base = {"variation": {"sun_elevation_deg": [10, 50], "camera_pitch_deg": [-6, 1]}}
    varied = {"variation": {**base["variation"], "camera_roll_deg": [-8, 5]}}
    rolls = []
    for seed in range(20):
        a = vary_scene(SceneSpec.model_validate(base), seed)
        b = vary_scene(SceneSpec.model_validate(varied), seed)
        assert a.camera.roll_deg == 0.0 and -8 <= b.camera.roll_deg <= 5
        assert (a.sun.elevation_deg, a.camera.pitch_deg) == (
            b.sun.elevation_deg,
            b.camera.pitch_deg,
        )
        rolls.append(b.camera.roll_deg)
    assert np.ptp(rolls) > 6.0


@pytest.mark.parametrize(
    ("text", "where", "says"),
    [
        ("camera: {roll_deg: 50}", "r.yaml:1: camera.roll_deg", ">= -45 and <= 45"),
        ("variation: {camera_roll_deg: [-60, 0]}", "r.yaml:1: variation.camera_roll_deg", "-45"),
        ("sequence: {camera_mount: rigid}", "r.yaml:1: sequence:", "allowed: platform ship"),
        (
            "sequence: {platform: ship, camera_mount: gimbal}",
            "r.yaml:1: sequence.camera_m",
            "'rigid'",
        ),
    ],
)
def test_bad_roll_input_names_file_field_and_allowed(text, where, says):
    with pytest.raises(SceneFileError) as err:
        parse_scene_text(text, "r.yaml")
    message = str(err.value)
    assert message.startswith(where) and says in message and "\n" not in message, message


# --------------------------------------------------------------------------------------------
# Rendered: the horizon and a library vessel's box


@pytest.mark.usefixtures("mitsuba_variant")
@pytest.mark.parametrize("roll", [10.0, -20.0])
def test_the_rendered_horizon_tilts_by_the_roll(roll):
    # A level camera (pitch 0) over a calm flat sea: the horizon runs through the image centre
    # with slope -tan(roll) in pixels (v down, square pixels). The sea ends 200 km away: a dip
    # of 0.0034 deg, 0.006 px here.
    width, height = 96, 54
    spec = small_spec(
        camera={"resolution": [width, height], "pitch_deg": 0.0, "roll_deg": roll},
        sun={"elevation_deg": 40.0, "azimuth_deg": 180.0},
    )
    loaded, _ = load_flat_scene(spec)
    u = np.arange(width) + 0.5
    expected = height / 2 - math.tan(math.radians(roll)) * (u - width / 2)
    # Geometry pass: the sky pixels of a column are those whose centre lies above the line.
    sky_rows = np.isinf(passes.render_geometry(loaded).distance_m).sum(axis=0)
    assert np.abs(sky_rows - expected).max() <= 0.5 + 0.01
    # Clean image: the brightest sky just above the horizon, then the edge down to the sea
    # (a mixed pixel as its fraction). Its fitted slope is the roll's.
    y = imaging.luminance(passes.render_clean(loaded, 4, 1, 0.9, 0.7))
    edges = []
    for column in y.T:
        j = int(np.argmax(column))
        sea = np.median(column[j + 2 :])
        edges.append(j + 1 + np.clip((column[j + 1] - sea) / (column[j] - sea), 0.0, 1.0))
    slope = np.polyfit(u, np.array(edges), 1)[0]
    assert slope == pytest.approx(-math.tan(math.radians(roll)), abs=0.01)


def _rolled_frame(level: Camera, points: np.ndarray, rod_m: float, roll: float) -> Camera:
    """``level`` rolled by ``roll``, its field of view and pixel count re-chosen so that the
    points fit with a margin and every rod stays ROD_PX wide (as ``framed_camera``)."""
    camera = replace(level, roll_deg=roll)
    forward, right, up = camera.basis()
    rel = points - camera.origin
    depth = rel @ forward
    half_x = 1.25 * np.abs(rel @ right / depth).max()
    half_y = 1.25 * np.abs(rel @ up / depth).max()
    width = max(160, math.ceil(2.0 * 1.2 * half_x * np.linalg.norm(rel, axis=1).max() / rod_m))
    return replace(
        camera,
        fov_deg=math.degrees(2.0 * math.atan(half_x)),
        width=width,
        height=math.ceil(width * half_y / half_x),
    )


@pytest.mark.usefixtures("mitsuba_variant")
@pytest.mark.parametrize(("kind", "roll"), [("tug", 15.0), ("sailboat", -25.0)])
def test_a_rolled_vessel_box_agrees_with_its_projected_mesh(kind, roll):
    # As test_annotations' unrolled check: the box of the vessel's pixels in the instance pass
    # equals the box of its visible mesh projected by the rolled camera model within 1 px.
    lo, hi = vessels.VESSEL_CLASSES[kind].length_range_m
    length = 0.5 * (lo + hi)
    placed = {"class": kind, "distance_m": max(30.0, 2.5 * length), "heading_deg": 210.0}
    spec = small_spec(
        camera={"height_m": 12.0},
        sea={"model": "flat", "quality": "low"},
        vessels={"placed": [{**placed, "bearing_deg": 0.0, "length_m": length}]},
    )
    geometry = build_geometry(spec, Camera.from_spec(spec.camera))
    (vessel,) = geometry.vessels
    visible = visible_points(vessel.parts)
    rod = thinnest_rod_m(framing_parts(vessel.parts))
    camera = _rolled_frame(framed_camera(12.0, visible, rod), visible, rod, roll)
    assert camera.width * camera.height < 400_000, (camera.width, camera.height)
    assert_rails_set_no_edge(camera, vessel.parts)
    geo = passes.render_geometry(build_scene(spec, camera, geometry, [1000.0]))
    (box,) = boxes_from_instances(geo.instance, [vessel.class_id], geo.footprint_px)
    expected = projected_box(camera, visible)
    assert expected[0] > 0 and expected[2] < camera.width
    assert expected[1] > 0 and expected[3] < camera.height
    measured = np.array([box.x0, box.y0, box.x1, box.y1])
    assert np.all(np.abs(measured - expected) <= 1.0), (camera, measured, expected)


# --------------------------------------------------------------------------------------------
# A rigidly mounted ship camera

RIGID = SHIP.replace("camera: {height_m: 15,", "camera: {height_m: 15, roll_deg: 12,").replace(
    "own_length_m: 60}", "own_length_m: 60, camera_mount: rigid}"
)


def _hull_rotation(heading_deg: float, pitch: float, roll: float) -> np.ndarray:
    """Rz(heading) · Ry(-pitch) · Rx(roll), written out: bow-up pitch, port-up roll."""
    h = math.radians(heading_deg)
    rz = np.array([[math.cos(h), -math.sin(h), 0], [math.sin(h), math.cos(h), 0], [0, 0, 1]])
    ry = np.array(
        [[math.cos(pitch), 0, -math.sin(pitch)], [0, 1, 0], [math.sin(pitch), 0, math.cos(pitch)]]
    )
    rx = np.array(
        [[1, 0, 0], [0, math.cos(roll), -math.sin(roll)], [0, math.sin(roll), math.cos(roll)]]
    )
    return rz @ ry @ rx


def test_a_rigid_camera_turns_with_the_own_ships_attitude():
    spec = parse_scene_text(RIGID, "rigid.yaml")
    level = parse_scene_text(RIGID.replace(", camera_mount: rigid", ""), "level.yaml")
    rolls = []
    for frame in range(3):
        t = float(frame)  # 1 fps
        params = ocean_params(spec)
        surface = ocean.make_surface(replace(params, time_s=params.time_s + t))
        x = 12 * vessels.KNOT_M_S * (t - 1.0)  # heading 0: along +x, at the origin at t = 1 s
        length, beam = 60.0, 60.0 * motion.OWN_BEAM_FRACTION
        z_bow, z_stern, z_port, z_stbd, z_mid = surface.height(
            np.array([x + 30, x - 30, x, x, x]), np.array([0, 0, beam / 2, -beam / 2, 0])
        )
        pitch, roll = math.atan((z_bow - z_stern) / length), math.atan((z_port - z_stbd) / beam)
        hull = _hull_rotation(0.0, pitch, roll)
        mast = Camera(15.0, 50.0, -2.0, 0.0, 64, 36, roll_deg=12.0)  # as mounted, hull level
        camera = frame_camera(spec, frame)
        for got, on_hull in zip(camera.basis(), mast.basis(), strict=True):
            assert got == pytest.approx(hull @ on_hull, abs=1e-12)
        top = np.array([x, 0.0, z_mid]) + hull @ np.array([0.0, 0.0, 15.0])
        assert camera.origin == pytest.approx(top, abs=1e-9)
        # The level mount keeps its roll and mast upright.
        still = frame_camera(level, frame)
        assert still.roll_deg == 12.0 and still.origin == pytest.approx([x, 0, 15 + z_mid])
        rolls.append(camera.roll_deg - 12.0)
    assert max(abs(r) for r in rolls) > 1.0  # a 10 m/s sea rolls a 10 m beam by degrees


def test_a_rigid_ship_sequence_labels_reproject_through_the_rolled_camera(tmp_path):
    scene = tmp_path / "rigidseq.yaml"
    scene.write_text(RIGID.replace("name: shipseq", "name: rigidseq"))
    out = tmp_path / "out"
    assert main(["render", str(scene), "--out", str(out), "--quiet"]) == 0
    spec = parse_scene_text(RIGID, "rigid.yaml")
    boxed = 0
    for frame in range(3):
        meta = json.loads((out / "meta" / f"rigidseq_f{frame:04d}.json").read_text())
        camera = frame_camera(spec, frame)
        assert meta["camera"]["roll_deg"] == 12.0 and meta["sequence"]["camera_mount"] == "rigid"
        assert meta["camera"]["position_m"] == pytest.approx(camera.origin.tolist())
        assert meta["camera"]["pitch_used_deg"] == pytest.approx(camera.pitch_deg)
        assert meta["camera"]["roll_used_deg"] == pytest.approx(camera.roll_deg)
        assert meta["camera"]["heading_used_deg"] == pytest.approx(camera.heading_deg)
        for vessel in meta["vessels"]:
            if vessel["box_px"] is None:
                continue
            boxed += 1
            pose = vessel["pose"]
            low, high = np.array(pose["bounds_m"])
            corners = np.array(
                [
                    [a, b, c]
                    for a in (low[0], high[0])
                    for b in (low[1], high[1])
                    for c in (low[2], high[2])
                ]
            )
            rotation = _hull_rotation(
                pose["heading_deg"], math.radians(pose["pitch_deg"]), math.radians(pose["roll_deg"])
            )
            u, v, front = camera.project(corners @ rotation.T + np.array(pose["position_m"]))
            assert front.all()
            x0, y0, x1, y1 = vessel["box_px"]
            # The labelled pixels lie inside the re-projected hull box (pixel edges: ±1 px).
            assert (
                u.min() - 1 <= x0 and x1 <= u.max() + 1 and v.min() - 1 <= y0 and y1 <= v.max() + 1
            )
    assert boxed >= 4
