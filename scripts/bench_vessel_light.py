"""The vessel-light pass's noise, time and smoothing bias per setting, and the crop figure.

The pass (``seahaze.render.vessel_light``) corrects the haze in front of vessels; its Monte
Carlo estimate is sparse where probes rarely meet a hull. On the default scene at one level
this renders the main pass once, then per setting (the pass's samples per pixel, share of
probe points drawn near a vessel, share of directions aimed at one, smoothing radius) the
pass alone with two sampler seeds, and reports over the pixels that are not vessels (sky
and sea), in the whole image and in a crop around the passenger ferry:

* ``noise``: rms of one image's noise (half the seeds' difference, times √2) of the
  correction, over the region's mean radiance;
* ``speckle``: the share of those pixels where that noise passes 2 % of the pixel's
  radiance, which shows at 100 % zoom as a bright or dark dot in the smooth haze;
* the pass's time (warm: after a render of a third seed).

The smoothing's bias: two unsmoothed renders ``A`` and ``B`` of ``--bias-spp`` samples with
independent seeds give the mean squared bias of a filter ``S`` without their noise, as the
mean of ``(S(A) − A)·(S(B) − B)`` (the noises are independent); its root, over the region's
mean radiance, per region (sky, sea, vessels).

Writes docs/images/vessel_light_speckle.png (the crop at 100 %: without the pass, then each
setting) and the section "The vessel-light pass's noise" of docs/benchmarks.md.

Usage: python scripts/bench_vessel_light.py [--res 1280x720] [--spp 42] [--vis 4000]
       [--bias-spp 169]
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import platform
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_gt_noise import TABLE_SEED, _session  # noqa: E402
from bench_modes import region_masks  # noqa: E402
from bench_passes import replace_section  # noqa: E402

FIGURE = ROOT / "docs" / "images" / "vessel_light_speckle.png"
SPECKLE = 0.02
"""One image's noise, relative to the pixel's radiance, above which a pixel is a speckle."""
SETTINGS = (
    ("mixture and phase function", 12, 0.0, 0.0, 0),
    ("near and aimed", 12, 0.5, 0.5, 0),
    ("mixture and phase function, smoothed", 6, 0.0, 0.0, 6),
    ("near and aimed, smoothed", 4, 0.5, 0.5, 4),
    ("near and aimed, smoothed (the default)", 3, 0.5, 0.5, 6),
    ("near and aimed, smoothed", 2, 0.5, 0.5, 6),
)
"""(label, the pass's spp, share of points drawn near a vessel, share of directions aimed at
one, smoothing radius in pixels)."""


def crop_of(session: Any) -> tuple[slice, slice]:
    """A window around the passenger ferry, a quarter of the image wide and high."""
    geo = session.pixels
    ferry = next(v.index for v in session.geometry.vessels if v.kind == "passenger_ferry")
    rows, cols = np.nonzero(geo.instance == ferry)
    h, w = geo.instance.shape
    half_h, half_w = h // 8, w // 8
    r0 = int(np.clip(rows.mean() - half_h, 0, h - 2 * half_h))
    c0 = int(np.clip(cols.mean() - half_w, 0, w - 2 * half_w))
    return slice(r0, r0 + 2 * half_h), slice(c0, c0 + 2 * half_w)


class Bench:
    """The default scene at one level, its main pass and its fixed diffuse table."""

    def __init__(self, res: tuple[int, int], spp: int, vis: float):
        from seahaze.visibility import channel_extinction

        self.spec, self.session = _session(res)
        self.spp, haze = spp, self.spec.haze
        self.sigma_rgb = channel_extinction(vis, haze.threshold, haze.extinction_spectrum)
        self.sigma = np.broadcast_to(self.sigma_rgb, (1, 3)).astype(float)
        self.grey = bool(np.all(self.sigma == self.sigma[:, 1:2]))
        renderer = self.renderer(0.0, 0.0, vessel_light_share=0.0)
        photons = renderer.settings.min_table_photons
        self.tables = renderer.tables(self.sigma, haze.albedo, haze.g, TABLE_SEED, photons)
        renderer.tables = lambda *a, **k: self.tables  # type: ignore[method-assign]
        run = renderer.render([self.sigma_rgb], haze.albedo, haze.g, spp, 1)
        self.main = run.levels[0]
        geo = self.session.pixels
        self.regions = region_masks(geo.distance_m, geo.instance)

    def renderer(self, near: float, aim: float, **settings: Any) -> Any:
        """A fresh renderer whose vessel-light probes are drawn near (``near``) and aimed at
        (``aim``) the vessels in these shares, with further estimator ``settings``."""
        from seahaze.render.estimator import EstimatorSettings
        from seahaze.render.physical import PhysicalRenderer

        chosen = EstimatorSettings(near_share=near, aim_share=aim, **settings)
        return PhysicalRenderer(self.session.loaded, self.spec, chosen, self.session.pixels)

    def correction(self, renderer: Any, share: float, radius: int, seed: int) -> np.ndarray:
        """The pass's (H, W, 3) correction of the level, at ``share`` of the spp, smoothed
        over ``radius`` pixels."""
        renderer.settings = dataclasses.replace(
            renderer.settings, vessel_light_share=share, vessel_light_radius_px=radius
        )
        haze = self.spec.haze
        image = renderer.vessel_light(self.sigma, haze.albedo, haze.g, self.tables, self.spp, seed)
        return image[..., 3:6]


def noise_row(bench: Bench, a: np.ndarray, b: np.ndarray, where: np.ndarray) -> tuple[float, ...]:
    """(noise, speckle share, mean correction), relative to the radiance, over ``where``."""
    noise = np.abs(a - b)[where].mean(axis=-1) / np.sqrt(2.0)
    radiance = bench.main[where].mean(axis=-1)
    mean = radiance.mean()
    return (
        float(np.sqrt(np.mean(noise**2)) / mean),
        float(np.mean(noise > SPECKLE * radiance)),
        float(a[where].mean() / mean),
    )


def smoothing_bias(bench: Bench, bias_spp: int) -> dict[str, dict[int, float]]:
    """The rms bias of smoothing, per region and radius, over the region's mean radiance."""
    from seahaze.render.segment_smooth import segments, smooth_within_segments

    renderer = bench.renderer(0.5, 0.5)
    share = bias_spp / bench.spp
    a, b = (bench.correction(renderer, share, 0, seed) for seed in (11, 12))
    geo = bench.session.pixels
    labels = segments(geo.instance, geo.distance_m)
    out: dict[str, dict[int, float]] = {}
    for radius in (2, 4, 6, 8):
        da = smooth_within_segments(a, labels, radius) - a
        db = smooth_within_segments(b, labels, radius) - b
        for name, where in bench.regions.items():
            square = float(np.mean((da * db)[where]))
            mean = bench.main[where].mean()
            out.setdefault(name, {})[radius] = np.sqrt(max(square, 0.0)) / mean
    return out


