"""The hazy-level modes against converged references in dense haze: 50, 100 and 200 m (issue #19).

Renders the dense-haze scene (``scenes/dense.yaml``) through the public API —
``seahaze.render.engine.render_scene`` with each mode, so a rewritten mode is measured as it
ships — and compares the mean luminance of every region (top, middle and bottom thirds; sky and
sea) with the converged ``reference`` images of ``scripts/make_dense_references.py``
(``assets/references/dense/``, digests checked). The physical mode runs ``--seeds`` times with
different seeds, so its own noise is measured too; ``reference`` at the old default depth (64)
shows what truncating the paths did.

Results: the "dense" section of docs/benchmarks.md and ``out/compare_dense.json``. Rerun it after
any change to the ``physical`` mode.

Usage: python scripts/compare_dense.py [--spp 256] [--seeds 4]
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "scripts"))
from bench_passes import replace_section  # noqa: E402
from make_dense_references import OUT as REFS  # noqa: E402
from make_dense_references import SCENE, region_masks, region_means, scene_digest  # noqa: E402

TOLERANCE = 0.03
"""A mode is validated at a level when every region is within 3 % of the reference."""


def load_references() -> dict:
    """The references' metadata (region means), after checking their checksums and digests."""
    meta = json.loads((REFS / "references.json").read_text())
    if meta["scene_sha256"] != scene_digest():
        sys.exit(f"{REFS} is stale: {SCENE.name} changed; rerun scripts/make_dense_references.py")
    for line in (REFS / "SHA256SUMS").read_text().splitlines():
        digest, name = line.split()
        if hashlib.sha256((REFS / name).read_bytes()).hexdigest() != digest:
            sys.exit(f"{REFS / name} does not match SHA256SUMS")
    return meta


def render(mode: str, spp: int, seed: int, levels: list[float], **render: object):
    from seahaze.render.engine import render_scene
    from seahaze.sceneio import load_scene
    from seahaze.spec import with_changes

    spec, _ = load_scene(SCENE)
    spec = with_changes(
        spec,
        {"render": {"mode": mode, "spp": spp, "seed": seed, **render}, "haze": {"levels": levels}},
    )
    start = time.perf_counter()
    scene = render_scene(spec, "dense")
    return scene, time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spp", type=int, default=256)
    parser.add_argument("--seeds", type=int, default=4)
    parser.add_argument("--truncated-spp", type=int, default=1024)
    args = parser.parse_args()

    meta = load_references()
    keys = sorted(meta["levels"], key=lambda k: meta["levels"][k]["visibility_m"])
    levels = [meta["levels"][k]["visibility_m"] for k in keys]
    runs: dict[str, list] = {"physical": [], "asm": [], "reference (max_depth 64)": []}
    world = None
    for seed in range(args.seeds):
        scene, seconds = render("physical", args.spp, 100 + seed, levels)
        runs["physical"].append((scene, seconds))
        world = scene.geometry
    runs["asm"].append(render("asm", args.spp, 100, levels))
    runs["reference (max_depth 64)"].append(
        render("reference", args.truncated_spp, 100, levels, max_depth=64)
    )
    masks = region_masks(world.distance_m)
    results: dict = {
        "spp": args.spp,
        "seeds": args.seeds,
        "truncated_spp": args.truncated_spp,
        "levels": {},
    }
    for key in keys:
        ref = meta["levels"][key]["regions"]
        entry: dict = {"reference": ref, "reference_spp": meta["levels"][key]["spp"]}
        for mode, scenes in runs.items():
            per_seed = [
                region_means(next(lv for lv in s.levels if lv.name == key).radiance, masks)
                for s, _ in scenes
            ]
            entry[mode] = {}
            for region in ref:
                values = np.array([m[region] for m in per_seed])
                ratio = values / ref[region]["mean"]
                entry[mode][region] = {
                    "ratio": float(ratio.mean()),
                    "ratio_stderr": float(ratio.std(ddof=1) / np.sqrt(len(ratio)))
                    if len(ratio) > 1
                    else None,
                }
        entry["physical_seconds"] = float(np.mean([t for _, t in runs["physical"]]))
        results["levels"][key] = entry
    out = ROOT / "out" / "compare_dense.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(results, indent=2) + "\n")
    write_section(results, meta, keys)
    print(json.dumps(results, indent=2))


def write_section(results: dict, meta: dict, keys: list[str]) -> None:
    """The "dense" section of docs/benchmarks.md."""
    import mitsuba as mi

    regions = ["top", "middle", "bottom", "sky", "sea"]
    lines = [
        "## Dense haze: 50, 100 and 200 m against converged references (`scenes/dense.yaml`)",
        "",
        f"48×27, camera 15 m inside the 300 m layer, no vessels; Mitsuba {mi.__version__}, "
        f"`{meta['variant']}`. References: `volpath` unbounded depth (Russian roulette), haze "
        f"box half-width {meta['box_half_width_m']:.0f} m, every region's mean to "
        f"{100 * meta['target_region_relative_stderr']:g} % (1 standard error) or the recorded "
        "error (`scripts/make_dense_references.py`); the reference rows give the mean luminance "
        "and its standard error. Modes rendered through `render_scene` "
        "(`scripts/compare_dense.py`): ratio of the region's mean luminance to the "
        f"reference's; `physical` at {results['spp']} spp, mean of {results['seeds']} seeds ± "
        "its standard error; `asm` at the same spp; `reference (max_depth 64)`, the old "
        f"default depth, at {results.get('truncated_spp', 1024)} spp. Regions: thirds of the "
        "frame, and sky and sea pixels. A reference that stopped at its time limit before "
        "reaching its target error says so in its row (its standard error is then larger).",
        "",
        "| V | mode | " + " | ".join(regions) + " |",
        "|---|---|" + "---|" * len(regions),
    ]
    for key in keys:
        entry = results["levels"][key]
        v = meta["levels"][key]["visibility_m"]
        ref = entry["reference"]
        cells = [
            f"{ref[r]['mean']:.4f} ± {100 * ref[r]['relative_stderr']:.1f} %"
            for r in regions
            if r in ref
        ]
        head = f"| {v:g} m | reference ({entry['reference_spp']} spp) | "
        lines.append(head + " | ".join(cells) + " |")
        for mode in ("physical", "asm", "reference (max_depth 64)"):
            cells = []
            for r in regions:
                if r not in entry[mode]:
                    continue
                cell = entry[mode][r]
                err = f" ± {cell['ratio_stderr']:.3f}" if cell["ratio_stderr"] is not None else ""
                cells.append(f"{cell['ratio']:.3f}{err}")
            lines.append(f"| | {mode} | " + " | ".join(cells) + " |")
    replace_section("dense", "\n".join(lines), "scripts/compare_dense.py")


if __name__ == "__main__":
    main()
