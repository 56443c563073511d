"""Read scene YAML files into validated :class:`~seahaze.spec.SceneSpec` objects.

Every problem is reported at once, each as ``file:line: field: message`` with what is
allowed, sorted by line, so a user fixes a file in one pass: the schema's errors, the
cross-field checks pydantic skips once a field of the same model has failed, and the checks the
schema cannot make (vessel classes, user meshes, the vessel layout), each run on the raw YAML
wherever the fields it reads are sound. A file refused whole (not UTF-8, not YAML, not a
mapping, too large or deep, a folder, unreadable) is located too, at line 1 where no better
line exists. Unknown keys and duplicate keys are errors.
User mesh files named by the scene are found, read and checked here too, and their paths made
absolute in the returned spec, so a bad file is a located message, never a traceback later;
so is a vessel layout that cannot be built (a vessel over the camera, two on one spot, a
sampler that cannot fit its vessels).

Hostile files are refused before they cost anything (:mod:`seahaze.yamlguard`,
docs/limits.md): a scene file is a regular file of at most 1 MiB, its YAML nests at most 32
levels, and its aliases neither refer to themselves nor expand beyond 20,000 nodes.
"""

from __future__ import annotations

import datetime
import math
import re
import stat
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, get_args, get_origin

import yaml
from pydantic import BaseModel, ValidationError

from .spec import BOUND_KINDS, MAX_PLACED_VESSELS, SceneSpec, UserMeshSpec, field_bounds, model_in
from .yamlguard import MAX_SCENE_BYTES, YamlLimitError, compose_limited, read_limited_text

Loc = tuple[str | int, ...]


@dataclass(frozen=True)
class Problem:
    """One thing wrong with a scene file."""

    file: str
    line: int
    field: str
    message: str

    def __str__(self) -> str:
        where = f"{self.file}:{self.line}" if self.line else self.file
        if self.message.startswith("…"):  # the count of the problems left out names no field
            return f"{where}: {self.message}"
        return f"{where}: {self.field or '(file)'}: {self.message}"


MAX_PROBLEMS = 20
"""Most problems reported per file (a file of 20,000 unknown keys gets 20 lines and a count)."""


class SceneFileError(Exception):
    """A scene file that cannot be used; ``problems`` lists every issue found."""

    def __init__(self, problems: list[Problem]):
        self.problems = problems
        super().__init__("\n".join(str(p) for p in problems))


def _index_lines(
    node: yaml.Node, loc: Loc, lines: dict[Loc, int], dupes: list[tuple[Loc, int]]
) -> None:
    """Record the 1-based line of every mapping key and sequence item, and duplicate keys.

    Iterative, so its depth is no limit (:mod:`seahaze.yamlguard` has bounded the node count)."""
    stack: list[tuple[yaml.Node, Loc]] = [(node, loc)]
    while stack:
        node, loc = stack.pop()
        lines.setdefault(loc, node.start_mark.line + 1)
        if isinstance(node, yaml.MappingNode):
            seen: set[str] = set()
            for key_node, value_node in node.value:
                key = str(key_node.value)
                child = (*loc, key)
                if key in seen:
                    dupes.append((child, key_node.start_mark.line + 1))
                seen.add(key)
                lines[child] = key_node.start_mark.line + 1
                stack.append((value_node, child))
        elif isinstance(node, yaml.SequenceNode):
            stack += [(item, (*loc, i)) for i, item in enumerate(node.value)]


def _line_for(loc: Loc, lines: dict[Loc, int]) -> int:
    """The line of the deepest part of ``loc`` present in the file (1 if none: every problem
    is located, an empty file's at its first line)."""
    for end in range(len(loc), -1, -1):
        if loc[:end] in lines:
            return lines[loc[:end]]
    return 1


def _field_info(loc: Loc):
    """The pydantic FieldInfo at ``loc`` inside SceneSpec, or None where it is not a field."""
    model: type[BaseModel] | None = SceneSpec
    info = None
    for part in loc:
        if model is None or not isinstance(part, str):
            continue
        fields = model.model_fields
        name = next((n for n, f in fields.items() if part in (n, f.alias)), None)
        if name is None:
            return None
        info = fields[name]
        annotation = info.annotation
        model = model_in(annotation)
    return info


