"""The rows of the ``hf`` layout (:mod:`seahaze.export.hf`): what a row holds, read from a
scene's files and checked, and the Parquet shards that hold them.

A row is one (scene, hazy level):

=====================  ========================================================================
``scene``              scene name (``meta/<scene>.json``)
``sequence``, ``frame``  a sequence's name and 0-based frame, else null
``split``              ``train``, ``val`` or ``test`` (``train`` for a dataset without a split)
``level``              the level's folder name, ``v0300`` …
``visibility_m``       visibility V of the level, m (``dataset.json``)
``sigma_per_m``        extinction at 550 nm, 1/m (``dataset.json``)
``sigma_rgb_per_m``    extinction per channel R, G, B, 1/m (``meta``)
``regulation``         the level's navigation regulation class (``dataset.json``)
``hazy``, ``clean``    Image: the PNG files themselves, 8-bit sRGB
``depth``              Image: float32 TIFF (mode ``F``), distance along each pixel's ray in m,
                       inf for sky (``depth/<scene>.exr``)
``objects``            the labelled vessels, in the label files' order: ``vessel`` (its index
                       in ``meta``), ``track_id`` (sequences, else null), ``category``
                       (ClassLabel), ``bbox`` (``[x, y, w, h]`` px, COCO's convention),
                       ``distance_m``, ``visible_fraction`` (unoccluded share), and at the
                       row's level ``apparent_contrast``, ``local_contrast``, ``visible``
                       (``discernible``: in ``labels_visible/``) and ``beyond_visibility``
=====================  ========================================================================

The features are written into each shard's schema (the ``huggingface`` key ``datasets`` reads)
in the ``Sequence`` form that every ``datasets`` from 2.x on reads.
"""

from __future__ import annotations

import io
import json
import math
import stat
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..dataset import Layout
from ..fileio import json_depth, read_exr
from ..visibility import CLEAN_LEVEL
from .source import ExportError, Level, SourceDataset, kind_text, value_text

MAX_META_BYTES = 64 << 20
"""Largest ``meta/<scene>.json`` read (a scene of 200 vessels is about 200 kB)."""
MAX_META_DEPTH = 32
ROWS_PER_GROUP = 100
"""Rows per Parquet row group, at most (``datasets``' choice for image datasets)."""
MAX_GROUP_BYTES = 64 << 20
"""Bytes per row group, at most: a reader holds one group of images in memory."""
TIFF_PREDICTOR_FLOAT = 3
"""TIFF's floating-point predictor: the depth compresses to about half of plain deflate."""


@dataclass(frozen=True)
class LevelLook:
    """How a vessel looks at one level (``meta``'s ``vessels[].levels[level]``)."""

    apparent_contrast: float | None
    local_contrast: float | None
    visible: bool | None
    beyond_visibility: bool | None


@dataclass(frozen=True)
class ObjectRecord:
    """A labelled vessel of a scene."""

    vessel: int
    track_id: int | None
    class_id: int
    bbox: tuple[float, float, float, float]
    """``[x, y, w, h]`` in pixels from ``box_px``'s edges."""
    distance_m: float
    visible_fraction: float | None
    levels: dict[str, LevelLook]


@dataclass(frozen=True)
class SceneRecord:
    """What the rows of one scene hold besides its files' pixels."""

    scene: str
    split: str
    sequence: str | None
    frame: int | None
    size: tuple[int, int]
    """(width, height) of its images, from the camera."""
    sigma_rgb: dict[str, tuple[float, float, float]]
    objects: tuple[ObjectRecord, ...]


# --------------------------------------------------------------------------------------------
# Reading a scene


