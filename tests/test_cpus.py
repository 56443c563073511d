"""The CPUs a process may use (issue #33): affinity and cgroup quota read from fake cgroup
folders, the ``--threads`` flag's bad values, threads shared by workers, and the same bytes
whatever the thread count."""

from __future__ import annotations

import math
import os
from pathlib import Path

import pytest

from conftest import cli_run
from seahaze.batch.executors import threads_per_worker
from seahaze.cpus import (
    CpuBudget,
    affinity_cpus,
    cgroup_cpu_quota,
    cpu_budget,
    max_threads,
    parse_threads,
    render_threads,
    usable_cpus,
)

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_SCENE = ROOT / "scenes" / "default.yaml"
AFFINITY = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()


def fake_cgroups(tmp_path: Path, files: dict[str, str], membership: str = "0::/\n") -> Path:
    """A cgroup mount under ``tmp_path/cgroup`` holding ``files`` (path → content), and the
    ``/proc/self/cgroup`` that places this process in it; returns the membership file."""
    for name, content in files.items():
        path = tmp_path / "cgroup" / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(content)
    (tmp_path / "cgroup").mkdir(exist_ok=True)
    self_cgroup = tmp_path / "self_cgroup"
    self_cgroup.write_text(membership)
    return self_cgroup


def quota_of(tmp_path: Path, files: dict[str, str], membership: str = "0::/\n") -> float | None:
    self_cgroup = fake_cgroups(tmp_path, files, membership)
    return cgroup_cpu_quota(tmp_path / "cgroup", self_cgroup)


def usable_of(tmp_path: Path, files: dict[str, str], membership: str = "0::/\n") -> int:
    self_cgroup = fake_cgroups(tmp_path, files, membership)
    return usable_cpus(tmp_path / "cgroup", self_cgroup)


# --------------------------------------------------------------------------------------------
# cgroup v2: cpu.max is "$MAX $PERIOD" in µs


def test_v2_no_limit_leaves_the_affinity(tmp_path):
    files = {"cpu.max": "max 100000\n"}
    assert quota_of(tmp_path, files) is None
    assert usable_of(tmp_path, files) == AFFINITY


def test_v2_quota_of_two_cpus(tmp_path):
    assert quota_of(tmp_path, {"cpu.max": "200000 100000\n"}) == 2.0
    assert usable_of(tmp_path, {"cpu.max": "200000 100000\n"}) == min(AFFINITY, 2)


def test_v2_half_a_cpu_still_gives_one(tmp_path):
    assert quota_of(tmp_path, {"cpu.max": "50000 100000\n"}) == 0.5
    assert usable_of(tmp_path, {"cpu.max": "50000 100000\n"}) == 1


def test_v2_fraction_rounds_down(tmp_path):
    assert quota_of(tmp_path, {"cpu.max": "150000 100000\n"}) == 1.5
    assert usable_of(tmp_path, {"cpu.max": "150000 100000\n"}) == 1


def test_v2_quota_larger_than_the_affinity_leaves_the_affinity(tmp_path):
    assert usable_of(tmp_path, {"cpu.max": "6400000 100000\n"}) == AFFINITY


def test_v2_other_period(tmp_path):
    assert quota_of(tmp_path, {"cpu.max": "75000 50000\n"}) == 1.5


def test_v2_an_ancestor_group_binds(tmp_path):
    files = {"job/cpu.max": "100000 100000\n", "job/step/cpu.max": "max 100000\n"}
    assert quota_of(tmp_path, files, "0::/job/step\n") == 1.0


def test_v2_the_tighter_of_group_and_ancestor(tmp_path):
    files = {"job/cpu.max": "400000 100000\n", "job/step/cpu.max": "300000 100000\n"}
    assert quota_of(tmp_path, files, "0::/job/step\n") == 3.0


def test_v2_group_path_outside_the_mount_reads_the_mount(tmp_path):
    # A container without a cgroup namespace lists the host's path; its mount is its group.
    files = {"cpu.max": "300000 100000\n"}
    assert quota_of(tmp_path, files, "0::/docker/0123abcd\n") == 3.0