def _allowed(loc: Loc) -> str:
    """Human text of what a field allows: range and unit, from the schema itself."""
    info = _field_info(loc)
    if info is None:
        return ""
    symbols = {"ge": ">=", "gt": ">", "le": "<=", "lt": "<"}
    found = field_bounds(info)
    if loc and isinstance(loc[-1], int):
        found = _item_bounds(info.annotation, loc[-1]) or found
    bounds = [
        f"{symbols[kind]} {value:g}"
        if isinstance(value, float | int)
        else f"{symbols[kind]} {value}"
        for kind, value in found
    ]
    extra = info.json_schema_extra if isinstance(info.json_schema_extra, dict) else {}
    unit = extra.get("unit")
    parts = []
    if bounds:
        parts.append(" and ".join(bounds))
    if unit and unit != "1":
        parts.append(f"in {unit}")
    return f" (allowed: {', '.join(parts)})" if parts else ""


def _item_bounds(annotation: Any, index: int) -> list[tuple[str, Any]]:
    """The bounds of item ``index`` of a ``list[Annotated[...]]`` or ``tuple[Annotated, ...]``
    field (such as ``haze.levels`` or ``camera.resolution``)."""
    args = [a for a in get_args(annotation) if a is not type(None)]
    if get_origin(annotation) is tuple:
        args = args[index : index + 1]
    elif get_origin(annotation) is not list:
        return []
    return [
        (kind, getattr(bound, kind))
        for meta in getattr(args[0] if args else None, "__metadata__", ())
        for bound in getattr(meta, "metadata", [meta])
        for kind in BOUND_KINDS
        if getattr(bound, kind, None) is not None
    ]


def _dotted(loc: Loc) -> str:
    text = ""
    for part in loc:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text


def _allowed_keys(loc: Loc) -> str:
    """For an unknown key: the keys its section does allow."""
    parent = (
        model_in(_field_info(loc[:-1]).annotation)
        if len(loc) > 1 and _field_info(loc[:-1])
        else SceneSpec
    )
    if parent is None:
        return ""
    keys = [f.alias or n for n, f in parent.model_fields.items()]
    return f"; allowed keys: {', '.join(keys)}"


def _clean_loc(raw: tuple[Any, ...]) -> Loc:
    """A pydantic error location as a path in the YAML: without the names pydantic adds for
    validator functions and for the members of a union such as ``float | Literal[...]``."""
    return tuple(
        p
        for p in raw
        if not (
            isinstance(p, str)
            and (p.startswith("function-") or "[" in p or p in ("float", "int", "str"))
        )
    )


def _message(item: Any, loc: Loc) -> str:
    """The text of one pydantic error at ``loc``, with what the field allows."""
    if item["type"] == "extra_forbidden":
        return f"unknown key '{loc[-1]}'{_allowed_keys(loc)}"
    if item["type"] == "missing" and loc and isinstance(loc[-1], int):
        parent = _field_info(loc[:-1])
        return f"missing list item {loc[-1] + 1} ({_dotted(loc[:-1])}: {parent.description})"
    return item["msg"].replace("Value error, ", "") + _allowed(loc)


MAX_LOCATED = 5 * MAX_PROBLEMS
"""Schema errors located per file; of a file with thousands (20,000 unknown keys) the others
are only counted."""


def _problems_from_validation(
    err: ValidationError, file: str, lines: dict[Loc, int], skip: set[Loc]
) -> tuple[list[Problem], int]:
    """The located problems of a schema error (none at the places in ``skip``, already
    reported better) and the count of the errors not located."""
    problems = []
    errors = err.errors(include_url=False)
    for item in errors[:MAX_LOCATED]:
        loc = _clean_loc(item["loc"])
        if loc in skip:
            continue
        problems.append(Problem(file, _line_for(loc, lines), _dotted(loc), _message(item, loc)))
    return problems, max(0, len(errors) - MAX_LOCATED)


