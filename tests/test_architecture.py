"""The shape of the code: imports flow one way (no cycles), modules stay small.

The import graph is read from the source with ``ast`` (every ``import`` and ``from … import``,
including those inside functions, which is where cycles hide), so the test needs no import of
seahaze and fails on a new cycle with the modules that form it.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"
PACKAGE = SRC / "seahaze"
MAX_LINES = 500
DECLARATIVE = {"seahaze.spec", "seahaze.vessels.merchant"}
"""Modules allowed past MAX_LINES: the scene schema's fields and the vessel builders, which read
as tables of parts rather than logic."""


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for p in PACKAGE.rglob("*.py")}


def _resolve(module: str, is_package: bool, level: int, target: str | None) -> str:
    """The absolute module name of a relative import in ``module``."""
    if level == 0:
        return target or ""
    base = module.split(".")
    if not is_package:
        base = base[:-1]
    base = base[: len(base) - (level - 1)]
    return ".".join(base + ([target] if target else []))


def import_graph() -> dict[str, set[str]]:
    """Module → the seahaze modules it imports (a name imported from a package counts as its
    submodule when one of that name exists, else as the package)."""
    modules = _modules()
    graph: dict[str, set[str]] = {name: set() for name in modules}
    for name, path in modules.items():
        is_package = path.name == "__init__.py"
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            targets: list[str] = []
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = _resolve(name, is_package, node.level, node.module)
                for alias in node.names:
                    sub = f"{base}.{alias.name}"
                    targets.append(sub if sub in modules else base)
            for target in targets:
                while target and target not in modules:
                    target = target.rpartition(".")[0]
                if target and target != name:
                    graph[name].add(target)
    return graph


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One import cycle as a list of modules (first repeated at the end), or None."""
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                return [*stack[stack.index(nxt) :], nxt]
            if nxt not in state and (cycle := visit(nxt)) is not None:
                return cycle
        stack.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state and (cycle := visit(node)) is not None:
            return cycle
    return None


def test_the_import_graph_has_no_cycle() -> None:
    cycle = find_cycle(import_graph())
    assert cycle is None, "import cycle: " + " -> ".join(cycle or [])


def test_the_cycle_finder_finds_a_cycle() -> None:
    # The checker itself must be able to fail: a lazy back-edge closes a loop.
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert find_cycle(graph) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set()}) is None


def test_relative_imports_resolve_like_python() -> None:
    assert _resolve("seahaze.render.physical", False, 1, "passes") == "seahaze.render.passes"
    assert _resolve("seahaze.render.physical", False, 2, "haze") == "seahaze.haze"
    assert _resolve("seahaze.batch", True, 1, "plan") == "seahaze.batch.plan"
    assert _resolve("seahaze.batch", True, 2, None) == "seahaze"


def test_render_layer_does_not_import_writers_or_orchestration() -> None:
    # Rendering returns data: nothing under seahaze.render reaches the dataset writer, the
    # batch, verify or the command line.
    graph = import_graph()
    forbidden = ("seahaze.dataset", "seahaze.batch", "seahaze.verify", "seahaze.cli")
    for module, imports in graph.items():
        if module.startswith("seahaze.render"):
            bad = sorted(i for i in imports if i.startswith(forbidden))
            assert not bad, f"{module} imports {bad}"


@pytest.mark.parametrize("module", sorted(_modules()))
def test_modules_stay_readable(module: str) -> None:
    lines = len(_modules()[module].read_text(encoding="utf-8").splitlines())
    if module not in DECLARATIVE:
        assert lines <= MAX_LINES, f"{module}: {lines} lines; split it by idea"


def _imported_names(path: Path, module: str) -> list[tuple[str, str]]:
    """(module, name) of every ``from seahaze… import name`` in ``path``, lazy ones included."""
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            base = _resolve(package + ".x", False, node.level, node.module) if node.level else None
            target = base if node.level else node.module or ""
            if target.startswith("seahaze"):
                out += [(target, alias.name) for alias in node.names]
    return out


SCRIPTS = sorted((SRC.parent / "scripts").glob("*.py"))


@pytest.mark.parametrize("path", [*sorted(PACKAGE.rglob("*.py")), *SCRIPTS], ids=lambda p: p.name)
def test_every_imported_name_exists(path: Path) -> None:
    # Lazy imports inside functions run only on their code path: a name moved by a
    # restructuring fails there, at run time, unless checked here.
    import importlib

    module = _module_name(path) if path.is_relative_to(SRC) else "scripts"
    for target, name in _imported_names(path, module):
        imported = importlib.import_module(target)
        if not hasattr(imported, name):
            importlib.import_module(f"{target}.{name}")  # a submodule, or ImportError
