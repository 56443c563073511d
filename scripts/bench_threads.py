"""Benchmark how a render slows down on a loaded machine, with drjit's default thread count and
with fewer threads, and write the "threads" section of docs/benchmarks.md (issue #33).

A small render of the default scene (``--res 320x180 --spp 16 --vis 1000``, kernels compiled
beforehand) runs as a fresh ``seahaze render`` process on an idle machine and beside 1 and 2
busy processes this script starts (each a Python loop spinning on one CPU), once with the
default thread count (the CPUs this process may use, :func:`seahaze.cpus.usable_cpus`) and
once with ``--threads 1``, in rounds that alternate the order. Each run records the process's
wall time, the scene's own time from the render's JSON-lines log, the CPU time of the render
process (user + system, from ``wait4``) and of the busy processes, and the machine's CPU time
from ``/proc/stat``: what is left is other work on the machine (other engineers' renders), and
its steal time (the hypervisor giving the vCPUs to other machines).

Usage: python scripts/bench_threads.py [--rounds 3] [--busy 0,1,2]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_passes import replace_section  # noqa: E402
from seahaze.cpus import cpu_budget  # noqa: E402

SCENE = ROOT / "scenes" / "default.yaml"
RENDER_ARGS = ["--res", "320x180", "--spp", "16", "--vis", "1000"]
TICKS = os.sysconf("SC_CLK_TCK")
SPIN = "while True: pass"
"""A busy process: one CPU kept busy until killed."""


@dataclass
class Run:
    """One render: its load, thread setting and what was measured."""

    busy: int
    threads: str
    wall_s: float
    scene_s: float
    cpu_s: float
    busy_cpu_s: float
    machine_busy_s: float
    steal_s: float
    involuntary_switches: int
    load_before: float

    @property
    def others_cpu(self) -> float:
        """CPUs' worth of other work on the machine during the run (neither the render nor
        this script's busy processes)."""
        return max(0.0, self.machine_busy_s - self.cpu_s - self.busy_cpu_s) / self.wall_s


def machine_times() -> tuple[float, float]:
    """The machine's busy and steal CPU seconds since boot, all CPUs (``/proc/stat``)."""
    fields = [int(x) for x in Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:]]
    user, nice, system, _idle, _iowait, irq, softirq, steal = fields[:8]
    return (user + nice + system + irq + softirq) / TICKS, steal / TICKS


def process_cpu(pid: int) -> float:
    """CPU seconds (user + system) a running process has used (``/proc/PID/stat``)."""
    stat = Path(f"/proc/{pid}/stat").read_text()
    fields = stat.rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICKS


def start_busy(count: int) -> list[subprocess.Popen]:
    """``count`` processes that each keep one CPU busy, given a second to start spinning."""
    procs = [subprocess.Popen([sys.executable, "-c", SPIN]) for _ in range(count)]
    time.sleep(1.0 if procs else 0.0)
    return procs


def stop_busy(procs: list[subprocess.Popen]) -> None:
    """Kill the busy processes this script started, each by its own id."""
    for proc in procs:
        proc.kill()
        proc.wait()


def render_once(busy: list[subprocess.Popen], threads: str, work: Path) -> Run:
    """One fresh ``seahaze render`` process into an empty folder beside ``busy``."""
    out = Path(tempfile.mkdtemp(dir=work))
    log = out.with_suffix(".jsonl")
    command = [sys.executable, "-m", "seahaze.cli", "render", str(SCENE), *RENDER_ARGS]
    command += ["--out", str(out), "--quiet", "--log", str(log)]
    if threads != "default":
        command += ["--threads", threads]
    load_before = os.getloadavg()[0]
    busy_before = sum(process_cpu(p.pid) for p in busy)
    machine_before, steal_before = machine_times()
    start = time.perf_counter()
    proc = subprocess.Popen(command, stdout=subprocess.DEVNULL)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - start
    machine_after, steal_after = machine_times()
    if os.waitstatus_to_exitcode(status) != 0:
        raise RuntimeError(f"render failed: {' '.join(command)}")
    records = [json.loads(line) for line in log.read_text().splitlines()]
    scene = next(r["seconds"] for r in records if r["event"] == "scene_done")
    return Run(
        busy=len(busy),
        threads=threads,
        wall_s=wall,
        scene_s=scene,
        cpu_s=usage.ru_utime + usage.ru_stime,
        busy_cpu_s=sum(process_cpu(p.pid) for p in busy) - busy_before,
        machine_busy_s=machine_after - machine_before,
        steal_s=steal_after - steal_before,
        involuntary_switches=usage.ru_nivcsw,
        load_before=load_before,
    )


def measure(rounds: int, loads: list[int], settings: list[str], work: Path) -> list[Run]:
    """Every (load, threads) pair ``rounds`` times; the thread settings alternate their order
    from round to round, so a drift in the machine's other load does not favour one."""
    runs: list[Run] = []
    for index in range(rounds):
        for busy_count in loads:
            busy = start_busy(busy_count)
            try:
                order = settings if index % 2 == 0 else settings[::-1]
                for threads in order:
                    run = render_once(busy, threads, work)
                    runs.append(run)
                    print(
                        f"round {index + 1}: {busy_count} busy, threads {threads}: wall "
                        f"{run.wall_s:.2f} s, scene {run.scene_s:.2f} s, CPU {run.cpu_s:.2f} s, "
                        f"others {run.others_cpu:.2f} CPU, steal {run.steal_s:.2f} s",
                        file=sys.stderr,
                        flush=True,
                    )
            finally:
                stop_busy(busy)
    return runs


