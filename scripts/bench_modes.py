"""Speed versus error of every hazy-level mode against converged references (issues #5, #6).

The benchmark scene (``scenes/benchmark.yaml``, 80×45) is rendered at 300, 1000 and 4000 m by
each mode at several sample counts. Each configuration runs in its own process, so its peak
memory is its own; kernels are compiled by a warm-up render first (1 spp, or in ``physical``,
whose sampler bakes its count into the kernels, the same spp and another seed), so the times
are warm.
Errors are measured against the converged ``reference`` images in
``assets/references/benchmark/`` (``scripts/make_references.py``; checksums verified):

* relative error = mean absolute error / mean, on luminance, over all pixels and over the sea,
  sky and vessel pixels (from the geometry pass);
* the reference's own noise floor, ``sqrt(2/π) · mean(SE) / mean``: the error a perfect
  renderer would show against it;
* the time ``reference`` would need for the same error, from its error at the highest spp
  measured scaled by ``1/sqrt(time)`` (Monte Carlo convergence);
* the error of the visibility ``seahaze verify`` measures in the mode at the same spp.

Results: the "modes" section of docs/benchmarks.md, ``docs/images/bench_speed_error.png``
(log-log) and ``docs/images/bench_strip.png`` (reference, asm and physical side by side).

Usage: python scripts/bench_modes.py [--quick] [--configs MODE:SPP+SPP,...] [--reuse]
"""

from __future__ import annotations

import argparse
import hashlib
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "scripts"))
from bench_passes import proc_status_mib, replace_section  # noqa: E402

SCENE = ROOT / "scenes" / "benchmark.yaml"
REFS = ROOT / "assets" / "references" / "benchmark"
IMAGES = ROOT / "docs" / "images"
LEVELS = (300.0, 1000.0, 4000.0)
CONFIGS: dict[str, tuple[int, ...]] = {
    "reference": (16, 64, 256, 1024),
    "asm": (64,),
    "physical": (4, 16, 64, 256, 1024),
}
QUICK: dict[str, tuple[int, ...]] = {"reference": (16, 64), "asm": (64,), "physical": (16, 64)}
STRIP_SPP = {"reference": 64, "asm": 64, "physical": 64}


def child(mode: str, spp: int, out: Path) -> None:
    """Render the three levels in ``mode`` at ``spp`` and save radiance, timings and memory."""
    from seahaze.render.engine import render_scene
    from seahaze.sceneio import load_scene
    from seahaze.spec import with_overrides

    spec, _ = load_scene(SCENE)
    spec = with_overrides(spec, spp=spp, mode=mode, levels=[float(v) for v in LEVELS])
    # Compiles every kernel. The physical pass's multijitter sampler bakes its sample count
    # into the kernels (the main pass's and the vessel-light pass's), so its warm-up takes the
    # same count, with another seed; the other modes' kernels serve every count.
    warm_spp = spp if mode == "physical" else 1
    render_scene(with_overrides(spec, spp=warm_spp, seed=spec.render.seed + 1), "warm-up")
    scene = render_scene(spec, "benchmark")
    if mode == "physical":
        # One pass renders the clean image and every level: its time shared by the levels.
        pass_seconds = scene.timings["pass"]
        seconds = [pass_seconds / len(scene.levels)] * len(scene.levels)
        clean_seconds = float("nan")
    else:
        seconds = [scene.timings[f"level_{level.name}"] for level in scene.levels]
        clean_seconds = scene.timings["clean"]
    peak_mib = proc_status_mib("VmHWM")
    vis_error, vis_stderr = measured_visibility_errors(mode, spp)
    np.savez(
        out,
        images=np.stack([level.radiance for level in scene.levels]),
        seconds=np.array(seconds),
        clean_seconds=clean_seconds,
        peak_mib=peak_mib,
        vis_error=vis_error,
        vis_stderr=vis_stderr,
        variant=scene.variant,
        distance=scene.geometry.distance_m,
        instance=scene.geometry.instance,
        elevation=scene.geometry.elevation_deg(),
    )


def measured_visibility_errors(mode: str, spp: int) -> tuple[np.ndarray, np.ndarray]:
    """Relative error of the visibility ``seahaze verify`` measures at each level, and its
    standard error: the thin-target calibration scene under the benchmark scene's sun, sky and
    haze, rendered in ``mode`` at ``spp`` (4 batches; NaN where the fit fails at low spp)."""
    from seahaze.sceneio import load_scene
    from seahaze.verify import VerifySettings, run_verify

    spec, _ = load_scene(SCENE)
    settings = VerifySettings(mode=mode, spp=max(spp, 4), batches=4, seed=1)
    report = run_verify(spec, list(LEVELS), settings)
    error = np.array([level.error for level in report.levels])
    stderr = np.array([level.stderr_m / level.visibility_m for level in report.levels])
    return error, stderr


