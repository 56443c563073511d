"""The haze medium a scene's ``haze`` section describes: the one place that picks its kind."""

from __future__ import annotations

from typing import Any

from .fog_layer import fog_layer_medium
from .medium import HazeMedium, HomogeneousSlab


def haze_medium(haze: Any, camera_height_m: float | None = None) -> HazeMedium:
    """The medium a scene's ``haze`` section (:class:`seahaze.spec.HazeSpec`) describes: a
    homogeneous slab from :data:`seahaze.medium.HAZE_BOTTOM_M` to ``haze.top_m``, or with
    ``haze.fog_layer`` a :class:`seahaze.fog_layer.FogLayer` whose density is 1 at
    ``camera_height_m`` (m; needed then)."""
    albedo, g = float(haze.albedo), float(haze.g)
    fog = getattr(haze, "fog_layer", None)
    if fog is None:
        return HomogeneousSlab(top=float(haze.top_m), albedo=albedo, g=g)
    if camera_height_m is None:
        raise ValueError("a fog layer's density is set at the camera's height: give it")
    return fog_layer_medium(
        fog.top_m, fog.edge_m, fog.above_ratio, haze.top_m, camera_height_m, albedo, g
    )
