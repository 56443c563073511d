"""Measure the ``reference`` mode's exact medium for haze that varies across the sea.

Since 2026-11-28 the reference path-traces the field itself (``seahaze.render.field_medium``)
instead of a grid of it. Three questions, on the scene of scripts/bench_nonuniform.py (a 12 m
camera over the sea, four vessels) with its patches (correlation 250 m, anisotropy 3,
vertical 50 m, density ratio 20) and its bank (edge at 1 km, bearing 20°, edge 60 m, near
ratio 0.15):

(1) Is the kernel's field the field? Its density at 200,000 random points of the render's
    haze box against ``NonUniformHaze.density_at`` (numpy, float64), and its majorant against
    the densest of them.
(2) Is the reference unbiased? With the haze's albedo 0 nothing scatters, so a sky pixel's
    level over its clean value is the transmittance of the pixel's rays. Against the exact
    transmittance averaged over 4 × 4 rays per pixel (``NonUniformHaze.ray_path_length`` to
    where the ray leaves the box): per band of elevation, the means and z = (reference −
    exact) / its binomial standard error, at 300, 1000 and 4000 m. With the grid the same
    check showed the grid's error (docs/benchmarks.md, the grid section).
(3) What does it cost? The reference at 160×90, 64 spp, levels 300, 1000 and 4000 m (warm:
    the second of two runs), with the exact field, with the former grid (32 × 384 × 384 cells,
    rebuilt here as it was) and for uniform haze.

Deterministic (fixed seeds); only times vary. Writes the "field_medium" section of
docs/benchmarks.md with ``--doc``.

Usage: python scripts/bench_field_medium.py [--quick] [--doc]
"""

from __future__ import annotations

import argparse
import itertools
import math
import os
import platform
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_nonuniform import (
    BANDS_DEG,
    BANK,
    GRID_SHAPE,
    PATCHY,
    Rays,
    rays_in_box,
    scene_spec,
    session_rays,
    sigma_of,
    whole_sky_pixels,
)
from bench_passes import replace_section

SCRIPT = "scripts/bench_field_medium.py"
LEVELS = [300.0, 1000.0, 4000.0]
SUBPIXELS = 4
MIN_T = 1e-3
"""Bands whose exact transmittance is below this are left out of (2)."""


# -- (1) the kernel's density ----------------------------------------------------------------------
def density_row(name: str, haze: dict[str, Any], points: int = 200_000) -> dict[str, Any]:
    """(1) for one haze: the kernel's density against numpy's over the render's box."""
    import mitsuba as mi

    from seahaze.render.engine import open_session
    from seahaze.render.field_medium import FieldMedium

    spec = scene_spec(haze, width=64, height=36, levels=LEVELS, mode="reference")
    session = open_session(spec)
    rays, medium = session_rays(session), session.loaded.medium
    rng = np.random.default_rng(0)
    p = rng.uniform(rays.box_min, rays.box_max, (points, 3))
    box = FieldMedium(medium, rays.box_min, rays.box_max)
    got = np.asarray(box.density(mi.Point3f(*(mi.Float(p[:, k]) for k in range(3)))), float)
    want = medium.density_at(p[:, 0], p[:, 1], p[:, 2])
    relative = np.abs(got - want) / np.maximum(want, 1e-12)
    return {
        "scene": name,
        "half_width": float(0.5 * (rays.box_max[0] - rays.box_min[0])),
        "max_rel": float(relative.max()),
        "median_rel": float(np.median(relative)),
        "densest": float(want.max()),
        "peak": box.peak,
        "mean": float(want.mean()),
    }


