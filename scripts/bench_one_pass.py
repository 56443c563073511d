"""Benchmark the physical mode's one pass for all levels (issue 13) and write docs/benchmarks.md.

Measured, each as a fresh ``seahaze render`` process where a whole render is timed (start-up,
geometry, kernel loading, every write included), all in one run of this script:

* **dataset size**: the default scene's 12-image set at 1280×720 and the scene's spp, against
  its clean pass alone (Mitsuba's clean render at the same size and spp, warm, in-process);
  per-pass timings from the render's JSON-lines log; the process's peak memory;
* **levels**: the whole 11-level render of the default scene at 320×180 against a 1-level render
  of the same (``--vis 1000``);
* **CI size**: scenes of ``scenes/msvd.yaml`` at 160×90, 4 spp (12 images each), per-scene time
  from the log (the first scene, which loads the kernels, reported apart);
* **MSVD size**: scenes/hour of ``scenes/msvd.yaml`` at 1280×720 and the time for 1026 scenes;
* **pairs**: per-pixel error correlation between the clean image and each level, against a
  1024-spp render of the same scene and seed (default scene, 320×180, 32 spp), on the sea
  within 200 m and over the whole frame.

Usage: python scripts/bench_one_pass.py [--quick]
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

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_passes import replace_section  # noqa: E402

DEFAULT = ROOT / "scenes" / "default.yaml"
MSVD = ROOT / "scenes" / "msvd.yaml"
MSVD_SCENES = 1026


def warm_render(args: list[str], out: Path, warm_args: list[str] | None = None) -> dict:
    """:func:`render` of ``args`` after an untimed render of ``warm_args`` (default the same):
    a kernel is compiled per image size, sample count and level count, so the timed render
    starts from the disk cache as a user's second render with those settings does."""
    render(warm_args or args, out.parent / f"{out.name}-warm")
    return render(args, out)


def render(args: list[str], out: Path) -> dict:
    """Run ``seahaze render ARGS --out OUT --quiet --log`` as a fresh process; wall time, the
    log's per-scene records and the peak resident memory (MiB) of the process."""
    log = out.parent / f"{out.name}.jsonl"
    command = [sys.executable, "-m", "seahaze.cli", "render", *args, "--out", str(out)]
    command += ["--quiet", "--log", str(log)]
    start = time.perf_counter()
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL)
    _, status, usage = os.wait4(process.pid, 0)
    wall = time.perf_counter() - start
    if status != 0:
        raise SystemExit(f"render failed ({status}): {' '.join(command)}")
    events = [json.loads(line) for line in log.read_text().splitlines()]
    scenes = [e for e in events if e["event"] == "scene_done"]
    return {"wall_s": wall, "scenes": scenes, "peak_mib": usage.ru_maxrss / 1024}


def clean_pass_seconds(res: tuple[int, int], spp: int) -> tuple[float, float]:
    """The default scene's clean image alone, warm, in-process: Mitsuba's clean render (the
    clean pass before the one pass) and the physical mode's own pass with no hazy level (the
    same estimator as the 12-image pass, so the same noise in the clean image)."""
    from seahaze.render import passes
    from seahaze.render.engine import open_session
    from seahaze.render.physical import PhysicalRenderer
    from seahaze.sceneio import load_scene
    from seahaze.spec import with_overrides

    spec, _ = load_scene(DEFAULT)
    spec = with_overrides(spec, resolution=res, spp=spp)
    session = open_session(spec)
    haze = spec.haze
    passes.render_clean(session.loaded, spp, 0, haze.albedo, haze.g)  # load the kernel
    start = time.perf_counter()
    passes.render_clean(session.loaded, spp, 1, haze.albedo, haze.g)
    mitsuba = time.perf_counter() - start
    renderer = PhysicalRenderer(session.loaded, spec)
    renderer.render([], haze.albedo, haze.g, spp, 0)  # load the kernel
    start = time.perf_counter()
    renderer.render([], haze.albedo, haze.g, spp, 1)
    return mitsuba, time.perf_counter() - start


