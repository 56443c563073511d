"""Reading YAML from users without tracebacks, hangs or unbounded memory (docs/limits.md).

PyYAML composes recursively (a few thousand ``[`` raise RecursionError), follows recursive
anchors into cyclic structures, and lets a few aliases expand into millions of nodes (the
"billion laughs"); ``open()`` on a FIFO blocks and ``/dev/zero`` never ends. Here a text file is
read only if it is a regular file within a size limit, and YAML is composed only after its
nesting is checked on the event stream (which does not recurse), then measured once composed —
expanded size and depth, memoised per node, cycles refused — before anything walks it.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path
from typing import Any

import yaml

MAX_SCENE_BYTES = 1 << 20
"""Largest scene file (1 MiB; the default scene is 1.5 kB, 200 placed vessels about 20 kB)."""
MAX_YAML_DEPTH = 32
"""Deepest nesting of mappings and lists (a scene needs 5: vessels.placed[i].mesh.path)."""
MAX_YAML_NODES = 20_000
"""Most YAML nodes once aliases are expanded (200 placed vessels are about 2,500)."""
_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
"""libyaml's parser where PyYAML has it (20x faster on a 1 MiB file), else the pure-Python one;
both construct with PyYAML's safe constructor."""


class YamlLimitError(ValueError):
    """Text that is not read: ``line`` (1-based; 0 for a file not read at all, whose problem
    is the whole file) and a one-line ``message``."""

    def __init__(self, line: int, message: str):
        self.line, self.message = line, message
        super().__init__(f"{line}: {message}" if line else message)


def read_limited_text(path: Path, limit: int, what: str, expected: str) -> str:
    """The UTF-8 text of the regular file ``path`` of at most ``limit`` bytes.

    ``what`` names the file in messages ("a scene file"), ``expected`` says what it should be.
    A missing file, a folder, a device, FIFO or socket, a larger file, an unreadable one and
    bytes that are not UTF-8 raise :class:`YamlLimitError` without blocking or reading more
    than ``limit + 1`` bytes.
    """
    size = f"{limit / (1 << 20):g} MiB" if limit >= 1 << 20 else f"{limit:,} bytes"
    try:
        info = path.stat()
    except FileNotFoundError:
        raise YamlLimitError(0, "no such file") from None
    except (OSError, ValueError) as exc:  # ValueError: a NUL byte in the name
        raise YamlLimitError(0, f"cannot read: {exc}") from None
    if stat.S_ISDIR(info.st_mode):
        raise YamlLimitError(0, f"is a folder; {expected}")
    if not stat.S_ISREG(info.st_mode):
        raise YamlLimitError(0, f"not a regular file (a device, FIFO or socket); {expected}")
    if info.st_size > limit:
        raise YamlLimitError(0, f"{info.st_size:,} bytes; {what} is at most {size}")
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
        with os.fdopen(fd, "rb") as handle:
            raw = handle.read(limit + 1)
    except OSError as exc:
        raise YamlLimitError(0, f"cannot read: {exc.strerror or exc}") from None
    if len(raw) > limit:
        raise YamlLimitError(0, f"more than {size}; {what} is at most {size}")
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw[: exc.start].count(b"\n") + 1
        raise YamlLimitError(line, f"not UTF-8 text (a binary file?); {expected}") from None


def compose_limited(text: str) -> tuple[Any, yaml.Node | None]:
    """The data and the node tree of one YAML document, after the limits are checked.

    Raises :class:`YamlLimitError` for text beyond the limits and for anything PyYAML rejects
    (syntax, several documents, an integer of more than 4300 digits, a date like 2024-13-45).
    """
    if len(text) > MAX_SCENE_BYTES:
        raise YamlLimitError(1, f"{len(text):,} characters; at most 1 MiB")
    _check_nesting(text)
    loader = None
    node = None
    try:
        loader = _LOADER(text)
        node = loader.get_single_node()
        if node is None:
            return None, None
        _check_structure(node)
        return loader.construct_document(node), node
    except yaml.YAMLError as exc:
        # The problem's place, else its context's (a second document: where it starts).
        mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
        line = mark.line + 1 if mark is not None else 1
        if isinstance(exc, yaml.reader.ReaderError):  # a control character: its position
            line = text.count("\n", 0, max(0, exc.position)) + 1
        reason = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise YamlLimitError(line, f"not valid YAML: {reason}") from None
    except (ValueError, OverflowError) as exc:
        if isinstance(exc, YamlLimitError):
            raise
        # The constructor's own errors (a date like 2024-13-45, an integer of 5000 digits):
        # PyYAML gives no line for them, the scalar that raises is looked for.
        reason = str(exc).split(";")[0].splitlines()[0] if str(exc) else type(exc).__name__
        line = _failing_scalar_line(node) if node is not None else 1
        raise YamlLimitError(line, f"not valid YAML: {reason}") from None
    finally:
        if loader is not None:
            loader.dispose()


