"""The dataset folder a batch renders into: whose it is, its manifest, what changed since,
whether finished scenes are intact, and clean-up.

Every function here reads or tidies the folder; none renders. seahaze writes only into a new or
empty folder or one of its own datasets, and deletes or overwrites only its own files: those a
readable manifest of its format lists (its scenes × its levels), never "any file in a level
folder" (docs/batches.md).
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .. import fileio
from ..dataset import FORMAT_VERSION, Layout
from ..dataset.layout import TRANSMISSION_CHANNELS
from ..dataset.manifest import BOOKKEEPING_KEYS
from ..spec import SceneSpec
from ..visibility import CLEAN_LEVEL, is_level_name
from .errors import ForeignFolderError
from .lock import LOCK_NAME

FORMAT = "seahaze-dataset"
"""``dataset.json``'s ``format``: the marker of a folder seahaze made."""
DATA_YAML_MARK = "# seahaze dataset"
"""The first line of the ``data.yaml`` seahaze writes: its second marker."""
MAX_MANIFEST_BYTES = 1 << 30
MAX_MANIFEST_DEPTH = 64
STATUSES = ("pending", "done", "failed")
KINDS = (
    "images",
    "labels",
    "exr",
    "depth",
    "meta",
    "coco",
    "mot",
    "labels_visible",
    "coco_visible",
    "transmission",
)
"""The folders of a dataset (docs/dataset-format.md)."""
LEVEL_KINDS = ("images", "labels", "exr", "labels_visible", "transmission")
"""The folders that hold one folder per level."""
STRAY_SUFFIXES = (".png", ".jpg", ".jpeg", ".txt")
"""Files in a level folder that the COCO writer reads: one that is not the dataset's would
break it at the end of the batch, so it is refused at the start."""

_TMP_FILE = re.compile(r"^\..+\.tmp\d+$")  # seahaze.fileio.atomic_target's temporary names


@dataclass(frozen=True)
class FolderState:
    """What :func:`inspect_folder` found: a usable manifest of seahaze's, or why the folder's
    own manifest is damaged (both None: a new or empty folder)."""

    manifest: dict[str, Any] | None = None
    damaged: str | None = None


def inspect_folder(root: Path) -> FolderState:
    """Whose ``root`` is. Raises :class:`ForeignFolderError` for a file, a non-empty folder
    seahaze did not make, another program's ``dataset.json`` or a newer format."""
    if not root.exists() and not root.is_symlink():
        parent = next((p for p in root.parents if p.exists()), None)
        if parent is not None and not parent.is_dir():
            raise ForeignFolderError(f"--out {root}: {parent} is a file, not a folder")
        return FolderState()
    if not root.is_dir():
        raise ForeignFolderError(f"--out {root} is not a folder; give a new or empty folder")
    path = root / "dataset.json"
    if not path.exists():
        others = sorted(e.name for e in root.iterdir() if not _own_leftover(root, e.name))
        if not others:
            return FolderState()
        if _has_own_mark(root):
            return FolderState(damaged="it is missing")
        raise ForeignFolderError(
            f"{root} is not empty ({', '.join(others[:3])}{', …' if len(others) > 3 else ''}) "
            "and is not a seahaze dataset (no dataset.json); seahaze writes only into a new or "
            "empty folder or one of its own datasets: choose another --out"
        )
    data, problem = _load_json(path)
    if problem is None:
        if not isinstance(data, dict) or data.get("format") != FORMAT:
            found = data.get("format") if isinstance(data, dict) else type(data).__name__
            raise ForeignFolderError(
                f"{path} is not a seahaze manifest (format {found!r}, not {FORMAT!r}); seahaze "
                "does not write into or delete from a folder it did not make, even with "
                "--force: choose another --out"
            )
        version = data.get("format_version")
        if isinstance(version, int) and not isinstance(version, bool) and version > FORMAT_VERSION:
            raise ForeignFolderError(
                f"{path} has format_version {version}, written by a newer seahaze; this one "
                f"reads {FORMAT_VERSION}: use that version or choose another --out"
            )
        problem = manifest_problem(data)
        if problem is None:
            return FolderState(manifest=data)
        return FolderState(damaged=problem)
    if _has_own_mark(root):
        return FolderState(damaged=problem)
    raise ForeignFolderError(
        f"cannot read {path} ({problem}) and nothing else marks {root} as a seahaze dataset "
        "(no data.yaml of seahaze's): choose another --out"
    )


