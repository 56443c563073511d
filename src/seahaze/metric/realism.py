"""How a detector trained on photographs scores seahaze's vessels: the realism benchmark's
arithmetic, by vessel class, box height and level.

The detector knows COCO's classes, not seahaze's: every vessel class is COCO's ``boat``, so the
scores are class-agnostic (a detection of ``boat`` finds a vessel of any class). A group of
vessels (one class, one band of box heights, one level) is scored with the others kept as
COCO's *crowd* regions: a ``boat`` detection on a vessel outside the group is neither a hit nor
a false positive, the way COCO treats the objects an evaluation leaves out. AP50 and recall
are ``faster_coco_eval``'s (pycocotools' ``COCOeval``): IoU 0.5, up to 100 detections per
image, recall over every score the detector kept.

A vessel is *confused* when the detection of highest score that covers its box (IoU ≥ 0.5,
any class) is not ``boat``: a container ship read as a ``train``, a ferry as an ``airplane``.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from faster_coco_eval import COCO, COCOeval_faster

from seahaze.metric.centernet import VESSEL_LABEL, Detection

IOU_THRESHOLD = 0.5
"""Overlap a detection needs with a vessel's box to find it (COCO's AP50)."""

MAX_DETECTIONS = 100
"""Detections per image the scores consider, highest score first (COCO's ``maxDets``)."""

HEIGHT_BANDS: tuple[tuple[str, float, float], ...] = (
    ("< 8 px", 0.0, 8.0),
    ("8–16 px", 8.0, 16.0),
    ("16–32 px", 16.0, 32.0),
    ("≥ 32 px", 32.0, math.inf),
)
"""Bands of box height (pixels): name, lower bound (inclusive), upper bound (exclusive)."""


@dataclass(frozen=True)
class Vessel:
    """One labelled vessel: the image it is in, its class and its box (pixels, corners)."""

    image: str
    cls: str
    x0: float
    y0: float
    x1: float
    y1: float

    @property
    def height_px(self) -> float:
        return self.y1 - self.y0

    @property
    def band(self) -> str:
        """The name of the :data:`HEIGHT_BANDS` band its box height falls in."""
        return height_band(self.height_px)


@dataclass(frozen=True)
class GroupScore:
    """Scores of one group of vessels."""

    vessels: int
    ap50: float | None
    """AP at IoU 0.5 (None without vessels)."""
    recall: float | None
    """Share of the group's vessels found at IoU 0.5 by some ``boat`` detection."""


def height_band(height_px: float) -> str:
    """Name of the band of :data:`HEIGHT_BANDS` that holds a box ``height_px`` high."""
    for name, low, high in HEIGHT_BANDS:
        if low <= height_px < high:
            return name
    raise ValueError(f"box height must be >= 0 px, got {height_px}")


def iou(a: Vessel | Detection, b: Vessel | Detection) -> float:
    """Intersection over union of two boxes given by their corners."""
    w = min(a.x1, b.x1) - max(a.x0, b.x0)
    h = min(a.y1, b.y1) - max(a.y0, b.y0)
    if w <= 0.0 or h <= 0.0:
        return 0.0
    inter = w * h
    union = (a.x1 - a.x0) * (a.y1 - a.y0) + (b.x1 - b.x0) * (b.y1 - b.y0) - inter
    return inter / union


def _quiet(*_args: object, **_kwargs: object) -> None:
    """A print function that prints nothing (the evaluator logs every step)."""


def score_group(
    vessels: Sequence[Vessel],
    detections: Mapping[str, Sequence[Detection]],
    in_group: Callable[[Vessel], bool],
) -> GroupScore:
    """AP50 and recall of the ``boat`` detections on the vessels for which ``in_group`` is
    true, the other vessels kept as crowd regions (module docstring). ``detections``: every
    image's detections, by the image names the vessels carry (images without vessels count
    too: their detections are false positives)."""
    counted = sum(1 for v in vessels if in_group(v))
    if counted == 0:
        return GroupScore(0, None, None)
    names = sorted(set(detections) | {v.image for v in vessels})
    index = {name: i for i, name in enumerate(names, start=1)}
    annotations = [
        {
            "id": i,
            "image_id": index[v.image],
            "category_id": 1,
            "bbox": [v.x0, v.y0, v.x1 - v.x0, v.y1 - v.y0],
            "area": (v.x1 - v.x0) * (v.y1 - v.y0),
            "iscrowd": 0 if in_group(v) else 1,
        }
        for i, v in enumerate(vessels, start=1)
    ]
    found = [
        {
            "image_id": index[name],
            "category_id": 1,
            "bbox": [d.x0, d.y0, d.x1 - d.x0, d.y1 - d.y0],
            "score": d.score,
        }
        for name, dets in detections.items()
        for d in dets
        if d.label == VESSEL_LABEL and d.x1 > d.x0 and d.y1 > d.y0
    ]
    truth = {
        "images": [{"id": i, "file_name": n} for n, i in index.items()],
        "annotations": annotations,
        "categories": [{"id": 1, "name": VESSEL_LABEL}],
    }
    if not found:
        return GroupScore(counted, 0.0, 0.0)
    gt = COCO(truth, print_function=_quiet)
    ev = COCOeval_faster(gt, gt.loadRes(found), iouType="bbox", print_function=_quiet)
    ev.params.iouThrs = np.array([IOU_THRESHOLD])
    ev.params.maxDets = [MAX_DETECTIONS]
    ev.evaluate()
    ev.accumulate()
    # precision[T, R, K, A, M] over 101 recall points, recall[T, K, A, M]; area "all".
    precision = np.asarray(ev.eval["precision"])[0, :, 0, 0, -1]
    recall = float(np.asarray(ev.eval["recall"])[0, 0, 0, -1])
    ap50 = float(np.mean(np.maximum(precision, 0.0)))
    return GroupScore(counted, ap50, max(recall, 0.0))


def confusion(
    vessels: Sequence[Vessel], detections: Mapping[str, Sequence[Detection]]
) -> dict[str, Counter[str]]:
    """For each vessel class, how many of its vessels each COCO class other than ``boat``
    took (module docstring: the covering detection of highest score is not ``boat``)."""
    out: dict[str, Counter[str]] = {}
    for v in vessels:
        covering = [d for d in detections.get(v.image, ()) if iou(v, d) >= IOU_THRESHOLD]
        counts = out.setdefault(v.cls, Counter())
        if covering:
            best = max(covering, key=lambda d: d.score)
            if best.label != VESSEL_LABEL:
                counts[best.label] += 1
    return out