def _reject_non_finite(
    data: Any, loc: Loc, lines: dict[Loc, int], file: str
) -> list[tuple[Loc, Problem]]:
    """YAML accepts .nan and .inf as floats, and dates and !!binary as values; no scene field
    means them. Iterative: the structure's depth is bounded but need not be small."""
    problems: list[tuple[Loc, Problem]] = []
    stack = [(data, loc)]
    while stack and len(problems) < MAX_PROBLEMS:
        item, where = stack.pop()
        message = None
        if isinstance(item, float) and not math.isfinite(item):
            message = f"{item} is not a finite number"
        elif isinstance(item, bytes | datetime.date | set):
            message = f"a YAML {type(item).__name__} value; write a plain number or string"
        elif isinstance(item, dict):
            stack += [(v, (*where, str(k))) for k, v in item.items()]
        elif isinstance(item, list):
            stack += [(v, (*where, i)) for i, v in enumerate(item)]
        if message:
            problem = Problem(file, _line_for(where, lines), _dotted(where), message)
            problems.append((where, problem))
    return problems


def _under(loc: Loc, prefix: Loc) -> bool:
    """Whether ``loc`` is ``prefix`` or lies inside it."""
    return loc[: len(prefix)] == prefix


def _copy_tree(data: Any) -> Any:
    """A copy of the YAML data's dicts and lists (an alias becomes its own copy), so removing a
    value in one place leaves the user's data and the other places alone."""
    if isinstance(data, dict):
        return {k: _copy_tree(v) for k, v in data.items()}
    if isinstance(data, list):
        return [_copy_tree(v) for v in data]
    return data


def _remove(data: Any, loc: Loc) -> Loc | None:
    """Remove the field at ``loc`` (a list item: its whole list, so no index shifts) so that
    its default takes its place; the path removed, or None where there is nothing to remove."""
    while loc and isinstance(loc[-1], int):
        loc = loc[:-1]
    if not loc:
        return None
    node = data
    for part in loc[:-1]:
        if not isinstance(node, dict | list):
            return None
        try:
            node = node[part]  # type: ignore[index]
        except (KeyError, IndexError, TypeError):
            return None
    if not isinstance(node, dict) or loc[-1] not in node:
        return None
    del node[loc[-1]]
    return loc


def _names(name: str, message: str) -> bool:
    """Whether ``message`` carries the field name ``name`` as a word (``top_m`` in
    ``fog_layer.top_m``, not in ``stop_ms``)."""
    return re.search(rf"(?<!\w){re.escape(name)}(?!\w)", message) is not None


def _targets(loc: Loc, message: str) -> list[Loc]:
    """What to remove for an error at ``loc``: where a model's own check failed, the fields it
    compares, which it names (``own_speed_kn and own_heading_deg describe an own ship``), so
    the rest of the model still reaches the checks above it; else the value at ``loc``."""
    info = _field_info(loc) if loc else None
    model = model_in(info.annotation) if info is not None else None
    if model is None:
        return [loc]
    named = {
        name: {name, field.alias or name}
        for name, field in model.model_fields.items()
        if _names(field.alias or name, message) or _names(name, message)
    }
    if not named or len(named) == len(model.model_fields):
        # A message that lists every field ("allowed fields: frames, fps, …") compares none.
        return [loc]
    return [(*loc, key) for keys in named.values() for key in keys]


def _rests_on_removed(where: Loc, message: str, removed: set[Loc]) -> bool:
    """Whether a cross-field check at ``where`` may have seen a default where the user's value
    failed. Every cross-field check of spec.py names the fields it compares in its message
    (``fog_layer.top_m ... must not pass top_m``), so a removed field inside ``where`` whose
    name the message does not carry was not read: the check saw the user's own values."""
    for loc in removed:
        if not _under(loc, where):
            continue
        name = next((p for p in reversed(loc) if isinstance(p, str)), "")
        if name and _names(name, message):
            return True
    return False


