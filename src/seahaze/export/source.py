"""The dataset an export reads: a finished seahaze dataset folder, checked before any file is
made, with its levels, scenes and each scene's split."""

from __future__ import annotations

import json
import math
import stat
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..dataset import FORMAT_VERSION, Layout
from ..dataset.splits import SPLIT_NAMES, scene_splits, split_order
from ..fileio import json_depth
from ..visibility import CLEAN_LEVEL, is_level_name

MAX_MANIFEST_BYTES = 1 << 30
"""Largest ``dataset.json`` read (10,000 scenes of sequences' configs are about 60 MB)."""
MAX_MANIFEST_DEPTH = 64
"""Deepest nesting read: a manifest needs about 10 (scenes.<name>.config.vessels.placed[i]...)."""


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
    manifest: dict[str, Any] = field(default_factory=dict, repr=False, compare=False)
    """``dataset.json`` as read (its parts above checked; the ``hf`` card reads the rest)."""

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
    data = read_manifest(layout.manifest)
    known = _levels(data, layout.manifest)
    chosen = _select(known, levels, layout.manifest)
    scenes = scene_splits(data)
    order = tuple(split_order(data))
    # A scene of another split (a hand-edited manifest) would be left out of every folder.
    stray = next(((name, split) for name, split in scenes.items() if split not in order), None)
    if stray is not None:
        raise ExportError(
            f"{layout.manifest}: scene {stray[0]!r} has split {value_text(stray[1])}; allowed: "
            f"{', '.join(order)} (it would be left out of the export)"
        )
    _check_finished(layout, data, [CLEAN_LEVEL, *(lv.name for lv in chosen)])
    return SourceDataset(layout, tuple(chosen), scenes, order, tuple(data["classes"]), data)


def read_manifest(path: Path) -> dict[str, Any]:
    """The seahaze manifest (``dataset.json``) at ``path``, every part an export or a split
    reads checked for its type: config (and its split), levels, classes, and each scene's name,
    status and split. It is data from disk, so a hand edit or another program's file is an
    :class:`ExportError` (one line naming the file and the field), never a traceback; a file
    past 1 GiB or nested deeper than :data:`MAX_MANIFEST_DEPTH` is not parsed further."""
    data = _load_json(path)
    if not (isinstance(data, dict) and data.get("format") == "seahaze-dataset"):
        raise ExportError(f"{path}: not a seahaze dataset manifest (format: seahaze-dataset)")
    version = data.get("format_version")
    if isinstance(version, bool) or version != FORMAT_VERSION:  # true == 1 in Python
        raise ExportError(
            f"{path}: format_version {value_text(version)}; this seahaze reads {FORMAT_VERSION}"
        )
    if not isinstance(data.get("scenes"), dict) or not data["scenes"]:
        raise ExportError(f"{path}: the manifest lists no scenes (scenes: a mapping of names)")
    problem = _shape_problem(data)
    if problem is not None:
        raise ExportError(
            f"{path}: {problem}; the manifest is damaged: rerun the 'seahaze render' command "
            "that made the dataset"
        )
    return data


def _load_json(path: Path) -> Any:
    """The JSON document of the regular file ``path``, within the size and nesting limits."""
    try:
        info = path.stat()
    except FileNotFoundError:
        info = None
    except OSError as err:
        raise ExportError(f"{path}: cannot read the manifest ({err.strerror or err})") from None
    if info is None or not stat.S_ISREG(info.st_mode):
        what = "missing" if info is None else "not a regular file"
        raise ExportError(
            f"{path}: {what}; not a seahaze dataset (one is written by 'seahaze render')"
        )
    if info.st_size > MAX_MANIFEST_BYTES:
        raise ExportError(f"{path}: {info.st_size:,} bytes; a manifest is at most 1 GiB")
    try:
        data = json.loads(path.read_bytes())
    except RecursionError:
        raise ExportError(
            f"{path}: nested deeper than {MAX_MANIFEST_DEPTH}; not a seahaze manifest"
        ) from None
    except (OSError, UnicodeDecodeError, ValueError) as err:
        # ValueError: invalid JSON, or an integer of more than 4300 digits.
        reason = str(err).splitlines()[0] if str(err) else type(err).__name__
        raise ExportError(f"{path}: cannot read the manifest (not valid JSON: {reason})") from None
    if json_depth(data, MAX_MANIFEST_DEPTH) > MAX_MANIFEST_DEPTH:
        raise ExportError(
            f"{path}: nested deeper than {MAX_MANIFEST_DEPTH}; not a seahaze manifest"
        )
    return data


