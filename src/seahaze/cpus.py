"""How many CPUs this process may use, and the render threads that follow from it.

Two things bound it, and the smaller wins (at least 1):

- **Affinity**: the CPUs the scheduler may run this process on (``os.sched_getaffinity``;
  ``taskset``, ``docker --cpuset-cpus``, SLURM's ``--cpus-per-task``).
- **A cgroup CPU quota**: a group's processes may run ``quota`` µs of CPU time in every
  ``period`` µs, ``quota / period`` CPUs' worth, and are throttled for the rest of the period
  beyond it (``docker --cpus``, Kubernetes CPU limits). cgroup v2 keeps it in ``cpu.max`` as
  ``"$MAX $PERIOD"`` in µs, ``max`` for no limit (the Linux kernel's
  Documentation/admin-guide/cgroup-v2.rst, "CPU Interface Files"); cgroup v1 in
  ``cpu.cfs_quota_us`` (−1: no limit) and ``cpu.cfs_period_us``
  (Documentation/scheduler/sched-bwc.rst). A limit set on an ancestor group binds too, so the
  group's folder and every folder above it up to the mount are read.

A quota of 1.5 CPUs gives 1 thread, not 2: threads that together use more than the quota are
throttled for the rest of each period, and a kernel of drjit's waits at its end for its last
thread. The load other processes put on a shared machine is not counted: it changes by the
second, Linux shares the CPUs between sessions first (autogroups) and then among a session's
threads, and on a loaded 2-vCPU machine a render at 1 thread was no faster than at 2, its CPU
time the same (docs/benchmarks.md, "How does a render slow down on a loaded machine?").
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

CGROUP_ROOT = Path("/sys/fs/cgroup")
"""Where the cgroup file systems are mounted: the v2 hierarchy itself, or one folder per v1
controller (``cpu``, ``cpu,cpuacct``) beside ``unified``."""
SELF_CGROUP = Path("/proc/self/cgroup")
"""This process's groups, one line per hierarchy: ``ID:CONTROLLERS:PATH`` (v2: ``0::PATH``)."""
V1_CPU_MOUNTS = ("cpu", "cpu,cpuacct", "cpuacct,cpu")
"""Folders under :data:`CGROUP_ROOT` where cgroup v1 mounts its ``cpu`` controller."""
MAX_THREADS_PER_CPU = 4
"""``--threads`` accepts at most this many threads per CPU of the machine: more only adds
threads that wait for one another."""


@dataclass(frozen=True)
class CpuBudget:
    """The CPUs this process may use and where the bound comes from."""

    affinity: int
    """CPUs in this process's affinity mask."""
    quota: float | None
    """CPUs' worth of time the tightest cgroup quota allows (``quota / period``); None: none."""

    @property
    def usable(self) -> int:
        """Whole CPUs this process may keep busy: the smaller bound, at least 1."""
        if self.quota is None:
            return max(1, self.affinity)
        return max(1, min(self.affinity, math.floor(self.quota)))

    def describe(self) -> str:
        """One phrase for messages and benchmark notes, e.g. ``2 CPU(s) (affinity 2, no cgroup
        quota)``."""
        quota = "no cgroup quota" if self.quota is None else f"cgroup quota {self.quota:g} CPU"
        return f"{self.usable} CPU(s) (affinity {self.affinity}, {quota})"


