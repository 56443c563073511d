"""Dataset batches (issue 7): scene variants, resume after SIGKILL, lock, config changes, write
errors, local worker processes, a Dask LocalCluster, and a small CI dataset regenerated and
validated.

Every render here uses a tiny template (48×27 px, 1 spp, one level, a low-density sea, two
vessels) except the CI dataset, which renders the issue's 3 scenes × 12 images at 160×90, 4 spp.
One uninterrupted run (the ``reference`` fixture) is the result every other run must match
byte for byte.
"""

from __future__ import annotations

import errno
import io
import json
import logging
import math
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from PIL import Image

from seahaze import fileio
from seahaze.batch import (
    LOCK_NAME,
    BatchPlan,
    DatasetLock,
    Reporter,
    plan_scenes,
    run_batch,
    scene_seed,
)
from seahaze.cli import main
from seahaze.fileio import read_exr
from seahaze.sceneio import SceneFileError, load_scene, parse_scene_text
from seahaze.vessels import CLASS_NAMES

TINY = """\
name: tiny
camera: {height_m: 12, pitch_deg: -2, resolution: [48, 27]}
sun: {elevation_deg: 30, azimuth_deg: 140}
sea: {quality: low, seed: 99}
vessels:
  sample: {count: 2, distance_m: [150, 1500], seed: 5}
haze: {levels: [1000]}
render: {spp: 1, airlight_spp: 16, seed: 3}
variation:
  camera_heading_deg: [-30, 30]
  sun_elevation_deg: [10, 50]
  wind_speed: [3, 10]
  sea_direction_deg: [0, 90]
"""
COUNT = 3


def _tree(root: Path) -> dict[str, bytes]:
    """Every file under ``root`` by relative path; data.yaml's absolute root made neutral."""
    files = {}
    for path in sorted(root.rglob("*")):
        if path.is_file():
            data = path.read_bytes()
            if path.name == "data.yaml":
                data = data.replace(str(root.resolve()).encode(), b"<root>")
            files[path.relative_to(root).as_posix()] = data
    return files


def _assert_same_tree(actual: Path, expected: Path) -> None:
    a, b = _tree(actual), _tree(expected)
    assert sorted(a) == sorted(b), "different file sets"
    differing = [name for name in a if a[name] != b[name]]
    assert not differing, f"files differ: {differing}"


def _render(template: Path, out: Path, *extra: str) -> int:
    return main(
        ["render", str(template), "--scenes", str(COUNT), "--out", str(out), "--quiet", *extra]
    )


def _manifest(root: Path) -> dict:
    return json.loads((root / "dataset.json").read_text())


def _statuses(root: Path) -> dict[str, str]:
    return {name: s["status"] for name, s in _manifest(root)["scenes"].items()}


