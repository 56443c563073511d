"""A detector in the loop: run an Ultralytics model and write the prediction files the metric
reads (``PRED/<level>/<scene>.txt``, ``class cx cy w h conf`` normalised).

The settings are the metric's, not Ultralytics' ``predict`` defaults: confidence 0.001 (AP
integrates the whole precision–recall curve; ``predict``'s default 0.25 would cut its tail),
NMS IoU 0.7 and up to 300 detections per image, as ``yolo val`` uses, and the image size the
model was trained at unless ``imgsz`` is given. Ultralytics is imported only here, on demand
(``pip install 'seahaze[detect]'``), and kept offline: ``YOLO_OFFLINE`` is set before its
import, a weights file must exist locally (nothing is downloaded), and nothing is plotted or
saved by Ultralytics itself. See docs/detectors.md.
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from seahaze.dataset.owned import ForeignFileError, OwnedFiles
from seahaze.fileio import write_text
from seahaze.metric.errors import MetricInputError, located

INSTALL_HINT = (
    "--model needs Ultralytics: install PyTorch for your machine, then "
    "pip install 'seahaze[detect]' (docs/detectors.md)"
)


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
        }

    @property
    def imgsz(self) -> int | list[int]:
        """The inference size: the setting, else the model's training size, else 640."""
        if self.settings.imgsz is not None:
            return self.settings.imgsz
        return self.model.overrides.get("imgsz") or 640


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
        raise located(weights, f"cannot load the model ({exc.__class__.__name__}: {exc})") from None
    if model.task != "detect":
        raise located(weights, f"a {model.task!r} model; the metric needs a detection model")
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
    """``(scene, prediction file text)`` for every image, in batches, in ``images``' order."""
    s = detector.settings
    items = list(images.items())
    for start in range(0, len(items), s.batch):
        chunk = items[start : start + s.batch]
        results = detector.model.predict(
            source=[str(path) for _, path in chunk],
            conf=s.conf,
            iou=s.iou,
            max_det=s.max_det,
            imgsz=detector.imgsz,
            device=s.device,
            verbose=False,
            save=False,
        )
        for (scene, _), result in zip(chunk, results, strict=True):
            yield scene, prediction_text(result)


def prediction_text(result: Any) -> str:
    """One image's detections as ``class cx cy w h conf`` lines, normalised, 6 decimals, most
    confident first (an empty text: no detection)."""
    boxes = result.boxes
    rows = zip(boxes.cls.tolist(), boxes.xywhn.tolist(), boxes.conf.tolist(), strict=True)
    lines = [
        f"{int(c)} {x:.6f} {y:.6f} {w:.6f} {h:.6f} {p:.6f}"
        for c, (x, y, w, h), p in sorted(rows, key=lambda r: -r[2])
    ]
    return "".join(line + "\n" for line in lines)


def write_predictions(
    detector: Detector, folders: Mapping[str, Mapping[str, Path]], pred_root: Path
) -> int:
    """Run the detector on each folder's images and write ``pred_root/<folder>/<scene>.txt``
    (``""`` as a folder name: ``pred_root`` itself). Returns the number of detections.

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
    owned.release(rel for rel in stale if str(Path(rel).parent) in written)
    return detections


def _relative(folder: str, scene: str) -> str:
    return f"{folder}/{scene}.txt" if folder else f"{scene}.txt"