MAX_REPAIR_ROUNDS = 8
"""Rounds of removing failed fields to reach the cross-field checks they hid (a scene nests 5
levels: a round per level suffices)."""


def _hidden_checks(
    data: dict[str, Any], failed: list[tuple[Loc, str]]
) -> tuple[list[tuple[Loc, str]], SceneSpec | None, set[Loc]]:
    """The cross-field checks the schema error skipped, run without the failed fields.

    pydantic runs a model's own checks (``haze.fog_layer`` below ``haze.top_m``, a sequence's
    mast height) only when all its fields are valid, so ``haze.albedo: 1.9`` hid them until it
    was fixed. Here the failed fields (``(location, pydantic's message)``) are removed (their
    defaults take their place, :func:`_targets`) and the data validated again, round by round,
    each check found reported unless it may rest on a removed field
    (:func:`_rests_on_removed`). Returns those ``(location, message)`` pairs, the spec of what
    remains (None if none could be built) and the paths removed.
    """
    repaired, removed = _copy_tree(data), set()
    found: list[tuple[Loc, str]] = []
    failed_at = {loc for loc, _ in failed}
    pending = failed
    for _ in range(MAX_REPAIR_ROUNDS):
        progress = False
        for loc, message in pending:
            for target in _targets(loc, message):
                gone = _remove(repaired, target)
                if gone is not None:
                    removed.add(gone)
                    progress = True
        try:
            return found, SceneSpec.model_validate(repaired), removed
        except ValidationError as err:
            errors = err.errors(include_url=False)
        pending = []
        for item in errors:
            loc = _clean_loc(item["loc"])
            if not loc:  # SceneSpec's own checks: each run below
                continue
            if item["type"] == "missing":
                # A required field removed in an earlier round: its model goes as a whole.
                pending.append((loc[:-1], ""))
                continue
            if loc in failed_at:  # told already; its removal did not take
                pending.append((loc, item["msg"]))
                continue
            message = _message(item, loc)
            if not _rests_on_removed(loc, message, removed):
                found.append((loc, message))
            pending.append((loc, item["msg"]))
        if not pending or not progress:
            break
    spec = _unchecked_scene(repaired)
    if spec is None:
        return found, None, removed
    return (
        found + [((), m) for m in _scene_checks(spec) if not _rests_on_removed((), m, removed)],
        spec,
        removed,
    )


def _unchecked_scene(data: dict[str, Any]) -> SceneSpec | None:
    """The scene of ``data`` with every section validated but SceneSpec's own cross-section
    checks not run (None if a section is invalid): the checks are then run one by one, each
    reported, where pydantic stops at the first that fails."""
    values = {}
    for name, info in SceneSpec.model_fields.items():
        if name not in data:
            continue
        model, value = model_in(info.annotation), data[name]
        try:
            values[name] = model.model_validate(value) if model and value is not None else value
        except ValidationError:
            return None
    return SceneSpec.model_construct(**values)


def _scene_checks(spec: SceneSpec) -> list[str]:
    """The messages of SceneSpec's own ``mode="after"`` validators on ``spec``, every one run
    (pydantic's documented ``__pydantic_decorators__`` lists them)."""
    messages = []
    for decorator in SceneSpec.__pydantic_decorators__.model_validators.values():
        if decorator.info.mode != "after":
            continue
        try:
            decorator.func(spec)
        except ValueError as exc:
            messages.append(str(exc))
    return messages


LAYOUT_READS: tuple[Loc, ...] = (("camera",), ("vessels",), ("render", "seed"), ("sequence",))
"""What :func:`layout_problems` reads of a scene (:func:`seahaze.world.frame_layout`): the
layout is checked when none of it failed, whatever else did."""


