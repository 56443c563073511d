"""Issue #35: ``seahaze validate`` (and ``render``) report every problem of a scene file in one
round, each as ``seahaze: error: FILE:LINE: FIELD: MESSAGE`` sorted by line, and every file
refused whole is located too.

A negative camera height, a 600° field of view, albedo 1.9 and an unknown vessel class used to
come in two rounds (the schema's errors, then the class once they were fixed), the second with
a prefix the first lacked.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

from seahaze.cli import main
from seahaze.sceneio import MAX_PROBLEMS, SceneFileError, parse_scene_text

ROOT = Path(__file__).resolve().parents[1]
WORKBOAT = ROOT / "assets" / "meshes" / "workboat.ply"
LINE = re.compile(r"^seahaze: error: (?P<file>.+?):(?P<line>\d+): (?P<field>[^ :]+): (?P<text>.+)$")
"""A problem line: one prefix, the file, its line, the dotted field (or ``(file)``), the text."""
MORE = re.compile(r"^seahaze: error: (?P<file>.+?):(?P<line>\d+): … and (?P<n>\d+) more problem")

# Nine problems of five kinds in one file: schema (camera, haze, a class weight), semantic
# (an unknown class in the list and in the sampler's mix), a missing user mesh, speed and
# length outside the class's ranges. Each is independent of the others.
MANY = """\
camera:
  height_m: -3
  fov_deg: 600
haze:
  albedo: 1.9
vessels:
  placed:
    - {class: submarine, distance_m: 500}
    - {class: tug, distance_m: 800, mesh: {path: nowhere.obj, scale_m: 30}}
    - {class: tug, distance_m: 900, speed_kn: 35, length_m: 3}
  sample: {count: 2, classes: {yacht: 1, tug: -1}}
