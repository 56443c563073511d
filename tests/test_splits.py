"""Scene-disjoint train/val/test splits (issue 18): decided per scene from (master seed, scene
name), so they are disjoint by construction and stable when a batch grows; recorded in
dataset.json, used by data.yaml's lists; a dataset without --split is unchanged."""

from __future__ import annotations

import json
import math
import shutil
from collections import Counter
from pathlib import Path

import pytest
import yaml

from conftest import SPLIT_SCENES
from seahaze.batch import plan_scenes
from seahaze.cli import main
from seahaze.dataset.splits import SPLIT_NAMES, SplitError, SplitFractions, scene_unit
from seahaze.sceneio import load_scene

FRACTIONS = SplitFractions(0.8, 0.1, 0.1)
FRACTIONS_DS = SplitFractions(0.5, 0.25, 0.25)  # conftest's SPLIT_FRACTIONS


def _manifest(root: Path) -> dict:
    return json.loads((root / "dataset.json").read_text())


def _list_scenes(root: Path, split: str) -> list[str]:
    lines = (root / f"{split}.txt").read_text().splitlines()
    assert all(line.startswith("./images/clean/") and line.endswith(".png") for line in lines)
    return [Path(line).stem for line in lines]


# --------------------------------------------------------------------------------------------
# The rule, without rendering


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ("0.8,0.2", "expected 3 comma-separated fractions"),
        ("0.8,0.1,0.2", "must sum to 1"),
        ("0.8,x,0.1", "must be numbers"),
        ("1.2,-0.1,-0.1", "in [0, 1]"),
        ("0,0.5,0.5", "train fraction must be > 0"),
        ("nan,0.5,0.5", "in [0, 1]"),
    ],
)
def test_bad_fractions_say_what_is_allowed(text, says):
    with pytest.raises(SplitError) as err:
        SplitFractions.parse(text)
    assert says in str(err.value)


def test_a_scene_split_depends_only_on_seed_and_name():
    # The unit value is a pure function: the same inputs give the same value in any order.
    a = [scene_unit(1, f"msvd_{i:05d}") for i in range(50)]
    b = [scene_unit(1, f"msvd_{i:05d}") for i in reversed(range(50))][::-1]
    assert a == b and all(0.0 <= u < 1.0 for u in a)
    assert scene_unit(2, "msvd_00000") != scene_unit(1, "msvd_00000")
    # The cumulative edges: u < 0.8 train, < 0.9 val, else test.
    for i, u in enumerate(a):
        expected = "train" if u < 0.8 else "val" if u < 0.9 else "test"
        assert FRACTIONS.split_of(1, f"msvd_{i:05d}") == expected


def test_fractions_are_met_within_binomial_noise():
    n = 4000
    counts = Counter(FRACTIONS.split_of(7, f"s_{i}") for i in range(n))
    for name, fraction in FRACTIONS.as_dict().items():
        sigma = math.sqrt(n * fraction * (1 - fraction))
        assert abs(counts[name] - n * fraction) < 4 * sigma, (name, counts)


def test_an_empty_split_gets_no_scene():
    fractions = SplitFractions(0.9, 0.1, 0.0)
    assert {fractions.split_of(3, f"s_{i}") for i in range(500)} == {"train", "val"}


def test_planned_splits_are_stable_when_the_batch_grows(split_template):
    spec, name = load_scene(split_template)
    small = plan_scenes([(spec, name)], 10, split=FRACTIONS)
    large = plan_scenes([(spec, name)], 1000, split=FRACTIONS)
    assert [(j.name, j.split) for j in small.jobs] == [(j.name, j.split) for j in large.jobs[:10]]
    # Another template in the batch leaves these scenes' splits (and seeds) as they were.
    mixed = plan_scenes([(spec, "other"), (spec, name)], 10, split=FRACTIONS)
    assert [(j.name, j.split, j.spec) for j in mixed.jobs[10:]] == [
        (j.name, j.split, j.spec) for j in small.jobs
    ]
    assert {j.split for j in large.jobs} == set(SPLIT_NAMES)
    # The master seed decides: another one moves scenes between splits.
    other = plan_scenes([(spec, name)], 1000, master_seed=4, split=FRACTIONS)
    assert [j.split for j in other.jobs] != [j.split for j in large.jobs]


def test_without_split_the_plan_records_none(split_template):
    spec, name = load_scene(split_template)
    plan = plan_scenes([(spec, name)], 3)
    assert all(job.split is None for job in plan.jobs)
    assert "split" not in plan.config()
    assert all("split" not in job.entry("pending") for job in plan.jobs)


# --------------------------------------------------------------------------------------------
# A rendered dataset with --split