def parse_scene_text(
    text: str, file: str = "<scene>", base_dir: str | Path | None = None
) -> SceneSpec:
    """Validate YAML text into a SceneSpec; raises :class:`SceneFileError` listing every problem.

    Relative user-mesh paths are looked up in ``base_dir`` (the scene file's folder; default the
    working directory), then in the repository's ``assets/``.
    """
    try:
        data, node = compose_limited(text)
    except YamlLimitError as exc:
        raise SceneFileError([Problem(file, exc.line or 1, "", exc.message)]) from None
    if data is None:
        data = {}
    if not isinstance(data, dict):
        line = node.start_mark.line + 1 if node is not None else 1
        message = f"a scene is a mapping of sections, got {type(data).__name__}"
        raise SceneFileError([Problem(file, line, "", message)])
    lines: dict[Loc, int] = {}
    dupes: list[tuple[Loc, int]] = []
    if node is not None:
        _index_lines(node, (), lines, dupes)
    problems = [
        Problem(file, line, _dotted(loc), "duplicate key (the later value would silently win)")
        for loc, line in dupes
    ]
    odd_values = _reject_non_finite(data, (), lines, file)
    problems += [problem for _, problem in odd_values]
    # Places whose values are doubtful: the layout is not checked on them.
    doubtful = [loc for loc, _ in dupes] + [loc for loc, _ in odd_values]
    failed: list[Loc] = []
    unlocated = 0
    try:
        spec: SceneSpec | None = SceneSpec.model_validate(data)
    except ValidationError as err:
        # `.nan` fails its bounds too: the one problem is told once, as not finite.
        skip = {loc for loc, _ in odd_values}
        located, unlocated = _problems_from_validation(err, file, lines, skip)
        problems += located
        errors = err.errors(include_url=False)
        hidden, spec, removed = _hidden_checks(
            data, [(_clean_loc(item["loc"]), item["msg"]) for item in errors]
        )
        failed = [_clean_loc(item["loc"]) for item in errors]
        problems += [Problem(file, _line_for(loc, lines), _dotted(loc), m) for loc, m in hidden]
        # SceneSpec's own checks (location ()) compare sections; the layout reads none of them.
        doubtful += [loc for loc in failed if loc] + list(removed)

    def sound(loc: Loc) -> bool:
        return not any(_under(bad, loc) for bad in failed)

    vessel_problems, mesh_paths = _vessel_problems(data, sound, file, lines, base_dir)
    problems += vessel_problems
    if spec is not None:
        spec = _with_mesh_paths(spec, mesh_paths)
    layout_sound = not any(_under(a, b) or _under(b, a) for a in doubtful for b in LAYOUT_READS)
    if spec is not None and layout_sound and not vessel_problems:
        # A vessel that cannot be built has no footprint: the layout waits for it.
        problems += [
            Problem(file, _line_for(loc, lines), _dotted(loc), message)
            for loc, message in layout_problems(spec)
        ]
    if problems or unlocated:
        raise SceneFileError(_capped(problems, unlocated, file))
    assert spec is not None
    return spec


def _capped(problems: list[Problem], unlocated: int, file: str) -> list[Problem]:
    """The problems once each, sorted by line, at most :data:`MAX_PROBLEMS` and a count of the
    rest (``unlocated`` more were counted, not located)."""
    problems = sorted(dict.fromkeys(problems), key=lambda p: p.line)
    shown = problems[:MAX_PROBLEMS]
    rest = len(problems) - len(shown) + unlocated
    if not rest:
        return shown
    # The count sits at the first line left out (the last shown where none was located).
    line = [*problems[len(shown) :], *reversed(shown), Problem(file, 1, "", "")][0].line
    return [*shown, Problem(file, line, "", f"… and {rest} more problem(s)")]


