"""A hostile pass over the surfaces added since the first corpus (issue #35): sequences,
``seahaze export``, ``--split``, ``--workers``, user meshes, and ``seahaze metric``'s tables,
datasets and ``--model``. Every case is refused with exit code 2 and one line on stderr naming
the file or flag, the field and what is allowed (argparse's own refusals: its usage lines and
one error line) — no traceback, no hang (each well under 10 s) — and leaves every watched
folder as it was, seahaze's state folder included: no output folder or file created, nothing
changed or deleted.

Cases per surface (``test_the_corpus_counts_match_this_docstring`` keeps them true):

- sequences: 46 — ``--frames`` 0/-1/huge, ``--fps`` 0/-5/NaN/±inf/huge, ``--fps`` on a still
  scene, flags that are not numbers, ``sequence:`` blocks: empty, without ``frames``, bad
  ``frames``/``fps``/``platform``, unknown keys, own-ship fields on a shore mast,
  ``encounters`` and ``camera_mount``
- split: 11 — wrong count, not numbers, sums other than 1, negative, NaN, inf, train 0
- workers: 4 — 0, -1, 100000, 10^20
- meshes: 8 — empty file, NaN and inf vertices (also an unused one in a PLY, and one a PLY
  face uses, which trimesh's processed load drops with the face), zero extent, up axis equal
  to the forward axis (2)
- export: 66 — every ``--layout`` on a half-finished dataset, ``--out`` inside or above the
  dataset or through a link into it, onto a file or under one, onto a foreign folder or a
  planted record, ``--levels``, unknown layout and link, missing images, damaged
  ``dataset.json`` (deep, scene entries that are not mappings, levels without a visibility,
  names that escape, NaN, 5000-digit numbers …), a FIFO or folder as manifest
- export hf: 17 — ``--layout hf`` on the hand-written dataset: a scene's meta deep, not a
  mapping, missing or a folder, a labelled vessel's box reversed or not numbers, its class not a
  class, a level missing from its meta, a label file that disagrees with the meta, the depth
  missing or truncated, an image of another size; a bad ``--license``, one for another layout;
  no pyarrow (run always; the others need it)
- table: 29 — ``seahaze metric newvis --table``: deep JSON, wrong types, non-finite and huge
  numbers, a NUL or a 200 kB field in a CSV, not UTF-8, 2 MiB, a FIFO or folder
- metric dataset: 6 — deep, alias-bomb, nested-names and binary ``data.yaml``; a damaged
  ``dataset.json`` read for ``--split``
- model: 6 — ``--model`` weights missing or a folder (calibrate, newvis); garbage weights (2,
  run only with Ultralytics installed), garbage weights without Ultralytics (1, run only
  without it)

No case renders: a render that starts fails the test (the ``no_render`` fixture), and the
dataset the export and metric cases read is written by hand (``fake_dataset``: 8×4 px images,
depth and meta, four scenes, two levels, three splits) and checked to export cleanly in every
layout (``hf`` where pyarrow is installed).
"""

from __future__ import annotations

import importlib.util
import json
import os
import re
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from conftest import cli_run
from seahaze.dataset.manifest import data_yaml_text, level_entries, manifest
from seahaze.dataset.owned import STATE_ENV
from seahaze.export.layouts import LAYOUTS as EXPORT_LAYOUTS
from seahaze.fileio import write_exr
from seahaze.sceneio import parse_scene_text
from seahaze.spec import OverrideError, with_overrides

ROOT = Path(__file__).resolve().parents[1]
TINY = ROOT / "tests" / "data" / "hostile" / "tiny.yaml"
HAS_ULTRALYTICS = importlib.util.find_spec("ultralytics") is not None
HAS_PYARROW = importlib.util.find_spec("pyarrow") is not None


# --------------------------------------------------------------------------------------------
# Running a case


def run(args: list[str]) -> tuple[int, str, str]:
    """``seahaze ARGS`` in this process within the case deadline (:func:`conftest.cli_run`)."""
    return cli_run(args)


def snapshot(*roots: Path) -> dict[str, tuple[str, int, int]]:
    """Every path under ``roots`` with its kind, size and modification time (links are not
    followed, a FIFO is not opened)."""
    seen: dict[str, tuple[str, int, int]] = {}
    for root in roots:
        if not root.exists() and not root.is_symlink():
            continue
        st = os.lstat(root)
        seen[str(root)] = ("root", st.st_size, st.st_mtime_ns)
        for folder, dirs, files in os.walk(root, followlinks=False):
            for name in [*dirs, *files]:
                st = os.lstat(os.path.join(folder, name))
                kind = "dir" if name in dirs else "file"
                seen[os.path.join(folder, name)] = (kind, st.st_size, st.st_mtime_ns)
    return seen


def refused(
    args: list[str],
    watch: list[Path],
    words: tuple[str, ...] = (),
    *,
    usage: bool = False,
    scene: Path | None = None,
    max_lines: int = 1,
) -> str:
    """Run ``args``; assert exit 2, one line on stderr (``usage``: argparse's usage lines and
    its one error line; ``scene``: a scene file's refusal, one line per problem (at most
    ``max_lines``), each starting with the file), no traceback, nothing in ``watch`` (nor seahaze's
    state folder) created, changed or deleted, and each of ``words`` in the message. Returns
    stderr."""
    watched = [*watch, Path(os.environ[STATE_ENV])]
    before = snapshot(*watched)
    code, out, err = run(args)
    assert code == 2, (code, out, err)
    assert "Traceback" not in err and "Traceback" not in out, err
    lines = [line for line in err.splitlines() if line.strip()]
    if usage:
        assert lines and lines[0].startswith("usage:") and ": error: " in lines[-1], err
    elif scene is not None:
        assert 1 <= len(lines) <= max_lines, err
        assert all(line.removeprefix("seahaze: error: ").startswith(f"{scene}:") for line in lines)
    else:
        assert len(lines) == 1, err
        assert len(lines[0]) < 600, err
    for word in words:
        assert word in err, (word, err)
    assert snapshot(*watched) == before, "a refused case changed the folders"
    return err