@pytest.fixture(scope="module")
def template(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("scenes") / "tiny.yaml"
    path.write_text(TINY)
    return path


@pytest.fixture(scope="module")
def reference(template, tmp_path_factory) -> Path:
    """The tiny batch rendered once, uninterrupted, in this process, with a JSON-lines log."""
    out = tmp_path_factory.mktemp("reference")
    log = out.parent / "reference.jsonl"
    assert _render(template, out, "--log", str(log)) == 0
    return out


# --------------------------------------------------------------------------------------------
# Planning: seeds and variation (no rendering)


def test_scene_seeds_and_variation_follow_seed_template_and_index(template):
    spec, name = load_scene(template)
    plan = plan_scenes([(spec, name)], 6)
    again = plan_scenes([(spec, name)], 6)
    assert [j.spec for j in plan.jobs] == [j.spec for j in again.jobs]
    assert [j.name for j in plan.jobs] == [f"tiny_{i:05d}" for i in range(6)]
    seeds = [j.spec.render.seed for j in plan.jobs]
    assert len(set(seeds)) == 6
    assert seeds == [scene_seed(spec.render.seed, name, i) for i in range(6)]
    other = plan_scenes([(spec, name)], 6, master_seed=spec.render.seed + 1)
    assert not {j.spec.render.seed for j in other.jobs} & set(seeds)

    variation = spec.variation
    headings = [j.spec.camera.heading_deg for j in plan.jobs]
    for job in plan.jobs:
        s = job.spec
        assert (
            variation.camera_heading_deg[0]
            <= s.camera.heading_deg
            <= (variation.camera_heading_deg[1])
        )
        assert (
            variation.sun_elevation_deg[0]
            <= s.sun.elevation_deg
            <= (variation.sun_elevation_deg[1])
        )
        assert variation.wind_speed[0] <= s.sea.wind_speed <= variation.wind_speed[1]
        assert 0 <= s.sea.direction_deg <= 90
        assert s.sun.azimuth_deg == spec.sun.azimuth_deg  # no range: the template's value
        # resample_sea / resample_layout (default on): the template's fixed seeds are dropped
        assert s.sea.seed is None and s.vessels.sample.seed is None
    assert len(set(headings)) == 6 and np.ptp(headings) > 10.0


def test_variation_can_keep_the_template_layout_and_sea(template):
    spec = parse_scene_text(TINY + "  resample_sea: false\n  resample_layout: false\n", "keep.yaml")
    jobs = plan_scenes([(spec, "keep")], 2).jobs
    assert {j.spec.sea.seed for j in jobs} == {99}
    assert {j.spec.vessels.sample.seed for j in jobs} == {5}


def test_without_scenes_count_the_scene_renders_as_written(template):
    spec, name = load_scene(template)
    (job,) = plan_scenes([(spec, name)]).jobs
    assert job.name == "tiny" and job.spec == spec and job.index is None


@pytest.mark.parametrize(
    ("text", "where", "says"),
    [
        ("variation:\n  sun_elevation_deg: [10, 95]\n", "x.yaml:2", "less than or equal to 89.5"),
        ("variation:\n  wind_speed: [12, 4]\n", "x.yaml:1", "low <= high"),
        ("variation:\n  sun_height: [1, 2]\n", "x.yaml:2", "allowed keys: camera_heading_deg"),
    ],
)
def test_variation_errors_name_file_line_field_and_allowed_values(text, where, says):
    with pytest.raises(SceneFileError) as err:
        parse_scene_text(text, "x.yaml")
    message = str(err.value)
    assert message.startswith(where) and "variation" in message and says in message


def test_two_templates_draw_independent_scenes(template):
    spec, _ = load_scene(template)
    plan = plan_scenes([(spec, "north"), (spec, "south")], 2)
    assert [j.name for j in plan.jobs] == [
        "north_00000",
        "north_00001",
        "south_00000",
        "south_00001",
    ]
    assert len({j.spec.render.seed for j in plan.jobs}) == 4


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["--scenes", "0"], "--scenes 0"),
        (["--workers", "0"], "--workers 0"),
        (["--executor", "dask"], "needs --scheduler"),
        (["--scheduler", "tcp://127.0.0.1:1"], "needs --executor dask"),
        (["--executor", "dask", "--scheduler", "tcp://x:1", "--workers", "2"], "--workers is"),
    ],
)
def test_bad_batch_arguments_exit_2_with_a_message(template, tmp_path, capsys, args, says):
    code = main(["render", str(template), "--out", str(tmp_path / "out"), *args])
    err = capsys.readouterr().err
    assert code == 2 and says in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()


def test_a_folder_without_scene_files_is_bad_input(tmp_path, capsys):
    assert main(["render", str(tmp_path), "--out", str(tmp_path / "out")]) == 2
    assert "holds no scene files" in capsys.readouterr().err


def test_unreachable_dask_scheduler_is_reported(template, tmp_path, capsys):
    args = ["--executor", "dask", "--scheduler", "tcp://127.0.0.1:9"]
    code = main(["render", str(template), "--out", str(tmp_path), "--scenes", "1", *args])
    err = capsys.readouterr().err
    assert code == 2 and "cannot reach the Dask scheduler" in err
    assert not (tmp_path / "dataset.json").exists()  # refused before touching the folder


class _Stream(io.StringIO):
    def __init__(self, tty: bool):
        super().__init__()
        self.tty = tty

    def isatty(self) -> bool:
        return self.tty


