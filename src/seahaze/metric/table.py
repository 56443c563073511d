"""The visibility–detection calibration table and the New Visibility of the MSVD paper (Eq. 5).

A calibration table maps graded visibility levels ``v_1 < … < v_n`` (m) to a detector's mAP50
``I_1 … I_n`` on the hazy images of each level. A restored accuracy ``I'`` (mAP50 of the same
detector on dehazed images) is mapped back to a visibility by piecewise-linear interpolation:

    v' = v_j + (I' - I_j) / (I_{j+1} - I_j) * (v_{j+1} - v_j)    for I' in [I_j, I_{j+1}]

Rules that the paper leaves implicit (see docs/metric.md):

* **Above the table** (``I'`` greater than every ``I_k``): the visibility is beyond the calibrated
  range; it is reported as the bound ``> v`` (the paper prints '-' for "> 4000 m"), never
  extrapolated.
* **Below the table** (``I' < I_1``): the lowest level ``v_1`` is reported as an upper bound
  (``<= v_1``), as the paper does for SGIF-PFF at 300 m (0.074 < 0.078 → 300 m), flagged.
* **Non-monotone table** (some ``I_{k+1} <= I_k``): Eq. 5 is applied to the running maximum
  ``E_k = max(I_1..I_k)`` (the monotone upper envelope) and, where several visibilities reach the
  value, the lowest is taken. For a strictly increasing table this is exactly Eq. 5; otherwise it
  never reports more visibility than the first crossing of the raw curve, so dehazing gains are
  not overstated. The violations are reported to the user.
"""

from __future__ import annotations

import csv
import json
import math
import os
import stat
from collections.abc import Sequence
from dataclasses import dataclass, field
from enum import StrEnum
from itertools import pairwise
from pathlib import Path
from typing import Any

from seahaze.fileio import json_depth
from seahaze.metric.errors import MetricInputError, located
from seahaze.visibility import REGULATION_CLASSES, RegulationClass, regulation_class

MAX_TABLE_BYTES = 1 << 20
"""Largest table file read (1 MiB; a table of 64 levels is about 10 kB)."""
MAX_TABLE_DEPTH = 32
"""Deepest JSON nesting read (a table needs 3: levels[i].map50; kept extras a few more)."""

TABLE_FORMAT = "seahaze.metric.table/1"
"""The ``format`` tag written into (and expected in) a table's JSON file."""

CSV_COLUMNS: tuple[str, str] = ("visibility_m", "map50")
"""The columns of a table's CSV file."""


@dataclass(frozen=True)
class CalibrationPoint:
    """One row of a calibration table: a visibility level and the detector's mAP50 there."""

    visibility_m: float
    map50: float
    level: str | None = None
    """Dataset folder of the level (``v0300``), when the point was measured by seahaze."""
    map50_95: float | None = None
    images: int | None = None
    objects: int | None = None
    detections: int | None = None


@dataclass(frozen=True)
class CalibrationTable:
    """A detector's visibility → mAP50 mapping (paper, Stage 1), sorted by visibility.

    Build it with :func:`make_table` (or the loaders), which validate the points.
    """

    points: tuple[CalibrationPoint, ...]
    detector: str | None = None
    evaluator: str | None = None
    """Which AP implementation produced the mAP50 values; tables from different evaluators are
    not interchangeable (docs/metric.md, "COCO AP50 versus Ultralytics")."""
    dataset: str | None = None
    extra: dict[str, object] = field(default_factory=dict, compare=False)
    """Additional JSON fields kept on a round trip (for example the clean level's scores)."""

    @property
    def visibilities_m(self) -> tuple[float, ...]:
        """The levels ``v_1 < … < v_n`` in metres."""
        return tuple(p.visibility_m for p in self.points)

    @property
    def map50s(self) -> tuple[float, ...]:
        """The mAP50 values ``I_1 … I_n`` in level order."""
        return tuple(p.map50 for p in self.points)

    @property
    def envelope(self) -> tuple[float, ...]:
        """The running maximum ``E_k = max(I_1..I_k)`` that the interpolation inverts."""
        return running_max(self.map50s)

    def violations(self) -> list[tuple[CalibrationPoint, CalibrationPoint]]:
        """Adjacent pairs whose mAP50 does not increase with visibility (``I_{k+1} <= I_k``)."""
        return [(a, b) for a, b in pairwise(self.points) if b.map50 <= a.map50]

    @property
    def is_monotone(self) -> bool:
        """Whether mAP50 strictly increases with visibility, so Eq. 5 has a unique answer."""
        return not self.violations()