@pytest.fixture
def no_render(monkeypatch):
    """A case that reaches the renderer fails at once (a render cannot be interrupted)."""

    def render_scene(*_args, **_kwargs):
        raise AssertionError("a render started")

    monkeypatch.setattr("seahaze.batch.executors.render_scene", render_scene)


def render_refused(
    tmp_path: Path,
    flags: list[str],
    words: tuple[str, ...] = (),
    scene: Path = TINY,
    max_lines: int = 1,
) -> str:
    """``seahaze render SCENE --out tmp/out FLAGS`` is refused and makes no ``out``."""
    out = tmp_path / "out"
    args = ["render", str(scene), "--out", str(out), "--quiet", *flags]
    located = None if scene == TINY else scene
    err = refused(args, [tmp_path], words, scene=located, max_lines=max_lines)
    assert not out.exists()
    return err


def scene_file(tmp_path: Path, extra: str, name: str = "s.yaml") -> Path:
    """The tiny scene with ``extra`` YAML appended, as a file in ``tmp_path``."""
    path = tmp_path / name
    path.write_text(TINY.read_text() + extra)
    return path


# --------------------------------------------------------------------------------------------
# Sequences: flags

FRAMES_FLAGS = [
    (["--frames", "0"], "--frames 0: must be within 1..10,000"),
    (["--frames=-1"], "--frames -1: must be within 1..10,000"),
    (["--frames", "10001"], "must be within 1..10,000"),
    (["--frames", "99999999999999999999"], "must be within 1..10,000"),
    (["--frames", "3", "--fps", "0"], "--fps 0: must be within 0 (excluded)..120"),
    (["--frames", "3", "--fps=-5"], "--fps -5: must be within"),
    (["--frames", "3", "--fps", "nan"], "--fps nan: must be within"),
    (["--frames", "3", "--fps", "inf"], "--fps inf: must be within"),
    (["--frames", "3", "--fps=-inf"], "--fps -inf: must be within"),
    (["--frames", "3", "--fps", "1e308"], "must be within 0 (excluded)..120"),
    (["--frames", "3", "--fps", "121"], "must be within 0 (excluded)..120"),
    (["--frames", "5", "--fps", "1e-300"], "past the sea's limit"),
    # Issue 35, case 3: --fps on a still scene made it a 100-frame sequence.
    (["--fps", "5"], "--fps 5 needs a sequence: pass --frames N too"),
    (["--fps", "0.5"], "--fps 0.5 needs a sequence"),
]


@pytest.mark.parametrize(
    ("flags", "words"), FRAMES_FLAGS, ids=[" ".join(f) for f, _ in FRAMES_FLAGS]
)
def test_bad_frames_and_fps_are_refused(flags, words, tmp_path, no_render):
    render_refused(tmp_path, flags, (words,))


ARGPARSE_FLAGS = [["--frames", "2.5"], ["--frames", "many"], ["--fps", "fast"]]


@pytest.mark.parametrize("flags", ARGPARSE_FLAGS, ids=[" ".join(f) for f in ARGPARSE_FLAGS])
def test_flags_that_are_not_numbers_get_argparse_usage(flags, tmp_path, no_render):
    out = tmp_path / "out"
    refused(["render", str(TINY), "--out", str(out), *flags], [tmp_path], usage=True)
    assert not out.exists()


def test_fps_alone_needs_a_sequence_and_frames_make_one():
    still = parse_scene_text(TINY.read_text(), "tiny.yaml")
    with pytest.raises(OverrideError, match=r"^--fps 5 needs a sequence: .*--frames N"):
        with_overrides(still, fps=5.0)
    made = with_overrides(still, frames=4, fps=5.0)
    assert (made.sequence.frames, made.sequence.fps) == (4, 5.0)
    sequence = parse_scene_text(TINY.read_text() + "sequence: {frames: 3}\n", "seq.yaml")
    assert with_overrides(sequence, fps=2.0).sequence.fps == 2.0
    assert with_overrides(still, frames=2).sequence.fps == 10.0


# --------------------------------------------------------------------------------------------
# Sequences: the scene file's `sequence:`

SEQUENCE_BLOCKS = [
    # Issue 35, case 4: an empty block rendered 100 frames.
    ("sequence: {}", ("sequence: frames is missing", "allowed fields: frames, fps")),
    ("sequence:", ("sequence: an empty sequence block", "allowed fields: frames")),
    ("sequence: {fps: 5}", ("sequence: frames is missing", "frames 1..10000")),
    ("sequence: {platform: ship}", ("frames is missing",)),
    ("sequence: {frames: 0}", ("sequence.frames", ">= 1")),
    ("sequence: {frames: 10001}", ("sequence.frames", "<= 10000")),
    ("sequence: {frames: 2.5}", ("sequence.frames", "integer")),
    ("sequence: {frames: many}", ("sequence.frames", "integer")),
    ("sequence: {frames: true}", ("sequence.frames", "not true/false")),
    ("sequence: {frames: -1}", ("sequence.frames", ">= 1")),
    ("sequence: {frames: 3, fps: 0}", ("sequence.fps", "> 0")),
    ("sequence: {frames: 3, fps: .nan}", ("sequence.fps",)),
    ("sequence: {frames: 3, fps: .inf}", ("sequence.fps",)),
    ("sequence: {frames: 3, fps: 500}", ("sequence.fps", "<= 120")),
    ("sequence: {frames: 3, platform: boat}", ("sequence.platform", "'shore'")),
    ("sequence: {frames: 3, bogus: 1}", ("sequence.bogus", "allowed keys: frames")),
    ("sequence: {frames: 3, own_speed_kn: 5}", ("sequence:", "platform ship")),
    ("sequence: {frames: 3, platform: ship, own_length_m: 1}", ("sequence.own_length_m", ">= 5")),
    ("sequence: {frames: 3, encounters: 2}", ("encounters 2 needs an encounter kind",)),
    (
        "sequence: {frames: 3, encounter: crossing, encounters: 0}",
        ("sequence.encounters", ">= 1"),
    ),
    (
        "sequence: {frames: 3, encounter: crossing, encounters: 9}",
        ("sequence.encounters", "<= 8"),
    ),
    (
        "sequence: {frames: 3, encounter: crossing, encounters: 1.5}",
        ("sequence.encounters", "integer"),
    ),
    ("sequence: {frames: 3, encounter: sideways}", ("sequence.encounter", "'head_on'")),
    ("sequence: {frames: 3, camera_mount: rigid}", ("camera_mount rigid", "platform ship")),
    ("sequence: {frames: 3, platform: ship, camera_mount: gimbal}", ("sequence.camera_mount",)),
    ("sequence: {frames: 3, platform: ship, camera_mount: 1}", ("sequence.camera_mount",)),
    ("sequence: [1, 2]", ("sequence",)),
    ("sequence: 5", ("sequence",)),
    ("camera: {height_m: 80}\nsequence: {frames: 3}", ("allowed: 5..60 m",)),
]