@pytest.mark.parametrize("tty", [False, True])
def test_progress_shows_scenes_images_per_second_and_eta(template, tty):
    spec, name = load_scene(template)
    jobs = plan_scenes([(spec, name)], 3).jobs
    stream = _Stream(tty)
    reporter = Reporter(stream=stream)
    reporter.start(planned=3, done_before=1, to_render=2)
    reporter.scene_done(jobs[1], 2.0, {"clean": 1.0})
    reporter.close()
    text = stream.getvalue()
    assert "2/3" in text  # scenes done, of all (including those done before)
    if tty:  # tqdm: "2/3 [00:00<00:00, ..., 12.34 img/s]", the ETA after "<"
        assert "img/s" in text and "<" in text
    else:
        assert "images/s, ETA" in text
    quiet = _Stream(tty)
    silent = Reporter(stream=quiet, quiet=True)
    silent.start(planned=3, done_before=1, to_render=2)
    silent.scene_done(jobs[1], 2.0, {})
    silent.close()
    assert quiet.getvalue() == ""


def test_a_scene_that_renders_for_long_gives_heartbeats(template, tmp_path):
    """Without a terminal, a line and a ``heartbeat`` log event come every ``heartbeat_s``
    while a scene renders (a batch log never sits silent for minutes), naming the step the
    render is in; they come from the signal watcher's thread while the main one renders."""
    spec, name = load_scene(template)
    plan = plan_scenes([(spec, name)], 1)
    stream, log = _Stream(False), tmp_path / "log.jsonl"
    reporter = Reporter(stream=stream, log=log, heartbeat_s=0.5)
    assert run_batch(plan, tmp_path / "out", reporter=reporter).outcome == "complete"
    reporter.close()
    events = [json.loads(line) for line in log.open()]
    beats = [e for e in events if e["event"] == "heartbeat"]
    assert beats and all(e["done"] == 0 and e["planned"] == 1 for e in beats)
    assert [e["seconds"] for e in beats] == sorted(e["seconds"] for e in beats)
    assert "0/1 scenes" in stream.getvalue() and "elapsed, rendering" in stream.getvalue()
    steps = {e["stage"].split(": ", 1)[1].split(" ")[0] for e in beats if "stage" in e}
    assert steps and steps <= {"building", "scene", "diffuse", "camera", "vessel-light", "clean"}
    assert events[0]["event"] == "start" and events[-1]["event"] == "end"


# --------------------------------------------------------------------------------------------
# The reference batch, resume, lock, config changes, write errors


def test_reference_batch_is_complete_and_logged(reference):
    manifest = _manifest(reference)
    assert list(manifest["scenes"]) == [f"tiny_{i:05d}" for i in range(COUNT)]
    assert set(_statuses(reference).values()) == {"done"}
    assert manifest["config"]["batch"] == {
        "scenes_per_template": COUNT,
        "master_seeds": {"tiny": 3},
    }
    for name in manifest["scenes"]:
        for level in ("clean", "v1000"):
            assert (reference / "images" / level / f"{name}.png").is_file()
    assert not (reference / LOCK_NAME).exists()
    events = [json.loads(line) for line in (reference.parent / "reference.jsonl").open()]
    assert [e["event"] for e in events] == ["start"] + ["scene_done"] * COUNT + ["end"]
    done = [e for e in events if e["event"] == "scene_done"]
    assert all(e["images"] == 2 and e["seconds"] > 0 and "pass" in e["timings"] for e in done)
    assert events[-1]["outcome"] == "complete" and events[-1]["images"] == 2 * COUNT


