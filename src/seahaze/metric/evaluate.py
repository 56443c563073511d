"""mAP50 / mAP50-95 of YOLO-format predictions with a maintained COCO evaluator.

AP is computed by ``faster_coco_eval`` (a C++ port of pycocotools' ``COCOeval`` that gives the
same numbers): bounding-box AP with 101-point interpolated precision, averaged over the classes
that have ground truth; mAP50 at IoU 0.50, mAP50-95 over IoU 0.50:0.05:0.95. seahaze only
converts YOLO files to COCO dictionaries and reads the evaluator's result; it does not compute
AP itself. See docs/metric.md for how this differs from Ultralytics' own mAP.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import faster_coco_eval
import numpy as np
from faster_coco_eval import COCO, COCOeval_faster

from seahaze.metric.errors import MetricInputError, located
from seahaze.metric.reader import (
    PAPER_LABELS,
    Dataset,
    ImageTruth,
    YoloBox,
    level_visibility_m,
    load_level_truth,
    load_predictions,
    outside_split,
    prediction_dir,
    sort_levels,
)
from seahaze.metric.table import CalibrationPoint, CalibrationTable, make_table
from seahaze.visibility import CLEAN_LEVEL, is_level_name

DEFAULT_MAX_DETS = 100
"""Detections kept per image and class, highest confidence first (the COCO default)."""


def evaluator_name(max_dets: int = DEFAULT_MAX_DETS) -> str:
    """The evaluator tag stored in calibration tables (which AP implementation and settings)."""
    return (
        f"faster_coco_eval {faster_coco_eval.__version__}: COCO bbox AP, 101-point "
        f"interpolation, maxDets={max_dets}"
    )


def same_evaluator(tag: str | None, max_dets: int = DEFAULT_MAX_DETS) -> bool:
    """Whether a table's evaluator tag is this module's COCO evaluator with ``max_dets``
    (any faster_coco_eval version: they all reproduce pycocotools)."""
    return (
        tag is not None
        and tag.startswith("faster_coco_eval ")
        and tag.endswith(f"maxDets={max_dets}")
    )


@dataclass(frozen=True)
class CocoScores:
    """COCO detection scores of one image set."""

    map50: float | None
    """mAP at IoU 0.50; None when the set has no ground-truth object."""
    map50_95: float | None
    """mAP averaged over IoU 0.50:0.05:0.95; None when there is no ground-truth object."""
    ap50_per_class: dict[str, float] = field(default_factory=dict)
    """AP50 of each class that has ground truth."""
    images: int = 0
    objects: int = 0
    detections: int = 0


def build_coco(
    truth: Sequence[ImageTruth],
    predictions: Mapping[str, Sequence[YoloBox]],
    class_names: Sequence[str],
) -> tuple[dict[str, list[dict[str, object]]], list[dict[str, object]]]:
    """COCO ground-truth dictionary and detection list for YOLO boxes.

    Boxes are converted to pixels with each image's own size. Ids start at 1 because
    pycocotools treats a matched ground-truth id of 0 as "unmatched"; category id = class + 1.
    Predictions for scenes not in ``truth`` raise :class:`MetricInputError`.
    """
    images, annotations, detections = [], [], []
    index = {img.name: i for i, img in enumerate(truth, start=1)}
    unknown = sorted(set(predictions) - set(index))
    if unknown:
        raise MetricInputError(f"predictions for scenes without ground truth: {unknown[:3]}")
    for image_id, img in enumerate(truth, start=1):
        images.append(
            {"id": image_id, "file_name": img.name, "width": img.width, "height": img.height}
        )
        for box in img.boxes:
            x, y, w, h = box.to_pixels(img.width, img.height)
            annotations.append(
                {
                    "id": len(annotations) + 1,
                    "image_id": image_id,
                    "category_id": box.class_id + 1,
                    "bbox": [x, y, w, h],
                    "area": w * h,
                    "iscrowd": 0,
                }
            )
    for name, boxes in predictions.items():
        img = truth[index[name] - 1]
        for box in boxes:
            x, y, w, h = box.to_pixels(img.width, img.height)
            detections.append(
                {
                    "image_id": index[name],
                    "category_id": box.class_id + 1,
                    "bbox": [x, y, w, h],
                    "score": box.conf,
                }
            )
    categories = [{"id": i + 1, "name": n} for i, n in enumerate(class_names)]
    return {"images": images, "annotations": annotations, "categories": categories}, detections


def _quiet(*_args: object, **_kwargs: object) -> None:
    """A print function that prints nothing (the evaluators log every step)."""


def coco_scores(
    truth: Sequence[ImageTruth],
    predictions: Mapping[str, Sequence[YoloBox]],
    class_names: Sequence[str],
    *,
    max_dets: int = DEFAULT_MAX_DETS,
) -> CocoScores:
    """mAP50, mAP50-95 and per-class AP50 of ``predictions`` against ``truth`` (faster_coco_eval).

    ``max_dets`` caps the detections per image and class (highest confidence first), COCO's
    ``maxDets``. The maps are None when there is no ground-truth object at all.
    """
    if max_dets < 1:
        raise MetricInputError(f"--max-dets must be >= 1, got {max_dets}")
    gt_dict, dt_list = build_coco(truth, predictions, class_names)
    n_obj, n_det = len(gt_dict["annotations"]), len(dt_list)
    if n_obj == 0:
        return CocoScores(None, None, {}, len(truth), 0, n_det)
    gt = COCO(gt_dict, print_function=_quiet)
    dt = gt.loadRes(dt_list)
    ev = COCOeval_faster(gt, dt, iouType="bbox", print_function=_quiet)
    # The summary reads maxDets[-1]; keep COCO's 1 and 10 below it for the AR entries.
    ev.params.maxDets = [d for d in (1, 10) if d < max_dets] + [max_dets]
    ev.evaluate()
    ev.accumulate()
    ev.summarize()
    # stats[0] = AP@[.50:.95], stats[1] = AP@.50, both at area 'all' and maxDets[-1].
    map50_95, map50 = float(ev.stats[0]), float(ev.stats[1])
    return CocoScores(map50, map50_95, _per_class_ap50(ev, class_names), len(truth), n_obj, n_det)


def _per_class_ap50(ev: COCOeval_faster, class_names: Sequence[str]) -> dict[str, float]:
    """AP50 per class from the evaluator's accumulated precision[T, R, K, A, M] array (mean
    over the 101 recall thresholds, as COCO's own summary does; -1 marks classes without GT)."""
    precision = np.asarray(ev.eval["precision"])
    t = int(np.argmin(np.abs(np.asarray(ev.params.iouThrs) - 0.5)))
    out: dict[str, float] = {}
    for k, cat_id in enumerate(ev.params.catIds):
        p = precision[t, :, k, 0, -1]
        if np.all(p > -1):
            out[class_names[int(cat_id) - 1]] = float(np.mean(p))
    return out