@pytest.mark.parametrize(
    ("block", "words"), SEQUENCE_BLOCKS, ids=[b.replace("\n", " ") for b, _ in SEQUENCE_BLOCKS]
)
def test_bad_sequence_blocks_are_refused_before_rendering(block, words, tmp_path, no_render):
    # TINY has its own camera: line; a second one would be a duplicate key, so swap it.
    text = TINY.read_text()
    if block.startswith("camera:"):
        text = re.sub(r"(?m)^camera: .*\n", "", text)
    scene = tmp_path / "s.yaml"
    scene.write_text(text + block + "\n")
    # A value both non-finite and out of range may be reported twice for its one field, as
    # the scene-file reader lists every problem (docs/limits.md): one line each.
    most = 2 if ".nan" in block or ".inf" in block else 1
    render_refused(tmp_path, [], (str(scene), *words), scene=scene, max_lines=most)


def test_a_sequence_with_frames_still_loads():
    for block in ("sequence: {frames: 1}", "sequence: {frames: 3, platform: ship}"):
        spec = parse_scene_text(TINY.read_text() + block + "\n", "ok.yaml")
        assert spec.sequence is not None and spec.sequence.frames in (1, 3)


# --------------------------------------------------------------------------------------------
# --split and --workers

SPLITS = [
    "0.5,0.5",
    "a,b,c",
    "0.8,0.1,0.2",
    "-0.1,0.6,0.5",
    "nan,0.5,0.5",
    "inf,0,0",
    "1e400,0,0",
    "0,0.5,0.5",
    "",
    "0.8,0.1,0.1,0",
    "0.8,,0.2",
]


@pytest.mark.parametrize("split", SPLITS)
def test_bad_split_fractions_are_refused(split, tmp_path, no_render):
    render_refused(tmp_path, [f"--split={split}"], ("--split",))


WORKERS = ["0", "-1", "100000", "99999999999999999999"]


@pytest.mark.parametrize("workers", WORKERS)
def test_bad_worker_counts_are_refused(workers, tmp_path, no_render):
    render_refused(
        tmp_path, [f"--workers={workers}"], (f"--workers {workers}: must be within 1..",)
    )


# --------------------------------------------------------------------------------------------
# User meshes

NAN_PLY = """ply
format ascii 1.0
element vertex 4
property float x
property float y
property float z
element face 2
property list uchar int vertex_indices
end_header
0 0 0
1 0 0
nan 1 0
0 0 1
3 0 1 2
3 0 1 3
"""
MESHES = [
    pytest.param("empty.obj", "", "contains no triangles", id="empty.obj"),
    pytest.param(
        "nan_vertex.obj",
        "v nan 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\n",
        "mesh",
        id="nan_vertex.obj",
    ),
    pytest.param(
        "inf_vertex.obj",
        "v inf 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\n",
        "mesh",
        id="inf_vertex.obj",
    ),
    pytest.param(
        "one_point.obj", "v 1 1 1\nv 1 1 1\nv 1 1 1\nf 1 2 3\n", "zero extent", id="one_point"
    ),
    pytest.param(  # (an OBJ reader drops an unused vertex whole: nothing to refuse there)
        "nan_unused.ply",
        NAN_PLY.replace("element vertex 4", "element vertex 5")
        .replace("nan 1 0", "0 1 0")
        .replace("0 0 1\n3", "0 0 1\nnan nan nan\n3"),
        "mesh",
        id="nan_unused.ply",
    ),
    pytest.param("nan_vertex.ply", NAN_PLY, "mesh", id="nan_vertex.ply"),
]
AXES = [("+z", "+z"), ("+x", "-x")]


@pytest.mark.parametrize(("name", "text", "words"), MESHES)
def test_bad_user_mesh_files_are_refused(name, text, words, tmp_path, no_render):
    (tmp_path / name).write_text(text)
    scene = scene_file(
        tmp_path,
        f"vessels:\n  placed:\n    - {{class: tug, distance_m: 500, "
        f"mesh: {{path: {name}, scale_m: 30}}}}\n",
    )
    render_refused(tmp_path, [], (str(scene), "vessels.placed[0].mesh.path", words), scene=scene)


@pytest.mark.parametrize(("up", "forward"), AXES, ids=[f"{u} {f}" for u, f in AXES])
def test_a_mesh_whose_up_axis_is_its_forward_axis_is_refused(up, forward, tmp_path, no_render):
    (tmp_path / "boat.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\n")
    scene = scene_file(
        tmp_path,
        "vessels:\n  placed:\n    - {class: tug, distance_m: 500, mesh: {path: boat.obj, "
        f"scale_m: 30, up_axis: '{up}', forward_axis: '{forward}'}}}}\n",
    )
    render_refused(tmp_path, [], ("must be perpendicular", "vessels.placed[0].mesh"), scene=scene)


# --------------------------------------------------------------------------------------------
# A finished dataset, written by hand (no render): two levels, four scenes in three splits

LEVELS_M = [500.0, 2000.0]
SCENES = {"tiny_00000": "train", "tiny_00001": "train", "tiny_00002": "val", "tiny_00003": "test"}
CLASSES = ("container_ship", "tug")


