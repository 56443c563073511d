"""``seahaze metric``: eval, calibrate and newvis (the MSVD paper's visibility metric).

The main CLI calls :func:`register` with its subparsers and then ``args.func(args)``; every
handler returns an exit code: 0 on success, 2 on bad input (one line on stderr, no traceback).
All logic lives in :mod:`seahaze.metric.table`, :mod:`seahaze.metric.evaluate` and, for a
detector in the loop (``--model``), :mod:`seahaze.metric.detect`.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from functools import wraps
from pathlib import Path
from typing import TYPE_CHECKING

from seahaze.metric.errors import MetricInputError
from seahaze.metric.evaluate import (
    DEFAULT_MAX_DETS,
    LevelResult,
    calibrate,
    check_calibratable,
    evaluate_level,
    evaluator_name,
    format_score,
    same_evaluator,
    table_labels,
)
from seahaze.metric.evaluate import evaluate_dataset as evaluate_levels
from seahaze.metric.reader import (
    LABEL_FOLDERS,
    PAPER_LABELS,
    Dataset,
    dehazed_images,
    level_visibility_m,
    load_dataset,
    parse_level,
    scene_images,
)
from seahaze.metric.table import (
    Bound,
    CalibrationTable,
    class_range,
    describe,
    load_table,
    new_visibility,
    round_m,
    save_table,
)
from seahaze.visibility import CLEAN_LEVEL

if TYPE_CHECKING:  # imported on demand: it is the only module that needs Ultralytics
    from seahaze.metric.detect import Detector

Handler = Callable[[argparse.Namespace], int]
EXIT_INPUT = 2


def _guarded(command: str) -> Callable[[Handler], Handler]:
    """Turn :class:`MetricInputError` (and OS errors on our own files) into a one-line message
    on stderr and exit code 2, so bad input never shows a traceback."""

    def decorate(handler: Handler) -> Handler:
        @wraps(handler)
        def run(args: argparse.Namespace) -> int:
            try:
                return handler(args)
            except MetricInputError as exc:
                print(f"seahaze metric {command}: error: {exc}", file=sys.stderr)
            except OSError as exc:
                where = f"{exc.filename}: " if exc.filename else ""
                print(
                    f"seahaze metric {command}: error: {where}{exc.strerror or exc}",
                    file=sys.stderr,
                )
            return EXIT_INPUT

        return run

    return decorate


def _warn(message: str) -> None:
    print(f"warning: {message}", file=sys.stderr)


def _warn_non_monotone(table: CalibrationTable) -> None:
    """Report where mAP50 does not rise with visibility and the rule applied there."""
    bad = table.violations()
    if bad:
        pairs = ", ".join(
            f"{a.visibility_m:g} m ({a.map50:.4f}) -> {b.visibility_m:g} m ({b.map50:.4f})"
            for a, b in bad
        )
        _warn(
            f"table is not monotone: mAP50 does not increase at {pairs}; Eq. 5 is applied to "
            "its running maximum, taking the lowest visibility (docs/metric.md)"
        )


def _results_table(results: list[LevelResult]) -> list[str]:
    lines = [
        f"{'level':<8}{'vis_m':>7}{'images':>8}{'objects':>9}{'dets':>8}"
        f"{'mAP50':>9}{'mAP50-95':>10}"
    ]
    for r in results:
        s = r.scores
        vis = "-" if r.visibility_m is None else f"{r.visibility_m:g}"
        lines.append(
            f"{r.level:<8}{vis:>7}{s.images:>8}{s.objects:>9}{s.detections:>8}"
            f"{format_score(s.map50):>9}{format_score(s.map50_95):>10}"
        )
    return lines


def _result_json(r: LevelResult) -> dict[str, object]:
    s = r.scores
    return {
        "level": r.level,
        "visibility_m": r.visibility_m,
        "map50": s.map50,
        "map50_95": s.map50_95,
        "ap50_per_class": s.ap50_per_class,
        "images": s.images,
        "objects": s.objects,
        "detections": s.detections,
        "pred_dir": str(r.pred_dir),
    }


# --------------------------------------------------------------------------------------------
# a detector in the loop (--model)


def _detector(args: argparse.Namespace, dataset: Dataset) -> Detector:
    """The ``--model`` detector with the ``--imgsz``/``--device``/``--batch`` settings."""
    from seahaze.metric.detect import DetectorSettings, load_detector

    settings = DetectorSettings(imgsz=args.imgsz, device=args.device, batch=args.batch)
    return load_detector(args.model, dataset.names, settings)


def _run_detector(
    args: argparse.Namespace, dataset: Dataset, folders: dict[str, dict[str, Path]]
) -> dict[str, object]:
    """Run ``--model`` on ``folders`` (prediction folder → scene → image), writing the
    predictions under ``--pred``; returns what the table records about the run."""
    from seahaze.metric.detect import write_predictions

    detector = _detector(args, dataset)
    images = sum(len(v) for v in folders.values())
    detections, warnings = write_predictions(detector, folders, args.pred)
    for line in warnings:
        _warn(line)
    print(
        f"{detector.weights.name}: {detections} detections on {images} images "
        f"(conf >= {detector.settings.conf:g}, imgsz {detector.imgsz}) written to {args.pred}"
    )
    return detector.describe()


# --------------------------------------------------------------------------------------------
# eval


@_guarded("eval")
def cmd_eval(args: argparse.Namespace) -> int:
    """``seahaze metric eval``: mAP50 and mAP50-95 per level."""
    dataset = load_dataset(args.dataset, args.split, args.labels)
    level = parse_level(args.level) if args.level else None
    results = evaluate_levels(dataset, args.pred, level=level, max_dets=args.max_dets)
    if args.json:
        print(
            json.dumps(
                {
                    "evaluator": evaluator_name(args.max_dets),
                    "labels": dataset.labels,
                    "levels": [_result_json(r) for r in results],
                },
                indent=2,
            )
        )
    else:
        print("\n".join(_results_table(results)))
        print(f"({evaluator_name(args.max_dets)}{_truth_note(dataset)})")
    return 0


def _truth_note(dataset: Dataset) -> str:
    """What the scores were measured against, where it is not the paper's labels."""
    if dataset.labels == PAPER_LABELS:
        return ""  # the default's output stays as it was
    return f"; ground truth {LABEL_FOLDERS[dataset.labels]}/: the vessels each level's image shows"