def running_max(values: Sequence[float]) -> tuple[float, ...]:
    """The running maximum of ``values`` (same length)."""
    out: list[float] = []
    for value in values:
        out.append(value if not out else max(out[-1], value))
    return tuple(out)


def make_table(
    points: Sequence[CalibrationPoint],
    *,
    detector: str | None = None,
    evaluator: str | None = None,
    dataset: str | None = None,
    extra: dict[str, object] | None = None,
) -> CalibrationTable:
    """Validate ``points`` and return them as a :class:`CalibrationTable` sorted by visibility.

    Raises :class:`MetricInputError` for fewer than 2 points, a visibility that is not a finite
    positive number of metres, an mAP50 outside [0, 1] or a visibility given twice.
    """
    if len(points) < 2:
        raise MetricInputError(
            f"a calibration table needs at least 2 levels to interpolate, got {len(points)}"
        )
    for p in points:
        if not (math.isfinite(p.visibility_m) and p.visibility_m > 0):
            raise MetricInputError(
                f"visibility must be a finite number of metres > 0, got {p.visibility_m!r}"
            )
        if not (math.isfinite(p.map50) and 0.0 <= p.map50 <= 1.0):
            raise MetricInputError(f"mAP50 must be a number in [0, 1], got {p.map50!r}")
    ordered = tuple(sorted(points, key=lambda p: p.visibility_m))
    for a, b in pairwise(ordered):
        if a.visibility_m == b.visibility_m:
            raise MetricInputError(
                f"visibility {a.visibility_m:g} m appears twice; give one row per level"
            )
    return CalibrationTable(
        ordered, detector=detector, evaluator=evaluator, dataset=dataset, extra=dict(extra or {})
    )


# --------------------------------------------------------------------------------------------
# New Visibility (Eq. 5)


class Bound(StrEnum):
    """Where a restored mAP50 falls relative to the calibration table."""

    WITHIN = "within"
    """Interpolated by Eq. 5."""
    ABOVE = "above"
    """Higher than every table value: visibility beyond the table (``> visibility_m``)."""
    BELOW = "below"
    """Lower than the first level's value: the lowest level is an upper bound (``<= v_1``)."""


@dataclass(frozen=True)
class NewVisibility:
    """The visibility a restored mAP50 corresponds to (paper, Stage 2)."""

    map50: float
    visibility_m: float
    """Eq. 5's value when ``bound`` is WITHIN; otherwise the table bound it exceeds/undercuts."""
    bound: Bound
    bracket: tuple[CalibrationPoint, CalibrationPoint] | None
    """The envelope points ``(v_j, E_j)``, ``(v_{j+1}, E_{j+1})`` used by Eq. 5 (WITHIN only;
    both equal the first point when the value equals ``I_1``)."""
    level_m: float | None = None
    """Visibility of the hazy input the restored images came from, for the gain."""

    @property
    def gain_m(self) -> float | None:
        """``visibility_m - level_m`` (a bound itself when ``bound`` is not WITHIN)."""
        return None if self.level_m is None else self.visibility_m - self.level_m

    @property
    def regulation(self) -> RegulationClass:
        """The paper's Table 1 class of ``visibility_m`` (a bound when ``bound`` is not WITHIN)."""
        return regulation_class(self.visibility_m)


