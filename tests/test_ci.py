"""CI runs the README's test command word for word, and then the slow proofs that command
leaves out, so that every test runs in CI (issue 33: `make test` within 10 minutes, the slow
proofs behind an explicit marker that CI still runs)."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _ci_commands() -> list[str]:
    lines = (ROOT / ".ci" / "run").read_text().splitlines()
    return [line.strip() for line in lines[1:] if line.strip() and not line.startswith("#")]


def _make_recipe(target: str) -> list[str]:
    """The words of ``target``'s one recipe line in the Makefile."""
    text = (ROOT / "Makefile").read_text()
    match = re.search(rf"^{re.escape(target)}:.*\n\t(.+)$", text, re.MULTILINE)
    assert match, f"Makefile has no recipe for {target}"
    return shlex.split(match.group(1))


def test_ci_runs_the_readmes_test_command_then_the_slow_proofs():
    readme = (ROOT / "README.md").read_text()
    quickstart = readme.split("## Quickstart", 1)[1].split("```bash", 1)[1].split("```", 1)[0]
    test_command = next(
        line.split("#")[0].strip() for line in quickstart.splitlines() if "test" in line
    )
    commands = _ci_commands()
    assert commands[-2:] == [test_command, "make test-slow"], commands


def test_the_two_make_targets_split_the_suite_by_the_slow_marker():
    fast, slow = _make_recipe("test"), _make_recipe("test-slow")
    # pytest's own -m (after "-m pytest"): the marker expression.
    fast_at, slow_at = (
        len(fast) - 1 - fast[::-1].index("-m"),
        len(slow) - 1 - slow[::-1].index("-m"),
    )
    assert fast[fast_at + 1] == "not slow" and slow[slow_at + 1] == "slow"
    # Everything else alike: the same interpreter, workers and options.
    assert fast[:fast_at] == slow[:slow_at] and fast[fast_at + 2 :] == slow[slow_at + 2 :]
    pyproject = (ROOT / "pyproject.toml").read_text()
    assert "--strict-markers" in pyproject and '"slow:' in pyproject
