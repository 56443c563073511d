"""The metric on one split of a dataset, restored images named by scene, and the --model flags'
input checks (issue 18). Ultralytics itself is exercised in test_ultralytics.py."""

from __future__ import annotations

import importlib.util
import json
import re
import shutil
from pathlib import Path

import pytest

from seahaze.cli import main
from seahaze.metric import load_dataset
from seahaze.metric.errors import MetricInputError
from seahaze.metric.reader import dehazed_images, scene_images


def _splits(root: Path) -> dict[str, list[str]]:
    out: dict[str, list[str]] = {}
    for name, entry in json.loads((root / "dataset.json").read_text())["scenes"].items():
        out.setdefault(entry["split"], []).append(name)
    return out


def _perfect(dataset: Path, pred: Path, levels: tuple[str, ...], scenes: list[str]) -> None:
    """Predictions equal to the labels, confidence 1, for ``scenes`` at ``levels``."""
    for level in levels:
        (pred / level).mkdir(parents=True, exist_ok=True)
        for scene in scenes:
            lines = (dataset / "labels" / level / f"{scene}.txt").read_text().splitlines()
            (pred / level / f"{scene}.txt").write_text("".join(f"{ln} 1.0\n" for ln in lines))


def _json_out(capsys) -> dict:
    out = capsys.readouterr().out
    return json.loads(out[out.index("{") :])


def test_a_split_holds_only_its_scenes(split_dataset):
    splits = _splits(split_dataset)
    for split, scenes in splits.items():
        data = load_dataset(split_dataset, split)
        assert data.split == split and data.members == frozenset(scenes)
        assert sorted(scene_images(data, "v0500")) == sorted(scenes)
    assert len(scene_images(load_dataset(split_dataset), "v0500")) == sum(map(len, splits.values()))


def test_eval_on_a_split_ignores_predictions_of_other_scenes(split_dataset, tmp_path, capsys):
    splits = _splits(split_dataset)
    pred = tmp_path / "pred"
    _perfect(split_dataset, pred, ("v0500",), splits["train"])
    # Wrong boxes for the other scenes: they would lower the score if they were read.
    for scene in splits["val"] + splits["test"]:
        (pred / "v0500" / f"{scene}.txt").write_text("0 0.5 0.5 0.1 0.1 0.99\n")
    args = ["metric", "eval", "--dataset", str(split_dataset), "--pred", str(pred), "--json"]
    assert main([*args, "--split", "train"]) == 0
    (level,) = _json_out(capsys)["levels"]
    assert level["images"] == len(splits["train"]) and level["map50"] == pytest.approx(1.0)
    assert main(args) == 0  # every scene: the wrong boxes count
    assert _json_out(capsys)["levels"][0]["map50"] < 1.0


def test_calibrate_on_a_split_records_it(split_dataset, tmp_path, capsys):
    test = _splits(split_dataset)["test"]
    pred, table = tmp_path / "pred", tmp_path / "t"
    _perfect(split_dataset, pred, ("v0500", "v2000"), test)
    args = ["metric", "calibrate", "--dataset", str(split_dataset), "--pred", str(pred)]
    assert main([*args, "--detector", "oracle", "--out", str(table), "--split", "test"]) == 0
    doc = json.loads(table.with_suffix(".json").read_text())
    assert doc["split"] == "test"
    assert [row["images"] for row in doc["levels"]] == [len(test), len(test)]
    assert all(row["map50"] == pytest.approx(1.0) for row in doc["levels"])


def test_an_unknown_split_is_one_line_exit_2(split_dataset, dataset, tmp_path, capsys):
    (tmp_path / "p").mkdir()
    base = ["metric", "eval", "--pred", str(tmp_path / "p")]
    assert main([*base, "--dataset", str(split_dataset), "--split", "holdout"]) == 2
    err = capsys.readouterr().err
    assert "--split 'holdout': the dataset's splits are train, val, test" in err
    assert err.count("\n") == 1
    assert main([*base, "--dataset", str(dataset), "--split", "test"]) == 2
    assert "the dataset's splits are all" in capsys.readouterr().err