def _is_number(value: Any) -> bool:
    """A finite int or float of the YAML (``true`` is no number here, as in the schema)."""
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def _vessel_problems(
    data: dict[str, Any],
    sound: Callable[[Loc], bool],
    file: str,
    lines: dict[Loc, int],
    base_dir: str | Path | None,
) -> tuple[list[Problem], dict[int, Path]]:
    """What the schema cannot know of the vessels: their classes (in the library), lengths
    and speeds (in their class's ranges) and user meshes (found, readable, usable).

    Read from the raw YAML, one vessel at a time, so a camera block or another vessel that
    failed the schema hides none of it; a value is checked only where ``sound`` (it passed the
    schema), so no problem is told twice. Returns the problems and each usable user mesh's
    absolute path by vessel index.
    """
    from .vessels import CLASS_NAMES, length_problem, speed_problem

    def problem(loc: Loc, message: str) -> Problem:
        return Problem(file, _line_for(loc, lines), _dotted(loc), message)

    allowed = ", ".join(CLASS_NAMES)
    problems: list[Problem] = []
    paths: dict[int, Path] = {}
    vessels = data.get("vessels")
    vessels = vessels if isinstance(vessels, dict) else {}
    placed = vessels.get("placed")
    # Beyond MAX_PLACED_VESSELS the schema refused the list: no more meshes are read for it.
    placed = placed[:MAX_PLACED_VESSELS] if isinstance(placed, list) else []
    for i, raw in enumerate(placed):
        if not isinstance(raw, dict):
            continue
        base: Loc = ("vessels", "placed", i)
        key = "class" if "class" in raw or "kind" not in raw else "kind"  # populate_by_name
        kind = raw.get(key)
        known = isinstance(kind, str) and kind in CLASS_NAMES
        if isinstance(kind, str) and not known and sound((*base, key)):
            problems.append(
                problem((*base, key), f"unknown vessel class '{kind}'; allowed: {allowed}")
            )
        checks = [("speed_kn", speed_problem)]
        if raw.get("mesh") is None:  # with a mesh, its length is mesh.scale_m
            checks.append(("length_m", length_problem))
        for name, check in checks:
            value = raw.get(name)
            if known and _is_number(value) and sound((*base, name)):
                text = check(kind, float(value))
                if text is not None:
                    problems.append(problem((*base, name), text))
        mesh_problem, path = _user_mesh(raw, kind if known else None, base, base_dir, sound)
        if mesh_problem is not None:
            problems.append(problem(*mesh_problem))
        elif path is not None:
            paths[i] = path
    sample = vessels.get("sample")
    classes = sample.get("classes") if isinstance(sample, dict) else None
    for kind in classes if isinstance(classes, dict) else ():
        if isinstance(kind, str) and kind not in CLASS_NAMES:
            loc = ("vessels", "sample", "classes", kind)
            problems.append(problem(loc, f"unknown vessel class '{kind}'; allowed: {allowed}"))
    return sorted(problems, key=lambda p: p.line), paths


def _user_mesh(
    raw: dict[str, Any],
    kind: str | None,
    base: Loc,
    base_dir: str | Path | None,
    sound: Callable[[Loc], bool],
) -> tuple[tuple[Loc, str] | None, Path | None]:
    """Find, read and check one placed vessel's user mesh (``raw['mesh']``): its problem as
    ``(location, message)``, or its absolute path (None without a usable mesh block).

    The mesh is loaded once here (small files load in milliseconds) because only reading it
    tells a truncated or wrong-content file from a good one; it is loaded only for a known
    ``kind`` (an unknown class is its own problem).
    """
    from . import vessels

    loc: Loc = (*base, "mesh", "path")
    if not isinstance(raw.get("mesh"), dict) or not sound((*base, "mesh")):
        return None, None
    try:
        mesh = UserMeshSpec.model_validate(raw["mesh"])
    except ValidationError:  # reported by the schema
        return None, None
    search = vessels.mesh_search_dirs(base_dir)
    allowed = ", ".join(vessels.SUPPORTED_FORMATS)
    suffix = Path(mesh.path).suffix.lower()
    if suffix not in vessels.SUPPORTED_FORMATS:
        return (loc, f"unsupported mesh format '{suffix or mesh.path}'; allowed: {allowed}"), None
    path = vessels.resolve_mesh_path(mesh.path, search)
    if path is None:
        where = " or ".join(str(d) for d in search)
        return (
            loc,
            f"no such mesh file '{mesh.path}' (looked in {where}); allowed: an absolute path "
            "or one relative to the scene file's folder or to assets/",
        ), None
    size_problem = _mesh_file_problem(Path(path))
    if size_problem:
        return (loc, size_problem), None
    if kind is None:
        return None, None
    try:
        vessels.load_user_mesh(
            path, kind, mesh.scale_m, mesh.up_axis, mesh.forward_axis, draft_m=mesh.draft_m
        )
    except vessels.SubmergedMeshError as exc:
        return ((*base, "mesh", "draft_m"), str(exc)), None
    except Exception as exc:  # trimesh raises many types; each is a located message
        text = str(exc).strip()
        reason = text.splitlines()[0] if text else type(exc).__name__
        return (
            loc,
            f"cannot use the mesh: {reason}; allowed: a readable {allowed} file with triangles",
        ), None
    return None, Path(path)


