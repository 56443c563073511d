"""Benchmark a sequence: the cost of one frame of ``scenes/encounter.yaml`` against a still scene.

Renders, in one process, the scene as a still (``frame`` None: the mid-sequence poses) and then
``--frames`` frames of its sequence, each through ``render_scene`` and ``write_scene`` into a
temporary folder, exactly as a batch renders them. Per pass (geometry build, Mitsuba scene
load, geometry pass, the one physical pass for clean + levels, the writes) it reports the
median over the frames and the still's time; the first render of the process pays the kernel
compilation, so the still is rendered twice (the first timed apart) and the frames reuse the
compiled kernels as a batch's later scenes do. Results go to the "sequence" section of
docs/benchmarks.md.

Usage: python scripts/bench_sequence.py [--res 160x90] [--spp 4] [--vis 1000,4000] [--frames 4]
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "encounter.yaml"
PASSES = ("geometry_build", "scene_load", "aov", "pass", "write", "total")


def _replace_section():
    """``replace_section`` of scripts/bench_passes.py (scripts are not a package)."""
    spec = importlib.util.spec_from_file_location(
        "bench_passes", ROOT / "scripts" / "bench_passes.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.replace_section


def render_one(spec, name: str, frame: int | None, root: Path) -> dict[str, float]:
    """Render and write one frame (or the still); seconds per pass."""
    from seahaze.dataset import Layout
    from seahaze.dataset.writer import write_scene
    from seahaze.render.engine import render_scene

    start = time.perf_counter()
    scene = render_scene(spec, name, frame=frame)
    written = time.perf_counter()
    write_scene(Layout(root), scene)
    timings = dict(scene.timings)
    timings["write"] = time.perf_counter() - written
    timings["total"] = time.perf_counter() - start
    return timings


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--res", default="160x90")
    parser.add_argument("--spp", type=int, default=4)
    parser.add_argument("--vis", default="1000,4000", help="levels, or 'scene' for the scene's")
    parser.add_argument("--frames", type=int, default=4)
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args()
    sys.path.insert(0, str(ROOT / "src"))
    from seahaze.render.variant import select_variant
    from seahaze.sceneio import load_scene
    from seahaze.spec import with_overrides

    width, height = (int(v) for v in args.res.split("x"))
    # "scene": the scene's own levels (the 11 graded ones).
    levels = None if args.vis == "scene" else [float(v) for v in args.vis.split(",")]
    spec, name = load_scene(SCENE)
    spec = with_overrides(spec, spp=args.spp, resolution=(width, height), levels=levels)
    n_levels = len(spec.haze.levels)
    load_before = os.getloadavg()[0]
    with tempfile.TemporaryDirectory(prefix="seahaze-bench-seq-") as tmp:
        # The first render of a process compiles the kernels: timed apart, then the still again.
        first = render_one(spec, f"{name}_first", None, Path(tmp))
        still = render_one(spec, f"{name}_still", None, Path(tmp))
        frames = [render_one(spec, f"{name}_f{i:04d}", i, Path(tmp)) for i in range(args.frames)]
    load_after = os.getloadavg()[0]
    median = {key: statistics.median(f.get(key, 0.0) for f in frames) for key in PASSES}
    fps = spec.sequence.fps
    n_frames = spec.sequence.frames
    rows = [
        f"| {key} | {first.get(key, 0.0):.2f} | {still.get(key, 0.0):.2f} | {median[key]:.2f} | "
        f"{min(f.get(key, 0.0) for f in frames):.2f}–{max(f.get(key, 0.0) for f in frames):.2f} |"
        for key in PASSES
    ]
    body = "\n".join(
        [
            f"## Sequences: one frame of `scenes/encounter.yaml` ({width}×{height}, "
            f"{args.spp} spp, clean + {n_levels} levels, `physical`)",
            "",
            f"Machine: {platform.machine()}, {os.cpu_count()} vCPU shared with other work "
            f"(1-minute load {load_before:.1f} → {load_after:.1f}); variant "
            f"`{select_variant(spec.render.variant)}`. One process renders the still (the "
            "scene as written) twice — the first render of a process compiles the kernels — "
            f"and then {args.frames} frames of the sequence, each rendered and written as a "
            "batch does; seconds per pass.",
            "",
            "| pass | first render (s) | still (s) | median frame (s) | frames min–max (s) |",
            "|---|---|---|---|---|",
            *rows,
            "",
            f"A frame costs {median['total'] / still['total']:.2f}× the still rendered after "
            "the kernels are compiled. Each frame builds its own sea mesh (the waves at its "
            "time) and places its vessels, and loads its own Mitsuba scene; what does not "
            "change is reused: the vessel models (built once per class, length and seed), "
            "each hull's solved ship-wave field, and the compiled kernels (the vessels are "
            f"one fixed set of meshes). The scene's {n_frames} frames ({n_frames / fps:g} s at "
            f"{fps:g} fps) "
            f"take about {n_frames * median['total'] / 60:.0f} min at this size on this "
            "machine.",
        ]
    )
    print(body)
    if not args.no_write:
        _replace_section()("sequence", body, "scripts/bench_sequence.py")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
