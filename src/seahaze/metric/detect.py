"""A detector in the loop: run an Ultralytics model and write the prediction files the metric
reads (``PRED/<level>/<scene>.txt``, ``class cx cy w h conf`` normalised).

The boxes are the ones ``yolo val`` scores, not ``yolo predict``'s: each batch of images (sorted
by aspect ratio) is letterboxed into ``yolo val``'s rectangle (the image's long side at the
inference size, half a stride of extra padding, grey 114, centred) and NMS keeps a box once per
class above the threshold (``multi_label``), with ``yolo val``'s settings: confidence 0.001,
NMS IoU 0.7, up to 300 detections per image, and the image size the model was trained at unless
``imgsz`` is given. The model runs through Ultralytics' own ``AutoBackend`` (what ``val`` and
``predict`` use) and its public ``non_max_suppression`` and ``scale_boxes``; no Ultralytics code
is patched. Ultralytics is imported only here, on demand (``pip install 'seahaze[detect]'``),
and kept offline: ``YOLO_OFFLINE`` is set before its import, a weights file must exist locally
(nothing is downloaded), and nothing is plotted or saved by Ultralytics itself. See
docs/detectors.md.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import asdict, dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from seahaze.dataset.owned import ForeignFileError, OwnedFiles
from seahaze.fileio import write_text
from seahaze.metric.errors import MetricInputError, located

INSTALL_HINT = (
    "--model needs Ultralytics: install PyTorch for your machine, then "
    "pip install 'seahaze[detect]' (docs/detectors.md)"
)
VAL_PAD = 0.5
"""Extra padding of ``yolo val``'s rectangles, in strides (``pad`` of ``build_yolo_dataset``
for every mode but ``train``)."""
PAD_VALUE = 114
"""Grey of the letterbox border (Ultralytics' ``LetterBox`` default)."""


@dataclass(frozen=True)
class DetectorSettings:
    """How the detector runs; stored in the prediction folder's record and the table."""

    conf: float = 0.001
    iou: float = 0.7
    max_det: int = 300
    imgsz: int | None = None
    """None: the size the model was trained at (what ``yolo val`` uses)."""
    device: str | None = None
    """None: Ultralytics' choice (the first GPU, else the CPU)."""
    batch: int = 16

    def __post_init__(self) -> None:
        if not 0.0 <= self.conf < 1.0:
            raise MetricInputError(f"detector confidence must be in [0, 1), got {self.conf}")
        if self.imgsz is not None and not 32 <= self.imgsz <= 8192:
            raise MetricInputError(f"--imgsz must be within 32..8192 pixels, got {self.imgsz}")
        if self.batch < 1:
            raise MetricInputError(f"--batch must be >= 1, got {self.batch}")


@dataclass(frozen=True)
class Detector:
    """A loaded Ultralytics detection model and the settings it runs with."""

    model: Any
    weights: Path
    settings: DetectorSettings

    def describe(self) -> dict[str, object]:
        """What the table and the prediction record store about the run."""
        import ultralytics

        return {
            "weights": str(self.weights),
            "ultralytics": ultralytics.__version__,
            **{k: v for k, v in asdict(self.settings).items() if k != "batch"},
            "imgsz_used": self.imgsz,
            "boxes": "yolo val (rectangular letterbox, pad 0.5; multi-label NMS)",
        }

    @property
    def imgsz(self) -> int:
        """The inference size: the setting, else the model's training size (its largest side
        if a list), else 640."""
        if self.settings.imgsz is not None:
            return self.settings.imgsz
        size = self.model.overrides.get("imgsz") or 640
        return int(size if isinstance(size, int) else max(size))

    @cached_property
    def backend(self) -> Any:
        """The model on its device, Conv and BatchNorm fused, in eval mode: Ultralytics'
        ``AutoBackend``, as ``yolo val`` and ``yolo predict`` wrap it."""
        from ultralytics.nn.autobackend import AutoBackend
        from ultralytics.utils.torch_utils import select_device

        device = select_device(self.settings.device, verbose=False)
        backend = AutoBackend(self.model.model, device=device, fuse=True, verbose=False)
        backend.eval()
        return backend


def load_detector(
    weights: Path, class_names: Sequence[str], settings: DetectorSettings | None = None
) -> Detector:
    """Load ``weights`` (a trained Ultralytics ``.pt``) for the dataset's classes.

    Raises :class:`MetricInputError` when Ultralytics is not installed, the file is missing or
    not a detection model, or its classes are not the dataset's (by id and name).
    """
    weights = Path(weights)
    if not weights.is_file():
        raise located(
            weights,
            "weights file not found; give a trained Ultralytics .pt file (nothing is downloaded)",
        )
    os.environ.setdefault("YOLO_OFFLINE", "1")  # no connectivity, update or telemetry checks
    try:
        from ultralytics import YOLO
    except ImportError:
        raise MetricInputError(INSTALL_HINT) from None
    try:
        model = YOLO(str(weights), task="detect")
    except Exception as exc:  # Ultralytics raises many types for an unusable file
        # Their messages run to several lines (a pickle's, PyTorch's advice): the first says it.
        first = next((line.strip() for line in str(exc).splitlines() if line.strip()), "")
        first = first if len(first) <= 200 else first[:200] + "…"
        raise located(
            weights,
            f"cannot load the model ({exc.__class__.__name__}: {first}); give a trained "
            "Ultralytics detection .pt file",
        ) from None
    if model.task != "detect":
        raise located(weights, f"a {model.task!r} model; the metric needs a detection model")
    if isinstance(model.model, (str, Path)):  # an exported format (ONNX, TensorRT, ...)
        raise located(weights, "not a PyTorch model; give the trained .pt file")
    names = [str(model.names[i]) for i in sorted(model.names)]
    if names != list(class_names):
        first = next(
            (i for i, (a, b) in enumerate(zip(names, class_names, strict=False)) if a != b),
            min(len(names), len(class_names)),
        )
        raise located(
            weights,
            f"the model's classes are not the dataset's (data.yaml names): class {first} is "
            f"{_name(names, first)!r} in the model, {_name(class_names, first)!r} in the "
            f"dataset ({len(names)} vs {len(class_names)} classes); train it on this dataset",
        )
    settings = settings or DetectorSettings()
    _check_device(settings.device)
    return Detector(model, weights.resolve(), settings)


def _check_device(device: str | None) -> None:
    """Raise :class:`MetricInputError` (one line) for a ``--device`` this machine lacks, before
    any image is read (Ultralytics' own message spans many lines)."""
    if device is None:
        return
    from ultralytics.utils.torch_utils import select_device

    try:
        select_device(device, verbose=False)
    except ValueError as exc:
        first = next((line for line in str(exc).splitlines() if line.strip()), str(exc))
        raise MetricInputError(f"--device {device}: {first.strip()}") from None


def _name(names: Sequence[str], i: int) -> str | None:
    return names[i] if i < len(names) else None


def predict(detector: Detector, images: Mapping[str, Path]) -> Iterator[tuple[str, str]]:
    """``(scene, prediction file text)`` for every image: the boxes ``yolo val`` makes of them.

    As ``yolo val`` does: the images are sorted by aspect ratio (height / width) and taken
    ``batch`` at a time; each is resized so that its long side is the inference size; a batch
    shares one canvas, ``ceil(side · imgsz / stride + 0.5) · stride`` on each side, with
    ``side`` 1 for the long side and the batch's extreme aspect ratio for the short one; each
    image is centred on it, grey 114 around it; NMS keeps a box once for every class above the
    confidence threshold; the boxes are mapped back to the image. The scenes come in that
    order.
    """
    import torch

    s = detector.settings
    backend = detector.backend
    stride = int(backend.stride)
    sizes = {scene: _image_size(path) for scene, path in images.items()}
    order = sorted(images, key=lambda scene: sizes[scene][0] / sizes[scene][1])
    for start in range(0, len(order), s.batch):
        chunk = order[start : start + s.batch]
        ratios = [sizes[scene][0] / sizes[scene][1] for scene in chunk]
        canvas = val_canvas(min(ratios), max(ratios), detector.imgsz, stride)
        placed = [_letterbox(images[scene], detector.imgsz, canvas) for scene in chunk]
        batch = torch.from_numpy(np.stack([p.image for p in placed]))
        with torch.inference_mode():
            x = batch.to(backend.device).permute(0, 3, 1, 2).flip(1).contiguous()
            outputs = _nms(backend(x.float() / 255), s, getattr(backend, "end2end", False))
        for scene, p, out in zip(chunk, placed, outputs, strict=True):
            yield scene, prediction_text(p.boxes(out, canvas))


def val_canvas(ratio_min: float, ratio_max: float, imgsz: int, stride: int) -> tuple[int, int]:
    """``(height, width)`` of ``yolo val``'s canvas for a batch whose images' aspect ratios
    (height / width) span ``ratio_min..ratio_max`` (``set_rectangle`` of Ultralytics'
    ``BaseDataset`` with ``pad`` 0.5): e.g. 320×180 images at ``imgsz`` 320 → 224×352."""
    shape = (1.0, 1.0)
    if ratio_max < 1:
        shape = (ratio_max, 1.0)
    elif ratio_min > 1:
        shape = (1.0, 1.0 / ratio_min)
    h, w = (math.ceil(side * imgsz / stride + VAL_PAD) * stride for side in shape)
    return h, w


@dataclass(frozen=True)
class _Placed:
    """One image on its canvas: the pixels and how to map boxes back to the image."""

    image: Any
    """The canvas, BGR uint8 (height, width, 3)."""
    shape: tuple[int, int]
    """The image's own (height, width)."""
    gain: tuple[float, float]
    """Canvas pixels per image pixel, (vertical, horizontal)."""
    pad: tuple[int, int]
    """The image's offset on the canvas, (left, top)."""

    def boxes(self, detections: Any, canvas: tuple[int, int]) -> Any:
        """``detections`` (x1 y1 x2 y2 conf class on the canvas) as Ultralytics ``Boxes`` of the
        image (clipped to it), as ``yolo val`` scales them."""
        from ultralytics.engine.results import Boxes
        from ultralytics.utils.ops import scale_boxes

        detections = detections[:, :6].clone()
        ratio_pad = (self.gain, self.pad)
        detections[:, :4] = scale_boxes(canvas, detections[:, :4], self.shape, ratio_pad=ratio_pad)
        return Boxes(detections, self.shape)


def _letterbox(path: Path, imgsz: int, canvas: tuple[int, int]) -> _Placed:
    """Read ``path`` and place it on ``canvas`` as ``yolo val`` does (``load_image`` of
    Ultralytics' ``BaseDataset``, then ``LetterBox(scaleup=False)``)."""
    import cv2

    image = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if image is None:
        raise located(path, "cannot read the image")
    h0, w0 = image.shape[:2]
    r = imgsz / max(h0, w0)
    if r != 1:  # long side to imgsz (up or down), as val's load_image
        size = (min(math.ceil(w0 * r), imgsz), min(math.ceil(h0 * r), imgsz))
        image = cv2.resize(image, size, interpolation=cv2.INTER_LINEAR)
    h, w = image.shape[:2]
    g = min(canvas[0] / h, canvas[1] / w, 1.0)  # never scaled up onto the canvas
    if g != 1:
        size = (max(round(w * g), 1), max(round(h * g), 1))
        image = cv2.resize(image, size, interpolation=cv2.INTER_LINEAR)
    dh, dw = (canvas[0] - image.shape[0]) / 2, (canvas[1] - image.shape[1]) / 2
    top, bottom = round(dh - 0.1), round(dh + 0.1)
    left, right = round(dw - 0.1), round(dw + 0.1)
    image = cv2.copyMakeBorder(
        image, top, bottom, left, right, cv2.BORDER_CONSTANT, value=(PAD_VALUE,) * 3
    )
    return _Placed(image, (h0, w0), (h / h0 * g, w / w0 * g), (left, top))


def _image_size(path: Path) -> tuple[int, int]:
    """``(height, width)`` of an image, from its header."""
    from PIL import Image

    try:
        with Image.open(path) as image:
            width, height = image.size
    except OSError as exc:
        raise located(path, f"cannot read the image ({exc})") from None
    return height, width


def _nms(raw: Any, settings: DetectorSettings, end2end: bool) -> list[Any]:
    """Ultralytics' NMS as ``yolo val`` calls it: a box is kept once for every class above
    ``conf`` (``multi_label``; an end-to-end model's output is only filtered); per image, rows
    ``x1 y1 x2 y2 conf class``."""
    try:
        from ultralytics.utils.nms import non_max_suppression
    except ImportError:  # Ultralytics before the nms module
        from ultralytics.utils.ops import non_max_suppression
    return non_max_suppression(
        raw,
        settings.conf,
        settings.iou,
        multi_label=True,
        max_det=settings.max_det,
        **({"end2end": True} if end2end else {}),
    )


def prediction_text(boxes: Any) -> str:
    """One image's detections (Ultralytics ``Boxes``) as ``class cx cy w h conf`` lines,
    normalised, 6 decimals, most confident first (an empty text: no detection)."""
    rows = zip(boxes.cls.tolist(), boxes.xywhn.tolist(), boxes.conf.tolist(), strict=True)
    lines = [
        f"{int(c)} {x:.6f} {y:.6f} {w:.6f} {h:.6f} {p:.6f}"
        for c, (x, y, w, h), p in sorted(rows, key=lambda r: -r[2])
    ]
    return "".join(line + "\n" for line in lines)


def write_predictions(
    detector: Detector, folders: Mapping[str, Mapping[str, Path]], pred_root: Path
) -> tuple[int, list[str]]:
    """Run the detector on each folder's images and write ``pred_root/<folder>/<scene>.txt``
    (``""`` as a folder name: ``pred_root`` itself). Returns the number of detections and
    warnings (record entries not trusted, files of an earlier run left alone).

    Files seahaze did not write are never overwritten (:mod:`seahaze.dataset.owned`); files of
    an earlier run in the folders written now are replaced or, for scenes no longer there,
    deleted.
    """
    targets = {
        _relative(folder, scene): path
        for folder, images in folders.items()
        for scene, path in images.items()
    }
    try:
        owned = OwnedFiles.open(pred_root)
        owned.check(targets)
    except ForeignFileError as err:
        raise MetricInputError(str(err)) from None
    written = {str(Path(rel).parent) for rel in targets}
    info = {"tool": "seahaze metric", "detector": detector.describe()}
    stale = owned.claim(targets, info)
    detections = 0
    for folder, images in folders.items():
        for scene, text in predict(detector, images):
            write_text(pred_root / _relative(folder, scene), text)
            detections += text.count("\n")
    owned.seal(targets)
    kept = owned.release(rel for rel in stale if str(Path(rel).parent) in written)
    return detections, [*owned.ignored, *kept]


def _relative(folder: str, scene: str) -> str:
    return f"{folder}/{scene}.txt" if folder else f"{scene}.txt"
