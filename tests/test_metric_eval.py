"""mAP of YOLO predictions (faster_coco_eval), dataset reading, and the eval/calibrate/newvis CLI.

Expected AP values are worked out by hand from the COCO definition: detections of a class are
ranked by confidence; precision is made monotone (each value replaced by the maximum to its
right); AP is the mean, over the 101 recall thresholds r = 0, 0.01, ..., 1, of that precision at
the first rank whose recall reaches r (0 when recall never reaches r).
"""

from __future__ import annotations

import argparse
import copy
import json
import random
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from seahaze.metric import cli as metric_cli
from seahaze.metric.errors import MetricInputError
from seahaze.metric.evaluate import build_coco, coco_scores
from seahaze.metric.reader import ImageTruth, YoloBox, load_dataset, load_level_truth

NAMES = ["container_ship", "fishing_boat", "buoy"]

# Two scenes, four class-0 objects in all (normalised cx, cy, w, h).
OBJECTS = {
    "a": [(0.2, 0.3, 0.1, 0.1), (0.6, 0.5, 0.2, 0.1)],
    "b": [(0.3, 0.7, 0.1, 0.2), (0.8, 0.2, 0.1, 0.1)],
}
FAR = (0.95, 0.95, 0.05, 0.05)  # overlaps no object


def _truth(sizes: dict[str, tuple[int, int]] | None = None) -> list[ImageTruth]:
    sizes = sizes or {"a": (200, 100), "b": (160, 120)}
    return [
        ImageTruth(name, *sizes[name], tuple(YoloBox(0, *box) for box in boxes))
        for name, boxes in OBJECTS.items()
    ]


def _pred(box: tuple[float, float, float, float], conf: float, cls: int = 0) -> YoloBox:
    return YoloBox(cls, *box, conf)


HALF_MISSED = {  # 2 of 4 objects found, plus the most confident detection a false positive
    "a": [_pred(FAR, 0.95), _pred(OBJECTS["a"][0], 0.9)],
    "b": [_pred(OBJECTS["b"][0], 0.8)],
}
# Ranks: FP, TP, TP -> recall 0, 1/4, 2/4; precision 0, 1/2, 2/3 -> monotone 2/3, 2/3, 2/3.
# Thresholds r <= 0.5 (51 of 101) get 2/3, the rest 0: AP = 51/101 * 2/3 = 34/101.
AP_HALF_MISSED = 34 / 101

THREE_OF_FOUR = {  # 3 of 4 found behind one confident false positive
    "a": [_pred(FAR, 0.95), _pred(OBJECTS["a"][0], 0.9), _pred(OBJECTS["a"][1], 0.7)],
    "b": [_pred(OBJECTS["b"][0], 0.8)],
}
# Recall 0, 1/4, 2/4, 3/4; precision 0, 1/2, 2/3, 3/4 -> monotone 3/4 up to recall 0.75
# (76 thresholds): AP = 76/101 * 3/4 = 57/101.
AP_THREE_OF_FOUR = 57 / 101

PERFECT = {name: [_pred(box, 0.9) for box in boxes] for name, boxes in OBJECTS.items()}


def test_perfect_predictions_score_one() -> None:
    s = coco_scores(_truth(), PERFECT, NAMES)
    assert (s.map50, s.map50_95) == (pytest.approx(1.0), pytest.approx(1.0))
    assert (s.images, s.objects, s.detections) == (2, 4, 4)


def test_half_missed_with_a_confident_false_positive() -> None:
    s = coco_scores(_truth(), HALF_MISSED, NAMES)
    assert s.map50 == pytest.approx(AP_HALF_MISSED, abs=1e-12)
    assert s.map50_95 == pytest.approx(AP_HALF_MISSED, abs=1e-12)  # exact boxes: every IoU
    assert s.ap50_per_class == {"container_ship": pytest.approx(AP_HALF_MISSED)}
    assert coco_scores(_truth(), THREE_OF_FOUR, NAMES).map50 == pytest.approx(AP_THREE_OF_FOUR)


