"""Benchmark dataset batches: scenes per hour of the default scene with 1 and 2 local workers.

Each configuration runs ``seahaze render scenes/default.yaml --scenes N`` as a fresh process into
an empty temporary folder (clean image + the 11 graded levels, `physical` mode in one pass, the
scene's own spp), so the wall time includes start-up, geometry, kernel compilation and every
write. Throughput is
scenes / wall time; the per-scene time is the median of the JSON-lines log's ``scene_done``
seconds. The MSVD projection divides 1026 scenes (12,312 images = 1026 × (clean + 11 levels))
by the throughput. Results go to the "batch" section of docs/benchmarks.md.

Usage: python scripts/bench_batch.py [--res 640x360,1280x720] [--workers 1,2] [--scenes 4]
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "default.yaml"
MSVD_SCENES = 1026
MSVD_IMAGES = 12312


def _replace_section():
    """``replace_section`` of scripts/bench_passes.py (scripts are not a package)."""
    spec = importlib.util.spec_from_file_location(
        "bench_passes", ROOT / "scripts" / "bench_passes.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.replace_section


def run(res: str, workers: int, scenes: int) -> dict:
    """Render ``scenes`` scenes at ``res`` with ``workers`` local workers; timings and rates."""
    with tempfile.TemporaryDirectory(prefix="seahaze-bench-") as tmp:
        out, log = Path(tmp) / "out", Path(tmp) / "log.jsonl"
        command = [sys.executable, "-m", "seahaze.cli", "render", str(SCENE), "--scenes"]
        command += [str(scenes), "--res", res, "--workers", str(workers), "--out", str(out)]
        command += ["--quiet", "--log", str(log)]
        load_before = os.getloadavg()[0]
        start = time.perf_counter()
        subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
        wall = time.perf_counter() - start
        events = [json.loads(line) for line in log.read_text().splitlines()]
        images = sum(1 for _ in (out / "images").rglob("*.png"))
    per_scene = [e["seconds"] for e in events if e["event"] == "scene_done"]
    return {
        "res": res,
        "workers": workers,
        "scenes": scenes,
        "images": images,
        "wall_s": wall,
        "scene_median_s": statistics.median(per_scene),
        "scenes_per_hour": scenes / wall * 3600.0,
        "images_per_s": images / wall,
        "load_before": load_before,
        "load_after": os.getloadavg()[0],
    }


def _res(res: str) -> str:
    return res.replace("x", "×")


def write_section(rows: list[dict]) -> None:
    """Write the batch table and the MSVD projection into docs/benchmarks.md."""
    cores = len(os.sched_getaffinity(0))
    from seahaze.sceneio import load_scene

    spp = load_scene(SCENE)[0].render.spp
    lines = [
        f"## Dataset batches, default scene (clean + 11 levels, `physical`, {spp} spp)",
        "",
        f"Machine: {platform.machine()}, {cores} vCPU (1-minute load average before and after "
        "each run in the table, the benchmark's own renders included); variant `llvm_ad_rgb`. "
        "Each row is "
        "one fresh `seahaze render scenes/default.yaml --scenes N --workers K` into an empty "
        "folder: wall time includes start-up, geometry, kernel compilation and all writes. "
        "`--workers K` gives each worker cores/K drjit threads.",
        "",
        "| resolution | workers | scenes | wall (s) | median s/scene (in its worker) | "
        "scenes/hour | images/s | MSVD size (1026 scenes) | load |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        hours = MSVD_SCENES / r["scenes_per_hour"]
        lines.append(
            f"| {_res(r['res'])} | {r['workers']} | {r['scenes']} | "
            f"{r['wall_s']:.0f} | {r['scene_median_s']:.1f} | {r['scenes_per_hour']:.0f} | "
            f"{r['images_per_s']:.2f} | {hours:.1f} h | "
            f"{r['load_before']:.1f} → {r['load_after']:.1f} |"
        )
    resolutions = list(dict.fromkeys(r["res"] for r in rows))
    best = {res: max(r["scenes_per_hour"] for r in rows if r["res"] == res) for res in resolutions}
    text = (
        f"MSVD size is {MSVD_IMAGES:,} images = {MSVD_SCENES} scenes × 12 images. At the best "
        "rate measured here one such machine needs "
        + ", ".join(f"{MSVD_SCENES / rate:.1f} h at {_res(res)}" for res, rate in best.items())
        + "."
    )
    gains = []
    for res in resolutions:
        rate = {r["workers"]: r["scenes_per_hour"] for r in rows if r["res"] == res}
        gains += [f"×{rate[k] / rate[1]:.2f} at {_res(res)}" for k in sorted(rate) if k > 1]
    if gains:
        text += f" More workers change the rate by {', '.join(gains)}"
        if all(float(g.split()[0][1:]) < 1.1 for g in gains):
            text += (
                ": no gain here, as each render pass already runs on every core through drjit "
                "and workers only interleave"
            )
        text += "."
    # Every later row's load includes the renders of the row before it: only the first row's
    # starting load tells of other work on the machine.
    if rows[0]["load_before"] > 0.5 * cores:
        text += (
            " Other work was running when the benchmark started (load "
            f"{rows[0]['load_before']:.1f} on {cores} vCPUs), so these rates are pessimistic."
        )
    text += (
        " Scenes are independent, so the time divides by the number of such machines on a Dask "
        "cluster (`--executor dask`, docs/batches.md). GPU workers (`cuda_ad_rgb`) were not "
        "measured here."
    )
    lines += ["", text]
    _replace_section()("batch", "\n".join(lines), "scripts/bench_batch.py")


def main() -> int:
    """Run every configuration and write the section."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--res", default="640x360,1280x720")
    parser.add_argument("--workers", default="1,2")
    parser.add_argument("--scenes", type=int, default=4, help="scenes per configuration")
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args()
    rows = []
    for res in args.res.split(","):
        for workers in (int(w) for w in args.workers.split(",")):
            row = run(res, workers, args.scenes)
            print(
                f"{res} × {workers} worker(s): {row['wall_s']:.0f} s for {row['scenes']} scenes, "
                f"{row['scenes_per_hour']:.0f} scenes/h, median {row['scene_median_s']:.1f} "
                f"s/scene, load {row['load_before']:.1f} → {row['load_after']:.1f}",
                flush=True,
            )
            rows.append(row)
    if not args.no_write:
        write_section(rows)
        print("wrote docs/benchmarks.md (batch section)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
