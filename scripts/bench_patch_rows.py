"""How close is ``physical`` in the small parts of the sea that a whole-image reference cannot
resolve?

In drifting patches at 300 m the sea seen through less haze than the level's mean (``thin``:
the pixel's ray holds less than 1/1.5 of it) and through more (``dense``: more than 1.5×) are
a few dozen pixels of the benchmark scene (80×45) near the horizon; a whole-image ``volpath``
reference of 8 batches of 1024 spp (``scripts/bench_patch_diffuse.py``) knows their means to
about 3 %. This script renders the reference over the rows they lie in alone (the film
cropped to them, so a batch costs that share of a whole one), batch after batch (sampler
seeds past those of ``compare_components.py``'s references; kept in ``--cache``, so a run
that is stopped goes on where it stopped), and compares ``physical``'s renders there (as
``bench_patch_diffuse.py`` renders them: each with its own seed and so its own traced box).
Each region's standard error is the spread of its mean between the batches (which holds for
the heavy-tailed sunlit paths of dense haze, where per-pixel errors would not).

Usage: python scripts/bench_patch_rows.py [--v 300] [--batches 48] [--seeds 16]
       [--patches 400,3,60,30] [--rows 20:27] [--cache DIR] [--doc]
"""

from __future__ import annotations

import argparse
import hashlib
import platform
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_modes import LEVELS, SCENE, region_masks
from bench_passes import replace_section
from bench_patch_diffuse import patches_of
from compare_components import physical_renderer

ROOT = Path(__file__).resolve().parents[1]
SEED_OFFSET = 300000
"""The reference batches' seeds begin here (``compare_components.py``'s at 200000)."""


def cropped_sensor(loaded, rows: tuple[int, int]):
    """The scene's camera with its film cropped to image rows ``[rows[0], rows[1])`` (whole
    width): the same pose, field of view, clipping and box filter, its rays starting in the
    haze box's medium as the scene's own sensor's do."""
    import mitsuba as mi

    sensor = loaded.scene.sensors()[0]
    width, height = (int(x) for x in sensor.film().size())
    params = mi.traverse(sensor)
    matrix = np.array(sensor.world_transform().matrix, dtype=np.float64).reshape(4, 4)
    media = [s.interior_medium() for s in loaded.scene.shapes() if s.interior_medium() is not None]
    film = {
        "type": "hdrfilm",
        "width": width,
        "height": height,
        "crop_offset_x": 0,
        "crop_offset_y": rows[0],
        "crop_width": width,
        "crop_height": rows[1] - rows[0],
        "rfilter": {"type": "box"},
        "pixel_format": "rgb",
    }
    return mi.load_dict(
        {
            "type": "perspective",
            "fov": float(params["x_fov"][0]),
            "fov_axis": "x",
            "near_clip": float(params["near_clip"]),
            "far_clip": float(params["far_clip"]),
            "to_world": mi.ScalarTransform4f(matrix.tolist()),
            "sampler": {"type": "independent"},
            "film": film,
            "medium": media[0],
        }
    )


def row_batches(base, v: float, sigma, rows: tuple[int, int], batches: int, cache: Path):
    """(batches, rows, width) ``volpath`` luminance of image rows ``rows`` at level ``v``
    (extinction ``sigma``), one image per batch of 1024 spp; the batches done so far are kept
    in ``cache`` after each one."""
    from seahaze.imaging import luminance
    from seahaze.render.engine import open_session
    from seahaze.render.wavefront import render_film
    from seahaze.seeds import RenderPass, render_seed
    from seahaze.spec import with_overrides

    session = open_session(with_overrides(base, mode="reference", levels=sorted({*LEVELS, v})))
    loaded = session.loaded
    key = f"{loaded.spec.model_dump_json()}|{sigma}|rows {rows[0]}:{rows[1]}"
    path = cache / f"rows-{hashlib.blake2b(key.encode(), digest_size=12).hexdigest()}.npz"
    runs = list(np.load(path)["runs"]) if path.exists() else []
    if len(runs) >= batches:
        return np.array(runs[:batches])
    haze = base.haze
    loaded.set_haze(sigma, haze.albedo, haze.g)
    sensor = cropped_sensor(loaded, rows)
    seed0 = loaded.spec.render.seed
    cache.mkdir(parents=True, exist_ok=True)
    while len(runs) < batches:
        loaded.bind_paint()
        seed = render_seed(seed0, RenderPass.CONVERGED_REFERENCE, 7, SEED_OFFSET + len(runs))
        image = render_film(loaded.scene, sensor, loaded.scene.integrator(), 1024, seed)
        runs.append(luminance(np.maximum(image, 0.0)))
        np.savez(path, runs=np.array(runs))
        print(f"reference batch {len(runs)}/{batches}", flush=True)
    return np.array(runs)


