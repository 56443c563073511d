"""Benchmark the two ways a Hugging Face ``datasets`` export can store a seahaze dataset.

The same rows (one per scene and hazy level: hazy image, clean image, depth, visibility, σ,
split, vessels) are written twice from one rendered dataset:

* **Parquet shards** — ``seahaze export --layout hf``: the PNG and depth-TIFF bytes inside
  ``data/<level>/<split>-*.parquet``, the features in the Parquet schema;
* **imagefolder** — the layout ``datasets``' ``imagefolder`` builder reads: per level and
  split a ``metadata.jsonl`` whose ``hazy_file_name``, ``clean_file_name`` and
  ``depth_file_name`` name files beside it, the PNGs hard-linked from the dataset (no pixel
  copied) and each scene's depth TIFF written once and hard-linked into every level.

For each it measures the export's wall time, the bytes it adds to the disk (files that are not
links to the dataset's own, each counted once) and its number of files, then with ``datasets``:
the first ``load_dataset`` (which prepares the Arrow cache) and the size of that cache, a full
pass decoding every image of every split, a second ``load_dataset`` (cached) and a streamed
pass (``streaming=True``) decoding every image of the train split. Each load or pass is timed
twice (fresh cache each time for the first load) and the faster kept. The "Hugging Face export"
section of docs/benchmarks.md is rewritten with the table.

``--replicate N`` measures a dataset of N scenes as well, made of hard links to the rendered
ones under new names (MSVD's 1026 scenes without rendering them): the file counts and bytes of
a dataset of that size.

Usage: python scripts/bench_hf_export.py [--dataset DIR] [--scenes 12] [--res 640x360]
       [--spp 8] [--replicate 1026] [--runs 2]   (without --dataset it renders
       scenes/default.yaml, 11 levels, split 0.5,0.25,0.25, into a temporary folder)
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "default.yaml"
MSVD_SCENES = 1026
"""Scenes of MSVD (12,312 images: a clean image and 11 levels each)."""


def _replace_section() -> Callable[..., None]:
    """``replace_section`` of scripts/bench_passes.py (scripts are not a package)."""
    spec = importlib.util.spec_from_file_location(
        "bench_passes", ROOT / "scripts" / "bench_passes.py"
    )
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.replace_section


def render(out: Path, scenes: int, res: str, spp: int) -> None:
    """The benchmark's dataset: ``scenes`` scenes of the default scene, 11 levels."""
    seahaze = str(Path(sys.executable).parent / "seahaze")
    args = [seahaze, "render", str(SCENE), "--scenes", str(scenes)]
    args += ["--split", "0.5,0.25,0.25", "--vis", "300..4000", "--res", res, "--spp", str(spp)]
    subprocess.run([*args, "--out", str(out), "--quiet"], check=True)


def replicate(dataset: Path, out: Path, scenes: int) -> Path:
    """A dataset of ``scenes`` scenes at ``out`` made of hard links to the files of
    ``dataset``'s scenes in turn (each copy keeps its original's split): the file counts and
    sizes of a larger dataset without rendering it. Only what an export reads is linked."""
    data = json.loads((dataset / "dataset.json").read_text())
    originals = list(data["scenes"])
    levels = ["clean", *(level["name"] for level in data["levels"])]
    copies = {}
    for i in range(scenes):
        original = originals[i % len(originals)]
        name = f"copy_{i:05d}"
        copies[name] = data["scenes"][original]
        links = [(f"meta/{original}.json", f"meta/{name}.json")]
        links.append((f"depth/{original}.exr", f"depth/{name}.exr"))
        for level in levels:
            links.append((f"images/{level}/{original}.png", f"images/{level}/{name}.png"))
            links.append((f"labels/{level}/{original}.txt", f"labels/{level}/{name}.txt"))
        for source, target in links:
            (out / target).parent.mkdir(parents=True, exist_ok=True)
            os.link(dataset / source, out / target)
    (out / "dataset.json").write_text(json.dumps({**data, "scenes": copies}))
    return out