@dataclass(frozen=True)
class LevelResult:
    """Scores of one level's prediction set."""

    level: str
    visibility_m: float | None
    """None for the clean level."""
    scores: CocoScores
    pred_dir: Path


def evaluate_level(
    dataset: Dataset,
    level: str,
    pred_root: Path | str,
    *,
    allow_flat: bool = False,
    max_dets: int = DEFAULT_MAX_DETS,
) -> LevelResult:
    """Score the predictions of one level against the dataset's labels.

    Predictions are read from ``pred_root/<level>/`` or, when ``allow_flat``, from ``pred_root``
    itself. Raises :class:`MetricInputError` for missing or malformed files.
    """
    if level not in dataset.levels:
        raise located(
            dataset.root / "images" / level,
            f"level {level!r} not in the dataset (levels: {', '.join(dataset.levels)})",
        )
    truth = load_level_truth(dataset, level)
    folder = prediction_dir(pred_root, level, allow_flat=allow_flat)
    skipped = outside_split(dataset, level)
    preds = load_predictions(folder, (t.name for t in truth), len(dataset.names), skipped)
    scores = coco_scores(truth, preds, dataset.names, max_dets=max_dets)
    return LevelResult(level, level_visibility_m(level), scores, folder)


def prediction_levels(dataset: Dataset, pred_root: Path | str) -> list[str]:
    """Dataset levels that have a folder under ``pred_root``, clean first then by visibility."""
    root = Path(pred_root)
    if not root.is_dir():
        raise located(root, "prediction folder not found")
    found = [p.name for p in root.iterdir() if p.is_dir() and is_level_name(p.name)]
    unknown = sorted(set(found) - set(dataset.levels))
    if unknown:
        raise located(
            root / unknown[0],
            f"level folder not in the dataset (levels: {', '.join(dataset.levels)})",
        )
    return sort_levels(found)