# --------------------------------------------------------------------------------------------
# calibrate


@_guarded("calibrate")
def cmd_calibrate(args: argparse.Namespace) -> int:
    """``seahaze metric calibrate``: the detector's level → mAP50 table, saved as CSV + JSON;
    with ``--model`` the detector first predicts every level into ``--pred``."""
    dataset = load_dataset(args.dataset, args.split, args.labels)
    detector = args.detector or (args.model.stem if args.model else None)
    if detector is None:
        raise MetricInputError("--detector NAME is needed without --model (e.g. yolo11n)")
    check_calibratable(dataset, detector)
    run = None
    if args.model is not None:
        folders = {level: scene_images(dataset, level) for level in dataset.levels}
        run = _run_detector(args, dataset, folders)
    table, results = calibrate(dataset, args.pred, detector, max_dets=args.max_dets)
    if run is not None:
        table.extra["detector_run"] = run
    csv_path, json_path = save_table(table, args.out)
    print("\n".join(_results_table(results)))
    print(
        f"calibration table of {table.detector} ({len(table.points)} levels"
        f"{_truth_note(dataset)}) written to {csv_path} and {json_path}"
    )
    _warn_non_monotone(table)
    return 0


# --------------------------------------------------------------------------------------------
# newvis


@_guarded("newvis")
def cmd_newvis(args: argparse.Namespace) -> int:
    """``seahaze metric newvis``: New Visibility, gain and regulation class of a restored mAP50."""
    if (args.map is None) == (args.pred is None):
        raise MetricInputError("give either --map VALUE or --pred DIR (with --dataset and --level)")
    if (args.model is None) != (args.images is None):
        raise MetricInputError("--model and --images go together (with --pred, --dataset, --level)")
    table = load_table(args.table)
    level = parse_level(args.level) if args.level else None
    if level == CLEAN_LEVEL:
        raise MetricInputError(
            "--level clean has no visibility; give the hazy level the "
            "restored images came from (e.g. 800 or v0800)"
        )
    level_m = level_visibility_m(level) if level else None
    if args.pred is not None:
        if args.dataset is None or level is None:
            raise MetricInputError("--pred needs --dataset DIR and --level (e.g. v0800)")
        dataset = load_dataset(args.dataset, args.split, args.labels)
        if args.model is not None:
            folders = {level: dehazed_images(args.images, dataset, level)}
            _run_detector(args, dataset, folders)
        scores = evaluate_level(
            dataset, level, args.pred, allow_flat=True, max_dets=args.max_dets
        ).scores
        if scores.map50 is None:
            raise MetricInputError(
                f"{dataset.label_dir(level)}: no labelled objects, so mAP50 is undefined"
            )
        if not same_evaluator(table.evaluator, args.max_dets):
            # Not fatal: a CSV table carries no evaluator, but the user must know the values may
            # come from a different AP definition (e.g. Ultralytics' val).
            _warn(
                f"table {args.table} was not built by this evaluator "
                f"({table.evaluator or 'unknown'}); mAP50 from different evaluators is not "
                "interchangeable"
            )
        if table_labels(table) != dataset.labels:
            # Not fatal, as for the evaluator: a CSV table says nothing (read as the paper's),
            # but the two scores must come from the same ground truth to be compared.
            _warn(
                f"table {args.table} was calibrated against --labels {table_labels(table)} "
                f"({LABEL_FOLDERS[table_labels(table)]}/), the restored images are scored "
                f"against --labels {dataset.labels} ({LABEL_FOLDERS[dataset.labels]}/); mAP50 "
                "against different ground truths is not comparable"
            )
        value = scores.map50
    else:
        value = args.map
    result = new_visibility(table, value, level_m)
    _warn_non_monotone(table)
    if args.json:
        cls = result.regulation
        print(
            json.dumps(
                {
                    "detector": table.detector,
                    "map50": result.map50,
                    "bound": str(result.bound),
                    "visibility_m": result.visibility_m,
                    "visibility_m_rounded": round_m(result.visibility_m),
                    "level_m": result.level_m,
                    "gain_m": result.gain_m,
                    "regulation": {
                        "key": cls.key,
                        "label": cls.label,
                        "haze": cls.haze,
                        "range": class_range(cls),
                        "qualifier": {
                            Bound.WITHIN: None,
                            Bound.ABOVE: "at least",
                            Bound.BELOW: "at most",
                        }[result.bound],
                    },
                    "table_monotone": table.is_monotone,
                },
                indent=2,
            )
        )
    else:
        name = table.detector or Path(args.table).name
        lo, hi = table.points[0].visibility_m, table.points[-1].visibility_m
        print(f"table: {name} ({len(table.points)} levels, {lo:g}–{hi:g} m)")
        print("\n".join(describe(result, table)))
    return 0


