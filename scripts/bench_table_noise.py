"""The diffuse tables' noise in the images: each region's mean against the converged references,
over several seeds, per table photon count (``physical``), into docs/benchmarks.md.

A diffuse table is traced from a finite number of photons, and its noise does not average out
over pixels: it moves a level's whole brightness. So a single render's bias against a reference
mixes the renderer's bias with its table's luck. This script renders the benchmark scene
(``scenes/benchmark.yaml``, 80×45, 300, 1000 and 4000 m) with ``--seeds`` sampler seeds (each
traces its own tables) at each photon count and reports, per level and region (sea, sky,
vessels), the mean over the seeds of the relative bias against the ``reference`` images of
``assets/references/benchmark`` (what the renderer converges to) and the spread between seeds
(the level-wide error one scene of a dataset carries). The references' own standard error of
each region's mean is given beside them.

Usage: python scripts/bench_table_noise.py [--photons 131072,1048576] [--seeds 6] [--spp 128]
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_modes import (  # noqa: E402
    LEVELS,
    SCENE,
    load_references,
    region_masks,
    region_mean_stderr,
)
from bench_passes import replace_section  # noqa: E402

REGIONS = ("sea", "sky", "vessel")


def measure(photons: int, seeds: int, spp: int) -> dict:
    """Relative bias (seeds × levels × regions) against the references, the references' own
    standard error of each region mean (levels × regions) and the tables' time."""
    from seahaze.imaging import luminance
    from seahaze.render.engine import open_session
    from seahaze.render.estimator import EstimatorSettings
    from seahaze.render.physical import PhysicalRenderer
    from seahaze.sceneio import load_scene
    from seahaze.spec import with_overrides
    from seahaze.visibility import channel_extinction

    spec, _ = load_scene(SCENE)
    spec = with_overrides(spec, mode="physical", levels=list(LEVELS))
    rgb, se, _ = load_references()
    session = open_session(spec)
    masks = region_masks(session.pixels.distance_m, session.pixels.instance)
    haze = spec.haze
    sigmas = [channel_extinction(v, haze.threshold, haze.extinction_spectrum) for v in LEVELS]
    renderer = PhysicalRenderer(session.loaded, spec, EstimatorSettings(table_photons=photons))
    keys = [f"v{int(v):04d}" for v in LEVELS]
    refs = [luminance(rgb[k]) for k in keys]
    bias = np.empty((seeds, len(LEVELS), len(REGIONS)))
    table_s = []
    for i, seed in enumerate(range(1, seeds + 1)):
        run = renderer.render(sigmas, haze.albedo, haze.g, spp, seed)
        table_s.append(run.table_seconds)
        for j, (image, y_ref) in enumerate(zip(run.levels, refs, strict=True)):
            y = luminance(image)
            for k, name in enumerate(REGIONS):
                m = masks[name]
                bias[i, j, k] = y[m].mean() / y_ref[m].mean() - 1.0
    ref_se = np.array(
        [
            [region_mean_stderr(se[key], masks[n], y[masks[n]].mean()) for n in REGIONS]
            for key, y in zip(keys, refs, strict=True)
        ]
    )
    return {"bias": bias, "ref_se": ref_se, "table_s": float(np.median(table_s))}


def write_doc(results: dict[int, dict], seeds: int, spp: int, seconds: float) -> None:
    lines = [
        "## The diffuse tables' noise (scripts/bench_table_noise.py)",
        "",
        f"Machine: {platform.machine()}, {len(os.sched_getaffinity(0))} vCPU. Benchmark scene "
        f"(80×45), `physical`, {spp} spp, {seeds} sampler seeds per photon count (each traces "
        "its own tables), against the converged `reference` images: per level and region, the "
        "mean over the seeds of the relative bias of the region's mean luminance, ± its spread "
        "between seeds (1σ: the level-wide error one render carries). Reference: the standard "
        "error of the reference's own region mean. Tables: eleven-level cost is about 11/3 of "
        f"the three-level time given. Measured in {seconds:.0f} s.",
        "",
        "| photons per table | tables (s, 3 levels) | V (m) | sea | sky | vessel | reference |",
        "|---|---|---|---|---|---|---|",
    ]
    for photons, r in results.items():
        bias, ref_se = 100 * r["bias"], 100 * r["ref_se"]
        for j, v in enumerate(LEVELS):
            cells = [
                f"{bias[:, j, k].mean():+.2f} ± {bias[:, j, k].std(ddof=1):.2f} %"
                for k in range(len(REGIONS))
            ]
            ref = " / ".join(f"{x:.2f}" for x in ref_se[j])
            lines.append(
                f"| {photons:,} | {r['table_s']:.2f} | {v:g} | " + " | ".join(cells) + f" | "
                f"{ref} % |"
            )
    replace_section("table-noise", "\n".join(lines), "scripts/bench_table_noise.py")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--photons", default="131072,1048576", help="comma-separated counts")
    parser.add_argument("--seeds", type=int, default=6)
    parser.add_argument("--spp", type=int, default=128)
    args = parser.parse_args()
    start = time.perf_counter()
    results = {}
    for photons in (int(p) for p in args.photons.split(",")):
        results[photons] = measure(photons, args.seeds, args.spp)
        worst = np.abs(results[photons]["bias"].mean(0)).max()
        spread = results[photons]["bias"].std(0, ddof=1).max()
        print(f"{photons}: worst mean bias {100 * worst:.2f} %, widest spread {100 * spread:.2f} %")
    write_doc(results, args.seeds, args.spp, time.perf_counter() - start)


if __name__ == "__main__":
    main()