def test_v2_a_sibling_group_does_not_bind(tmp_path):
    files = {"other/cpu.max": "100000 100000\n", "mine/cpu.max": "max 100000\n"}
    assert quota_of(tmp_path, files, "0::/mine\n") is None


# --------------------------------------------------------------------------------------------
# cgroup v1: cpu.cfs_quota_us (-1: no limit) over cpu.cfs_period_us


def test_v1_no_limit(tmp_path):
    files = {"cpu/cpu.cfs_quota_us": "-1\n", "cpu/cpu.cfs_period_us": "100000\n"}
    assert quota_of(tmp_path, files, "3:cpu:/\n") is None
    assert usable_of(tmp_path, files, "3:cpu:/\n") == AFFINITY


def test_v1_quota_of_one_cpu(tmp_path):
    files = {"cpu/cpu.cfs_quota_us": "100000\n", "cpu/cpu.cfs_period_us": "100000\n"}
    assert quota_of(tmp_path, files, "3:cpu:/\n") == 1.0
    assert usable_of(tmp_path, files, "3:cpu:/\n") == 1


def test_v1_joint_cpu_cpuacct_mount_and_group(tmp_path):
    files = {
        "cpu,cpuacct/slurm/job7/cpu.cfs_quota_us": "250000\n",
        "cpu,cpuacct/slurm/job7/cpu.cfs_period_us": "100000\n",
    }
    membership = "5:memory:/slurm/job7\n4:cpu,cpuacct:/slurm/job7\n0::/\n"
    assert quota_of(tmp_path, files, membership) == 2.5


def test_v1_quota_without_period_is_no_limit(tmp_path):
    assert quota_of(tmp_path, {"cpu/cpu.cfs_quota_us": "100000\n"}, "3:cpu:/\n") is None


def test_v1_and_v2_together_the_tighter_wins(tmp_path):
    files = {
        "cpu.max": "300000 100000\n",
        "cpu/cpu.cfs_quota_us": "100000\n",
        "cpu/cpu.cfs_period_us": "50000\n",
    }
    assert quota_of(tmp_path, files, "3:cpu:/\n0::/\n") == 2.0


# --------------------------------------------------------------------------------------------
# nothing to read, or something damaged: no limit, never an error


def test_no_cgroup_files(tmp_path):
    assert quota_of(tmp_path, {}) is None
    assert usable_of(tmp_path, {}) == AFFINITY


def test_no_membership_file_reads_the_mount(tmp_path):
    fake_cgroups(tmp_path, {"cpu.max": "100000 100000\n"})
    assert cgroup_cpu_quota(tmp_path / "cgroup", tmp_path / "absent") == 1.0


@pytest.mark.parametrize("content", ["", "garbage\n", "0 100000\n", "-5 100000\n", "max\n"])
def test_damaged_or_zero_cpu_max_is_no_limit(tmp_path, content):
    assert quota_of(tmp_path, {"cpu.max": content}) is None


def test_cpu_max_without_period_uses_the_kernels_default(tmp_path):
    assert quota_of(tmp_path, {"cpu.max": "200000\n"}) == 2.0


def test_budget_describes_its_bounds(tmp_path):
    self_cgroup = fake_cgroups(tmp_path, {"cpu.max": "150000 100000\n"})
    budget = cpu_budget(tmp_path / "cgroup", self_cgroup)
    assert budget == CpuBudget(AFFINITY, 1.5)
    assert budget.describe() == f"1 CPU(s) (affinity {AFFINITY}, cgroup quota 1.5 CPU)"
    assert CpuBudget(3, None).describe() == "3 CPU(s) (affinity 3, no cgroup quota)"


# --------------------------------------------------------------------------------------------
# this machine


def test_this_process_uses_at_most_its_affinity():
    assert affinity_cpus() == AFFINITY
    assert 1 <= usable_cpus() <= AFFINITY


def test_this_process_matches_its_own_quota():
    quota = cgroup_cpu_quota()
    expected = AFFINITY if quota is None else max(1, min(AFFINITY, math.floor(quota)))
    assert usable_cpus() == expected


# --------------------------------------------------------------------------------------------
# threads