def damaged_message(root: Path, problem: str) -> str:
    """The refusal of a folder whose own manifest is damaged, saying what to do."""
    return (
        f"{root / 'dataset.json'} is damaged ({problem}), so seahaze cannot tell which scenes "
        "are done. Rerun with --force to rebuild it: the damaged file is kept as "
        "dataset.json.damaged, every planned scene is rendered again, no other file is deleted"
    )


def _own_leftover(root: Path, name: str) -> bool:
    """The files a run killed before its first manifest can leave: the lock, data.yaml and
    temporaries."""
    if name == LOCK_NAME or _TMP_FILE.match(name):
        return True
    return name == "data.yaml" and _has_own_mark(root)


def _has_own_mark(root: Path) -> bool:
    """Whether ``root/data.yaml`` starts with the line seahaze writes."""
    try:
        with open(root / "data.yaml", "rb") as handle:
            return handle.read(len(DATA_YAML_MARK)).decode("utf-8", "replace") == DATA_YAML_MARK
    except OSError:
        return False


def _load_json(path: Path) -> tuple[Any, str | None]:
    """The JSON document at ``path``, or None and why it cannot be read."""
    try:
        if path.stat().st_size > MAX_MANIFEST_BYTES:
            return None, "larger than 1 GiB"
        data = json.loads(path.read_bytes())
    except OSError as err:
        return None, f"cannot be read: {err.strerror or err}"
    except RecursionError:
        return None, "nested too deeply"
    except (UnicodeDecodeError, ValueError) as err:
        return None, f"not valid JSON: {str(err).splitlines()[0] if str(err) else err}"
    if fileio.json_depth(data, MAX_MANIFEST_DEPTH) > MAX_MANIFEST_DEPTH:
        return None, "nested too deeply"
    return data, None


def _is_plain_name(name: Any) -> bool:
    """A scene name that is one file-name component (no folder, no parent)."""
    return (
        isinstance(name, str)
        and bool(name)
        and name not in (".", "..")
        and "/" not in name
        and "\\" not in name
        and "\x00" not in name
    )


def manifest_problem(data: dict[str, Any]) -> str | None:
    """Why a seahaze manifest cannot be used (None: it can): every part a run reads must have
    its type, scene and level names must be plain file names."""
    if not isinstance(data.get("format_version"), int):
        return "format_version is not a number"
    if not isinstance(data.get("config"), dict):
        return "'config' is not a mapping"
    levels = data.get("levels")
    if not isinstance(levels, list) or not all(
        isinstance(e, dict) and isinstance(e.get("name"), str) and is_level_name(e["name"])
        for e in levels
    ):
        return "'levels' is not a list of levels with names like v0300"
    classes = data.get("classes")
    if not isinstance(classes, list) or not all(isinstance(c, str) for c in classes):
        return "'classes' is not a list of names"
    scenes = data.get("scenes")
    if not isinstance(scenes, dict):
        return f"'scenes' is a {type(scenes).__name__}, not a mapping"
    for name, entry in scenes.items():
        if not _is_plain_name(name):
            return f"scene name {name!r} is not a file name"
        if not isinstance(entry, dict) or entry.get("status") not in STATUSES:
            return f"scene {name!r} has no status {'/'.join(STATUSES)}"
        if not isinstance(entry.get("config", {}), dict):
            return f"scene {name!r} has a config that is not a mapping"
    return None


def keep_damaged(path: Path) -> Path:
    """Move a damaged manifest aside as ``dataset.json.damaged`` (replacing an older one)."""
    target = path.with_name(path.name + ".damaged")
    if path.exists():
        os.replace(path, target)
    return target


def describe_error(err: BaseException) -> str:
    text = str(err).strip().splitlines()
    return f"{type(err).__name__}: {text[0] if text else ''}".rstrip(": ")


