"""Time the physical pass of two versions of seahaze in one run: this checkout against a git
revision, alternating, so that a restructuring's speed is compared on the same machine state.

Each measurement is ``scripts/bench_pass_ratios.py`` (in-process, kernels compiled before
timing: the 11-level pass, one level, Mitsuba's clean pass; best of three) run in a fresh
process with ``PYTHONPATH`` pointing at the version's ``src/``. The versions alternate
(A B A B …) over ``--rounds`` rounds and each figure is the median over its rounds. Results go
to the "versions" section of docs/benchmarks.md with ``--doc``.

Usage: python scripts/bench_versions.py --before REV [--rounds 3] [--doc]
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_passes import replace_section

ROOT = Path(__file__).resolve().parents[1]
CASES = (("scenes/default.yaml", "160x90", 4), ("scenes/default.yaml", "320x180", 16))
"""(scene, size, spp): the CI size and a mid size, the default scene's 11 levels."""
FIGURES = re.compile(
    r"one pass (?P<all>[\d.]+) s .* one level (?P<one>[\d.]+) s .* Mitsuba's clean pass "
    r"(?P<clean>[\d.]+) s"
)


def measure(src: Path, scene: str, size: str, spp: int) -> dict[str, float]:
    """One bench_pass_ratios run of the seahaze in ``src``: seconds of the 11-level pass, of
    one level and of Mitsuba's clean pass."""
    command = [sys.executable, str(ROOT / "scripts" / "bench_pass_ratios.py"), scene, size]
    env = {**os.environ, "PYTHONPATH": str(src)}
    out = subprocess.run(
        [*command, str(spp)], cwd=ROOT, env=env, capture_output=True, text=True, check=True
    ).stdout
    match = FIGURES.search(out)
    if match is None:
        raise RuntimeError(f"unexpected output of bench_pass_ratios.py: {out!r}")
    return {key: float(value) for key, value in match.groupdict().items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", required=True, help="git revision to compare against")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--doc", action="store_true", help="write docs/benchmarks.md's section")
    args = parser.parse_args()
    revision = subprocess.run(
        ["git", "rev-parse", "--short", args.before],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run(
            ["git", "worktree", "add", "--detach", tmp, revision],
            cwd=ROOT,
            check=True,
            capture_output=True,
        )
        try:
            versions = {
                f"before ({revision})": Path(tmp) / "src",
                "after (this checkout)": ROOT / "src",
            }
            rows = run_cases(versions, args.rounds)
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", tmp], cwd=ROOT, check=True)
    lines = report(rows, args.rounds)
    print("\n".join(lines))
    if args.doc:
        replace_section("versions", "\n".join(lines), "scripts/bench_versions.py")


def run_cases(versions: dict[str, Path], rounds: int) -> list[tuple[str, str, dict]]:
    """Per case and version, the median of each figure over the rounds."""
    rows = []
    for scene, size, spp in CASES:
        runs: dict[str, list[dict[str, float]]] = {name: [] for name in versions}
        for _ in range(rounds):
            for name, src in versions.items():
                runs[name].append(measure(src, scene, size, spp))
        for name in versions:
            median = {k: statistics.median(r[k] for r in runs[name]) for k in runs[name][0]}
            rows.append((f"{size}, {spp} spp", name, median))
    return rows


def report(rows: list[tuple[str, str, dict]], rounds: int) -> list[str]:
    """The section's markdown table."""
    lines = [
        "## Speed of two versions of the physical pass (scripts/bench_versions.py)",
        "",
        f"Default scene, 11 levels; medians of {rounds} alternating rounds, each the best of "
        f"three in-process calls after a compiling one ({platform.machine()}, "
        f"{platform.python_version()}).",
        "",
        "| size | version | 11 levels (s) | 1 level (s) | clean (s) | 11/1 | 12 images / clean |",
        "|---|---|---|---|---|---|---|",
    ]
    for case, name, m in rows:
        lines.append(
            f"| {case} | {name} | {m['all']:.2f} | {m['one']:.2f} | {m['clean']:.2f} | "
            f"{m['all'] / m['one']:.2f} | {m['all'] / m['clean']:.2f} |"
        )
    return lines


if __name__ == "__main__":
    main()