def _with_mesh_paths(spec: SceneSpec, paths: dict[int, Path]) -> SceneSpec:
    """``spec`` with the user meshes at their absolute paths (later steps need not search)."""
    if not paths:
        return spec
    placed = list(spec.vessels.placed)
    for i, path in paths.items():
        mesh = placed[i].mesh if i < len(placed) else None
        if mesh is not None:
            placed[i] = placed[i].model_copy(
                update={"mesh": mesh.model_copy(update={"path": str(path)})}
            )
    vessels = spec.vessels.model_copy(update={"placed": placed})
    return spec.model_copy(update={"vessels": vessels})


def layout_problems(spec: SceneSpec) -> list[tuple[Loc, str]]:
    """Whether the vessel layout of ``spec`` (with its ``render.seed``) can be built: a vessel
    over the camera, two on one spot, a sampler that cannot fit its vessels or, in a sequence,
    courses that meet at any frame would otherwise fail the render. Returns ``(location,
    message)`` pairs; the layout is cheap (no meshes but the user meshes, which are small)."""
    from .camera import Camera
    from .motion import MotionError
    from .world import frame_layout

    if not spec.vessels.placed and (spec.vessels.sample is None or not spec.vessels.sample.count):
        return []
    try:
        # A sequence's courses are checked over every frame: no two hulls may ever meet.
        frame_layout(spec, Camera.from_spec(spec.camera), 0 if spec.sequence else None)
    except MotionError as exc:
        return [(("sequence",), f"the vessels' courses cannot be sailed: {exc}")]
    except (ValueError, FileNotFoundError) as exc:  # LayoutError is a ValueError
        text = str(exc).strip().splitlines()
        message = text[0] if text else type(exc).__name__
        sample_failed = message.startswith("could not place vessel")
        loc: Loc = ("vessels", "sample") if sample_failed else ("vessels", "placed")
        return [(loc, f"the vessels cannot be laid out: {message}")]
    return []


MAX_MESH_BYTES = 256 << 20
"""Largest user mesh file (256 MiB: a few million triangles)."""


def _mesh_file_problem(path: Path) -> str | None:
    """A user mesh must be a regular file of at most :data:`MAX_MESH_BYTES` (a symlink to
    ``/dev/zero`` named ``hull.obj`` would be read forever)."""
    try:
        info = path.stat()
    except OSError as exc:
        return f"cannot read the mesh: {exc.strerror or exc}"
    if not stat.S_ISREG(info.st_mode):
        return "the mesh is not a regular file (a folder, device or FIFO)"
    if info.st_size > MAX_MESH_BYTES:
        return f"the mesh file is {info.st_size / 2**20:,.0f} MiB; at most 256 MiB"
    return None


def load_scene(path: str | Path) -> tuple[SceneSpec, str]:
    """Load and validate a scene file; returns the spec and the scene name.

    Raises :class:`SceneFileError` for a missing, unreadable or invalid file.
    """
    path = Path(path)
    try:
        text = read_limited_text(path, MAX_SCENE_BYTES, "a scene file", "a scene is a YAML file")
    except YamlLimitError as exc:
        # A file not read at all (missing, a folder, too large) is located at its line 1.
        raise SceneFileError([Problem(str(path), exc.line or 1, "", exc.message)]) from None
    spec = parse_scene_text(text, str(path), path.parent)
    return spec, spec.name or path.stem