def main() -> None:
    from seahaze.render import physical

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--res", default="1280x720")
    parser.add_argument("--spp", type=int, default=42)
    parser.add_argument("--vis", type=float, default=4000.0)
    parser.add_argument("--bias-spp", type=int, default=169)
    args = parser.parse_args()
    res = tuple(int(v) for v in args.res.split("x"))
    bench = Bench(res, args.spp, args.vis)
    crop = crop_of(bench.session)
    in_crop = np.zeros_like(bench.regions["sky"])
    in_crop[crop] = True
    open_haze = ~bench.regions["vessel"]
    rows, tiles = [], [("without the pass", bench.main)]
    for label, pass_spp, near, aim, radius in SETTINGS:
        share = pass_spp / args.spp
        renderer = bench.renderer(near, aim)
        bench.correction(renderer, share, radius, 3)  # compile
        start = time.perf_counter()
        a = bench.correction(renderer, share, radius, 1)
        seconds = time.perf_counter() - start
        b = bench.correction(renderer, share, radius, 2)
        spp = physical.vessel_light_spp(args.spp)
        whole = noise_row(bench, a, b, open_haze)
        near_ferry = noise_row(bench, a, b, open_haze & in_crop)
        rows.append((label, share, near, aim, radius, spp, seconds, whole, near_ferry))
        tiles.append((f"{label} ({spp} spp)", bench.main + a))
        print(rows[-1], flush=True)
    bias = smoothing_bias(bench, args.bias_spp)
    print(bias, flush=True)
    write_figure(tiles, crop, bench.session)
    write_section(rows, bias, res, args)