def _flatten(data: Any, prefix: str = "") -> dict[str, Any]:
    if isinstance(data, dict):
        out: dict[str, Any] = {}
        for key, value in data.items():
            out.update(_flatten(value, f"{prefix}.{key}" if prefix else str(key)))
        return out
    return {prefix: data}


def with_current_defaults(existing: dict[str, Any]) -> dict[str, Any]:
    """The folder's manifest with each scene's recorded config re-validated by this version's
    schema, so a field added since (at its default, which keeps the old behaviour) is not a
    change. A config that no longer validates is kept as recorded: it differs for real."""
    scenes = existing.get("scenes")
    if not isinstance(scenes, dict):
        return existing
    upgraded = {}
    for name, entry in scenes.items():
        config = entry.get("config") if isinstance(entry, dict) else None
        if isinstance(config, dict):
            try:
                config = SceneSpec.model_validate(config).model_dump(mode="json", by_alias=True)
                entry = {**entry, "config": config}
            except ValueError:
                pass
        upgraded[name] = entry
    return {**existing, "scenes": upgraded}


UNUSED_BY_MODE: dict[str, tuple[tuple[str, str], ...]] = {
    "physical": (("render", "max_depth"),),
}
"""Settings a hazy-level mode never reads: a different value there is not a change (the
``physical`` mode has no ``volpath`` levels; ``render.max_depth``'s default changed from 64 to
unbounded in issue #19 without changing a ``physical`` dataset)."""


def comparable(entry: dict[str, Any]) -> dict[str, Any]:
    """A scene's manifest entry without its bookkeeping (state, error, content hash) and the
    settings its mode never reads."""
    out = {k: v for k, v in entry.items() if k not in BOOKKEEPING_KEYS}
    config = out.get("config")
    if isinstance(config, dict):
        mode = (config.get("render") or {}).get("mode")
        for section, key in UNUSED_BY_MODE.get(mode, ()):
            if isinstance(config.get(section), dict) and key in config[section]:
                config = {**config, section: {**config[section]}}
                del config[section][key]
        out["config"] = config
    return out


def differences(old: dict[str, Any], new: dict[str, Any]) -> list[str]:
    """Human lines for what differs between a folder's manifest and the planned one."""
    lines = []
    for key in ("format", "format_version"):
        if old.get(key) != new[key]:
            return [f"{key} is {old.get(key)!r} there, {new[key]!r} now"]
    for key in ("config", "levels", "classes"):
        a, b = _flatten(old.get(key)), _flatten(new[key])
        for path in sorted(set(a) | set(b)):
            if a.get(path, "(none)") != b.get(path, "(none)"):
                lines.append(
                    f"{path}: {a.get(path, '(none)')!r} there, {b.get(path, '(none)')!r} now"
                )
    old_scenes, new_scenes = old.get("scenes") or {}, new["scenes"]
    gone = [n for n in old_scenes if n not in new_scenes]
    added = [n for n in new_scenes if n not in old_scenes]
    if gone:
        lines.append(f"{len(gone)} scene(s) not in the new config, e.g. {gone[0]}")
    if added:
        lines.append(f"{len(added)} scene(s) not in the folder, e.g. {added[0]}")
    for name, entry in new_scenes.items():
        if name not in old_scenes:
            continue
        a, b = _flatten(comparable(old_scenes[name])), _flatten(comparable(entry))
        changed = [p for p in sorted(set(a) | set(b)) if a.get(p, "(none)") != b.get(p, "(none)")]
        if changed:
            p = changed[0]
            more = f" (and {len(changed) - 1} more)" if len(changed) > 1 else ""
            lines.append(
                f"scene {name}: {p} is {a.get(p, '(none)')!r} there, "
                f"{b.get(p, '(none)')!r} now{more}"
            )
    return lines


def remove_temporaries(root: Path) -> int:
    """Delete temporary files a killed run left behind, in the dataset's own folders only;
    returns how many."""
    removed = 0
    for folder in _own_folders(root):
        for entry in os.scandir(folder):
            if _TMP_FILE.match(entry.name) and entry.is_file(follow_symlinks=False):
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(entry.path)
                    removed += 1
    return removed


