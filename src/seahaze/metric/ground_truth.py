"""The COCO ground-truth files of a dataset: ``coco/<level>.json``, one per level.

Built from the dataset's YOLO labels with the converter the metric evaluates with
(:func:`seahaze.metric.evaluate.build_coco`), so a perfect prediction set scores AP50 = 1 against
these files. ``file_name`` is relative to the dataset root. A sequence's frames also carry
their video, frame and track ids (:mod:`seahaze.dataset.tracks`).
"""

from __future__ import annotations

from pathlib import Path

from ..dataset.layout import Layout
from ..dataset.tracks import add_video_fields
from ..fileio import write_json
from .evaluate import build_coco
from .reader import load_dataset, load_level_truth


def write_coco(root: Path) -> None:
    """Write the COCO ground truth of every level of the dataset at ``root``."""
    data = load_dataset(root)
    for level in data.levels:
        truth, _ = build_coco(load_level_truth(data, level), {}, data.names)
        for image in truth["images"]:
            image["file_name"] = f"images/{level}/{image['file_name']}.png"
        add_video_fields(truth, root)  # sequences' frames: video, frame and track ids
        write_json(Layout(root).coco(level), truth)