def evaluate_dataset(
    dataset: Dataset,
    pred_root: Path | str,
    *,
    level: str | None = None,
    max_dets: int = DEFAULT_MAX_DETS,
) -> list[LevelResult]:
    """Score every level that has predictions (or only ``level``, where ``pred_root`` may also be
    a flat folder of that level's files). Raises if there is nothing to evaluate."""
    if level is not None:
        return [evaluate_level(dataset, level, pred_root, allow_flat=True, max_dets=max_dets)]
    levels = prediction_levels(dataset, pred_root)
    if not levels:
        raise located(
            pred_root,
            "no level folders (clean, v0300, ...); use PRED/<level>/"
            "<scene>.txt, or pass --level for a folder of one level",
        )
    return [evaluate_level(dataset, lv, pred_root, max_dets=max_dets) for lv in levels]


def check_calibratable(dataset: Dataset, detector: str) -> None:
    """Raise :class:`MetricInputError` unless a table can be built: a detector name and at
    least 2 hazy levels (checked before a detector runs on every level)."""
    if not detector.strip():
        raise MetricInputError("--detector must name the detector (e.g. yolo11n)")
    hazy = dataset.hazy_levels
    if len(hazy) < 2:
        raise located(
            dataset.root / "images", f"calibration needs at least 2 hazy levels, found {len(hazy)}"
        )


def calibrate(
    dataset: Dataset, pred_root: Path | str, detector: str, *, max_dets: int = DEFAULT_MAX_DETS
) -> tuple[CalibrationTable, list[LevelResult]]:
    """Build the visibility → mAP50 table of a detector from its predictions on every hazy level
    of the dataset (paper, Stage 1).

    Every hazy level needs ``pred_root/<level>/`` (a missing folder is an error, not a zero);
    the clean level is scored too when its folder exists and is kept in the JSON as a reference.
    A dataset opened with ``labels="visible"`` is scored against its visible-object labels, and
    the table records ``labels: visible``.
    """
    check_calibratable(dataset, detector)
    hazy = dataset.hazy_levels
    results = [evaluate_level(dataset, lv, pred_root, max_dets=max_dets) for lv in hazy]
    points = []
    for r in results:
        if r.scores.map50 is None or r.visibility_m is None:
            raise located(
                dataset.label_dir(r.level),
                "no labelled objects at this level, so its mAP50 is undefined",
            )
        points.append(
            CalibrationPoint(
                r.visibility_m,
                r.scores.map50,
                level=r.level,
                map50_95=r.scores.map50_95,
                images=r.scores.images,
                objects=r.scores.objects,
                detections=r.scores.detections,
            )
        )
    extra: dict[str, object] = {} if dataset.split is None else {"split": dataset.split}
    if dataset.labels != PAPER_LABELS:
        # Only the other protocol is recorded: a table of the paper's protocol keeps the bytes
        # it always had, and a table without the key is read as the paper's (table_labels).
        extra["labels"] = dataset.labels
    if CLEAN_LEVEL in dataset.levels and (Path(pred_root) / CLEAN_LEVEL).is_dir():
        clean = evaluate_level(dataset, CLEAN_LEVEL, pred_root, max_dets=max_dets)
        results.insert(0, clean)
        extra["clean"] = {
            "map50": clean.scores.map50,
            "map50_95": clean.scores.map50_95,
            "images": clean.scores.images,
            "objects": clean.scores.objects,
        }
    table = make_table(
        points,
        detector=detector.strip(),
        evaluator=evaluator_name(max_dets),
        dataset=str(Path(dataset.root).resolve()),
        extra=extra,
    )
    return table, results


def table_labels(table: CalibrationTable) -> str:
    """The ground truth (``--labels``) a table was calibrated against: its ``labels`` entry,
    else ``paper`` (tables of the paper's protocol, CSV files and published tables have none)."""
    value = table.extra.get("labels", PAPER_LABELS)
    return value if isinstance(value, str) else PAPER_LABELS


def format_score(value: float | None) -> str:
    """A score for tables: 4 decimals, or ``n/a`` when undefined."""
    return "n/a" if value is None or math.isnan(value) else f"{value:.4f}"