def write_imagefolder(dataset: Path, out: Path) -> None:
    """The rows of the ``hf`` layout as an ``imagefolder`` dataset (see the module doc)."""
    from seahaze.export.hf import hub_split, plan_hf
    from seahaze.export.hf_rows import depth_tiff, read_scene
    from seahaze.export.source import open_finished
    from seahaze.visibility import CLEAN_LEVEL

    source = open_finished(dataset)
    plan_hf(source)  # the same checks of every file as the Parquet export makes
    layout = source.layout
    levels = [level.name for level in source.levels]
    regulation = {e["name"]: e.get("regulation") for e in source.manifest["levels"]}
    configs: dict[str, list[str]] = {}
    for split in source.splits:
        name = hub_split(split)
        scenes = source.scenes_of(split)
        if not scenes:
            continue
        depth_of: dict[str, Path] = {}
        for level in source.levels:
            folder = out / level.name / name
            for sub in ("hazy", "clean", "depth"):
                (folder / sub).mkdir(parents=True, exist_ok=True)
            lines = []
            for scene in scenes:
                record = read_scene(
                    layout, scene, name, levels, source.classes, source.manifest["scenes"][scene]
                )
                os.link(layout.image(level.name, scene), folder / "hazy" / f"{scene}.png")
                os.link(layout.image(CLEAN_LEVEL, scene), folder / "clean" / f"{scene}.png")
                depth = folder / "depth" / f"{scene}.tiff"
                if scene in depth_of:
                    os.link(depth_of[scene], depth)
                else:
                    depth.write_bytes(depth_tiff(layout.depth(scene)))
                    depth_of[scene] = depth
                looks = [obj.levels[level.name] for obj in record.objects]
                lines.append(
                    {
                        "hazy_file_name": f"hazy/{scene}.png",
                        "clean_file_name": f"clean/{scene}.png",
                        "depth_file_name": f"depth/{scene}.tiff",
                        "scene": scene,
                        "split": name,
                        "level": level.name,
                        "visibility_m": level.visibility_m,
                        "sigma_per_m": level.sigma_per_m,
                        "sigma_rgb_per_m": list(record.sigma_rgb[level.name]),
                        "regulation": regulation.get(level.name),
                        "objects": {
                            "category": [o.class_id for o in record.objects],
                            "bbox": [list(o.bbox) for o in record.objects],
                            "distance_m": [o.distance_m for o in record.objects],
                            "visible": [look.visible for look in looks],
                            "local_contrast": [look.local_contrast for look in looks],
                        },
                    }
                )
            text = "".join(json.dumps(line) + "\n" for line in lines)
            (folder / "metadata.jsonl").write_text(text)
            configs.setdefault(level.name, []).append(name)
    front = ["---", "configs:", "- config_name: all", "  default: true", "  data_files:"]
    for split in dict.fromkeys(s for splits in configs.values() for s in splits):
        front += [f"  - split: {split}", f"    path: '*/{split}/**'"]
    for level, splits in configs.items():
        front += [f"- config_name: {level}", "  data_files:"]
        for split in splits:
            front += [f"  - split: {split}", f"    path: {level}/{split}/**"]
    (out / "README.md").write_text("\n".join([*front, "---", "", "imagefolder benchmark", ""]))


def disk_use(view: Path, dataset: Path) -> tuple[int, int]:
    """(bytes the view adds to the disk, files in the view): files that are links to the
    dataset's files add nothing, and a file linked twice in the view counts once."""
    theirs = {(p.stat().st_dev, p.stat().st_ino) for p in dataset.rglob("*") if p.is_file()}
    seen: set[tuple[int, int]] = set()
    added = files = 0
    for path in view.rglob("*"):
        if not path.is_file() or path.name.startswith(".seahaze"):
            continue
        files += 1
        st = path.stat()
        key = (st.st_dev, st.st_ino)
        if key not in theirs and key not in seen:
            seen.add(key)
            added += st.st_size
    return added, files