def correlations(res: tuple[int, int], spp: int, converged_spp: int) -> list[dict]:
    """Per level: correlation of the per-pixel error of the clean image and the level."""
    from seahaze.render.engine import open_session
    from seahaze.render.physical import PhysicalRenderer
    from seahaze.sceneio import load_scene
    from seahaze.spec import with_overrides
    from seahaze.visibility import channel_extinction

    spec, _ = load_scene(DEFAULT)
    spec = with_overrides(spec, resolution=res)
    session = open_session(spec)
    haze = spec.haze
    renderer = PhysicalRenderer(session.loaded, spec)
    sigmas = [channel_extinction(v, haze.threshold, haze.extinction_spectrum) for v in haze.levels]
    ref = renderer.render(sigmas, haze.albedo, haze.g, converged_spp, 1000)
    run = renderer.render(sigmas, haze.albedo, haze.g, spp, 1)
    geo = session.pixels
    near = np.isfinite(geo.distance_m) & (geo.instance < 0) & (geo.distance_m < 200.0)
    rows = []
    clean_err = run.clean - ref.clean
    for v, level, level_ref in zip(haze.levels, run.levels, ref.levels, strict=True):
        err = level - level_ref
        rows.append(
            {
                "level": v,
                "near_sea": float(np.corrcoef(clean_err[near].ravel(), err[near].ravel())[0, 1]),
                "frame": float(np.corrcoef(clean_err.ravel(), err.ravel())[0, 1]),
            }
        )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer scenes, smaller sizes")
    parser.add_argument(
        "--correlation-only",
        action="store_true",
        help="only the clean/level error correlation (its own section of docs/benchmarks.md)",
    )
    args = parser.parse_args()

    spp = _spec_spp(DEFAULT)
    converged_spp = 256 if args.quick else 1024
    if args.correlation_only:
        write_correlation(correlations((320, 180), spp, converged_spp), spp, converged_spp)
        return
    full = (640, 360) if args.quick else (1280, 720)
    results: dict = {"load_before": os.getloadavg()[1]}
    with tempfile.TemporaryDirectory(prefix="seahaze-bench-") as tmp:
        work = Path(tmp)
        res_arg = f"{full[0]}x{full[1]}"
        results["set"] = warm_render([str(DEFAULT), "--res", res_arg], work / "set")
        results["clean_s"], results["own_clean_s"] = clean_pass_seconds(full, spp)
        results["eleven"] = warm_render([str(DEFAULT), "--res", "320x180"], work / "eleven")
        one = [str(DEFAULT), "--res", "320x180", "--vis", "1000"]
        results["one"] = warm_render(one, work / "one")
        n_ci = 3 if args.quick else 6
        ci = [str(MSVD), "--res", "160x90", "--spp", "4"]
        results["ci"] = warm_render(
            [*ci, "--scenes", str(n_ci)], work / "ci", [*ci, "--scenes", "1"]
        )
        n_msvd = 2 if args.quick else 4
        msvd = [str(MSVD), "--scenes", str(n_msvd)]
        results["msvd"] = warm_render(msvd, work / "msvd", [str(MSVD), "--scenes", "1"])
        results["correlation"] = correlations((320, 180), spp, converged_spp)
    results["load_after"] = os.getloadavg()[1]
    (ROOT / "out").mkdir(exist_ok=True)
    (ROOT / "out" / "bench_one_pass.json").write_text(json.dumps(results, indent=2))
    write_section(results, spp, full)
    write_correlation(results["correlation"], spp, converged_spp)


def _spec_spp(path: Path) -> int:
    """The samples per pixel a scene file asks for."""
    from seahaze.sceneio import load_scene

    return load_scene(path)[0].render.spp


def _scene_s(run: dict, skip_first: bool = False) -> list[float]:
    scenes = run["scenes"][1:] if skip_first and len(run["scenes"]) > 1 else run["scenes"]
    return [s["seconds"] for s in scenes]