def new_visibility(
    table: CalibrationTable, map50: float, level_m: float | None = None
) -> NewVisibility:
    """Map a restored mAP50 to a visibility with Eq. 5 on the table's monotone envelope.

    ``level_m`` is the physical visibility of the hazy images that were restored; it only feeds
    :attr:`NewVisibility.gain_m`. Values outside the table are returned as flagged bounds (see the
    module docstring), never extrapolated. Raises :class:`MetricInputError` if ``map50`` is not a
    number in [0, 1] or ``level_m`` is not a positive distance.
    """
    if not (math.isfinite(map50) and 0.0 <= map50 <= 1.0):
        raise MetricInputError(f"mAP50 must be a number in [0, 1], got {map50!r}")
    if level_m is not None and not (math.isfinite(level_m) and level_m > 0):
        raise MetricInputError(f"level must be a visibility in metres > 0, got {level_m!r}")
    env = table.envelope
    pts = table.points
    if map50 > env[-1]:
        # Bound at the first level that reaches the table's best mAP50: for a monotone table that
        # is the last level (the paper's '> 4000 m'); beyond it nothing was calibrated.
        top = pts[env.index(env[-1])]
        return NewVisibility(map50, top.visibility_m, Bound.ABOVE, None, level_m)
    if map50 < env[0]:
        return NewVisibility(map50, pts[0].visibility_m, Bound.BELOW, None, level_m)
    k = next(i for i, e in enumerate(env) if e >= map50)
    if k == 0:
        return NewVisibility(map50, pts[0].visibility_m, Bound.WITHIN, (pts[0], pts[0]), level_m)
    # env[k-1] < map50 <= env[k], and env[k] == I_k because the envelope rose at k.
    lo = CalibrationPoint(pts[k - 1].visibility_m, env[k - 1], pts[k - 1].level)
    hi = pts[k]
    v = lo.visibility_m + (map50 - lo.map50) / (hi.map50 - lo.map50) * (
        hi.visibility_m - lo.visibility_m
    )
    return NewVisibility(map50, v, Bound.WITHIN, (lo, hi), level_m)


def round_m(value: float) -> int:
    """Round metres half up, as a table of whole metres is printed (not banker's rounding)."""
    return math.floor(value + 0.5)


def class_range(cls: RegulationClass) -> str:
    """The visibility range of a regulation class in words (``1000–2000 m``, ``>= 4000 m``)."""
    i = REGULATION_CLASSES.index(cls)
    lower = 0.0 if i == 0 else REGULATION_CLASSES[i - 1].upper_m
    if math.isinf(cls.upper_m):
        return f">= {lower:g} m"
    return f"< {cls.upper_m:g} m" if lower == 0 else f"{lower:g}–{cls.upper_m:g} m"


def describe(result: NewVisibility, table: CalibrationTable) -> list[str]:
    """Human-readable lines for a :class:`NewVisibility` (used by ``seahaze metric newvis``)."""
    cls = result.regulation
    v = round_m(result.visibility_m)
    lines = [f"mAP50: {result.map50:.4f}"]
    if result.bound is Bound.WITHIN:
        lo, hi = result.bracket or (table.points[0], table.points[0])
        how = (
            "equals the first level"
            if lo is hi
            else f"Eq. 5 between {lo.visibility_m:g} m (mAP50 {lo.map50:.4f}) and "
            f"{hi.visibility_m:g} m (mAP50 {hi.map50:.4f})"
        )
        if lo is not hi and not table.is_monotone:
            how += " of the table's running maximum"
        lines.append(f"new visibility: {v} m ({how})")
        regulation = f"{cls.label} ({cls.haze}, {class_range(cls)})"
        prefix = ""
    elif result.bound is Bound.ABOVE:
        lines.append(
            f"new visibility: > {v} m (beyond the table: mAP50 above its highest value, "
            f"{max(table.map50s):.4f}; the paper prints '-')"
        )
        regulation = f"at least {cls.label} ({class_range(cls)})"
        prefix = "> "
    else:
        lines.append(
            f"new visibility: <= {v} m (lower bound: mAP50 below the first level's "
            f"{table.points[0].map50:.4f} at {v} m; not extrapolated)"
        )
        regulation = f"{cls.label} or stricter (visibility at most {v} m)"
        prefix = "<= "
    if result.level_m is not None and result.gain_m is not None:
        gain = round_m(result.visibility_m) - round_m(result.level_m)
        lines.append(f"gain: {prefix}{gain:+d} m over {result.level_m:g} m")
    lines.append(f"regulation class: {regulation}")
    return lines


