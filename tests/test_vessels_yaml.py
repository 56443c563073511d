"""Vessels from the scene YAML: user meshes (paths, errors, class ids, boxes) and follow_slope."""

from __future__ import annotations

import importlib.util
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
import trimesh

from seahaze.camera import Camera
from seahaze.cli import main
from seahaze.labels import boxes_from_instances
from seahaze.render import passes
from seahaze.render.scene import build_scene
from seahaze.sceneio import SceneFileError, load_scene, parse_scene_text
from seahaze.spec import SceneSpec
from seahaze.vessels import CLASS_NAMES, load_user_mesh
from seahaze.vessels.user_mesh import ASSETS_DIR
from seahaze.world import build_geometry
from test_annotations import projected_box, visible_points

ROOT = Path(__file__).resolve().parents[1]
WORKBOAT = ROOT / "assets" / "meshes" / "workboat.ply"

# The workboat file is +y up, +z forward (glTF convention), 16 units long, 4.8 wide.
MESH_YAML = """\
camera: {{height_m: 10, pitch_deg: -1, fov_deg: 40, resolution: [160, 90]}}
sea: {{model: flat, quality: low}}
vessels:
  placed:
    - class: tug
      distance_m: 120
      bearing_deg: 4
      heading_deg: 150
      mesh:
        path: {path}
        scale_m: 24
        up_axis: "+y"
        forward_axis: "+z"
        draft_m: 1.2
"""


def docs_yaml_blocks() -> list[str]:
    return re.findall(r"```yaml\n(.*?)```", (ROOT / "docs" / "scenes.md").read_text(), re.S)


def test_docs_example_loads_the_asset_mesh_with_follow_slope(tmp_path: Path) -> None:
    (block,) = [b for b in docs_yaml_blocks() if "mesh:" in b]
    # The example's path is relative to assets/, found from any scene folder.
    spec = parse_scene_text(block, "example.yaml", tmp_path)
    assert spec.vessels.follow_slope is True
    mesh = spec.vessels.placed[0].mesh
    assert Path(mesh.path) == WORKBOAT.resolve() == (ASSETS_DIR / "meshes" / "workboat.ply")
    assert (mesh.scale_m, mesh.up_axis, mesh.forward_axis, mesh.draft_m) == (16, "+y", "+z", 0.9)
    assert parse_scene_text("").vessels.follow_slope is False


