"""Render the sea-state gallery of docs/sea-states.md: Beaufort 1–8, clean and at 1000 m.

One scene per force, the same everywhere but the sea: a camera 20 m up looking 2.5° down, the
sun at 30° on the left behind the camera, a trawler under way at 350 m and a container ship at
1.8 km. The sea is the Beaufort preset of :func:`seahaze.ocean.ocean_params_for_beaufort` (the
nominal wind, and the fetch at which the spectrum's Hs matches the WMO table where a wind sea
can), each force with its own wave seed. Rendered through the public engine API
(:func:`seahaze.render.engine.render_scene`) in the ``physical`` mode, so the script follows
whatever that mode becomes. Deterministic: fixed seeds, same bytes on the same machine and
Mitsuba variant.

Writes ``docs/images/gallery_bft<N>.png`` (clean | 1000 m, side by side) and prints the table
rows of docs/sea-states.md.

Usage: python scripts/make_sea_gallery.py [--forces 1-8] [--res 640x360] [--spp 32] [--out DIR]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "images"
VISIBILITY_M = 1000.0


def gallery_spec(force: int, width: int, height: int, spp: int):
    """The scene of Beaufort ``force`` (see the module docstring)."""
    from seahaze import ocean
    from seahaze.spec import SceneSpec

    preset = ocean.ocean_params_for_beaufort(force)
    return SceneSpec.model_validate(
        {
            "name": f"gallery_bft{force}",
            "camera": {
                "height_m": 20.0,
                "fov_deg": 60.0,
                "pitch_deg": -2.5,
                "heading_deg": 0.0,
                "resolution": [width, height],
            },
            "sun": {"elevation_deg": 30.0, "azimuth_deg": 140.0},
            "sky": {"turbidity": 3.0},
            "sea": {
                "model": "fft",
                "spectrum": "jonswap",
                "beaufort": force,
                "fetch_km": preset.fetch_km,
                "direction_deg": 20.0,
                "seed": 100 + force,  # one sea per force (one seed would scale one pattern)
                "quality": "medium",
            },
            "vessels": {
                "placed": [
                    {
                        "class": "fishing_boat",
                        "distance_m": 350.0,
                        "bearing_deg": -12.0,
                        "heading_deg": 215.0,
                        "length_m": 22.0,
                        "speed_kn": 8.0,
                    },
                    {
                        "class": "container_ship",
                        "distance_m": 1800.0,
                        "bearing_deg": 11.0,
                        "heading_deg": 170.0,
                        "length_m": 240.0,
                        "speed_kn": 18.0,
                    },
                ]
            },
            "haze": {"levels": [VISIBILITY_M], "albedo": 0.998, "g": 0.75, "top_m": 300.0},
            "render": {"mode": "physical", "spp": spp, "seed": 16},
        }
    )


def render_force(force: int, width: int, height: int, spp: int, out: Path = OUT) -> dict:
    """Render one force, write its PNG and return the numbers of its table row."""
    from PIL import Image

    from seahaze import imaging, ocean
    from seahaze.render.engine import render_scene

    spec = gallery_spec(force, width, height, spp)
    start = time.perf_counter()
    scene = render_scene(spec, spec.name or "gallery")
    seconds = time.perf_counter() - start
    clean = imaging.to_srgb8(scene.clean, scene.exposure)
    hazy = imaging.to_srgb8(scene.levels[0].radiance, scene.exposure)
    out.mkdir(parents=True, exist_ok=True)
    path = out / f"gallery_bft{force}.png"
    Image.fromarray(np.concatenate([clean, hazy], axis=1)).save(path, optimize=True)
    preset = ocean.ocean_params_for_beaufort(force)
    surface = ocean.make_surface(preset)
    return {
        "force": force,
        "wind": preset.wind_speed,
        "fetch": preset.fetch_km,
        "hs": surface.significant_wave_height_m,
        "coverage": ocean.whitecap_coverage(preset.wind_speed),
        "alpha": scene.meta["sea"]["roughness_used"],
        "seconds": seconds,
        "path": path,
    }


def _forces(text: str) -> list[int]:
    if "-" in text:
        lo, hi = (int(v) for v in text.split("-"))
        return list(range(lo, hi + 1))
    return [int(v) for v in text.split(",")]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--forces", default="1-8", help="Beaufort forces, e.g. 1-8 or 2,5,8")
    parser.add_argument("--res", default="640x360", help="width x height of each half")
    parser.add_argument("--spp", type=int, default=32)
    parser.add_argument("--out", type=Path, default=OUT, help="folder of the PNGs")
    args = parser.parse_args()
    width, height = (int(v) for v in args.res.lower().split("x"))
    print("| force | wind (m/s) | fetch (km) | Hs (m) | whitecaps W | far alpha | time (s) |")
    print("|---|---|---|---|---|---|---|")
    for force in _forces(args.forces):
        row = render_force(force, width, height, args.spp, args.out)
        print(
            f"| {row['force']} | {row['wind']:.2f} | {row['fetch']:.0f} | {row['hs']:.2f} | "
            f"{100 * row['coverage']:.2f} % | {row['alpha']:.3f} | {row['seconds']:.0f} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
