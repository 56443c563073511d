"""Scene YAML validation: good files load; every malformed file gives a clear, located message."""

from __future__ import annotations

from pathlib import Path

import pytest

from seahaze.cli import main
from seahaze.sceneio import SceneFileError, load_scene, parse_scene_text

ROOT = Path(__file__).resolve().parents[1]


def test_default_scene_is_valid():
    spec, name = load_scene(ROOT / "scenes" / "default.yaml")
    assert name == "default"
    assert len(spec.haze.levels) == 11


def test_empty_file_gives_all_defaults():
    spec = parse_scene_text("")
    assert spec.camera.fov_deg == 60.0 and spec.haze.threshold == "koschmieder"


BAD_SCENES = [
    # (yaml text, expected line, field, words the message must contain)
    (
        "camera:\n  height_m: -3\n",
        2,
        "camera.height_m",
        ["greater than or equal", "allowed", "in m"],
    ),
    ("camera:\n  heigth_m: 10\n", 2, "camera.heigth_m", ["unknown key", "height_m"]),
    ("sun:\n  elevation_deg: 95\n", 2, "sun.elevation_deg", ["less than or equal", "89.5"]),
    ("haze:\n  threshold: fog\n", 2, "haze.threshold", ["koschmieder", "mor"]),
    ("haze:\n  albedo: 1.5\n", 2, "haze.albedo", ["less than or equal to 1"]),
    ("haze:\n  levels: [300, -1]\n", 2, "haze.levels[1]", ["greater than or equal to 10"]),
    (
        "camera:\n  resolution: [640]\n",
        2,
        "camera.resolution[1]",
        ["missing list item 2", "width and height"],
    ),
    ("render:\n  mode: fast\n", 2, "render.mode", ["reference", "asm"]),
    ("render:\n  spp: lots\n", 2, "render.spp", ["integer"]),
    ("sea:\n  model: wavy\n", 2, "sea.model", ["flat", "gerstner", "fft"]),
    ("camera: {fov_deg: 60}\ncamera: {fov_deg: 30}\n", 2, "camera", ["duplicate key"]),
    (
        "vessels:\n  placed:\n    - {class: submarine, distance_m: 500}\n",
        3,
        "vessels.placed[0].class",
        ["unknown vessel class", "tug"],
    ),
    (
        "vessels:\n  placed:\n    - {class: tug, distance_m: 500, length_m: 400}\n",
        3,
        "vessels.placed[0].length_m",
        ["outside the tug range"],
    ),
    (
        "vessels:\n  sample: {count: 3, distance_m: [4000, 100]}\n",
        2,
        "vessels.sample",
        ["near < far"],
    ),
    ("haze:\n  top_m: .nan\n", 2, "haze.top_m", ["finite"]),
    ("camera: [1, 2]\n", 1, "camera", ["valid dictionary"]),
    ("camera:\n  height_m: 10\n   pitch_deg: 3\n", 3, "", ["not valid YAML"]),
    ("- just\n- a list\n", 1, "", ["mapping of sections"]),
]


@pytest.mark.parametrize(("text", "line", "field", "words"), BAD_SCENES)
def test_malformed_scene_is_reported_with_line_field_and_allowed_values(text, line, field, words):
    with pytest.raises(SceneFileError) as info:
        parse_scene_text(text, "bad.yaml")
    problem = info.value.problems[0]
    assert problem.file == "bad.yaml"
    assert problem.line == line
    assert problem.field == field
    for word in words:
        assert word in problem.message, problem.message


def test_every_problem_is_reported_at_once():
    text = "camera:\n  height_m: -1\n  fov_deg: 500\nsun:\n  colour: red\n"
    with pytest.raises(SceneFileError) as info:
        parse_scene_text(text, "x.yaml")
    assert [p.line for p in info.value.problems] == [2, 3, 5]


def test_validate_command_prints_problems_without_traceback(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text("haze:\n  g: 2\n")
    assert main(["validate", str(bad)]) == 2
    err = capsys.readouterr().err
    assert f"{bad}:2: haze.g:" in err and "Traceback" not in err


def test_validate_command_missing_file(tmp_path, capsys):
    assert main(["validate", str(tmp_path / "nope.yaml")]) == 2
    assert "no such file" in capsys.readouterr().err


def test_validate_command_accepts_default(capsys):
    assert main(["validate", str(ROOT / "scenes" / "default.yaml")]) == 0
    assert "ok: default" in capsys.readouterr().out


@pytest.mark.parametrize(
    "args",
    [["--vis", "abc"], ["--vis", "4000..300"], ["--vis", "0"], ["--res", "100"], ["--spp", "0"]],
)
def test_render_rejects_bad_arguments_with_exit_2(args, capsys, tmp_path):
    assert (
        main(["render", str(ROOT / "scenes" / "default.yaml"), "--out", str(tmp_path), *args]) == 2
    )
    err = capsys.readouterr().err
    assert err.startswith("seahaze: error:") and len(err.strip().splitlines()) == 1


def test_levels_command_prints_sigma_and_class(capsys):
    assert main(["levels", "--vis", "300,800"]) == 0
    out = capsys.readouterr().out
    assert "0.013040" in out and "strict" in out and "restricted" in out