def scene_meta(levels: list[dict]) -> dict:
    """The parts of ``meta/<scene>.json`` an ``hf`` export reads: one tug boxed in the middle of
    the 8×4 image (the label files' ``1 0.5 0.5 0.25 0.5``)."""
    names = ["clean", *(lv["name"] for lv in levels)]
    look = {"apparent_contrast": -0.1, "beyond_visibility": False}
    look |= {"local_contrast": 0.2, "discernible": True}
    vessel = {"index": 0, "class": "tug", "class_id": 1, "distance_m": 300.0}
    vessel |= {"box_px": [3.0, 1.0, 5.0, 3.0], "visible_fraction": 1.0}
    return {
        "camera": {"resolution": [8, 4]},
        "levels": [
            {"name": lv["name"], "sigma_rgb_per_m": [lv["sigma_per_m"]] * 3} for lv in levels
        ],
        "vessels": [{**vessel, "levels": {name: look for name in names}}],
    }


def write_dataset(root: Path) -> Path:
    """A finished seahaze dataset as ``seahaze render --split`` leaves it, 8×4 px images."""
    levels = level_entries(LEVELS_M, "koschmieder")
    names = ["clean", *(lv["name"] for lv in levels)]
    for level in names:
        (root / "images" / level).mkdir(parents=True)
        (root / "labels" / level).mkdir(parents=True)
        for scene in SCENES:
            Image.new("RGB", (8, 4), (40, 60, 90)).save(root / "images" / level / f"{scene}.png")
            (root / "labels" / level / f"{scene}.txt").write_text("1 0.5 0.5 0.25 0.5\n")
    (root / "meta").mkdir()
    (root / "depth").mkdir()
    depth = np.full((4, 8), np.inf, np.float32)
    depth[2:] = 300.0
    for scene in SCENES:
        (root / "meta" / f"{scene}.json").write_text(json.dumps(scene_meta(levels)))
        write_exr(root / "depth" / f"{scene}.exr", {"Z": depth})
    scenes = {
        name: {"status": "done", "seed": i, "template": "tiny", "index": i, "split": split}
        for i, (name, split) in enumerate(SCENES.items())
    }
    config = {"threshold": "koschmieder", "split": {"train": 0.5, "val": 0.25, "test": 0.25}}
    data = manifest(config, levels, CLASSES, scenes)
    (root / "dataset.json").write_text(json.dumps(data, indent=1))
    (root / "data.yaml").write_text(data_yaml_text(root, names[1:], CLASSES))
    return root


@pytest.fixture(scope="module")
def fake_dataset(tmp_path_factory) -> Path:
    """The hand-written dataset (read-only: :func:`dataset_copy` it to damage it)."""
    return write_dataset(tmp_path_factory.mktemp("fake") / "ds")


def dataset_copy(source: Path, target: Path) -> Path:
    shutil.copytree(source, target)
    return target


def test_the_hand_written_dataset_exports_in_every_layout(fake_dataset, tmp_path):
    """The control: the cases below fail for what they change, not for the fixture."""
    for layout in LAYOUTS:
        out_dir = tmp_path / layout
        code, out, err = run(
            ["export", str(fake_dataset), "--layout", layout, "--out", str(out_dir)]
        )
        if layout == "hf" and not HAS_PYARROW:
            assert code == 2 and "seahaze[hf]" in err, err
            continue
        assert code == 0 and "exported" in out, err


# --------------------------------------------------------------------------------------------
# export: flags and --out

LAYOUTS = list(EXPORT_LAYOUTS)


@pytest.mark.parametrize("layout", LAYOUTS)
def test_a_half_finished_dataset_is_refused_in_every_layout(layout, fake_dataset, tmp_path):
    ds = dataset_copy(fake_dataset, tmp_path / "ds")
    data = json.loads((ds / "dataset.json").read_text())
    data["scenes"]["tiny_00002"]["status"] = "pending"
    (ds / "dataset.json").write_text(json.dumps(data))
    out = tmp_path / "out"
    refused(
        ["export", str(ds), "--layout", layout, "--out", str(out)],
        [tmp_path],
        ("not a finished dataset", "tiny_00002: pending"),
    )
    assert not out.exists()


def export_refused(
    dataset: Path, out: Path, watch: list[Path], words: tuple[str, ...], *flags: str
) -> str:
    layout = [] if "--layout" in flags else ["--layout", "paired"]
    return refused(["export", str(dataset), *layout, "--out", str(out), *flags], watch, words)


def test_out_inside_or_above_the_dataset_is_refused(fake_dataset, tmp_path):
    ds = dataset_copy(fake_dataset, tmp_path / "train")  # named like a split folder
    watch = [tmp_path]
    export_refused(ds, ds, watch, ("inside the dataset",))
    export_refused(ds, ds / "export", watch, ("inside the dataset",))
    # --out its parent: the paired layout's train/hazy/ would be the dataset's own folder.
    export_refused(ds, tmp_path, watch, ("its train/ would be inside the dataset",))
    # A folder of --out that is a link into the dataset.
    out = tmp_path / "out"
    out.mkdir()
    (out / "train").symlink_to(ds / "images")
    export_refused(ds, out, watch, ("would be inside the dataset",))


def test_out_that_is_a_file_or_lies_under_one_is_refused(fake_dataset, tmp_path):
    a_file = tmp_path / "notes.txt"
    a_file.write_text("mine\n")
    export_refused(fake_dataset, a_file, [tmp_path, fake_dataset], ("is a file, not a folder",))
    export_refused(fake_dataset, a_file / "sub", [tmp_path, fake_dataset], ("lies under the file",))


def test_a_foreign_folder_is_never_overwritten(fake_dataset, tmp_path):
    foreign = tmp_path / "foreign"
    (foreign / "train").mkdir(parents=True)
    (foreign / "train" / "pairs.csv").write_text("my own pairs\n")
    (foreign / "photo.png").write_bytes(b"not seahaze's")
    export_refused(fake_dataset, foreign, [tmp_path], ("pairs.csv", "was not written by seahaze"))
    record = foreign / ".seahaze-owned.json"
    record.write_text("[[[[" * 10 + "garbage")
    export_refused(fake_dataset, foreign, [tmp_path], ("cannot read seahaze's list",))
    assert (foreign / "train" / "pairs.csv").read_text() == "my own pairs\n"


