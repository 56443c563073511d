"""Ctrl-C and SIGTERM stop a render busy in a long pass within seconds, and the folder resumes
to the same bytes as an uninterrupted run (issue #35).

drjit compiles and runs a pass's kernel without returning to Python; a render called from the
main thread used to ignore the signal until the pass ended (12 minutes at 2000 spp). The signal
comes a moment after the scene is loaded, while the pass compiles or runs. How soon the render
stops is checked on a one pass of about 30 s on the project's 2-vCPU machine, far longer than
the few seconds allowed. That an interrupted folder resumes to an uninterrupted run's files is
checked on a pass of about 6 s: that check does not depend on the pass's length, and it renders
the pass twice more (the resume and the uninterrupted run).
"""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from seahaze.batch import LOCK_NAME
from seahaze.fileio import read_exr

SCENE = """\
name: long
camera: {{height_m: 12, pitch_deg: -1, resolution: [{width}, {height}]}}
sea: {{quality: low, seed: 4}}
vessels:
  placed:
    - {{class: tug, distance_m: 300, bearing_deg: 3, length_m: 30}}
haze: {{levels: [1000]}}
render: {{spp: 1024, seed: 5}}
"""
EXIT_WITHIN_S = 5.0


@pytest.fixture(scope="module")
def scene(tmp_path_factory) -> Path:
    """One scene whose one pass takes about 30 s here (256×144 at 1024 spp)."""
    path = tmp_path_factory.mktemp("interrupts") / "long.yaml"
    path.write_text(SCENE.format(width=256, height=144))
    return path


@pytest.fixture(scope="module")
def small_scene(tmp_path_factory) -> Path:
    """A scene whose one pass takes about 6 s here (128×72 at 1024 spp): for the folders that
    are resumed and compared, and for two local workers."""
    path = tmp_path_factory.mktemp("interrupts_small") / "long.yaml"
    path.write_text(SCENE.format(width=128, height=72))
    return path


def _command(scene: Path, out: Path, *extra: str) -> list[str]:
    return [sys.executable, "-m", "seahaze.cli", "render", str(scene), "--out", str(out), *extra]


def _interrupt(
    command: list[str], ready: Callable[[subprocess.Popen], bool], delay_s: float, signum: int
) -> tuple[int, float]:
    """Start ``command``, wait until ``ready(process)`` and ``delay_s`` more, send
    ``signum``; its exit code and the seconds from the signal to its exit."""
    # A terminal's Ctrl-C: the child starts with the signal's default handling even when this
    # run inherited it ignored (a job started with & by a shell without job control ignores
    # SIGINT, and seahaze rightly leaves an ignored SIGINT ignored).
    process = subprocess.Popen(
        command,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signum, signal.SIG_DFL),
    )
    try:
        deadline = time.monotonic() + 120
        while not ready(process):
            assert process.poll() is None and time.monotonic() < deadline, "never got ready"
        time.sleep(delay_s)
        assert process.poll() is None, "the render ended before the signal"
        sent = time.monotonic()
        process.send_signal(signum)
        code = process.wait(timeout=120)
        return code, time.monotonic() - sent
    finally:
        process.kill()
        process.wait()


def _scene_loaded(process: subprocess.Popen) -> bool:
    """The in-process render printed that its scene is loaded: its one pass comes next."""
    assert process.stderr is not None
    return "scene loaded" in process.stderr.readline()


def _batch_started(log: Path) -> Callable[[subprocess.Popen], bool]:
    def started(_process: subprocess.Popen) -> bool:
        time.sleep(0.05)
        return log.exists() and '"event": "start"' in log.read_text()

    return started


def _statuses(out: Path) -> dict[str, str]:
    scenes = json.loads((out / "dataset.json").read_text())["scenes"]
    return {name: entry["status"] for name, entry in scenes.items()}


def _tree(root: Path) -> dict[str, bytes]:
    files = {}
    for path in sorted(root.rglob("*")):
        if path.is_file() and not path.name.startswith("."):
            data = path.read_bytes()
            files[path.relative_to(root).as_posix()] = data.replace(str(root).encode(), b"ROOT")
    return files


def _numbers_close(a: Any, b: Any, where: str) -> None:
    if isinstance(a, dict) and isinstance(b, dict):
        assert a.keys() == b.keys(), where
        for key in a:
            if key != "files_sha256":  # the hash of the EXRs below
                _numbers_close(a[key], b[key], f"{where}.{key}")
    elif isinstance(a, list) and isinstance(b, list):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _numbers_close(x, y, f"{where}[{i}]")
    elif isinstance(a, float) or isinstance(b, float):
        assert a == pytest.approx(b, rel=1e-5, abs=1e-9), where
    else:
        assert a == b, where


JSON_FROM_RADIANCE = ("meta", "dataset.json", "coco", "coco_visible")
"""Files holding numbers measured on the linear images (contrasts; COCO copies them from
meta): compared to float precision on a GPU, as the EXRs."""


