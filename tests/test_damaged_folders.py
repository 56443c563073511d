"""A finished dataset folder damaged in 30 ways, then the same command rerun (issue #19).

Every damage is either repaired (the scene is rendered again and its files come back byte for
byte) or refused with exit code 2 and a message saying what to do — never a traceback, never
"nothing to render" over a broken file, never a deleted file seahaze did not write.
"""

from __future__ import annotations

import contextlib
import io
import json
import shutil
from collections.abc import Callable
from pathlib import Path

import pytest

from seahaze.cli import main

SCENE = """\
name: dmg
camera: {height_m: 12, pitch_deg: -2, resolution: [32, 18]}
sea: {quality: low, seed: 4}
vessels:
  placed:
    - {class: tug, distance_m: 120, bearing_deg: 5, length_m: 30}
haze: {levels: [1000]}
render: {spp: 1, seed: 2}
"""
FILES = [
    "images/clean/dmg.png",
    "images/v1000/dmg.png",
    "labels/clean/dmg.txt",
    "labels/v1000/dmg.txt",
    "exr/clean/dmg.exr",
    "exr/v1000/dmg.exr",
    "depth/dmg.exr",
    "meta/dmg.json",
    "coco/v1000.json",
    "data.yaml",
]


def _run(args: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(args)
    return code, out.getvalue(), err.getvalue()


@pytest.fixture(scope="module")
def scene(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("scene") / "dmg.yaml"
    path.write_text(SCENE)
    return path


@pytest.fixture(scope="module")
def finished(scene, tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("finished") / "ds"
    code, _, err = _run(["render", str(scene), "--out", str(out), "--quiet"])
    assert code == 0, err
    return out


def _copy(finished: Path, tmp_path: Path) -> Path:
    out = tmp_path / "ds"
    shutil.copytree(finished, out)
    return out


def _rerun(scene: Path, out: Path, *extra: str) -> tuple[int, str, str]:
    return _run(["render", str(scene), "--out", str(out), "--quiet", *extra])


def _truncate(path: Path) -> None:
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])


def _manifest_edit(edit: Callable[[dict], object]) -> Callable[[Path], None]:
    def apply(out: Path) -> None:
        path = out / "dataset.json"
        data = json.loads(path.read_text())
        result = edit(data)
        path.write_text(json.dumps(data if result is None else result))

    return apply


def _png_of_other_size(path: Path) -> None:
    from PIL import Image

    Image.new("RGB", (7, 5)).save(path)


def _jpeg_bytes(path: Path) -> None:
    from PIL import Image

    Image.new("RGB", (32, 18)).save(path, format="JPEG")


def _rgb_exr_as_depth(out: Path) -> None:
    shutil.copyfile(out / "exr/clean/dmg.exr", out / "depth/dmg.exr")


# Damage → the file that must come back identical after the rerun re-renders the scene.
REPAIRED: dict[str, tuple[Callable[[Path], None], str]] = {
    "zero-byte PNG": (lambda o: (o / FILES[0]).write_bytes(b""), FILES[0]),
    "truncated PNG": (lambda o: _truncate(o / FILES[1]), FILES[1]),
    "PNG of another size": (lambda o: _png_of_other_size(o / FILES[0]), FILES[0]),
    "JPEG under a .png name": (lambda o: _jpeg_bytes(o / FILES[1]), FILES[1]),
    "missing PNG": (lambda o: (o / FILES[0]).unlink(), FILES[0]),
    "label of binary junk": (lambda o: (o / FILES[2]).write_bytes(bytes(range(256))), FILES[2]),
    "label with a bad line": (lambda o: (o / FILES[3]).write_text("0 0.5 0.5 7 0.1\n"), FILES[3]),
    "label with a class beyond the library": (
        lambda o: (o / FILES[2]).write_text("99 0.5 0.5 0.1 0.1\n"),
        FILES[2],
    ),
    "truncated EXR": (lambda o: _truncate(o / FILES[4]), FILES[4]),
    "zero-byte EXR": (lambda o: (o / FILES[5]).write_bytes(b""), FILES[5]),
    "truncated depth EXR": (lambda o: _truncate(o / FILES[6]), FILES[6]),
    "RGB EXR as the depth file": (_rgb_exr_as_depth, FILES[6]),
    "empty meta file": (lambda o: (o / FILES[7]).write_text(""), FILES[7]),
    "meta file of deep JSON": (lambda o: (o / FILES[7]).write_text("[" * 100_000), FILES[7]),
    "meta file that is a list": (lambda o: (o / FILES[7]).write_text("[1, 2]"), FILES[7]),
    "deleted COCO file": (lambda o: (o / FILES[8]).unlink(), FILES[8]),
    "deleted data.yaml": (lambda o: (o / FILES[9]).unlink(), FILES[9]),
    "temporary file of a killed run": (
        lambda o: (o / "images/clean/.dmg.png.tmp4242").write_bytes(b"partial"),
        FILES[0],
    ),
}


NOT_RENDERED = {"deleted COCO file", "deleted data.yaml", "temporary file of a killed run"}
RENDERED_END_TO_END = {"zero-byte PNG", "truncated EXR", "label of binary junk", "empty meta file"}


@pytest.mark.parametrize("damage", sorted(set(REPAIRED) - NOT_RENDERED))
def test_resume_detects_the_damage(damage, finished, tmp_path):
    """The cheap check of a finished scene's files finds every damage (no render needed)."""
    from seahaze.batch.folder import scene_file_problem
    from seahaze.dataset import Layout

    apply, restored = REPAIRED[damage]
    out = _copy(finished, tmp_path)
    assert scene_file_problem(Layout(out), "dmg", ["v1000"], True, (32, 18)) is None
    apply(out)
    problem = scene_file_problem(Layout(out), "dmg", ["v1000"], True, (32, 18))
    assert problem is not None and problem.startswith(restored), problem


@pytest.mark.parametrize("damage", sorted(RENDERED_END_TO_END | NOT_RENDERED))
def test_damaged_output_is_repaired_by_the_same_command(damage, scene, finished, tmp_path):
    apply = REPAIRED[damage][0]
    out = _copy(finished, tmp_path)
    apply(out)
    code, stdout, err = _rerun(scene, out)
    assert code == 0, err
    assert "Traceback" not in err
    assert not (out / "images/clean/.dmg.png.tmp4242").exists()
    for rel in FILES:
        ours, theirs = (out / rel).read_bytes(), (finished / rel).read_bytes()
        if rel == "data.yaml":  # it names its folder
            ours = ours.replace(str(out).encode(), str(finished).encode())
        assert ours == theirs, rel
    if damage in NOT_RENDERED:
        assert "nothing to render" in stdout
    else:
        assert "rendering it again" in err and "wrote 1 scene(s)" in stdout


DAMAGED_MANIFESTS: dict[str, Callable[[Path], None]] = {
    "zero-byte dataset.json": lambda o: (o / "dataset.json").write_bytes(b""),
    "truncated dataset.json": lambda o: _truncate(o / "dataset.json"),
    "dataset.json of binary junk": lambda o: (o / "dataset.json").write_bytes(bytes(range(256))),
    "deeply nested dataset.json": lambda o: (o / "dataset.json").write_text("[" * 100_000),
    "dataset.json nested inside valid JSON": _manifest_edit(
        lambda d: d.update(config=json.loads("[" * 200 + "]" * 200))
    ),
    "scenes as a list": _manifest_edit(lambda d: d.update(scenes=[])),
    "a scene entry that is a string": _manifest_edit(lambda d: d["scenes"].update(dmg="done")),
    "a scene with an unknown status": _manifest_edit(
        lambda d: d["scenes"]["dmg"].update(status="finished")
    ),
    "a scene name that climbs out": _manifest_edit(
        lambda d: d["scenes"].update({"../../etc/x": {"status": "done"}})
    ),
    "levels that are not level names": _manifest_edit(lambda d: d.update(levels=[{"name": 7}])),
    "config that is a number": _manifest_edit(lambda d: d.update(config=5)),
    "deleted dataset.json": lambda o: (o / "dataset.json").unlink(),
}


REBUILT = {"zero-byte dataset.json", "scenes as a list", "deleted dataset.json"}


@pytest.mark.parametrize("damage", sorted(DAMAGED_MANIFESTS))
def test_damaged_manifest_is_refused_with_what_to_do(damage, scene, finished, tmp_path):
    out = _copy(finished, tmp_path)
    DAMAGED_MANIFESTS[damage](out)
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    code, _, err = _rerun(scene, out)
    assert code == 2 and "Traceback" not in err
    assert "dataset.json" in err and "--force" in err and "damaged" in err
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before


@pytest.mark.parametrize("damage", sorted(REBUILT))
def test_damaged_manifest_is_rebuilt_with_force(damage, scene, finished, tmp_path):
    out = _copy(finished, tmp_path)
    (out / "notes.txt").write_text("mine\n")
    DAMAGED_MANIFESTS[damage](out)
    code, _, err = _rerun(scene, out, "--force")
    assert code == 0, err
    assert (out / "notes.txt").read_text() == "mine\n"
    assert json.loads((out / "dataset.json").read_text())["scenes"]["dmg"]["status"] == "done"
    for rel in FILES[:8]:
        assert (out / rel).read_bytes() == (finished / rel).read_bytes(), rel
    if damage != "deleted dataset.json":
        assert (out / "dataset.json.damaged").exists()
    assert _run(["render", str(scene), "--out", str(out), "--quiet"])[0] == 0


def test_another_programs_manifest_is_never_touched(scene, finished, tmp_path):
    out = _copy(finished, tmp_path)
    foreign = {"format": "labelme", "images": ["a.png"]}
    (out / "dataset.json").write_text(json.dumps(foreign))
    before = sorted(p.relative_to(out).as_posix() for p in out.rglob("*"))
    for extra in ([], ["--force"], ["--force", "--vis", "300"]):
        code, _, err = _rerun(scene, out, *extra)
        assert code == 2 and "not a seahaze manifest" in err
    assert sorted(p.relative_to(out).as_posix() for p in out.rglob("*")) == before
    assert json.loads((out / "dataset.json").read_text()) == foreign


def test_foreign_images_in_level_folders_are_refused_and_kept(scene, finished, tmp_path):
    out = _copy(finished, tmp_path)
    stray = out / "images/clean/holiday.png"
    stray.write_bytes(b"a photo")
    label = out / "labels/v1000/extra.txt"
    label.write_text("0 0.5 0.5 0.1 0.1\n")
    code, _, err = _rerun(scene, out)
    assert code == 2 and "images/clean/holiday.png" in err and "move them out" in err
    assert stray.read_bytes() == b"a photo" and label.exists()
    stray.unlink()
    label.unlink()
    assert _rerun(scene, out)[0] == 0


def test_force_deletes_only_the_files_the_old_manifest_lists(scene, finished, tmp_path):
    out = _copy(finished, tmp_path)
    keep = {
        "notes.txt": b"mine",
        "labels/v1000/README.md": b"not a label",
        "exr/v1000/other.exr": b"someone else's",
        "extra/.x.png.tmp7": b"not a seahaze temporary",
    }
    for rel, data in keep.items():
        (out / rel).parent.mkdir(parents=True, exist_ok=True)
        (out / rel).write_bytes(data)
    code, _, err = _rerun(scene, out, "--vis", "2000")
    assert code == 2 and "another configuration" in err
    code, _, err = _rerun(scene, out, "--vis", "2000", "--force")
    assert code == 0, err
    for rel, data in keep.items():
        assert (out / rel).read_bytes() == data, rel
    assert not (out / "images/v1000/dmg.png").exists()
    assert not (out / "exr/v1000/dmg.exr").exists() and not (out / "coco/v1000.json").exists()
    assert (out / "images/v2000/dmg.png").exists()


def test_force_deletes_nothing_through_a_level_folder_that_leads_outside(scene, finished, tmp_path):
    out = _copy(finished, tmp_path)
    elsewhere = tmp_path / "photos"
    shutil.move(out / "exr" / "v1000", elsewhere)  # the same names, outside the dataset
    (out / "exr" / "v1000").symlink_to(elsewhere, target_is_directory=True)
    before = {p: p.read_bytes() for p in elsewhere.iterdir()}
    assert before
    code, _, err = _rerun(scene, out, "--vis", "2000", "--force")
    assert code == 0, err
    assert {p: p.read_bytes() for p in elsewhere.iterdir()} == before
    assert not (out / "images/v1000/dmg.png").exists()  # the dataset's own: removed


def test_force_refuses_to_leave_a_level_folder_the_coco_writer_would_read(
    scene, finished, tmp_path
):
    out = _copy(finished, tmp_path)
    (out / "images/v1000/README.md").write_text("not an image")
    code, _, err = _rerun(scene, out, "--vis", "2000", "--force")
    assert code == 2 and "images/v1000/README.md" in err
    assert (out / "images/v1000/dmg.png").exists()  # nothing was deleted


def test_a_folder_where_a_file_should_be_is_refused(scene, finished, tmp_path):
    out = _copy(finished, tmp_path)
    (out / "images/clean/dmg.png").unlink()
    (out / "images/clean/dmg.png").mkdir()
    code, _, err = _rerun(scene, out)
    assert code == 2 and "images/clean/dmg.png" in err and "not a file" in err


def test_the_damage_catalogue_is_complete():
    """30 kinds of damage, as the issue's hostile user tried."""
    others = 6  # the other tests here: foreign manifest, strays, --force twice, a folder, OpenEXR
    assert len(REPAIRED) + len(DAMAGED_MANIFESTS) + others >= 30


def test_openexr_write_failure_stops_the_batch_like_a_full_disk(
    scene, finished, tmp_path, monkeypatch
):
    """OpenEXR reports a failed write as RuntimeError; it used to fail each scene in turn."""
    import OpenEXR

    real = OpenEXR.File

    class FullDisk:
        def __init__(self, *args, **kwargs):
            self.file = real(*args, **kwargs)

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return False

        def write(self, path):
            raise RuntimeError(f"Error writing to {path}: No space left on device")

    out = _copy(finished, tmp_path)
    (out / "images/clean/dmg.png").unlink()
    monkeypatch.setattr(OpenEXR, "File", FullDisk)
    code, _, err = _rerun(scene, out)
    assert code == 3, err
    assert "OpenEXR" in err and "rerun the same command" in err and "Traceback" not in err
    assert json.loads((out / "dataset.json").read_text())["scenes"]["dmg"]["status"] == "pending"
    monkeypatch.setattr(OpenEXR, "File", real)
    assert _rerun(scene, out)[0] == 0
    assert (out / FILES[0]).read_bytes() == (finished / FILES[0]).read_bytes()


SECOND_SCENE = SCENE.replace("name: dmg", "name: other").replace(
    "distance_m: 120", "distance_m: 90"
)


@pytest.fixture(scope="module")
def two_scenes(scene, tmp_path_factory) -> tuple[list[Path], Path]:
    """A finished dataset of two scenes of the same size, levels and files."""
    other = scene.parent / "other.yaml"
    other.write_text(SECOND_SCENE)
    out = tmp_path_factory.mktemp("two") / "ds"
    code, _, err = _run(["render", str(scene), str(other), "--out", str(out), "--quiet"])
    assert code == 0, err
    return [scene, other], out


def _swap(a: Path, b: Path) -> None:
    data = a.read_bytes()
    a.write_bytes(b.read_bytes())
    b.write_bytes(data)


def test_resume_rerenders_scenes_whose_pngs_were_swapped(two_scenes, tmp_path):
    """Each swapped PNG passes the cheap check (right size, a valid PNG); the content hash
    recorded at write time finds it, and the rerun brings back the original bytes."""
    from seahaze.batch.folder import scene_file_problem
    from seahaze.dataset import Layout

    scenes, finished = two_scenes
    out = _copy(finished, tmp_path)
    a, b = out / "images/clean/dmg.png", out / "images/clean/other.png"
    assert a.read_bytes() != b.read_bytes()
    _swap(a, b)
    for name in ("dmg", "other"):
        assert scene_file_problem(Layout(out), name, ["v1000"], True, (32, 18)) is None
    code, stdout, err = _run(["render", *map(str, scenes), "--out", str(out), "--quiet"])
    assert code == 0, err
    assert err.count("content hash differs") == 2 and "wrote 2 scene(s)" in stdout
    for path in sorted(finished.rglob("*")):
        if path.is_file() and path.name != "data.yaml":
            rel = path.relative_to(finished)
            assert (out / rel).read_bytes() == path.read_bytes(), rel


def test_a_finished_scene_records_the_hash_of_its_files(two_scenes):
    """files_sha256 is the SHA-256 of (relative path, SHA-256 of the file) lines, computed here
    independently from the files on disk."""
    import hashlib

    _, out = two_scenes
    record = json.loads((out / "dataset.json").read_text())["scenes"]["dmg"]
    lines = "".join(
        f"{rel}\0{hashlib.sha256((out / rel).read_bytes()).hexdigest()}\n"
        for rel in ["meta/dmg.json", "depth/dmg.exr"]
        + [
            f"{kind}/{level}/dmg.{ext}"
            for level in ("clean", "v1000")
            for kind, ext in (("images", "png"), ("labels", "txt"), ("exr", "exr"))
            + ((("transmission", "exr"),) if level != "clean" else ())
        ]
    )
    assert record["files_sha256"] == hashlib.sha256(lines.encode()).hexdigest()


@pytest.mark.parametrize(
    ("recorded", "rerendered"),
    [(None, False), ("0" * 64, True), ("not a hash", True), (["a list"], True)],
)
def test_a_record_without_a_valid_hash(scene, finished, tmp_path, recorded, rerendered):
    """No hash (a dataset made before seahaze kept one): the intact scene is kept and gets the
    hash of its files; a wrong or malformed hash: the scene is rendered again."""
    out = _copy(finished, tmp_path)
    good = json.loads((out / "dataset.json").read_text())["scenes"]["dmg"]["files_sha256"]

    def edit(data: dict) -> None:
        entry = data["scenes"]["dmg"]
        if recorded is None:
            del entry["files_sha256"]
        else:
            entry["files_sha256"] = recorded

    _manifest_edit(edit)(out)
    code, stdout, err = _rerun(scene, out)
    assert code == 0, err
    assert ("rendering it again" in err) == rerendered
    assert ("nothing to render" in stdout) == (not rerendered)
    assert json.loads((out / "dataset.json").read_text())["scenes"]["dmg"]["files_sha256"] == good
    for rel in FILES:
        if rel != "data.yaml":
            assert (out / rel).read_bytes() == (finished / rel).read_bytes(), rel
