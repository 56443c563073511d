"""The dataset-wide files: the ``dataset.json`` manifest and the Ultralytics ``data.yaml``."""

from __future__ import annotations

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


def data_yaml_text(root: Path, level_names: list[str], class_names: tuple[str, ...]) -> str:
    """Ultralytics dataset YAML: absolute root, ``train``/``val`` = clean, one split per level.

    Ultralytics resolves a relative ``path`` against its own datasets folder, so the root is
    written absolute.
    """
    data: dict[str, Any] = {
        "path": str(root.resolve()),
        "train": f"images/{CLEAN_LEVEL}",
        "val": f"images/{CLEAN_LEVEL}",
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
