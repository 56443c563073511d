"""Banding of the 8-bit PNGs, and what dithering them costs (issue 34).

Renders the default scene (clean and V = 300, 1000, 4000 m; or reads a dataset folder rendered
with EXRs and denoising off, ``--dataset``), quantises each image's float radiance, exposed as
the dataset's PNGs are, in four ways and compares each with the float code values (the sRGB
encoding × 255, float64):

- ``nearest``: the nearest code (seahaze before the dither, ``render.dither: off``);
- ``triangular``: seahaze's dither, ``imaging.to_srgb8`` with the image's dither seed;
- ``uniform``: random rounding, uniform noise of one code before truncation (the alternative);
- ``bayer``: an ordered 8×8 Bayer threshold matrix, the same in every image.

Per image and way it reports, over the rows that are sky across the whole width: the distinct
codes per column (green, median) and the longest run of one code down a column (median, max);
the banding, as the rms and largest mean error of 2×32-pixel blocks (all channels); how even the
grain is, as the error's standard deviation in ten bins of the float's position between codes
(lowest..highest); and over the whole image: the rms error, PSNR and SSIM against the float
codes (SSIM by scikit-image, of the ``denoise`` extra), the bias of the dark channel (15-pixel
minimum of the channels' minimum, the prior of dark-channel dehazing) in the sky and the sea,
the PNG's size and the time to quantise and write it (fileio.write_png, best of three). A
16-bit PNG, the other option the issue named, is measured once per image: its size (a minimal
encoder: zlib level 6, Sub filter; neither Pillow nor imageio writes 16-bit RGB), what Pillow
reads from it, and the size of the image's EXR (float32, ZIP) beside it. It writes the "dither"
section of docs/benchmarks.md and a figure: the green channel of a crop of the V = 4000 m sky,
stretched to the crop's float range, float | nearest | triangular | uniform at 100 %
(docs/images/dither_crop.png).

Usage: python scripts/bench_dither.py [--res 1280x720] [--spp 16] [--dataset DIR]
"""

from __future__ import annotations

import argparse
import io
import json
import os
import platform
import struct
import sys
import tempfile
import time
import zlib
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_passes import replace_section
from seahaze import fileio, imaging
from seahaze.seeds import dither_seed

ROOT = Path(__file__).resolve().parents[1]
FIGURE = ROOT / "docs" / "images" / "dither_crop.png"
LEVELS = ("clean", "v0300", "v1000", "v4000")
BAYER8 = np.array(
    [
        [0, 32, 8, 40, 2, 34, 10, 42],
        [48, 16, 56, 24, 50, 18, 58, 26],
        [12, 44, 4, 36, 14, 46, 6, 38],
        [60, 28, 52, 20, 62, 30, 54, 22],
        [3, 35, 11, 43, 1, 33, 9, 41],
        [51, 19, 59, 27, 49, 17, 57, 25],
        [15, 47, 7, 39, 13, 45, 5, 37],
        [63, 31, 55, 23, 61, 29, 53, 21],
    ]
)
"""The ordered dither matrix of Bayer (1973), thresholds (i + 0.5)/64 of a code."""
DARK_PATCH = 15
BLOCK = (2, 32)


def code_positions(linear: np.ndarray) -> np.ndarray:
    """The sRGB encoding × 255 of exposed linear values (clipped to [0, 1]), float64."""
    v = np.clip(np.nan_to_num(linear.astype(np.float64), nan=0.0), 0.0, 1.0)
    return np.where(v <= 0.0031308, v * 12.92, 1.055 * v ** (1 / 2.4) - 0.055) * 255.0