@pytest.mark.slow
def test_sigkill_mid_batch_then_resume_gives_identical_files(template, reference, tmp_path, capsys):
    out = tmp_path / "killed"
    command = [sys.executable, "-m", "seahaze.cli", "render", str(template)]
    command += ["--scenes", str(COUNT), "--out", str(out), "--quiet"]
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 180
    try:
        while time.monotonic() < deadline and process.poll() is None:
            if (out / "dataset.json").exists() and "done" in _statuses(out).values():
                break
            time.sleep(0.02)
        process.send_signal(signal.SIGKILL)  # no chance to clean up: lock and temp files stay
    finally:
        process.kill()
        process.wait()
    statuses = _statuses(out)
    assert "done" in statuses.values() and "pending" in statuses.values(), statuses
    assert (out / LOCK_NAME).exists()  # left behind by the killed process

    # Resume with two local worker processes: only the missing scenes, same bytes.
    missing = sum(s != "done" for s in statuses.values())
    assert _render(template, out, "--workers", "2") == 0
    captured = capsys.readouterr()
    assert "taking over the lock left by pid" in captured.err
    assert f"wrote {missing} scene(s)" in captured.out
    _assert_same_tree(out, reference)


@pytest.mark.parametrize("kind", ["folder", "link"])
def test_a_lock_name_that_is_not_a_lock_file_is_refused(kind, tmp_path) -> None:
    from seahaze.batch import LOCK_NAME
    from seahaze.batch.errors import DatasetLockedError

    out = tmp_path / "ds"
    out.mkdir()
    victim = tmp_path / "victim.txt"
    victim.write_text("not to be truncated")
    if kind == "folder":
        (out / LOCK_NAME).mkdir()
    else:
        (out / LOCK_NAME).symlink_to(victim)
    with pytest.raises(DatasetLockedError, match="not seahaze's lock file"), DatasetLock(out):
        pass
    assert victim.read_text() == "not to be truncated"


def test_a_second_process_is_refused_by_the_lock(template, reference, tmp_path, capsys):
    out = tmp_path / "locked"
    shutil.copytree(reference, out)
    before = _tree(out)
    with DatasetLock(out):  # flock is per open file: a second open in this process conflicts
        code = _render(template, out)
    err = capsys.readouterr().err
    assert code == 2 and "in use by another seahaze process" in err and f"pid {os.getpid()}" in err
    assert _tree(out) == before


def test_a_stale_lock_of_a_dead_process_is_taken_over(template, reference, tmp_path, capsys):
    out = tmp_path / "stale"
    shutil.copytree(reference, out)
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    (out / LOCK_NAME).write_text(f"pid {dead.pid} on elsewhere\n")
    assert _render(template, out) == 0
    captured = capsys.readouterr()
    assert f"taking over the lock left by pid {dead.pid}" in captured.err
    assert "nothing to render" in captured.out
    _assert_same_tree(out, reference)  # lock file gone


def test_a_changed_config_is_refused_unless_forced(template, reference, tmp_path, capsys):
    out = tmp_path / "changed"
    shutil.copytree(reference, out)
    before = _tree(out)
    assert _render(template, out, "--spp", "2") == 2
    err = capsys.readouterr().err
    assert "another configuration" in err and "render.spp" in err and "--force" in err
    assert _tree(out) == before

    # Fewer scenes with --force: the dropped scene's files go, the kept ones are not re-rendered.
    two = ["render", str(template), "--scenes", "2", "--out", str(out), "--quiet"]
    assert main(two) == 2
    assert main([*two, "--force"]) == 0
    assert list(_statuses(out)) == ["tiny_00000", "tiny_00001"]
    assert not list(out.rglob("tiny_00002.*"))
    coco = json.loads((out / "coco" / "v1000.json").read_text())
    assert len(coco["images"]) == 2
    for rel, data in _tree(reference).items():
        if "tiny_00002" not in rel and rel.split("/")[0] in ("images", "labels", "exr", "meta"):
            assert (out / rel).read_bytes() == data, rel

    # A scene whose recorded config differs is re-rendered under --force, and only that one.
    manifest = _manifest(out)
    manifest["scenes"]["tiny_00001"]["config"]["render"]["spp"] = 7
    (out / "dataset.json").write_text(json.dumps(manifest, indent=2) + "\n")
    (out / "images" / "clean" / "tiny_00001.png").unlink()
    capsys.readouterr()
    assert main(two) == 2
    assert "scene tiny_00001: config.render.spp" in capsys.readouterr().err
    assert main([*two, "--force"]) == 0
    ref = reference / "images" / "clean" / "tiny_00001.png"
    assert (out / "images" / "clean" / "tiny_00001.png").read_bytes() == ref.read_bytes()
    assert set(_statuses(out).values()) == {"done"}


