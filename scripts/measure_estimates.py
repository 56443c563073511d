"""Fit and check ``seahaze render``'s memory, compilation and start-up estimate (issue #36).

``seahaze render`` estimates a job before it starts (``src/seahaze/cli/limits.py``): it asks
for ``--yes`` before a job of an hour or more, or one that needs more than 80 % of the
machine's memory. This script runs the real command, as a user would, in fresh processes:

* **fit** (``--fit``): peak resident memory of the default scene at 1024×576 and 2048×1152
  and one and eleven levels, per mode (the least-squares ``base + pixels · (per_pixel + images ·
  per_image)``), and the wall time of a render with an empty kernel cache, with the kernels of
  another size cached, and with its own kernels cached, at a small size (compilation = the
  difference). It prints the constants to paste into ``limits.py``.
* **check** (default): for each configuration of :data:`CHECKS`, in order and sharing one
  kernel cache (``HOME`` and ``SEAHAZE_STATE_DIR`` in a fresh folder, so the first render of
  a kind compiles everything, as on a new machine), ``seahaze render --estimate`` and then the
  render itself: wall time (the whole command) and peak resident memory (``wait4``). Writes the
  table of docs/limits.md ("Estimated and measured").

The render-time constants come from ``scripts/measure_cost_model.py``; run it first on the same
machine. Usage: python scripts/measure_estimates.py [--fit] [--only LABEL]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from seahaze.cli.limits import STARTUP_S

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "scripts"))
from bench_passes import replace_section  # noqa: E402

SEAHAZE = [sys.executable, "-m", "seahaze.cli"]
LIMITS_DOC = ROOT / "docs" / "limits.md"


@dataclass(frozen=True)
class Check:
    label: str
    args: tuple[str, ...]
    run: bool = True
    """False: only the estimate and the gate (a job this machine cannot hold)."""


CHECKS = [
    Check("64×36, 1 spp (nothing compiled)", ("--res", "64x36", "--spp", "1")),
    Check("64×36, 1 spp (compiled)", ("--res", "64x36", "--spp", "1")),
    Check("320×180, 16 spp", ("--res", "320x180", "--spp", "16")),
    Check("1280×720, 42 spp (the default scene)", ()),
    Check("1280×720, 42 spp (compiled)", ()),
    Check("1920×1080, 4 spp", ("--res", "1920x1080", "--spp", "4")),
    Check("160×90, 4096 spp", ("--res", "160x90", "--spp", "4096")),
    Check("64×36, 65536 spp", ("--res", "64x36", "--spp", "65536")),
    Check("4096×2304, 1 spp", ("--res", "4096x2304", "--spp", "1")),
    Check("8192×4608, 1 spp, one level", ("--res", "8192x4608", "--spp", "1", "--vis", "1000")),
    Check(
        "320×180, 16 spp, reference, 3 levels",
        ("--res", "320x180", "--spp", "16", "--mode", "reference", "--vis", "300,1000,4000"),
    ),
    Check("320×180, 16 spp, asm", ("--res", "320x180", "--spp", "16", "--mode", "asm")),
    Check("8192×8192, 1 spp", ("--res", "8192x8192", "--spp", "1"), run=False),
]


@dataclass
class Run:
    code: int
    seconds: float
    peak_bytes: int
    stderr: str


def environment(home: Path) -> dict[str, str]:
    """A user whose drjit kernel cache and seahaze state live in ``home``."""
    return {**os.environ, "HOME": str(home), "SEAHAZE_STATE_DIR": str(home / "state")}


def run(args: list[str], env: dict[str, str]) -> Run:
    """Run ``seahaze render ARGS`` and measure its wall time and peak resident memory."""
    start = time.perf_counter()
    process = subprocess.Popen(
        [*SEAHAZE, "render", *args, "--quiet"],
        env=env,
        cwd=ROOT,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    stderr = process.stderr.read() if process.stderr else ""
    _, status, usage = os.wait4(process.pid, 0)
    seconds = time.perf_counter() - start
    process.returncode = os.waitstatus_to_exitcode(status)
    return Run(process.returncode, seconds, usage.ru_maxrss * 1024, stderr)


def estimate(args: list[str], env: dict[str, str]) -> dict:
    out = subprocess.run(
        [*SEAHAZE, "render", *args, "--estimate"],
        env=env,
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(out.stdout)


def fit_memory(home: Path, work: Path) -> dict[str, tuple[float, float, float]]:
    """Per mode: (base, per_pixel, per_image) bytes from four renders' peak memory."""
    env = environment(home)
    fits = {}
    for mode in ("physical", "reference", "asm"):
        rows, peaks = [], []
        for res in ("1024x576", "2048x1152"):  # the sizes where memory matters
            for vis in ("1000", "300..4000"):
                width, height = (int(x) for x in res.split("x"))
                images = 2 if vis == "1000" else 12
                args = ["--res", res, "--spp", "1", "--mode", mode, "--vis", vis]
                done = run([*args, "--out", str(work / f"mem-{mode}-{res}-{images}")], env)
                assert done.code == 0, done.stderr
                rows.append([1.0, width * height, width * height * images])
                peaks.append(done.peak_bytes)
                print(f"  memory {mode} {res} {images} images: {done.peak_bytes / 2**20:.0f} MiB")
        (base, per_pixel, per_image), *_ = np.linalg.lstsq(np.array(rows), np.array(peaks))
        fits[mode] = (float(base), float(per_pixel), float(per_image))
    return fits