def test_no_predictions_and_no_objects() -> None:
    assert coco_scores(_truth(), {}, NAMES).map50 == 0.0
    empty = [ImageTruth("a", 10, 10, ())]
    s = coco_scores(empty, {"a": [_pred(FAR, 0.5)]}, NAMES)
    assert s.map50 is None and s.map50_95 is None and s.detections == 1


def test_iou_thresholds_for_map50_95() -> None:
    # A 100x100 px box and a prediction shifted 20 px: IoU = 80/120 = 2/3, a match at IoU
    # 0.50, 0.55, 0.60, 0.65 but not 0.70..0.95 -> AP 1 at 4 of 10 thresholds.
    truth = [ImageTruth("a", 400, 200, (YoloBox(0, 0.25, 0.5, 0.25, 0.5),))]
    pred = {"a": [YoloBox(0, 0.25 + 20 / 400, 0.5, 0.25, 0.5, 0.9)]}
    s = coco_scores(truth, pred, NAMES)
    assert s.map50 == pytest.approx(1.0) and s.map50_95 == pytest.approx(0.4)


def test_mean_over_classes_with_ground_truth() -> None:
    # Class 1 found perfectly; class 0 as HALF_MISSED; a class-2 detection (no class-2 object
    # anywhere) is ignored, as in COCO and Ultralytics.
    truth = _truth()
    truth[0] = ImageTruth("a", 200, 100, (*truth[0].boxes, YoloBox(1, 0.5, 0.2, 0.1, 0.1)))
    preds = copy.deepcopy(HALF_MISSED)
    preds["a"] += [YoloBox(1, 0.5, 0.2, 0.1, 0.1, 0.3), _pred(FAR, 0.99, cls=2)]
    s = coco_scores(truth, preds, NAMES)
    assert s.ap50_per_class == {
        "container_ship": pytest.approx(AP_HALF_MISSED),
        "fishing_boat": pytest.approx(1.0),
    }
    assert s.map50 == pytest.approx((1 + AP_HALF_MISSED) / 2)


def test_max_dets_keeps_the_most_confident() -> None:
    # One object; two confident false positives rank above the true positive.
    truth = [ImageTruth("a", 100, 100, (YoloBox(0, 0.5, 0.5, 0.2, 0.2),))]
    preds = {
        "a": [_pred(FAR, 0.9), _pred((0.1, 0.1, 0.1, 0.1), 0.8), _pred((0.5, 0.5, 0.2, 0.2), 0.7)]
    }
    assert coco_scores(truth, preds, NAMES).map50 == pytest.approx(1 / 3)  # precision 1/3
    assert coco_scores(truth, preds, NAMES, max_dets=2).map50 == 0.0


def test_build_coco_uses_each_image_size() -> None:
    gt, dt = build_coco(_truth(), {"b": [_pred(OBJECTS["b"][0], 0.8)]}, NAMES)
    assert [(i["width"], i["height"]) for i in gt["images"]] == [(200, 100), (160, 120)]
    assert gt["annotations"][0]["bbox"] == pytest.approx([30, 25, 20, 10])
    assert gt["annotations"][0]["id"] == 1 and gt["annotations"][0]["category_id"] == 1
    assert dt[0]["image_id"] == 2 and dt[0]["bbox"] == pytest.approx([40, 72, 16, 24])
    with pytest.raises(MetricInputError, match="without ground truth"):
        build_coco(_truth(), {"zzz": []}, NAMES)


def _random_set(seed: int) -> tuple[list[ImageTruth], dict[str, list[YoloBox]]]:
    rng = random.Random(seed)
    truth, preds = [], {}
    for i in range(25):
        boxes = tuple(
            YoloBox(
                rng.randrange(3),
                rng.uniform(0.2, 0.8),
                rng.uniform(0.2, 0.8),
                rng.uniform(0.05, 0.3),
                rng.uniform(0.05, 0.3),
            )
            for _ in range(rng.randrange(0, 5))
        )
        truth.append(ImageTruth(f"s{i}", rng.choice([640, 320]), rng.choice([480, 240]), boxes))
        found = [
            YoloBox(
                b.class_id if rng.random() > 0.1 else rng.randrange(3),
                b.cx + rng.gauss(0, 0.02),
                b.cy + rng.gauss(0, 0.02),
                b.w * rng.uniform(0.8, 1.2),
                b.h * rng.uniform(0.8, 1.2),
                rng.random(),
            )
            for b in boxes
            if rng.random() > 0.3
        ]
        found += [
            YoloBox(rng.randrange(3), rng.random(), rng.random(), 0.1, 0.1, rng.random())
            for _ in range(rng.randrange(0, 3))
        ]
        preds[f"s{i}"] = found
    return truth, preds


