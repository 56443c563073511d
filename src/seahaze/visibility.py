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

Wavelength-dependent extinction (optional)
    Haze extinction falls with wavelength as ``sigma(λ) = sigma550 · (λ / 550 nm)^-q``. Kim's
    size-distribution exponent ``q(V)`` (Kim, McArthur & Korevaar 2001, "Comparison of laser
    beam propagation at 785 nm and 1550 nm in fog and haze for optical wireless
    communications", Proc. SPIE 4214, 26–37; V in km): 1.6 for V > 50, 1.3 for 6 < V ≤ 50,
    0.16 V + 0.34 for 1 < V ≤ 6, V − 0.5 for 0.5 < V ≤ 1, 0 for V ≤ 0.5 (fog is grey). Each RGB
    channel takes the extinction at its effective wavelength (647, 544, 443 nm): the wavelength
    whose extinction is the mean extinction over the channel's response to daylight, so that
    the channel's transmittance is right to first order in the optical depth. The label V
    stays defined at 550 nm.

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

REFERENCE_WAVELENGTH_NM = 550.0
"""Wavelength (nm) at which visibility and the extinction ``sigma = -ln(eps) / V`` are defined."""

CHANNEL_WAVELENGTHS_NM: tuple[float, float, float] = (647.0, 544.0, 443.0)
"""Effective wavelengths (nm) of the linear-sRGB R, G, B channels for haze extinction:
``λ_c = 550 · <(λ/550)^-q>_c^(-1/q)``, the mean over the channel's spectral response to D65
daylight (CIE 1931 2° colour-matching functions → linear sRGB, IEC 61966-2-1). Computed with
colour-science at q = 1; they move by under 2 nm over q = 0.5 … 1.3 (tests/test_visibility.py)."""

GRADED_LEVELS_M: tuple[int, ...] = (300, 400, 500, 800, 1000, 1300, 1600, 2000, 2500, 3000, 4000)
"""The MSVD graded visibility levels in metres (paper, Table 2)."""


class Threshold(StrEnum):
    """Contrast-threshold convention that links visibility to extinction."""

    KOSCHMIEDER = "koschmieder"
    MOR = "mor"


class ExtinctionSpectrum(StrEnum):
    """How the haze extinction depends on wavelength."""

    GREY = "grey"
    """The same extinction ``sigma550`` in every channel (the MSVD convention)."""
    KIM = "kim"
    """``sigma550 · (λ / 550)^-q(V)`` per channel, with Kim's ``q(V)``."""


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


def kim_exponent(visibility_m: float) -> float:
    """Kim's wavelength exponent ``q`` (dimensionless) for a visibility ``V`` in metres.

    Piecewise in ``V`` (km): 1.6 above 50, 1.3 above 6, ``0.16 V + 0.34`` above 1, ``V − 0.5``
    above 0.5, else 0 (Kim, McArthur & Korevaar 2001). Continuous except at 50 km.
    """
    if not math.isfinite(visibility_m) or visibility_m <= 0:
        raise ValueError(
            f"visibility must be a finite positive distance in metres, got {visibility_m}"
        )
    v_km = visibility_m / 1000.0
    if v_km > 50.0:
        return 1.6
    if v_km > 6.0:
        return 1.3
    if v_km > 1.0:
        return 0.16 * v_km + 0.34
    if v_km > 0.5:
        return v_km - 0.5
    return 0.0


def channel_extinction(
    visibility_m: float,
    threshold: Threshold | str = Threshold.KOSCHMIEDER,
    spectrum: ExtinctionSpectrum | str = ExtinctionSpectrum.GREY,
) -> np.ndarray:
    """Extinction coefficients (1/m) of the R, G, B channels, shape (3,), for visibility ``V``.

    ``grey``: ``sigma550`` in all three. ``kim``: ``sigma550 · (λ_c / 550)^-q(V)`` at the
    channels' effective wavelengths :data:`CHANNEL_WAVELENGTHS_NM`.
    """
    sigma550 = extinction_coefficient(visibility_m, threshold)
    if ExtinctionSpectrum(spectrum) is ExtinctionSpectrum.GREY:
        return np.full(3, sigma550)
    ratio = np.asarray(CHANNEL_WAVELENGTHS_NM) / REFERENCE_WAVELENGTH_NM
    return sigma550 * ratio ** -kim_exponent(visibility_m)


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
    """Apparent contrast of a black target at ``distance_m`` against the horizon:
    ``-exp(-sigma d)``."""
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


CLEAN_LEVEL = "clean"
"""Name of the haze-free level (its folder in a dataset), beside the hazy levels' ``v0300``..."""


_LEVEL_NAME = re.compile(r"^v(\d+)$")


MIN_LEVEL_M = 10.0
"""Thinnest visibility a level may have (m): below it a 300 m layer is more than 100 optical
depths thick and the frame is uniform fog (docs/limits.md)."""
MAX_LEVEL_M = 1.0e6
"""Clearest visibility a level may have (m)."""
MAX_LEVELS = 64
"""Most hazy levels per scene (the paper has 11); each costs a render."""


def level_name(visibility_m: float) -> str:
    """Folder name of a level: ``v`` plus the metres, zero-padded to 4 digits (``v0300``).

    Names carry whole metres, so two levels less than a metre apart could share a folder:
    :func:`level_name_clash` finds them and every entry point refuses them.
    """
    return f"v{round(visibility_m):04d}"


def level_name_clash(visibilities_m: list[float] | tuple[float, ...]) -> str | None:
    """A one-line message when two levels get the same folder name (else None)."""
    seen: dict[str, float] = {}
    for v in visibilities_m:
        name = level_name(v)
        if name in seen:
            return (
                f"levels {seen[name]:g} and {v:g} m would share the folder {name} (level names "
                "carry whole metres); give each level a different whole number of metres"
            )
        seen[name] = v
    return None


def is_level_name(name: str) -> bool:
    """Whether ``name`` is a level folder name (``clean`` or ``v`` + a positive integer)."""
    match = _LEVEL_NAME.match(name)
    return name == CLEAN_LEVEL or (match is not None and int(match[1]) > 0)


class VisSelectionError(ValueError):
    """A ``--vis`` selection that cannot be parsed; the message is one line for the user."""


_NUMBER = r"\d+(?:\.\d+)?"
_RANGE = re.compile(rf"^({_NUMBER})\.\.({_NUMBER})(?::(\d+))?$")


def _positive(text: str, spec: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise VisSelectionError(f"--vis {spec!r}: {text!r} is not a number of metres") from None
    if not math.isfinite(value) or not MIN_LEVEL_M <= value <= MAX_LEVEL_M:
        raise VisSelectionError(
            f"--vis {spec!r}: visibility must be within {MIN_LEVEL_M:g}..{MAX_LEVEL_M:g} m, "
            f"got {text}"
        )
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
            if len(match[3]) > 6 or not 1 <= int(match[3]) <= MAX_LEVELS:
                raise VisSelectionError(
                    f"--vis {spec!r}: the level count must be within 1..{MAX_LEVELS}"
                )
            count = int(match[3])
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
    levels = sorted({_positive(p, spec) for p in parts})
    if len(levels) > MAX_LEVELS:
        raise VisSelectionError(f"--vis {spec!r}: {len(levels)} levels; at most {MAX_LEVELS}")
    clash = level_name_clash(levels)
    if clash:
        raise VisSelectionError(f"--vis {spec!r}: {clash}")
    return levels