EXPORT_FLAGS = [
    (["--levels", "v0300"], ("--levels v0300: not a hazy level", "v0500, v2000")),
    (["--levels", "clean"], ("--levels clean: not a hazy level",)),
    (["--levels", "abc"], ("--levels 'abc'",)),
    (["--levels", ","], ("no level named",)),
    (["--levels", "0"], ("--levels '0'",)),
    (["--levels=-500"], ("--levels '-500'",)),
    (["--levels", "500.5"], ("--levels '500.5'",)),
]


@pytest.mark.parametrize(
    ("flags", "words"), EXPORT_FLAGS, ids=[" ".join(f) for f, _ in EXPORT_FLAGS]
)
def test_unknown_levels_are_refused(flags, words, fake_dataset, tmp_path):
    out = tmp_path / "out"
    export_refused(fake_dataset, out, [tmp_path, fake_dataset], words, *flags)
    assert not out.exists()


EXPORT_USAGE = [["--layout", "coco"], ["--link", "reflink"], []]


@pytest.mark.parametrize(
    "flags", EXPORT_USAGE, ids=[" ".join(f) or "no layout" for f in EXPORT_USAGE]
)
def test_unknown_layout_and_link_get_argparse_usage(flags, fake_dataset, tmp_path):
    out = tmp_path / "out"
    args = ["export", str(fake_dataset), "--out", str(out), *flags]
    if flags[:1] == ["--link"]:
        args += ["--layout", "paired"]
    refused(args, [tmp_path, fake_dataset], usage=True)
    assert not out.exists()


def test_a_missing_image_or_no_dataset_is_refused(fake_dataset, tmp_path):
    ds = dataset_copy(fake_dataset, tmp_path / "ds")
    (ds / "images" / "v2000" / "tiny_00001.png").unlink()
    out = tmp_path / "out"
    export_refused(ds, out, [tmp_path], ("tiny_00001.png: missing", "incomplete"))
    export_refused(tmp_path / "nowhere", out, [tmp_path], ("not a folder",))
    export_refused(ds / "dataset.json", out, [tmp_path], ("not a folder",))
    assert not out.exists()


# --------------------------------------------------------------------------------------------
# export: damaged dataset.json (issue 35, case 1)


def _deep(levels: int) -> str:
    return "[" * levels + "]" * levels


MANIFEST_DAMAGE = {
    # name: (change to the manifest dict, or replacement text; words)
    "deeply_nested": (_deep(100_000), ("nested deeper than 64",)),
    "nested_in_config": (
        lambda d: d["config"].update(deep=json.loads(_deep(200))),
        ("nested deeper than 64",),
    ),
    "scene_is_a_string": (
        lambda d: d["scenes"].update(tiny_00001="done"),
        ("scenes.tiny_00001 is a string", "allowed: a mapping"),
    ),
    "scene_is_a_list": (
        lambda d: d["scenes"].update(tiny_00001=[1]),
        ("scenes.tiny_00001 is a list",),
    ),
    "level_without_visibility": (
        lambda d: d["levels"][1].pop("visibility_m"),
        ("levels[1].visibility_m is missing", "allowed: a finite number > 0 m"),
    ),
    "level_without_sigma": (
        lambda d: d["levels"][0].pop("sigma_per_m"),
        ("levels[0].sigma_per_m is missing",),
    ),
    "visibility_a_string": (
        lambda d: d["levels"][0].update(visibility_m="500"),
        ("levels[0].visibility_m is '500'",),
    ),
    "visibility_nan": (
        lambda d: d["levels"][0].update(visibility_m=float("nan")),
        ("levels[0].visibility_m is nan",),
    ),
    "visibility_huge_int": (
        lambda d: d["levels"][0].update(visibility_m=10**400),
        ("more than 40 digits",),
    ),
    "visibility_negative": (
        lambda d: d["levels"][0].update(visibility_m=-500),
        ("levels[0].visibility_m is -500",),
    ),
    "visibility_true": (
        lambda d: d["levels"][0].update(visibility_m=True),
        ("levels[0].visibility_m is true/false",),
    ),
    "level_is_a_number": (lambda d: d["levels"].__setitem__(0, 500), ("levels[0] is a number",)),
    "level_name_escapes": (
        lambda d: d["levels"][0].update(name="../../etc"),
        ("levels[0].name is '../../etc'", "v0300"),
    ),
    "level_name_5000_digits": (
        lambda d: d["levels"][0].update(name="v" + "1" * 5000),
        ("levels[0].name is 'v111",),
    ),
    "level_name_clean": (lambda d: d["levels"][0].update(name="clean"), ("levels[0].name",)),
    "level_twice": (
        lambda d: d["levels"].append(dict(d["levels"][0])),
        ("listed twice",),
    ),
    "levels_empty": (lambda d: d.update(levels=[]), ("levels is empty",)),
    "levels_a_mapping": (lambda d: d.update(levels={"v0500": 1}), ("levels is a mapping",)),
    "scenes_a_list": (lambda d: d.update(scenes=["tiny_00000"]), ("lists no scenes",)),
    "scenes_empty": (lambda d: d.update(scenes={}), ("lists no scenes",)),
    "scene_name_escapes": (
        lambda d: d["scenes"].update({"../../evil": d["scenes"]["tiny_00000"]}),
        ("scene name '../../evil' is not a file name",),
    ),
    "scene_name_newline": (
        lambda d: d["scenes"].update({"a\nb": d["scenes"]["tiny_00000"]}),
        ("is not a file name",),
    ),
    "scene_status_null": (
        lambda d: d["scenes"]["tiny_00000"].update(status=None),
        ("scenes.tiny_00000.status is missing",),
    ),
    "scene_split_a_list": (
        lambda d: d["scenes"]["tiny_00000"].update(split=["train"]),
        ("scenes.tiny_00000.split is a list", "train, val, test"),
    ),
    "scene_split_unknown": (
        lambda d: d["scenes"]["tiny_00000"].update(split="holdout"),
        ("split 'holdout'; allowed: train, val, test",),
    ),
    "classes_numbers": (lambda d: d.update(classes=[1, 2]), ("classes is not a list",)),
    "config_a_list": (lambda d: d.update(config=[1]), ("config is a list",)),
    "config_split_a_string": (
        lambda d: d["config"].update(split="0.8,0.1,0.1"),
        ("config.split is a string",),
    ),
    "format_version_true": (lambda d: d.update(format_version=True), ("format_version true",)),
    "format_version_2": (lambda d: d.update(format_version=2), ("format_version 2",)),
    "not_json": ("{not json", ("not valid JSON",)),
    "int_of_5000_digits": ('{"format": ' + "1" * 5000 + "}", ("not valid JSON",)),
    "null": ("null", ("not a seahaze dataset manifest",)),
    "a_string": ('"seahaze-dataset"', ("not a seahaze dataset manifest",)),
    "empty_file": ("", ("not valid JSON",)),
    "not_utf8": (b"\xff\xfe{}".decode("latin-1"), ("cannot read the manifest",)),
}