def benchmark_world_digest() -> str:
    """The geometry digest of the benchmark scene as this seahaze builds it."""
    from seahaze.camera import Camera
    from seahaze.sceneio import load_scene
    from seahaze.world import build_geometry

    spec, _ = load_scene(SCENE)
    return build_geometry(spec, Camera.from_spec(spec.camera)).digest()


def load_references() -> tuple[dict[str, np.ndarray], dict[str, np.ndarray], dict]:
    """Reference radiance and luminance standard error per level, after checking checksums."""
    from seahaze.fileio import read_exr

    meta = json.loads((REFS / "references.json").read_text())
    if meta["scene_sha256"] != hashlib.sha256(SCENE.read_bytes()).hexdigest():
        raise SystemExit("scenes/benchmark.yaml changed since the references were rendered")
    if meta.get("world_sha256") != benchmark_world_digest():
        raise SystemExit(
            "the benchmark scene's geometry changed since the references were rendered "
            "(ocean or vessel generator): rerun scripts/make_references.py"
        )
    for line in (REFS / "SHA256SUMS").read_text().split("\n"):
        if line.strip():
            digest, name = line.split()
            if hashlib.sha256((REFS / name).read_bytes()).hexdigest() != digest:
                raise SystemExit(f"checksum mismatch for {REFS / name}")
    rgb, se = {}, {}
    for key in ["clean", *(f"v{int(v):04d}" for v in LEVELS)]:
        channels = read_exr(REFS / f"{key}.exr")
        rgb[key] = (
            channels["RGB"]
            if "RGB" in channels
            else np.stack([channels[c] for c in "RGB"], axis=-1)
        )
        se[key] = channels["Y_SE"]
    return rgb, se, meta


def region_masks(distance: np.ndarray, instance: np.ndarray) -> dict[str, np.ndarray]:
    """Sea, sky and vessel pixels from the geometry pass's distance and instance buffers."""
    sky = np.isinf(distance)
    vessel = instance >= 0
    return {"sea": ~sky & ~vessel, "sky": sky, "vessel": vessel}


def region_mean_stderr(se: np.ndarray, mask: np.ndarray, mean: float) -> float:
    """Standard error of a region's mean from its pixels' standard errors ``se`` (independent
    per pixel), relative to the region's ``mean``."""
    return float(np.sqrt(np.sum(se[mask] ** 2)) / mask.sum() / mean)


def errors(
    y: np.ndarray, y_ref: np.ndarray, se_ref: np.ndarray, regions: dict[str, np.ndarray]
) -> dict[str, float]:
    """Per region: relative mean absolute error (``name``), relative bias of the region's mean
    (``bias_name``) and the standard error of the reference's region mean relative to it
    (``bias_se_name``, from its per-pixel standard errors ``se_ref``, independent per pixel);
    ``bias`` is the whole image's."""
    out: dict[str, float] = {}
    for name, m in regions.items():
        mean_ref = y_ref[m].mean()
        out[name] = float(np.abs(y[m] - y_ref[m]).mean() / mean_ref)
        out[f"bias_{name}"] = float(y[m].mean() / mean_ref - 1.0)
        out[f"bias_se_{name}"] = region_mean_stderr(se_ref, m, mean_ref)
    out["bias"] = out["bias_all"]
    return out


def run_configs(configs: dict[str, tuple[int, ...]], work: Path, reuse: bool) -> list[dict]:
    """Run every (mode, spp) in its own process (``reuse``: take a result already in ``work``
    instead, to redo only the report); return their results."""
    rows = []
    for mode, spps in configs.items():
        for spp in spps:
            out = work / f"{mode}-{spp}.npz"
            if reuse and out.exists():
                print(f"{mode} {spp} spp: reusing {out}", flush=True)
            else:
                print(f"{mode} {spp} spp ...", flush=True)
                subprocess.run(
                    [sys.executable, __file__, "--child", mode, str(spp), str(out)], check=True
                )
            data = np.load(out)
            rows.append({"mode": mode, "spp": spp, **{k: data[k] for k in data.files}})
    return rows