def median(runs: list[Run], attr: str) -> float:
    """The median of ``attr`` over ``runs``."""
    return statistics.median(getattr(r, attr) for r in runs)


def table(runs: list[Run], loads: list[int], settings: list[str]) -> list[str]:
    """The section's table: one row per (busy processes, threads), medians over the rounds."""
    idle = [r for r in runs if r.busy == 0 and r.threads == "default"]
    idle_scene, idle_cpu = median(idle, "scene_s"), median(idle, "cpu_s")
    lines = [
        "| busy processes | threads | runs | wall (s) | scene (s) | scene × no busy | "
        "render CPU (s) | CPU × no busy | CPUs it got | others' work (CPUs) | load average | "
        "involuntary switches |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for busy in loads:
        for threads in settings:
            rows = [r for r in runs if r.busy == busy and r.threads == threads]
            count = cpu_budget().usable if threads == "default" else int(threads)
            label = f"{count} (default)" if threads == "default" else f"{count} (`--threads`)"
            wall = median(rows, "wall_s")
            scene, cpu = median(rows, "scene_s"), median(rows, "cpu_s")
            lines.append(
                f"| {busy} | {label} | {len(rows)} | {wall:.2f} | {scene:.2f} | "
                f"{scene / idle_scene:.2f} | {cpu:.2f} | {cpu / idle_cpu:.2f} | "
                f"{cpu / wall:.2f} | {median(rows, 'others_cpu'):.2f} | "
                f"{median(rows, 'load_before'):.1f} | {int(median(rows, 'involuntary_switches'))} |"
            )
    return lines


def session_share(count: int = 2, seconds: float = 5.0) -> tuple[float, float]:
    """CPUs that ``count`` busy processes of this session get together, and CPUs the
    machine's other work takes meanwhile, over ``seconds``. Linux's autogroups
    (``/proc/sys/kernel/sched_autogroup_enabled``) share the CPUs between sessions first,
    then among a session's threads: a session's processes together get its group's share."""
    busy = start_busy(count)
    try:
        before, (machine_before, _) = sum(process_cpu(p.pid) for p in busy), machine_times()
        time.sleep(seconds)
        after, (machine_after, _) = sum(process_cpu(p.pid) for p in busy), machine_times()
    finally:
        stop_busy(busy)
    got = (after - before) / seconds
    return got, max(0.0, (machine_after - machine_before) / seconds - got)


def write_section(
    runs: list[Run],
    loads: list[int],
    settings: list[str],
    seconds: float,
    share: tuple[float, float],
) -> None:
    """Write the table of ``runs`` into docs/benchmarks.md; ``share``: :func:`session_share`."""
    budget = cpu_budget()
    steal = sum(r.steal_s for r in runs) / sum(r.wall_s for r in runs)
    lines = [
        "## Renders beside busy processes (scripts/bench_threads.py)",
        "",
        f"Machine: {platform.machine()}, {os.cpu_count()} vCPU, this process "
        f"{budget.describe()}; variant `llvm_ad_rgb`; `{SCENE.relative_to(ROOT)}` "
        f"{' '.join(RENDER_ARGS)}, kernels compiled beforehand. Each row: the median of "
        f"{len(runs) // (len(loads) * len(settings))} fresh `seahaze render` processes; the "
        f"benchmark took {seconds / 60:.1f} min. Scene: the render's own time (the log's "
        "`seconds`, without start-up); × no busy: over the first row; render CPU: user + "
        "system time of the render process (above 1× no busy: work the load added, such as "
        "spinning threads or kernels compiled again); CPUs it got: render CPU over wall; "
        "others' work: the machine's CPU time during the run that was neither the render nor "
        "the busy processes (other engineers' renders), in CPUs; load average: 1 minute, "
        f"before the run. Steal time: {steal:.2f} CPU on average. Before the "
        f"renders, 2 busy processes of this session got {share[0]:.2f} CPUs together while "
        f"the machine's other work took {share[1]:.2f} (sessions share the CPUs first: "
        "autogroups).",
        "",
        *table(runs, loads, settings),
    ]
    replace_section("threads", "\n".join(lines), "scripts/bench_threads.py")


def warm_up(settings: list[str], work: Path) -> None:
    """Compile each thread setting's kernels once (one thread compiles its own reduction
    kernels), so no measured run compiles."""
    for threads in settings:
        render_once([], threads, work)


def main() -> int:
    # A SIGTERM runs the finally blocks too: the busy processes never outlive the script.
    signal.signal(signal.SIGTERM, lambda _signum, _frame: sys.exit(143))
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--busy", default="0,1,2", help="busy-process counts, comma-separated")
    parser.add_argument("--no-write", action="store_true", help="print, do not touch the docs")
    args = parser.parse_args()
    loads = [int(x) for x in args.busy.split(",")]
    settings = ["default", "1"]
    start = time.perf_counter()
    share = session_share()
    with tempfile.TemporaryDirectory(prefix="seahaze-threads-") as tmp:
        warm_up(settings, Path(tmp))
        runs = measure(args.rounds, loads, settings, Path(tmp))
    seconds = time.perf_counter() - start
    print("\n".join(table(runs, loads, settings)))
    if not args.no_write:
        write_section(runs, loads, settings, seconds, share)
    return 0


if __name__ == "__main__":
    sys.exit(main())