def compare(base, v: float, seeds: int, batches: int, rows, cache: Path) -> dict:
    """Per small region (the sea's thin and dense parts): its pixels, the reference's mean over
    the rows and its standard error, ``physical``'s error against it (the mean of ``seeds``
    renders) and one render's scatter."""
    from seahaze.imaging import luminance
    from seahaze.render.pixel_density import pixel_density_ratio
    from seahaze.visibility import channel_extinction

    haze = base.haze
    sigma = channel_extinction(v, haze.threshold, haze.extinction_spectrum)
    session, renderer = physical_renderer(base, v)
    renders = np.array(
        [
            luminance(renderer.render([sigma], haze.albedo, haze.g, 256, seed).levels[0])
            for seed in range(1, seeds + 1)
        ]
    )
    sea = region_masks(session.pixels.distance_m, session.pixels.instance)["sea"]
    ratio = pixel_density_ratio(renderer.field, renderer.geometry)
    masks = {"sea thin": sea & (ratio < 1 / 1.5), "sea dense": sea & (ratio > 1.5)}
    masks = {name: mask for name, mask in masks.items() if mask.any()}
    found = np.flatnonzero(np.any(list(masks.values()), axis=(0, 2)))
    rows = rows or (int(found.min()), int(found.max()) + 1)
    if found.min() < rows[0] or found.max() >= rows[1]:
        raise SystemExit(f"--rows {rows[0]}:{rows[1]} miss rows {found.min()}..{found.max()}")
    reference = row_batches(base, v, sigma, rows, batches, cache)
    results = {}
    for name, mask in masks.items():
        inside = mask[rows[0] : rows[1]]
        per_batch = np.array([b[inside].mean() for b in reference])
        mean = per_batch.mean()
        one = [r[mask].mean() / mean - 1.0 for r in renders]
        results[name] = {
            "pixels": int(mask.sum()),
            "error": float(renders.mean(0)[mask].mean() / mean - 1.0),
            "se": float(per_batch.std(ddof=1) / np.sqrt(len(per_batch)) / mean),
            "one": float(np.std(one, ddof=1)),
        }
    return {"rows": rows, "batches": len(reference), "seeds": seeds, "regions": results}


def table(v: float, patches: str, result: dict) -> str:
    """The result as docs/benchmarks.md's table, its caption saying how it was made."""
    r0, r1 = result["rows"]
    lines = [
        "## physical in the sea's small parts, against a reference of their rows "
        "(scripts/bench_patch_rows.py)",
        "",
        f"Machine: {platform.machine()}, `llvm_ad_rgb`. Benchmark scene (80×45), patches "
        f"{patches} (CORRELATION m, ANISOTROPY, VERTICAL m, density RATIO), V = {v:g} m. "
        f"`volpath`: {result['batches']} batches of 1024 spp over image rows {r0}–{r1 - 1} "
        f"alone; `physical`: {result['seeds']} renders of 256 spp. Per cent: the error of the "
        "renders' mean ± the reference's standard error (the spread of the region's mean "
        "between its batches), then (in brackets) one render's 1σ scatter.",
        "",
        "| region | pixels | physical against the reference |",
        "|---|---|---|",
    ]
    for name, r in result["regions"].items():
        lines.append(
            f"| {name} | {r['pixels']} | {100 * r['error']:+.2f} ± {100 * r['se']:.2f} "
            f"({100 * r['one']:.2f}) |"
        )
    return "\n".join(lines)


def main() -> None:
    from seahaze.sceneio import load_scene
    from seahaze.spec import with_changes

    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--v", type=float, default=300.0, help="the level's visibility (m)")
    parser.add_argument("--batches", type=int, default=48, help="reference batches of 1024 spp")
    parser.add_argument("--seeds", type=int, default=16, help="physical renders (seeds 1 … N)")
    parser.add_argument(
        "--patches",
        default="400,3,60,30",
        help="haze.patches as CORRELATION,ANISOTROPY,VERTICAL,RATIO",
    )
    parser.add_argument(
        "--rows", default=None, help="image rows A:B to render (default: those the regions hold)"
    )
    parser.add_argument(
        "--cache", type=Path, default=ROOT / "out" / "compare-cache", help="reference batches"
    )
    parser.add_argument("--doc", action="store_true", help="write the table into docs/")
    args = parser.parse_args()
    rows = tuple(int(x) for x in args.rows.split(":")) if args.rows else None
    base, _ = load_scene(SCENE)
    base = with_changes(base, {"haze": {"patches": patches_of(args.patches)}})
    result = compare(base, args.v, args.seeds, args.batches, rows, args.cache)
    text = table(args.v, args.patches, result)
    print(text)
    if args.doc:
        replace_section("patch-rows", text, "scripts/bench_patch_rows.py")


if __name__ == "__main__":
    main()
