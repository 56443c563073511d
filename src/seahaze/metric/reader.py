"""Reading a seahaze dataset and YOLO-format label / prediction files for the metric.

Dataset layout (written by the renderer)::

    DIR/data.yaml                   # Ultralytics: names {0: container_ship, ...}, split per level
    DIR/images/<level>/<scene>.png  # level: clean, v0300, v0400, ... (zero-padded metres)
    DIR/labels/<level>/<scene>.txt  # 'class cx cy w h' normalised; an empty file = no objects
    DIR/labels_visible/<level>/<scene>.txt  # labels.write_visible: the vessels each image shows

Which label folder is the ground truth is the dataset's ``labels`` (``--labels``, see
:data:`LABEL_FOLDERS`): ``paper`` (``labels/``, every labelled vessel at every level, the MSVD
protocol and the default) or ``visible`` (``labels_visible/``).

A prediction folder mirrors the labels: ``PRED/<level>/<scene>.txt`` with
``class cx cy w h conf`` lines, or ``PRED/<scene>.txt`` for a single level. A missing prediction
file means no detections for that image. A dataset opened with a split (``--split test``) holds
only the scenes ``dataset.json`` puts in that split.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path

from PIL import Image, UnidentifiedImageError

from seahaze.dataset.splits import scene_splits, split_order
from seahaze.metric.errors import MetricInputError, located
from seahaze.visibility import CLEAN_LEVEL, is_level_name, level_name
from seahaze.yamlguard import MAX_SCENE_BYTES, YamlLimitError, compose_limited, read_limited_text

IMAGE_SUFFIXES: tuple[str, ...] = (".png", ".jpg", ".jpeg")
"""Image files recognised in ``images/<level>/`` (the renderer writes PNG)."""

LABEL_FOLDERS: dict[str, str] = {"paper": "labels", "visible": "labels_visible"}
"""``--labels`` → the folder of YOLO labels scored against: ``paper`` (every labelled vessel at
every level, the MSVD paper's protocol) or ``visible`` (per level the vessels seen in that
level's image, written with ``labels.write_visible``; docs/metric.md)."""
PAPER_LABELS = "paper"
"""The default ``--labels``: the paper's protocol."""

_LEVEL = re.compile(r"^v(\d+)$")
_LEVEL_ARG = re.compile(r"^v?(\d+(?:\.\d+)?)\s*(?:m)?$", re.IGNORECASE)
_COORD_TOL = 1e-6  # normalised coordinates written with rounding may exceed [0, 1] by this much


def level_visibility_m(level: str) -> float | None:
    """Visibility (m) of a level folder: ``v0300`` → 300.0, ``clean`` → None.

    Raises :class:`MetricInputError` for any other name.
    """
    if level == CLEAN_LEVEL:
        return None
    match = _LEVEL.match(level)
    if not match or int(match[1]) <= 0:
        raise MetricInputError(f"level {level!r} is not 'clean' or 'v' + metres (e.g. v0300)")
    return float(int(match[1]))


def parse_level(text: str) -> str:
    """The level folder for a ``--level`` argument: ``800``, ``800m``, ``v800``, ``v0800`` →
    ``v0800``; ``clean`` → ``clean``. Raises :class:`MetricInputError` otherwise."""
    value = text.strip()
    if value.lower() == CLEAN_LEVEL:
        return CLEAN_LEVEL
    match = _LEVEL_ARG.match(value)
    if not match or float(match[1]) <= 0 or not float(match[1]).is_integer():
        raise MetricInputError(
            f"--level {text!r}: expected whole metres (800), a level folder (v0800) or 'clean'"
        )
    return level_name(float(match[1]))


def _level_key(level: str) -> tuple[int, float]:
    vis = level_visibility_m(level)
    return (0, 0.0) if vis is None else (1, vis)


def sort_levels(levels: Iterable[str]) -> list[str]:
    """Level names ordered ``clean`` first, then by increasing visibility."""
    return sorted(levels, key=_level_key)


# --------------------------------------------------------------------------------------------
# YOLO text files


@dataclass(frozen=True)
class YoloBox:
    """One YOLO line: class id and a normalised centre/size box; ``conf`` for predictions."""

    class_id: int
    cx: float
    cy: float
    w: float
    h: float
    conf: float | None = None

    def to_pixels(self, width: int, height: int) -> tuple[float, float, float, float]:
        """The box as COCO ``[x_min, y_min, width, height]`` in pixels of a width×height image."""
        return (
            (self.cx - self.w / 2) * width,
            (self.cy - self.h / 2) * height,
            self.w * width,
            self.h * height,
        )


LABEL_FORMAT = "class cx cy w h"
PRED_FORMAT = "class cx cy w h conf"


def parse_yolo_line(text: str, num_classes: int, *, with_conf: bool) -> YoloBox:
    """Parse one non-empty YOLO line; raise :class:`MetricInputError` (without location) saying
    what is wrong and what is allowed."""
    fields = text.split()
    expected = 6 if with_conf else 5
    fmt = PRED_FORMAT if with_conf else LABEL_FORMAT
    if len(fields) != expected:
        hint = (
            " (predictions need the confidence column; Ultralytics writes it with save_conf=True)"
            if with_conf and len(fields) == 5
            else ""
        )
        raise MetricInputError(f"expected {expected} values '{fmt}', got {len(fields)}{hint}")
    try:
        class_id = int(fields[0])
    except ValueError:
        raise MetricInputError(
            f"class must be an integer in 0..{num_classes - 1}, got {fields[0]!r}"
        ) from None
    if not 0 <= class_id < num_classes:
        raise MetricInputError(
            f"class {class_id} out of range; data.yaml names {num_classes} classes "
            f"(0..{num_classes - 1})"
        )
    values: list[float] = []
    for name, raw in zip(fmt.split()[1:], fields[1:], strict=True):
        try:
            value = float(raw)
        except ValueError:
            raise MetricInputError(f"{name} must be a number, got {raw!r}") from None
        if not math.isfinite(value) or not -_COORD_TOL <= value <= 1 + _COORD_TOL:
            raise MetricInputError(f"{name} must be a number in [0, 1] (normalised), got {raw!r}")
        values.append(value)
    cx, cy, w, h = values[:4]
    if not with_conf and (w <= 0 or h <= 0):
        raise MetricInputError(f"box width and height must be > 0, got w={fields[3]} h={fields[4]}")
    return YoloBox(class_id, cx, cy, w, h, values[4] if with_conf else None)


def read_yolo_file(path: Path, num_classes: int, *, with_conf: bool) -> list[YoloBox]:
    """All boxes of a YOLO label (``with_conf=False``) or prediction (``True``) file.

    Blank lines are skipped; an empty file means no objects. Raises :class:`MetricInputError`
    naming the file and line for anything malformed.
    """
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise located(
            path,
            f"cannot read ({exc.__class__.__name__}); expected a text file "
            f"of '{PRED_FORMAT if with_conf else LABEL_FORMAT}' lines",
        ) from None
    boxes: list[YoloBox] = []
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.strip():
            continue
        try:
            boxes.append(parse_yolo_line(line, num_classes, with_conf=with_conf))
        except MetricInputError as exc:
            raise located(path, str(exc), number) from None
    return boxes


# --------------------------------------------------------------------------------------------
# Dataset


@dataclass(frozen=True)
class Dataset:
    """A seahaze dataset on disk: its root, class names and level folders."""

    root: Path
    names: tuple[str, ...]
    levels: tuple[str, ...]
    """Level folders under ``images/``: ``clean`` first, then by increasing visibility."""
    split: str | None = None
    """The split the dataset was opened with (None: every scene)."""
    members: frozenset[str] | None = None
    """The scenes of ``split`` (None: every scene)."""
    labels: str = PAPER_LABELS
    """The ground truth scored against, a key of :data:`LABEL_FOLDERS`."""

    def image_dir(self, level: str) -> Path:
        """``root/images/<level>``."""
        return self.root / "images" / level

    def label_dir(self, level: str) -> Path:
        """The level's ground-truth folder: ``root/labels/<level>``, or with ``labels``
        ``visible`` ``root/labels_visible/<level>``."""
        return self.root / LABEL_FOLDERS[self.labels] / level

    @property
    def hazy_levels(self) -> tuple[str, ...]:
        """The levels with a visibility (all but ``clean``), by increasing visibility."""
        return tuple(lv for lv in self.levels if lv != CLEAN_LEVEL)


@dataclass(frozen=True)
class ImageTruth:
    """Ground truth of one image: scene name (file stem), pixel size and labelled boxes."""

    name: str
    width: int
    height: int
    boxes: tuple[YoloBox, ...]


def _class_names(path: Path, doc: object) -> tuple[str, ...]:
    names = doc.get("names") if isinstance(doc, dict) else None
    values = names.values() if isinstance(names, dict) else names
    if isinstance(values, Iterable) and not all(
        isinstance(n, str | int | float) and not isinstance(n, bool) for n in values
    ):
        raise located(path, "names must be class names (strings), not lists or mappings")
    if isinstance(names, list) and names:
        return tuple(str(n) for n in names)
    if isinstance(names, dict) and names:
        keys = sorted(names, key=str)
        if sorted(k for k in keys if isinstance(k, int)) != list(range(len(keys))):
            shown = ", ".join(str(k)[:20] for k in keys[:10]) + (", …" if len(keys) > 10 else "")
            raise located(path, f"names must map the class ids 0..N-1 to names, got ids {shown}")
        return tuple(str(names[k]) for k in range(len(keys)))
    raise located(path, "missing 'names' (a list or a {0: name, 1: ...} mapping of classes)")


def load_dataset(root: Path | str, split: str | None = None, labels: str = PAPER_LABELS) -> Dataset:
    """Open a dataset folder: class names from ``data.yaml``, levels from ``images/``; with
    ``split``, only the scenes ``dataset.json`` puts in that split; ``labels`` picks the ground
    truth (:data:`LABEL_FOLDERS`: ``paper``, the default, or ``visible``).

    Raises :class:`MetricInputError` if ``data.yaml`` or ``images/`` is missing or unusable,
    the dataset has no such split, or ``labels`` is ``visible`` and it has no visible labels.
    """
    root = Path(root)
    if not root.is_dir():
        raise located(root, "dataset folder not found")
    if labels not in LABEL_FOLDERS:
        raise MetricInputError(f"--labels {labels!r}: allowed {', '.join(LABEL_FOLDERS)}")
    data_yaml = root / "data.yaml"
    if not data_yaml.is_file():
        raise located(
            data_yaml,
            "missing; a seahaze dataset has data.yaml, images/<level>/ and labels/<level>/",
        )
    try:
        # Limited like a scene file: size, nesting and alias expansion are checked before
        # anything walks it (a deep or "billion laughs" data.yaml was a traceback or a hang).
        text = read_limited_text(data_yaml, MAX_SCENE_BYTES, "data.yaml", "expected YAML")
        doc, _ = compose_limited(text)
    except YamlLimitError as exc:
        raise located(data_yaml, exc.message, exc.line or None) from None
    names = _class_names(data_yaml, doc)
    images = root / "images"
    if not images.is_dir():
        raise located(images, "missing; expected one folder per level (clean, v0300, ...)")
    levels = sort_levels(p.name for p in images.iterdir() if p.is_dir() and is_level_name(p.name))
    if not levels:
        raise located(images, "no level folders (clean, v0300, v0400, ...)")
    members = _split_members(root / "dataset.json", split) if split is not None else None
    if labels != PAPER_LABELS and not (root / LABEL_FOLDERS[labels]).is_dir():
        # Checked here, before a detector runs on every level, and said in terms of the
        # dataset: a folder rendered without labels.write_visible (or before it existed).
        raise MetricInputError(
            f"--labels {labels}: dataset {root} has no {LABEL_FOLDERS[labels]}/ folder (it was "
            "rendered without labels.write_visible, or before that option existed); render it "
            f"with labels.write_visible: true, or score every vessel with --labels {PAPER_LABELS}"
        )
    return Dataset(root, names, tuple(levels), split, members, labels)


def _split_members(manifest: Path, split: str) -> frozenset[str]:
    """The scenes ``manifest`` puts in ``split``; raises for a missing, unreadable or damaged
    manifest (read as ``seahaze export`` reads it: hostile JSON is a message) or split."""
    from seahaze.export.source import ExportError, read_manifest

    if not manifest.exists() and not manifest.is_symlink():
        raise located(manifest, "missing; --split needs the dataset's manifest")
    try:
        data = read_manifest(manifest)
    except ExportError as exc:
        raise MetricInputError(str(exc)) from None
    allowed = split_order(data)
    if split not in allowed:
        raise located(manifest, f"--split {split!r}: the dataset's splits are {', '.join(allowed)}")
    return frozenset(name for name, s in scene_splits(data).items() if s == split)


def _image_size(path: Path) -> tuple[int, int]:
    try:
        with Image.open(path) as img:  # reads the header only
            return img.size
    except (OSError, UnidentifiedImageError) as exc:
        raise located(
            path,
            f"cannot read the image size ({exc.__class__.__name__}); expected a PNG/JPEG image",
        ) from None


def scene_images(dataset: Dataset, level: str) -> dict[str, Path]:
    """Scene name → image path for a level. Raises if the level folder is missing, empty or
    holds two images of the same scene."""
    folder = dataset.image_dir(level)
    if not folder.is_dir():
        raise located(
            folder, f"level {level!r} not in the dataset (levels: {', '.join(dataset.levels)})"
        )
    scenes: dict[str, Path] = {}
    for path in sorted(folder.iterdir()):
        if path.suffix.lower() not in IMAGE_SUFFIXES or not path.is_file():
            continue
        if path.stem in scenes:
            raise located(path, f"scene {path.stem!r} has two images ({scenes[path.stem].name})")
        scenes[path.stem] = path
    if not scenes:
        raise located(folder, f"no images ({', '.join(IMAGE_SUFFIXES)})")
    if dataset.members is None:
        return scenes
    chosen = {name: path for name, path in scenes.items() if name in dataset.members}
    if not chosen:
        raise located(folder, f"no image of a scene of split {dataset.split!r}")
    return chosen


def outside_split(dataset: Dataset, level: str) -> frozenset[str]:
    """Scenes of ``level`` that the dataset's split leaves out (their predictions are ignored)."""
    if dataset.members is None:
        return frozenset()
    folder = dataset.image_dir(level)
    stems = {p.stem for p in folder.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES}
    return frozenset(stems - dataset.members)


def load_level_truth(dataset: Dataset, level: str) -> list[ImageTruth]:
    """Ground truth of every image of a level, its size read from the image with Pillow.

    Every image needs its label file (an empty one for no objects); a label without an image is
    an error too, because either would silently change the score.
    """
    scenes = scene_images(dataset, level)
    label_dir = dataset.label_dir(level)
    if not label_dir.is_dir():
        raise located(label_dir, f"missing; expected one '{LABEL_FORMAT}' file per image")
    skipped = outside_split(dataset, level)
    orphans = sorted(
        p.name for p in label_dir.glob("*.txt") if p.stem not in scenes and p.stem not in skipped
    )
    if orphans:
        raise located(
            label_dir / orphans[0], f"label without an image in {dataset.image_dir(level)}"
        )
    truth: list[ImageTruth] = []
    for name, image in scenes.items():
        label = label_dir / f"{name}.txt"
        if not label.is_file():
            raise located(
                label, f"missing label file for {image.name} (an empty file means no objects)"
            )
        width, height = _image_size(image)
        boxes = read_yolo_file(label, len(dataset.names), with_conf=False)
        truth.append(ImageTruth(name, width, height, tuple(boxes)))
    return truth


def prediction_dir(pred_root: Path | str, level: str, *, allow_flat: bool) -> Path:
    """The folder holding a level's prediction files: ``PRED/<level>/`` if it exists, else
    ``PRED`` itself when ``allow_flat`` (a single-level folder, as given with ``--level``)."""
    root = Path(pred_root)
    if not root.is_dir():
        raise located(root, "prediction folder not found")
    if (root / level).is_dir():
        return root / level
    others = sorted(p.name for p in root.iterdir() if p.is_dir() and is_level_name(p.name))
    if allow_flat and not others:
        return root
    if others:
        raise located(
            root / level,
            f"missing, but {root} has folders for other levels ({', '.join(sort_levels(others))})",
        )
    raise located(
        root / level, f"missing; predictions for level {level} go in PRED/{level}/<scene>.txt"
    )


def load_predictions(
    folder: Path, scenes: Iterable[str], num_classes: int, ignored: Iterable[str] = ()
) -> Mapping[str, list[YoloBox]]:
    """Scene → predicted boxes from ``folder/<scene>.txt`` (``class cx cy w h conf``).

    A missing file is an image without detections. A ``.txt`` file whose scene is not in the
    level is an error: a misnamed folder would otherwise score as "no detections". Files of
    ``ignored`` scenes (of the level, outside the split evaluated) are skipped.
    """
    wanted = set(scenes)
    skip = set(ignored)
    stray = sorted(
        p.name for p in folder.glob("*.txt") if p.stem not in wanted and p.stem not in skip
    )
    if stray:
        raise located(
            folder / stray[0],
            f"prediction for a scene that is not in the level "
            f"({len(stray)} such file(s)); file names must match "
            "the image names",
        )
    out: dict[str, list[YoloBox]] = {}
    for name in sorted(wanted):
        path = folder / f"{name}.txt"
        if path.exists() and not path.is_file():
            # A folder (or device) under a prediction's name would score as "no detections".
            raise located(path, "not a file: a prediction is a text file of boxes")
        out[name] = read_yolo_file(path, num_classes, with_conf=True) if path.is_file() else []
    return out


def dehazed_images(folder: Path | str, dataset: Dataset, level: str) -> dict[str, Path]:
    """Scene → restored image in ``folder`` for every scene of ``level`` (of the dataset's
    split): ``<scene>.png`` or ``<scene>_<level>.png`` (the hazy name of ``seahaze export
    --layout paired``, which restoration code usually keeps), PNG or JPEG.

    Raises :class:`MetricInputError` for a missing folder, a scene without a restored image or
    with two, and an image that is no scene of the level.
    """
    root = Path(folder)
    if not root.is_dir():
        raise located(root, "folder of restored images not found")
    scenes = set(scene_images(dataset, level))
    skipped = outside_split(dataset, level)
    found: dict[str, Path] = {}
    for path in sorted(root.iterdir()):
        if path.suffix.lower() not in IMAGE_SUFFIXES or not path.is_file():
            continue
        stem = path.stem.removesuffix(f"_{level}")
        if stem in skipped:
            continue
        if stem not in scenes:
            raise located(path, f"not an image of a scene of level {level} (name: <scene>.png)")
        if stem in found:
            raise located(path, f"scene {stem!r} has two restored images ({found[stem].name})")
        found[stem] = path
    missing = sorted(scenes - set(found))
    if missing:
        raise located(
            root / f"{missing[0]}.png",
            f"missing: {len(missing)} of {len(scenes)} scenes of {level} have no restored image",
        )
    return {scene: found[scene] for scene in sorted(found)}