@pytest.mark.parametrize("name", sorted(MANIFEST_DAMAGE))
def test_a_damaged_manifest_is_one_line(name, fake_dataset, tmp_path):
    ds = dataset_copy(fake_dataset, tmp_path / "ds")
    change, words = MANIFEST_DAMAGE[name]
    path = ds / "dataset.json"
    if callable(change):
        data = json.loads(path.read_text())
        change(data)
        path.write_text(json.dumps(data))
    elif name == "not_utf8":
        path.write_bytes(change.encode("latin-1"))
    else:
        path.write_text(change)
    out = tmp_path / "out"
    for layout in ("paired", "yolo"):
        export_refused(ds, out, [tmp_path], (str(path), *words), "--layout", layout)
    assert not out.exists()


def test_a_manifest_that_is_not_a_file_is_refused(fake_dataset, tmp_path):
    ds = dataset_copy(fake_dataset, tmp_path / "ds")
    out = tmp_path / "out"
    (ds / "dataset.json").unlink()
    os.mkfifo(ds / "dataset.json")  # reading it would block until a writer comes
    export_refused(ds, out, [tmp_path], ("not a regular file",))
    (ds / "dataset.json").unlink()
    (ds / "dataset.json").mkdir()
    export_refused(ds, out, [tmp_path], ("not a regular file",))
    (ds / "dataset.json").rmdir()
    export_refused(ds, out, [tmp_path], ("dataset.json: missing",))
    assert not out.exists()


# --------------------------------------------------------------------------------------------
# metric newvis --table (issue 35, case 2)

GOOD_ROWS = [{"visibility_m": 300, "map50": 0.2}, {"visibility_m": 1000, "map50": 0.5}]


def _table(**changes: object) -> str:
    doc = {"format": "seahaze.metric.table/1", "detector": "yolo", "levels": GOOD_ROWS}
    doc.update(changes)
    return json.dumps(doc)


TABLES = {
    # name: (suffix, text, words)
    "deeply_nested": (".json", _deep(100_000), ("nested deeper than 32",)),
    "deeply_nested_object": (".json", '{"a":' * 50_000 + "1" + "}" * 50_000, ("nested",)),
    "nested_extra": (".json", _table(extra=json.loads(_deep(40))), ("nested deeper than 32",)),
    "levels_a_string": (".json", _table(levels="300,1000"), ("'levels' list",)),
    "level_a_string": (".json", _table(levels=["300", "1000"]), ("levels[0] must be an object",)),
    "visibility_text": (
        ".json",
        _table(levels=[{"visibility_m": "abc", "map50": 0.1}, GOOD_ROWS[1]]),
        ("levels[0].visibility_m must be a number, got 'abc'",),
    ),
    "visibility_a_list": (
        ".json",
        _table(levels=[{"visibility_m": [300], "map50": 0.1}, GOOD_ROWS[1]]),
        ("levels[0].visibility_m must be a number, got a list",),
    ),
    "visibility_1e400": (
        ".json",
        _table(levels=[{"visibility_m": 1e400, "map50": 0.1}, GOOD_ROWS[1]]),
        ("must be a finite number",),
    ),
    "visibility_400_digits": (
        ".json",
        '{"levels": [{"visibility_m": ' + "9" * 400 + ', "map50": 0.1}, {"visibility_m": 1000, '
        '"map50": 0.5}]}',
        ("must be a finite number", "more than 40 digits"),
    ),
    "visibility_5000_digits": (
        ".json",
        '{"levels": [{"visibility_m": ' + "9" * 5000 + ', "map50": 0.1}]}',
        ("not a usable JSON table",),
    ),
    "map50_nan": (
        ".json",
        '{"levels": [{"visibility_m": 300, "map50": NaN}, {"visibility_m": 1000, "map50": 0.5}]}',
        ("levels[0].map50 must be a finite number",),
    ),
    "map50_two": (
        ".json",
        _table(levels=[{"visibility_m": 300, "map50": 2}, GOOD_ROWS[1]]),
        ("mAP50 must be a number in [0, 1]",),
    ),
    "map50_95_huge": (
        ".json",
        '{"levels": [{"visibility_m": 300, "map50": 0.1, "map50_95": ' + "9" * 400 + "}, "
        '{"visibility_m": 1000, "map50": 0.5}]}',
        None,  # accepted: an unusable optional score is dropped, not a traceback
    ),
    "detector_a_list": (".json", _table(detector=[[1]]), ("detector must be a name",)),
    "one_level": (".json", _table(levels=GOOD_ROWS[:1]), ("at least 2 levels",)),
    "same_level_twice": (".json", _table(levels=[GOOD_ROWS[0]] * 2), ("appears twice",)),
    "null": (".json", "null", ("expected a JSON object",)),
    "a_list": (".json", "[]", ("expected a JSON object",)),
    "not_json": (".json", "{levels", ("not valid JSON",)),
    "empty_json": (".json", "", ("not valid JSON",)),
    "csv_nul": (".csv", "visibility_m,map50\n300,0.1\x00\n1000,0.5\n", ("t.csv:2: map50",)),
    "csv_huge_field": (".csv", "visibility_m,map50\n" + "9" * 200_000 + ",0.1\n", ("CSV",)),
    "csv_header": (".csv", "vis,map\n300,0.1\n1000,0.5\n", ("header must name the columns",)),
    "csv_empty": (".csv", "", ("empty table",)),
    "csv_inf": (".csv", "visibility_m,map50\ninf,0.1\n1000,0.5\n", ("finite number",)),
    "too_large": (".json", " " * (2 << 20) + "{}", ("larger than 1 MiB",)),
    "not_utf8": (".csv", "visibility_m,map50\n300,0.1\n\udcff\n", ("not UTF-8", ":3:")),
}