def _failing_scalar_line(root: yaml.Node) -> int:
    """The 1-based line of the first scalar under ``root`` (in file order) that PyYAML's safe
    constructor cannot turn into a value; 1 if each does on its own."""
    scalars: list[yaml.ScalarNode] = []
    stack = [root]
    seen: set[int] = set()
    while stack:  # iterative and once per node: aliases share nodes, and depth is no limit
        node = stack.pop()
        if id(node) in seen:
            continue
        seen.add(id(node))
        if isinstance(node, yaml.ScalarNode):
            scalars.append(node)
        else:
            stack += _children(node)
    constructor = yaml.SafeLoader("")
    try:
        for node in sorted(scalars, key=lambda n: (n.start_mark.line, n.start_mark.column)):
            try:
                constructor.construct_object(node)
            except (ValueError, OverflowError, yaml.YAMLError):
                return node.start_mark.line + 1
    finally:
        constructor.dispose()
    return 1


def _check_nesting(text: str) -> None:
    """Refuse nesting deeper than :data:`MAX_YAML_DEPTH` on the event stream, at the first
    level too deep. Syntax errors are left to the composer, which reports their line.

    libyaml 0.2.5 as bundled with PyYAML 6.0.4 refuses 1000 levels itself, and its scanner
    reads up to 1024 characters ahead of the event it hands out (to find simple keys), so a
    line of ``[`` can hit that limit before the 33rd event: it is the same refusal.
    """
    depth = 0
    try:
        for event in yaml.parse(text, Loader=_LOADER):
            if isinstance(event, yaml.CollectionStartEvent):
                depth += 1
                if depth > MAX_YAML_DEPTH:
                    raise _too_deep(event.start_mark.line + 1)
            elif isinstance(event, yaml.CollectionEndEvent):
                depth -= 1
    except yaml.YAMLError as exc:
        if "nesting depth" in str(getattr(exc, "problem", "")):
            mark = getattr(exc, "problem_mark", None)
            raise _too_deep(mark.line + 1 if mark is not None else 1) from None


def _too_deep(line: int) -> YamlLimitError:
    """The refusal of text nested deeper than :data:`MAX_YAML_DEPTH`, at 1-based ``line``."""
    return YamlLimitError(line, f"nested deeper than {MAX_YAML_DEPTH} levels; a scene needs 5")


def _check_structure(root: yaml.Node) -> None:
    """Refuse an alias inside its own anchor, and aliases that expand beyond
    :data:`MAX_YAML_NODES` nodes or :data:`MAX_YAML_DEPTH` levels, without expanding them."""
    size: dict[int, int] = {}
    depth: dict[int, int] = {}
    on_path: set[int] = set()
    stack: list[tuple[yaml.Node, bool]] = [(root, False)]
    while stack:
        node, children_done = stack.pop()
        key, kids = id(node), _children(node)
        if children_done:
            on_path.discard(key)
            size[key] = 1 + sum(size[id(k)] for k in kids)
            depth[key] = 1 + max((depth[id(k)] for k in kids), default=0)
            line = node.start_mark.line + 1
            if size[key] > MAX_YAML_NODES:
                raise YamlLimitError(
                    line,
                    f"more than {MAX_YAML_NODES:,} YAML nodes (aliases expanded); a scene has a "
                    "few thousand: write the values out or use fewer aliases",
                )
            if depth[key] > MAX_YAML_DEPTH:
                raise YamlLimitError(
                    line, f"its aliases nest deeper than {MAX_YAML_DEPTH} levels; a scene needs 5"
                )
            continue
        if key in size:
            continue
        on_path.add(key)
        stack.append((node, True))
        for kid in kids:
            kid_key = id(kid)
            if kid_key in size:
                continue
            if isinstance(kid, yaml.ScalarNode):
                size[kid_key] = depth[kid_key] = 1
            elif kid_key in on_path:
                raise YamlLimitError(
                    kid.start_mark.line + 1,
                    "a YAML alias refers to a node that contains it (a recursive anchor); a "
                    "scene is a tree",
                )
            else:
                stack.append((kid, False))


def _children(node: yaml.Node) -> list[yaml.Node]:
    if isinstance(node, yaml.MappingNode):
        return [n for pair in node.value for n in pair]
    if isinstance(node, yaml.SequenceNode):
        return list(node.value)
    return []
