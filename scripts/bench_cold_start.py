"""How much longer is a render with an empty kernel cache than the same render again?

Issue 33's "cold start" target: the first render of a configuration should not pay minutes of
compilation, cold at most 2× warm. Each configuration is rendered by a fresh `seahaze render`
process with ``HOME`` pointed at an empty folder (drjit's kernel cache is ``~/.drjit``: empty,
as on a fresh machine), then by a second process with the cache the first left. The wall time
of each whole process is measured (start-up, geometry, compilation, render and writes).

Configurations: the README's ``make render`` (the default scene, its 1280×720 and 42 spp, clean
+ 11 levels) and the issue's small render (the default scene at 320×180, 16 spp, 11 levels).

Usage: python scripts/bench_cold_start.py [--doc]
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_passes import replace_section  # noqa: E402

CONFIGS = {
    "`make render` (default scene, 1280×720, 42 spp, 11 levels)": [],
    "default scene, 320×180, 16 spp, 11 levels": ["--res", "320x180", "--spp", "16"],
}
"""Label → extra `seahaze render` arguments after the scene and `--vis 300..4000`."""


def timed_render(extra: list[str], home: Path, out: Path) -> float:
    """Wall seconds of one `seahaze render` process of the default scene into ``out``."""
    command = [
        str(Path(sys.executable).parent / "seahaze"),
        "render",
        str(ROOT / "scenes" / "default.yaml"),
        "--vis",
        "300..4000",
        "--out",
        str(out),
        "--quiet",
        *extra,
    ]
    start = time.perf_counter()
    subprocess.run(command, env={**os.environ, "HOME": str(home)}, check=True)
    return time.perf_counter() - start


def measure() -> list[tuple[str, float, float]]:
    """(label, cold s, warm s) per configuration, each with its own empty cache."""
    rows = []
    for label, extra in CONFIGS.items():
        with tempfile.TemporaryDirectory() as tmp:
            home = Path(tmp) / "home"
            home.mkdir()
            cold = timed_render(extra, home, Path(tmp) / "cold")
            warm = timed_render(extra, home, Path(tmp) / "warm")
        rows.append((label, cold, warm))
        print(f"{label}: cold {cold:.1f} s, warm {warm:.1f} s, {cold / warm:.2f}x", flush=True)
    return rows


def write_doc(rows: list[tuple[str, float, float]]) -> None:
    """The "cold-start" section of docs/benchmarks.md from ``rows``."""
    lines = [
        "## Cold and warm renders (scripts/bench_cold_start.py)",
        "",
        "Whole `seahaze render` processes (start-up, geometry, compilation, render, writes): "
        "cold with an empty drjit kernel cache, warm with the cache the cold run left. "
        f"Machine: {platform.machine()}, {len(os.sched_getaffinity(0))} vCPU, "
        "`llvm_ad_rgb`. Target (issue 33): cold ≤ 2× warm.",
        "",
        "| render | cold (s) | warm (s) | cold / warm |",
        "|---|---|---|---|",
    ]
    for label, cold, warm in rows:
        lines.append(f"| {label} | {cold:.1f} | {warm:.1f} | **{cold / warm:.2f}×** |")
    replace_section("cold-start", "\n".join(lines), "scripts/bench_cold_start.py")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--doc", action="store_true", help="write docs/benchmarks.md")
    args = parser.parse_args()
    rows = measure()
    if args.doc:
        write_doc(rows)


if __name__ == "__main__":
    main()