@pytest.mark.parametrize("seed", [1, 2])
def test_faster_coco_eval_matches_pycocotools(seed: int) -> None:
    pycoco = pytest.importorskip("pycocotools.cocoeval")
    from pycocotools.coco import COCO

    truth, preds = _random_set(seed)
    ours = coco_scores(truth, preds, NAMES)
    gt_dict, dt_list = build_coco(truth, preds, NAMES)
    gt = COCO()
    gt.dataset = copy.deepcopy(gt_dict)
    gt.createIndex()
    ev = pycoco.COCOeval(gt, gt.loadRes(copy.deepcopy(dt_list)), "bbox")
    ev.evaluate()
    ev.accumulate()
    ev.summarize()
    assert 0.1 < ours.map50 < 0.99  # a non-trivial case
    assert ours.map50 == pytest.approx(ev.stats[1], abs=1e-12)
    assert ours.map50_95 == pytest.approx(ev.stats[0], abs=1e-12)


# ---------------------------------------------------------------- datasets on disk

LEVELS = ("clean", "v0300", "v0500", "v1000")


def _write_yolo(path: Path, rows: Sequence[Sequence[float]]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("".join(" ".join(f"{v:g}" for v in row) + "\n" for row in rows))


def _write_preds(root: Path, level: str, preds: dict[str, list[YoloBox]]) -> None:
    for name, boxes in preds.items():
        _write_yolo(
            root / level / f"{name}.txt",
            [(b.class_id, b.cx, b.cy, b.w, b.h, b.conf) for b in boxes],
        )


@pytest.fixture
def dataset(tmp_path: Path) -> Path:
    """A 4-level dataset whose levels all hold the two scenes of OBJECTS."""
    root = tmp_path / "ds"
    root.mkdir()
    names = "".join(f"  {i}: {n}\n" for i, n in enumerate(NAMES))
    splits = "".join(f"{lv}: images/{lv}\n" for lv in LEVELS)
    (root / "data.yaml").write_text(f"path: {root}\n{splits}names:\n{names}")
    for level in LEVELS:
        (root / "images" / level).mkdir(parents=True)
        for name, size in (("a", (40, 20)), ("b", (32, 24))):
            Image.new("RGB", size).save(root / "images" / level / f"{name}.png")
            _write_yolo(
                root / "labels" / level / f"{name}.txt", [(0, *box) for box in OBJECTS[name]]
            )
    return root


@pytest.fixture
def detector_preds(tmp_path: Path) -> Path:
    """A detector's predictions on the hazy levels: worse in denser haze (monotone table)."""
    root = tmp_path / "pred"
    for level, preds in (
        ("clean", PERFECT),
        ("v0300", HALF_MISSED),
        ("v0500", THREE_OF_FOUR),
        ("v1000", PERFECT),
    ):
        _write_preds(root, level, preds)
    return root


def _run(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="seahaze")
    metric_cli.register(parser.add_subparsers(dest="command"))
    args = parser.parse_args(argv)
    return args.func(args)


def test_load_dataset_reads_sizes_from_png(dataset: Path) -> None:
    ds = load_dataset(dataset)
    assert ds.names == tuple(NAMES) and ds.levels == LEVELS
    truth = load_level_truth(ds, "v0300")
    assert [(t.name, t.width, t.height, len(t.boxes)) for t in truth] == [
        ("a", 40, 20, 2),
        ("b", 32, 24, 2),
    ]


def test_cli_eval(dataset: Path, detector_preds: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert (
        _run(["metric", "eval", "--dataset", str(dataset), "--pred", str(detector_preds), "--json"])
        == 0
    )
    doc = json.loads(capsys.readouterr().out)
    got = {lv["level"]: lv["map50"] for lv in doc["levels"]}
    assert got == {
        "clean": pytest.approx(1.0),
        "v0300": pytest.approx(AP_HALF_MISSED),
        "v0500": pytest.approx(AP_THREE_OF_FOUR),
        "v1000": pytest.approx(1.0),
    }
    assert (
        _run(
            [
                "metric",
                "eval",
                "--dataset",
                str(dataset),
                "--pred",
                str(detector_preds / "v0300"),
                "--level",
                "300",
            ]
        )
        == 0
    )
    out = capsys.readouterr().out
    assert "v0300" in out and f"{AP_HALF_MISSED:.4f}" in out and "v0500" not in out


def test_cli_calibrate_then_newvis(
    dataset: Path, detector_preds: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "tables" / "toy"
    assert (
        _run(
            [
                "metric",
                "calibrate",
                "--dataset",
                str(dataset),
                "--pred",
                str(detector_preds),
                "--detector",
                "toy-det",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    capsys.readouterr()
    rows = (tmp_path / "tables" / "toy.csv").read_text().splitlines()
    assert rows[0] == "visibility_m,map50"
    assert [tuple(map(float, r.split(","))) for r in rows[1:]] == [
        (300, pytest.approx(AP_HALF_MISSED)),
        (500, pytest.approx(AP_THREE_OF_FOUR)),
        (1000, pytest.approx(1.0)),
    ]
    doc = json.loads((tmp_path / "tables" / "toy.json").read_text())
    assert doc["detector"] == "toy-det" and doc["clean"]["map50"] == pytest.approx(1.0)
    assert doc["evaluator"].startswith("faster_coco_eval")
    assert [lv["level"] for lv in doc["levels"]] == ["v0300", "v0500", "v1000"]

    # Dehazed v0300 images on which the detector does as well as at 500 m -> 500 m, +200 m.
    dehazed = tmp_path / "dehazed"
    _write_preds(dehazed, "v0300", THREE_OF_FOUR)
    assert (
        _run(
            [
                "metric",
                "newvis",
                "--table",
                str(out) + ".json",
                "--pred",
                str(dehazed),
                "--dataset",
                str(dataset),
                "--level",
                "v0300",
                "--json",
            ]
        )
        == 0
    )
    captured = capsys.readouterr()
    result = json.loads(captured.out)
    assert result["visibility_m"] == pytest.approx(500) and result["gain_m"] == pytest.approx(200)
    assert result["regulation"]["key"] == "restricted" and captured.err == ""

    # Eq. 5 between (300 m, 34/101) and (500 m, 57/101): 0.5 -> 300 + 16.5/23 * 200 m.
    assert (
        _run(["metric", "newvis", "--table", str(out) + ".csv", "--map", "0.5", "--level", "300"])
        == 0
    )
    text = capsys.readouterr().out
    assert f"new visibility: {round(300 + 16.5 / 23 * 200)} m" in text
    assert "Strict navigation restrictions" in text


def _error_line(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    return lines[0]


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ("0 0.5 0.5 0.1 0.1", "a.txt:2: expected 6 values 'class cx cy w h conf', got 5"),
        ("0 0.5 0.5 0.1 0.1 0.9 7", "a.txt:2: expected 6 values"),
        ("3 0.5 0.5 0.1 0.1 0.9", "a.txt:2: class 3 out of range; data.yaml names 3 classes"),
        ("x 0.5 0.5 0.1 0.1 0.9", "a.txt:2: class must be an integer in 0..2, got 'x'"),
        ("0 0.5 abc 0.1 0.1 0.9", "a.txt:2: cy must be a number, got 'abc'"),
        ("0 0.5 0.5 0.1 0.1 nan", "a.txt:2: conf must be a number in [0, 1]"),
        ("0 1.5 0.5 0.1 0.1 0.9", "a.txt:2: cx must be a number in [0, 1]"),
    ],
)
def test_cli_malformed_prediction_lines(
    dataset: Path, tmp_path: Path, line: str, message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    pred = tmp_path / "bad"
    pred.mkdir()
    (pred / "a.txt").write_text(f"0 0.2 0.3 0.1 0.1 0.9\n{line}\n")
    assert (
        _run(["metric", "eval", "--dataset", str(dataset), "--pred", str(pred), "--level", "v0300"])
        == 2
    )
    err = _error_line(capsys)
    assert err.startswith("seahaze metric eval: error: ") and message in err


def test_cli_bad_dataset_and_layout(
    dataset: Path, detector_preds: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    def fails(argv: list[str], message: str) -> None:
        assert _run(["metric", *argv]) == 2
        assert message in _error_line(capsys)

    ds, pred = str(dataset), str(detector_preds)
    fails(
        ["eval", "--dataset", str(tmp_path / "none"), "--pred", pred],
        "none: dataset folder not found",
    )
    fails(
        ["eval", "--dataset", ds, "--pred", pred, "--level", "v0400"],
        "level 'v0400' not in the dataset",
    )
    (detector_preds / "v0500" / "zzz.txt").write_text("")
    fails(["eval", "--dataset", ds, "--pred", pred], "zzz.txt: prediction for a scene that")
    (detector_preds / "v0500" / "zzz.txt").unlink()
    # A folder under a prediction's name once scored as "no detections".
    named = detector_preds / "v0500" / "b.txt"
    saved = named.read_bytes() if named.is_file() else None
    named.unlink(missing_ok=True)
    named.mkdir()
    fails(["eval", "--dataset", ds, "--pred", pred], "b.txt: not a file")
    named.rmdir()
    if saved is not None:
        named.write_bytes(saved)
    (dataset / "labels" / "v1000" / "b.txt").write_text("0 0.5 0.5 0 0.1\n")
    fails(["eval", "--dataset", ds, "--pred", pred], "b.txt:1: box width and height must be > 0")
    (dataset / "labels" / "v1000" / "b.txt").unlink()
    fails(["eval", "--dataset", ds, "--pred", pred], "b.txt: missing label file for b.png")
    (dataset / "data.yaml").write_text("path: .\n")
    fails(["eval", "--dataset", ds, "--pred", pred], "data.yaml: missing 'names'")
    (dataset / "data.yaml").unlink()
    fails(["eval", "--dataset", ds, "--pred", pred], "data.yaml: missing")


def test_cli_calibrate_needs_every_hazy_level(
    dataset: Path, detector_preds: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for f in (detector_preds / "v0500").iterdir():
        f.unlink()
    (detector_preds / "v0500").rmdir()
    assert (
        _run(
            [
                "metric",
                "calibrate",
                "--dataset",
                str(dataset),
                "--pred",
                str(detector_preds),
                "--detector",
                "d",
                "--out",
                str(tmp_path / "t"),
            ]
        )
        == 2
    )
    assert "v0500: missing, but" in _error_line(capsys)
    assert not (tmp_path / "t.csv").exists()


def test_cli_calibrate_reports_non_monotone(
    dataset: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pred = tmp_path / "p"
    for level, preds in (("v0300", THREE_OF_FOUR), ("v0500", HALF_MISSED), ("v1000", PERFECT)):
        _write_preds(pred, level, preds)
    assert (
        _run(
            [
                "metric",
                "calibrate",
                "--dataset",
                str(dataset),
                "--pred",
                str(pred),
                "--detector",
                "d",
                "--out",
                str(tmp_path / "t"),
            ]
        )
        == 0
    )
    err = capsys.readouterr().err
    assert "table is not monotone" in err and "300 m" in err and "500 m" in err


def test_cli_metric_without_subcommand_prints_help(capsys: pytest.CaptureFixture[str]) -> None:
    assert _run(["metric"]) == 2
    assert "calibrate" in capsys.readouterr().err


def test_image_sizes_do_not_change_ap() -> None:
    # IoU of axis-aligned boxes is invariant to scaling x and y, so only the labels matter.
    a = coco_scores(_truth({"a": (200, 100), "b": (160, 120)}), HALF_MISSED, NAMES)
    b = coco_scores(_truth({"a": (1920, 1080), "b": (64, 64)}), HALF_MISSED, NAMES)
    assert np.isclose(a.map50, b.map50)