@pytest.mark.parametrize("name", sorted(TABLES))
def test_a_malformed_table_is_one_line(name, tmp_path):
    suffix, text, words = TABLES[name]
    path = tmp_path / f"t{suffix}"
    path.write_bytes(text.encode("utf-8", "surrogateescape"))
    args = ["metric", "newvis", "--table", str(path), "--map", "0.3"]
    if words is None:
        code, out, err = run(args)
        assert code == 0 and "new visibility" in out and "Traceback" not in err, err
        return
    refused(args, [tmp_path], (f"seahaze metric newvis: error: {path}", *words))


def test_a_table_that_is_not_a_file_is_one_line(tmp_path):
    fifo = tmp_path / "t.json"
    os.mkfifo(fifo)
    for path, words in (
        (fifo, "not a regular file"),
        (tmp_path, "not a regular file"),
        (tmp_path / "missing.csv", "calibration table not found"),
    ):
        refused(["metric", "newvis", "--table", str(path), "--map", "0.3"], [tmp_path], (words,))


# --------------------------------------------------------------------------------------------
# metric: the dataset's data.yaml and, with --split, its dataset.json

METRIC_DATASET = {
    # name: (file, text, words)
    "data_yaml_deep": ("data.yaml", "names: " + "[" * 5000 + "]" * 5000, ("nested deeper",)),
    "data_yaml_alias_bomb": (
        "data.yaml",
        "a: &a [x, x, x, x, x, x, x, x, x, x]\n"
        + "".join(
            f"{c}: &{c} [*{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}]\n"
            for p, c in zip("abcdefg", "bcdefgh", strict=True)
        )
        + "names: [*h]\n",
        ("more than 20,000 YAML nodes",),
    ),
    "data_yaml_nested_names": ("data.yaml", "names: [[a, b], c]\n", ("names must be class names",)),
    "data_yaml_binary": ("data.yaml", "names: [a]\n\udcff\n", ("not UTF-8",)),
    "manifest_deep_with_split": ("dataset.json", _deep(100_000), ("nested deeper than 64",)),
    "manifest_scene_a_string_with_split": (
        "dataset.json",
        None,  # the hand-written manifest with one scene entry a string
        ("scenes.tiny_00001 is a string",),
    ),
}


@pytest.mark.parametrize("name", sorted(METRIC_DATASET))
def test_a_damaged_dataset_is_one_line_for_the_metric(name, fake_dataset, tmp_path):
    ds = dataset_copy(fake_dataset, tmp_path / "ds")
    file, text, words = METRIC_DATASET[name]
    if text is None:
        data = json.loads((ds / file).read_text())
        data["scenes"]["tiny_00001"] = "done"
        text = json.dumps(data)
    (ds / file).write_bytes(text.encode("utf-8", "surrogateescape"))
    (tmp_path / "pred").mkdir()
    refused(
        [
            *("metric", "eval", "--dataset", str(ds), "--pred", str(tmp_path / "pred")),
            *("--split", "test"),
        ],
        [tmp_path],
        (f"seahaze metric eval: error: {ds / file}", *words),
    )


# --------------------------------------------------------------------------------------------
# metric --model


def calibrate_with(dataset: Path, weights: Path, tmp_path: Path) -> list[str]:
    """``seahaze metric calibrate`` of ``dataset`` with ``--model weights``, writing into
    ``tmp_path`` (``pred/`` and ``table.*``) if it ever got that far."""
    pred, table = tmp_path / "pred", tmp_path / "table"
    return [
        *("metric", "calibrate", "--dataset", str(dataset), "--pred", str(pred)),
        *("--model", str(weights), "--out", str(table)),
    ]


def test_missing_weights_are_refused_before_any_prediction(fake_dataset, tmp_path):
    for weights in (tmp_path / "missing.pt", tmp_path):
        refused(
            calibrate_with(fake_dataset, weights, tmp_path),
            [tmp_path, fake_dataset],
            (f"{weights}: weights file not found", "nothing is downloaded"),
        )
    # newvis with restored images of level v0500 and a table: it gets as far as the weights.
    images = tmp_path / "restored"
    shutil.copytree(fake_dataset / "images" / "v0500", images)
    table = tmp_path / "t.json"
    table.write_text(_table())
    refused(
        [
            *("metric", "newvis", "--table", str(table), "--pred", str(tmp_path / "pred")),
            *("--dataset", str(fake_dataset), "--level", "500"),
            *("--model", str(tmp_path / "missing.pt"), "--images", str(images)),
        ],
        [tmp_path, fake_dataset],
        ("missing.pt: weights file not found",),
    )
    assert not (tmp_path / "pred").exists() and not (tmp_path / "table.csv").exists()


@pytest.mark.skipif(not HAS_ULTRALYTICS, reason="ultralytics is not installed")
@pytest.mark.parametrize("content", [b"", b"\x80\x04garbage not a checkpoint" * 10])
def test_garbage_weights_are_one_line(content, fake_dataset, tmp_path):
    weights = tmp_path / "w.pt"
    weights.write_bytes(content)
    refused(
        calibrate_with(fake_dataset, weights, tmp_path),
        [tmp_path, fake_dataset],
        (str(weights), "cannot load the model"),
    )


