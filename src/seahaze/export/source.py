"""The dataset an export reads: a finished seahaze dataset folder, checked before any file is
made, with its levels, scenes and each scene's split."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..dataset import FORMAT_VERSION, Layout
from ..dataset.splits import scene_splits, split_order
from ..visibility import CLEAN_LEVEL


class ExportError(Exception):
    """Bad input or a refused export; the message is one line naming the file and what is
    allowed, and nothing was written."""


@dataclass(frozen=True)
class Level:
    """A hazy level of the dataset."""

    name: str
    visibility_m: float
    sigma_per_m: float


@dataclass(frozen=True)
class SourceDataset:
    """A finished dataset: every scene done, every image and label on disk."""

    layout: Layout
    levels: tuple[Level, ...]
    """The hazy levels exported, by increasing visibility."""
    scenes: dict[str, str]
    """Scene → split (``train``, ``val``, ``test``; ``all`` without a split), in plan order."""
    splits: tuple[str, ...]
    classes: tuple[str, ...]

    @property
    def root(self) -> Path:
        return self.layout.root

    def scenes_of(self, split: str) -> list[str]:
        """The scenes of one split, in the manifest's order."""
        return [scene for scene, s in self.scenes.items() if s == split]

    def level_names(self, with_clean: bool = False) -> list[str]:
        """Names of the exported hazy levels (``clean`` first when ``with_clean``)."""
        return [CLEAN_LEVEL] * with_clean + [level.name for level in self.levels]


def open_finished(root: Path, levels: list[str] | None = None) -> SourceDataset:
    """The finished seahaze dataset at ``root`` with the hazy ``levels`` (default all).

    Raises :class:`ExportError` for a folder that is not a seahaze dataset, one whose scenes are
    not all done or whose files are missing, and for a level it does not have.
    """
    root = Path(root).resolve()
    if not root.is_dir():
        raise ExportError(f"{root}: not a folder; give a dataset folder written by seahaze render")
    layout = Layout(root)
    data = _read_manifest(layout.manifest)
    known = [
        Level(lv["name"], float(lv["visibility_m"]), float(lv["sigma_per_m"]))
        for lv in data["levels"]
    ]
    chosen = _select(known, levels, layout.manifest)
    scenes = scene_splits(data)
    order = tuple(split_order(data))
    # A scene of another split (a hand-edited manifest) would be left out of every folder.
    stray = next(((name, split) for name, split in scenes.items() if split not in order), None)
    if stray is not None:
        raise ExportError(
            f"{layout.manifest}: scene {stray[0]!r} has split {stray[1]!r}; allowed: "
            f"{', '.join(order)} (it would be left out of the export)"
        )
    _check_finished(layout, data, [CLEAN_LEVEL, *(lv.name for lv in chosen)])
    return SourceDataset(layout, tuple(chosen), scenes, order, tuple(data["classes"]))


def _read_manifest(path: Path) -> dict[str, Any]:
    if not path.is_file():
        raise ExportError(
            f"{path}: missing; not a seahaze dataset (one is written by 'seahaze render')"
        )
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as err:
        raise ExportError(f"{path}: cannot read the manifest ({type(err).__name__})") from None
    if not (isinstance(data, dict) and data.get("format") == "seahaze-dataset"):
        raise ExportError(f"{path}: not a seahaze dataset manifest (format: seahaze-dataset)")
    if data.get("format_version") != FORMAT_VERSION:
        raise ExportError(
            f"{path}: format_version {data.get('format_version')!r}; this seahaze reads "
            f"{FORMAT_VERSION}"
        )
    if not isinstance(data.get("scenes"), dict) or not data["scenes"]:
        raise ExportError(f"{path}: the manifest lists no scenes")
    return data


def _select(known: list[Level], wanted: list[str] | None, manifest: Path) -> list[Level]:
    if wanted is None:
        return known
    by_name = {level.name: level for level in known}
    unknown = [name for name in wanted if name not in by_name]
    if unknown:
        raise ExportError(
            f"--levels {unknown[0]}: not a hazy level of {manifest.parent} "
            f"(levels: {', '.join(by_name) or 'none'})"
        )
    return sorted({by_name[name] for name in wanted}, key=lambda lv: lv.visibility_m)


def _check_finished(layout: Layout, data: dict[str, Any], levels: list[str]) -> None:
    """Every scene done and its image and label of every exported level on disk."""
    scenes = data["scenes"]
    unfinished = [name for name, entry in scenes.items() if entry.get("status") != "done"]
    if unfinished:
        status = scenes[unfinished[0]].get("status")
        raise ExportError(
            f"{layout.root}: not a finished dataset: {len(unfinished)} of {len(scenes)} scenes "
            f"are not done (e.g. {unfinished[0]}: {status}); rerun its 'seahaze render' command"
        )
    for scene in scenes:
        for level in levels:
            for path in (layout.image(level, scene), layout.label(level, scene)):
                if not path.is_file():
                    raise ExportError(f"{path}: missing; the dataset is incomplete")