# --------------------------------------------------------------------------------------------
# Files


def table_paths(out: Path | str) -> tuple[Path, Path]:
    """The CSV and JSON paths of a table written to ``out`` (a ``.csv``/``.json`` suffix is
    dropped: ``--out tables/yolo11`` → ``tables/yolo11.csv`` and ``tables/yolo11.json``)."""
    path = Path(out)
    if path.suffix.lower() in (".csv", ".json"):
        path = path.with_suffix("")
    return path.with_name(path.name + ".csv"), path.with_name(path.name + ".json")


def table_to_json(table: CalibrationTable) -> dict[str, object]:
    """The JSON document of a table (``format``, ``detector``, ``evaluator``, ``levels``...)."""
    levels = []
    for p in table.points:
        row: dict[str, object] = {"visibility_m": p.visibility_m, "map50": p.map50}
        for key in ("level", "map50_95", "images", "objects", "detections"):
            value = getattr(p, key)
            if value is not None:
                row[key] = value
        levels.append(row)
    doc: dict[str, object] = {
        "format": TABLE_FORMAT,
        "detector": table.detector,
        "metric": "mAP50",
        "evaluator": table.evaluator,
        "dataset": table.dataset,
        "levels": levels,
    }
    doc.update(table.extra)
    return doc


def save_table(table: CalibrationTable, out: Path | str) -> tuple[Path, Path]:
    """Write ``table`` as CSV (``visibility_m,map50``) and JSON next to each other.

    Returns the two paths (see :func:`table_paths`). Parent folders are created. A file in the
    way that is not a table seahaze wrote (a JSON without its format tag, a CSV without its
    header or without that JSON beside it) is never overwritten: :class:`MetricInputError`
    names it, nothing written.
    """
    csv_path, json_path = table_paths(out)
    for path in (csv_path, json_path):
        if (path.exists() or path.is_symlink()) and not _written_by_seahaze(csv_path, json_path):
            raise MetricInputError(
                f"{path} exists and is not a calibration table seahaze wrote; it is never "
                "overwritten: choose another --out or move it"
            )
    csv_path.parent.mkdir(parents=True, exist_ok=True)
    with csv_path.open("w", newline="", encoding="utf-8") as fh:
        writer = csv.writer(fh, lineterminator="\n")
        writer.writerow(CSV_COLUMNS)
        for p in table.points:
            writer.writerow([f"{p.visibility_m:g}", repr(p.map50)])
    json_path.write_text(json.dumps(table_to_json(table), indent=2) + "\n", encoding="utf-8")
    return csv_path, json_path


def _written_by_seahaze(csv_path: Path, json_path: Path) -> bool:
    """Whether the table files at these paths are a pair seahaze wrote: regular files, the JSON
    tagged with :data:`TABLE_FORMAT`, the CSV (if there) opening with :data:`CSV_COLUMNS`."""
    try:
        if json_path.is_symlink() or not json_path.is_file() or csv_path.is_symlink():
            return False
        if json.loads(json_path.read_text(encoding="utf-8")).get("format") != TABLE_FORMAT:
            return False
        if csv_path.exists():
            with csv_path.open(encoding="utf-8", newline="") as fh:
                return next(csv.reader(fh), None) == list(CSV_COLUMNS)
    except (OSError, ValueError, AttributeError, UnicodeDecodeError, RecursionError):
        return False
    return True