def _shape_problem(data: dict[str, Any]) -> str | None:
    """What in the parts an export reads does not have its type (None: all do)."""
    config = data.get("config")
    if not isinstance(config, dict):
        return f"config is {kind_text(config)}; allowed: a mapping"
    split = config.get("split")
    if split is not None and not isinstance(split, dict):
        return f"config.split is {kind_text(split)}; allowed: a mapping of {', '.join(SPLIT_NAMES)}"
    levels = data.get("levels")
    if not isinstance(levels, list) or not levels:
        what = "empty" if isinstance(levels, list) else kind_text(levels)
        return f"levels is {what}; allowed: a list of at least one hazy level"
    classes = data.get("classes")
    if not isinstance(classes, list) or not all(isinstance(c, str) and c for c in classes):
        return "classes is not a list of class names"
    for name, entry in data["scenes"].items():
        if not _is_plain_name(name):
            return (
                f"scene name {value_text(name)} is not a file name (no '/', '..' or control "
                "character)"
            )
        if not isinstance(entry, dict):
            return f"scenes.{name} is {kind_text(entry)}; allowed: a mapping with status and split"
        if not isinstance(entry.get("status"), str):
            return f"scenes.{name}.status is {kind_text(entry.get('status'))}; allowed: done"
        if not isinstance(entry.get("split", ""), str | None):
            return (
                f"scenes.{name}.split is {kind_text(entry['split'])}; allowed: "
                f"{', '.join(SPLIT_NAMES)}"
            )
    return None


def _levels(data: dict[str, Any], path: Path) -> list[Level]:
    """The manifest's hazy levels, each with a folder name, a visibility and an extinction."""
    known: list[Level] = []
    for i, entry in enumerate(data["levels"]):
        where = f"{path}: levels[{i}]"
        if not isinstance(entry, dict):
            raise ExportError(
                f"{where} is {kind_text(entry)}; allowed: a mapping with name, "
                "visibility_m and sigma_per_m"
            )
        name = entry.get("name")
        # Length first: is_level_name reads the digits as an int (a 5000-digit one raises).
        if (
            not (isinstance(name, str) and len(name) <= 12 and is_level_name(name))
            or name == CLEAN_LEVEL
        ):
            raise ExportError(
                f"{where}.name is {value_text(name)}; allowed: a level folder name such as v0300"
            )
        if any(level.name == name for level in known):
            raise ExportError(f"{where}.name {name} is listed twice; allowed: one entry per level")
        values = []
        for key, low in (("visibility_m", "> 0 m"), ("sigma_per_m", "> 0 per m")):
            value = entry.get(key)
            if key not in entry:
                raise ExportError(f"{where}.{key} is missing; allowed: a finite number {low}")
            if not (isinstance(value, int | float) and not isinstance(value, bool)):
                raise ExportError(
                    f"{where}.{key} is {value_text(value)}; allowed: a finite number {low}"
                )
            number = _finite(value)
            if number is None or number <= 0:
                raise ExportError(
                    f"{where}.{key} is {value_text(value)}; allowed: a finite number {low}"
                )
            values.append(number)
        known.append(Level(name, values[0], values[1]))
    return known


def _finite(value: int | float) -> float | None:
    """``value`` as a finite float (None for NaN, an infinity or an integer beyond float)."""
    try:
        number = float(value)
    except OverflowError:
        return None
    return number if math.isfinite(number) else None


def _is_plain_name(name: Any) -> bool:
    """A scene name that is one file-name component (no folder, no parent, no control
    character)."""
    return (
        isinstance(name, str)
        and 0 < len(name) <= 255
        and name not in (".", "..")
        and name.isprintable()  # no NUL, newline or other control character
        and not any(c in name for c in "/\\")
    )


def kind_text(value: Any) -> str:
    """``value``'s JSON kind in words, for messages."""
    kinds = {dict: "a mapping", list: "a list", str: "a string", bool: "true/false"}
    if value is None:
        return "missing (or null)"
    return next((text for kind, text in kinds.items() if isinstance(value, kind)), "a number")


def value_text(value: Any) -> str:
    """``value`` for a one-line message: a string or number as written, anything else by its
    kind (a repr of a huge or deep value would be a page long, or recurse)."""
    if isinstance(value, str):
        return repr(value[:40] + ("…" if len(value) > 40 else ""))
    if isinstance(value, bool) or value is None:
        return kind_text(value)
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, int):
        return str(value) if abs(value) < 10**40 else "an integer of more than 40 digits"
    return kind_text(value)


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
        status = scenes[unfinished[0]]["status"][:40]  # a string: read_manifest checked it
        raise ExportError(
            f"{layout.root}: not a finished dataset: {len(unfinished)} of {len(scenes)} scenes "
            f"are not done (e.g. {unfinished[0]}: {status}); rerun its 'seahaze render' command"
        )
    for scene in scenes:
        for level in levels:
            for path in (layout.image(level, scene), layout.label(level, scene)):
                if not path.is_file():
                    raise ExportError(f"{path}: missing; the dataset is incomplete")
