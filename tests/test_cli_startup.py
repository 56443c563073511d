"""The ``seahaze`` command starts light: building its parser (what ``seahaze levels``, ``classes``,
``validate`` and every ``--help`` pay before they do anything) imports neither the renderer nor
the scene geometry. ``seahaze.verify`` loads its submodules when a name is first asked for.

Each check runs in a fresh interpreter: this test process has long imported everything.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

HEAVY = ("drjit", "mitsuba", "trimesh", "seahaze.world", "seahaze.vessels", "seahaze.verify.run")
"""Modules a render needs and a parser must not (their start-up cost: docs/benchmarks.md, "What
does a render spend outside the pass?")."""


def fresh_python(code: str) -> str:
    """What ``code`` prints in a new interpreter."""
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True
    )
    return done.stdout.strip()


def test_building_the_parser_imports_no_renderer_or_geometry() -> None:
    loaded = fresh_python(
        "import json, sys, seahaze.cli; seahaze.cli.build_parser(); "
        f"print(json.dumps([m for m in {HEAVY!r} if m in sys.modules]))"
    )
    assert json.loads(loaded) == []


def test_verify_names_load_their_submodule_on_first_use() -> None:
    loaded = fresh_python(
        "import json, sys, seahaze.verify as v; before = 'seahaze.verify.run' in sys.modules; "
        "f = v.run_verify; print(json.dumps([before, 'seahaze.verify.run' in sys.modules, "
        "f is sys.modules['seahaze.verify.run'].run_verify, v.DEFAULT_SPP]))"
    )
    assert json.loads(loaded) == [False, True, True, 4096]


def test_every_public_verify_name_resolves_and_others_do_not() -> None:
    import seahaze.verify as verify

    for name in verify.__all__:
        assert getattr(verify, name) is not None, name
    with pytest.raises(AttributeError, match="no attribute 'not_a_name'"):
        _ = verify.not_a_name