def load_table(path: Path | str) -> CalibrationTable:
    """Read a calibration table from a ``.json`` (seahaze's) or ``.csv`` (``visibility_m,map50``)
    file. A path without suffix that does not exist is tried as ``.json`` then ``.csv``.

    Raises :class:`MetricInputError` naming the file (and line) for anything unusable.
    """
    path = Path(path)
    if not path.exists() and not path.suffix:
        for candidate in (path.with_name(path.name + ".json"), path.with_name(path.name + ".csv")):
            if candidate.is_file():
                path = candidate
                break
    if not path.is_file():
        what = (
            "not a regular file (a folder, FIFO or device); expected a calibration table"
            if path.exists()
            else "calibration table not found"
        )
        raise located(path, f"{what} (a .json or .csv file written by 'seahaze metric calibrate')")
    text = _read_text(path)
    is_json = path.suffix.lower() == ".json" or (
        path.suffix.lower() != ".csv" and text.lstrip().startswith("{")
    )
    try:
        return _table_from_json(path, text) if is_json else _table_from_csv(path, text)
    except MetricInputError as exc:
        if str(exc).startswith(str(path)):
            raise
        raise located(path, str(exc)) from None


def _read_text(path: Path) -> str:
    """The UTF-8 text of the table file (a BOM dropped), at most :data:`MAX_TABLE_BYTES`; the
    file is opened without blocking (``is_file`` was checked, but it may be swapped since)."""
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
        with os.fdopen(fd, "rb") as handle:
            if not stat.S_ISREG(os.fstat(handle.fileno()).st_mode):
                raise located(path, "not a regular file; expected a .json or .csv table")
            raw = handle.read(MAX_TABLE_BYTES + 1)
    except OSError as exc:
        raise located(path, f"cannot read the table ({exc.strerror or exc})") from None
    if len(raw) > MAX_TABLE_BYTES:
        raise located(path, "larger than 1 MiB; a calibration table is a few kB")
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw[: exc.start].count(b"\n") + 1
        raise located(path, "not UTF-8 text; expected a .json or .csv table", line) from None


def _shown(text: object) -> str:
    """A value for a one-line message: a short repr of a string or number, else its kind (a
    nested value's repr could be pages long or recurse)."""
    if isinstance(text, str):
        return repr(text[:40] + ("…" if len(text) > 40 else ""))
    if isinstance(text, float) or (isinstance(text, int) and abs(text) < 10**40):
        return repr(text)
    if isinstance(text, int):
        return "an integer of more than 40 digits"
    return {dict: "an object", list: "a list", type(None): "null"}.get(type(text), "a value")


def _number(path: Path, line: int | None, column: str, text: object) -> float:
    """``text`` as a float, or a located error naming the column."""
    if isinstance(text, bool) or not isinstance(text, str | int | float):
        raise located(path, f"{column} must be a number, got {_shown(text)}", line)
    try:
        value = float(text)
    except ValueError:
        raise located(path, f"{column} must be a number, got {_shown(text)}", line) from None
    except OverflowError:  # an integer beyond float
        raise located(path, f"{column} must be a finite number, got {_shown(text)}", line) from None
    if not math.isfinite(value):
        raise located(path, f"{column} must be a finite number, got {_shown(text)}", line)
    return value


def _table_from_csv(path: Path, text: str) -> CalibrationTable:
    rows = csv.reader(text.splitlines())
    try:
        return _rows_to_table(path, rows)
    except csv.Error as exc:  # a NUL byte, a field past the csv module's size limit
        raise located(path, f"not a CSV table ({exc})", rows.line_num) from None


