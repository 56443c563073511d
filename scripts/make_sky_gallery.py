"""Render the gallery of skies: docs/images/sky_gallery.png.

The default scene (``scenes/default.yaml``) under five skies: clear with the sun at 28° (the
scene as written), clear with a low sun at 5° (dawn or dusk light), broken cloud
(``sky.model: broken``, ``scenes/broken_cloud.yaml``'s sky), overcast (``sky.model:
overcast``, ``scenes/overcast.yaml``'s sky) and twilight (``sky.model: twilight``, the sun 3°
below the horizon ahead and to the right, ``scenes/twilight.yaml``'s). Each row holds the
clean image and the levels 2000 m and 500 m, rendered in the ``physical`` mode through
:func:`seahaze.render.engine.render_scene` and shown at the scene's own exposure, as the
dataset's PNGs are. Deterministic: fixed seeds, the same pixels on the same machine and Mitsuba
variant.

Usage: python scripts/make_sky_gallery.py [--res 480x270] [--spp 16] [--out PNG]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from make_nonuniform_gallery import labelled, save_sheet

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "images" / "sky_gallery.png"
LEVELS_M = (2000.0, 500.0)
SKIES = {
    "clear, sun at 28°": {},
    "clear, sun at 5°": {"sun": {"elevation_deg": 5.0}},
    "broken cloud, 5 oktas": {
        "sky": {"model": "broken", "clouds": {"oktas": 5, "base_height_m": 900}}
    },
    "overcast": {"sky": {"model": "overcast"}},
    "twilight, sun 3° below": {
        "sun": {"elevation_deg": -3.0, "azimuth_deg": -25.0},
        "sky": {"model": "twilight"},
    },
}
"""Each row's changes to the default scene."""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--res", default="480x270", help="width x height of each tile")
    parser.add_argument("--spp", type=int, default=16)
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args()
    from seahaze import imaging
    from seahaze.render.engine import render_scene
    from seahaze.sceneio import load_scene
    from seahaze.spec import with_changes, with_overrides

    width, height = (int(v) for v in args.res.lower().split("x"))
    base, _ = load_scene(ROOT / "scenes" / "default.yaml")
    base = with_overrides(base, resolution=(width, height), spp=args.spp, levels=list(LEVELS_M))
    tiles = []
    for name, changes in SKIES.items():
        start = time.perf_counter()
        scene = render_scene(with_changes(base, changes), "sky")
        print(f"{name}: rendered in {time.perf_counter() - start:.0f} s", flush=True)
        tiles.append(labelled(imaging.to_srgb8(scene.clean, scene.exposure), f"{name}: clean"))
        for level in scene.levels:
            image = imaging.to_srgb8(level.radiance, scene.exposure)
            tiles.append(labelled(image, f"{name}: {level.visibility_m:g} m"))
    save_sheet(tiles, 1 + len(LEVELS_M), args.out)


if __name__ == "__main__":
    main()
