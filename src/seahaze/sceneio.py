"""Read scene YAML files into validated :class:`~seahaze.spec.SceneSpec` objects.

Every problem is reported at once, each with ``file:line``, the dotted field and what is
allowed, so a user fixes a file in one pass. Unknown keys and duplicate keys are errors.
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
import stat
from dataclasses import dataclass
from pathlib import Path
from typing import Any, get_args, get_origin

import yaml
from pydantic import BaseModel, ValidationError

from .spec import BOUND_KINDS, SceneSpec, field_bounds, model_in
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
    """The line of the deepest part of ``loc`` present in the file (0 if none)."""
    for end in range(len(loc), -1, -1):
        if loc[:end] in lines:
            return lines[loc[:end]]
    return 0


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


def _problems_from_validation(
    err: ValidationError, file: str, lines: dict[Loc, int]
) -> list[Problem]:
    problems = []
    # A file of thousands of unknown keys gets thousands of errors: only the first are located
    # (MAX_PROBLEMS are shown), the count of the others is kept.
    errors = err.errors(include_url=False)
    for item in errors[: 5 * MAX_PROBLEMS]:
        loc = tuple(
            p for p in item["loc"] if not (isinstance(p, str) and p.startswith("function-"))
        )
        # pydantic puts the union member name in loc for `float | Literal[...]`; drop such parts.
        loc = tuple(
            p
            for p in loc
            if not (isinstance(p, str) and ("[" in p or p in ("float", "int", "str")))
        )
        if item["type"] == "extra_forbidden":
            message = f"unknown key '{loc[-1]}'{_allowed_keys(loc)}"
        elif item["type"] == "missing" and loc and isinstance(loc[-1], int):
            parent = _field_info(loc[:-1])
            message = f"missing list item {loc[-1] + 1} ({_dotted(loc[:-1])}: {parent.description})"
        else:
            message = item["msg"].replace("Value error, ", "") + _allowed(loc)
        problems.append(Problem(file, _line_for(loc, lines), _dotted(loc), message))
    # Several union branches can report the same place; keep one message per place and text.
    problems = list(dict.fromkeys(problems))
    if len(errors) > 5 * MAX_PROBLEMS:
        problems.append(Problem(file, 0, "", f"… and {len(errors) - 5 * MAX_PROBLEMS} more"))
    return problems


def _reject_non_finite(data: Any, loc: Loc, lines: dict[Loc, int], file: str) -> list[Problem]:
    """YAML accepts .nan and .inf as floats, and dates and !!binary as values; no scene field
    means them. Iterative: the structure's depth is bounded but need not be small."""
    problems, stack = [], [(data, loc)]
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
            problems.append(Problem(file, _line_for(where, lines), _dotted(where), message))
    return problems


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
        raise SceneFileError([Problem(file, exc.line, "", exc.message)]) from None
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise SceneFileError(
            [Problem(file, 1, "", f"a scene is a mapping of sections, got {type(data).__name__}")]
        )
    lines: dict[Loc, int] = {}
    dupes: list[tuple[Loc, int]] = []
    if node is not None:
        _index_lines(node, (), lines, dupes)
    problems = [
        Problem(file, line, _dotted(loc), "duplicate key (the later value would silently win)")
        for loc, line in dupes
    ]
    problems += _reject_non_finite(data, (), lines, file)
    try:
        spec = SceneSpec.model_validate(data)
    except ValidationError as err:
        problems += _problems_from_validation(err, file, lines)
        spec = None
    if spec is not None:
        problems += _check_vessel_classes(spec, file, lines)
        mesh_problems, spec = _resolve_user_meshes(spec, file, lines, base_dir)
        problems += mesh_problems
    if spec is not None and not problems:
        problems += [
            Problem(file, _line_for(loc, lines), _dotted(loc), message)
            for loc, message in layout_problems(spec)
        ]
    if problems:
        problems = sorted(problems, key=lambda p: (p.message.startswith("…"), p.line))
        if len(problems) > MAX_PROBLEMS:
            more = len(problems) - MAX_PROBLEMS
            rest = Problem(file, 0, "", f"… and {more} more problem(s)")
            problems = [*problems[:MAX_PROBLEMS], rest]
        raise SceneFileError(problems)
    assert spec is not None
    return spec