def write_section(r: dict, spp: int, full: tuple[int, int]) -> None:
    """The "one pass" section of docs/benchmarks.md."""
    set_run, clean = r["set"], r["clean_s"]
    t = set_run["scenes"][0]["timings"]
    breakdown = ", ".join(f"{k} {v:.1f} s" for k, v in t.items() if k != "total")
    ci = _scene_s(r["ci"], skip_first=True)
    msvd = _scene_s(r["msvd"], skip_first=True)
    per_scene = float(np.median(msvd))
    # The MSVD template renders at its own spp, not the default scene's.
    msvd_spp = _spec_spp(MSVD)
    lines = [
        "## One pass for all levels (`physical`, scripts/bench_one_pass.py)",
        "",
        f"Machine: {platform.machine()}, {len(os.sched_getaffinity(0))} vCPU. Each render is a "
        "fresh `seahaze render` process (start-up, geometry, kernels from the disk cache, every "
        "write included). Load average (5 min) of the machine before and after the run: "
        f"{r.get('load_before', float('nan')):.1f} and {r.get('load_after', float('nan')):.1f} "
        "(other jobs running make every time longer, and the ratios noisier).",
        "",
        "| measure | value | target |",
        "|---|---|---|",
        f"| default scene, 12 images at {full[0]}×{full[1]}, {spp} spp: whole render | "
        f"{set_run['wall_s']:.1f} s | |",
        f"| … its clean pass alone (Mitsuba's clean render, warm) | {clean:.1f} s | |",
        f"| … ratio | **{set_run['wall_s'] / clean:.2f}×** | ≤ 3× |",
        f"| … the physical mode's own clean pass alone (no level, warm) | "
        f"{r['own_clean_s']:.1f} s | |",
        f"| … the 12-image render's pass over it | {t['pass']:.1f} s / {r['own_clean_s']:.1f} s "
        f"= {t['pass'] / r['own_clean_s']:.2f}× | |",
        f"| … peak memory of the process | {set_run['peak_mib']:.0f} MiB | fits 24 GiB |",
        f"| default scene at 320×180: 11 levels / 1 level | {r['eleven']['wall_s']:.1f} s / "
        f"{r['one']['wall_s']:.1f} s = **{r['eleven']['wall_s'] / r['one']['wall_s']:.2f}×** | "
        "≤ 1.6× |",
        f"| `scenes/msvd.yaml` at 160×90, 4 spp, 12 images: per scene (median) | "
        f"**{np.median(ci):.2f} s** (first scene {r['ci']['scenes'][0]['seconds']:.2f} s) | "
        "≤ 3 s |",
        f"| `scenes/msvd.yaml` at 1280×720, {msvd_spp} spp: per scene (median) | {per_scene:.1f} s "
        f"({3600 / per_scene:.0f} scenes/hour) | |",
        f"| MSVD size, {MSVD_SCENES} scenes (12,312 images), one such machine | "
        f"**{MSVD_SCENES * per_scene / 3600:.1f} h** | |",
        "",
        f"Per-pass time of the {full[0]}×{full[1]} render: {breakdown}.",
    ]
    replace_section("one-pass", "\n".join(lines), "scripts/bench_one_pass.py")


def write_correlation(rows: list[dict], spp: int, converged_spp: int) -> None:
    """The "one-pass-correlation" section of docs/benchmarks.md."""
    lines = [
        "### Clean and hazy noise in a pair (scripts/bench_one_pass.py)",
        "",
        "Per-pixel error correlation between the clean image and each level, each against a "
        f"converged render ({converged_spp} spp, another seed) of the default scene at 320×180, "
        f"{spp} spp: on the sea within 200 m of the camera, and over the frame. Independent "
        "renders would give about 0; the thicker the haze, the more of a level is its own "
        "in-scattering and the less it follows the clean image.",
        "",
        "| V (m) | " + " | ".join(f"{c['level']:g}" for c in rows) + " |",
        "|---|" + "---|" * len(rows),
        "| near sea | " + " | ".join(f"{c['near_sea']:.2f}" for c in rows) + " |",
        "| frame | " + " | ".join(f"{c['frame']:.2f}" for c in rows) + " |",
    ]
    replace_section("one-pass-correlation", "\n".join(lines), "scripts/bench_one_pass.py")


if __name__ == "__main__":
    main()