def _own_folders(root: Path) -> list[Path]:
    """The root and the folders seahaze writes files into (level folders by their names)."""
    folders = [root]
    for kind in KINDS:
        base = root / kind
        if not base.is_dir() or base.is_symlink():
            continue
        folders.append(base)
        if kind in LEVEL_KINDS:
            folders += [p for p in base.iterdir() if is_level_name(p.name) and p.is_dir()]
        elif kind == "mot":  # mot/<level>/<sequence>/ and its gt/
            for level in (p for p in base.iterdir() if is_level_name(p.name) and p.is_dir()):
                for seq in (p for p in level.iterdir() if p.is_dir() and not p.is_symlink()):
                    folders += [seq] + ([seq / "gt"] if (seq / "gt").is_dir() else [])
    return folders


def prune(root: Path, old: dict[str, Any], keep_scenes: set[str], keep_levels: set[str]) -> int:
    """Under ``force``: delete the files of scenes and levels the new config no longer has.

    Only files the old manifest lists are candidates — its scenes × its levels (``clean``
    included), their meta and depth, its levels' COCO files and its sequences' MOTChallenge
    files at those levels — so a file seahaze did not
    write is never deleted; a candidate whose folder resolves outside ``root`` (a level folder
    replaced by a symbolic link) is left alone too. Level folders left empty are removed."""
    layout = Layout(root)
    levels = [CLEAN_LEVEL, *(e["name"] for e in old.get("levels", []))]
    doomed: list[Path] = []
    for scene in old.get("scenes", {}):
        for level in levels:
            if scene not in keep_scenes or level not in keep_levels:
                doomed += [
                    layout.image(level, scene),
                    layout.label(level, scene),
                    layout.exr(level, scene),
                    layout.transmission(level, scene),
                    layout.visible_label(level, scene),
                ]
        if scene not in keep_scenes:
            doomed += [layout.meta(scene), layout.depth(scene)]
    doomed += [layout.coco(level) for level in levels if level not in keep_levels]
    doomed += [layout.coco_visible(level) for level in levels if level not in keep_levels]
    mot = _mot_files(layout, old, [level for level in levels if level not in keep_levels])
    removed = 0
    inside = root.resolve()
    for path in doomed:
        if not path.parent.resolve().is_relative_to(inside):
            continue  # a folder that leads elsewhere: not the dataset's files
        if path.is_file() and not path.is_symlink():
            path.unlink()
            removed += 1
    for path in mot:  # img1/ holds links seahaze made: a link is removed, never followed
        if path.parent.resolve().is_relative_to(inside) and (path.is_symlink() or path.is_file()):
            path.unlink()
            removed += 1
    for level in levels:
        if level not in keep_levels:
            _remove_empty_tree(root / "mot" / level)
    for level in levels:
        if level not in keep_levels:
            for kind in LEVEL_KINDS:
                with contextlib.suppress(OSError):
                    (root / kind / level).rmdir()  # only when empty
    return removed


def _mot_files(layout: Layout, old: dict[str, Any], levels: list[str]) -> list[Path]:
    """The MOTChallenge files seahaze wrote at ``levels`` for the old manifest's sequences:
    each sequence's ``seqinfo.ini``, ``gt/gt.txt`` and ``img1/`` frame links, and the levels'
    ``seqmap.txt``."""
    frames: dict[str, int] = {}
    for entry in (old.get("scenes") or {}).values():
        sequence = entry.get("sequence") if isinstance(entry, dict) else None
        if isinstance(sequence, str) and _is_plain_name(sequence):
            frames[sequence] = frames.get(sequence, 0) + 1
    files: list[Path] = []
    for level in levels:
        files.append(layout.mot_seqmap(level))
        for sequence, count in frames.items():
            files += [layout.mot_seqinfo(level, sequence), layout.mot_gt(level, sequence)]
            files += [layout.mot_frame(level, sequence, k) for k in range(1, count + 1)]
    return files


def _remove_empty_tree(folder: Path) -> None:
    """Remove ``folder`` and the folders under it, deepest first, where they are empty (a
    file seahaze did not write keeps its folders)."""
    if not folder.is_dir() or folder.is_symlink():
        return
    for path in sorted(folder.rglob("*"), key=lambda p: len(p.parts), reverse=True):
        if path.is_dir() and not path.is_symlink():
            with contextlib.suppress(OSError):
                path.rmdir()
    with contextlib.suppress(OSError):
        folder.rmdir()


