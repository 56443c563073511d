"""Render the gallery of vessel classes: docs/images/vessel_gallery.png.

Every class of the vessel library at 200, 800 and 2000 m from the default scene's camera
(``scenes/default.yaml``: 15 m up, 60° field of view, 1280×720), broadside, clean, in the
``physical`` mode, each shown as a crop at 100 % around its box: what a detector sees of it in
the dataset. One scene per class holds the three (at bearings −12°, 0° and +12°, so that none
hides another). Deterministic: fixed seeds, the same pixels on the same machine and Mitsuba
variant.

Usage: python scripts/make_vessel_gallery.py [--spp 16] [--crop 320x160] [--out PNG]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from make_nonuniform_gallery import labelled, save_sheet

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "images" / "vessel_gallery.png"
SCENES = (((200.0, 0.0),), ((800.0, -10.0), (2000.0, 10.0)))
"""Per class, the scenes rendered: (distance in m, bearing in degrees) of each vessel."""
HEADING_DEG = 90.0
"""Broadside to the camera (the camera looks along +x at heading 0)."""


def where_it_is(spec, position_m: list[float]) -> tuple[float, float]:
    """The pixel a vessel's position (m, world) projects to in ``spec``'s camera."""
    from seahaze.world import frame_camera

    u, v, _ = frame_camera(spec).project(np.asarray([position_m], float))
    return float(u[0]), float(v[0])


def tile_of(image: np.ndarray, box, width: int, height: int) -> tuple[np.ndarray, int]:
    """A ``width × height`` tile of ``image`` around ``box``: a crop at 100 % centred on it, or
    where the box (with a margin) does not fit, the box's surroundings scaled down by the
    smallest whole factor that fits; returns the tile and that factor (1: 100 %)."""
    from PIL import Image

    cx, cy = 0.5 * (box.x0 + box.x1), 0.5 * (box.y0 + box.y1)
    factor = max(
        1, int(np.ceil(max(1.1 * (box.x1 - box.x0) / width, 1.1 * (box.y1 - box.y0) / height)))
    )
    w, h = width * factor, height * factor
    rows, columns = image.shape[:2]
    w, h = min(w, columns), min(h, rows)
    x0 = int(np.clip(round(cx - w / 2), 0, columns - w))
    y0 = int(np.clip(round(cy - h / 2), 0, rows - h))
    crop = image[y0 : y0 + h, x0 : x0 + w]
    if factor == 1:
        return crop, 1
    scaled = Image.fromarray(crop).resize((width, height), Image.Resampling.LANCZOS)
    return np.asarray(scaled), factor


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spp", type=int, default=16)
    parser.add_argument("--crop", default="320x160", help="width x height of each tile")
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args()
    from seahaze import imaging
    from seahaze.render.engine import render_scene
    from seahaze.sceneio import load_scene
    from seahaze.spec import with_changes, with_overrides
    from seahaze.vessels.library import VESSEL_CLASSES

    crop_w, crop_h = (int(v) for v in args.crop.lower().split("x"))
    base, _ = load_scene(ROOT / "scenes" / "default.yaml")
    base = with_overrides(base, spp=args.spp, levels=[4000.0])  # one level: the least work
    tiles = []
    for name in VESSEL_CLASSES:
        for vessels in SCENES:
            placed = [
                {"class": name, "distance_m": d, "bearing_deg": b, "heading_deg": HEADING_DEG}
                for d, b in vessels
            ]
            spec = with_changes(base, {"vessels": {"placed": placed}})
            start = time.perf_counter()
            scene = render_scene(spec, name)
            print(f"{name} {vessels}: {time.perf_counter() - start:.0f} s", flush=True)
            image = imaging.to_srgb8(scene.clean, scene.exposure)
            by_vessel = {box.vessel: box for box in scene.boxes}
            for index, (distance, _) in enumerate(vessels):
                label = f"{name.replace('_', ' ')}, {distance:g} m"
                box = by_vessel.get(index)
                if box is None:  # smaller than the labels' least box: show where it is
                    u, v = where_it_is(spec, scene.meta["vessels"][index]["position_m"])
                    box = SimpleNamespace(x0=u, x1=u, y0=v, y1=v)
                    label += ", no box (too small)"
                else:
                    label += f", {box.y1 - box.y0:.0f} px"
                tile, factor = tile_of(image, box, crop_w, crop_h)
                tiles.append(
                    labelled(tile, label + (", 100 %" if factor == 1 else f", 1/{factor}"))
                )
    save_sheet(tiles, sum(len(vessels) for vessels in SCENES), args.out)


if __name__ == "__main__":
    main()
