"""What a scene's metadata says about its vessels and levels, measured on the rendered images.

Apparent contrast (Koschmieder)
    ``C = (L_vessel − L_horizon) / L_horizon`` on luminance, with ``L_vessel`` the mean over the
    vessel's visible pixels and ``L_horizon`` the mean of the sky within
    :data:`HORIZON_SKY_BAND_DEG` above the horizon. Koschmieder's law predicts
    ``C(d) = C₀ exp(−σ d)``; a vessel farther than the visibility is flagged
    ``beyond_visibility`` (its contrast is below the threshold for a black object).

    One horizon luminance serves every direction, so a vessel seen against the sea, or in fog
    where the sea beside the waterline is darker than the horizon sky, reads a contrast it does
    not have against what is behind it (a tanker at 2.6 km read about −0.05 at V = 300 m,
    invisible in the image). :mod:`seahaze.visible` measures each vessel against its local
    background: ``local_contrast`` and ``discernible`` beside this value.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from . import imaging
from .labels import Box
from .visibility import Threshold
from .visible import LocalContrast
from .world import SceneGeometry

HORIZON_SKY_BAND_DEG = 2.0
"""Sky pixels this close above the horizon define the horizon luminance for contrasts."""

LevelContrasts = dict[str, tuple[float, list[float | None]]]
"""Level name → (visibility in m, ``inf`` for clean; apparent contrast per vessel or None)."""
LevelLocalContrasts = dict[str, list[LocalContrast]]
"""Level name → per vessel its contrast against its local background (:mod:`seahaze.visible`)."""


def horizon_luminance(
    radiance: np.ndarray, distance: np.ndarray, elevation: np.ndarray
) -> float | None:
    """Mean luminance of the sky just above the horizon, or None where none is in view.

    The mean, not the median: Monte Carlo noise is skewed (rare bright samples), so the median
    of a noisy band reads low and would bias every apparent contrast.
    """
    band = np.isinf(distance) & (elevation >= 0.0) & (elevation < HORIZON_SKY_BAND_DEG)
    return float(np.mean(imaging.luminance(radiance[band]))) if band.sum() >= 4 else None


def apparent_contrasts(
    radiance: np.ndarray, instance: np.ndarray, n_vessels: int, horizon: float | None
) -> list[float | None]:
    """Per vessel ``(L_vessel - L_horizon) / L_horizon`` over its visible pixels (Koschmieder C)."""
    y = imaging.luminance(radiance)
    out: list[float | None] = []
    for vessel in range(n_vessels):
        mask = instance == vessel
        ok = horizon is not None and horizon > 0 and mask.any()
        out.append(float((y[mask].mean() - horizon) / horizon) if ok else None)
    return out


def vessel_meta(
    geometry: SceneGeometry,
    boxes: list[Box],
    footprint_px: np.ndarray,
    level_contrasts: LevelContrasts,
    local: LevelLocalContrasts | None = None,
    threshold: Threshold | str = Threshold.KOSCHMIEDER,
) -> list[dict[str, Any]]:
    """The ``vessels`` list of a scene's metadata: pose, speed through the water, size, box,
    visibility, and per level the apparent contrast and whether the vessel lies beyond the
    visibility; with ``local``, also its contrast against its local background, the part of it
    that gave that (brighter or darker than its background in the clean image) and the sky's
    share in that background, and whether ``|C|`` exceeds ``threshold``'s ``eps``."""
    by_vessel = {b.vessel: b for b in boxes}
    out = []
    for v in geometry.vessels:
        p = v.placement
        box = by_vessel.get(v.index)
        # From the camera: at the origin but on a moving (ship) platform, where x - 0.0 == x.
        cx, cy = geometry.camera_xy
        distance = float(np.hypot(p.x - cx, p.y - cy))
        out.append(
            {
                "index": v.index,
                "class": v.kind,
                "class_id": v.class_id,
                "position_m": [p.x, p.y, v.waterline_z],
                "heading_deg": p.heading_deg,
                "speed_m_s": v.speed_m_s,
                "speed_kn": v.speed_kn,
                "length_m": v.length_m,
                "beam_m": v.beam_m,
                "air_draft_m": v.air_draft_m,
                "distance_m": distance,
                "bearing_deg": p.bearing_deg,
                "box_px": None if box is None else [box.x0, box.y0, box.x1, box.y1],
                "visible_pixels": 0 if box is None else box.pixels,
                "unoccluded_pixels": int(footprint_px[v.index])
                if v.index < len(footprint_px)
                else 0,
                "visible_fraction": None if box is None else box.visible_fraction,
                "levels": {
                    level: {
                        "apparent_contrast": contrasts[v.index],
                        "beyond_visibility": distance > visibility,
                        **_local_entry(local, level, v.index, threshold),
                    }
                    for level, (visibility, contrasts) in level_contrasts.items()
                },
            }
        )
    return out


def _local_entry(
    local: LevelLocalContrasts | None, level: str, vessel: int, threshold: Threshold | str
) -> dict[str, Any]:
    """A level's local-contrast fields of one vessel (none without ``local``)."""
    if local is None or level not in local:
        return {}
    measured = local[level][vessel]
    return {
        "local_contrast": measured.contrast,
        "local_part": measured.part,
        "local_sky_share": measured.sky_share,
        "discernible": measured.discernible(threshold),
    }
