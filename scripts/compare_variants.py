"""Compare two renders of the same scene, config and seed made under different Mitsuba variants
(e.g. ``cuda_ad_rgb`` on a GPU against ``llvm_ad_rgb`` on a CPU): which files are byte-identical,
how many PNG values differ and by how much, and each linear EXR channel's mean relative
difference. Used for docs/benchmarks.md, "How fast is cuda_ad_rgb on a GPU, and does the suite
pass there?" (the GPU's renders come from scripts/bench_gpu.sh).

Usage: python scripts/compare_variants.py DATASET_A DATASET_B
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from PIL import Image

from seahaze.fileio import read_exr

PATH_BOUND = ("data.yaml",)
"""Files that name their own folder, so differ between any two folders."""


def png_difference(a: Path, b: Path) -> tuple[int, int, int]:
    """Values that differ, values in all, and the largest difference (code values)."""
    x = np.asarray(Image.open(a), np.int64)
    y = np.asarray(Image.open(b), np.int64)
    differ = np.abs(x - y)
    return int(np.count_nonzero(differ)), differ.size, int(differ.max())


def exr_differences(a: Path, b: Path) -> dict[str, float]:
    """Per channel: mean |a - b| over mean |b|, over the values finite in both (the sky's
    distance is infinite in both)."""
    x, y = read_exr(a), read_exr(b)
    out = {}
    for channel in x:
        u, v = x[channel].astype(np.float64), y[channel].astype(np.float64)
        finite = np.isfinite(u) & np.isfinite(v)
        scale = np.abs(v[finite]).mean()
        out[channel] = float(np.abs(u[finite] - v[finite]).mean() / scale) if scale > 0 else 0.0
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("a", type=Path)
    parser.add_argument("b", type=Path)
    args = parser.parse_args()
    files = sorted(p.relative_to(args.a) for p in args.a.rglob("*") if p.is_file())
    files = [f for f in files if f.name not in PATH_BOUND]
    same = sum((args.a / f).read_bytes() == (args.b / f).read_bytes() for f in files)
    print(f"{len(files)} files, {same} byte-identical")
    pngs = [png_difference(args.a / f, args.b / f) for f in files if f.suffix == ".png"]
    differing, total = sum(p[0] for p in pngs), sum(p[1] for p in pngs)
    print(
        f"PNG values differing: {differing} of {total} ({differing / max(total, 1):.2e}), "
        f"largest {max((p[2] for p in pngs), default=0)} code values"
    )
    print("| EXR | channel | mean relative difference |\n|---|---|---|")
    for f in files:
        if f.suffix == ".exr":
            for channel, rel in exr_differences(args.a / f, args.b / f).items():
                print(f"| {f.as_posix()} | {channel} | {rel:.1e} |")


if __name__ == "__main__":
    main()