def _check_vessel_classes(spec: SceneSpec, file: str, lines: dict[Loc, int]) -> list[Problem]:
    """Vessel classes are checked against the library, which the schema cannot know."""
    from .vessels import CLASS_NAMES, length_problem, speed_problem

    allowed = ", ".join(CLASS_NAMES)
    problems = []
    for i, vessel in enumerate(spec.vessels.placed):
        loc: Loc = ("vessels", "placed", i, "class")
        if vessel.kind not in CLASS_NAMES:
            problems.append(
                Problem(
                    file,
                    _line_for(loc, lines),
                    _dotted(loc),
                    f"unknown vessel class '{vessel.kind}'; allowed: {allowed}",
                )
            )
            continue
        problem = None if vessel.length_m is None else length_problem(vessel.kind, vessel.length_m)
        if problem is not None:
            loc = ("vessels", "placed", i, "length_m")
            problems.append(Problem(file, _line_for(loc, lines), _dotted(loc), problem))
        problem = None if vessel.speed_kn is None else speed_problem(vessel.kind, vessel.speed_kn)
        if problem is not None:
            loc = ("vessels", "placed", i, "speed_kn")
            problems.append(Problem(file, _line_for(loc, lines), _dotted(loc), problem))
    sampler = spec.vessels.sample
    for kind in (sampler.classes or {}) if sampler else {}:
        if kind not in CLASS_NAMES:
            loc = ("vessels", "sample", "classes", kind)
            problems.append(
                Problem(
                    file,
                    _line_for(loc, lines),
                    _dotted(loc),
                    f"unknown vessel class '{kind}'; allowed: {allowed}",
                )
            )
    return problems


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


def _resolve_user_meshes(
    spec: SceneSpec, file: str, lines: dict[Loc, int], base_dir: str | Path | None
) -> tuple[list[Problem], SceneSpec]:
    """Find, read and check every user mesh; the spec with their absolute paths.

    The mesh is loaded once here (small files load in milliseconds) because only reading it
    tells a truncated or wrong-content file from a good one.
    """
    from .vessels import (
        CLASS_NAMES,
        SUPPORTED_FORMATS,
        SubmergedMeshError,
        load_user_mesh,
        mesh_search_dirs,
        resolve_mesh_path,
    )

    search = mesh_search_dirs(base_dir)
    allowed = ", ".join(SUPPORTED_FORMATS)
    problems = []
    placed = list(spec.vessels.placed)
    for i, vessel in enumerate(placed):
        mesh = vessel.mesh
        if mesh is None:
            continue
        loc: Loc = ("vessels", "placed", i, "mesh", "path")

        def problem(message: str, loc: Loc = loc) -> Problem:
            return Problem(file, _line_for(loc, lines), _dotted(loc), message)

        suffix = Path(mesh.path).suffix.lower()
        if suffix not in SUPPORTED_FORMATS:
            problems.append(
                problem(f"unsupported mesh format '{suffix or mesh.path}'; allowed: {allowed}")
            )
            continue
        path = resolve_mesh_path(mesh.path, search)
        if path is None:
            where = " or ".join(str(d) for d in search)
            problems.append(
                problem(
                    f"no such mesh file '{mesh.path}' (looked in {where}); allowed: an "
                    f"absolute path or one relative to the scene file's folder or to assets/"
                )
            )
            continue
        size_problem = _mesh_file_problem(Path(path))
        if size_problem:
            problems.append(problem(size_problem))
            continue
        if vessel.kind in CLASS_NAMES:  # an unknown class is reported by _check_vessel_classes
            try:
                load_user_mesh(
                    path,
                    vessel.kind,
                    mesh.scale_m,
                    mesh.up_axis,
                    mesh.forward_axis,
                    draft_m=mesh.draft_m,
                )
            except SubmergedMeshError as exc:
                draft_loc: Loc = ("vessels", "placed", i, "mesh", "draft_m")
                problems.append(problem(str(exc), draft_loc))
                continue
            except Exception as exc:  # trimesh raises many types; each is a located message
                text = str(exc).strip()
                reason = text.splitlines()[0] if text else type(exc).__name__
                problems.append(
                    problem(
                        f"cannot use the mesh: {reason}; allowed: a readable {allowed} file "
                        "with triangles"
                    )
                )
                continue
        resolved = mesh.model_copy(update={"path": str(path)})
        placed[i] = vessel.model_copy(update={"mesh": resolved})
    vessels = spec.vessels.model_copy(update={"placed": placed})
    return problems, spec.model_copy(update={"vessels": vessels})


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
        raise SceneFileError([Problem(str(path), exc.line, "", exc.message)]) from None
    spec = parse_scene_text(text, str(path), path.parent)
    return spec, spec.name or path.stem