def _cmd_help(parser: argparse.ArgumentParser) -> Handler:
    def run(_args: argparse.Namespace) -> int:
        parser.print_help(sys.stderr)
        return EXIT_INPUT

    return run


def _add_detector_flags(parser: argparse.ArgumentParser) -> None:
    """``--imgsz``, ``--device`` and ``--batch`` of a ``--model`` run."""
    parser.add_argument(
        "--imgsz",
        type=int,
        metavar="N",
        help="with --model: inference size in pixels (default: the model's training size)",
    )
    parser.add_argument(
        "--device", metavar="DEV", help="with --model: cpu, 0, cuda:0 … (default: Ultralytics')"
    )
    parser.add_argument(
        "--batch", type=int, default=16, metavar="N", help="with --model: images per batch (16)"
    )


def register(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``metric`` command (eval, calibrate, newvis) to the main CLI's subparsers."""
    metric = subparsers.add_parser(
        "metric",
        help="detector-based visibility metric (MSVD paper, Eq. 5)",
        description="Visibility metric of the MSVD paper: mAP50 per level (eval), a detector's "
        "visibility-mAP50 table (calibrate), and the New Visibility of restored "
        "images (newvis). See docs/metric.md.",
    )
    metric.set_defaults(func=_cmd_help(metric))
    sub = metric.add_subparsers(dest="metric_command", metavar="{eval,calibrate,newvis}")

    split = {
        "metavar": "NAME",
        "help": "only the scenes of this split of dataset.json (train, val, test; default: "
        "every scene, the paper's protocol)",
    }
    model = {
        "type": Path,
        "metavar": "WEIGHTS.pt",
        "help": "a trained Ultralytics detector: run it first as yolo val runs it (confidence "
        "0.001, IoU 0.7, 300 detections, its training image size) and write PRED_DIR's files "
        "(needs pip install 'seahaze[detect]'; docs/detectors.md)",
    }
    labels = {
        "choices": tuple(LABEL_FOLDERS),
        "default": PAPER_LABELS,
        "help": "ground truth: paper (labels/<level>/, every labelled vessel at every level: "
        "the MSVD paper's protocol, the default) or visible (labels_visible/<level>/, only "
        "the vessels seen in each level's image; needs a dataset rendered with "
        "labels.write_visible; docs/metric.md)",
    }
    max_dets = {
        "type": int,
        "default": DEFAULT_MAX_DETS,
        "metavar": "N",
        "help": f"detections kept per image and class, by confidence "
        f"(COCO maxDets; default {DEFAULT_MAX_DETS})",
    }

    ev = sub.add_parser(
        "eval",
        help="mAP50 and mAP50-95 of YOLO predictions per level",
        description="COCO mAP50 and mAP50-95 (faster_coco_eval) of YOLO-format "
        "predictions 'class cx cy w h conf' against the dataset's "
        "labels (--labels: every vessel, or the vessels each image shows), per level.",
    )
    ev.add_argument(
        "--dataset",
        required=True,
        type=Path,
        metavar="DIR",
        help="seahaze dataset (data.yaml, images/<level>/, labels/<level>/)",
    )
    ev.add_argument(
        "--pred",
        required=True,
        type=Path,
        metavar="PRED_DIR",
        help="predictions: PRED_DIR/<level>/<scene>.txt (or PRED_DIR/<scene>.txt with --level)",
    )
    ev.add_argument("--level", help="only this level (v1000, 1000 or clean)")
    ev.add_argument("--split", **split)
    ev.add_argument("--labels", **labels)
    ev.add_argument("--max-dets", **max_dets)
    ev.add_argument("--json", action="store_true", help="print JSON instead of a table")
    ev.set_defaults(func=cmd_eval)

    cal = sub.add_parser(
        "calibrate",
        help="build a detector's visibility -> mAP50 table",
        description="Score a detector's predictions on every hazy level and "
        "save the table as OUT.csv (visibility_m,map50) and "
        "OUT.json (with the detector's name).",
    )
    cal.add_argument("--dataset", required=True, type=Path, metavar="DIR")
    cal.add_argument(
        "--pred",
        required=True,
        type=Path,
        metavar="PRED_DIR",
        help="the detector's predictions on the hazy images: "
        "PRED_DIR/<level>/<scene>.txt for every level (written there with --model)",
    )
    cal.add_argument(
        "--detector",
        metavar="NAME",
        help="detector name stored in the table (e.g. yolo11n; default with --model: the "
        "weights file's name without suffix)",
    )
    cal.add_argument("--model", **model)
    _add_detector_flags(cal)
    cal.add_argument("--split", **split)
    cal.add_argument("--labels", **labels)
    cal.add_argument(
        "--out", required=True, type=Path, metavar="T", help="output path; writes T.csv and T.json"
    )
    cal.add_argument("--max-dets", **max_dets)
    cal.set_defaults(func=cmd_calibrate)

    nv = sub.add_parser(
        "newvis",
        help="New Visibility, gain and regulation class",
        description="Map a restored mAP50 (given, or computed from dehazed "
        "predictions) to a visibility with the calibration table "
        "(Eq. 5) and report the gain and regulation class.",
    )
    nv.add_argument(
        "--table", required=True, type=Path, metavar="T", help="calibration table (.json or .csv)"
    )
    nv.add_argument("--map", type=float, metavar="VALUE", help="restored mAP50 in [0, 1]")
    nv.add_argument(
        "--pred",
        type=Path,
        metavar="PRED_DIR",
        help="predictions on the dehazed images of --level (instead of --map)",
    )
    nv.add_argument("--dataset", type=Path, metavar="DIR", help="dataset for --pred")
    nv.add_argument("--level", help="visibility of the hazy input (800 or v0800)")
    nv.add_argument("--model", **model)
    nv.add_argument(
        "--images",
        type=Path,
        metavar="DIR",
        help="with --model: the restored images of --level, named <scene>.png or "
        "<scene>_<level>.png; the predictions go to PRED_DIR/<level>/",
    )
    _add_detector_flags(nv)
    nv.add_argument("--split", **split)
    nv.add_argument("--labels", **labels)
    nv.add_argument("--max-dets", **max_dets)
    nv.add_argument("--json", action="store_true", help="print JSON")
    nv.set_defaults(func=cmd_newvis)