def _assert_pngs_within_one_level(ours: Path, reference: Path) -> None:
    """Two PNGs of the same size whose pixels differ by at most one code value, at no more
    than 1 pixel in 1000: the quantised form of a float-precision difference."""
    from PIL import Image

    x = np.asarray(Image.open(ours), dtype=np.int64)
    y = np.asarray(Image.open(reference), dtype=np.int64)
    assert x.shape == y.shape, ours
    differ = np.abs(x - y)
    assert differ.max() <= 1 and np.mean(differ > 0) <= 1e-3, (ours, differ.max())


def _assert_same_dataset(ours: Path, reference: Path, variant: str) -> None:
    """The resumed folder holds what an uninterrupted run writes, every file byte for byte.
    Under ``cuda_ad_rgb`` the GPU adds samples into pixels in no fixed order, so two runs
    differ in the last bits of the linear EXRs (and of the numbers meta and dataset.json derive
    from them), and a PNG pixel can round one code value apart: there those are compared to
    float precision and to one code value (docs/limits.md, "Reproducibility")."""
    a, b = _tree(ours), _tree(reference)
    assert a.keys() == b.keys()
    for rel in a:
        if not variant.startswith("cuda"):
            assert a[rel] == b[rel], rel
        elif rel.endswith(".png"):
            _assert_pngs_within_one_level(ours / rel, reference / rel)
        elif rel.startswith("exr/"):
            x, y = read_exr(ours / rel), read_exr(reference / rel)
            assert x.keys() == y.keys(), rel
            for channel in x:
                np.testing.assert_allclose(x[channel], y[channel], rtol=1e-5, atol=1e-7)
        elif rel.endswith(".json") and rel.split("/")[0] in JSON_FROM_RADIANCE:
            _numbers_close(json.loads(a[rel]), json.loads(b[rel]), rel)
        else:
            assert a[rel] == b[rel], rel


def _uninterrupted(scene: Path, out: Path, *extra: str) -> Path:
    done = subprocess.run(_command(scene, out, *extra, "--quiet"), capture_output=True)
    assert done.returncode == 0, done.stderr
    return out


def test_ctrl_c_stops_a_long_pass_at_once(scene, tmp_path):
    out = tmp_path / "ds"
    # Past the scene's geometry and load: in its one pass, compiling or rendering.
    code, seconds = _interrupt(_command(scene, out), _scene_loaded, 3.0, signal.SIGINT)
    assert code == 130 and seconds < EXIT_WITHIN_S, (code, seconds)
    assert not (out / LOCK_NAME).exists() and _statuses(out) == {"long": "pending"}


@pytest.mark.slow
def test_a_folder_interrupted_in_its_pass_resumes_to_the_uninterrupted_files(
    small_scene, tmp_path, mitsuba_variant
):
    out = tmp_path / "ds"
    command = _command(small_scene, out)
    code, _ = _interrupt(command, _scene_loaded, 1.5, signal.SIGINT)
    assert code == 130
    assert not (out / LOCK_NAME).exists()
    assert _statuses(out) == {"long": "pending"}
    resumed = subprocess.run([*command, "--quiet"], capture_output=True, text=True)
    assert resumed.returncode == 0, resumed.stderr
    reference = _uninterrupted(small_scene, tmp_path / "uninterrupted")
    _assert_same_dataset(out, reference, mitsuba_variant)


@pytest.mark.slow
def test_ctrl_c_stops_local_workers_and_the_folder_resumes(small_scene, tmp_path, mitsuba_variant):
    out, log = tmp_path / "ds", tmp_path / "log.jsonl"
    command = _command(small_scene, out, "--scenes", "2", "--workers", "2", "--log", str(log))
    # The workers start, load Mitsuba and the scene, and compile and render the pass.
    code, seconds = _interrupt(command, _batch_started(log), 6.0, signal.SIGINT)
    assert code == 130 and seconds < EXIT_WITHIN_S, (code, seconds)
    assert not (out / LOCK_NAME).exists()
    assert "done" not in _statuses(out).values()
    resumed = subprocess.run([*command, "--quiet"], capture_output=True, text=True)
    assert resumed.returncode == 0, resumed.stderr
    reference = _uninterrupted(small_scene, tmp_path / "uninterrupted", "--scenes", "2")
    _assert_same_dataset(out, reference, mitsuba_variant)


def test_sigterm_stops_a_long_pass_at_once(scene, tmp_path):
    out = tmp_path / "ds"
    code, seconds = _interrupt(_command(scene, out), _scene_loaded, 1.5, signal.SIGTERM)
    assert code == 130 and seconds < EXIT_WITHIN_S, (code, seconds)
    assert not (out / LOCK_NAME).exists() and _statuses(out) == {"long": "pending"}
