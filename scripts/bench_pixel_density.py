"""What the ``physical`` mode's equivalent profiles cost: a 12-image set (clean + the 11 graded
levels) of haze that varies across the sea against the same scene in uniform haze.

``scenes/patchy.yaml`` (1280×720, 42 spp unless ``--res``/``--spp`` say otherwise) is rendered
in ``physical`` three ways, each in a process of its own (so that each memory peak is its
own): its patches, a bank instead (edge 900 m ahead, edge scale 80 m, near ratio 0.2), and
uniform haze (no patches). Each process renders the set twice and reports the second (warm:
its kernels compiled) and its peak resident memory; for the varying haze also the time of the
pixels' ratios alone (``PhysicalRenderer.pixel_ratios``: the view's quadrature, which the
``transmission/`` maps share, the sun's depths and, in a bank, its own diffuse field). All in
one run, so the ratios compare like with like.

Usage: python scripts/bench_pixel_density.py [--res 1280x720] [--spp 42] [--doc]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_passes import replace_section

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "patchy.yaml"
SCRIPT = "scripts/bench_pixel_density.py"
BANK = {"distance_m": 900.0, "bearing_deg": 0.0, "edge_m": 80.0, "near_ratio": 0.2}
CASES = ("uniform", "patches", "bank")


def case_spec(case: str, res: tuple[int, int], spp: int):
    """The patchy scene's spec with ``case``'s haze at ``res`` and ``spp``, in physical."""
    from seahaze.sceneio import load_scene

    spec, name = load_scene(SCENE)
    haze = spec.haze.model_dump(exclude_none=True)
    haze.pop("patches", None)
    if case == "patches":
        haze["patches"] = spec.haze.patches.model_dump()
    elif case == "bank":
        haze["bank"] = BANK
    data = spec.model_dump(exclude_none=True)
    data["haze"] = haze
    data["camera"]["resolution"] = list(res)
    data["render"] |= {"mode": "physical", "spp": spp}
    return type(spec).model_validate(data), name


def child(case: str, res: tuple[int, int], spp: int) -> dict:
    """Render ``case``'s set twice; the warm time, the ratios' time and the memory peak."""
    from seahaze.render.engine import open_session, render_scene
    from seahaze.render.physical import PhysicalRenderer
    from seahaze.visibility import GRADED_LEVELS_M, extinction_coefficient

    spec, name = case_spec(case, res, spp)
    render_scene(spec, name)  # compiles the kernels
    start = time.perf_counter()
    render_scene(spec, name)
    warm = time.perf_counter() - start
    ratios = 0.0
    if case != "uniform":
        session = open_session(spec)
        renderer = PhysicalRenderer(session.loaded, spec, geometry=session.pixels)
        start = time.perf_counter()
        sigma = [extinction_coefficient(v) for v in GRADED_LEVELS_M]
        # As the render asks for them: a bank's own field traced with the tables' photons.
        settings = renderer.settings
        photons = settings.bank_photons_for(settings.photons_for(res[0] * res[1] * spp))
        renderer.pixel_ratios(np.asarray(sigma), spec.render.seed, photons)
        ratios = time.perf_counter() - start
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20  # KiB -> GiB
    return {"case": case, "warm_s": warm, "ratios_s": ratios, "peak_gib": peak}


def section(rows: list[dict], res: tuple[int, int], spp: int) -> list[str]:
    uniform = next(r for r in rows if r["case"] == "uniform")["warm_s"]
    lines = [
        f"## What the physical mode's equivalent profiles cost ({SCRIPT})",
        "",
        f"Machine: {platform.machine()}, {len(os.sched_getaffinity(0))} vCPU. "
        f"`scenes/patchy.yaml` in `physical`, {res[0]}×{res[1]}, {spp} spp, clean + 11 "
        "graded levels, warm (second render in its process); the ratios' share is the pixels' "
        "density ratios alone (the view's quadrature, shared with the `transmission/` maps, "
        "the sun's depths and the own diffuse field of the bank or the patches, traced with "
        "the tables' photons). One run; each case in its own process.",
        "",
        "| haze | 12 images (s) | / uniform | ratios (s) | peak memory (GiB) |",
        "|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['case']} | {r['warm_s']:.1f} | {r['warm_s'] / uniform:.2f} | "
            f"{r['ratios_s']:.1f} | {r['peak_gib']:.2f} |"
        )
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--res", default="1280x720", help="WIDTHxHEIGHT")
    parser.add_argument("--spp", type=int, default=42, help="samples per pixel")
    parser.add_argument("--doc", action="store_true", help="write docs/benchmarks.md's section")
    parser.add_argument("--child", choices=CASES, help=argparse.SUPPRESS)
    args = parser.parse_args()
    res = tuple(int(x) for x in args.res.split("x"))
    if args.child:
        print(json.dumps(child(args.child, res, args.spp)))
        return
    rows = []
    for case in CASES:
        command = [sys.executable, __file__, "--child", case, "--res", args.res]
        out = subprocess.run(
            [*command, "--spp", str(args.spp)], check=True, capture_output=True, text=True
        )
        rows.append(json.loads(out.stdout.strip().splitlines()[-1]))
        print(rows[-1], flush=True)
    lines = section(rows, res, args.spp)
    print("\n".join(lines))
    if args.doc:
        replace_section("pixel_density", "\n".join(lines), SCRIPT)


if __name__ == "__main__":
    main()