"""
EXPECTED = [
    (2, "camera.height_m", ">= 0.5"),
    (3, "camera.fov_deg", "<= 120"),
    (5, "haze.albedo", "<= 1"),
    (8, "vessels.placed[0].class", "unknown vessel class 'submarine'"),
    (9, "vessels.placed[1].mesh.path", "no such mesh file 'nowhere.obj'"),
    (10, "vessels.placed[2].speed_kn", "tug speed 35 kn is outside the tug range"),
    (10, "vessels.placed[2].length_m", "tug length 3 m is outside the tug range"),
    (11, "vessels.sample.classes.tug", "greater than 0"),
    (11, "vessels.sample.classes.yacht", "unknown vessel class 'yacht'"),
]


def run(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, list[str]]:
    """``seahaze ARGS``: the exit code and the non-empty lines of stderr."""
    code = main(args)
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return code, [line for line in err.splitlines() if line.strip()]


def parsed(lines: list[str]) -> list[re.Match[str]]:
    """Each line as a problem line; fails on a line without the one prefix and FILE:LINE."""
    matches = [LINE.match(line) for line in lines]
    assert all(matches), lines
    return [m for m in matches if m]


def write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_problems_of_every_kind_come_in_one_run(tmp_path, capsys):
    scene = write(tmp_path, "many.yaml", MANY)
    code, lines = run(["validate", str(scene)], capsys)
    assert code == 2
    found = parsed(lines)
    assert len(found) == len(EXPECTED), lines
    for match, (line, field, words) in zip(found, EXPECTED, strict=True):
        assert match["file"] == str(scene)
        assert (int(match["line"]), match["field"]) == (line, field), match.string
        assert words in match["text"], match.string
    numbers = [int(m["line"]) for m in found]
    assert numbers == sorted(numbers)


def test_render_prints_the_same_lines_as_validate(tmp_path, capsys):
    scene = write(tmp_path, "many.yaml", MANY)
    _, validated = run(["validate", str(scene)], capsys)
    code, rendered = run(["render", str(scene), "--out", str(tmp_path / "out")], capsys)
    assert code == 2
    assert rendered == validated
    assert not (tmp_path / "out").exists()


def test_one_problem_has_the_same_prefix_as_many(tmp_path, capsys):
    one = write(
        tmp_path, "one.yaml", "vessels:\n  placed:\n    - {class: yacht, distance_m: 300}\n"
    )
    code, lines = run(["validate", str(one)], capsys)
    assert code == 2
    (match,) = parsed(lines)
    assert (match["line"], match["field"]) == ("3", "vessels.placed[0].class")


def test_problems_of_several_files_each_keep_their_file(tmp_path, capsys):
    first = write(tmp_path, "a.yaml", "camera:\n  fov_deg: 600\n")
    second = write(tmp_path, "b.yaml", "sun: {}\nhaze: {albedo: 2}\nsky: {colour: red}\n")
    code, lines = run(["validate", str(first), str(second)], capsys)
    assert code == 2
    found = [(m["file"], int(m["line"]), m["field"]) for m in parsed(lines)]
    assert found == [
        (str(first), 2, "camera.fov_deg"),
        (str(second), 2, "haze.albedo"),
        (str(second), 3, "sky.colour"),
    ]


def test_cross_field_checks_are_not_hidden_by_an_unrelated_field(tmp_path, capsys):
    # pydantic skips a model's own checks once one of its fields fails, and SceneSpec's once
    # any field anywhere does: the fog over the haze top, the shore mast, the sea's clock and
    # a shore platform's own-ship settings all came only after albedo and heading were fixed.
    scene = write(
        tmp_path,
        "cross.yaml",
        "camera: {height_m: 80, heading_deg: 900}\n"
        "sea: {time_s: 999999}\n"
        "haze:\n  albedo: 1.9\n  top_m: 100\n  fog_layer: {top_m: 90, edge_m: 10}\n"
        "sequence: {frames: 1000, fps: 0.01, own_speed_kn: 5}\n",
    )
    code, lines = run(["validate", str(scene)], capsys)
    assert code == 2
    text = "\n".join(lines)
    for words in (
        "camera.heading_deg: Input should be less than or equal to 360",
        "haze.albedo: Input should be less than or equal to 1",
        ":3: haze: fog_layer.top_m + 2 fog_layer.edge_m (110 m) must not pass top_m (100 m)",
        "camera.height_m 80 m does not fit a sequence's shore mast",
        "past the sea's limit",
        ":7: sequence: own_speed_kn and own_heading_deg describe an own ship",
    ):
        assert words in text, text
    assert len(parsed(lines)) == 6


def test_a_cross_field_check_is_not_run_on_a_default_in_place_of_a_bad_value(tmp_path, capsys):
    # fps 500 fails; the sea-clock check must not judge the default 10 fps in its place (10,000
    # frames at 10 fps would end past the sea's limit, at 500 fps they do not).
    scene = write(
        tmp_path,
        "clock.yaml",
        "sea: {time_s: 999500}\nhaze: {albedo: 2}\nsequence: {frames: 10000, fps: 500}\n",
    )
    code, lines = run(["validate", str(scene)], capsys)
    assert code == 2
    fields = [m["field"] for m in parsed(lines)]
    assert fields == ["haze.albedo", "sequence.fps"], lines


def test_the_layout_is_checked_beside_an_unrelated_schema_error(tmp_path, capsys):
    scene = write(
        tmp_path,
        "layout.yaml",
        "haze: {albedo: 1.9}\nvessels:\n  placed:\n"
        "    - {class: tug, distance_m: 300, bearing_deg: 0}\n"
        "    - {class: tug, distance_m: 300, bearing_deg: 0}\n",
    )
    code, lines = run(["validate", str(scene)], capsys)
    assert code == 2
    found = parsed(lines)
    assert [(m["line"], m["field"]) for m in found] == [
        ("1", "haze.albedo"),
        ("3", "vessels.placed"),
    ]
    assert "cannot be laid out" in found[1]["text"] and "overlap" in found[1]["text"]


def test_the_layout_waits_for_a_camera_that_failed(tmp_path, capsys):
    # The layout reads the camera: with a bad one it is not judged (no guess at a default).
    scene = write(
        tmp_path,
        "layout.yaml",
        "camera: {fov_deg: 600}\nvessels:\n  placed:\n"
        "    - {class: tug, distance_m: 300, bearing_deg: 0}\n"
        "    - {class: tug, distance_m: 300, bearing_deg: 0}\n",
    )
    _, lines = run(["validate", str(scene)], capsys)
    assert [m["field"] for m in parsed(lines)] == ["camera.fov_deg"]


def test_no_problem_is_told_twice():
    text = (
        "haze:\n  top_m: .nan\n"
        "vessels:\n  placed:\n    - {class: tug, distance_m: 300, length_m: 600}\n"
        f"    - {{class: tug, distance_m: 500, length_m: 30, mesh: {{path: {WORKBOAT}, "
        "scale_m: 20}}\n"
    )
    with pytest.raises(SceneFileError) as info:
        parse_scene_text(text, "twice.yaml")
    found = [(p.line, p.field) for p in info.value.problems]
    # .nan: not finite (not also out of bounds); 600 m: the schema's bound (not also the tug's
    # range); length with a mesh: the schema's rule (not also the tug's range).
    assert found == [(2, "haze.top_m"), (5, "vessels.placed[0].length_m"), (6, "vessels.placed[1]")]
    assert "not a finite number" in info.value.problems[0].message


def test_the_cap_counts_the_rest(tmp_path, capsys):
    keys = "".join(f"  k{i}: {i}\n" for i in range(300))
    scene = write(tmp_path, "keys.yaml", "camera: {fov_deg: 600}\nsun:\n" + keys)
    code, lines = run(["validate", str(scene)], capsys)
    assert code == 2
    *problems, more = lines
    assert len(problems) == MAX_PROBLEMS
    found = parsed(problems)
    assert (found[0]["line"], found[0]["field"]) == ("1", "camera.fov_deg")
    assert all(m["field"].startswith("sun.k") for m in found[1:])
    numbers = [int(m["line"]) for m in found]
    assert numbers == sorted(numbers)
    match = MORE.match(more)
    assert match, more
    # 301 problems: 100 located (20 shown, 80 left) and 201 only counted.
    assert match["file"] == str(scene) and int(match["n"]) == 301 - MAX_PROBLEMS
    assert int(match["line"]) == numbers[-1] + 1


# Files refused whole: each is one located line. (text, line)
WHOLE_FILE = {
    "not_utf8": (b"camera:\n  height_m: 3\n\xff\xfe junk\n", 3),
    "nul_bytes": (b"camera:\n  height_m: 3\x00\n", 2),
    "top_list": (b"# a list\n\n- a\n- b\n", 3),
    "top_scalar": (b"just words\n", 1),
    "syntax": (b"camera:\n  height_m: 10\n   pitch_deg: 3\n", 3),
    "tab_indent": (b"camera:\n\theight_m: 3\n", 2),
    "two_documents": (b"camera: {}\n---\nsun: {}\n", 2),
    "undefined_alias": (b"sun: {}\ncamera: *nowhere\n", 2),
    "recursive_alias": (b"sun: {}\ncamera: &a\n  x: *a\n", 2),
    "bad_date": (b"name: x\nsea:\n  time_s: 2024-13-45\n", 3),
    "huge_integer": (b"sun: {}\nrender:\n  seed: " + b"9" * 5000 + b"\n", 3),
    "deep_nesting": (b"sun: {}\ncamera: " + b"[" * 40 + b"]" * 40 + b"\n", 2),
    "alias_bomb": (
        b"a: &a [x, x, x, x, x, x, x, x, x, x]\n"
        + b"".join(
            f"{k}: &{k} [{', '.join([f'*{p}'] * 10)}]\n".encode()
            for p, k in zip("abcde", "bcdef", strict=True)
        ),
        0,
    ),
}


@pytest.mark.parametrize("stem", sorted(WHOLE_FILE))
def test_a_file_refused_whole_is_located(tmp_path, capsys, stem):
    data, line = WHOLE_FILE[stem]
    scene = tmp_path / f"{stem}.yaml"
    scene.write_bytes(data)
    code, lines = run(["validate", str(scene)], capsys)
    assert code == 2
    (match,) = parsed(lines)
    assert match["file"] == str(scene)
    if line:
        assert int(match["line"]) == line, match.string
    else:
        assert int(match["line"]) >= 1, match.string


def test_a_duplicate_key_is_located_beside_the_other_problems(tmp_path, capsys):
    scene = write(tmp_path, "dupe.yaml", "camera:\n  height_m: 10\n  height_m: 12\nhaze: {g: 2}\n")
    code, lines = run(["validate", str(scene)], capsys)
    assert code == 2
    found = [(m["line"], m["field"]) for m in parsed(lines)]
    assert found == [("3", "camera.height_m"), ("4", "haze.g")]
    assert "duplicate key" in lines[0]


def test_paths_that_are_not_scene_files_are_located_at_line_1(tmp_path, capsys):
    folder = tmp_path / "folder.yaml"
    folder.mkdir()
    loop = tmp_path / "loop.yaml"
    loop.symlink_to(loop)
    big = tmp_path / "big.yaml"
    big.write_text("# padding\n" * 220_000)
    cases = {
        folder: "is a folder",
        loop: "cannot read",
        big: "at most 1 MiB",
        tmp_path / "missing.yaml": "no such file",
    }
    if hasattr(os, "mkfifo"):
        fifo = tmp_path / "pipe.yaml"
        os.mkfifo(fifo)
        cases[fifo] = "not a regular file"
    for path, words in cases.items():
        code, lines = run(["validate", str(path)], capsys)
        assert code == 2
        (match,) = parsed(lines)
        assert (match["file"], match["line"], match["field"]) == (str(path), "1", "(file)")
        assert words in match["text"]


def test_an_empty_file_is_the_default_scene(tmp_path, capsys):
    # Not a rejection: an empty (or comments-only) scene file takes every default.
    for text in ("", "# nothing set\n"):
        scene = write(tmp_path, "empty.yaml", text)
        code, lines = run(["validate", str(scene)], capsys)
        assert code == 0 and not lines


def test_every_problem_has_a_line():
    for text in ("[1, 2]", "camera: [1, 2]", "sequence: {frames: 5}\ncamera: {height_m: 80}\n"):
        with pytest.raises(SceneFileError) as info:
            parse_scene_text(text, "x.yaml")
        assert all(p.line >= 1 for p in info.value.problems)
        assert all(str(p).startswith("x.yaml:") for p in info.value.problems)