# -- (2) transmittance against the exact field -----------------------------------------------------
def transmittance_rows(name: str, haze: dict[str, Any], res: tuple[int, int], spp: int) -> list:
    """(2) for one haze: per level and band of elevation, the reference's sky transmittance
    (albedo 0, level over clean) against the exact pixel-area mean."""
    from seahaze.render.engine import render_scene
    from seahaze.scene_medium import scene_haze_medium
    from seahaze.world import frame_camera

    spec = scene_spec(
        haze, width=res[0], height=res[1], levels=LEVELS, mode="reference", spp=spp, albedo=0.0
    )
    scene = render_scene(spec, "field_medium")
    camera = frame_camera(spec, None)
    medium = scene_haze_medium(spec, camera)
    geo = scene.geometry
    rays = rays_in_box(
        geo, (camera.x_m, camera.y_m), scene.meta["haze"]["box_half_width_m"], medium
    )
    whole = whole_sky_pixels(rays.sky.reshape(geo.distance_m.shape)).reshape(-1)[rays.sky]
    lengths = _subpixel_lengths(camera, rays, medium)
    elevation = geo.elevation_deg().reshape(-1)[rays.sky]
    clean = scene.clean[..., 1].reshape(-1)[rays.sky].astype(np.float64)
    rows = []
    for level in scene.levels:
        exact = np.exp(-sigma_of(level.visibility_m) * lengths).mean(axis=1)
        ref = level.radiance[..., 1].reshape(-1)[rays.sky].astype(np.float64) / clean
        for lo, hi in itertools.pairwise(BANDS_DEG):
            band = (elevation >= lo) & (elevation < hi) & whole
            if not band.any() or exact[band].mean() < MIN_T:
                continue
            se = math.sqrt(np.sum(exact[band] * (1.0 - exact[band])) / spp) / band.sum()
            rows.append(
                {
                    "scene": name,
                    "level": level.visibility_m,
                    "band": f"{lo:g}–{hi:g}°",
                    "pixels": int(band.sum()),
                    "exact": float(exact[band].mean()),
                    "ref": float(ref[band].mean()),
                    "se": se,
                    "z": (float(ref[band].mean()) - float(exact[band].mean())) / se,
                    "tau_span": float(np.ptp(-np.log(np.maximum(exact[band], 1e-300)))),
                }
            )
    return rows


def _subpixel_lengths(camera: Any, rays: Rays, medium: Any) -> np.ndarray:
    """Exact reduced lengths (m) of SUBPIXELS² rays spread over each sky pixel (the film's box
    filter), to where each leaves the haze box: (sky pixels, SUBPIXELS²)."""
    v, u = np.mgrid[0 : camera.height, 0 : camera.width]
    sky = rays.sky
    offsets = (np.arange(SUBPIXELS) + 0.5) / SUBPIXELS
    out = []
    for oy in offsets:
        for ox in offsets:
            d = camera.ray_directions(u + ox, v + oy).reshape(-1, 3)[sky]
            sub = Rays(rays.origin, d, np.full(len(d), np.inf), rays.box_min, rays.box_max)
            side, vertical = sub.exits(rays.box_min, rays.box_max)
            out.append(medium.ray_path_length(rays.origin, d, np.minimum(side, vertical)))
    return np.stack(out, axis=-1)


# -- (3) cost -------------------------------------------------------------------------------------
def cost_row(name: str, haze: dict[str, Any], res: tuple[int, int], spp: int, grid: bool):
    """(3): the reference's warm time for the three levels (the second of two renders)."""
    from seahaze.render.engine import render_scene

    spec = scene_spec(haze, width=res[0], height=res[1], levels=LEVELS, mode="reference", spp=spp)
    restore = _use_grid() if grid else None
    try:
        times = []
        for _ in range(2):
            start = time.perf_counter()
            render_scene(spec, "field_medium_cost")
            times.append(time.perf_counter() - start)
    finally:
        if restore:
            restore()
    label = f"{name} ({'grid ' + str(GRID_SHAPE) if grid else 'exact field'})"
    return {"scene": label if haze else "uniform", "cold": times[0], "warm": times[1]}


def _use_grid():
    """Make NonUniformHaze give the reference its former grid medium; returns the undo."""
    import mitsuba as mi

    from seahaze.medium import grid_medium_dict
    from seahaze.nonuniform import NonUniformHaze

    saved = NonUniformHaze.mitsuba_medium, NonUniformHaze.mitsuba_level
    grids: dict[int, np.ndarray] = {}

    def medium(self, box_min, box_max):
        grids[id(self)] = self.density_grid_over(box_min, box_max, GRID_SHAPE)
        volume = mi.VolumeGrid(np.repeat(grids[id(self)][..., None], 3, axis=-1) * 0.0)
        return grid_medium_dict(volume, box_min, box_max, self.albedo, self.g)

    def level(self, sigma_rgb, albedo, g):
        data = grids[id(self)][..., None] * np.asarray(sigma_rgb, np.float32)
        return {
            "sigma_t.data": mi.TensorXf(data.astype(np.float32)),
            "albedo.value.value": albedo,
            "phase_function.g": g,
        }

    NonUniformHaze.mitsuba_medium, NonUniformHaze.mitsuba_level = medium, level

    def restore() -> None:
        NonUniformHaze.mitsuba_medium, NonUniformHaze.mitsuba_level = saved

    return restore