def folder_bytes(folder: Path) -> int:
    return sum(p.stat().st_size for p in folder.rglob("*") if p.is_file())


def decode_all(rows: Any) -> int:
    """Decode every image of ``rows`` to arrays (what a training loop does); the row count."""
    count = 0
    for row in rows:
        for key in ("hazy", "clean", "depth"):
            np.asarray(row[key])
        count += 1
    return count


def best_of(runs: int, work: Callable[[], Any]) -> tuple[float, Any]:
    times, result = [], None
    for _ in range(runs):
        start = time.perf_counter()
        result = work()
        times.append(time.perf_counter() - start)
    return min(times), result


def measure(
    name: str, view: Path, dataset: Path, export_s: float, scratch: Path, runs: int
) -> dict:
    """Every figure of one format (see the module doc)."""
    import datasets

    added, files = disk_use(view, dataset)
    caches: list[Path] = []

    def first_load() -> Any:
        if caches:  # the previous run's cache: only one is kept on the disk
            shutil.rmtree(caches[-1], ignore_errors=True)
        caches.append(scratch / f"cache-{name}-{len(caches)}")
        return datasets.load_dataset(str(view), cache_dir=str(caches[-1]))

    load_s, loaded = best_of(runs, first_load)
    rows = sum(split.num_rows for split in loaded.values())
    pass_s, decoded = best_of(runs, lambda: sum(decode_all(split) for split in loaded.values()))
    assert decoded == rows
    cache = str(caches[-1])
    again_s, _ = best_of(runs, lambda: datasets.load_dataset(str(view), cache_dir=cache))

    def stream() -> int:
        return decode_all(datasets.load_dataset(str(view), split="train", streaming=True))

    stream_s, streamed = best_of(runs, stream)
    figures = {
        "format": name,
        "export_s": export_s,
        "added_mb": added / 1e6,
        "files": files,
        "rows": rows,
        "load_s": load_s,
        "cache_mb": folder_bytes(caches[-1]) / 1e6,
        "pass_s": pass_s,
        "again_s": again_s,
        "stream_rows": streamed,
        "stream_s": stream_s,
    }
    shutil.rmtree(caches[-1], ignore_errors=True)
    return figures


def measure_both(dataset: Path, scratch: Path, runs: int) -> list[dict]:
    """The figures of the Parquet export and of the imagefolder one of ``dataset``."""
    from seahaze.export import export_dataset

    results = []
    for name, write in (
        ("parquet", lambda out: export_dataset(dataset, out, "hf")),
        ("imagefolder", lambda out: write_imagefolder(dataset, out)),
    ):
        view = scratch / f"view-{name}"
        start = time.perf_counter()
        write(view)
        export_s = time.perf_counter() - start
        results.append(measure(name, view, dataset, export_s, scratch, runs))
        shutil.rmtree(view)
    return results


def depth_sizes(dataset: Path) -> dict[str, float]:
    """MB of every scene's depth as the EXR, as the TIFF of the export and as raw float32
    compressed by zstd (what a Parquet array column would hold)."""
    import pyarrow as pa

    from seahaze.export.hf_rows import depth_tiff
    from seahaze.fileio import read_exr

    sizes = {"exr": 0.0, "tiff": 0.0, "zstd": 0.0}
    for path in sorted((dataset / "depth").glob("*.exr")):
        sizes["exr"] += path.stat().st_size / 1e6
        sizes["tiff"] += len(depth_tiff(path)) / 1e6
        raw = np.ascontiguousarray(read_exr(path)["Z"], dtype=np.float32).tobytes()
        sizes["zstd"] += pa.compress(raw, codec="zstd", asbytes=True).__len__() / 1e6
    return sizes


