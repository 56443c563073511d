"""Measure the constants of the render-time cost model (``seahaze.cli.limits``, issue #19).

``seahaze render`` estimates a job's time before it starts and asks for ``--yes`` when it is an
hour or more (docs/limits.md). The model is linear in the work, per scene::

    core-seconds = setup(sea quality) + pixels · (aov + images · write)
                   + pixels · spp · clean
                   + Σ_levels [ fixed(mode, V) + pixels · spp · per_sample(mode, V) ]

except in ``physical``, whose one pass gives the clean image and every level::

    core-seconds = setup + writes + pixels · spp · (pass + (levels − 1) · level)
                   + Σ_levels table(V)

and wall time = core-seconds / cores. This script measures every constant on this machine with
the default scene (vessels included) through the public API (``open_session``,
``SceneSession.render_clean``, ``LevelRenderer.render``, ``write_scene``), in CPU time of the
process (user + system, all threads: a shared machine's load does not inflate it as much as wall
time), each pass run twice and the second run measured (kernels bake the sample count in, so
the first compiles). Per-sample constants are the slope between
two sample counts, fixed costs the intercept; ``V``-dependent ones are measured at 50, 300 and
4000 m and interpolated in log V.

It prints the constants as the Python block to paste into ``src/seahaze/cli/limits.py`` and
writes the "cost model" section of docs/benchmarks.md.

Usage: python scripts/measure_cost_model.py [--res 96x54] [--spp 4,64]
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "scripts"))
from bench_passes import replace_section  # noqa: E402

SCENE = ROOT / "scenes" / "default.yaml"
LEVELS = (50.0, 300.0, 4000.0)


def cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def timed(fn):
    start = cpu()
    result = fn()
    return result, cpu() - start


def measure(mode: str, res: tuple[int, int], spp: int) -> dict[str, float]:
    """CPU seconds of every pass of the default scene in ``mode`` at ``res`` and ``spp``
    (``physical``: only the clean pass and the writes; its one pass is
    :func:`measure_physical`'s)."""
    from seahaze.dataset import Layout
    from seahaze.dataset.writer import write_scene
    from seahaze.render.engine import open_session, render_scene
    from seahaze.sceneio import load_scene
    from seahaze.spec import with_overrides
    from seahaze.visibility import channel_extinction

    spec, _ = load_scene(SCENE)
    spec = with_overrides(spec, spp=spp, resolution=res, mode=mode, levels=list(LEVELS))
    out: dict[str, float] = {}
    # Kernels bake the sample count in: every pass runs once to compile, then is measured.
    for _ in range(2):
        session, out["open"] = timed(lambda: open_session(spec))
        clean, out["clean"] = timed(session.render_clean)
        renderer = session.level_renderer(clean)
        for i, v in enumerate(() if mode == "physical" else LEVELS):
            sigma = channel_extinction(v)
            _, out[f"level_{v:g}"] = timed(lambda r=renderer, s=sigma, i=i: r.render(s, i))
    small = with_overrides(spec, spp=1, levels=[300.0])
    scene = render_scene(small, "cost")
    with tempfile.TemporaryDirectory() as tmp:
        _, out["write_2_images"] = timed(lambda: write_scene(Layout(Path(tmp)), scene))
    return out


def measure_physical(res: tuple[int, int], spp: int) -> dict[str, float]:
    """CPU seconds of the physical one pass with one level and with the default scene's
    graded levels (tables apart: a level adds ~6 % to a pass, lost in the noise of three), and
    of each diffuse table of :data:`LEVELS` alone."""
    from seahaze.haze import extinction_rgb
    from seahaze.render.engine import open_session
    from seahaze.render.physical import PhysicalRenderer
    from seahaze.sceneio import load_scene
    from seahaze.spec import with_overrides
    from seahaze.visibility import channel_extinction

    spec, _ = load_scene(SCENE)
    spec = with_overrides(spec, spp=spp, resolution=res)
    haze = spec.haze
    renderer = PhysicalRenderer(open_session(spec).loaded, spec)
    sigmas = [channel_extinction(v) for v in haze.levels]
    tables, table_cpu = renderer.tables, [0.0]

    def timed_tables(*args):
        result, seconds = timed(lambda: tables(*args))
        table_cpu[0] += seconds
        return result

    renderer.tables = timed_tables
    out: dict[str, float] = {}
    for _ in range(2):  # the first run loads the kernels
        for n in (1, len(sigmas)):
            table_cpu[0] = 0.0
            _, total = timed(lambda n=n: renderer.render(sigmas[:n], haze.albedo, haze.g, spp, 1))
            out[f"pass_{'all' if n > 1 else 1}"] = total - table_cpu[0]
    out["levels"] = len(sigmas)
    for v in LEVELS:
        rgb = extinction_rgb(channel_extinction(v))[None, :]
        _, out[f"table_{v:g}"] = timed(lambda rgb=rgb: tables(rgb, haze.albedo, haze.g, 7))
    return out


def geometry_seconds() -> dict[str, float]:
    """CPU seconds of the sea and vessel geometry per sea quality."""
    from seahaze.camera import Camera
    from seahaze.sceneio import load_scene
    from seahaze.spec import with_changes
    from seahaze.world import build_geometry

    base, _ = load_scene(SCENE)
    out = {}
    for quality in ("low", "medium", "high"):
        spec = with_changes(base, {"sea": {"quality": quality}})
        _, out[quality] = timed(
            lambda spec=spec: build_geometry(spec, Camera.from_spec(spec.camera))
        )
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--res", default="96x54")
    parser.add_argument("--spp", default="4,64")
    args = parser.parse_args()
    width, height = (int(x) for x in args.res.lower().split("x"))
    low, high = (int(x) for x in args.spp.split(","))
    pixels = width * height
    started = time.time()

    runs = {
        mode: {spp: measure(mode, (width, height), spp) for spp in (low, high)}
        for mode in ("physical", "reference", "asm")
    }
    passes = {spp: measure_physical((width, height), spp) for spp in (low, high)}
    geometry = geometry_seconds()

    def slope(mode: str, key: str) -> tuple[float, float]:
        a, b = runs[mode][low][key], runs[mode][high][key]
        per = max((b - a) / (pixels * (high - low)), 0.0)
        return per, max(a - per * pixels * low, 0.0)

    clean = [slope(m, "clean")[0] for m in runs]
    c_clean = sorted(clean)[1]  # the median of the three modes' clean passes (the same pass)

    def pass_slope(key: str) -> float:
        a, b = passes[low][key], passes[high][key]
        return max((b - a) / (pixels * (high - low)), 0.0)

    n_all = int(passes[high]["levels"])
    per_pass, per_all = pass_slope("pass_1"), pass_slope("pass_all")
    per_level = max((per_all - per_pass) / (n_all - 1), 0.0)
    tables = {v: passes[high][f"table_{v:g}"] for v in LEVELS}
    reference = {v: slope("reference", f"level_{v:g}") for v in LEVELS}
    asm = {v: runs["asm"][high][f"level_{v:g}"] for v in LEVELS}
    opens = [runs[m][s]["open"] for m in runs for s in (low, high)]
    aov_and_load = max(sorted(opens)[len(opens) // 2] - geometry["medium"], 0.0)
    write_px = runs["physical"][high]["write_2_images"] / (2 * pixels)
    consts = {
        "SETUP_CORE_S": {q: round(g + aov_and_load, 2) for q, g in geometry.items()},
        "CLEAN_CORE_S": float(f"{c_clean:.3g}"),
        "WRITE_CORE_S": float(f"{write_px:.3g}"),
        # The physical pass's work per sample does not depend on V (its tables do).
        "PHYSICAL_PASS_CORE_S": float(f"{per_pass:.3g}"),
        "PHYSICAL_LEVEL_CORE_S": float(f"{per_level:.3g}"),
        "PHYSICAL_TABLE_S": {v: round(tables[v], 2) for v in LEVELS},
        "REFERENCE_CORE_S": {v: float(f"{reference[v][0]:.3g}") for v in LEVELS},
        "ASM_LEVEL_S": {v: round(asm[v], 2) for v in LEVELS},
    }
    cores = len(os.sched_getaffinity(0))
    print("# measured by scripts/measure_cost_model.py")
    for key, value in consts.items():
        print(f"{key} = {value!r}")
    lines = [
        "## Cost model of `seahaze render`'s time estimate",
        "",
        f"Machine: {platform.machine()}, {cores} vCPU (shared); default scene, {width}×{height}, "
        f"{low} and {high} spp; CPU seconds of the process (all threads), warm kernels. "
        f"Measured in {time.time() - started:.0f} s by `scripts/measure_cost_model.py`; the "
        "constants are in `src/seahaze/cli/limits.py`, the model in docs/limits.md.",
        "",
        "| constant | value | meaning |",
        "|---|---|---|",
        "| setup (low / medium / high sea) | "
        + " / ".join(f"{consts['SETUP_CORE_S'][q]:.2f} s" for q in ("low", "medium", "high"))
        + " | geometry, scene load and geometry pass, per scene |",
        f"| clean | {c_clean:.3g} s | per pixel-sample |",
        f"| write | {write_px:.3g} s | per pixel and image (PNG, EXR, labels) |",
    ]
    lines.append(
        f"| physical pass | {consts['PHYSICAL_PASS_CORE_S']:.3g} s | per pixel-sample: the one "
        "pass with its clean image and one level |"
    )
    lines.append(
        f"| physical level | {consts['PHYSICAL_LEVEL_CORE_S']:.3g} s | per pixel-sample and "
        f"further level (a pass of {n_all} levels against one) |"
    )
    for v in LEVELS:
        lines.append(
            f"| physical table, V = {v:g} m | {tables[v]:.2f} s | per level (its diffuse table "
            "at 2^17 photons; scaled by the photons traced) |"
        )
    for v in LEVELS:
        lines.append(f"| reference, V = {v:g} m | {reference[v][0]:.3g} s | per pixel-sample |")
    for v in LEVELS:
        lines.append(
            f"| asm, V = {v:g} m | {asm[v]:.2f} s | per level (airlight, 1024 spp; composite) |"
        )
    replace_section("cost", "\n".join(lines), "scripts/measure_cost_model.py")


if __name__ == "__main__":
    main()
