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


def code_lines(source: str) -> int:
    """Lines of ``source`` that hold code: not blank, not only a comment, not part of a
    docstring (a string expression standing alone as a statement)."""
    tree = ast.parse(source)
    docs: set[int] = set()
    for node in ast.walk(tree):
        value = node.value if isinstance(node, ast.Expr) else None
        if isinstance(value, ast.Constant) and isinstance(value.value, str):
            docs.update(range(node.lineno, (node.end_lineno or node.lineno) + 1))
    count = 0
    for number, line in enumerate(source.splitlines(), start=1):
        text = line.strip()
        if text and not text.startswith("#") and number not in docs:
            count += 1
    return count


def test_code_lines_leave_out_docstrings_comments_and_blanks() -> None:
    source = (
        '"""Doc\nstring."""\n\n# a comment\nx = 1\n\n\ndef f():\n    """Doc."""\n    return x\n'
    )
    assert code_lines(source) == 3


@pytest.mark.parametrize("module", sorted(_modules()))
def test_modules_stay_readable(module: str) -> None:
    # A module is split by idea when its code grows, whatever its prose: counting docstrings
    # and comments rewarded squeezing them.
    lines = code_lines(_modules()[module].read_text(encoding="utf-8"))
    if module not in DECLARATIVE:
        assert lines <= MAX_LINES, f"{module}: {lines} lines of code; split it by idea"


TESTS_AND_SCRIPTS = sorted(
    [*(SRC.parent / "tests").glob("*.py"), *(SRC.parent / "scripts").glob("*.py")]
)


def private_uses(source: str) -> list[str]:
    """Where ``source`` reaches a private name of seahaze: ``from seahaze… import _name`` or
    ``obj._name`` on anything but ``self``/``cls`` (dunders are public protocol)."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("seahaze"):
            found += [f"import {a.name}" for a in node.names if _is_private(a.name)]
        elif isinstance(node, ast.Attribute) and _is_private(node.attr):
            owner = node.value.id if isinstance(node.value, ast.Name) else None
            if owner not in ("self", "cls"):
                found.append(f"line {node.lineno}: .{node.attr}")
    return found


def _is_private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def test_the_private_name_finder_finds_them() -> None:
    source = "from seahaze.render.scene import _sensor_dict\nr._vessel_light(1)\nself._x = 2\n"
    assert private_uses(source) == ["import _sensor_dict", "line 2: ._vessel_light"]


@pytest.mark.parametrize("path", TESTS_AND_SCRIPTS, ids=lambda p: p.name)
def test_tests_and_scripts_use_public_names_only(path: Path) -> None:
    # Private names may change with any restructuring; what tests and benchmarks rely on is
    # the public interface, documented.
    assert not private_uses(path.read_text(encoding="utf-8")), private_uses(path.read_text())


def tuning_changes(source: str) -> list[str]:
    """Where ``source`` changes a module-level constant (an UPPER_CASE name) of another module:
    by assignment to ``module.NAME`` or ``monkeypatch.setattr(module, "NAME", …)``."""
    found = []
    for node in ast.walk(ast.parse(source)):
        targets = node.targets if isinstance(node, ast.Assign) else []
        for target in targets:
            for part in ast.walk(target):
                if isinstance(part, ast.Attribute) and part.attr.isupper():
                    found.append(f"line {node.lineno}: .{part.attr} =")
        if (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Attribute)
            and node.func.attr == "setattr"
            and len(node.args) >= 2
            and isinstance(node.args[1], ast.Constant)
            and str(node.args[1].value).isupper()
        ):
            found.append(f"line {node.lineno}: setattr {node.args[1].value}")
    return found


def test_the_tuning_change_finder_finds_them() -> None:
    source = 'physical.SHARE = 0.0\nmonkeypatch.setattr(vl, "AIM_SHARE", 0)\nx.share = 1\n'
    assert tuning_changes(source) == ["line 1: .SHARE =", "line 2: setattr AIM_SHARE"]


@pytest.mark.parametrize("path", [*TESTS_AND_SCRIPTS, *sorted(PACKAGE.rglob("*.py"))])
def test_no_module_constant_is_changed_at_run_time(path: Path) -> None:
    # Tuning is an EstimatorSettings passed in (seahaze.render.estimator): a module constant
    # changed at run time reaches kernels traced before or after it unpredictably.
    assert not tuning_changes(path.read_text(encoding="utf-8"))


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
def test_every_imported_name_exists(path: Path, mitsuba_variant) -> None:
    # Lazy imports inside functions run only on their code path: a name moved by a
    # restructuring fails there, at run time, unless checked here. The integrator modules
    # derive from a Mitsuba variant's classes, so a variant is set first.
    import importlib

    module = _module_name(path) if path.is_relative_to(SRC) else "scripts"
    for target, name in _imported_names(path, module):
        imported = importlib.import_module(target)
        if not hasattr(imported, name):
            importlib.import_module(f"{target}.{name}")  # a submodule, or ImportError
