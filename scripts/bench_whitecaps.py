"""Benchmark the whitecap coverage the rendered images show against the coverage law.

Whitecap coverage ``W`` is measured on photographs (Monahan & O'Muircheartaigh 1980, whose law
``W = 3.84e-6·U10^3.41`` this checks) and on video (Callaghan & White 2009, "Automated
processing of sea surface images for the determination of whitecap coverage", J. Atmos. Oceanic
Technol. 26, 383-394) as a brightness-threshold fraction of the sea's area: a pixel is whitecap
where it is brighter than the surrounding water by a threshold, and the whitecap pixels' share
of the imaged sea area is ``W``. This script measures rendered images the same way:

* **Water reference.** The water's brightness changes with the viewing angle (Fresnel
  reflection of a sky that brightens toward the horizon), so the threshold is set against the
  water at the same range: the median luminance of the sea pixels of the same image row
  (whitecaps cover a few per cent, so the median is water).
* **Threshold.** A pixel is whitecap where its luminance exceeds :data:`THRESHOLD_RATIO` (2.5)
  times that median. The 2.0 and 3.5 columns show how much the figure depends on it.
* **What the threshold means.** Koepke's (1984) effective reflectance 0.22 is fresh foam (0.55)
  decaying exponentially until it no longer counts as whitecap, ``(1 - e^-T)/T = 0.4``,
  ``T = 2.23``: the faintest counted whitecap reflects ``0.55·e^-2.23 = 0.059``
  (:data:`~seahaze.ocean.whitecaps.COUNTED_FOAM_REFLECTANCE`). Which foam reflectance the
  luminance threshold asks for depends on how bright the water is against a white sea, so every
  view is rendered twice more (calibration, not part of the photograph): with a white
  Lambertian sea (all foam, reflectance 1: luminance ``D``) and with black foam (reflectance 0:
  ``(1 - f)·water``). A pixel's foam albedo is then ``f·R = (L - L_black)/D``, and the
  threshold's foam reflectance is ``2.5·water/D`` (area-weighted mean over the band). The
  column "foam ≥ 0.059" is the share of the band whose rendered foam albedo reaches Koepke's
  faintest counted whitecap: the coverage a photograph would show with its threshold there.
* **Area, not pixels.** The law is a fraction of the sea's area. A pixel's area on the sea is
  ``Ω·d²/sin(α)`` (solid angle, distance, depression angle), which grows like ``d³``: weighted
  over the whole image the horizon's pixels, each a mixture of whitecaps and water that no
  threshold can split, would decide the figure. Photographic methods count whitecaps only
  where a pixel is smaller than a whitecap, so the measurement is restricted to the near-field
  band where a pixel's extent along the range, ``d·δ/sin(α)`` (``δ`` the pixel angle), is at
  most :data:`FOOTPRINT_M`, and inside that band each pixel counts by its world area.

The scene is ``tests/data/open_sea.yaml`` (no vessels, camera 20 m up looking 12° down, the sun
behind the camera) at each wind, viewed at six headings (:data:`HEADINGS_DEG`), the sun turning
with the camera, on two wave seeds (:data:`SEA_SEEDS`). The clean image only (``physical``
mode's clean pass). Results go to the "whitecaps" section of docs/benchmarks.md; ``--save``
keeps them as JSON and ``--before`` adds a saved run as the "before" columns.

Usage: python scripts/bench_whitecaps.py [--winds 8,12,15,20] [--res 640x360] [--spp 16]
       [--save FILE.json] [--before FILE.json] [--images DIR] [--no-doc]
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "tests" / "data" / "open_sea.yaml"
sys.path.insert(0, str(ROOT / "scripts"))

from bench_passes import replace_section  # noqa: E402

LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
"""Rec. 709 luminance weights of linear RGB."""
THRESHOLD_RATIO = 2.5
"""A pixel is whitecap where its luminance exceeds this many times the local water's (module
docstring)."""
SENSITIVITY_RATIOS = (2.0, 3.5)
"""Other thresholds reported, to show how much the coverage depends on the threshold."""
FOOTPRINT_M = 1.0
"""Largest extent (m) of a pixel along the range on the sea for it to count: whitecaps are
metres across from 8 m/s, so a pixel of at most a metre resolves them."""
SEA_SEEDS = (11, 12)
"""Wave seeds: two independent seas per wind."""
HEADINGS_DEG = (0.0, 60.0, 120.0, 180.0, 240.0, 300.0)
"""Camera headings (deg): six views of the periodic sea, each over a near-field band of
5000-7000 m² at 640×360, so that the whitecaps of the dominant waves (peak wavelengths of
60-200 m at 8-20 m/s) are sampled over several wavelengths squared."""


def pixel_world_area(
    directions: np.ndarray, distance_m: np.ndarray, forward: np.ndarray, width: int, fov_deg: float
) -> np.ndarray:
    """Area (m²) on a flat sea of every pixel of a perspective camera: its solid angle
    ``(2·tan(fov/2)/width)²·cos³θ`` (``θ`` off the optical axis ``forward``) times ``d²``,
    over ``sin(α)`` (``α`` the ray's depression angle)."""
    side = 2.0 * math.tan(math.radians(fov_deg) / 2.0) / width
    cos_axis = np.clip(directions @ forward, 1e-6, 1.0)
    sin_depression = np.maximum(-directions[..., 2], 1e-6)
    return side**2 * cos_axis**3 * distance_m**2 / sin_depression


def range_footprint_m(directions: np.ndarray, distance_m: np.ndarray, pixel_rad: float):
    """Extent (m) of every pixel along the range on a flat sea: ``d·δ/sin(α)``."""
    return distance_m * pixel_rad / np.maximum(-directions[..., 2], 1e-6)


def row_water_luminance(luminance: np.ndarray, sea: np.ndarray) -> np.ndarray:
    """(H, 1) median luminance of each row's sea pixels: the water at that range (NaN where a
    row has no sea)."""
    masked = np.where(sea, luminance, np.nan)
    with np.errstate(all="ignore"):
        import warnings

        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            return np.nanmedian(masked, axis=1, keepdims=True)


def measure_coverage(
    luminance: np.ndarray,
    sea: np.ndarray,
    area_m2: np.ndarray,
    footprint_m: np.ndarray,
    ratio: float = THRESHOLD_RATIO,
    max_footprint_m: float = FOOTPRINT_M,
) -> tuple[float, float]:
    """Whitecap coverage (fraction of the sea area) of an image by the photographic method
    (module docstring), and the sea area (m²) it was measured over."""
    water = row_water_luminance(luminance, sea)
    band = sea & (footprint_m <= max_footprint_m) & np.isfinite(water)
    whitecap = band & (luminance > ratio * water)
    total = float(np.sum(area_m2[band]))
    return float(np.sum(area_m2[whitecap])) / max(total, 1e-12), total


def global_median_fraction(luminance: np.ndarray, sea: np.ndarray, ratio: float = 2.5) -> float:
    """Share of all sea pixels brighter than ``ratio`` times the sea's median (per pixel, not
    per area: the first measurement of issue 32, for comparison)."""
    values = luminance[sea]
    return float(np.mean(values > ratio * np.median(values)))


def open_sea_spec(
    wind: float, heading_deg: float, res: tuple[int, int], spp: int, sea_seed: int = SEA_SEEDS[0]
):
    """The benchmark scene at wind ``wind`` (m/s), camera heading ``heading_deg`` and wave seed
    ``sea_seed``."""
    import yaml

    from seahaze.spec import SceneSpec

    data = yaml.safe_load(SCENE.read_text())
    data["sea"]["wind_speed"] = wind
    data["camera"]["heading_deg"] = heading_deg
    data["sea"]["seed"] = sea_seed
    # The sun keeps its place relative to the view (behind the camera: no glitter in view).
    data["sun"]["azimuth_deg"] = (data["sun"]["azimuth_deg"] + heading_deg) % 360.0
    data["camera"]["resolution"] = list(res)
    data["render"]["spp"] = spp
    return SceneSpec.model_validate(data)


def calibration_luminances(session, spp: int) -> tuple[np.ndarray, np.ndarray]:
    """Luminance of the view with a white Lambertian sea (every vertex foam of reflectance 1)
    and with black foam (reflectance 0), at the same samples as the image."""
    from dataclasses import replace

    from seahaze.render.engine import open_session
    from seahaze.world import SEA_FOAM, SEA_FOAM_REFLECTANCE

    geometry = session.geometry
    attributes = geometry.sea.attributes
    if SEA_FOAM not in attributes:  # no foam at all: foam albedo 0 everywhere
        attributes = {
            **attributes,
            SEA_FOAM: np.zeros(len(geometry.sea.vertices), np.float32),
            SEA_FOAM_REFLECTANCE: np.zeros(len(geometry.sea.vertices), np.float32),
        }
    one = np.ones_like(attributes[SEA_FOAM])
    out = []
    for changes in ({SEA_FOAM: one, SEA_FOAM_REFLECTANCE: one}, {SEA_FOAM_REFLECTANCE: 0 * one}):
        sea = replace(geometry.sea, attributes={**attributes, **changes})
        variant = open_session(session.spec, geometry=replace(geometry, sea=sea))
        out.append(variant.render_clean(spp) @ LUMINANCE)
    return out[0], out[1]


def render_view(
    wind: float, heading_deg: float, res: tuple[int, int], spp: int, sea_seed: int
) -> dict:
    """Render one view's clean image and measure it; returns the figures and the image."""
    from seahaze.ocean.whitecaps import COUNTED_FOAM_REFLECTANCE
    from seahaze.render.engine import open_session

    spec = open_sea_spec(wind, heading_deg, res, spp, sea_seed)
    start = time.perf_counter()
    session = open_session(spec)
    rgb = session.render_clean()
    seconds = time.perf_counter() - start
    geo, camera = session.pixels, session.camera
    luminance = rgb @ LUMINANCE
    sea = np.isfinite(geo.distance_m) & (geo.instance == -1)
    forward = camera.basis()[0]
    directions = geo.directions.astype(float)
    distance = np.where(sea, geo.distance_m, 0.0).astype(float)
    area = pixel_world_area(directions, distance, forward, res[0], spec.camera.fov_deg)
    pixel_rad = 2.0 * math.tan(math.radians(spec.camera.fov_deg) / 2.0) / res[0]
    footprint = range_footprint_m(directions, distance, pixel_rad)
    result = {"seconds": seconds, "global": global_median_fraction(luminance, sea)}
    for ratio in (THRESHOLD_RATIO, *SENSITIVITY_RATIOS):
        coverage, band_area = measure_coverage(luminance, sea, area, footprint, ratio)
        result[f"coverage_{ratio:g}"] = coverage
        result["band_area_m2"] = band_area
    white, black = calibration_luminances(session, spp)
    water = row_water_luminance(luminance, sea)
    band = sea & (footprint <= FOOTPRINT_M) & np.isfinite(water)
    foam_albedo = (luminance - black) / np.maximum(white, 1e-12)
    counted = band & (foam_albedo >= COUNTED_FOAM_REFLECTANCE)
    result["coverage_koepke"] = float(np.sum(area[counted]) / np.sum(area[band]))
    threshold = THRESHOLD_RATIO * np.broadcast_to(water, luminance.shape) / np.maximum(white, 1e-12)
    result["threshold_reflectance"] = float(np.sum((area * threshold)[band]) / np.sum(area[band]))
    result["rgb"] = rgb
    return result


def measure_wind(wind: float, res: tuple[int, int], spp: int, images: Path | None) -> dict:
    """Coverage at ``wind`` over :data:`HEADINGS_DEG` and :data:`SEA_SEEDS`, each view weighted
    by its band's area; ``spread``: the lowest and highest seed's coverage (the sampling's
    scatter)."""
    from seahaze.ocean import whitecap_coverage

    views = []
    for seed, heading in itertools.product(SEA_SEEDS, HEADINGS_DEG):
        view = render_view(wind, heading, res, spp, seed)
        rgb = view.pop("rgb")
        if images is not None:
            save_png(rgb, images / f"whitecaps_u{wind:g}_s{seed}_h{heading:g}.png")
        view["seed"] = seed
        views.append(view)
    area = sum(v["band_area_m2"] for v in views)
    row: dict[str, float] = {"wind": wind, "law": float(whitecap_coverage(wind))}
    for key in [k for k in views[0] if k.startswith(("coverage_", "threshold_"))]:
        row[key] = sum(v[key] * v["band_area_m2"] for v in views) / area
    row["global"] = float(np.mean([v["global"] for v in views]))
    row["band_area_m2"] = area
    key = f"coverage_{THRESHOLD_RATIO:g}"
    per_seed = [
        sum(v[key] * v["band_area_m2"] for v in views if v["seed"] == seed)
        / sum(v["band_area_m2"] for v in views if v["seed"] == seed)
        for seed in SEA_SEEDS
    ]
    row["spread"] = [min(per_seed), max(per_seed)]
    row["seconds"] = sum(v["seconds"] for v in views)
    return row


def save_png(rgb: np.ndarray, path: Path) -> None:
    """Write a linear RGB image as an sRGB PNG (exposure 1, clipped), for looking at."""
    from PIL import Image

    path.parent.mkdir(parents=True, exist_ok=True)
    c = np.clip(rgb, 0.0, 1.0)
    srgb = np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055)
    Image.fromarray((srgb * 255.0 + 0.5).astype(np.uint8)).save(path)


