"""Render a sloop's sails against the sun: docs/images/sail_gallery.png.

The sailboat of the vessel library, 12 m, 150 m from a camera 6 m up (20° field of view,
480×270), broadside to it, under a sun 20° high at four azimuths: in front of the camera
(behind the sails), 60° and 120° round, and behind the camera (on the sails). Clean, in the
``physical`` mode, each at its own exposure (as a camera would take it), shown as a crop at
100 % around the boat. Sailcloth passes :data:`seahaze.vessels.materials.SAILCLOTH_TRANSMITTANCE`
of its light through, so the backlit sails glow where opaque ones stood dark (docs/vessels.md).
Deterministic: fixed seeds, the same pixels on the same machine and Mitsuba variant.

Usage: python scripts/make_sail_gallery.py [--spp 64] [--out PNG]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from make_nonuniform_gallery import labelled, save_sheet
from make_vessel_gallery import tile_of

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "images" / "sail_gallery.png"
SUN_AZIMUTHS_DEG = (0.0, 60.0, 120.0, 180.0)
"""Sun azimuths (the camera looks along azimuth 0): from behind the sails to behind the camera."""
SCENE = """\
name: sails
camera: {height_m: 6, fov_deg: 20, pitch_deg: -0.5, heading_deg: 0, resolution: [480, 270]}
sun: {elevation_deg: 20, azimuth_deg: 0}
sea: {quality: medium, seed: 3, wind_speed: 6, direction_deg: 30}
vessels:
  placed:
    - {class: sailboat, distance_m: 150, bearing_deg: 0, heading_deg: 100, length_m: 12}
haze: {levels: [4000]}
render: {mode: physical, spp: 64, seed: 1}
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spp", type=int, default=64)
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args()
    from seahaze import imaging
    from seahaze.render.engine import render_scene
    from seahaze.sceneio import parse_scene_text
    from seahaze.spec import with_changes, with_overrides

    base = with_overrides(parse_scene_text(SCENE, "sails.yaml"), spp=args.spp)
    scenes = []
    for azimuth in SUN_AZIMUTHS_DEG:
        spec = with_changes(base, {"sun": {"elevation_deg": 20.0, "azimuth_deg": azimuth}})
        start = time.perf_counter()
        scenes.append((azimuth, render_scene(spec, "sails")))
        print(f"sun at {azimuth:g}°: {time.perf_counter() - start:.0f} s", flush=True)
    tiles = []
    for azimuth, scene in scenes:
        image = imaging.to_srgb8(scene.clean, scene.exposure)
        tile, _ = tile_of(image, scene.boxes[0], 240, 200)
        where = {0.0: "behind the sails", 180.0: "on the sails"}.get(azimuth, f"{azimuth:g}° round")
        tiles.append(labelled(tile, f"sun {where}"))
    save_sheet(tiles, len(tiles), args.out)


if __name__ == "__main__":
    main()