def test_a_manifest_without_a_field_added_since_resumes(template, reference, tmp_path, capsys):
    # A folder written before haze.extinction_spectrum existed: the field at its default keeps
    # the old behaviour, so the folder resumes without --force and nothing is re-rendered.
    out = tmp_path / "older"
    shutil.copytree(reference, out)
    manifest = _manifest(out)
    for entry in manifest["scenes"].values():
        del entry["config"]["haze"]["extinction_spectrum"]
    (out / "dataset.json").write_text(json.dumps(manifest, indent=2) + "\n")
    clean = out / "images" / "clean" / "tiny_00000.png"
    stamp = clean.stat().st_mtime_ns
    assert _render(template, out) == 0, capsys.readouterr().err
    assert clean.stat().st_mtime_ns == stamp
    # The same field set to another value is a real change.
    manifest = _manifest(out)
    manifest["scenes"]["tiny_00000"]["config"]["haze"]["extinction_spectrum"] = "kim"
    (out / "dataset.json").write_text(json.dumps(manifest, indent=2) + "\n")
    assert _render(template, out) == 2
    assert "config.haze.extinction_spectrum" in capsys.readouterr().err


def test_a_full_disk_stops_cleanly_and_keeps_finished_scenes(
    template, reference, tmp_path, monkeypatch, capsys
):
    out = tmp_path / "full"
    shutil.copytree(reference, out)
    manifest = _manifest(out)
    for name in ("tiny_00001", "tiny_00002"):
        manifest["scenes"][name]["status"] = "pending"
    (out / "dataset.json").write_text(json.dumps(manifest, indent=2) + "\n")
    real_write_png = fileio.write_png

    def write_png(path, image8):
        if "tiny_00002" in str(path):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))
        real_write_png(path, image8)

    monkeypatch.setattr(fileio, "write_png", write_png)
    assert _render(template, out) == 3
    err = capsys.readouterr().err
    assert "No space left on device" in err and "rerun the same command" in err
    assert "Traceback" not in err
    assert _statuses(out) == {"tiny_00000": "done", "tiny_00001": "done", "tiny_00002": "pending"}
    assert not (out / LOCK_NAME).exists()
    assert not [p for p in out.rglob(".*") if ".tmp" in p.name]
    for rel in ("images/clean/tiny_00001.png", "exr/v1000/tiny_00001.exr", "meta/tiny_00001.json"):
        assert (out / rel).read_bytes() == (reference / rel).read_bytes(), rel

    monkeypatch.setattr(fileio, "write_png", real_write_png)
    assert _render(template, out) == 0
    assert "wrote 1 scene(s)" in capsys.readouterr().out
    _assert_same_tree(out, reference)


@pytest.mark.slow
def test_dask_local_cluster_gives_the_local_result(template, reference, tmp_path):
    distributed = pytest.importorskip("distributed")
    out = tmp_path / "dask"
    with distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        dashboard_address=None,
        silence_logs=logging.ERROR,
    ) as cluster:
        code = _render(
            template, out, "--executor", "dask", "--scheduler", cluster.scheduler_address
        )
    assert code == 0
    _assert_same_tree(out, reference)


# --------------------------------------------------------------------------------------------
# CI regeneration: 3 scenes × 12 images at 160×90, 4 spp, validated


CI_SCENE = Path(__file__).parent / "data" / "ci_batch.yaml"


def _check_labels(text: str) -> None:
    for line in text.splitlines():
        cls, *box = line.split()
        assert 0 <= int(cls) < len(CLASS_NAMES)
        assert len(box) == 4 and all(0.0 <= float(v) <= 1.0 for v in box), line


