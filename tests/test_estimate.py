"""The job estimate: memory by image size and levels, compilation by what this machine has
compiled, the gate, and ``seahaze render --estimate`` (issue #36).

The estimate's accuracy against real runs (within 1.5× from 64×36 to 8192×4608 and 1 to
65536 spp) is a benchmark, ``scripts/measure_estimates.py`` (docs/limits.md), not a test: the
machines are noisy. These tests hold its arithmetic and its plumbing.
"""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

import pytest

from seahaze.cli import limits, main
from seahaze.sceneio import parse_scene_text
from seahaze.spec import with_overrides

GIB = 2**30


def spec_of(width: int = 64, height: int = 36, spp: int = 1, levels=None, mode="physical"):
    spec = parse_scene_text("camera: {height_m: 10}\n", "s.yaml")
    return with_overrides(spec, resolution=(width, height), spp=spp, levels=levels, mode=mode)


def run(args: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(args)
    return code, out.getvalue(), err.getvalue()


def test_memory_grows_with_pixels_and_images_by_the_fitted_constants():
    small, large = spec_of(1000, 1000), spec_of(2000, 1000)
    images = len(small.haze.levels) + 1
    per_pixel = (
        limits.BYTES_PER_PIXEL["physical"] + images * limits.BYTES_PER_PIXEL_IMAGE["physical"]
    )
    assert limits.scene_bytes(large) - limits.scene_bytes(small) == pytest.approx(
        1e6 * per_pixel, rel=1e-9
    )
    one_level = spec_of(1000, 1000, levels=[1000.0])
    assert limits.scene_bytes(small) - limits.scene_bytes(one_level) == pytest.approx(
        1e6 * (images - 2) * limits.BYTES_PER_PIXEL_IMAGE["physical"], rel=1e-9
    )


def test_an_8192_square_job_needs_yes_on_a_24_gib_machine():
    job = limits.estimate([(spec_of(8192, 8192), 1)], limits.KernelRecord())
    assert job.scene_bytes > 0.8 * 24 * GIB
    reason = limits.confirmation_needed(job, memory=24 * GIB)
    assert reason is not None and "one scene needs about" in reason and "24.0 GiB" in reason
    assert limits.confirmation_needed(job, memory=1024 * GIB) is None  # it is fast enough


def test_scenes_rendered_at_once_add_their_memory():
    spec = spec_of(2048, 1152)
    one = limits.estimate([(spec, 8)], limits.KernelRecord())
    four = limits.estimate([(spec, 8)], limits.KernelRecord(), at_once=4)
    assert four.peak_bytes == 4 * one.scene_bytes
    # One process writes a scene while the next renders: its 12 images at 81 B a pixel each
    # are held meanwhile (a single scene holds nothing more).
    held = 2048 * 1152 * 12 * 81
    assert one.peak_bytes == one.scene_bytes + held
    assert limits.estimate([(spec, 1)], limits.KernelRecord()).peak_bytes == one.scene_bytes
    reason = limits.confirmation_needed(one, memory=int(one.peak_bytes / 0.8) - 1)
    assert reason is not None and reason.startswith("one scene with the last one's images")
    assert limits.estimate([(spec, 2)], limits.KernelRecord(), at_once=4).peak_bytes == (
        2 * one.scene_bytes
    )
    needed = four.peak_bytes
    reason = limits.confirmation_needed(four, memory=int(needed / 0.8) - 1)
    assert reason is not None and reason.startswith("the scenes rendered at once need")


def test_compilation_is_counted_for_what_this_machine_has_not_compiled():
    first, bigger = spec_of(64, 36), spec_of(128, 72)
    other_kind = spec_of(64, 36, levels=[1000.0])
    empty = limits.KernelRecord()
    assert empty.compile_seconds([first]) == limits.COMPILE_S["physical"]
    # A second size of the same kind in the same job recompiles only what bakes in the size.
    assert empty.compile_seconds([first, bigger]) == (
        limits.COMPILE_S["physical"] + limits.RECOMPILE_S["physical"]
    )
    known = limits.KernelRecord([limits.kernel_key(first)])
    assert known.compile_seconds([first]) == 0.0
    assert known.compile_seconds([bigger]) == limits.RECOMPILE_S["physical"]
    assert known.compile_seconds([other_kind]) == limits.COMPILE_S["physical"]
    cold = limits.estimate([(first, 1)], empty)
    warm = limits.estimate([(first, 1)], known)
    assert cold.seconds - warm.seconds == pytest.approx(limits.COMPILE_S["physical"])
    assert cold.compile_seconds == limits.COMPILE_S["physical"] and warm.compile_seconds == 0


def test_the_kernel_record_survives_a_restart_and_ignores_damage(seahaze_state):
    spec = spec_of()
    limits.KernelRecord.load().remember([spec])
    assert limits.KernelRecord.load().compile_seconds([spec]) == 0.0
    path = limits.KernelRecord.path()
    for damage in (b"", b"[" * 100_000, b'{"kernels": 5}', bytes(range(256))):
        path.write_bytes(damage)
        assert limits.KernelRecord.load().keys == []  # a hint only: damage means "cold"
    record = limits.KernelRecord([f"k{i}" for i in range(limits.MAX_KERNEL_RECORDS)])
    record.remember([spec])
    assert len(record.keys) == limits.MAX_KERNEL_RECORDS and record.keys[0] == "k1"
    assert limits.KernelRecord.load().keys[-1] == limits.kernel_key(spec)


def test_estimate_flag_prints_json_and_touches_nothing(tmp_path: Path):
    out = tmp_path / "out"
    code, stdout, err = run(
        ["render", "--res", "64x36", "--spp", "2", "--out", str(out), "--estimate"]
    )
    assert code == 0, err
    record = json.loads(stdout)
    assert set(record) == {
        "scenes",
        "seconds",
        "compile_seconds",
        "scene_bytes",
        "peak_bytes",
        "needs_yes",
    }
    assert record["scenes"] == 1 and record["needs_yes"] is None
    assert record["compile_seconds"] == limits.COMPILE_S["physical"]  # a fresh state folder
    assert not out.exists()
    code, stdout, _ = run(["render", "--res", "8192x8192", "--out", str(out), "--estimate"])
    gate = json.loads(stdout)["needs_yes"]
    memory = limits.total_memory()
    if memory and json.loads(stdout)["peak_bytes"] > 0.8 * memory:
        assert "memory" in gate
    assert code == 0 and not out.exists()


def test_a_render_is_remembered_so_its_next_estimate_compiles_nothing(tmp_path: Path):
    args = ["render", "--res", "32x18", "--spp", "1", "--vis", "1000", "--quiet"]
    before = json.loads(run([*args, "--out", str(tmp_path / "a"), "--estimate"])[1])
    assert before["compile_seconds"] == limits.COMPILE_S["physical"]
    code, _, err = run([*args, "--out", str(tmp_path / "a")])
    assert code == 0, err
    after = json.loads(run([*args, "--out", str(tmp_path / "b"), "--estimate"])[1])
    assert after["compile_seconds"] == 0.0
    assert before["seconds"] - after["seconds"] == pytest.approx(before["compile_seconds"])
    bigger = json.loads(
        run([*args, "--res", "64x36", "--out", str(tmp_path / "c"), "--estimate"])[1]
    )
    assert bigger["compile_seconds"] == limits.RECOMPILE_S["physical"]