def _rows_to_table(path: Path, rows: Any) -> CalibrationTable:
    """The table of the CSV reader ``rows`` (a header, then one row per level)."""
    header: list[str] | None = None
    points: list[CalibrationPoint] = []
    for row in rows:
        line = rows.line_num
        if not row or all(not cell.strip() for cell in row) or row[0].lstrip().startswith("#"):
            continue
        cells = [cell.strip() for cell in row]
        if header is None:
            header = [cell.lower() for cell in cells]
            missing = [c for c in CSV_COLUMNS if c not in header]
            if missing:
                raise located(
                    path,
                    f"header must name the columns {','.join(CSV_COLUMNS)}, "
                    f"got {_shown(','.join(cells))}",
                    line,
                )
            continue
        if len(cells) != len(header):
            raise located(
                path,
                f"expected {len(header)} comma-separated values "
                f"({','.join(header)}), got {len(cells)}",
                line,
            )
        vis = _number(path, line, "visibility_m", cells[header.index("visibility_m")])
        m = _number(path, line, "map50", cells[header.index("map50")])
        if vis <= 0:
            raise located(path, f"visibility_m must be > 0 m, got {vis:g}", line)
        if not 0.0 <= m <= 1.0:
            raise located(path, f"map50 must be in [0, 1], got {m:g}", line)
        points.append(CalibrationPoint(vis, m))
    if header is None:
        raise located(
            path, f"empty table; expected a header '{','.join(CSV_COLUMNS)}' and at least 2 rows"
        )
    return make_table(points)


def _table_from_json(path: Path, text: str) -> CalibrationTable:
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise located(path, f"not valid JSON ({exc.msg})", exc.lineno) from None
    except RecursionError:
        raise located(path, f"JSON nested deeper than {MAX_TABLE_DEPTH}; not a table") from None
    except ValueError as exc:  # an integer of more than 4300 digits
        raise located(path, f"not a usable JSON table ({str(exc).splitlines()[0]})") from None
    if json_depth(doc, MAX_TABLE_DEPTH) > MAX_TABLE_DEPTH:
        raise located(path, f"JSON nested deeper than {MAX_TABLE_DEPTH}; not a table")
    if not isinstance(doc, dict) or not isinstance(doc.get("levels"), list):
        raise located(
            path, "expected a JSON object with a 'levels' list of {visibility_m, map50} objects"
        )
    for key in ("detector", "evaluator", "dataset"):
        if doc.get(key) is not None and not isinstance(doc[key], str):
            raise located(path, f"{key} must be a name (a string) or null, got {_shown(doc[key])}")
    points: list[CalibrationPoint] = []
    for i, row in enumerate(doc["levels"]):
        if not isinstance(row, dict) or "visibility_m" not in row or "map50" not in row:
            raise located(path, f"levels[{i}] must be an object with visibility_m and map50")
        where = f"levels[{i}]"
        vis = _number(path, None, f"{where}.visibility_m", row["visibility_m"])
        m = _number(path, None, f"{where}.map50", row["map50"])
        points.append(
            CalibrationPoint(
                vis,
                m,
                level=_opt_str(row.get("level")),
                map50_95=_opt_float(row.get("map50_95")),
                images=_opt_int(row.get("images")),
                objects=_opt_int(row.get("objects")),
                detections=_opt_int(row.get("detections")),
            )
        )
    known = {"format", "detector", "metric", "evaluator", "dataset", "levels"}
    extra = {k: v for k, v in doc.items() if k not in known}
    return make_table(
        points,
        detector=_opt_str(doc.get("detector")),
        evaluator=_opt_str(doc.get("evaluator")),
        dataset=_opt_str(doc.get("dataset")),
        extra=extra,
    )


def _opt_str(value: object) -> str | None:
    return None if value is None else str(value)


def _opt_float(value: object) -> float | None:
    if not isinstance(value, int | float) or isinstance(value, bool):
        return None
    try:
        number = float(value)
    except OverflowError:  # an integer beyond float: not a score
        return None
    return number if math.isfinite(number) else None


def _opt_int(value: object) -> int | None:
    return value if isinstance(value, int) and not isinstance(value, bool) else None