# -- the section ----------------------------------------------------------------------------------
def section(results: dict[str, Any]) -> list[str]:
    r2, r3 = results["transmittance"], results["cost"]
    lines = [
        f"## The reference's exact field: its density, its transmittance, its cost ({SCRIPT})",
        "",
        f"Machine: {platform.machine()}, {len(os.sched_getaffinity(0))} vCPU; variant "
        f"`{results['variant']}`. Scene of scripts/bench_nonuniform.py: patches (correlation "
        "250 m, anisotropy 3, vertical 50 m, density ratio 20) and bank (edge at 1000 m, "
        "bearing 20°, edge 60 m, near ratio 0.15).",
        "",
        "**(1) The kernel's density against numpy's** (200,000 random points of the render's "
        "haze box; relative error; the majorant is the field's bound).",
        "",
        "| scene | box half width (m) | max error | median error | densest point | majorant "
        "| majorant / mean |",
        "|---|---|---|---|---|---|---|",
    ]
    for row in results["density"]:
        lines.append(
            f"| {row['scene']} | {row['half_width']:.0f} | {row['max_rel']:.1e} | "
            f"{row['median_rel']:.1e} | {row['densest']:.3f} | {row['peak']:.3f} | "
            f"{row['peak'] / row['mean']:.2f} |"
        )
    lines += [
        "",
        f"**(2) Sky transmittance, reference (albedo 0, {r2['res'][0]}×{r2['res'][1]}, "
        f"{r2['spp']} spp) against the exact field** ({SUBPIXELS}×{SUBPIXELS} rays per pixel "
        "to the box's wall). z = (reference − exact) / the reference's binomial standard "
        "error; τ span the spread of the pixels' optical depths in the band.",
        "",
        "| scene | level (m) | band | pixels | T exact | T reference ± se | z | τ span |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for row in r2["rows"]:
        lines.append(
            f"| {row['scene']} | {row['level']:g} | {row['band']} | {row['pixels']} | "
            f"{row['exact']:.5f} | {row['ref']:.5f} ± {row['se']:.5f} | {row['z']:+.2f} | "
            f"{row['tau_span']:.2f} |"
        )
    zs = np.array([row["z"] for row in r2["rows"]])
    lines += [
        "",
        f"{len(zs)} bands: |z| at most {np.abs(zs).max():.2f}, mean z {zs.mean():+.2f}, "
        f"rms {math.sqrt(np.mean(zs**2)):.2f} (1 for an unbiased estimate).",
        "",
        f"**(3) Cost of the reference**, {r3['res'][0]}×{r3['res'][1]}, {r3['spp']} spp, "
        "levels 300, 1000 and 4000 m, whole render (sea, clean pass, levels); cold is the "
        "first render in the process, warm the second.",
        "",
        "| haze | cold (s) | warm (s) | warm / uniform |",
        "|---|---|---|---|",
    ]
    uniform = next(row["warm"] for row in r3["rows"] if row["scene"] == "uniform")
    for row in r3["rows"]:
        lines.append(
            f"| {row['scene']} | {row['cold']:.1f} | {row['warm']:.1f} | "
            f"{row['warm'] / uniform:.2f} |"
        )
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smaller sizes, fewer samples")
    parser.add_argument("--doc", action="store_true", help="write docs/benchmarks.md's section")
    args = parser.parse_args()
    from seahaze.render.variant import select_variant

    started = time.perf_counter()

    def say(text: str) -> None:
        print(f"[{time.perf_counter() - started:6.0f} s] {text}", flush=True)

    results: dict[str, Any] = {"variant": select_variant("auto")}
    results["density"] = [density_row("patchy", PATCHY), density_row("bank", BANK)]
    say("(1) done")
    res, spp = ((80, 45), 64) if args.quick else ((160, 90), 256)
    rows = []
    for name, haze in (("patchy", PATCHY), ("bank", BANK)):
        rows += transmittance_rows(name, haze, res, spp)
        say(f"(2) {name} done")
    results["transmittance"] = {"res": res, "spp": spp, "rows": rows}
    cost_res, cost_spp = ((80, 45), 16) if args.quick else ((160, 90), 64)
    cost = [cost_row("uniform", {}, cost_res, cost_spp, False)]
    for name, haze in (("patchy", PATCHY), ("bank", BANK)):
        cost.append(cost_row(name, haze, cost_res, cost_spp, False))
        cost.append(cost_row(name, haze, cost_res, cost_spp, True))
        say(f"(3) {name} done")
    results["cost"] = {"res": cost_res, "spp": cost_spp, "rows": cost}
    lines = section(results)
    print("\n".join(lines))
    if args.doc:
        replace_section("field_medium", "\n".join(lines), SCRIPT)


if __name__ == "__main__":
    main()