def quantisers(scene: str, seed: int) -> dict[str, Callable[[np.ndarray, float, str], np.ndarray]]:
    """Each way of quantising ``radiance × exposure`` of image ``level``, as uint8 codes."""
    rng = np.random.default_rng(seed)

    def uniform(radiance: np.ndarray, exposure: float, level: str) -> np.ndarray:
        x = code_positions(radiance * np.float32(exposure))
        return np.clip(np.floor(x + rng.random(x.shape)), 0, 255).astype(np.uint8)

    def bayer(radiance: np.ndarray, exposure: float, level: str) -> np.ndarray:
        x = code_positions(radiance * np.float32(exposure))
        h, w = x.shape[:2]
        t = (np.tile(BAYER8, (h // 8 + 1, w // 8 + 1))[:h, :w] + 0.5) / 64.0
        return np.clip(np.floor(x + t[..., None]), 0, 255).astype(np.uint8)

    return {
        "nearest": lambda r, e, level: imaging.to_srgb8(r, e),
        "triangular": lambda r, e, level: imaging.to_srgb8(r, e, dither_seed(seed, scene, level)),
        "uniform": uniform,
        "bayer": bayer,
    }


def longest_run(column: np.ndarray) -> int:
    """The longest run of one value in a 1-D array."""
    changes = np.flatnonzero(np.diff(column.astype(np.int32)) != 0)
    edges = np.concatenate([[-1], changes, [len(column) - 1]])
    return int(np.diff(edges).max())


def ssim(image: np.ndarray, reference: np.ndarray) -> float:
    """SSIM of two (H, W, 3) images in code units, as scripts/bench_gt_noise.py computes it
    (scikit-image's defaults: 7×7 window, data range 255)."""
    from skimage.metrics import structural_similarity

    return float(
        structural_similarity(image.astype(np.float64), reference, channel_axis=2, data_range=255.0)
    )


def dark_channel(image: np.ndarray) -> np.ndarray:
    """He et al.'s dark channel: the minimum over a patch of the channels' minimum."""
    from scipy import ndimage

    return ndimage.minimum_filter(image.min(axis=2), size=DARK_PATCH)


def png16_bytes(codes16: np.ndarray) -> bytes:
    """A 16-bit RGB PNG of (H, W, 3) uint16 values: zlib level 6, Sub filter on every row."""
    h, w, _ = codes16.shape
    raw = codes16.astype(">u2").view(np.uint8).reshape(h, w * 6).astype(np.int16)
    raw[:, 6:] -= raw[:, :-6].copy()
    rows = np.empty((h, 1 + w * 6), dtype=np.uint8)
    rows[:, 0] = 1
    rows[:, 1:] = raw % 256

    def chunk(kind: bytes, data: bytes) -> bytes:
        return (
            struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
        )

    header = struct.pack(">IIBBBBB", w, h, 16, 2, 0, 0, 0)
    return (
        fileio.PNG_SIGNATURE
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(rows.tobytes(), 6))
        + chunk(b"IEND", b"")
    )


def measure_image(
    radiance: np.ndarray,
    exposure: float,
    level: str,
    sky_rows: np.ndarray,
    sea_rows: np.ndarray,
    ways: dict[str, Callable[[np.ndarray, float, str], np.ndarray]],
    tmp: Path,
) -> list[dict[str, Any]]:
    """Every way's figures for one image."""
    x = code_positions(radiance * np.float32(exposure))
    frac = (x - np.floor(x))[sky_rows].ravel()
    bins = np.minimum((frac * 10).astype(int), 9)
    dark_float = dark_channel(x)
    rows = []
    for way, quantise in ways.items():
        y = quantise(radiance, exposure, level)
        times = []
        for _ in range(3):
            start = time.perf_counter()
            fileio.write_png(tmp / f"{level}_{way}.png", quantise(radiance, exposure, level))
            times.append(time.perf_counter() - start)
        err = y - x
        sky = y[sky_rows]
        distinct = [len(np.unique(sky[:, c, 1])) for c in range(sky.shape[1])]
        h, w = (len(sky_rows) // BLOCK[0]) * BLOCK[0], (x.shape[1] // BLOCK[1]) * BLOCK[1]
        blocks = err[sky_rows][:h, :w].reshape(h // BLOCK[0], BLOCK[0], w // BLOCK[1], -1)
        block_means = blocks.mean(axis=(1, 3))
        sky_err = err[sky_rows].ravel()
        grain = [sky_err[bins == b].std() for b in range(10) if np.any(bins == b)]
        runs = [longest_run(sky[:, c, 1]) for c in range(sky.shape[1])]
        dark = dark_channel(y.astype(np.float64)) - dark_float
        mse = float(np.mean(err**2))
        rows.append(
            {
                "level": level,
                "way": way,
                "distinct": float(np.median(distinct)),
                "run_median": float(np.median(runs)),
                "run_max": int(max(runs)),
                "band_rms": float(np.sqrt(np.mean(block_means**2))),
                "band_max": float(np.abs(block_means).max()),
                "grain": (float(min(grain)), float(max(grain))),
                "rms": float(np.sqrt(mse)),
                "psnr": 10 * np.log10(255.0**2 / mse),
                "ssim": ssim(y, x),
                "dark_sky": float(dark[sky_rows].mean()),
                "dark_sea": float(dark[sea_rows].mean()),
                "kib": (tmp / f"{level}_{way}.png").stat().st_size / 1024,
                # The comparison ways run in float64 here, not as seahaze would: no time.
                "ms": 1000 * min(times) if way in ("nearest", "triangular") else None,
            }
        )
    return rows


def measure_png16(radiance: np.ndarray, exposure: float, level: str) -> dict[str, Any]:
    """A 16-bit PNG of the image: size, encode time, and what Pillow reads from it."""
    from PIL import Image

    x = code_positions(radiance * np.float32(exposure))
    codes16 = np.round(x * 257.0).astype(np.uint16)
    start = time.perf_counter()
    data = png16_bytes(codes16)
    seconds = time.perf_counter() - start
    with Image.open(io.BytesIO(data)) as image:
        mode, read = image.mode, np.asarray(image)
    err = read.astype(np.float64) - x
    return {
        "level": level,
        "kib": len(data) / 1024,
        "ms": 1000 * seconds,
        "pil_mode": mode,
        "pil_dtype": str(read.dtype),
        "pil_is_high_byte": bool(np.array_equal(read, (codes16 >> 8).astype(np.uint8))),
        "pil_rms": float(np.sqrt(np.mean(err**2))),
    }


def render_dataset(out: Path, res: tuple[int, int], spp: int) -> None:
    """The default scene, clean and three levels, with EXRs, into ``out``."""
    from seahaze.cli import main as seahaze_main

    args = ["render", str(ROOT / "scenes" / "default.yaml"), "--vis", "300,1000,4000"]
    args += ["--res", f"{res[0]}x{res[1]}", "--spp", str(spp), "--split", "none"]
    args += ["--out", str(out), "--quiet"]
    if seahaze_main(args) != 0:
        raise SystemExit("the render failed")


def crop_figure(radiance: np.ndarray, exposure: float, ways: dict, sky_rows: np.ndarray) -> None:
    """Green channel of a sky crop of V = 4000 m, stretched to the float's range, side by side."""
    from PIL import Image

    h, w = min(len(sky_rows), 290), 190
    c0 = radiance.shape[1] // 2 - w // 2 + radiance.shape[1] // 8
    rows = sky_rows[:h]
    x = code_positions(radiance * np.float32(exposure))[rows, c0 : c0 + w, 1]
    lo, hi = float(x.min()), float(x.max())
    tiles = [x]
    for way in ("nearest", "triangular", "uniform"):
        tiles.append(ways[way](radiance, exposure, "v4000")[rows, c0 : c0 + w, 1])
    gap = np.full((h, 6), 255, dtype=np.uint8)
    parts = []
    for tile in tiles:
        stretched = np.clip((tile - lo) * 255.0 / max(hi - lo, 1e-6), 0, 255)
        parts += [stretched.astype(np.uint8), gap]
    FIGURE.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(np.concatenate(parts[:-1], axis=1)).save(FIGURE, optimize=True)
    print(f"wrote {FIGURE} (stretch {lo:.1f}..{hi:.1f} codes, ×{255 / (hi - lo):.1f})")


def write_section(rows: list[dict], png16: list[dict], context: dict[str, Any]) -> None:
    """The "dither" section of docs/benchmarks.md."""
    lines = [
        f"## Banding and dither, default scene, {context['res']}, {context['spp']} spp "
        "(scripts/bench_dither.py)",
        "",
        f"Machine: {platform.machine()}, {len(os.sched_getaffinity(0))} vCPU. Sky: the "
        f"{context['sky_rows']} rows that are sky across the whole width; sea: the "
        f"{context['sea_rows']} rows below the horizon band. Render noise of the float sky "
        f"(rms of the green code minus its 5×5 mean): {context['sky_noise']}. SSIM: "
        "scikit-image's defaults, as in the ground-truth noise sections. Times only for "
        "seahaze's own code (the comparison ways are computed in float64 by the script).",
        "",
        "| image | way | sky: codes per column | sky: longest run, median / max (rows) | "
        "sky: 2×32 block mean error, rms / max | sky: error std by position between codes | "
        "rms error | PSNR (dB) | SSIM | dark channel bias, sky / sea | PNG (KiB) | "
        "quantise + write (ms) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['level']} | {r['way']} | {r['distinct']:.0f} | {r['run_median']:.0f} / "
            f"{r['run_max']} | {r['band_rms']:.3f} / {r['band_max']:.3f} | "
            f"{r['grain'][0]:.2f}..{r['grain'][1]:.2f} | {r['rms']:.3f} | {r['psnr']:.2f} | "
            f"{r['ssim']:.5f} | {r['dark_sky']:+.2f} / {r['dark_sea']:+.2f} | {r['kib']:.0f} | "
            f"{'—' if r['ms'] is None else format(r['ms'], '.0f')} |"
        )
    lines += [
        "",
        "Errors in codes (1/255), against the float code values. A 16-bit PNG of the same "
        "images (the nearest of 65,535 steps):",
        "",
        "| image | 16-bit PNG (KiB) | encode (ms) | the image's EXR (KiB) | Pillow reads | "
        "Pillow's values are the high bytes | rms error of what Pillow reads |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in png16:
        lines.append(
            f"| {r['level']} | {r['kib']:.0f} | {r['ms']:.0f} | {r['exr_kib']:.0f} | "
            f"mode {r['pil_mode']}, "
            f"{r['pil_dtype']} | {'yes' if r['pil_is_high_byte'] else 'no'} | "
            f"{r['pil_rms']:.3f} |"
        )
    replace_section("dither", "\n".join(lines), "scripts/bench_dither.py")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--res", default="1280x720", help="render size (default 1280x720)")
    parser.add_argument("--spp", type=int, default=16, help="samples per pixel (default 16)")
    parser.add_argument("--dataset", type=Path, help="read this dataset instead of rendering")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as scratch:
        tmp = Path(scratch)
        root = args.dataset
        if root is None:
            root = tmp / "dataset"
            width, height = (int(v) for v in args.res.split("x"))
            render_dataset(root, (width, height), args.spp)
        manifest = json.loads((root / "dataset.json").read_text())
        scene = sorted(manifest["scenes"])[0]
        seed = int(manifest["scenes"][scene]["seed"])
        meta = json.loads((root / "meta" / f"{scene}.json").read_text())
        exposure = float(meta["exposure"])
        distance = fileio.read_exr(root / "depth" / f"{scene}.exr")["Z"]
        sky = np.isinf(distance)
        sky_rows = np.flatnonzero(sky.all(axis=1))
        ground = np.flatnonzero((~sky).all(axis=1))
        sea_rows = ground[ground > sky_rows.max()]
        ways = quantisers(scene, seed)
        rows: list[dict] = []
        png16: list[dict] = []
        noise = []
        for level in LEVELS:
            radiance = fileio.read_exr(root / "exr" / level / f"{scene}.exr")["RGB"]
            rows += measure_image(radiance, exposure, level, sky_rows, sea_rows, ways, tmp)
            exr_kib = (root / "exr" / level / f"{scene}.exr").stat().st_size / 1024
            png16.append(measure_png16(radiance, exposure, level) | {"exr_kib": exr_kib})
            from scipy import ndimage

            g = code_positions(radiance * np.float32(exposure))[sky_rows][..., 1]
            noise.append(f"{level} {np.std(g - ndimage.uniform_filter(g, 5)):.3f}")
            if level == "v4000":
                crop_figure(radiance, exposure, ways, sky_rows)
            print(f"{level} done", flush=True)
        height, width = sky.shape
        context = {
            "res": f"{width}×{height}",
            "spp": meta["render"]["spp"],
            "sky_rows": len(sky_rows),
            "sea_rows": len(sea_rows),
            "sky_noise": ", ".join(noise) + " codes",
        }
    write_section(rows, png16, context)
    for r in rows:
        print(r)


if __name__ == "__main__":
    main()