@pytest.mark.slow
def test_ci_dataset_regenerates_and_validates(tmp_path):
    template = CI_SCENE
    out = tmp_path / "ci"
    assert main(["render", str(template), "--scenes", "3", "--out", str(out), "--quiet"]) == 0

    manifest = _manifest(out)
    levels = ["clean"] + [level["name"] for level in manifest["levels"]]
    assert len(levels) == 12 and set(_statuses(out).values()) == {"done"}
    data = yaml.safe_load((out / "data.yaml").read_text())
    assert all(data[level] == str(out.resolve() / "images" / level) for level in levels)
    assert data["names"] == dict(enumerate(CLASS_NAMES))
    boxes = 0
    for name in manifest["scenes"]:
        labels = {(out / "labels" / lv / f"{name}.txt").read_text() for lv in levels}
        assert len(labels) == 1  # the same boxes at every level
        _check_labels(labels.pop())
        boxes += len((out / "labels" / "clean" / f"{name}.txt").read_text().splitlines())
        for level in levels:
            with Image.open(out / "images" / level / f"{name}.png") as image:
                assert image.size == (160, 90) and image.mode == "RGB"
            radiance = read_exr(out / "exr" / level / f"{name}.exr")["RGB"]
            assert radiance.shape == (90, 160, 3) and np.isfinite(radiance).all()
            assert (radiance >= 0).all()
        depth = read_exr(out / "depth" / f"{name}.exr")["Z"]
        assert not np.isnan(depth).any() and (depth > 0).all()
        meta = json.loads((out / "meta" / f"{name}.json").read_text())
        assert [lv["name"] for lv in meta["levels"]] == levels[1:]
        for vessel in meta["vessels"]:
            for value in vessel["levels"].values():
                c = value["apparent_contrast"]
                assert c is None or math.isfinite(c)
    assert boxes > 0, "no vessel labelled in the whole CI dataset"
    for level in levels:
        coco = json.loads((out / "coco" / f"{level}.json").read_text())
        assert len(coco["images"]) == 3 and len(coco["annotations"]) == boxes
    headings = {s["config"]["camera"]["heading_deg"] for s in manifest["scenes"].values()}
    assert len(headings) == 3

    # Determinism: the middle scene rendered alone, in another folder, gives the same bytes.
    spec, name = load_scene(template)
    full = plan_scenes([(spec, name)], 3)
    alone = BatchPlan((full.jobs[1],), full.levels, full.threshold, full.count)
    again = tmp_path / "again"
    assert run_batch(alone, again).outcome == "complete"
    scene = full.jobs[1].name
    for path in again.rglob(f"{scene}.*"):
        rel = path.relative_to(again)
        assert path.read_bytes() == (out / rel).read_bytes(), rel


@pytest.mark.usefixtures("mitsuba_variant")
def test_an_in_process_batch_gives_each_scene_once_its_files_are_written(tmp_path):
    """In one process a scene's files are written while the next scene renders; each outcome
    still comes in the jobs' order, and only once every file of its scene is on disk (its
    meta.json is written last), a failed scene in its place between the others."""
    from conftest import small_spec
    from seahaze.batch.executors import SceneDone, start_executor
    from seahaze.batch.plan import SceneJob
    from seahaze.dataset.layout import Layout

    spec = small_spec(haze={"levels": [1000]}, render={"spp": 1})
    broken = spec.model_copy(update={"render": spec.render.model_copy(update={"mode": "nope"})})
    jobs = [
        SceneJob("s0", spec, "t"),
        SceneJob("s1", broken, "t"),
        SceneJob("s2", spec.model_copy(update={"name": "other"}), "t"),
    ]
    layout = Layout(tmp_path)
    seen, totals = [], []
    start = time.perf_counter()
    for name, outcome in start_executor(jobs, tmp_path, 1, None, lambda _: None).results():
        seen.append(name)
        if name == "s1":
            assert isinstance(outcome, Exception)
            continue
        assert isinstance(outcome, SceneDone) and outcome.timings["total"] > 0.0
        assert layout.meta(name).is_file() and layout.depth(name).is_file()
        totals.append(outcome.timings["total"])
    assert seen == ["s0", "s1", "s2"]
    # A scene's total is its share of the batch's time: the totals never add up to more.
    assert sum(totals) < time.perf_counter() - start