def analyse(rows: list[dict]) -> list[dict]:
    """Per (mode, spp, level): time, memory, errors; and the reference-time equivalent."""
    from seahaze.imaging import luminance

    ref_rgb, ref_se, _ = load_references()
    first = rows[0]
    regions = region_masks(first["distance"], first["instance"])
    regions = {"all": np.ones_like(regions["sky"]), **regions}
    table = []
    for row in rows:
        for i, v in enumerate(LEVELS):
            key = f"v{int(v):04d}"
            y_ref = luminance(ref_rgb[key])
            err = errors(luminance(row["images"][i]), y_ref, ref_se[key], regions)
            floor = float(np.sqrt(2 / np.pi) * ref_se[key].mean() / y_ref.mean())
            table.append(
                {
                    "mode": row["mode"],
                    "spp": row["spp"],
                    "level": v,
                    "seconds": float(row["seconds"][i]),
                    "clean_seconds": float(row["clean_seconds"]),
                    "peak_mib": float(row["peak_mib"]),
                    "vis_error": float(row["vis_error"][i]),
                    "vis_stderr": float(row["vis_stderr"][i]),
                    "floor": floor,
                    **err,
                }
            )
    for v in LEVELS:
        refs = [r for r in table if r["mode"] == "reference" and r["level"] == v]
        best = max(refs, key=lambda r: r["spp"]) if refs else None
        for r in table:
            if r["level"] != v or best is None:
                continue
            # Reference error above its own floor falls as 1/sqrt(time).
            e_ref = max(best["all"] ** 2 - best["floor"] ** 2, 1e-12) ** 0.5
            e = max(r["all"] ** 2 - r["floor"] ** 2, 1e-12) ** 0.5
            r["reference_seconds_same_error"] = best["seconds"] * (e_ref / e) ** 2
    return table


