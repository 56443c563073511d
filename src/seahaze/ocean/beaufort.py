"""Beaufort wind force presets: wind speed and probable wave height per force 0–12.

Source: the Beaufort wind force scale as published by the WMO (*Manual on Marine Meteorological
Services*, WMO-No. 558, Annex; wind-speed limits also in WMO-No. 306) and reproduced in the Met
Office table "Beaufort wind force scale" (National Meteorological Library, Fact sheet 6). The
wind speeds are 10-minute means at 10 m; the "probable" and "probable maximum" wave heights
refer to well-developed wind waves of the open sea, remote from land, and are a guide only (the
sea lags the wind). We treat the probable height as the typical significant wave height Hs.

The nominal wind speed is the middle of each class; force 12 has no upper limit and is given
32.7 m/s + half the width of force 11 (2.05 m/s) = 34.75 m/s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from scipy.optimize import brentq

from .base import OceanParams
from .spectra import SeaSpectrum


@dataclass(frozen=True)
class BeaufortForce:
    """One row of the Beaufort scale.

    Attributes:
        force: Beaufort number 0–12.
        name: WMO descriptive term.
        wind_min, wind_max: class limits (m/s at 10 m); ``wind_max`` is ``inf`` for force 12.
        probable_wave_height: probable wave height (m), used as the typical Hs.
        probable_max_wave_height: probable maximum wave height (m), ``nan`` where the table
            gives none.
    """

    force: int
    name: str
    wind_min: float
    wind_max: float
    probable_wave_height: float
    probable_max_wave_height: float

    @property
    def wind_speed(self) -> float:
        """Nominal (mid-class) wind speed at 10 m (m/s)."""
        if math.isinf(self.wind_max):
            return self.wind_min + 2.05
        return 0.5 * (self.wind_min + self.wind_max)


BEAUFORT_SCALE: tuple[BeaufortForce, ...] = (
    BeaufortForce(0, "Calm", 0.0, 0.2, 0.0, 0.0),
    BeaufortForce(1, "Light air", 0.3, 1.5, 0.1, 0.1),
    BeaufortForce(2, "Light breeze", 1.6, 3.3, 0.2, 0.3),
    BeaufortForce(3, "Gentle breeze", 3.4, 5.4, 0.6, 1.0),
    BeaufortForce(4, "Moderate breeze", 5.5, 7.9, 1.0, 1.5),
    BeaufortForce(5, "Fresh breeze", 8.0, 10.7, 2.0, 2.5),
    BeaufortForce(6, "Strong breeze", 10.8, 13.8, 3.0, 4.0),
    BeaufortForce(7, "Near gale", 13.9, 17.1, 4.0, 5.5),
    BeaufortForce(8, "Gale", 17.2, 20.7, 5.5, 7.5),
    BeaufortForce(9, "Strong gale", 20.8, 24.4, 7.0, 10.0),
    BeaufortForce(10, "Storm", 24.5, 28.4, 9.0, 12.5),
    BeaufortForce(11, "Violent storm", 28.5, 32.6, 11.5, 16.0),
    BeaufortForce(12, "Hurricane", 32.7, math.inf, 14.0, math.nan),
)
"""The Beaufort scale, forces 0–12 (WMO-No. 558 / Met Office)."""


def beaufort(force: int) -> BeaufortForce:
    """The row of :data:`BEAUFORT_SCALE` for ``force`` (0–12)."""
    if not 0 <= force <= 12:
        raise ValueError(f"Beaufort force must be 0..12, got {force}")
    return BEAUFORT_SCALE[force]


def beaufort_wind_speed(force: int) -> float:
    """Nominal wind speed (m/s at 10 m) of a Beaufort force."""
    return beaufort(force).wind_speed


def beaufort_wave_height(force: int) -> float:
    """Typical significant wave height (m) of a Beaufort force (the table's probable height)."""
    return beaufort(force).probable_wave_height


def beaufort_force_for_wind(wind_speed: float) -> int:
    """Beaufort force of a wind speed (m/s at 10 m); class limits are rounded to 0.1 m/s."""
    rounded = round(wind_speed, 1)
    for row in reversed(BEAUFORT_SCALE):
        if rounded >= row.wind_min:
            return row.force
    return 0


MAX_FETCH_KM = 2000.0
"""Upper fetch for the Beaufort preset search (well beyond full development)."""


def fetch_for_wave_height(
    wind_speed: float, target_hs: float, spectrum: SeaSpectrum | None = None
) -> float:
    """Fetch (km) at which the JONSWAP spectrum for ``wind_speed`` (m/s at 10 m) has
    ``Hs = target_hs`` (m); :data:`MAX_FETCH_KM` (a fully developed sea) if even that is lower.
    """
    base = spectrum or SeaSpectrum(name="jonswap")

    def hs_minus_target(log_fetch: float) -> float:
        s = replace(base, name="jonswap", wind_speed=wind_speed, fetch_km=math.exp(log_fetch))
        return s.significant_wave_height - target_hs

    lo, hi = math.log(0.1), math.log(MAX_FETCH_KM)
    if hs_minus_target(hi) <= 0.0:
        return MAX_FETCH_KM
    if hs_minus_target(lo) >= 0.0:
        return 0.1
    return math.exp(brentq(hs_minus_target, lo, hi, xtol=1e-4))


def ocean_params_for_beaufort(force: int, **overrides: object) -> OceanParams:
    """:class:`OceanParams` for a Beaufort force: JONSWAP with the nominal wind speed and the
    fetch that gives the table's probable wave height as Hs (capped at a fully developed sea,
    which for forces 1–3 is lower than the table, the table's heights including some swell).
    Force 0 gives a flat sea. ``overrides`` replace any field (e.g. ``seed``, ``model``)."""
    row = beaufort(force)
    if force == 0:
        params = OceanParams(model="flat", wind_speed=row.wind_speed)
    else:
        fetch = fetch_for_wave_height(row.wind_speed, row.probable_wave_height)
        params = OceanParams(spectrum="jonswap", wind_speed=row.wind_speed, fetch_km=fetch)
    return replace(params, **overrides)  # type: ignore[arg-type]