def _table(rows: list[dict], before: dict[float, dict]) -> list[str]:
    key = f"coverage_{THRESHOLD_RATIO:g}"
    low, high = SENSITIVITY_RATIOS
    head = "| U10 (m/s) | W (law) |"
    rule = "|---|---|"
    if before:
        head += " before: rendered | ratio |"
        rule += "---|---|"
    head += (
        f" rendered | ratio | seeds' range | at {low:g}× | at {high:g}× |"
        " sea pixels > 2.5× median | threshold as foam reflectance |"
    )
    rule += "---|---|---|---|---|---|---|"
    calibrated = any("coverage_koepke" in r for r in before.values())
    if calibrated:
        head += " before: foam ≥ 0.059 | ratio |"
        rule += "---|---|"
    head += " foam ≥ 0.059 | ratio |"
    rule += "---|---|"
    lines = [head, rule]
    for row in rows:
        law = row["law"]
        line = f"| {row['wind']:g} | {100 * law:.2f} % |"
        old = before.get(row["wind"])
        if before and old is not None:
            line += f" {100 * old[key]:.2f} % | {old[key] / law:.2f} |"
        elif before:
            line += " | |"
        line += (
            f" {100 * row[key]:.2f} % | {row[key] / law:.2f} |"
            f" {row['spread'][0] / law:.2f}–{row['spread'][1] / law:.2f} |"
            f" {100 * row[f'coverage_{low:g}']:.2f} % | {100 * row[f'coverage_{high:g}']:.2f} % |"
            f" {100 * row['global']:.2f} % |"
        )
        line += f" {row['threshold_reflectance']:.3f} |" if "coverage_koepke" in row else " |"
        if calibrated:
            if old is not None and "coverage_koepke" in old:
                koepke = old["coverage_koepke"]
                line += f" {100 * koepke:.2f} % | {koepke / law:.2f} |"
            else:
                line += " | |"
        if "coverage_koepke" in row:
            koepke = row["coverage_koepke"]
            line += f" {100 * koepke:.2f} % | {koepke / law:.2f} |"
        else:
            line += " | |"
        lines.append(line)
    return lines