def test_threads_are_shared_by_the_workers():
    assert threads_per_worker(2, 4) == 2
    assert threads_per_worker(3, 8) == 2
    assert threads_per_worker(4, 2) == 1
    assert threads_per_worker(1, 3) == 3
    assert threads_per_worker(2) == max(1, usable_cpus() // 2)


def test_parse_threads_accepts_the_range():
    assert parse_threads("1") == 1
    assert parse_threads(" 3 ") == 3
    assert parse_threads(str(max_threads())) == max_threads()
    assert max_threads() == 4 * (os.cpu_count() or 1)


@pytest.mark.parametrize("text", ["0", "-1", "1.5", "two", "", str(4 * (os.cpu_count() or 1) + 1)])
def test_parse_threads_refuses_with_the_allowed_values(text):
    with pytest.raises(ValueError, match=rf"within 1\.\.{max_threads()}"):
        parse_threads(text)


def test_render_threads_sets_and_restores_drjits_pool():
    import drjit as dr

    before = dr.thread_count()
    with render_threads(1) as used:
        assert used == 1
        assert dr.thread_count() == 1
    assert dr.thread_count() == before
    with render_threads(None) as used:
        assert used == usable_cpus()
        assert dr.thread_count() == usable_cpus()
    assert dr.thread_count() == before


# --------------------------------------------------------------------------------------------
# the flag: bad values are bad input (one line, exit 2, no traceback)

BAD_THREADS = ["0", "-1", "-3", "2.5", "many", "", "1e3", "100000"]


def assert_one_line_refusal(code: int, err: str) -> None:
    lines = [line for line in err.splitlines() if line.strip()]
    assert code == 2, err
    assert "Traceback" not in err
    assert len(lines) == 1, err
    assert lines[0].startswith("seahaze: error: --threads ")
    assert f"within 1..{max_threads()}" in lines[0]


@pytest.mark.parametrize("value", BAD_THREADS)
def test_render_refuses_bad_threads(tmp_path, value):
    code, _, err = cli_run(["render", "--threads", value, "--out", str(tmp_path / "out")])
    assert_one_line_refusal(code, err)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("value", BAD_THREADS)
def test_verify_refuses_bad_threads(tmp_path, value):
    code, _, err = cli_run(["verify", "--threads", value, "--out", str(tmp_path / "out")])
    assert_one_line_refusal(code, err)
    assert not (tmp_path / "out").exists()


def test_render_refuses_threads_for_a_dask_cluster(tmp_path):
    args = ["render", "--executor", "dask", "--scheduler", "tcp://127.0.0.1:1", "--threads", "2"]
    code, _, err = cli_run([*args, "--out", str(tmp_path / "out")])
    assert code == 2
    assert err.strip() == (
        "seahaze: error: --threads is for --executor local; a Dask worker renders with its "
        "own threads"
    )


def test_render_estimate_accepts_threads(tmp_path):
    code, out, err = cli_run(
        ["render", str(DEFAULT_SCENE), "--threads", "1", "--estimate", "--out", str(tmp_path)]
    )
    assert code == 0, err
    assert '"scenes": 1' in out


# --------------------------------------------------------------------------------------------
# the same bytes whatever the thread count


def test_one_and_two_threads_give_the_same_files(tmp_path):
    # The default scene (vessels; physical: its photon tracer reduces into per-thread copies)
    # at CI size: every image, distance and label identical.
    args = ["render", str(DEFAULT_SCENE), "--res", "160x90", "--spp", "4", "--vis", "1000"]
    trees = {}
    for threads in ("1", "2"):
        out = tmp_path / f"t{threads}"
        code, _, err = cli_run([*args, "--threads", threads, "--out", str(out), "--quiet"], 300)
        assert code == 0, err
        trees[threads] = {
            p.relative_to(out): p.read_bytes()
            for p in sorted(out.rglob("*"))
            if p.is_file() and p.suffix in (".png", ".exr", ".txt") and p.parent != out
        }
    assert len(trees["1"]) >= 8
    assert trees["1"].keys() == trees["2"].keys()
    differing = [str(name) for name in trees["1"] if trees["1"][name] != trees["2"][name]]
    assert differing == []
