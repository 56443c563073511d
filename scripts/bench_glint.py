"""The glint lobe on the hulls: the clean image's noise per region with and without it.

A sunlit hull is lit by the sea's sun glint, a caustic that the hull's cosine-weighted BSDF
samples find only now and then (``scripts/measure_gt_variance.py``: ~8 % rms on the ferry). The
``physical`` integrator draws a share of a hull's continuation directions from a lobe around the
sun's mirror image in the sea (:meth:`seahaze.render.glint_lobe.GlintLobe.continue_path`).
This script renders the default scene's clean image with that share at 0 (BSDF sampling alone,
the renderer before it) and at the default ``EstimatorSettings.glint_share``, each at two
sampler seeds, and reports per region (sky, sea, each vessel class) the rms per-pixel noise of
the luminance relative to the region's mean (``√(½ mean (a − b)²)``, no converged render
needed), the PSNR of the 8-bit image's noise, and the pass's time (the second seed's, warm). It
writes the "glint" section of docs/benchmarks.md and a crop figure of the ferry and the fishing
boat at 100 % and ×3, nearest-neighbour (docs/images/glint_crop.png).

Whether the lobe is unbiased is a test (tests/test_gt_noise.py), not this script's business.

Usage: python scripts/bench_glint.py [--res 1280x720] [--spp 42]
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_gt_noise import SEED, _res, _session, two_seed_psnr
from bench_passes import replace_section
from measure_gt_variance import regions

ROOT = Path(__file__).resolve().parents[1]
FIGURE = ROOT / "docs" / "images" / "glint_crop.png"
CROP_CLASSES = ("passenger_ferry", "fishing_boat")
ZOOM = 3
CROP = (48, 120)
"""Rows and columns of each crop (at 100 %)."""


def clean_pair(session: Any, spec: Any, share: float, spp: int) -> tuple[list[np.ndarray], float]:
    """The clean image at two sampler seeds with glint share ``share``, and the second pass's
    time (s)."""
    from seahaze.render.estimator import EstimatorSettings
    from seahaze.render.physical import PhysicalRenderer

    settings = EstimatorSettings(glint_share=share)
    renderer = PhysicalRenderer(session.loaded, spec, settings)
    images, seconds = [], 0.0
    for seed in (SEED, SEED + 1):
        start = time.perf_counter()
        images.append(renderer.render([], spec.haze.albedo, spec.haze.g, spp, seed).clean)
        seconds = time.perf_counter() - start
    return images, seconds


def noise(images: list[np.ndarray], masks: dict[str, np.ndarray], exposure: float) -> dict:
    """PSNR of one image's 8-bit noise and each region's relative rms luminance noise."""
    from seahaze import imaging

    out: dict[str, float] = {"psnr": two_seed_psnr(*images, exposure)}
    ya, yb = (imaging.luminance(x) for x in images)
    for name, mask in masks.items():
        mean = 0.5 * (ya[mask].mean() + yb[mask].mean())
        out[name] = float(np.sqrt(0.5 * np.mean((ya[mask] - yb[mask]) ** 2)) / mean)
    return out


def write_figure(tiles: list[tuple[str, np.ndarray]], session: Any, exposure: float) -> None:
    """Each setting's clean image around :data:`CROP_CLASSES`, at 100 % and ×:data:`ZOOM`."""
    from PIL import Image, ImageDraw

    from seahaze import imaging

    geo = session.pixels
    rows = []
    for kind in CROP_CLASSES:
        index = next(v.index for v in session.geometry.vessels if v.kind == kind)
        r, c = np.nonzero(geo.instance == index)
        # A window centred on the vessel's pixels (its superstructure, not the mast's tip).
        h, w = geo.instance.shape
        r0 = int(np.clip(r.mean() - CROP[0] // 2, 0, h - CROP[0]))
        c0 = int(np.clip(c.mean() - CROP[1] // 2, 0, w - CROP[1]))
        crop = (slice(r0, r0 + CROP[0]), slice(c0, c0 + CROP[1]))
        for label, image in tiles:
            pixels = imaging.to_srgb8(image[crop], exposure)
            rows.append((f"{kind}, {label}", pixels))
    width = max(p.shape[1] * (1 + ZOOM) + 8 for _, p in rows)
    height = sum(p.shape[0] * ZOOM + 16 for _, p in rows)
    canvas = Image.new("RGB", (width, height), "white")
    draw = ImageDraw.Draw(canvas)
    y = 0
    for label, pixels in rows:
        draw.text((2, y + 1), label, fill="black")
        h, w = pixels.shape[:2]
        canvas.paste(Image.fromarray(pixels), (0, y + 14))
        big = Image.fromarray(pixels).resize((w * ZOOM, h * ZOOM), Image.NEAREST)
        canvas.paste(big, (w + 8, y + 14))
        y += h * ZOOM + 16
    FIGURE.parent.mkdir(parents=True, exist_ok=True)
    canvas.save(FIGURE)


def main() -> None:
    from seahaze import imaging
    from seahaze.render.estimator import DEFAULT_SETTINGS
    from seahaze.render.glint_lobe import lobe_kappa

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--res", default="1280x720", type=_res)
    parser.add_argument("--spp", type=int, default=42)
    args = parser.parse_args()
    spec, session = _session(args.res)
    masks = regions(session)
    geo = session.pixels
    settings = [
        ("BSDF sampling alone (before)", 0.0),
        (f"glint lobe, share {DEFAULT_SETTINGS.glint_share}", DEFAULT_SETTINGS.glint_share),
    ]
    runs = [(label, *clean_pair(session, spec, share, args.spp)) for label, share in settings]
    exposure = imaging.auto_exposure(runs[0][1][0], geo.distance_m, geo.elevation_deg())
    results = [(label, noise(images, masks, exposure), seconds) for label, images, seconds in runs]
    names = list(masks)
    lines = [
        "## The glint on the hulls (scripts/bench_glint.py)",
        "",
        f"Machine: {platform.machine()}, {len(os.sched_getaffinity(0))} vCPU (shared). Default "
        f"scene's clean image at {args.res[0]}×{args.res[1]}, {args.spp} spp, two sampler seeds "
        "per setting: per region, one image's rms per-pixel luminance noise relative to the "
        "region's mean; PSNR of the 8-bit image's noise; the warm clean-only pass. The lobe: "
        f"von Mises–Fisher, κ = {lobe_kappa(spec.sea.wind_speed):.1f} (the scene's wind, "
        f"{spec.sea.wind_speed:g} m/s), around the sun's mirror image in the sea.",
        "",
        "| setting | pass (s) | clean PSNR (dB) | " + " | ".join(names) + " |",
        "|---|---|---|" + "---|" * len(names),
    ]
    for label, result, seconds in results:
        cells = " | ".join(f"{100 * result[n]:.1f} %" for n in names)
        lines.append(f"| {label} | {seconds:.1f} | **{result['psnr']:.1f}** | {cells} |")
        print(label, f"{seconds:.1f} s", f"{result['psnr']:.2f} dB", cells, flush=True)
    lines += [
        "",
        f"![glint crop](images/{FIGURE.name})",
        "",
        f"*The ferry's and the fishing boat's white superstructures in the clean image at "
        f"{args.spp} spp, at 100 % and ×{ZOOM} (nearest-neighbour), without and with the lobe "
        "(first seed).*",
    ]
    write_figure([(label, images[0]) for label, images, _ in runs], session, exposure)
    replace_section("glint", "\n".join(lines), "scripts/bench_glint.py")


if __name__ == "__main__":
    main()