def scene_file_problem(
    layout: Layout,
    scene: str,
    levels: list[str],
    exr: bool,
    size: tuple[int, int],
    visible: bool = False,
) -> str | None:
    """The first missing, truncated or unreadable file of a finished scene (None: all are
    intact); ``visible``: the scene writes visible-object labels too. Cheap: headers and file
    ends only (:mod:`seahaze.fileio`)."""
    for path in layout.scene_files(scene, levels, exr, visible):
        problem = file_problem(path, scene, size)
        if problem is not None:
            return f"{path.relative_to(layout.root)} {problem}"
    return None


def scene_digest(
    layout: Layout, scene: str, levels: list[str], exr: bool, visible: bool = False
) -> str:
    """The SHA-256 of every file of a scene (:meth:`Layout.scene_files`), each named by its
    path relative to the dataset: what the manifest's ``files_sha256`` records when the scene
    is written and what resume compares before keeping it. Raises OSError for a file that
    cannot be read."""
    combined = hashlib.sha256()
    for path in layout.scene_files(scene, levels, exr, visible):
        with open(path, "rb") as handle:
            content = hashlib.file_digest(handle, "sha256").hexdigest()
        combined.update(f"{path.relative_to(layout.root).as_posix()}\0{content}\n".encode())
    return combined.hexdigest()


def recorded_digest(entry: dict[str, Any]) -> str | None:
    """A scene record's ``files_sha256`` when it is one (64 lowercase hex digits), else None:
    the manifest is data from disk."""
    value = entry.get("files_sha256")
    if isinstance(value, str) and re.fullmatch(r"[0-9a-f]{64}", value):
        return value
    return None


def file_problem(path: Path, scene: str, size: tuple[int, int]) -> str | None:
    """Whether one file of a scene is intact, by its kind (the folder under the root)."""
    if not path.is_file():
        return "is missing" if not path.exists() else "is not a file"
    kind = path.parent.name if path.parent.parent.name not in KINDS else path.parent.parent.name
    if kind == "images":
        return fileio.check_png(path, size)
    if kind == "exr":
        return fileio.check_exr(path, size, {"R", "G", "B"})
    if kind == "depth":
        return fileio.check_exr(path, size, {"Z"})
    if kind == "transmission":
        return fileio.check_exr(path, size, set(TRANSMISSION_CHANNELS))
    if kind in ("labels", "labels_visible"):
        return check_label(path)
    return fileio.check_json(path)


_LABEL_LINE = re.compile(r"^(\d+)( (?:0|1|0\.\d+|1\.0+)){4}$")


def check_label(path: Path) -> str | None:
    """Whether a label file is UTF-8 text of ``class cx cy w h`` lines (class a vessel class,
    coordinates in [0, 1]), as seahaze writes them; an empty file (no vessel) is valid."""
    from ..vessels import CLASS_NAMES

    try:
        with open(path, "rb") as handle:
            raw = handle.read(1 << 20)
        text = raw.decode("utf-8")
    except OSError as err:
        return f"cannot be read ({err.strerror or err})"
    except UnicodeDecodeError:
        return "is not text"
    for line in text.splitlines():
        match = _LABEL_LINE.match(line)
        if match is None or int(match[1]) >= len(CLASS_NAMES):
            return "holds a line that is not 'class cx cy w h'"
    return None


def stray_files(root: Path, scenes: set[str], levels: set[str]) -> list[str]:
    """Images and label files in the level folders that are not the dataset's (its scenes at
    its levels): the COCO writer reads every one of them. Relative paths, sorted."""
    strays = []
    for kind in ("images", "labels"):
        base = root / kind
        if not base.is_dir():
            continue
        for folder in sorted(base.iterdir()):
            if not (is_level_name(folder.name) and folder.is_dir()):
                continue
            for path in sorted(folder.iterdir()):
                if path.suffix.lower() not in STRAY_SUFFIXES:
                    continue
                wanted = ".png" if kind == "images" else ".txt"
                if folder.name in levels and path.stem in scenes and path.suffix == wanted:
                    continue
                strays.append(path.relative_to(root).as_posix())
    return strays
