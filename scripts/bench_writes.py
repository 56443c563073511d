"""What a scene's files cost to write, by file kind and compression (issue 33: throughput).

Reads every file of one rendered scene in a dataset folder (PNG images, radiance EXRs,
transmission EXRs, the distance EXR) and encodes each again under the compressions a writer could
choose, on one thread (OpenEXR's thread count 1; Pillow's PNG encoder has one): the best of three
encodes per file, and its size. Pixels are the files' own, so every option encodes exactly what
the dataset holds. It writes the "writes" section of docs/benchmarks.md with ``--doc``.

- PNG (``images/``): zlib levels 1, 4 (seahaze's since 2026-11-29) and 6 (Pillow's default,
  seahaze's before);
- radiance EXR (``exr/``): none (seahaze's since 2026-11-29), ZIPS (one scanline a block) and
  ZIP (16 scanlines, seahaze's before);
- transmission EXR (``transmission/``) and distance EXR (``depth/``): none and ZIP (seahaze's).

Regenerate: ``seahaze render scenes/default.yaml --out out/writes --yes`` (its 1280×720 and
11 levels), then ``python scripts/bench_writes.py out/writes --doc``.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import OpenEXR
from PIL import Image

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_passes import replace_section
from seahaze import fileio

PNG_LEVELS = (1, 4, 6)
EXR_OPTIONS = {
    "exr": ("NO", "ZIPS", "ZIP"),
    "transmission": ("NO", "ZIP"),
    "depth": ("NO", "ZIP"),
}
CHOSEN = {"images": "level 4", "exr": "NO", "transmission": "ZIP", "depth": "ZIP"}
BEFORE = {"images": "level 6", "exr": "ZIP", "transmission": "ZIP", "depth": "ZIP"}


def best_of(encode: Callable[[Path], None], target: Path, runs: int = 3) -> tuple[float, int]:
    """Best wall time (s) of ``runs`` encodes into ``target``, and the file's size (bytes)."""
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        encode(target)
        times.append(time.perf_counter() - start)
    return min(times), target.stat().st_size


def exr_channels(path: Path) -> dict[str, np.ndarray]:
    """The file's channels under their own names (``R``, ``T.R``, ``Z``, …), float32 (H, W)."""
    out = {}
    for name, pixels in fileio.read_exr(path).items():
        if pixels.ndim == 3:
            prefix = "" if name == "RGB" else f"{name}."
            for i, c in enumerate("RGB"):
                out[prefix + c] = np.ascontiguousarray(pixels[..., i], dtype=np.float32)
        else:
            out[name] = np.ascontiguousarray(pixels, dtype=np.float32)
    return out


def exr_encoder(channels: dict[str, np.ndarray], compression: str) -> Callable[[Path], None]:
    header = {
        "compression": getattr(OpenEXR, f"{compression}_COMPRESSION"),
        "type": OpenEXR.scanlineimage,
    }

    def encode(target: Path) -> None:
        with OpenEXR.File(header, channels) as exr:
            exr.write(str(target))

    return encode


def png_encoder(pixels: np.ndarray, level: int) -> Callable[[Path], None]:
    def encode(target: Path) -> None:
        Image.fromarray(pixels, mode="RGB").save(target, format="PNG", compress_level=level)

    return encode


def scene_files(root: Path, scene: str) -> dict[str, list[Path]]:
    """The scene's files by kind (the dataset folder's sub-folder names)."""
    kinds = {kind: sorted(root.glob(f"{kind}/*/{scene}.*")) for kind in ("images", "exr")}
    kinds["transmission"] = sorted(root.glob(f"transmission/*/{scene}.exr"))
    kinds["depth"] = [root / "depth" / f"{scene}.exr"]
    return kinds


def measure(root: Path, scene: str) -> dict[str, dict[str, tuple[float, int, int]]]:
    """Per kind and option: (seconds, bytes, files) summed over the scene's files."""
    OpenEXR.set_global_thread_count(1)
    results: dict[str, dict[str, tuple[float, int, int]]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for kind, paths in scene_files(root, scene).items():
            if not paths:
                raise SystemExit(f"{root}: no {kind} files of scene {scene!r}")
            options: dict[str, list[tuple[float, int]]] = {}
            for path in paths:
                if kind == "images":
                    pixels = np.asarray(Image.open(path).convert("RGB"))
                    encoders = {f"level {lv}": png_encoder(pixels, lv) for lv in PNG_LEVELS}
                    suffix = ".png"
                else:
                    channels = exr_channels(path)
                    encoders = {c: exr_encoder(channels, c) for c in EXR_OPTIONS[kind]}
                    suffix = ".exr"
                for option, encode in encoders.items():
                    options.setdefault(option, []).append(
                        best_of(encode, Path(tmp) / f"{kind}{suffix}")
                    )
            results[kind] = {
                option: (sum(t for t, _ in runs), sum(b for _, b in runs), len(runs))
                for option, runs in options.items()
            }
    return results


def document(results: dict, root: Path, scene: str) -> str:
    """The benchmarks.md section of ``results``."""
    lines = [
        "## Writing a scene's files (scripts/bench_writes.py)",
        "",
        f"Scene `{scene}` of `{root.name}`; machine {platform.machine()}, "
        f"{os.cpu_count()} vCPU; one thread; each file encoded three times, the best kept. "
        "Seconds and MiB are the scene's files of that kind together.",
        "",
        "| files | option | seconds | MiB | per file |",
        "|---|---|---|---|---|",
    ]
    for kind, options in results.items():
        for option, (seconds, size, files) in options.items():
            mark = " (now)" if CHOSEN[kind] == option else ""
            mark += " (before)" if BEFORE[kind] == option else ""
            lines.append(
                f"| {kind} ({files}) | {option}{mark} | {seconds:.2f} | {size / 2**20:.1f} | "
                f"{seconds / files:.3f} s |"
            )
    total = {
        label: [sum(results[k][choice[k]][i] for k in results) for i in (0, 1)]
        for label, choice in (("before", BEFORE), ("now", CHOSEN))
    }
    lines += [
        "",
        f"Every file of the scene, one thread: before {total['before'][0]:.2f} s and "
        f"{total['before'][1] / 2**20:.1f} MiB, now {total['now'][0]:.2f} s and "
        f"{total['now'][1] / 2**20:.1f} MiB "
        f"({total['now'][0] / total['before'][0]:.2f}× the time, "
        f"{total['now'][1] / total['before'][1]:.2f}× the bytes).",
    ]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dataset", type=Path, help="a dataset folder rendered with EXRs")
    parser.add_argument("--scene", help="the scene to read (default: the first one)")
    parser.add_argument("--doc", action="store_true", help="write docs/benchmarks.md's section")
    args = parser.parse_args()
    scene = args.scene or sorted(p.stem for p in (args.dataset / "meta").glob("*.json"))[0]
    results = measure(args.dataset, scene)
    body = document(results, args.dataset, scene)
    print(body)
    if args.doc:
        replace_section("writes", body, "scripts/bench_writes.py")


if __name__ == "__main__":
    main()
