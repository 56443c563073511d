"""Meteorological visibility: extinction, graded levels and navigation regulation classes.

Every visibility-related constant of seahaze lives here.

Extinction from visibility (Koschmieder's law)
    A black object seen against the horizon sky through a homogeneous atmosphere has apparent
    contrast ``C(d) = -exp(-sigma * d)``. The visibility ``V`` is the distance at which ``|C|``
    falls to the observer's contrast threshold ``eps``, hence ``sigma = -ln(eps) / V``.

    * ``koschmieder`` (default): ``eps = 0.02`` → ``sigma = 3.912 / V`` (Koschmieder 1924;
      Middleton, *Vision through the Atmosphere*, 1952). This is the convention of the MSVD paper
      and of most dehazing literature.
    * ``mor``: ``eps = 0.05`` → ``sigma = 2.996 / V``, the WMO meteorological optical range
      (WMO-No. 8, *Guide to Instruments and Methods of Observation*, Vol. I, ch. 9; CIE 17.4).

    Both are defined at 550 nm. seahaze never mixes them: a dataset records its convention.

Graded levels
    The 11 levels (m) of the MSVD paper, Table 2: 300 400 500 800 1000 1300 1600 2000 2500 3000
    4000.

Regulation classes
    MSVD paper, Table 1 (navigation measures by visibility): < 50 m suspended; < 200 m near
    suspension; < 500 m strict restrictions; < 1000 m restricted; < 2000 m minor restrictions;
    < 4000 m normal navigation. Visibility of 4000 m and beyond is reported as ``clear``.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from enum import StrEnum

import numpy as np

GRADED_LEVELS_M: tuple[int, ...] = (300, 400, 500, 800, 1000, 1300, 1600, 2000, 2500, 3000, 4000)
"""The MSVD graded visibility levels in metres (paper, Table 2)."""


class Threshold(StrEnum):
    """Contrast-threshold convention that links visibility to extinction."""

    KOSCHMIEDER = "koschmieder"
    MOR = "mor"


CONTRAST_THRESHOLD: dict[Threshold, float] = {
    Threshold.KOSCHMIEDER: 0.02,
    Threshold.MOR: 0.05,
}
"""Observer contrast threshold ``eps`` per convention (dimensionless)."""


def extinction_coefficient(
    visibility_m: float | np.ndarray, threshold: Threshold | str = Threshold.KOSCHMIEDER
) -> float | np.ndarray:
    """Extinction coefficient ``sigma`` (1/m) at 550 nm for a visibility ``V`` (m).

    ``sigma = -ln(eps) / V``: 3.912 / V for Koschmieder (eps = 2 %), 2.996 / V for WMO MOR
    (eps = 5 %). Raises ``ValueError`` for a non-positive or non-finite visibility.
    """
    eps = CONTRAST_THRESHOLD[Threshold(threshold)]
    v = np.asarray(visibility_m, dtype=float)
    if not np.all(np.isfinite(v)) or np.any(v <= 0):
        raise ValueError(f"visibility must be a finite positive distance in metres, got {v}")
    sigma = -math.log(eps) / v
    return float(sigma) if sigma.ndim == 0 else sigma


def visibility_from_extinction(
    sigma_per_m: float, threshold: Threshold | str = Threshold.KOSCHMIEDER
) -> float:
    """Inverse of :func:`extinction_coefficient`: the visibility (m) for ``sigma`` (1/m)."""
    if not math.isfinite(sigma_per_m) or sigma_per_m <= 0:
        raise ValueError(f"extinction must be finite and positive, got {sigma_per_m}")
    return -math.log(CONTRAST_THRESHOLD[Threshold(threshold)]) / sigma_per_m


def koschmieder_contrast(
    distance_m: float | np.ndarray,
    visibility_m: float,
    threshold: Threshold | str = Threshold.KOSCHMIEDER,
) -> float | np.ndarray:
    """Apparent contrast of a black target at ``distance_m`` against the horizon: "
    "``-exp(-sigma d)``."""
    return -np.exp(-extinction_coefficient(visibility_m, threshold) * np.asarray(distance_m))


