"""How long does the test suite take from a fresh clone on a fresh machine?

Issue 33's target: `make test` at most 10 minutes on this project's machine from a fresh clone
with an empty kernel cache, its slow proofs behind an explicit marker that CI still runs. This
script does what CI does (``.ci/run``: ``make test``, then ``make test-slow``; tests/test_ci.py
holds ``.ci/run`` to exactly that): clones the repository's committed ``HEAD`` into a temporary
folder with ``../shared`` beside it, points ``HOME`` at an empty folder (drjit's kernel cache and
pip's download cache start empty, as on a fresh machine) and runs the two targets one after the
other, timing each. ``make test`` pays the install; ``make test-slow`` finds the kernels the first
compiled. It reports each run's wall time, pytest's own time and the test counts, and with
``--doc`` writes the "suite" section of docs/benchmarks.md.

Usage: python scripts/bench_suite.py [--doc]   (about 20 minutes on a 2-vCPU machine)
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_passes import replace_section  # noqa: E402

SUMMARY = re.compile(r"(\d+) passed(?:, (\d+) skipped)?.* in ([\d.]+)s")
"""pytest's last line: counts and its own seconds."""


TARGETS = ("test", "test-slow")
"""The Makefile targets CI runs, in its order."""


def _run_target(target: str, clone: Path, home: Path) -> dict:
    """``make TARGET`` in ``clone`` with ``HOME`` at ``home``: wall time, pytest time, counts."""
    start = time.perf_counter()
    done = subprocess.run(
        ["make", target],
        cwd=clone,
        env={**os.environ, "HOME": str(home)},
        capture_output=True,
        text=True,
    )
    wall = time.perf_counter() - start
    match = SUMMARY.search(done.stdout.strip().splitlines()[-1] if done.stdout.strip() else "")
    if done.returncode != 0 or match is None:
        sys.exit(f"make {target} failed (exit {done.returncode}):\n{done.stdout[-3000:]}")
    return {
        "target": target,
        "wall_s": wall,
        "pytest_s": float(match.group(3)),
        "passed": int(match.group(1)),
        "skipped": int(match.group(2) or 0),
    }


def run_suite() -> dict:
    """Clone, run CI's two targets with an empty ``HOME``; the commit and a row per target."""
    commit = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True
    ).stdout.strip()
    with tempfile.TemporaryDirectory() as tmp:
        root, home = Path(tmp) / "ci", Path(tmp) / "home"
        root.mkdir()
        home.mkdir()
        subprocess.run(["git", "clone", "-q", str(ROOT), str(root / "main")], check=True)
        (root / "shared").symlink_to(ROOT.parent / "shared")
        rows = [_run_target(target, root / "main", home) for target in TARGETS]
    return {"commit": commit, "rows": rows}


def write_doc(result: dict) -> None:
    """The "suite" section of docs/benchmarks.md from ``result``."""
    lines = [
        "## The test suite from a fresh clone (scripts/bench_suite.py)",
        "",
        f"Commit {result['commit']}, cloned into an empty folder; `make test` and then "
        "`make test-slow` (what `.ci/run` runs) with an empty `HOME` (empty kernel and pip "
        f"caches). Machine: {platform.machine()}, {len(os.sched_getaffinity(0))} vCPU, "
        "`llvm_ad_rgb`. Target (issue 33): `make test` ≤ 10 min.",
        "",
        "| command | tests passed | skipped | pytest (min) | whole command (min) |",
        "|---|---|---|---|---|",
    ]
    for row in result["rows"]:
        whole = "with the install" if row["target"] == "test" else "its kernels partly cached"
        lines.append(
            f"| `make {row['target']}` | {row['passed']} | {row['skipped']} | "
            f"{row['pytest_s'] / 60:.1f} | {row['wall_s'] / 60:.1f} ({whole}) |"
        )
    total = sum(row["wall_s"] for row in result["rows"])
    lines += ["", f"CI's whole run (both commands, the install included): {total / 60:.1f} min."]
    replace_section("suite", "\n".join(lines), "scripts/bench_suite.py")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--doc", action="store_true", help="write docs/benchmarks.md")
    args = parser.parse_args()
    result = run_suite()
    print(result)
    if args.doc:
        write_doc(result)


if __name__ == "__main__":
    main()
