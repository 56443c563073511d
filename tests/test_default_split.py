"""A scene-disjoint split by default (issue 34): ``seahaze render`` without ``--split`` splits a
new folder 0.8/0.1/0.1 by scene hash and says so; a batch too small for that gets one clear
line and still a usable ``data.yaml`` (train and val share no scene, val is not empty; one scene
is train = val); a folder that holds a dataset keeps the split it was made with, so folders
made before the default resume as they were; ``--split none`` is the old layout."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
import yaml

from seahaze.batch import plan_scenes
from seahaze.cli import main
from seahaze.dataset import data_yaml_text
from seahaze.dataset.splits import (
    DEFAULT_SPLIT,
    SPLIT_NAMES,
    SplitFractions,
    assign_splits,
    resolve_split,
)
from seahaze.sceneio import load_scene

ROOT = Path(__file__).resolve().parents[1]
DEFAULT = SplitFractions.parse(DEFAULT_SPLIT)

CLEAN_SPLIT_SEED = 23
"""A master seed whose 3 scenes of the tiny template get train, val and test by hash alone."""


def _listed(root: Path, split: str) -> list[str]:
    path = root / f"{split}.txt"
    if not path.exists():
        return []
    return [Path(line).stem for line in path.read_text().splitlines()]


def _render(template: Path, out: Path, *extra: str) -> int:
    args = ["render", str(template), "--scenes", "3", "--res", "32x18", "--out", str(out)]
    return main([*args, *extra])


# --------------------------------------------------------------------------------------------
# The rule, without rendering


def test_a_new_folder_gets_the_default_and_a_folder_keeps_what_it_records():
    assert resolve_split(None, None) == (DEFAULT, "the default")
    assert DEFAULT.as_dict() == {"train": 0.8, "val": 0.1, "test": 0.1}
    assert resolve_split("none", None)[0] is None
    assert resolve_split("0.5,0.25,0.25", None)[0] == SplitFractions(0.5, 0.25, 0.25)
    # A folder made before the default (or with --split none) records no split: it keeps none.
    old = {"config": {"threshold": "koschmieder", "batch": None}}
    assert resolve_split(None, old)[0] is None
    made = {"config": {"split": {"train": 0.5, "val": 0.25, "test": 0.25}}}
    assert resolve_split(None, made)[0] == SplitFractions(0.5, 0.25, 0.25)
    # --split decides over the record.
    assert resolve_split("none", made)[0] is None
    assert resolve_split("0.8,0.1,0.1", old)[0] == DEFAULT


@pytest.mark.parametrize("n", [1, 2, 3, 5, 12])
def test_small_batches_keep_train_and_val_non_empty_and_disjoint(n):
    for seed in range(200):
        scenes = [(f"s_{i:05d}", seed) for i in range(n)]
        assignment = assign_splits(DEFAULT, scenes)
        counts = assignment.counts()
        assert sum(counts.values()) == n and set(assignment.splits) == {s for s, _ in scenes}
        assert counts["train"] >= 1
        if n >= 2:
            assert counts["val"] >= 1
        # Only what must move moves: each move fills a split the hash left empty, and takes
        # no split's last scene.
        by_hash = {name: DEFAULT.split_of(seed, name) for name, _ in scenes}
        changed = {name for name in by_hash if by_hash[name] != assignment.splits[name]}
        assert changed == {scene for scene, _, _ in assignment.moved}
        assert len(assignment.moved) <= 2
        for scene, before, after in assignment.moved:
            assert by_hash[scene] == before and before != after
            assert after not in by_hash.values(), (seed, assignment)
        warning = assignment.warning()
        assert (warning is None) == (not assignment.moved and not assignment.empty())
        assert warning is None or "\n" not in warning


def test_large_batches_are_the_hash_alone():
    scenes = [(f"s_{i:05d}", 7) for i in range(400)]
    assignment = assign_splits(DEFAULT, scenes)
    assert not assignment.moved and assignment.warning() is None
    assert assignment.splits == {name: DEFAULT.split_of(7, name) for name, _ in scenes}
    assert "0.8,0.1,0.1 by scene hash" in assignment.describe()


def test_one_scene_is_train_and_data_yaml_validates_on_it():
    spec, name = load_scene(ROOT / "scenes" / "default.yaml")
    plan = plan_scenes([(spec, name)], split=DEFAULT)
    assert [job.split for job in plan.jobs] == ["train"]
    assert plan.config()["split"] == DEFAULT.as_dict()  # the setting asked for is recorded
    assert plan.split == SplitFractions(1.0, 0.0, 0.0)  # lists only for splits with scenes
    warning = plan.assignment.warning()
    assert warning is not None and "\n" not in warning
    assert "1 scene (default) is too few" in warning and "train = val" in warning
    data = yaml.safe_load(data_yaml_text(Path("/tmp/x"), ["v1000"], ("ship",), ["train"]))
    assert data["train"] == data["val"] == "train.txt" and "test" not in data


# --------------------------------------------------------------------------------------------
# seahaze render without --split


def test_render_without_split_writes_disjoint_train_and_val_and_says_so(
    split_template, tmp_path, capsys
):
    out = tmp_path / "ds"
    assert _render(split_template, out, "--seed", str(CLEAN_SPLIT_SEED)) == 0
    err = capsys.readouterr().err
    line = "[seahaze] split (the default): 0.8,0.1,0.1 by scene hash: train 1, val 1, test 1"
    assert line in err and "no scene in two splits" in err, err
    assert "warning" not in err
    data = yaml.safe_load((out / "data.yaml").read_text())
    assert {name: data[name] for name in SPLIT_NAMES} == {s: f"{s}.txt" for s in SPLIT_NAMES}
    lists = {name: _listed(out, name) for name in SPLIT_NAMES}
    assert all(len(scenes) == 1 for scenes in lists.values()), lists
    assert not set(lists["train"]) & set(lists["val"])
    assert not set(lists["train"]) & set(lists["test"])
    assert sorted(s for scenes in lists.values() for s in scenes) == [
        f"tiny_{i:05d}" for i in range(3)
    ]
    manifest = json.loads((out / "dataset.json").read_text())
    assert manifest["config"]["split"] == DEFAULT.as_dict()
    assert {n: e["split"] for n, e in manifest["scenes"].items()} == {
        scene: split for split, scenes in lists.items() for scene in scenes
    }


def test_a_small_batch_gets_one_warning_line_and_a_non_empty_val(split_template, tmp_path, capsys):
    out = tmp_path / "small"
    assert _render(split_template, out, "--quiet") == 0  # the template's seed: val empty by hash
    err = capsys.readouterr().err
    warnings = [line for line in err.splitlines() if line.startswith("seahaze: warning:")]
    assert len(warnings) == 1, err
    assert "split (the default): 3 scenes are too few for the split 0.8,0.1,0.1" in warnings[0]
    assert "so that val is not empty" in warnings[0] and "no test.txt" in warnings[0]
    train, val = _listed(out, "train"), _listed(out, "val")
    assert len(train) == 2 and len(val) == 1 and not set(train) & set(val)
    assert not (out / "test.txt").exists()
    data = yaml.safe_load((out / "data.yaml").read_text())
    assert (data["train"], data["val"]) == ("train.txt", "val.txt") and "test" not in data


def test_resuming_keeps_the_split_the_folder_was_made_with(split_template, tmp_path, capsys):
    out = tmp_path / "resume"
    assert _render(split_template, out, "--seed", str(CLEAN_SPLIT_SEED), "--quiet") == 0
    before = json.loads((out / "dataset.json").read_text())
    # The same command again: nothing to render, no configuration change.
    assert _render(split_template, out, "--seed", str(CLEAN_SPLIT_SEED)) == 0
    captured = capsys.readouterr()
    assert "nothing to render" in captured.out
    assert "split (kept from the folder's dataset.json)" in captured.err
    assert json.loads((out / "dataset.json").read_text()) == before
    # Another split is a configuration change, refused without --force, as an explicit one was.
    assert _render(split_template, out, "--seed", str(CLEAN_SPLIT_SEED), "--split", "none") == 2
    assert "split.train: 0.8 there, '(none)' now" in capsys.readouterr().err


def test_a_folder_made_without_a_split_resumes_as_it_was(dataset, tmp_path, capsys):
    # The dataset fixture has the manifest of a folder made before the default (no split key).
    out = tmp_path / "old"
    shutil.copytree(dataset, out, symlinks=True)
    assert "split" not in json.loads((out / "dataset.json").read_text())["config"]
    args = ["render", str(ROOT / "scenes" / "default.yaml"), "--vis", "300,4000", "--res"]
    args += ["64x36", "--spp", "2", "--out", str(out)]
    assert main(args) == 0
    captured = capsys.readouterr()
    assert "nothing to render" in captured.out
    assert "split: none (kept from the folder's dataset.json, made without a split)" in (
        captured.err
    )
    data = yaml.safe_load((out / "data.yaml").read_text())
    assert data["train"] == data["val"] == "images/clean"
    assert not list(out.glob("*.txt"))


def test_split_none_on_a_new_folder_is_the_old_layout(split_template, tmp_path, capsys):
    out = tmp_path / "none"
    assert _render(split_template, out, "--split", "none") == 0
    assert "[seahaze] split: none (--split none)" in capsys.readouterr().err
    manifest = json.loads((out / "dataset.json").read_text())
    assert "split" not in manifest["config"]
    assert all("split" not in entry for entry in manifest["scenes"].values())
    data = yaml.safe_load((out / "data.yaml").read_text())
    assert data["train"] == data["val"] == "images/clean" and "test" not in data
    assert not list(out.glob("*.txt"))