@dataclass(frozen=True)
class RegulationClass:
    """A navigation regulation class of the MSVD paper, Table 1."""

    key: str
    label: str
    haze: str
    """The paper's haze-density name for the class."""
    upper_m: float
    """Visibilities strictly below this bound (m) fall in the class."""


REGULATION_CLASSES: tuple[RegulationClass, ...] = (
    RegulationClass("suspended", "Navigation suspended", "very dense haze", 50.0),
    RegulationClass("near_suspension", "Near suspension of navigation", "dense haze", 200.0),
    RegulationClass("strict", "Strict navigation restrictions", "moderate haze", 500.0),
    RegulationClass("restricted", "Restricted navigation", "light haze", 1000.0),
    RegulationClass("minor", "Minor restrictions", "thin haze", 2000.0),
    RegulationClass("normal", "Normal navigation", "poor visibility", 4000.0),
    RegulationClass("clear", "Normal navigation (clear)", "clear", math.inf),
)
"""Classes in increasing visibility; a visibility belongs to the first whose bound exceeds it."""


def regulation_class(visibility_m: float) -> RegulationClass:
    """The navigation regulation class for a visibility in metres (paper, Table 1)."""
    if math.isnan(visibility_m) or visibility_m < 0:
        raise ValueError(
            f"visibility must be a non-negative distance in metres, got {visibility_m}"
        )
    for cls in REGULATION_CLASSES:
        if visibility_m < cls.upper_m:
            return cls
    return REGULATION_CLASSES[-1]


def level_name(visibility_m: float) -> str:
    """Folder name of a level: ``v`` plus the metres, zero-padded to 4 digits (``v0300``)."""
    return f"v{round(visibility_m):04d}"


class VisSelectionError(ValueError):
    """A ``--vis`` selection that cannot be parsed; the message is one line for the user."""


_NUMBER = r"\d+(?:\.\d+)?"
_RANGE = re.compile(rf"^({_NUMBER})\.\.({_NUMBER})(?::(\d+))?$")


def _positive(text: str, spec: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise VisSelectionError(f"--vis {spec!r}: {text!r} is not a number of metres") from None
    if not math.isfinite(value) or value <= 0:
        raise VisSelectionError(f"--vis {spec!r}: visibility must be > 0 m, got {text}")
    return value


def parse_vis_selection(spec: str) -> list[float]:
    """Parse a ``--vis`` selection into sorted visibilities in metres.

    Forms: ``A..B`` — the graded levels inside ``[A, B]``; ``A..B:N`` — ``N`` log-spaced levels
    from ``A`` to ``B`` inclusive (rounded to whole metres); ``300,1000,2500`` — exactly these.
    Raises :class:`VisSelectionError` with a one-line message on anything else.
    """
    text = spec.strip()
    if not text:
        raise VisSelectionError("--vis is empty; use A..B, A..B:N or a comma list like 300,1000")
    match = _RANGE.match(text)
    if match:
        lo, hi = _positive(match[1], spec), _positive(match[2], spec)
        if lo > hi:
            raise VisSelectionError(f"--vis {spec!r}: range is reversed ({lo:g} > {hi:g})")
        if match[3] is not None:
            count = int(match[3])
            if count < 1:
                raise VisSelectionError(f"--vis {spec!r}: the level count must be >= 1")
            if count == 1:
                return [float(round(lo))]
            values = np.geomspace(lo, hi, count)
            levels = sorted({float(round(v)) for v in values})
            if len(levels) < count:
                raise VisSelectionError(
                    f"--vis {spec!r}: {count} levels do not fit between {lo:g} and {hi:g} m "
                    "at 1 m resolution"
                )
            return levels
        levels = [float(v) for v in GRADED_LEVELS_M if lo <= v <= hi]
        if not levels:
            raise VisSelectionError(
                f"--vis {spec!r}: no graded level lies in [{lo:g}, {hi:g}] m "
                f"(graded levels: {', '.join(map(str, GRADED_LEVELS_M))})"
            )
        return levels
    if ".." in text:
        raise VisSelectionError(f"--vis {spec!r}: expected A..B or A..B:N with numbers in metres")
    parts = [p.strip() for p in text.split(",")]
    if any(not p for p in parts):
        raise VisSelectionError(f"--vis {spec!r}: empty entry in the comma list")
    return sorted({_positive(p, spec) for p in parts})
