"""How close is the ``physical`` mode in a fog bank, and how much does one render scatter?

``physical`` gives a bank the diffuse light of its own field (``render/bank_diffuse.py``: photons
traced through a strip across the bank's edge, each pixel's camera segment and later segments
scaled by their ratio to the tables' light). This script compares it per region with converged
``volpath`` references of the same bank (as ``scripts/compare_components.py`` does, whose
reference cache it shares): four renders of 256 spp, each with its own seed and so its own
traced bank, reported as the error of their mean and as the scatter of one render's region
error about it (their standard deviation: the bank's photon noise and the render's own). The
time is that of the bank's ratios alone (tracing the strip and summing the pixels' rays) for
the one level, with the photons the tables get at full size (2^20).

Usage: python scripts/bench_bank_diffuse.py [--cases 300,1000,4000]
       [--banks 900,0,80,0.2/600,35,150,0.35] [--cache DIR] [--doc]
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_modes import SCENE, region_masks
from bench_passes import replace_section
from compare_components import level_reference, physical_renderer, region_error

ROOT = Path(__file__).resolve().parents[1]
SEEDS = (1, 2, 3, 4)
"""The renders' seeds (compare_components.py's)."""
SPP = 256


def bank_of(text: str) -> dict:
    """``haze.bank`` from ``DISTANCE,BEARING,EDGE,NEAR``."""
    distance, bearing, edge, near = (float(x) for x in text.split(","))
    return {"distance_m": distance, "bearing_deg": bearing, "edge_m": edge, "near_ratio": near}


def measure(
    v: float,
    haze_changes: dict,
    cache: Path | None,
    batches: int,
    dense_thin: bool = False,
    company: tuple[float, ...] = (),
    seeds: tuple[int, ...] = SEEDS,
) -> dict:
    """Per region: the error of the renders' mean against the reference (``batches``
    of 1024 spp, compare_components.py's), the reference's standard error and the scatter of
    one render's error; and the ratios' time. ``haze_changes``: the benchmark scene's
    ``haze`` changes (a bank, patches); with
    ``dense_thin`` the sea, the sky and the vessels also where each pixel's ray holds more
    than 1.5× the level's mean haze and less than 1/1.5 of it (compare_components.py's).
    ``company``: other visibilities (m) rendered in the same pass, as a dataset's levels are
    (patches trace their field at some levels and interpolate the ones between); the
    results are level ``v``'s. ``seeds``: the renders' sampler seeds (each traces its own
    field), one render each. With ``dense_thin`` also ``largest hull``: the vessel with the
    most pixels."""
    from seahaze.imaging import luminance
    from seahaze.render.pixel_density import pixel_density_ratio
    from seahaze.sceneio import load_scene
    from seahaze.spec import with_changes
    from seahaze.visibility import channel_extinction

    base, _ = load_scene(SCENE)
    base = with_changes(base, {"haze": haze_changes})
    haze = base.haze
    sigma = channel_extinction(v, haze.threshold, haze.extinction_spectrum)
    _, _, (ref, ref_se) = level_reference(base, v, sigma, batches, cache)
    session, renderer = physical_renderer(base, v)
    visibilities = sorted({v, *company})
    sigmas = [channel_extinction(x, haze.threshold, haze.extinction_spectrum) for x in visibilities]
    green = np.array([float(s[1]) for s in sigmas])
    start = time.perf_counter()
    renderer.pixel_ratios(green, 0, renderer.settings.max_table_photons)
    ratios_s = time.perf_counter() - start
    at = visibilities.index(v)
    runs = [
        luminance(renderer.render(sigmas, haze.albedo, haze.g, SPP, seed).levels[at])
        for seed in seeds
    ]
    pixels = session.pixels
    masks = region_masks(pixels.distance_m, pixels.instance)
    if dense_thin:
        ratio = pixel_density_ratio(renderer.field, renderer.geometry)
        for name in ("sea", "sky", "vessel"):
            masks[f"{name} dense"] = masks[name] & (ratio > 1.5)
            masks[f"{name} thin"] = masks[name] & (ratio < 1 / 1.5)
        ids, counts = np.unique(pixels.instance[pixels.instance >= 0], return_counts=True)
        masks["largest hull"] = pixels.instance == ids[np.argmax(counts)]
    regions = {}
    for name, mask in masks.items():
        if not mask.any():
            continue
        mean, se = region_error(np.mean(runs, 0), ref, ref_se, mask)
        one = [region_error(run, ref, ref_se, mask)[0] for run in runs]
        regions[name] = (mean, se, float(np.std(one, ddof=1)))
    return {"regions": regions, "ratios_s": ratios_s}


def table(results: dict) -> str:
    """The results (by bank text and V) as docs/benchmarks.md's table, its caption saying how
    they were made."""
    lines = [
        "## physical in a fog bank against converged references (scripts/bench_bank_diffuse.py)",
        "",
        f"Machine: {platform.machine()}, `llvm_ad_rgb`. Benchmark scene (80×45); a bank is "
        "DISTANCE m ahead, BEARING°, EDGE m, NEAR ratio (`haze.bank`); `physical` "
        f"{len(SEEDS)} renders of {SPP} spp (their own seeds, so their own traced banks; 2^20 "
        "photons per level for tables and bank) against the `volpath` references of "
        "compare_components.py. Per cent: the error of the renders' mean ± the reference's "
        "standard error, then (in brackets) the standard deviation of one render's error. "
        "Ratios: the bank's strip traced and the pixels' rays summed, for the one level.",
        "",
        "| bank | V (m) | sea | sky | vessels | ratios (s) |",
        "|---|---|---|---|---|---|",
    ]
    for (bank, v), result in results.items():
        cells = [
            "{:+.2f} ± {:.2f} ({:.2f})".format(*(100 * x for x in result["regions"][r]))
            for r in ("sea", "sky", "vessel")
        ]
        lines.append(f"| {bank} | {v:g} | {' | '.join(cells)} | {result['ratios_s']:.1f} |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cases", default="300,1000,4000", help="visibilities (m)")
    parser.add_argument(
        "--banks",
        default="900,0,80,0.2/600,35,150,0.35",
        help="haze.bank as DISTANCE,BEARING,EDGE,NEAR, several separated by /",
    )
    parser.add_argument(
        "--cache",
        type=Path,
        default=ROOT / "out" / "compare-cache",
        help="where the volpath references are kept (compare_components.py's --cache)",
    )
    parser.add_argument("--doc", action="store_true", help="write the table into docs/")
    args = parser.parse_args()
    results = {}
    for bank in args.banks.split("/"):
        for v in (float(x) for x in args.cases.split(",")):
            batches = 8 if v == 1000.0 else 4  # the references' (the cache's key)
            results[bank, v] = measure(v, {"bank": bank_of(bank)}, args.cache, batches)
            print(table({(bank, v): results[bank, v]}).split("|---|")[-1], flush=True)
    text = table(results)
    print(text)
    if args.doc:
        replace_section("bank-diffuse", text, "scripts/bench_bank_diffuse.py")


if __name__ == "__main__":
    main()