def plot(table: list[dict]) -> None:
    """Log-log speed versus error, one line per mode and level."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5), dpi=120)
    colours = {"reference": "tab:red", "asm": "tab:orange", "physical": "tab:blue"}
    markers = {300.0: "o", 1000.0: "s", 4000.0: "^"}
    for mode, colour in colours.items():
        for v, marker in markers.items():
            pts = sorted(
                (r["seconds"], r["all"]) for r in table if r["mode"] == mode and r["level"] == v
            )
            if pts:
                xs, ys = zip(*pts, strict=True)
                ax.loglog(xs, ys, marker=marker, color=colour, label=f"{mode}, V = {v:g} m")
    floors = [r["floor"] for r in table]
    ax.axhline(max(floors), color="grey", ls=":", lw=1, label="reference noise floor (max)")
    ax.axhline(0.03, color="black", ls="--", lw=0.8, label="3 % target")
    ax.set_xlabel("wall seconds per level (80×45, warm)")
    ax.set_ylabel("relative error (MAE / mean luminance)")
    ax.set_title("seahaze modes: speed versus error (benchmark scene)")
    ax.legend(fontsize=7, ncol=2)
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    IMAGES.mkdir(parents=True, exist_ok=True)
    fig.savefig(IMAGES / "bench_speed_error.png")


def strip(rows: list[dict]) -> None:
    """Reference, asm and physical side by side per level (exposure from the clean reference)."""
    from PIL import Image, ImageDraw

    from seahaze.imaging import auto_exposure, to_srgb8

    ref_rgb, _, _ = load_references()
    first = rows[0]
    exposure = auto_exposure(ref_rgb["clean"], first["distance"], first["elevation"])
    scale = 4
    h, w = first["distance"].shape
    # Each mode at the sample count closest to STRIP_SPP among those that were run.
    spp_of = {
        m: min((r["spp"] for r in rows if r["mode"] == m), key=lambda n: abs(n - STRIP_SPP[m]))
        for m in ("reference", "asm", "physical")
        if any(r["mode"] == m for r in rows)
    }
    columns = [("reference (converged)", None)] + [(f"{m} {n} spp", m) for m, n in spp_of.items()]
    sheet = Image.new("RGB", (len(columns) * w * scale, len(LEVELS) * (h * scale + 14)), "black")
    draw = ImageDraw.Draw(sheet)
    for i, v in enumerate(LEVELS):
        y0 = i * (h * scale + 14)
        for j, (label, mode) in enumerate(columns):
            if mode is None:
                rgb = ref_rgb[f"v{int(v):04d}"]
            else:
                match = [r for r in rows if r["mode"] == mode and r["spp"] == spp_of[mode]]
                rgb = match[0]["images"][i]
            tile = Image.fromarray(to_srgb8(rgb, exposure)).resize((w * scale, h * scale), 0)
            sheet.paste(tile, (j * w * scale, y0 + 14))
            draw.text((j * w * scale + 3, y0 + 1), f"{label}, V = {v:g} m", fill="white")
    sheet.save(IMAGES / "bench_strip.png")


def write_doc(table: list[dict], meta: dict) -> None:
    import os
    import platform

    lv = meta["levels"]
    lines = [
        "## Speed versus error of the hazy-level modes (benchmark scene, 80×45)",
        "",
        f"Machine: {platform.machine()}, {len(os.sched_getaffinity(0))} vCPU. References: "
        "Mitsuba `volpath`, "
        + ", ".join(
            f"{k} {d['spp']:,} spp (standard error {100 * d['relative_stderr']:.1f} % of mean)"
            for k, d in sorted(lv.items())
        )
        + ". Error = mean absolute error / mean on luminance against the reference; the floor "
        "is what a perfect renderer would score against that reference (its own noise). "
        "'ref. time, same error' is the time `reference` would need for the same error above "
        "the floor, and ×faster its ratio to the mode's time. `physical` renders the clean image "
        "and every level in one pass: its 's / level' is that pass's time (tables included) "
        "over the three levels, and it has no separate clean pass. "
        "'V measured' is the error of the "
        "visibility that `seahaze verify` measures on its thin black targets under the same sun, "
        "sky and haze, rendered in the mode at the same spp (4 batches; ± one standard error; "
        "'–' where too few targets stand out of the noise to fit).",
        "",
        "| mode | spp | V (m) | s / level | clean s | peak MiB | all | sea | sky | vessel | "
        "bias | floor | ×faster than reference | V measured |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in table:
        speedup = r.get("reference_seconds_same_error", float("nan")) / r["seconds"]
        lines.append(
            f"| {r['mode']} | {r['spp']} | {r['level']:g} | {r['seconds']:.2f} | "
            f"{_seconds(r['clean_seconds'])} | {r['peak_mib']:.0f} | {100 * r['all']:.1f} % | "
            f"{100 * r['sea']:.1f} % | {100 * r['sky']:.1f} % | {100 * r['vessel']:.1f} % | "
            f"{100 * r['bias']:+.1f} % | {100 * r['floor']:.1f} % | {speedup:,.0f} | "
            f"{_percent_pm(r['vis_error'], r['vis_stderr'])} |"
        )
    lines += [
        "",
        "Bias of each region's mean against the reference's (± the reference's own standard "
        "error of that mean, its pixels' noise taken as independent):",
        "",
        "| mode | spp | V (m) | sea | sky | vessel |",
        "|---|---|---|---|---|---|",
    ]
    for r in table:
        lines.append(
            f"| {r['mode']} | {r['spp']} | {r['level']:g} | "
            + " | ".join(
                _percent_pm(r[f"bias_{k}"], r[f"bias_se_{k}"]) for k in ("sea", "sky", "vessel")
            )
            + " |"
        )
    lines += [
        "",
        "![speed versus error](images/bench_speed_error.png)",
        "",
        "![reference, asm and physical](images/bench_strip.png)",
    ]
    replace_section("modes", "\n".join(lines), "scripts/bench_modes.py")


def _seconds(value: float) -> str:
    """``1.23``, or a dash where there is no such pass."""
    return f"{value:.2f}" if np.isfinite(value) else "–"


def _percent_pm(value: float, stderr: float) -> str:
    """``+1.2 ± 0.4 %``, or a dash for a failed measurement."""
    if not np.isfinite(value):
        return "–"
    spread = f" ± {100 * stderr:.1f}" if np.isfinite(stderr) else ""
    return f"{100 * value:+.1f}{spread} %"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer sample counts")
    parser.add_argument(
        "--configs",
        help="modes and sample counts to run instead, e.g. reference:64,asm:64,physical:16+256",
    )
    parser.add_argument("--child", nargs=3, metavar=("MODE", "SPP", "OUT"), help=argparse.SUPPRESS)
    parser.add_argument("--work", type=Path, default=ROOT / "out" / "bench-modes")
    parser.add_argument(
        "--reuse", action="store_true", help="report from results already in --work, if present"
    )
    args = parser.parse_args()
    if args.child:
        child(args.child[0], int(args.child[1]), Path(args.child[2]))
        return
    args.work.mkdir(parents=True, exist_ok=True)
    configs = QUICK if args.quick else CONFIGS
    if args.configs:
        configs = {
            mode: tuple(int(n) for n in spps.split("+"))
            for mode, spps in (item.split(":") for item in args.configs.split(","))
        }
    rows = run_configs(configs, args.work, args.reuse)
    table = analyse(rows)
    (args.work / "results.json").write_text(json.dumps(table, indent=2))
    _, _, meta = load_references()
    plot(table)
    strip(rows)
    write_doc(table, meta)
    print((ROOT / "docs" / "benchmarks.md").read_text().split("<!-- modes:start")[1][:4000])


if __name__ == "__main__":
    main()
