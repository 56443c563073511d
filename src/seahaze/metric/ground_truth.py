"""The COCO ground-truth files of a dataset: ``coco/<level>.json``, one per level.

Built from the dataset's YOLO labels with the converter the metric evaluates with
(:func:`seahaze.metric.evaluate.build_coco`), so a perfect prediction set scores AP50 = 1 against
these files. ``file_name`` is relative to the dataset root. A sequence's frames also carry
their video, frame and track ids (:mod:`seahaze.dataset.tracks`).

A dataset rendered with ``labels.write_visible`` also gets ``coco_visible/<level>.json`` from
``labels_visible/<level>/``: the vessels seen in each level's image (docs/metric.md), with the
same image ids as ``coco/<level>.json``. Those carry no video or track fields.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from ..dataset.layout import Layout
from ..dataset.tracks import add_video_fields
from ..fileio import write_json
from .errors import located
from .evaluate import build_coco
from .reader import Dataset, ImageTruth, load_dataset, load_level_truth, read_yolo_file


def write_coco(root: Path) -> None:
    """Write the COCO ground truth of every level of the dataset at ``root`` (and its
    visible-object COCO where ``labels_visible/<level>/`` exists)."""
    data = load_dataset(root)
    layout = Layout(root)
    for level in data.levels:
        every = load_level_truth(data, level)
        truth, _ = build_coco(every, {}, data.names)
        _name_images(truth, level)
        add_video_fields(truth, root)  # sequences' frames: video, frame and track ids
        write_json(layout.coco(level), truth)
        if layout.visible_label_dir(level).is_dir():
            seen, _ = build_coco(visible_truth(data, level, every), {}, data.names)
            _name_images(seen, level)
            write_json(layout.coco_visible(level), seen)


def visible_truth(data: Dataset, level: str, every: list[ImageTruth]) -> list[ImageTruth]:
    """The images of ``every`` (a level's truth from ``labels/``) with the boxes of their
    ``labels_visible/<level>/`` files. A visible-label file without an image is not the
    dataset's and is ignored; an image without one raises :class:`MetricInputError`."""
    layout = Layout(data.root)
    out = []
    for image in every:
        path = layout.visible_label(level, image.name)
        if not path.is_file():
            raise located(path, f"missing visible-object label file for {image.name}")
        boxes = read_yolo_file(path, len(data.names), with_conf=False)
        out.append(replace(image, boxes=tuple(boxes)))
    return out


def _name_images(truth: dict[str, list[dict[str, object]]], level: str) -> None:
    for image in truth["images"]:
        image["file_name"] = f"images/{level}/{image['file_name']}.png"
