"""Which kernels does a new image size or sample count compile, and how long do they take?

The default scene's physical pass (clean + 11 levels) is rendered in one process, with an empty
drjit kernel cache (``HOME`` pointed at a new folder, as on a fresh machine), at 160×90 and 16
spp, then at 64×36 (a new size two octaves of pixel counts smaller: both under the sums'
smallest length, ``seahaze.render.wavefront.SMALLEST_SUM_CAPACITY``), then at 384×216 (a new
size over it: 82,944 pixels), then at 160×90 and 25 spp (a new sample count). drjit's kernel
history gives each launched kernel's operation count and the time its backend (LLVM or the CUDA
driver) spent compiling it; a kernel the cache held costs no backend time. The largest kernels
of each render are listed, and the "Cold start" section of docs/benchmarks.md is written.

Usage: python scripts/bench_kernel_sizes.py [--doc]
"""

from __future__ import annotations

import argparse
import json
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

CONFIGS = (((160, 90), 16), ((64, 36), 16), ((384, 216), 16), ((160, 90), 25))
"""(size, spp) rendered in this order, one after the other in one process."""
LARGEST = 3
"""Kernels listed per render (by backend time)."""


def measure() -> list[dict]:
    """Render every configuration of :data:`CONFIGS` in this process; per render its wall time
    and its largest compiled kernels (operations, backend seconds) and the total backend time."""
    import drjit as dr

    from seahaze.render.engine import open_session
    from seahaze.sceneio import load_scene
    from seahaze.spec import with_overrides
    from seahaze.visibility import GRADED_LEVELS_M, channel_extinction

    base, _ = load_scene(ROOT / "scenes" / "default.yaml")
    levels = list(GRADED_LEVELS_M)
    rows = []
    for (width, height), spp in CONFIGS:
        spec = with_overrides(base, resolution=(width, height), spp=spp, levels=levels)
        sigmas = [
            channel_extinction(v, spec.haze.threshold, spec.haze.extinction_spectrum)
            for v in levels
        ]
        dr.set_flag(dr.JitFlag.KernelHistory, True)
        dr.kernel_history()  # empties the history
        start = time.perf_counter()
        open_session(spec).level_renderer().render_all(sigmas)
        wall = time.perf_counter() - start
        kernels = [k for k in dr.kernel_history() if k.get("backend_time", 0.0) > 0.0]
        kernels.sort(key=lambda k: -k["backend_time"])
        rows.append(
            {
                "size": f"{width}×{height}",
                "spp": spp,
                "wall_s": wall,
                "backend_s": sum(k["backend_time"] for k in kernels) / 1000.0,
                "largest": [
                    (k.get("operation_count", 0), k["backend_time"] / 1000.0)
                    for k in kernels[:LARGEST]
                ],
            }
        )
    return rows


def write_doc(rows: list[dict]) -> None:
    """The "Cold start" section of docs/benchmarks.md from ``rows``."""
    lines = [
        "## Cold start: which kernels a new size or sample count compiles "
        "(scripts/bench_kernel_sizes.py)",
        "",
        "The default scene's physical pass (clean + 11 levels) in one process with an empty "
        "kernel cache, one render after the other; backend time is drjit's compilation of the "
        f"kernels the render launched. Machine: {platform.machine()}, "
        f"{len(os.sched_getaffinity(0))} vCPU, `llvm_ad_rgb`.",
        "",
        "| render | wall (s) | compiling (s) | largest kernels: operations, compile s |",
        "|---|---|---|---|",
    ]
    for row in rows:
        largest = "; ".join(f"{ops:,} ops, {s:.1f} s" for ops, s in row["largest"])
        lines.append(
            f"| {row['size']}, {row['spp']} spp | {row['wall_s']:.1f} | "
            f"{row['backend_s']:.1f} | {largest} |"
        )
    replace_section("kernel-sizes", "\n".join(lines), "scripts/bench_kernel_sizes.py")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--doc", action="store_true", help="write docs/benchmarks.md")
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        print(json.dumps(measure()))
        return
    with tempfile.TemporaryDirectory() as home:
        done = subprocess.run(
            [sys.executable, __file__, "--child"],
            env={**os.environ, "HOME": home},
            capture_output=True,
            text=True,
            check=True,
        )
    rows = json.loads(done.stdout.strip().splitlines()[-1])
    for row in rows:
        print(row)
    if args.doc:
        write_doc(rows)


if __name__ == "__main__":
    main()