class _Meta:
    """Typed reads from one parsed meta file; a wrong value is an :class:`ExportError` naming
    the file and the field."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def fail(self, where: str, value: Any, allowed: str) -> ExportError:
        return ExportError(
            f"{self.path}: {where} is {value_text(value)}; allowed: {allowed}; the dataset is "
            "damaged: rerun the 'seahaze render' command that made it"
        )

    def number(self, value: Any, where: str) -> float:
        if isinstance(value, int | float) and not isinstance(value, bool):
            try:
                number = float(value)
            except OverflowError:  # an integer beyond float
                number = math.inf
            if math.isfinite(number):
                return number
        raise self.fail(where, value, "a finite number")

    def optional(self, value: Any, where: str) -> float | None:
        if value is None:
            return None
        if isinstance(value, int | float) and not isinstance(value, bool):
            return self.number(value, where)
        raise self.fail(where, value, "a finite number or null")

    def integer(self, value: Any, where: str, low: int, high: int | None = None) -> int:
        if (
            isinstance(value, int)
            and not isinstance(value, bool)
            and low <= value
            and (high is None or value < high)
        ):
            return value
        span = f"{low} or more" if high is None else f"{low} to {high - 1}"
        raise self.fail(where, value, f"an integer, {span}")

    def flag(self, value: Any, where: str) -> bool | None:
        if value is None or isinstance(value, bool):
            return value
        raise self.fail(where, value, "true, false or null")

    def mapping(self, value: Any, where: str) -> dict[str, Any]:
        if isinstance(value, dict):
            return value
        raise ExportError(
            f"{self.path}: {where} is {kind_text(value)}; allowed: a mapping; the dataset is "
            "damaged: rerun the 'seahaze render' command that made it"
        )


def read_scene(
    layout: Layout,
    scene: str,
    split: str,
    levels: list[str],
    classes: tuple[str, ...],
    entry: dict[str, Any],
) -> SceneRecord:
    """The row contents of ``scene`` from ``meta/<scene>.json`` and its manifest ``entry``
    (a sequence's name and frame), its labelled vessels checked against
    ``labels/<level>/<scene>.txt`` of the clean image and every level in ``levels`` (the same
    vessels, in the same order, of the same classes and boxes). Raises :class:`ExportError`
    for a damaged file."""
    path = layout.meta(scene)
    meta = _Meta(path)
    data = meta.mapping(_load(path), "the file")
    camera = meta.mapping(data.get("camera"), "camera")
    size = camera.get("resolution")
    if not (isinstance(size, list) and len(size) == 2):
        raise meta.fail("camera.resolution", size, "[width, height]")
    width = meta.integer(size[0], "camera.resolution[0]", 1, 1 << 16)
    height = meta.integer(size[1], "camera.resolution[1]", 1, 1 << 16)
    sigma_rgb = _sigmas(meta, data.get("levels"), levels)
    vessels = data.get("vessels")
    if not isinstance(vessels, list):
        raise meta.fail("vessels", vessels, "a list")
    objects = []
    for i, vessel in enumerate(vessels):
        vessel = meta.mapping(vessel, f"vessels[{i}]")
        if vessel.get("box_px") is not None:
            objects.append(_object(meta, vessel, f"vessels[{i}]", levels, len(classes)))
    sequence, frame = entry.get("sequence"), entry.get("frame")
    is_frame = isinstance(sequence, str) and isinstance(frame, int) and frame >= 0
    if (sequence is not None or frame is not None) and not is_frame:
        raise ExportError(
            f"{layout.manifest}: scenes.{scene}: sequence {value_text(sequence)}, frame "
            f"{value_text(frame)}; allowed: a sequence's name and a frame number 0 or more"
        )
    for level in [CLEAN_LEVEL, *levels]:
        _match_labels(layout.label(level, scene), objects, (width, height))
    return SceneRecord(
        scene,
        split,
        sequence,
        frame,
        (width, height),
        sigma_rgb,
        tuple(objects),
    )


def _load(path: Path) -> Any:
    """The JSON document of the regular file ``path``, within the size and nesting limits."""
    try:
        info = path.stat()
        if not stat.S_ISREG(info.st_mode):
            raise ExportError(f"{path}: not a regular file; the dataset is damaged")
        if info.st_size > MAX_META_BYTES:
            raise ExportError(f"{path}: {info.st_size:,} bytes; a scene's meta is at most 64 MiB")
        data = json.loads(path.read_bytes())
    except FileNotFoundError:
        raise ExportError(f"{path}: missing; the dataset is incomplete") from None
    except RecursionError:
        raise ExportError(f"{path}: nested deeper than {MAX_META_DEPTH}; not a meta file") from None
    except (OSError, UnicodeDecodeError, ValueError) as err:
        reason = str(err).splitlines()[0] if str(err) else type(err).__name__
        raise ExportError(f"{path}: cannot read the scene's meta ({reason})") from None
    if json_depth(data, MAX_META_DEPTH) > MAX_META_DEPTH:
        raise ExportError(f"{path}: nested deeper than {MAX_META_DEPTH}; not a meta file")
    return data


def _sigmas(meta: _Meta, entries: Any, levels: list[str]) -> dict[str, tuple[float, float, float]]:
    if not isinstance(entries, list):
        raise meta.fail("levels", entries, "a list of the scene's levels")
    found: dict[str, tuple[float, float, float]] = {}
    for i, entry in enumerate(entries):
        entry = meta.mapping(entry, f"levels[{i}]")
        name = entry.get("name")
        if name not in levels:
            continue
        rgb = entry.get("sigma_rgb_per_m")
        if not (isinstance(rgb, list) and len(rgb) == 3):
            raise meta.fail(f"levels[{i}].sigma_rgb_per_m", rgb, "three numbers (R, G, B)")
        r, g, b = (meta.number(v, f"levels[{i}].sigma_rgb_per_m[{c}]") for c, v in enumerate(rgb))
        found[name] = (r, g, b)
    missing = [name for name in levels if name not in found]
    if missing:
        raise ExportError(
            f"{meta.path}: levels has no entry {missing[0]}; the dataset is damaged: rerun the "
            "'seahaze render' command that made it"
        )
    return found


def _object(
    meta: _Meta, vessel: dict[str, Any], where: str, levels: list[str], classes: int
) -> ObjectRecord:
    box = vessel["box_px"]
    if not (isinstance(box, list) and len(box) == 4):
        raise meta.fail(f"{where}.box_px", box, "[x0, y0, x1, y1] pixel edges or null")
    x0, y0, x1, y1 = (meta.number(v, f"{where}.box_px[{i}]") for i, v in enumerate(box))
    if not (x1 > x0 and y1 > y0):
        raise meta.fail(f"{where}.box_px", box, "x1 > x0 and y1 > y0")
    track = vessel.get("track_id")
    looks = meta.mapping(vessel.get("levels"), f"{where}.levels")
    by_level = {}
    for level in levels:
        look = meta.mapping(looks.get(level), f"{where}.levels.{level}")
        at = f"{where}.levels.{level}"
        by_level[level] = LevelLook(
            meta.optional(look.get("apparent_contrast"), f"{at}.apparent_contrast"),
            meta.optional(look.get("local_contrast"), f"{at}.local_contrast"),
            meta.flag(look.get("discernible"), f"{at}.discernible"),
            meta.flag(look.get("beyond_visibility"), f"{at}.beyond_visibility"),
        )
    return ObjectRecord(
        meta.integer(vessel.get("index"), f"{where}.index", 0),
        None if track is None else meta.integer(track, f"{where}.track_id", 0),
        meta.integer(vessel.get("class_id"), f"{where}.class_id", 0, classes),
        (x0, y0, x1 - x0, y1 - y0),
        meta.number(vessel.get("distance_m"), f"{where}.distance_m"),
        meta.optional(vessel.get("visible_fraction"), f"{where}.visible_fraction"),
        by_level,
    )


def _match_labels(path: Path, objects: list[ObjectRecord], size: tuple[int, int]) -> None:
    """The label file holds a line per labelled vessel of the meta, in order, of its class and
    box (to the file's 6 decimals): rows take their boxes from the meta's exact pixel edges."""
    try:
        lines = [line.split() for line in path.read_text(encoding="utf-8").splitlines()]
    except (OSError, UnicodeDecodeError) as err:
        raise ExportError(f"{path}: cannot be read ({err})") from None
    lines = [line for line in lines if line]
    problem = None
    if len(lines) != len(objects):
        problem = f"has {len(lines)} boxes where the scene's meta labels {len(objects)} vessels"
    for number, (line, obj) in enumerate(zip(lines, objects, strict=False), 1):
        if problem is not None:
            break
        x, y, w, h = obj.bbox
        expected = [obj.class_id, (x + w / 2) / size[0], (y + h / 2) / size[1]]
        expected += [w / size[0], h / size[1]]
        try:
            values = [int(line[0]), *(float(v) for v in line[1:])]
        except ValueError:
            values = []
        if len(values) != 5 or values[0] != obj.class_id:
            problem = f"line {number} is not a box of class {obj.class_id} (vessel {obj.vessel})"
        elif max(abs(a - b) for a, b in zip(values[1:], expected[1:], strict=True)) > 2e-6:
            problem = f"line {number} is not the box of vessel {obj.vessel} in the scene's meta"
    if problem is not None:
        raise ExportError(
            f"{path}: {problem}; the dataset is inconsistent: rerun the 'seahaze render' "
            "command that made it"
        )


# --------------------------------------------------------------------------------------------
# Features and shards


def features_json(classes: tuple[str, ...]) -> dict[str, Any]:
    """The ``datasets`` features of a row, as ``Features.to_dict`` of ``datasets`` 2.x and 3.x
    writes them (4.x and later read this ``Sequence`` form too)."""

    def value(dtype: str) -> dict[str, Any]:
        return {"dtype": dtype, "_type": "Value"}

    def sequence(feature: Any, length: int = -1) -> dict[str, Any]:
        return {"feature": feature, "length": length, "_type": "Sequence"}

    image = {"_type": "Image"}
    return {
        "scene": value("string"),
        "sequence": value("string"),
        "frame": value("int32"),
        "split": value("string"),
        "level": value("string"),
        "visibility_m": value("float64"),
        "sigma_per_m": value("float64"),
        "sigma_rgb_per_m": sequence(value("float64"), 3),
        "regulation": value("string"),
        "hazy": image,
        "clean": image,
        "depth": image,
        "objects": sequence(
            {
                "vessel": value("int32"),
                "track_id": value("int32"),
                "category": {"names": list(classes), "_type": "ClassLabel"},
                "bbox": sequence(value("float32"), 4),
                "distance_m": value("float64"),
                "visible_fraction": value("float64"),
                "apparent_contrast": value("float64"),
                "local_contrast": value("float64"),
                "visible": value("bool"),
                "beyond_visibility": value("bool"),
            }
        ),
    }


def arrow_schema(classes: tuple[str, ...]) -> Any:
    """The Arrow schema of a shard: exactly the types ``datasets`` derives from
    :func:`features_json` (else it ignores those features), with them as its metadata."""
    import pyarrow as pa

    image = pa.struct([("bytes", pa.binary()), ("path", pa.string())])
    objects = pa.struct(
        [
            ("vessel", pa.list_(pa.int32())),
            ("track_id", pa.list_(pa.int32())),
            ("category", pa.list_(pa.int64())),
            ("bbox", pa.list_(pa.list_(pa.float32(), 4))),
            ("distance_m", pa.list_(pa.float64())),
            ("visible_fraction", pa.list_(pa.float64())),
            ("apparent_contrast", pa.list_(pa.float64())),
            ("local_contrast", pa.list_(pa.float64())),
            ("visible", pa.list_(pa.bool_())),
            ("beyond_visibility", pa.list_(pa.bool_())),
        ]
    )
    fields = [
        ("scene", pa.string()),
        ("sequence", pa.string()),
        ("frame", pa.int32()),
        ("split", pa.string()),
        ("level", pa.string()),
        ("visibility_m", pa.float64()),
        ("sigma_per_m", pa.float64()),
        ("sigma_rgb_per_m", pa.list_(pa.float64(), 3)),
        ("regulation", pa.string()),
        ("hazy", image),
        ("clean", image),
        ("depth", image),
        ("objects", objects),
    ]
    info = {"info": {"features": features_json(classes)}}
    return pa.schema(fields, metadata={"huggingface": json.dumps(info)})


class DepthTiffs:
    """The depth TIFFs of the scenes being written: a scene's rows at every level share its
    depth, so it is encoded once per group of shards (the plan writes a group's levels in a
    row) and forgotten when the next group starts."""

    def __init__(self) -> None:
        self.group: tuple[str, ...] = ()
        self.tiffs: dict[str, bytes] = {}

    def get(self, layout: Layout, scene: str, group: tuple[str, ...]) -> bytes:
        if group != self.group:
            self.group, self.tiffs = group, {}
        if scene not in self.tiffs:
            self.tiffs[scene] = depth_tiff(layout.depth(scene))
        return self.tiffs[scene]


def depth_tiff(path: Path) -> bytes:
    """The distance channel ``Z`` of a depth EXR as a float32 TIFF (deflate, floating-point
    predictor): PIL opens it as a mode ``F`` image, exactly the EXR's values, inf included."""
    from PIL import Image

    try:
        depth = np.ascontiguousarray(read_exr(path)["Z"], dtype=np.float32)
    except (OSError, RuntimeError, KeyError, ValueError) as err:
        raise ExportError(
            f"{path}: cannot read the depth ({err}); the dataset is damaged"
        ) from None
    out = io.BytesIO()
    Image.fromarray(depth).save(
        out,
        format="TIFF",
        compression="tiff_adobe_deflate",
        tiffinfo={317: TIFF_PREDICTOR_FLOAT},  # 317: the TIFF Predictor tag
    )
    return out.getvalue()


def write_shard(
    path: Path, rows: list[SceneRecord], level: Level, source: SourceDataset, depth: DepthTiffs
) -> None:
    """Write the rows of ``rows``' scenes at ``level`` to the Parquet file ``path``."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    schema = arrow_schema(source.classes)
    regulation = _regulation(source, level.name)
    group = tuple(record.scene for record in rows)
    layout = source.layout
    strings = ["scene", "sequence", "split", "level", "regulation"]
    with pq.ParquetWriter(path, schema, compression="zstd", use_dictionary=strings) as writer:
        batch: list[dict[str, Any]] = []
        size = 0
        for record in rows:
            row = _row(record, level, regulation, layout, depth.get(layout, record.scene, group))
            batch.append(row)
            size += sum(len(row[key]["bytes"]) for key in ("hazy", "clean", "depth"))
            if len(batch) >= ROWS_PER_GROUP or size >= MAX_GROUP_BYTES:
                writer.write_table(pa.Table.from_pylist(batch, schema=schema))
                batch, size = [], 0
        if batch:
            writer.write_table(pa.Table.from_pylist(batch, schema=schema))


def _regulation(source: SourceDataset, level: str) -> str | None:
    """The regulation class of ``level`` in ``dataset.json`` (null where it has none)."""
    for entry in source.manifest.get("levels", []):
        if isinstance(entry, dict) and entry.get("name") == level:
            value = entry.get("regulation")
            return value if isinstance(value, str) else None
    return None


def _row(
    record: SceneRecord, level: Level, regulation: str | None, layout: Layout, depth: bytes
) -> dict[str, Any]:
    scene = record.scene
    looks = [obj.levels[level.name] for obj in record.objects]
    return {
        "scene": scene,
        "sequence": record.sequence,
        "frame": record.frame,
        "split": record.split,
        "level": level.name,
        "visibility_m": level.visibility_m,
        "sigma_per_m": level.sigma_per_m,
        "sigma_rgb_per_m": list(record.sigma_rgb[level.name]),
        "regulation": regulation,
        "hazy": _image(layout.image(level.name, scene), f"{scene}_{level.name}.png"),
        "clean": _image(layout.image(CLEAN_LEVEL, scene), f"{scene}.png"),
        "depth": {"bytes": depth, "path": f"{scene}_depth.tiff"},
        "objects": {
            "vessel": [obj.vessel for obj in record.objects],
            "track_id": [obj.track_id for obj in record.objects],
            "category": [obj.class_id for obj in record.objects],
            "bbox": [list(obj.bbox) for obj in record.objects],
            "distance_m": [obj.distance_m for obj in record.objects],
            "visible_fraction": [obj.visible_fraction for obj in record.objects],
            "apparent_contrast": [look.apparent_contrast for look in looks],
            "local_contrast": [look.local_contrast for look in looks],
            "visible": [look.visible for look in looks],
            "beyond_visibility": [look.beyond_visibility for look in looks],
        },
    }


def _image(path: Path, name: str) -> dict[str, Any]:
    """An Image value: the file's bytes (decoded by ``datasets`` on access), named ``name``."""
    return {"bytes": path.read_bytes(), "path": name}