def test_restored_images_are_found_by_scene_or_hazy_name(split_dataset, tmp_path):
    data = load_dataset(split_dataset)
    scenes = sorted(scene_images(data, "v0500"))
    restored = tmp_path / "restored"
    restored.mkdir()
    for i, scene in enumerate(scenes):  # both names restoration code keeps
        name = f"{scene}.png" if i % 2 else f"{scene}_v0500.png"
        shutil.copyfile(split_dataset / "images" / "v0500" / f"{scene}.png", restored / name)
    found = dehazed_images(restored, data, "v0500")
    assert sorted(found) == scenes
    assert all(found[s].stem.removesuffix("_v0500") == s for s in scenes)
    # Only a split's scenes are needed when the dataset is opened with it.
    test = load_dataset(split_dataset, "test")
    assert sorted(dehazed_images(restored, test, "v0500")) == sorted(test.members)

    (restored / "stranger.png").write_bytes((restored / found[scenes[0]].name).read_bytes())
    with pytest.raises(MetricInputError, match=r"stranger\.png: not an image of a scene"):
        dehazed_images(restored, data, "v0500")
    (restored / "stranger.png").unlink()
    found[scenes[0]].unlink()
    with pytest.raises(
        MetricInputError, match=re.escape(f"{scenes[0]}.png: missing: 1 of 6 scenes")
    ):
        dehazed_images(restored, data, "v0500")


def test_model_flags_check_their_input_first(split_dataset, tmp_path, capsys):
    ds = str(split_dataset)
    out = ["--pred", str(tmp_path / "p"), "--out", str(tmp_path / "t")]
    assert main(["metric", "calibrate", "--dataset", ds, "--model", "none.pt", *out]) == 2
    assert "none.pt: weights file not found" in capsys.readouterr().err
    assert main(["metric", "calibrate", "--dataset", ds, *out]) == 2
    assert "--detector NAME is needed without --model" in capsys.readouterr().err
    newvis = ["metric", "newvis", "--table", "t.json", "--dataset", ds, "--level", "v0500"]
    assert main([*newvis, "--pred", str(tmp_path / "p"), "--model", "w.pt"]) == 2
    assert "--model and --images go together" in capsys.readouterr().err
    assert not (tmp_path / "p").exists()


@pytest.mark.skipif(
    importlib.util.find_spec("ultralytics") is not None, reason="ultralytics is installed"
)
def test_model_without_ultralytics_says_how_to_install_it(split_dataset, tmp_path, capsys):
    weights = tmp_path / "w.pt"
    weights.write_bytes(b"not read")
    args = ["metric", "calibrate", "--dataset", str(split_dataset), "--model", str(weights)]
    assert main([*args, "--pred", str(tmp_path / "p"), "--out", str(tmp_path / "t")]) == 2
    err = capsys.readouterr().err
    assert "pip install 'seahaze[detect]'" in err and err.count("\n") == 1


def test_model_letterboxes_into_yolo_vals_rectangle():
    from seahaze.metric.detect import val_canvas

    # ceil(side * imgsz / stride + 0.5) * stride, side 1 for the long side (Ultralytics 8.4)
    assert val_canvas(180 / 320, 180 / 320, 320, 32) == (224, 352)  # predict: 192 x 320
    assert val_canvas(36 / 64, 36 / 64, 64, 32) == (64, 96)
    assert val_canvas(720 / 1280, 720 / 1280, 640, 32) == (384, 672)
    assert val_canvas(1.0, 1.0, 640, 32) == (672, 672)
    assert val_canvas(2.0, 2.0, 320, 32) == (352, 192)  # portrait
    assert val_canvas(0.5, 2.0, 320, 32) == (352, 352)  # a batch of both: square