def test_splits_are_disjoint_by_scene_and_recorded(split_dataset):
    manifest = _manifest(split_dataset)
    assert manifest["config"]["split"] == {"train": 0.5, "val": 0.25, "test": 0.25}
    recorded = {name: entry["split"] for name, entry in manifest["scenes"].items()}
    assert len(recorded) == SPLIT_SCENES
    lists = {split: _list_scenes(split_dataset, split) for split in SPLIT_NAMES}
    every = [scene for scenes in lists.values() for scene in scenes]
    assert sorted(every) == sorted(recorded)  # each scene in exactly one list
    for split, scenes in lists.items():
        assert scenes == [s for s, r in recorded.items() if r == split]
        for scene in scenes:  # the recorded split is the rule's
            assert FRACTIONS_DS.split_of(3, scene) == split
    # Every split is used by this fixture, so the disjointness checked above is not vacuous.
    assert all(lists.values()), lists


def test_data_yaml_uses_the_split_lists_and_absolute_levels(split_dataset):
    data = yaml.safe_load((split_dataset / "data.yaml").read_text())
    root = split_dataset.resolve()
    assert data["path"] == str(root)
    assert {k: data[k] for k in SPLIT_NAMES} == {s: f"{s}.txt" for s in SPLIT_NAMES}
    for level in ("v0500", "v2000"):
        assert data[level] == str(root / "images" / level)
    assert data["names"][0] == "container_ship"


def test_a_grown_batch_keeps_every_scene_split_and_file(split_template, split_dataset, tmp_path):
    out = tmp_path / "grown"
    shutil.copytree(split_dataset, out)
    before = _manifest(out)["scenes"]
    stamps = {p: p.stat().st_mtime_ns for p in (out / "images").rglob("*.png")}
    grow = ["render", str(split_template), "--scenes", str(SPLIT_SCENES + 3), "--split"]
    grow += ["0.5,0.25,0.25", "--out", str(out), "--quiet"]
    assert main(grow) == 2  # more scenes is a config change: refused without --force
    assert main([*grow, "--force"]) == 0
    after = _manifest(out)["scenes"]
    assert len(after) == SPLIT_SCENES + 3
    for name, entry in before.items():
        assert after[name]["split"] == entry["split"], name
    assert all(p.stat().st_mtime_ns == t for p, t in stamps.items())  # nothing re-rendered
    for name, entry in after.items():
        assert entry["split"] == FRACTIONS_DS.split_of(3, name)
    listed = sorted(s for split in SPLIT_NAMES for s in _list_scenes(out, split))
    assert listed == sorted(after)


def test_a_new_split_needs_force_and_renders_nothing(
    split_template, split_dataset, tmp_path, capsys
):
    out = tmp_path / "resplit"
    shutil.copytree(split_dataset, out)
    stamps = {p: p.stat().st_mtime_ns for p in (out / "images").rglob("*.png")}
    args = ["render", str(split_template), "--scenes", str(SPLIT_SCENES), "--out", str(out)]
    args += ["--quiet", "--split", "0.9,0.1,0"]
    assert main(args) == 2
    assert "split.train: 0.5 there, 0.9 now" in capsys.readouterr().err
    assert main([*args, "--force"]) == 0
    assert "nothing to render" in capsys.readouterr().out
    assert all(p.stat().st_mtime_ns == t for p, t in stamps.items())
    assert not (out / "test.txt").exists()  # the split is gone, and so is its list
    data = yaml.safe_load((out / "data.yaml").read_text())
    assert "test" not in data and data["train"] == "train.txt"
    assert {e["split"] for e in _manifest(out)["scenes"].values()} <= {"train", "val"}


@pytest.mark.parametrize("value", ["0.5,0.5", "a,b,c", "0.5,0.6,-0.1"])
def test_bad_split_flag_is_one_line_exit_2(split_template, tmp_path, capsys, value):
    args = ["render", str(split_template), "--split", value, "--out", str(tmp_path / "x")]
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"seahaze: error: --split '{value}':") and "\n" not in err
    assert "0.8,0.1,0.1" in err or "[0, 1]" in err
    assert not (tmp_path / "x").exists()


def test_a_dataset_without_split_keeps_its_manifest(dataset):
    # The session's default-scene dataset, rendered without --split: no split key anywhere,
    # train/val as before, no list files, and the levels absolute (so any cwd works).
    manifest = _manifest(dataset)
    assert "split" not in manifest["config"]
    assert all("split" not in entry for entry in manifest["scenes"].values())
    assert not list(dataset.glob("*.txt"))
    data = yaml.safe_load((dataset / "data.yaml").read_text())
    assert data["train"] == data["val"] == "images/clean" and "test" not in data