def write_section(rows: list[dict], before: dict[float, dict], res: tuple[int, int], spp: int):
    """Write the coverage table into docs/benchmarks.md's "whitecaps" section."""
    area = ", ".join(f"{r['band_area_m2']:.0f}" for r in rows)
    lines = [
        f"## Whitecap coverage on the images (scripts/bench_whitecaps.py, {res[0]}×{res[1]}, "
        f"{spp} spp)",
        "",
        f"Machine: {platform.machine()}, {len(os.sched_getaffinity(0))} vCPU; "
        f"headings {', '.join(f'{h:g}°' for h in HEADINGS_DEG)}; whitecap: luminance above "
        f"{THRESHOLD_RATIO:g}× the row's water median, pixels at most {FOOTPRINT_M:g} m along "
        f"the range, weighted by area (sea area measured per wind: {area} m²); foam ≥ 0.059: "
        "the rendered foam albedo, from a white-sea and a black-foam render of each view, at "
        "least Koepke's faintest counted whitecap.",
        "",
        *_table(rows, before),
    ]
    replace_section("whitecaps", "\n".join(lines), "scripts/bench_whitecaps.py")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--winds", default="8,12,15,20")
    parser.add_argument("--res", default="640x360")
    parser.add_argument("--spp", type=int, default=16)
    parser.add_argument("--save", type=Path, help="keep the measured rows as JSON")
    parser.add_argument("--before", type=Path, help="a saved run, shown as the before columns")
    parser.add_argument("--images", type=Path, help="write every view's clean PNG here")
    parser.add_argument("--no-doc", action="store_true", help="do not write docs/benchmarks.md")
    parser.add_argument("--load", type=Path, help="write the doc from a saved run, no render")
    args = parser.parse_args()
    res = tuple(int(x) for x in args.res.lower().split("x"))
    assert len(res) == 2
    rows = json.loads(args.load.read_text()) if args.load else []
    for wind in [] if args.load else (float(w) for w in args.winds.split(",")):
        row = measure_wind(wind, res, args.spp, args.images)
        print(
            f"U = {wind:g} m/s: law {100 * row['law']:.2f} %, rendered "
            f"{100 * row[f'coverage_{THRESHOLD_RATIO:g}']:.2f} % "
            f"(×{row[f'coverage_{THRESHOLD_RATIO:g}'] / row['law']:.2f}), global "
            f"{100 * row['global']:.2f} %, band {row['band_area_m2']:.0f} m², "
            f"{row['seconds']:.0f} s",
            flush=True,
        )
        rows.append(row)
    if args.save:
        args.save.write_text(json.dumps(rows, indent=1))
    before = {}
    if args.before:
        before = {r["wind"]: r for r in json.loads(args.before.read_text())}
    if not args.no_doc:
        write_section(rows, before, res, args.spp)
        print("wrote docs/benchmarks.md")
    return 0


if __name__ == "__main__":
    sys.exit(main())