def test_committed_workboat_is_the_generator_output() -> None:
    spec = importlib.util.spec_from_file_location(
        "make_example_mesh", ROOT / "scripts" / "make_example_mesh.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    expected = module.workboat_mesh()
    stored = trimesh.load(WORKBOAT, process=False)
    np.testing.assert_allclose(stored.vertices, expected.vertices, atol=1e-6)
    np.testing.assert_array_equal(stored.faces, expected.faces)
    np.testing.assert_array_equal(stored.visual.face_colors, expected.visual.face_colors)
    assert WORKBOAT.stat().st_size < 4000
    # The documented axes bring it into the vessel frame: bow (the stem at x = +8) forward,
    # mast top (z = 7) up, beam 4.8 across.
    model = load_user_mesh(WORKBOAT, "tug", 16.0, "+y", "+z", draft_m=0.9)
    np.testing.assert_allclose(model.bounds(), [[-8, -2.4, -0.9], [8, 2.4, 7.0]], atol=1e-5)
    assert len(model.parts) == 3  # hull, orange wheelhouse, white house and mast


def test_mesh_path_relative_to_the_scene_file(tmp_path: Path) -> None:
    folder = tmp_path / "boats"
    folder.mkdir()
    shutil.copy(WORKBOAT, folder / "my boat.ply")
    scene = tmp_path / "scene.yaml"
    scene.write_text(MESH_YAML.format(path='"boats/my boat.ply"'))
    spec, _ = load_scene(scene)
    assert spec.vessels.placed[0].mesh.path == str((folder / "my boat.ply").resolve())
    # An absolute path is taken as it is.
    scene.write_text(MESH_YAML.format(path=f'"{WORKBOAT}"'))
    assert load_scene(scene)[0].vessels.placed[0].mesh.path == str(WORKBOAT)


BAD_MESHES = [
    # (mesh lines, line of the problem, field, words the message must contain)
    ("path: missing.obj, scale_m: 20", 5, "vessels.placed[0].mesh.path", ["no such mesh file"]),
    ("path: boat.fbx, scale_m: 20", 5, "vessels.placed[0].mesh.path", [".fbx", ".glb", ".stl"]),
    ("path: garbage.ply, scale_m: 20", 5, "vessels.placed[0].mesh.path", ["cannot use", ".ply"]),
    ("path: empty.obj, scale_m: 20", 5, "vessels.placed[0].mesh.path", ["no triangles"]),
    ("path: x.obj, scale_m: 20, up_axis: up", 5, "vessels.placed[0].mesh.up_axis", ["'+z'"]),
    (
        "path: x.obj, scale_m: 20, up_axis: '+y', forward_axis: '-y'",
        5,
        "vessels.placed[0].mesh",
        ["perpendicular"],
    ),
    ("path: x.obj, scale_m: 0", 5, "vessels.placed[0].mesh.scale_m", ["greater than 0", "in m"]),
    ("scale_m: 20", 5, "vessels.placed[0].mesh.path", ["required"]),
    (  # a 7 m workboat is about 2.8 m high: 50 m of draft hides all of it (and its label)
        f"path: {WORKBOAT}, scale_m: 7, draft_m: 50",
        5,
        "vessels.placed[0].mesh.draft_m",
        ["draft_m 50 m sinks the whole mesh", "allowed: 0 <= draft_m <"],
    ),
]


@pytest.mark.parametrize(("mesh", "line", "field", "words"), BAD_MESHES)
def test_bad_mesh_is_reported_with_file_line_field_and_what_is_allowed(
    tmp_path: Path, mesh: str, line: int, field: str, words: list[str]
) -> None:
    (tmp_path / "garbage.ply").write_bytes(b"ply\nthis is not a mesh\n")
    (tmp_path / "empty.obj").write_text("# no geometry\n")
    scene = tmp_path / "bad.yaml"
    scene.write_text(
        f"vessels:\n  placed:\n    - class: tug\n      distance_m: 300\n      mesh: {{{mesh}}}\n"
    )
    with pytest.raises(SceneFileError) as info:
        load_scene(scene)
    (problem,) = info.value.problems
    assert (problem.file, problem.line, problem.field) == (str(scene), line, field)
    for word in words:
        assert word in problem.message, problem.message
    assert "\n" not in str(problem)


def test_length_with_a_mesh_is_rejected() -> None:
    text = (
        "vessels:\n  placed:\n    - class: tug\n      distance_m: 300\n      length_m: 30\n"
        f"      mesh: {{path: {WORKBOAT}, scale_m: 20}}\n"
    )
    with pytest.raises(SceneFileError) as info:
        parse_scene_text(text, "x.yaml")
    (problem,) = info.value.problems
    assert (problem.line, problem.field) == (3, "vessels.placed[0]")
    assert "mesh.scale_m" in problem.message


def test_validate_command_names_the_missing_mesh_without_traceback(tmp_path, capsys) -> None:
    scene = tmp_path / "bad.yaml"
    scene.write_text(MESH_YAML.format(path="nope/boat.glb"))
    assert main(["validate", str(scene)]) == 2
    err = capsys.readouterr().err
    assert f"{scene}:10: vessels.placed[0].mesh.path: no such mesh file 'nope/boat.glb'" in err
    assert "Traceback" not in err


@pytest.mark.usefixtures("mitsuba_variant")
def test_user_mesh_vessel_is_placed_labelled_with_its_class_and_boxed(tmp_path: Path) -> None:
    scene = tmp_path / "scene.yaml"
    scene.write_text(MESH_YAML.format(path="meshes/workboat.ply"))  # found under assets/
    spec, _ = load_scene(scene)
    camera = Camera.from_spec(spec.camera)
    geometry = build_geometry(spec, camera)
    (vessel,) = geometry.vessels
    assert vessel.class_id == CLASS_NAMES.index("tug")
    # Scaled 24/16 = 1.5: beam 4.8 -> 7.2 m; height 7.9 -> 11.85 m with the draft 1.2 m below.
    assert vessel.length_m == 24.0 and vessel.beam_m == pytest.approx(7.2, abs=1e-4)
    assert vessel.air_draft_m == pytest.approx(1.5 * 7.9 - 1.2, abs=1e-4)
    # The world mesh is the file in the vessel frame, turned to heading 150 deg and moved to
    # 120 m at bearing 4 deg on the flat sea (z = 0).
    model = load_user_mesh(WORKBOAT, "tug", 24.0, "+y", "+z", draft_m=1.2)
    heading, bearing = np.radians(150.0), np.radians(4.0)
    turn = np.array(
        [[np.cos(heading), -np.sin(heading), 0], [np.sin(heading), np.cos(heading), 0], [0, 0, 1]]
    )
    expected_world = np.vstack([part.mesh.vertices for part in model.parts]) @ turn.T + [
        120 * np.cos(bearing),
        120 * np.sin(bearing),
        0.0,
    ]
    world = np.vstack([part.vertices for part in vessel.parts])
    np.testing.assert_allclose(world, expected_world, atol=1e-4)
    loaded = build_scene(spec, camera, geometry, [1000.0])
    geo = passes.render_geometry(loaded)
    (box,) = boxes_from_instances(geo.instance, [vessel.class_id], geo.footprint_px)
    assert box.class_id == 5
    expected = projected_box(camera, visible_points(vessel.parts))
    measured = np.array([box.x0, box.y0, box.x1, box.y1])
    assert np.all(np.abs(measured - expected) <= 1.0), (measured, expected)


def _kabsch(source: np.ndarray, target: np.ndarray) -> np.ndarray:
    """The rotation R minimising |R source - target| over corresponding rows (SVD)."""
    u, _, vt = np.linalg.svd(source.T @ target)
    d = np.sign(np.linalg.det(vt.T @ u.T))
    return vt.T @ np.diag([1.0, 1.0, d]) @ u.T


def test_follow_slope_pitches_and_rolls_the_hull_to_the_sea() -> None:
    def build(follow: bool):
        data = {
            "camera": {"height_m": 10.0, "resolution": [64, 36]},
            "sea": {"model": "gerstner", "wind_speed": 12.0, "seed": 4, "quality": "low"},
            "vessels": {
                "follow_slope": follow,
                "placed": [
                    {
                        "class": "fishing_boat",
                        "distance_m": 150.0,
                        "bearing_deg": 3.0,
                        "heading_deg": 70.0,
                        "length_m": 20.0,
                    }
                ],
            },
        }
        spec = SceneSpec.model_validate(data)
        geometry = build_geometry(spec, Camera.from_spec(spec.camera))
        return geometry.vessels[0], geometry.surface

    upright, surface = build(False)
    tilted, _ = build(True)
    p = upright.placement
    origin = np.array([p.x, p.y, upright.waterline_z])
    assert tilted.waterline_z == upright.waterline_z  # heave is the same, only the attitude
    v0 = np.vstack([part.vertices for part in upright.parts]).astype(np.float64) - origin
    v1 = np.vstack([part.vertices for part in tilted.parts]).astype(np.float64) - origin
    rotation = _kabsch(v0, v1)
    np.testing.assert_allclose(v0 @ rotation.T, v1, atol=2e-3)  # a rotation about midships

    # Expected attitude, computed here from the sea heights at bow, stern and both sides.
    h = np.radians(p.heading_deg)
    fwd, port = np.array([np.cos(h), np.sin(h), 0.0]), np.array([-np.sin(h), np.cos(h), 0.0])
    ends = origin[None, :2] + np.array(
        [
            0.5 * upright.length_m * fwd[:2],
            -0.5 * upright.length_m * fwd[:2],
            0.5 * upright.beam_m * port[:2],
            -0.5 * upright.beam_m * port[:2],
        ]
    )
    z = surface.height(ends[:, 0], ends[:, 1])
    pitch = np.arctan((z[0] - z[1]) / upright.length_m)
    roll = np.arctan((z[2] - z[3]) / upright.beam_m)
    assert min(abs(np.degrees(pitch)), abs(np.degrees(roll))) > 0.3  # a real slope to follow
    bow, side = rotation @ fwd, rotation @ port
    assert bow[2] == pytest.approx(np.sin(pitch), abs=1e-5)  # bow up by the pitch
    assert side[2] == pytest.approx(np.cos(pitch) * np.sin(roll), abs=1e-5)  # port up by roll


@pytest.mark.parametrize(
    ("rule", "field"),
    [
        ("max_image_overlap: 1.5", "vessels.sample.max_image_overlap"),
        ("detectable: {share: 2}", "vessels.sample.detectable.share"),
    ],
)
def test_layout_rules_outside_zero_to_one_name_the_field_and_range(rule: str, field: str) -> None:
    with pytest.raises(SceneFileError) as info:
        parse_scene_text(f"vessels:\n  sample:\n    count: 3\n    {rule}\n", "o.yaml")
    message = str(info.value)
    assert message.startswith(f"o.yaml:4: {field}"), message
    assert "less than or equal to 1" in message and "\n" not in message


def test_a_sampler_without_the_layout_rules_records_neither() -> None:
    spec = parse_scene_text("vessels:\n  sample:\n    count: 3\n", "o.yaml")
    sample = spec.model_dump(mode="json")["vessels"]["sample"]
    assert "max_image_overlap" not in sample and "detectable" not in sample
    kept = parse_scene_text("vessels:\n  sample: {count: 3, max_image_overlap: 0.2}\n", "o.yaml")
    assert kept.model_dump(mode="json")["vessels"]["sample"]["max_image_overlap"] == 0.2