def affinity_cpus() -> int:
    """CPUs in this process's affinity mask; the machine's count where the system has no
    affinity call (macOS, Windows); at least 1."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return max(1, os.cpu_count() or 1)


def cpu_budget(root: Path = CGROUP_ROOT, membership: Path = SELF_CGROUP) -> CpuBudget:
    """This process's :class:`CpuBudget`: its affinity and the tightest cgroup quota found
    under ``root`` for the groups that ``membership`` (``/proc/self/cgroup``) lists."""
    return CpuBudget(affinity_cpus(), cgroup_cpu_quota(root, membership))


def usable_cpus(root: Path = CGROUP_ROOT, membership: Path = SELF_CGROUP) -> int:
    """Whole CPUs this process may use: its affinity and its cgroup quota, the smaller, at
    least 1 (see the module docstring)."""
    return cpu_budget(root, membership).usable


def cgroup_cpu_quota(root: Path = CGROUP_ROOT, membership: Path = SELF_CGROUP) -> float | None:
    """The tightest CPU quota of this process's cgroups and their ancestors, in CPUs
    (``quota / period``), from cgroup v2 and v1 files under ``root``; None where no group
    limits it (or the files are absent or unreadable)."""
    paths = _group_paths(membership)
    quotas = [q for folder in _quota_folders(root, paths) if (q := _folder_quota(folder))]
    return min(quotas) if quotas else None


def _group_paths(membership: Path) -> dict[str, str]:
    """This process's group path per hierarchy: ``"v2"`` and ``"cpu"`` (v1's ``cpu``
    controller); ``/`` for a hierarchy not listed (a cgroup namespace shows its root so)."""
    paths = {"v2": "/", "cpu": "/"}
    try:
        lines = membership.read_text().splitlines()
    except OSError:
        return paths
    for line in lines:
        parts = line.split(":", 2)
        if len(parts) != 3:
            continue
        _, controllers, path = parts
        if controllers == "":
            paths["v2"] = path or "/"
        elif "cpu" in controllers.split(","):
            paths["cpu"] = path or "/"
    return paths


def _quota_folders(root: Path, paths: dict[str, str]) -> Iterator[Path]:
    """Every folder whose quota binds this process: its group's in each hierarchy and all
    above it up to the mount. A group path that does not exist under the mount (a container
    sees its own group as the mount's root) still yields the mount itself."""
    mounts = [(root, paths["v2"]), (root / "unified", paths["v2"])]
    mounts += [(root / name, paths["cpu"]) for name in V1_CPU_MOUNTS]
    for mount, path in mounts:
        folder = mount / path.strip("/")
        yield folder
        while folder != mount:
            folder = folder.parent
            yield folder


def _folder_quota(folder: Path) -> float | None:
    """The quota of one group folder in CPUs: its v2 ``cpu.max`` or its v1
    ``cpu.cfs_quota_us`` / ``cpu.cfs_period_us``; None for no limit or no readable file."""
    v2 = _read(folder / "cpu.max")
    if v2 is not None:
        fields = v2.split()
        return _ratio(fields[0], fields[1] if len(fields) > 1 else "100000")
    quota = _read(folder / "cpu.cfs_quota_us")
    period = _read(folder / "cpu.cfs_period_us")
    if quota is None or period is None:
        return None
    return _ratio(quota, period)


def _ratio(quota: str, period: str) -> float | None:
    """``quota / period`` for two µs values; None for ``max``, −1 or anything not positive."""
    try:
        q, p = int(quota), int(period)
    except ValueError:  # "max" (v2's no limit) or a damaged file
        return None
    return q / p if q > 0 and p > 0 else None


def _read(path: Path) -> str | None:
    """A small text file's stripped content, None where it is absent or unreadable."""
    try:
        return path.read_text().strip() or None
    except OSError:
        return None


def max_threads() -> int:
    """Most render threads ``--threads`` accepts: :data:`MAX_THREADS_PER_CPU` per CPU of the
    machine (``os.cpu_count()``, not the affinity: a user may mean the whole machine)."""
    return MAX_THREADS_PER_CPU * (os.cpu_count() or 1)


def parse_threads(text: str) -> int:
    """``--threads`` text as a thread count, or ``ValueError`` whose message says the allowed
    values (the flag's name is the caller's to add)."""
    most = max_threads()
    allowed = (
        f"must be an integer within 1..{most} (render threads; default: the "
        f"{usable_cpus()} CPU(s) this process may use)"
    )
    try:
        threads = int(text.strip())
    except ValueError:
        raise ValueError(allowed) from None
    if not 1 <= threads <= most:
        raise ValueError(allowed)
    return threads


@contextmanager
def render_threads(threads: int | None) -> Iterator[int]:
    """Run the block with drjit's LLVM thread pool at ``threads`` (None: :func:`usable_cpus`)
    and put the pool's size back after it; yields the count used.

    drjit sizes its pool by the machine's cores, not by affinity or quota, and a kernel waits
    at its end for its slowest thread: more threads than CPUs leave it waiting on threads the
    scheduler has put aside. drjit's LLVM backend needs not be started yet (the pool is
    resized, libLLVM not loaded). One thread compiles the kernels that reduce into per-thread
    copies (the photon tracer's tallies) once more: with one thread drjit writes them straight
    into the array, another kernel (any two counts above 1 share one; both kept in drjit's
    disk cache)."""
    import drjit as dr

    count = threads if threads is not None else usable_cpus()
    before = dr.thread_count()
    dr.set_thread_count(count)
    try:
        yield count
    finally:
        dr.set_thread_count(before)
