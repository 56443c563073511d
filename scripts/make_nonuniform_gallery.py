"""Render the gallery of haze that varies across the sea: docs/images/nonuniform_gallery.png.

One scene, the benchmark scene of ``scripts/bench_nonuniform.py`` (a 12 m camera, sun behind on
the left, vessels at 250, 550, 1500 and 3000 m), whose haze section alone changes: uniform, a
fog layer (to 25 m, a quarter of its density above), patches (correlation 250 m, density ratio
20) and a bank (edge at 1 km, bearing 20° to the left, edge 60 m). Each at 500 m and 2000 m in
the ``asm`` mode, beside the effective visibility ``V_eff`` of its 2000 m level (log-scaled
grey from V/10, black, to 10 V, white; the sky's rays followed for 20 km), and the clean image
(the same for every haze). One exposure for every tile: the clean image's. Rendered through
:func:`seahaze.render.engine.render_scene`, so the gallery follows whatever the modes become.
Deterministic: fixed seeds, the same pixels on the same machine and Mitsuba variant.

Prints, per haze and level, the transmittance and effective visibility of each vessel (the
``transmission`` entries of its ``meta``) and the render's time.

Usage: python scripts/make_nonuniform_gallery.py [--res 640x360] [--spp 32] [--out PNG]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_nonuniform import HAZES, scene_spec

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "images" / "nonuniform_gallery.png"
LEVELS_M = (500.0, 2000.0)
ROWS = ("uniform", "fog layer", "patchy", "bank")
LABEL_PX = 22
"""Height of the band above each tile that holds its label."""
V_EFF_SPAN = 10.0
"""The V_eff map's grey runs from V / V_EFF_SPAN (black) to V · V_EFF_SPAN (white), log."""


def render(name: str, width: int, height: int, spp: int) -> Any:
    """The scene with haze ``name`` of :data:`bench_nonuniform.HAZES`, both levels, asm."""
    from seahaze.render.engine import render_scene

    spec = scene_spec(
        HAZES[name],
        width=width,
        height=height,
        levels=list(LEVELS_M),
        mode="asm",
        spp=spp,
        sea_quality="medium",
    )
    return render_scene(spec, name.replace(" ", "_"))


def v_eff_grey(v_eff: np.ndarray, visibility_m: float) -> np.ndarray:
    """(H, W, 3) uint8: log-scaled grey of ``v_eff`` (m), black at ``V / V_EFF_SPAN``, white at
    ``V · V_EFF_SPAN`` and beyond (``inf``: no haze on the ray)."""
    with np.errstate(divide="ignore"):
        t = np.log(np.asarray(v_eff, np.float64) / visibility_m) / np.log(V_EFF_SPAN)
    grey = np.clip(0.5 + 0.5 * np.nan_to_num(t, posinf=1.0), 0.0, 1.0)
    return np.repeat((255.0 * grey + 0.5).astype(np.uint8)[..., None], 3, axis=-1)


def legend(width: int, height: int) -> np.ndarray:
    """The V_eff maps' grey scale as a tile: a horizontal ramp with ticks every factor 10^0.5."""
    ramp = np.linspace(-1.0, 1.0, width)
    grey = (255.0 * (0.5 + 0.5 * ramp) + 0.5).astype(np.uint8)
    tile = np.full((height, width, 3), 255, np.uint8)
    band = slice(height // 2 - 20, height // 2 + 20)
    tile[band] = grey[None, :, None]
    return tile


def labelled(tile: np.ndarray, text: str) -> Any:
    """``tile`` (H, W, 3) uint8 under a white band holding ``text``."""
    from PIL import Image, ImageDraw, ImageFont

    h, w = tile.shape[:2]
    out = Image.new("RGB", (w, h + LABEL_PX), "white")
    out.paste(Image.fromarray(tile), (0, LABEL_PX))
    draw = ImageDraw.Draw(out)
    draw.text((6, 3), text, fill="black", font=ImageFont.load_default(size=15))
    return out


def legend_tile(width: int, height: int) -> Any:
    """The legend tile with its tick labels."""
    from PIL import ImageDraw, ImageFont

    image = labelled(legend(width, height), "V_eff / V, log grey (the maps' scale)")
    draw = ImageDraw.Draw(image)
    font = ImageFont.load_default(size=14)
    y = LABEL_PX + height // 2 + 26
    for value, text in ((0.1, "0.1"), (0.316, "0.32"), (1.0, "1"), (3.16, "3.2"), (10.0, "10")):
        x = int((0.5 + 0.5 * np.log10(value)) * (width - 1))
        draw.line([(x, y - 8), (x, y - 2)], fill="black")
        draw.text((min(max(x - 10, 2), width - 30), y), text, fill="black", font=font)
    return image


def save_sheet(tiles: list[Any], columns: int, out: Path) -> None:
    """Paste the labelled ``tiles`` (PIL images of one size) row by row, ``columns`` a row, on
    a white sheet and save it as the PNG ``out``."""
    from PIL import Image

    tile_w, tile_h = tiles[0].size
    rows = -(-len(tiles) // columns)
    sheet = Image.new("RGB", (columns * tile_w, rows * tile_h), "white")
    for i, tile in enumerate(tiles):
        sheet.paste(tile, ((i % columns) * tile_w, (i // columns) * tile_h))
    out.parent.mkdir(parents=True, exist_ok=True)
    sheet.save(out, optimize=True)
    print(f"wrote {out} ({sheet.size[0]}×{sheet.size[1]})")


def vessel_lines(name: str, scene: Any) -> list[str]:
    """Per level, each vessel's mean transmittance over its pixels and the effective
    visibility of the centre pixel's ray (``meta``)."""
    lines = []
    for level in scene.meta["levels"]:
        parts = []
        for vessel in scene.meta["vessels"]:
            entry = vessel["levels"][level["name"]]
            t = entry.get("transmittance_mean")
            shown = "not in view" if t is None else f"T {t:.3f}"
            parts.append(f"{vessel['class']} {vessel['distance_m']:.0f} m {shown}")
        centre = level["visibility_eff_centre_m"]
        lines.append(
            f"{name} {level['name']}: V_eff centre pixel {centre:.0f} m; " + ", ".join(parts)
        )
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--res", default="640x360", help="width x height of each tile")
    parser.add_argument("--spp", type=int, default=32)
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args()

    from seahaze import imaging

    width, height = (int(v) for v in args.res.lower().split("x"))
    scenes = {}
    for name in ROWS:
        start = time.perf_counter()
        scenes[name] = render(name, width, height, args.spp)
        print(f"{name}: rendered in {time.perf_counter() - start:.0f} s", flush=True)
        for line in vessel_lines(name, scenes[name]):
            print("  " + line, flush=True)
    first = scenes[ROWS[0]]
    exposure = first.exposure
    tiles = [
        labelled(imaging.to_srgb8(first.clean, exposure), "clean (the same for every haze)"),
        legend_tile(width, height),
        labelled(np.full((height, width, 3), 255, np.uint8), ""),
    ]
    for name in ROWS:
        scene = scenes[name]
        for level in scene.levels:
            text = f"{name}, {level.visibility_m:g} m (asm)"
            tiles.append(labelled(imaging.to_srgb8(level.radiance, exposure), text))
        last = scene.levels[-1]
        grey = v_eff_grey(last.transmission.visibility_eff_m, last.visibility_m)
        tiles.append(labelled(grey, f"{name}: V_eff at {last.visibility_m:g} m"))
    save_sheet(tiles, 3, args.out)


if __name__ == "__main__":
    main()