def fit_compile(work: Path) -> tuple[dict[str, tuple[float, float]], float]:
    """Per mode: (wall seconds compiling a new kind, compiling a new size of a known kind),
    and the start-up (a 96×54 render's warm wall time less its estimated render)."""
    compile_s, startup = {}, []
    for mode in ("physical", "reference", "asm"):
        with tempfile.TemporaryDirectory(dir=work) as home:
            env = environment(Path(home))
            common = ["--mode", mode, "--vis", "300..4000"]
            first = ["--res", "96x54", "--spp", "2", *common]
            other = ["--res", "128x72", "--spp", "6", *common]  # another size and spp
            cold = run([*first, "--out", f"{home}/a"], env).seconds
            warm = run([*first, "--out", f"{home}/b"], env).seconds
            new_size = run([*other, "--out", f"{home}/c"], env).seconds
            warm_other = run([*other, "--out", f"{home}/d"], env).seconds
            # A new size recompiles part of what a new kind compiles: noise aside, no more.
            full = max(cold - warm, 0.0)
            compile_s[mode] = (full, min(max(new_size - warm_other, 0.0), full))
            # The warm render's estimate holds no compiling: what it misses is the start-up.
            rendered = estimate([*first, "--out", f"{home}/e"], env)["seconds"] - STARTUP_S
            startup.append(warm - rendered)
            print(
                f"  compile {mode}: cold {cold:.1f} s, warm {warm:.1f} s, new size {new_size:.1f} s"
            )
    return compile_s, float(np.median(startup))


def fit(work: Path) -> None:
    memory = fit_memory(Path(tempfile.mkdtemp(dir=work)), work)
    compile_s, startup = fit_compile(work)
    print("# measured by scripts/measure_estimates.py --fit")
    for name, column, form in (
        ("BASE_BYTES", 0, "{:.3g}"),
        ("BYTES_PER_PIXEL", 1, "{:.0f}.0"),
        ("BYTES_PER_PIXEL_IMAGE", 2, "{:.0f}.0"),
    ):
        values = ", ".join(f"{mode!r}: {form.format(m[column])}" for mode, m in memory.items())
        print(f"{name} = {{{values}}}")
    print(f"STARTUP_S = {startup:.1f}")
    print(f"COMPILE_S = {{{', '.join(f'{m!r}: {c:.1f}' for m, (c, _) in compile_s.items())}}}")
    print(f"RECOMPILE_S = {{{', '.join(f'{m!r}: {r:.1f}' for m, (_, r) in compile_s.items())}}}")


def check(work: Path, only: str | None) -> None:
    home = work / "home"
    home.mkdir()
    env = environment(home)
    started = time.time()
    rows = []
    for i, item in enumerate(CHECKS):
        if only and only not in item.label:
            continue
        args = [*item.args, "--out", str(work / f"out{i}")]
        guess = estimate(args, env)
        if item.run:
            done = run(args, env)
            if done.code != 0:
                raise SystemExit(f"{item.label}: exit {done.code}\n{done.stderr}")
        else:
            done = run(args, env)  # without --yes: the gate must stop it at once
            assert done.code == 2 and "--yes" in done.stderr, done.stderr
        rows.append((item, guess, done))
        print(f"  {item.label}: {guess} -> {done.seconds:.1f} s, {done.peak_bytes / 2**30:.2f} GiB")
    write_table(rows, time.time() - started)


def write_table(rows: list[tuple[Check, dict, Run]], seconds: float) -> None:
    lines = [
        "| configuration (default scene, 11 levels, `physical` unless said) | estimated time "
        "(of which compiling) | measured time | ratio | estimated memory | measured peak | "
        "ratio |",
        "|---|---|---|---|---|---|---|",
    ]
    for item, guess, done in rows:
        peak = guess["peak_bytes"] / 2**30
        if not item.run:
            lines.append(
                f"| {item.label} | {guess['seconds']:.0f} s ({guess['compile_seconds']:.0f} s) | "
                f"stopped by the memory gate in {done.seconds:.1f} s (exit 2, `--yes` asked) | | "
                f"{peak:.1f} GiB | not run: more than this machine's memory | |"
            )
            continue
        time_ratio = done.seconds / guess["seconds"]
        memory_ratio = done.peak_bytes / guess["peak_bytes"]
        lines.append(
            f"| {item.label} | {guess['seconds']:.0f} s ({guess['compile_seconds']:.0f} s) | "
            f"{done.seconds:.0f} s | {time_ratio:.2f} | {peak:.2f} GiB | "
            f"{done.peak_bytes / 2**30:.2f} GiB | {memory_ratio:.2f} |"
        )
    cores = len(os.sched_getaffinity(0))
    memory = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30
    body = "\n".join(
        [
            f"Measured on {platform.machine()}, {cores} vCPU, {memory:.1f} GiB, `llvm_ad_rgb`, "
            f"in one run of {seconds / 60:.0f} min by `scripts/measure_estimates.py`, in this "
            "order, sharing one kernel cache that starts empty; ratio = measured / estimated.",
            "",
            *lines,
        ]
    )
    replace_section("estimates", body, "scripts/measure_estimates.py", LIMITS_DOC)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fit", action="store_true", help="measure and print the constants")
    parser.add_argument("--only", metavar="TEXT", help="check only configurations named so")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="seahaze-estimates-") as tmp:
        if args.fit:
            fit(Path(tmp))
        else:
            check(Path(tmp), args.only)


if __name__ == "__main__":
    main()
