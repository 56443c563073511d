"""Does the same scene and seed give the same bytes from run to run and at any thread count?

Renders one scene (``scenes/default.yaml`` at 128×72 and its own samples per pixel unless told
otherwise) through ``seahaze render`` in separate processes: the ``physical`` mode at 1, 2 and 4
threads and at 2 once more, and the ``reference`` mode (30 spp, 3 levels) at 1, 2 and 3
threads. Every file of each dataset is hashed (SHA-256) but ``data.yaml``, which names the
folder it was written to, and each run is compared with its mode's first. With ``--doc`` the
table goes to the "reproducibility" section of docs/benchmarks.md (docs/limits.md,
"Reproducibility", says what the layout of the samples does for it).

Usage: python scripts/bench_reproducibility.py [--scene PATH] [--res 128x72] [--doc]
(about 2 minutes on a 2-vCPU machine)
"""

from __future__ import annotations

import argparse
import hashlib
import os
import platform
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_passes import replace_section  # noqa: E402

REFERENCE = ["--mode", "reference", "--spp", "30", "--vis", "300..4000:3"]
"""The reference runs' settings: its kernels are slow to compile, so a short set of levels."""
RUNS = [
    ("physical", "1 thread", ["--threads", "1"]),
    ("physical", "2 threads", ["--threads", "2"]),
    ("physical", "2 threads, again", ["--threads", "2"]),
    ("physical", "4 threads", ["--threads", "4"]),
    ("reference", "1 thread", [*REFERENCE, "--threads", "1"]),
    ("reference", "2 threads", [*REFERENCE, "--threads", "2"]),
    ("reference", "3 threads", [*REFERENCE, "--threads", "3"]),
]
"""(mode, run, extra ``seahaze render`` arguments); each mode's first run is its yardstick."""
NAMES_THE_FOLDER = {"data.yaml"}
"""Files that hold the dataset's own path, so differ between folders by design."""


def hashes(folder: Path) -> dict[str, str]:
    """SHA-256 of every file under ``folder`` by relative path, but :data:`NAMES_THE_FOLDER`."""
    return {
        str(path.relative_to(folder)): hashlib.sha256(path.read_bytes()).hexdigest()
        for path in sorted(folder.rglob("*"))
        if path.is_file() and path.name not in NAMES_THE_FOLDER
    }


def render(scene: Path, res: str, out: Path, extra: list[str]) -> dict[str, str]:
    """One ``seahaze render`` of ``scene`` into ``out`` and the hashes of what it wrote."""
    command = [str(ROOT / ".venv" / "bin" / "seahaze"), "render", str(scene), "--res", res]
    done = subprocess.run(
        [*command, "--out", str(out), "--quiet", *extra], capture_output=True, text=True
    )
    if done.returncode != 0:
        sys.exit(f"seahaze render failed (exit {done.returncode}): {done.stderr.strip()}")
    return hashes(out)


def measure(scene: Path, res: str) -> list[dict]:
    """Every run of :data:`RUNS`, compared with its mode's first."""
    rows: list[dict] = []
    first: dict[str, dict[str, str]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for index, (mode, run, extra) in enumerate(RUNS):
            files = render(scene, res, Path(tmp) / f"run{index}", extra)
            yardstick = first.setdefault(mode, files)
            differ = sorted(
                k for k in files.keys() | yardstick.keys() if files.get(k) != yardstick.get(k)
            )
            rows.append({"mode": mode, "run": run, "files": len(files), "differ": differ})
            print(f"{mode}, {run}: {len(files)} files, {len(differ)} differ from the first")
    return rows


def write_doc(rows: list[dict], scene: Path, res: str) -> None:
    """The "reproducibility" section of docs/benchmarks.md."""
    lines = [
        "## Same bytes at any thread count? (scripts/bench_reproducibility.py)",
        "",
        f"`seahaze render {scene.relative_to(ROOT)} --res {res}` in separate processes, every "
        "file of each dataset hashed (but `data.yaml`, which names its folder) and compared "
        "with its mode's first run. `reference`: `--spp 30 --vis 300..4000:3`. Machine: "
        f"{platform.machine()}, {len(os.sched_getaffinity(0))} vCPU, `llvm_ad_rgb`.",
        "",
        "| mode | run | files | differing from the mode's first run |",
        "|---|---|---|---|",
    ]
    for row in rows:
        differ = ", ".join(row["differ"][:4]) + (" …" if len(row["differ"]) > 4 else "")
        lines.append(
            f"| {row['mode']} | {row['run']} | {row['files']} | "
            f"{len(row['differ'])}{': ' + differ if differ else ''} |"
        )
    replace_section("reproducibility", "\n".join(lines), "scripts/bench_reproducibility.py")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", type=Path, default=ROOT / "scenes" / "default.yaml")
    parser.add_argument("--res", default="128x72", help="image size, WxH")
    parser.add_argument("--doc", action="store_true", help="write docs/benchmarks.md")
    args = parser.parse_args()
    rows = measure(args.scene.resolve(), args.res)
    if args.doc:
        write_doc(rows, args.scene.resolve(), args.res)
    if any(row["differ"] for row in rows):
        sys.exit("some runs differ from their mode's first")


if __name__ == "__main__":
    main()