@pytest.mark.skipif(HAS_ULTRALYTICS, reason="ultralytics is installed")
def test_weights_without_ultralytics_name_the_install(fake_dataset, tmp_path):
    weights = tmp_path / "w.pt"
    weights.write_bytes(b"\x80\x04garbage")
    refused(
        calibrate_with(fake_dataset, weights, tmp_path),
        [tmp_path, fake_dataset],
        ("--model needs Ultralytics", "seahaze[detect]"),
    )


# --------------------------------------------------------------------------------------------
# export --layout hf: the files a row reads


def _meta_change(change):
    """A damage of ``tiny_00001``'s meta: ``change`` applied to its parsed JSON."""

    def damage(ds: Path) -> Path:
        path = ds / "meta" / "tiny_00001.json"
        data = json.loads(path.read_text())
        change(data)
        path.write_text(json.dumps(data))
        return path

    return damage


def _replace(rel: str, make):
    """A damage that replaces the dataset file ``rel`` by what ``make(path)`` leaves there."""

    def damage(ds: Path) -> Path:
        path = ds / rel
        path.unlink()
        make(path)
        return path

    return damage


def _truncate(rel: str):
    def damage(ds: Path) -> Path:
        path = ds / rel
        path.write_bytes(path.read_bytes()[:-40])
        return path

    return damage


VESSEL = ("vessels", 0)
HF_DAMAGE = {
    "meta_deep": (
        _replace("meta/tiny_00001.json", lambda p: p.write_text(_deep(100_000))),
        ("nested deeper than 32",),
    ),
    "meta_a_list": (
        _replace("meta/tiny_00001.json", lambda p: p.write_text("[]")),
        ("the file is a list; allowed: a mapping",),
    ),
    "meta_missing": (_replace("meta/tiny_00001.json", lambda p: None), ("missing",)),
    "meta_a_folder": (
        _replace("meta/tiny_00001.json", lambda p: p.mkdir()),
        ("not a regular file",),
    ),
    "box_reversed": (
        _meta_change(lambda d: d["vessels"][0].update(box_px=[5, 1, 3, 3])),
        ("vessels[0].box_px", "x1 > x0"),
    ),
    "box_strings": (
        _meta_change(lambda d: d["vessels"][0].update(box_px=["3", 1, 5, 3])),
        ("vessels[0].box_px[0] is '3'", "a finite number"),
    ),
    "class_not_a_class": (
        _meta_change(lambda d: d["vessels"][0].update(class_id=2)),
        ("vessels[0].class_id is 2", "0 to 1"),
    ),
    "class_true": (
        _meta_change(lambda d: d["vessels"][0].update(class_id=True)),
        ("vessels[0].class_id is true/false",),
    ),
    "level_missing": (
        _meta_change(lambda d: d["levels"].pop()),
        ("levels has no entry v2000",),
    ),
    "label_disagrees": (
        _replace("labels/v0500/tiny_00001.txt", lambda p: p.write_text("")),
        ("has 0 boxes where the scene's meta labels 1 vessels",),
    ),
    "depth_missing": (_replace("depth/tiny_00001.exr", lambda p: None), ("missing",)),
    "depth_truncated": (_truncate("depth/tiny_00001.exr"), ("truncated",)),
    "image_size": (
        _replace("images/clean/tiny_00001.png", lambda p: Image.new("RGB", (4, 4)).save(p)),
        ("is 4x4, not 8x4",),
    ),
}


@pytest.mark.skipif(not HAS_PYARROW, reason="pyarrow is not installed: pip install 'seahaze[hf]'")
@pytest.mark.parametrize("name", sorted(HF_DAMAGE))
def test_a_damaged_scene_file_refuses_the_hf_export(name, fake_dataset, tmp_path):
    ds = dataset_copy(fake_dataset, tmp_path / "ds")
    damage, words = HF_DAMAGE[name]
    path = damage(ds)
    out = tmp_path / "out"
    export_refused(ds, out, [tmp_path], (str(path), *words), "--layout", "hf")
    assert not out.exists()


HF_FLAGS = [
    (["--layout", "hf", "--license", "CC BY"], ("--license 'CC BY'", "cc-by-4.0")),
    (["--layout", "hf", "--license", "../../x"], ("--license '../../x'",)),
    (["--layout", "yolo", "--license", "mit"], ("only --layout hf writes a licence",)),
]


@pytest.mark.parametrize(("flags", "words"), HF_FLAGS, ids=[" ".join(f) for f, _ in HF_FLAGS])
def test_bad_licences_are_refused(flags, words, fake_dataset, tmp_path):
    export_refused(fake_dataset, tmp_path / "out", [tmp_path, fake_dataset], words, *flags)


def test_hf_without_pyarrow_names_the_extra(fake_dataset, tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "pyarrow", None)  # what `import pyarrow` meets without it
    monkeypatch.setitem(sys.modules, "pyarrow.parquet", None)
    watch = [tmp_path, fake_dataset]
    export_refused(fake_dataset, tmp_path / "out", watch, ("seahaze[hf]",), "--layout", "hf")


# --------------------------------------------------------------------------------------------
# The counts in the module docstring


def test_the_corpus_counts_match_this_docstring():
    counts = {
        "sequences": len(FRAMES_FLAGS) + len(ARGPARSE_FLAGS) + len(SEQUENCE_BLOCKS),
        "split": len(SPLITS),
        "workers": len(WORKERS),
        "meshes": len(MESHES) + len(AXES),
        "export hf": len(HF_DAMAGE) + len(HF_FLAGS) + 1,
        "export": len(LAYOUTS)
        + len(EXPORT_FLAGS)
        + len(EXPORT_USAGE)
        + len(MANIFEST_DAMAGE)
        + 4  # --out inside or above the dataset, or through a link into it
        + 2  # --out a file, or under one
        + 2  # a foreign folder, a planted record
        + 3  # a missing image, no dataset, a file as dataset
        + 3,  # dataset.json a FIFO, a folder, missing
        "table": sum(words is not None for _, _, words in TABLES.values()) + 3,  # + not files
        "metric dataset": len(METRIC_DATASET),
        "model": 3 + 2 + 1,  # missing weights (3 commands), garbage (2), no Ultralytics (1)
    }
    for surface, count in counts.items():
        assert f"- {surface}: {count} — " in __doc__, (surface, count)
