"""How long does the test suite take from a fresh clone on a fresh machine?

Issue 33's target: `make test` at most 10 minutes on this project's machine from a fresh clone
with an empty kernel cache. This script does what CI does: clones the repository's committed
``HEAD`` into a temporary folder with ``../shared`` beside it, points ``HOME`` at an empty folder
(drjit's kernel cache and pip's download cache start empty, as on a fresh machine) and runs
``bash .ci/run`` (``make test``: the install, then pytest). It reports the whole run's wall time,
pytest's own time and the test counts, and with ``--doc`` writes the "suite" section of
docs/benchmarks.md.

Usage: python scripts/bench_suite.py [--doc]   (about 15 minutes on a 2-vCPU machine)
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


def run_suite() -> dict:
    """Clone, run CI's command with an empty ``HOME``; wall time, pytest time and counts."""
    commit = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True
    ).stdout.strip()
    with tempfile.TemporaryDirectory() as tmp:
        root, home = Path(tmp) / "ci", Path(tmp) / "home"
        root.mkdir()
        home.mkdir()
        subprocess.run(["git", "clone", "-q", str(ROOT), str(root / "main")], check=True)
        (root / "shared").symlink_to(ROOT.parent / "shared")
        start = time.perf_counter()
        done = subprocess.run(
            ["bash", ".ci/run"],
            cwd=root / "main",
            env={**os.environ, "HOME": str(home)},
            capture_output=True,
            text=True,
        )
        wall = time.perf_counter() - start
    match = SUMMARY.search(done.stdout.strip().splitlines()[-1] if done.stdout.strip() else "")
    if done.returncode != 0 or match is None:
        sys.exit(f"the suite failed (exit {done.returncode}):\n{done.stdout[-3000:]}")
    return {
        "commit": commit,
        "wall_s": wall,
        "pytest_s": float(match.group(3)),
        "passed": int(match.group(1)),
        "skipped": int(match.group(2) or 0),
    }


def write_doc(row: dict) -> None:
    """The "suite" section of docs/benchmarks.md from ``row``."""
    lines = [
        "## The test suite from a fresh clone (scripts/bench_suite.py)",
        "",
        f"Commit {row['commit']}, cloned into an empty folder and run by `bash .ci/run` with an "
        "empty `HOME` (empty kernel and pip caches). Machine: "
        f"{platform.machine()}, {len(os.sched_getaffinity(0))} vCPU, `llvm_ad_rgb`. "
        "Target (issue 33): `make test` ≤ 10 min.",
        "",
        "| tests passed | skipped | pytest (min) | with the install (min) |",
        "|---|---|---|---|",
        f"| {row['passed']} | {row['skipped']} | {row['pytest_s'] / 60:.1f} | "
        f"{row['wall_s'] / 60:.1f} |",
    ]
    replace_section("suite", "\n".join(lines), "scripts/bench_suite.py")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--doc", action="store_true", help="write docs/benchmarks.md")
    args = parser.parse_args()
    row = run_suite()
    print(row)
    if args.doc:
        write_doc(row)


if __name__ == "__main__":
    main()
