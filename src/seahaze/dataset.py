"""The dataset folder: layout, Ultralytics ``data.yaml``, the ``dataset.json`` manifest, metadata.

Layout (docs/dataset-format.md)::

    OUT/data.yaml  OUT/dataset.json
    OUT/images/clean/<scene>.png       OUT/images/v0300/<scene>.png ...
    OUT/labels/<level>/<scene>.txt     OUT/depth/<scene>.exr
    OUT/exr/<level>/<scene>.exr        OUT/meta/<scene>.json
    OUT/coco/<level>.json

Every file is written atomically (temporary name, then rename), so an interrupted run never
leaves a truncated file under its final name. Outputs carry no timestamps: the same config and
seed give byte-identical files.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from . import __version__
from .imaging import atomic_target
from .visibility import Threshold, extinction_coefficient, level_name, regulation_class

CLEAN = "clean"
FORMAT_VERSION = 1


def write_text(path: Path, text: str) -> None:
    """Write a text file atomically."""
    with atomic_target(path) as tmp:
        tmp.write_text(text, encoding="utf-8")


def write_json(path: Path, data: Any) -> None:
    """Write JSON atomically, keys in a stable order, 2-space indent."""
    write_text(path, json.dumps(data, indent=2, sort_keys=False, allow_nan=False) + "\n")


@dataclass(frozen=True)
class Layout:
    """Paths of the files of one dataset folder."""

    root: Path

    def image(self, level: str, scene: str) -> Path:
        return self.root / "images" / level / f"{scene}.png"

    def label(self, level: str, scene: str) -> Path:
        return self.root / "labels" / level / f"{scene}.txt"

    def exr(self, level: str, scene: str) -> Path:
        return self.root / "exr" / level / f"{scene}.exr"

    def depth(self, scene: str) -> Path:
        return self.root / "depth" / f"{scene}.exr"

    def coco(self, level: str) -> Path:
        return self.root / "coco" / f"{level}.json"

    def meta(self, scene: str) -> Path:
        return self.root / "meta" / f"{scene}.json"

    @property
    def data_yaml(self) -> Path:
        return self.root / "data.yaml"

    @property
    def manifest(self) -> Path:
        return self.root / "dataset.json"


def level_entries(visibilities_m: list[float], threshold: Threshold | str) -> list[dict[str, Any]]:
    """Manifest entries of the hazy levels: name, visibility, extinction and regulation class."""
    entries = []
    for v in visibilities_m:
        cls = regulation_class(v)
        entries.append(
            {
                "name": level_name(v),
                "visibility_m": v,
                "sigma_per_m": extinction_coefficient(v, threshold),
                "regulation": cls.key,
                "regulation_label": cls.label,
            }
        )
    return entries


def data_yaml_text(root: Path, level_names: list[str], class_names: tuple[str, ...]) -> str:
    """Ultralytics dataset YAML: absolute root, ``train``/``val`` = clean, one split per level.

    Ultralytics resolves a relative ``path`` against its own datasets folder, so the root is
    written absolute; validate a level with ``yolo val data=OUT/data.yaml split=v1000``.
    """
    data: dict[str, Any] = {
        "path": str(root.resolve()),
        "train": f"images/{CLEAN}",
        "val": f"images/{CLEAN}",
    }
    for name in level_names:
        data[name] = f"images/{name}"
    data["names"] = dict(enumerate(class_names))
    return (
        "# seahaze dataset: one split per visibility level (see dataset.json)\n"
        + yaml.safe_dump(data, sort_keys=False)
    )


def manifest(
    config: dict[str, Any],
    levels: list[dict[str, Any]],
    class_names: tuple[str, ...],
    scenes: dict[str, Any],
) -> dict[str, Any]:
    """The ``dataset.json`` manifest."""
    return {
        "format": "seahaze-dataset",
        "format_version": FORMAT_VERSION,
        "seahaze_version": __version__,
        "config": config,
        "levels": levels,
        "classes": list(class_names),
        "scenes": scenes,
    }


def write_coco(root: Path) -> None:
    """COCO ground truth per level (``coco/<level>.json``) from the YOLO labels of every scene.

    Built with the same converter the metric evaluates with, so a perfect prediction set scores
    AP50 = 1 against these files. ``file_name`` is relative to the dataset root.
    """
    from .metric.dataset import load_dataset, load_level_truth
    from .metric.evaluate import build_coco

    data = load_dataset(root)
    for level in data.levels:
        truth, _ = build_coco(load_level_truth(data, level), {}, data.names)
        for image in truth["images"]:
            image["file_name"] = f"images/{level}/{image['file_name']}.png"
        write_json(Layout(root).coco(level), truth)
