"""How close is the ``physical`` mode in drifting patches, and how much does one render scatter?

``physical`` gives patches the diffuse light of their own field (``render/patch_diffuse.py``:
photons traced through a periodic box of the field around the camera, each cell's fluence over
the profile's scaling the profile's light; each pixel's camera segment and later segments
scaled by their ratio to the tables' light). This script compares it per region with converged
``volpath`` references of the same patches (as ``scripts/compare_components.py`` does, whose
reference cache it shares): four renders of 256 spp, each with its own seed and so its own
traced box, reported as the error of their mean and as the scatter of one render's region error
about it. Sea, sky and vessels are also compared where each pixel's ray holds more than 1.5×
the level's mean haze (``dense``) and less than 1/1.5 of it (``thin``). The time is that of the
patches' ratios alone (tracing the box and summing the pixels' rays) for the one level, with
the photons the tables get at full size (2^20).

A case ``V:A:B`` renders level ``V`` in one pass with levels ``A`` and ``B``, as a dataset's
levels are rendered: the field is traced at levels at most ``patch_diffuse.LEVEL_SPAN`` apart
and a level between takes its ratios interpolated from the two that bracket it
(``400:300:500`` and ``1300:1000:2000`` measure two graded levels so).

Usage: python scripts/bench_patch_diffuse.py [--cases 300,1000,4000,400:300:500,1300:1000:2000]
       [--patches 400,3,60,30/400,3,60,5] [--cache DIR] [--batches 4] [--seeds 16] [--doc]
"""

from __future__ import annotations

import argparse
import platform
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_bank_diffuse import SPP, measure
from bench_passes import replace_section

ROOT = Path(__file__).resolve().parents[1]
BATCHES = 4
"""The references' batches of 1024 spp by default (compare_components.py ``--batches``)."""
REGIONS = ("sea", "sky", "vessel", "sea dense", "sea thin", "vessel thin", "largest hull")
RENDERS = 16
"""Renders per case by default: one render's scatter (its box's photon noise) read from four
was off by a factor of up to five (0.4 % against 2.2 % from sixteen at 4000 m)."""


def patches_of(text: str) -> dict:
    """``haze.patches`` from ``CORRELATION,ANISOTROPY,VERTICAL,RATIO``."""
    corr, aniso, vertical, ratio = (float(x) for x in text.split(","))
    return {
        "correlation_m": corr,
        "anisotropy": aniso,
        "vertical_m": vertical,
        "density_ratio": ratio,
    }


def table(results: dict, batches: int = BATCHES, seeds: int = RENDERS) -> str:
    """The results (by patches text and case) as docs/benchmarks.md's table, its caption
    saying how they were made (the references of ``batches`` batches, ``seeds`` renders)."""
    lines = [
        "## physical in drifting patches against converged references "
        "(scripts/bench_patch_diffuse.py)",
        "",
        f"Machine: {platform.machine()}, `llvm_ad_rgb`. Benchmark scene (80×45); patches are "
        "CORRELATION m along the drift, ANISOTROPY, VERTICAL m, density RATIO "
        f"(`haze.patches`); `physical` {seeds} renders of {SPP} spp (their own seeds, so "
        "their own traced boxes; 2^20 photons per level for tables and box) against "
        f"`volpath` references of compare_components.py ({batches} × 1024 spp). Per cent: the "
        "error of the renders' mean ± the reference's standard error, then (in brackets) the "
        "standard deviation of "
        "one render's error. `dense`/`thin`: pixels whose ray holds more than 1.5× / less than "
        "1/1.5 of the level's mean haze (— where none); `largest hull`: the vessel with the most "
        "pixels (the passenger ferry at 600 m). Ratios: the box traced and the pixels' "
        "rays summed, for the level (for V with A and B, rendered in one pass with them: the "
        "field traced at A and B, interpolated at V).",
        "",
        f"| patches | V (m) | {' | '.join(REGIONS)} | ratios (s) |",
        "|---|---|" + "---|" * len(REGIONS) + "---|",
    ]
    for (patches, case), result in results.items():
        cells = [
            "{:+.2f} ± {:.2f} ({:.2f})".format(*(100 * x for x in result["regions"][r]))
            if r in result["regions"]
            else "—"
            for r in REGIONS
        ]
        v, *company = (float(x) for x in case.split(":"))
        level = f"{v:g}" + (f" with {', '.join(f'{c:g}' for c in company)}" if company else "")
        lines.append(f"| {patches} | {level} | {' | '.join(cells)} | {result['ratios_s']:.1f} |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument(
        "--cases",
        default="300,1000,4000,400:300:500,1300:1000:2000",
        help="visibilities (m); V:A:B renders V in one pass with A and B",
    )
    parser.add_argument(
        "--patches",
        default="400,3,60,30/400,3,60,5",
        help="haze.patches as CORRELATION,ANISOTROPY,VERTICAL,RATIO, several separated by /",
    )
    parser.add_argument(
        "--cache",
        type=Path,
        default=ROOT / "out" / "compare-cache",
        help="where the volpath references are kept (compare_components.py's --cache)",
    )
    parser.add_argument(
        "--batches", type=int, default=BATCHES, help="the references' batches of 1024 spp"
    )
    parser.add_argument(
        "--seeds", type=int, default=RENDERS, help="renders per case (sampler seeds 1 … N)"
    )
    parser.add_argument("--doc", action="store_true", help="write the table into docs/")
    args = parser.parse_args()
    results = {}
    for patches in args.patches.split("/"):
        for case in args.cases.split(","):
            v, *company = (float(x) for x in case.split(":"))
            changes = {"patches": patches_of(patches)}
            results[patches, case] = measure(
                v,
                changes,
                args.cache,
                args.batches,
                dense_thin=True,
                company=tuple(company),
                seeds=tuple(range(1, args.seeds + 1)),
            )
            row = table({(patches, case): results[patches, case]}, args.batches, args.seeds)
            print(row.split("|---|")[-1], flush=True)
    text = table(results, args.batches, args.seeds)
    print(text)
    if args.doc:
        replace_section("patch-diffuse", text, "scripts/bench_patch_diffuse.py")


if __name__ == "__main__":
    main()