LABELS = [
    ("export_s", "export (s)", "{:.1f}"),
    ("added_mb", "bytes added to the disk (MB)", "{:,.1f}"),
    ("files", "files", "{:,}"),
    ("load_s", "first `load_dataset`, preparing the cache (s)", "{:.2f}"),
    ("cache_mb", "its Arrow cache (MB)", "{:,.1f}"),
    ("pass_s", "decode every image of every row (s)", "{:.2f}"),
    ("again_s", "second `load_dataset`, cached (s)", "{:.2f}"),
    ("stream_s", "streamed pass over `train`, decoding (s)", "{:.2f}"),
]
"""Rows of the table: figure, label, format."""


def table(results: list[dict]) -> list[str]:
    by_name = {r["format"]: r for r in results}
    lines = [
        "| | Parquet shards (`--layout hf`) | imagefolder + metadata.jsonl |",
        "|---|---|---|",
    ]
    for key, label, fmt in LABELS:
        cells = [fmt.format(by_name[n][key]) for n in ("parquet", "imagefolder")]
        lines.append(f"| {label} | {cells[0]} | {cells[1]} |")
    rows = results[0]
    lines += ["", f"Rows: {rows['rows']:,} (both), {rows['stream_rows']:,} of them in `train`."]
    return lines


def section(tables: list[tuple[str, list[dict]]], depth: dict[str, float], scenes: int) -> str:
    import datasets
    import pyarrow

    load = os.getloadavg()
    lines = [
        "## Hugging Face export: Parquet shards against imagefolder (scripts/bench_hf_export.py)",
        "",
        f"Machine: {platform.machine()}, {os.cpu_count()} vCPU shared with other work (1-minute "
        f"load {load[0]:.1f} after the run); datasets {datasets.__version__}, pyarrow "
        f"{pyarrow.__version__}; the faster of the runs of each timing.",
    ]
    for about, results in tables:
        lines += ["", f"**{about}**", "", *table(results)]
    lines += [
        "",
        f"The depth of the {scenes} rendered scenes: EXR {depth['exr']:.2f} MB, float32 TIFF "
        f"(deflate, floating-point predictor; the export's) {depth['tiff']:.2f} MB, raw "
        f"float32 with zstd (a Parquet array column) {depth['zstd']:.2f} MB.",
    ]
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dataset", type=Path, help="a finished dataset (default: render one)")
    parser.add_argument("--scenes", type=int, default=12)
    parser.add_argument("--res", default="640x360")
    parser.add_argument("--spp", type=int, default=8)
    parser.add_argument(
        "--replicate",
        type=int,
        metavar="N",
        help="also measure a dataset of N scenes made of links to the rendered ones (scale)",
    )
    parser.add_argument("--runs", type=int, default=2, help="runs per timing, the best kept")
    parser.add_argument("--no-doc", action="store_true", help="print, do not edit the docs")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench_hf_") as tmp:
        scratch = Path(tmp)
        dataset = args.dataset
        if dataset is None:
            dataset = scratch / "dataset"
            render(dataset, args.scenes, args.res, args.spp)
        data = json.loads((dataset / "dataset.json").read_text())
        width, height = data["config"]["resolution"]
        scenes, levels = len(data["scenes"]), len(data["levels"])
        about = (
            f"`scenes/default.yaml`, {{n}} scenes at {width}×{height}, {data['config']['spp']} "
            f"spp, {levels} levels, split "
            f"{','.join(f'{v:g}' for v in data['config']['split'].values())}"
        )
        tables = [(about.format(n=scenes), measure_both(dataset, scratch, args.runs))]
        if args.replicate:
            big = replicate(dataset, scratch / "replicated", args.replicate)
            msvd = "MSVD's size: " if args.replicate == MSVD_SCENES else ""
            what = about.format(n=f"{args.replicate:,}") + (
                f" ({msvd}the {scenes} rendered scenes linked in turn under new names, "
                f"{args.replicate / scenes:.1f} times each)"
            )
            tables.append((what, measure_both(big, scratch, args.runs)))
        body = section(tables, depth_sizes(dataset), scenes)
    print(body)
    if not args.no_doc:
        _replace_section()("hf-export", body, "scripts/bench_hf_export.py")
    return 0


if __name__ == "__main__":
    sys.exit(main())
