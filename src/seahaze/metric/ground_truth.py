"""The COCO ground-truth files of a dataset: ``coco/<level>.json``, one per level.

Built from the dataset's YOLO labels with the converter the metric evaluates with
(:func:`seahaze.metric.evaluate.build_coco`), so a perfect prediction set scores AP50 = 1 against
these files. ``file_name`` is relative to the dataset root. A sequence's frames also carry
their video, frame and track ids (:mod:`seahaze.dataset.tracks`).

A dataset rendered with ``labels.write_visible`` also gets ``coco_visible/<level>.json`` from
``labels_visible/<level>/``: the vessels seen in each level's image (docs/metric.md), with the
same image ids as ``coco/<level>.json``. A sequence's ``coco_visible`` carries the same video
fields as its ``coco`` file (``videos``, each image's ``video_id`` and ``frame_id``, each
annotation's ``track_id`` and ``instance_id``), so a video tool reads either file the same way.
"""

from __future__ import annotations

import functools
import json
from collections import defaultdict
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

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
    # Every level's annotations read the same meta files: each is read once.
    meta_of = functools.cache(lambda scene: read_meta(layout, scene))
    for level in data.levels:
        every = load_level_truth(data, level)
        truth, _ = build_coco(every, {}, data.names)
        _name_images(truth, level)
        add_video_fields(truth, root)  # sequences' frames: video, frame and track ids
        add_object_optics(truth, meta_of, level)
        write_json(layout.coco(level), truth)
        if layout.visible_label_dir(level).is_dir():
            seen, _ = build_coco(visible_truth(data, level, every), {}, data.names)
            _name_images(seen, level)
            copy_matched_fields(truth, seen, layout.visible_label_dir(level))
            write_json(layout.coco_visible(level), seen)


OPTICS_KEYS = (
    "transmittance_mean",
    "transmittance_min",
    "optical_depth_centre",
    "local_contrast",
    "discernible",
)
"""Per-level facts of a vessel in ``meta`` that its COCO annotations carry (where the meta
has them: a dataset rendered before they existed has not)."""


def add_object_optics(
    truth: dict[str, Any], meta_of: Callable[[str], dict[str, Any]], level: str
) -> None:
    """Give each annotation of a level's COCO ``truth`` its vessel's distance and, from
    its scene's ``meta`` (``meta_of(scene)``), its :data:`OPTICS_KEYS` at ``level``: the
    transmittance over its pixels, the optical depth to its centre, its local contrast and
    whether it is discernible (docs/dataset-format.md). Annotations follow each label file's
    lines, that is the boxed vessels in index order
    (:func:`seahaze.metric.evaluate.build_coco`)."""
    boxed: dict[int, list[dict[str, Any]]] = {}
    for image in truth["images"]:
        meta = meta_of(Path(image["file_name"]).stem)
        vessels = sorted((v for v in meta["vessels"] if v["box_px"] is not None), key=_index)
        boxed[image["id"]] = vessels
    seen: dict[int, int] = defaultdict(int)
    for annotation in truth["annotations"]:
        vessels = boxed[annotation["image_id"]]
        k = seen[annotation["image_id"]]
        seen[annotation["image_id"]] += 1
        if k >= len(vessels):
            continue  # more label lines than boxed vessels: not this meta's (left as is)
        vessel = vessels[k]
        entry = vessel.get("levels", {}).get(level, {})
        annotation["distance_m"] = vessel.get("distance_m")
        annotation.update({key: entry[key] for key in OPTICS_KEYS if key in entry})


def _index(vessel: dict[str, Any]) -> int:
    return int(vessel["index"])


def read_meta(layout: Layout, scene: str) -> dict[str, Any]:
    """A scene's ``meta`` JSON (MetricInputError naming the file when it cannot be read)."""
    path = layout.meta(scene)
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as err:
        raise located(path, f"cannot read the scene's meta ({err})") from None


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


VIDEO_IMAGE_KEYS = ("video_id", "frame_id")
"""The video fields of a sequence frame's COCO image (``dataset.tracks.add_video_fields``)."""
TRACK_KEYS = ("track_id", "instance_id")
"""The track fields of a sequence frame's COCO annotation (``instance_id``: mmtracking's name)."""


def copy_matched_fields(every: dict[str, Any], seen: dict[str, Any], folder: Path) -> None:
    """Give ``seen`` (a level's ``coco_visible`` truth) the video fields of ``every`` (its
    ``coco`` truth, after :func:`~seahaze.dataset.tracks.add_video_fields` and
    :func:`add_object_optics`): ``videos``, each image's ``video_id`` and ``frame_id``, and
    each annotation the track ids, distance and optics of the annotation it is in ``every``
    (the video fields only where ``every`` has ``videos``: a sequence).

    The track ids are matched, not recomputed: a visible-label file holds lines of its
    ``labels/`` file in their order, so each visible annotation is the next annotation of its
    image in ``every`` with the same class and box (counting positions would give a boat the
    track id of the hidden ship before it). One that matches none raises
    :class:`MetricInputError` naming its file in ``folder`` (``labels_visible/<level>``): a
    visible label that is no vessel's.
    """
    images = {image["id"]: image for image in every["images"]}
    for image in seen["images"]:
        source = images[image["id"]]  # the same images, ids and order (build_coco)
        image.update({key: source[key] for key in VIDEO_IMAGE_KEYS if key in source})
    pending: dict[int, list[dict[str, Any]]] = defaultdict(list)
    for annotation in every["annotations"]:
        pending[annotation["image_id"]].append(annotation)
    for annotation in seen["annotations"]:
        queue = pending[annotation["image_id"]]
        key = (annotation["category_id"], annotation["bbox"])
        while queue and (queue[0]["category_id"], queue[0]["bbox"]) != key:
            queue.pop(0)
        if not queue:
            name = Path(images[annotation["image_id"]]["file_name"]).stem
            raise located(
                folder / f"{name}.txt",
                "a box that the scene's labels/ file does not hold in this order (visible "
                "labels are lines of labels/, in their order): a damaged or foreign file",
            )
        source = queue.pop(0)
        copied = (*TRACK_KEYS, "distance_m", *OPTICS_KEYS)
        annotation.update({key: source[key] for key in copied if key in source})
    if "videos" in every:
        seen["videos"] = every["videos"]


def _name_images(truth: dict[str, list[dict[str, object]]], level: str) -> None:
    for image in truth["images"]:
        image["file_name"] = f"images/{level}/{image['file_name']}.png"
