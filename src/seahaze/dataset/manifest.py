"""The dataset-wide files: the ``dataset.json`` manifest, the Ultralytics ``data.yaml`` and its
split lists."""

from __future__ import annotations

import hashlib
import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import yaml

from .. import __version__
from ..visibility import (
    CLEAN_LEVEL,
    Threshold,
    extinction_coefficient,
    level_name,
    regulation_class,
)
from .splits import SPLIT_NAMES

FORMAT_VERSION = 1


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


def data_yaml_text(
    root: Path,
    level_names: list[str],
    class_names: tuple[str, ...],
    split_names: Sequence[str] = (),
) -> str:
    """Ultralytics dataset YAML: absolute root, train/val(/test), one split per level (clean
    included).

    Without ``split_names`` (a dataset made with ``--split none``, or before splits were the
    default) ``train`` and ``val`` are every clean image; with them each is its list file
    (``train: train.txt``, :func:`split_list_text`). Splits without a scene are not named: where
    ``val`` is not (a batch of one scene, or a val fraction of 0), ``val`` is ``train.txt`` too,
    since Ultralytics refuses a dataset YAML without ``val``.
    Every level is a split of its own with an absolute folder, every scene of the level: Ultralytics
    resolves only ``train``/``val``/``test``/``minival`` against ``path`` (any other split is taken
    relative to the working directory) and finds an image's labels only through an ``/images/``
    component of its path. A relative ``path`` is resolved against Ultralytics' datasets folder,
    so the root is written absolute too.
    """
    root = root.resolve()
    data: dict[str, Any] = {"path": str(root)}
    if split_names:
        lists = {name: f"{name}.txt" for name in split_names}
        lists.setdefault("val", lists["train"])
        data.update({name: lists[name] for name in SPLIT_NAMES if name in lists})
    else:
        data.update({"train": f"images/{CLEAN_LEVEL}", "val": f"images/{CLEAN_LEVEL}"})
    for name in [CLEAN_LEVEL, *level_names]:
        data[name] = str(root / "images" / name)
    data["names"] = dict(enumerate(class_names))
    if not split_names:
        splits = "train/val: every scene"
    elif "val" in split_names:
        splits = "train/val/test: scene-disjoint splits"
    else:
        splits = "no val split: val is train"
    return (
        f"# seahaze dataset ({splits}); one split per visibility level, every scene\n"
        "# e.g. yolo val model=WEIGHTS.pt data=THIS_FILE split=v1000 (see README.md)\n"
        + yaml.safe_dump(data, sort_keys=False)
    )


def split_list_text(scenes: Sequence[str]) -> str:
    """An Ultralytics image list of the clean images of ``scenes``: one line
    ``./images/clean/<scene>.png`` each. Ultralytics resolves a leading ``./`` against the list's
    own folder (the convention of its COCO ``train2017.txt``), so the list stays valid when the
    dataset folder moves."""
    return "".join(f"./images/{CLEAN_LEVEL}/{scene}.png\n" for scene in scenes)


BOOKKEEPING_KEYS = ("status", "error", "files_sha256")
"""Keys of a scene's manifest record that say where its rendering stands, not what it is made
from: its state, the error it failed with, and the content hash of the files it was written
with (``files_sha256``, which resume checks before keeping a finished scene)."""


def config_hash(data: dict[str, Any]) -> str:
    """A short SHA-256 of what a dataset's content depends on: the manifest's format version,
    config, levels, classes and every scene's record (without :data:`BOOKKEEPING_KEYS`).

    Two folders with the same hash were made from the same configuration.
    """
    scenes = {
        name: {k: v for k, v in entry.items() if k not in BOOKKEEPING_KEYS}
        for name, entry in (data.get("scenes") or {}).items()
    }
    content = {key: data.get(key) for key in ("format_version", "config", "levels", "classes")}
    text = json.dumps({**content, "scenes": scenes}, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


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
