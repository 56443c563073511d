"""The dataset folder a batch renders into: its manifest, what changed since, and clean-up.

Every function here reads or tidies the folder; none renders.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
from pathlib import Path
from typing import Any

from ..spec import SceneSpec
from ..visibility import is_level_name
from .errors import ConfigChangedError

_TMP_FILE = re.compile(r"^\..+\.tmp\d+$")  # seahaze.fileio.atomic_target's temporary names


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
        a = _flatten({k: v for k, v in old_scenes[name].items() if k not in ("status", "error")})
        b = _flatten({k: v for k, v in entry.items() if k != "status"})
        changed = [p for p in sorted(set(a) | set(b)) if a.get(p, "(none)") != b.get(p, "(none)")]
        if changed:
            p = changed[0]
            more = f" (and {len(changed) - 1} more)" if len(changed) > 1 else ""
            lines.append(
                f"scene {name}: {p} is {a.get(p, '(none)')!r} there, "
                f"{b.get(p, '(none)')!r} now{more}"
            )
    return lines


def read_manifest(path: Path, force: bool) -> dict[str, Any] | None:
    """The folder's manifest; None where there is none. One that cannot be read is refused,
    or under ``force`` taken as an empty one (so every file not planned is deleted)."""
    if not path.exists():
        return None
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        problem = None if isinstance(data, dict) else "not a seahaze manifest"
    except (OSError, UnicodeDecodeError, ValueError) as err:
        problem = describe_error(err)
    if problem is None:
        return data
    if force:
        return {}
    raise ConfigChangedError(
        f"cannot use {path} ({problem}); choose another --out, or --force to replace the dataset"
    )


def remove_temporaries(root: Path) -> int:
    """Delete temporary files a killed run left behind; returns how many."""
    removed = 0
    for folder, _dirs, files in os.walk(root):
        for name in files:
            if _TMP_FILE.match(name):
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(os.path.join(folder, name))
                    removed += 1
    return removed


def prune(root: Path, keep_scenes: set[str], keep_levels: set[str]) -> int:
    """Under ``force``: delete files of scenes and levels the new config no longer has."""
    removed = 0
    for kind in ("images", "labels", "exr"):
        base = root / kind
        if not base.is_dir():
            continue
        for level_dir in base.iterdir():
            if not (level_dir.is_dir() and is_level_name(level_dir.name)):
                continue
            for path in level_dir.iterdir():
                if level_dir.name not in keep_levels or path.stem not in keep_scenes:
                    path.unlink()
                    removed += 1
            if level_dir.name not in keep_levels:
                with contextlib.suppress(OSError):
                    level_dir.rmdir()
    for kind, keep in (("depth", keep_scenes), ("meta", keep_scenes), ("coco", keep_levels)):
        base = root / kind
        for path in base.iterdir() if base.is_dir() else ():
            if path.is_file() and path.stem not in keep:
                path.unlink()
                removed += 1
    return removed