def write_figure(
    tiles: list[tuple[str, np.ndarray]], crop: tuple[slice, slice], session: Any
) -> None:
    """The crop of every tile at 100 %, two per row, at the first tile's auto exposure."""
    from PIL import Image, ImageDraw

    from seahaze import imaging

    geo = session.pixels
    exposure = imaging.auto_exposure(tiles[0][1], geo.distance_m, geo.elevation_deg())
    h = crop[0].stop - crop[0].start
    w = crop[1].stop - crop[1].start
    per_row = 2
    n_rows = (len(tiles) + per_row - 1) // per_row
    canvas = Image.new("RGB", (per_row * w + 4, n_rows * (h + 14)), "white")
    draw = ImageDraw.Draw(canvas)
    for i, (label, image) in enumerate(tiles):
        x, y = (i % per_row) * (w + 4), (i // per_row) * (h + 14)
        pixels = imaging.to_srgb8(np.maximum(image[crop], 0.0), exposure)
        canvas.paste(Image.fromarray(pixels), (x, y + 14))
        draw.text((x + 2, y + 1), label, fill="black")
    FIGURE.parent.mkdir(parents=True, exist_ok=True)
    canvas.save(FIGURE)


def write_section(
    rows: list[tuple], bias: dict[str, dict[int, float]], res: tuple[int, int], args: Any
) -> None:
    """The section "The vessel-light pass's noise" of docs/benchmarks.md."""
    pct = lambda v: f"{100 * v:.2f} %"  # noqa: E731
    lines = [
        "## The vessel-light pass's noise (scripts/bench_vessel_light.py)",
        "",
        f"Machine: {platform.machine()}, {len(os.sched_getaffinity(0))} vCPU (shared). Default "
        f"scene at {res[0]}×{res[1]}, main pass {args.spp} spp, one level (V = {args.vis:g} m), "
        "the pass's correction alone from two sampler seeds. Over the pixels that are not "
        "vessels, in the whole image and around the passenger ferry: one image's noise (rms, "
        f"over the mean radiance) and the share of pixels whose noise passes {100 * SPECKLE:g} % "
        "of their radiance (a dot at 100 % zoom); the pass's time (warm).",
        "",
        "| probes | spp | near | aimed | smoothing (px) | pass (s) | noise, whole | speckle, "
        "whole | noise, ferry | speckle, ferry | mean correction, ferry |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for label, _share, near, aim, radius, spp, seconds, whole, ferry in rows:
        lines.append(
            f"| {label} | {spp} | {near:g} | {aim:g} | {radius} | {seconds:.1f} | "
            f"{pct(whole[0])} | {pct(whole[1])} | {pct(ferry[0])} | {pct(ferry[1])} | "
            f"{100 * ferry[2]:+.2f} % |"
        )
    lines += [
        "",
        f"Bias of the smoothing (rms over the region, of the region's mean radiance; from two "
        f"unsmoothed {args.bias_spp}-spp renders, see the script):",
        "",
        "| region | " + " | ".join(f"radius {r} px" for r in bias["sky"]) + " |",
        "|---|" + "---|" * len(bias["sky"]),
    ]
    for name, by_radius in bias.items():
        lines.append(f"| {name} | " + " | ".join(pct(v) for v in by_radius.values()) + " |")
    lines += [
        "",
        "![the sky around the passenger ferry at 100 % zoom, without the pass and with it per "
        f"setting](images/{FIGURE.name})",
    ]
    replace_section("vessel-light-noise", "\n".join(lines), "scripts/bench_vessel_light.py")


if __name__ == "__main__":
    main()
