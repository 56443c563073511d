"""Ground-truth noise of the physical mode: PSNR, SSIM and per-region error against converged
renders, per setting (spp, denoise), into docs/benchmarks.md (issue 14).

The default scene's one pass (clean image and 11 levels) is rendered at each setting with one
sampler seed and compared with a converged render of the same scene (the same geometry,
the same diffuse-field tables and exposure; ``--ref-spp`` samples, another sampler seed), on

* the 8-bit sRGB images a dataset's PNGs hold (the scene's auto exposure of the converged
  clean image): PSNR and SSIM by scikit-image (``skimage.metrics``), the numbers dehazing
  papers report;
* linear luminance per region (sky, sea, each vessel class): rms per-pixel error and the mean
  (bias) relative to the region's converged mean;
* the apparent contrast of every vessel (``annotate.apparent_contrasts``, what ``meta``
  records) against the converged image's.

Sub-commands: ``render`` renders one setting's pass to an ``.npz`` (any source tree: run it
with another ``PYTHONPATH`` to measure an older renderer, ``--label`` names it); ``report``
compares every ``.npz`` given with the reference and writes the section and a crop figure.
``all`` does both for the settings of the table. ``seeds`` measures the noise alone at any
size, where a converged render would take too long (1280×720): two renders with different
sampler seeds differ by twice one image's noise variance, so ``PSNR = 10 log10(255² / (½ mean
(a − b)²))`` on the 8-bit images; it leaves out the bias (none in the clean image, which has no
table). Its results accumulate per size in ``out/gt_noise/seeds.json`` and their own section.
``full`` compares the clean image alone with one of more samples at any size, a check of
``seeds`` and of the clean image's bias where a 1024-spp pass is out of reach.

Usage: python scripts/bench_gt_noise.py all [--res 160x90] [--ref-spp 1024] [--before FILE]
       python scripts/bench_gt_noise.py seeds --res 1280x720 [--spp 32]
       python scripts/bench_gt_noise.py full --res 1280x720 --spp 42 --ref-spp 256
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_passes import replace_section  # noqa: E402
from measure_gt_variance import regions  # noqa: E402

DEFAULT = ROOT / "scenes" / "default.yaml"
OUT = ROOT / "out" / "gt_noise"
FIGURE = ROOT / "docs" / "images" / "gt_noise_crop.png"
SEED, REF_SEED, TABLE_SEED = 1, 1000, 7
"""Sampler seeds of the settings and of the converged reference, and the seed of the diffuse
tables all of them share (the scene's own seed fixes the geometry)."""


def _session(res: tuple[int, int]) -> tuple[Any, Any]:
    from seahaze.render.engine import open_session
    from seahaze.sceneio import load_scene
    from seahaze.spec import with_overrides

    spec, _ = load_scene(DEFAULT)
    spec = with_overrides(spec, resolution=res)
    return spec, open_session(spec)


def render(res: tuple[int, int], spp: int, seed: int, denoise: bool, out: Path, label: str) -> None:
    """One pass (clean + every level) of the default scene into ``out`` (.npz), with its time
    (the pass, warm: after a pass of the same spp and another seed) and the denoiser's."""
    from seahaze import imaging
    from seahaze.render.physical import PhysicalRenderer
    from seahaze.visibility import channel_extinction

    spec, session = _session(res)
    haze = spec.haze
    renderer = PhysicalRenderer(session.loaded, spec)
    # Every setting and the reference share one diffuse-field table (its own seed), so they
    # differ by their camera paths' noise only (written as a wrapper: older renderers too).
    tables = renderer.tables

    def fixed_tables(sigma: np.ndarray, albedo: float, g: float, _seed: int, *rest: Any) -> Any:
        return tables(sigma, albedo, g, TABLE_SEED, *rest)

    renderer.tables = fixed_tables  # type: ignore[method-assign]
    sigmas = [channel_extinction(v, haze.threshold, haze.extinction_spectrum) for v in haze.levels]
    # Compile (or load) the kernel first: it depends on the sample count.
    renderer.render(sigmas, haze.albedo, haze.g, spp, seed + 1)
    start = time.perf_counter()
    run = renderer.render(sigmas, haze.albedo, haze.g, spp, seed)
    seconds = time.perf_counter() - start
    images = np.stack([run.clean, *run.levels])
    denoise_s = 0.0
    if denoise:
        from seahaze.render import denoise as oidn

        start = time.perf_counter()
        geo = session.pixels
        exposure = imaging.auto_exposure(run.clean, geo.distance_m, geo.elevation_deg())
        features = oidn.feature_buffers(session.loaded, seed + 17)
        images = np.stack([oidn.denoise(image, features, exposure) for image in images])
        denoise_s = time.perf_counter() - start
    np.savez_compressed(
        out,
        images=images.astype(np.float32),
        seconds=seconds,
        denoise_seconds=denoise_s,
        spp=spp,
        denoise=denoise,
        label=label,
        levels=np.array(haze.levels, float),
    )
    print(f"{out.name}: {seconds:.1f} s + denoise {denoise_s:.1f} s", flush=True)


def compare(run: np.ndarray, ref: np.ndarray, session: Any) -> dict[str, Any]:
    """Metrics of every image of ``run`` (12, H, W, 3) against ``ref`` (same shape)."""
    from skimage.metrics import peak_signal_noise_ratio, structural_similarity

    from seahaze import annotate, imaging

    geo = session.pixels
    exposure = imaging.auto_exposure(ref[0], geo.distance_m, geo.elevation_deg())
    masks = regions(session)
    n_vessels = len(session.geometry.vessels)
    out: dict[str, Any] = {"psnr": [], "ssim": [], "regions": [], "contrast": []}
    for image, truth in zip(run, ref, strict=True):
        a, b = imaging.to_srgb8(image, exposure), imaging.to_srgb8(truth, exposure)
        out["psnr"].append(float(peak_signal_noise_ratio(b, a, data_range=255)))
        out["ssim"].append(float(structural_similarity(b, a, channel_axis=2, data_range=255)))
        y, y_ref = imaging.luminance(image), imaging.luminance(truth)
        per: dict[str, dict[str, float]] = {}
        for name, mask in masks.items():
            mean = float(np.mean(y_ref[mask]))
            err = y[mask] - y_ref[mask]
            per[name] = {
                "rms": float(np.sqrt(np.mean(err**2)) / mean),
                "bias": float(np.mean(err) / mean),
            }
        out["regions"].append(per)
        horizon = annotate.horizon_luminance(image, geo.distance_m, geo.elevation_deg())
        horizon_ref = annotate.horizon_luminance(truth, geo.distance_m, geo.elevation_deg())
        c = annotate.apparent_contrasts(image, geo.instance, n_vessels, horizon)
        c_ref = annotate.apparent_contrasts(truth, geo.instance, n_vessels, horizon_ref)
        out["contrast"].append([[_num(x), _num(r)] for x, r in zip(c, c_ref, strict=True)])
    return out


def _num(value: Any) -> float | None:
    return None if value is None or not np.isfinite(value) else float(value)


def report(files: list[Path], reference: Path, res: tuple[int, int]) -> None:
    """Compare every render in ``files`` with ``reference``; write the section and figure."""
    ref = np.load(reference)
    _, session = _session(res)
    results = []
    for f in files:
        data = np.load(f)
        metrics = compare(data["images"], ref["images"], session)
        results.append(
            {
                "label": str(data["label"]),
                "spp": int(data["spp"]),
                "denoise": bool(data["denoise"]),
                "seconds": float(data["seconds"]),
                "denoise_seconds": float(data["denoise_seconds"]),
                **metrics,
            }
        )
        print(
            f"{results[-1]['label']}: clean {metrics['psnr'][0]:.2f} dB, levels "
            f"{min(metrics['psnr'][1:]):.2f}–{max(metrics['psnr'][1:]):.2f} dB",
            flush=True,
        )
    (OUT / "report.json").write_text(json.dumps(results, indent=2))
    levels = [float(v) for v in ref["levels"]]
    write_figure(files, ref["images"], session)
    write_section(results, levels, res, int(ref["spp"]), session)


def write_figure(files: list[Path], ref: np.ndarray, session: Any) -> None:
    """A crop around the passenger ferry, nearest-neighbour ×4, of each setting's clean
    image and the converged one, side by side (docs/images/gt_noise_crop.png)."""
    from PIL import Image, ImageDraw

    from seahaze import imaging

    geo = session.pixels
    exposure = imaging.auto_exposure(ref[0], geo.distance_m, geo.elevation_deg())
    ferry = next(v.index for v in session.geometry.vessels if v.kind == "passenger_ferry")
    rows, cols = np.nonzero(geo.instance == ferry)
    h, w = geo.instance.shape
    half_h, half_w = max(8, h // 8), max(14, w // 8)
    r0 = int(np.clip(rows.mean() - half_h, 0, h - 2 * half_h))
    c0 = int(np.clip(cols.mean() - half_w, 0, w - 2 * half_w))
    crop = (slice(r0, r0 + 2 * half_h), slice(c0, c0 + 2 * half_w))
    zoom = 4
    tiles = [(str(np.load(f)["label"]).split(" (")[0], np.load(f)["images"][0]) for f in files]
    tiles.append(("converged", ref[0]))
    th, tw = 2 * half_h * zoom, 2 * half_w * zoom
    canvas = Image.new("RGB", (tw * len(tiles) + 4 * (len(tiles) - 1), th + 14), "white")
    draw = ImageDraw.Draw(canvas)
    for i, (label, image) in enumerate(tiles):
        pixels = imaging.to_srgb8(image[crop], exposure)
        tile = Image.fromarray(pixels).resize((tw, th), Image.NEAREST)
        canvas.paste(tile, (i * (tw + 4), 14))
        draw.text((i * (tw + 4) + 2, 1), label, fill="black")
    FIGURE.parent.mkdir(parents=True, exist_ok=True)
    canvas.save(FIGURE)


def write_section(
    results: list[dict], levels: list[float], res: tuple[int, int], ref_spp: int, session: Any
) -> None:
    """The "Ground-truth noise" section of docs/benchmarks.md."""
    names = list(results[0]["regions"][0])
    lines = [
        "## Ground-truth noise (`physical`, scripts/bench_gt_noise.py)",
        "",
        f"Machine: {platform.machine()}, {len(os.sched_getaffinity(0))} vCPU (shared). Default "
        f"scene at {res[0]}×{res[1]}, one pass (clean + {len(levels)} levels) per setting against "
        f"a converged pass of the current renderer ({ref_spp} spp, another sampler seed). PSNR "
        "and SSIM (scikit-image) on the 8-bit sRGB images at the converged clean image's auto "
        "exposure; time: the warm pass (and the denoiser: feature pass + 12 filters).",
        "",
        "| setting | pass (s) | denoise (s) | clean PSNR (dB) | levels PSNR min–max (dB) "
        "| clean SSIM | levels SSIM min |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in results:
        lines.append(
            f"| {r['label']} | {r['seconds']:.1f} | {r['denoise_seconds']:.1f} | "
            f"**{r['psnr'][0]:.1f}** | {min(r['psnr'][1:]):.1f}–{max(r['psnr'][1:]):.1f} | "
            f"{r['ssim'][0]:.4f} | {min(r['ssim'][1:]):.4f} |"
        )
    lines += [
        "",
        "Per-region rms per-pixel error of the clean image's luminance, relative to the region's "
        "converged mean (in brackets: the mean error, the bias plus the noise of the mean):",
        "",
        "| setting | " + " | ".join(names) + " |",
        "|---|" + "---|" * len(names),
    ]
    for r in results:
        cells = [
            f"{100 * r['regions'][0][n]['rms']:.1f} % ({100 * r['regions'][0][n]['bias']:+.1f})"
            for n in names
        ]
        lines.append(f"| {r['label']} | " + " | ".join(cells) + " |")
    lines += [
        "",
        "Worst level: per region, the largest rms error and the largest |mean error| over the "
        f"{len(levels)} levels:",
        "",
        "| setting | " + " | ".join(names) + " |",
        "|---|" + "---|" * len(names),
    ]
    for r in results:
        cells = []
        for n in names:
            rms = max(level[n]["rms"] for level in r["regions"][1:])
            bias = max(abs(level[n]["bias"]) for level in r["regions"][1:])
            cells.append(f"{100 * rms:.1f} % ({100 * bias:.1f})")
        lines.append(f"| {r['label']} | " + " | ".join(cells) + " |")
    lines += [
        "",
        "Apparent contrast of every vessel (what `meta` records) against the converged image's: "
        "largest absolute difference over the vessels, for the clean image and over all levels, "
        "and over the faint ones (|C| < 0.1 in the converged level):",
        "",
        "| setting | clean | all levels | faint vessels |",
        "|---|---|---|---|",
    ]
    for r in results:
        pairs = [(i, p) for i, per in enumerate(r["contrast"]) for p in per if None not in p]
        clean = max((abs(a - b) for i, (a, b) in pairs if i == 0), default=float("nan"))
        level = max((abs(a - b) for i, (a, b) in pairs if i > 0), default=float("nan"))
        faint = [abs(a - b) for i, (a, b) in pairs if i > 0 and abs(b) < 0.1]
        lines.append(
            f"| {r['label']} | {clean:.4f} | {level:.4f} | "
            f"{max(faint, default=float('nan')):.4f} ({len(faint)}) |"
        )
    lines += [
        "",
        f"![crop](images/{FIGURE.name})",
        "",
        "*The passenger ferry's white superstructure in the clean image, nearest-neighbour ×4, "
        "per setting and converged.*",
    ]
    replace_section("gt-noise", "\n".join(lines), "scripts/bench_gt_noise.py")


def two_seed_psnr(a: np.ndarray, b: np.ndarray, exposure: float) -> float:
    """PSNR (dB) of one image's noise from two renders ``a``, ``b`` that differ only in the
    sampler seed, on their 8-bit sRGB images: ``10 log10(255² / (½ mean (a − b)²))``."""
    from seahaze import imaging

    a8 = imaging.to_srgb8(a, exposure).astype(np.float64)
    b8 = imaging.to_srgb8(b, exposure).astype(np.float64)
    return float(10.0 * np.log10(255.0**2 / (0.5 * np.mean((a8 - b8) ** 2))))


def seeds(res: tuple[int, int], spp: int) -> None:
    """Noise-only PSNR of the clean image and every level at ``res`` from two sampler seeds
    (module docstring); updates ``out/gt_noise/seeds.json`` and the section."""
    from seahaze import imaging
    from seahaze.render.physical import PhysicalRenderer
    from seahaze.visibility import channel_extinction

    spec, session = _session(res)
    haze = spec.haze
    renderer = PhysicalRenderer(session.loaded, spec)
    sigmas = [channel_extinction(v, haze.threshold, haze.extinction_spectrum) for v in haze.levels]
    runs, seconds = [], []
    for seed in (SEED, SEED + 1):
        start = time.perf_counter()
        run = renderer.render(sigmas, haze.albedo, haze.g, spp, seed)
        seconds.append(time.perf_counter() - start)
        runs.append(np.stack([run.clean, *run.levels]))
    geo = session.pixels
    mean_clean = 0.5 * (runs[0][0] + runs[1][0])
    exposure = imaging.auto_exposure(mean_clean, geo.distance_m, geo.elevation_deg())
    psnr = [two_seed_psnr(a, b, exposure) for a, b in zip(*runs, strict=True)]
    store = OUT / "seeds.json"
    results = json.loads(store.read_text()) if store.exists() else {}
    key = f"{res[0]}x{res[1]} {spp}"
    results[key] = {"res": list(res), "spp": spp, "psnr": psnr, "pass_s": seconds[-1]}
    store.write_text(json.dumps(results, indent=2))
    print(f"{key}: clean {psnr[0]:.2f} dB, levels {min(psnr[1:]):.2f}–{max(psnr[1:]):.2f} dB")
    rows = sorted(results.values(), key=lambda r: (r["res"][0] * r["res"][1], r["spp"]))
    lines = [
        "### Noise by image size (scripts/bench_gt_noise.py seeds)",
        "",
        f"Machine: {platform.machine()}, {len(os.sched_getaffinity(0))} vCPU (shared). The "
        "default scene's one pass at two sampler seeds; PSNR of one image's noise on the 8-bit "
        "sRGB images (half the mean squared difference of the two). Each seed traces its own "
        "diffuse tables, so the levels' figures include the tables' noise; a bias would not "
        "show (the clean image, which has no table, has none). Pass: the second render's "
        "time, tables included.",
        "",
        "| size | spp | clean PSNR (dB) | levels PSNR min–max (dB) | pass (s) |",
        "|---|---|---|---|---|",
    ]
    for r in rows:
        p = r["psnr"]
        lines.append(
            f"| {r['res'][0]}×{r['res'][1]} | {r['spp']} | **{p[0]:.1f}** | "
            f"{min(p[1:]):.1f}–{max(p[1:]):.1f} | {r['pass_s']:.1f} |"
        )
    replace_section("gt-noise-size", "\n".join(lines), "scripts/bench_gt_noise.py")


def clean_against_reference(res: tuple[int, int], spp: int, ref_spp: int) -> None:
    """The clean image alone at ``spp`` against one at ``ref_spp`` (another sampler seed), at a
    size where a 1024-spp pass would take too long: PSNR on the 8-bit images as measured, and
    corrected for the reference's own noise (its variance is ``spp / ref_spp`` of the
    image's, the same estimator), plus each region's mean against the reference's; the
    "gt-noise-full" section."""
    from skimage.metrics import peak_signal_noise_ratio

    from seahaze import imaging
    from seahaze.render.physical import PhysicalRenderer

    spec, session = _session(res)
    renderer = PhysicalRenderer(session.loaded, spec)
    image, ref = (
        renderer.render([], spec.haze.albedo, spec.haze.g, n, seed).clean
        for n, seed in ((spp, SEED), (ref_spp, REF_SEED))
    )
    geo = session.pixels
    exposure = imaging.auto_exposure(ref, geo.distance_m, geo.elevation_deg())
    a8, r8 = imaging.to_srgb8(image, exposure), imaging.to_srgb8(ref, exposure)
    raw = float(peak_signal_noise_ratio(r8, a8, data_range=255))
    corrected = raw + 10.0 * np.log10(1.0 + spp / ref_spp)
    y, y_ref = imaging.luminance(image), imaging.luminance(ref)
    means = {k: float(y[m].mean() / y_ref[m].mean() - 1.0) for k, m in regions(session).items()}
    print(f"clean {raw:.2f} dB against {ref_spp} spp, {corrected:.2f} dB corrected")
    lines = [
        "### The clean image at full size against a higher-spp render (bench_gt_noise.py full)",
        "",
        f"Default scene, clean image at {res[0]}×{res[1]} and {spp} spp against {ref_spp} spp "
        f"(another sampler seed): PSNR **{raw:.2f} dB** as measured, a lower bound (the "
        f"reference's own noise included), **{corrected:.2f} dB** corrected for it. Mean "
        "luminance per region against the reference's: "
        + ", ".join(f"{k} {100 * v:+.2f} %" for k, v in means.items())
        + ".",
    ]
    replace_section("gt-noise-full", "\n".join(lines), "scripts/bench_gt_noise.py")


def _res(text: str) -> tuple[int, int]:
    w, h = (int(v) for v in text.split("x"))
    return w, h


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("command", choices=["render", "report", "all", "seeds", "full"])
    parser.add_argument("--res", default="160x90", type=_res)
    parser.add_argument("--spp", type=int, default=32, help="render: samples per pixel")
    parser.add_argument(
        "--spps", type=int, nargs="+", default=[32, 64], help="all: the settings' spp"
    )
    parser.add_argument("--ref-spp", type=int, default=1024)
    parser.add_argument("--seed", type=int, default=SEED)
    parser.add_argument("--denoise", action="store_true")
    parser.add_argument("--label", default="")
    parser.add_argument("--out", type=Path, help="render: the .npz to write")
    parser.add_argument("--before", type=Path, nargs="*", default=[], help="renders to add")
    args = parser.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    tag = f"{args.res[0]}x{args.res[1]}"
    reference = OUT / f"reference_{tag}_{args.ref_spp}.npz"
    if args.command == "seeds":
        seeds(args.res, args.spp)
        return
    if args.command == "full":
        clean_against_reference(args.res, args.spp, args.ref_spp)
        return
    if args.command == "render":
        label = args.label or f"{args.spp} spp{', denoised' if args.denoise else ''}"
        out = args.out or OUT / f"{tag}_{args.spp}_{int(args.denoise)}.npz"
        render(args.res, args.spp, args.seed, args.denoise, out, label)
        return
    if args.command == "all":
        if not reference.exists():
            render(args.res, args.ref_spp, REF_SEED, False, reference, "converged")
        for spp in args.spps:
            for denoise in (False, True):
                label = f"{spp} spp{', denoised' if denoise else ''}"
                render(
                    args.res,
                    spp,
                    args.seed,
                    denoise,
                    OUT / f"{tag}_{spp}_{int(denoise)}.npz",
                    label,
                )
    files = [*args.before, *sorted(OUT.glob(f"{tag}_*.npz"))]
    report(files, reference, args.res)


if __name__ == "__main__":
    main()
