"""The state a ``physical`` camera path carries from one segment to the next."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass
class HazePath:
    """What a camera path carries from one segment to the next (drjit values; a dataclass is
    a drjit pytree, so it can be the state of a symbolic loop)."""

    ray: Any
    active: Any
    depth: Any
    beta: Any
    clean: Any
    res: list
    """Each level's radiance so far."""
    att: list
    """Each level's transmittance from the camera to the path's current vertex."""
    prev_si: Any
    """The last surface as an ``Interaction3f`` (its position is all the sky's density needs):
    a whole ``SurfaceInteraction3f`` would carry some fifty more values through the loop."""
    prev_pdf: Any
    prev_delta: Any

    @classmethod
    def start(cls, ray: Any, active: Any, n_levels: int, grey: bool) -> HazePath:
        """A path at the camera; ``grey`` levels carry one transmittance, not an RGB one."""
        import drjit as dr
        import mitsuba as mi

        return cls(
            ray=ray,
            active=active,
            depth=mi.UInt32(0),
            beta=mi.Color3f(1.0),
            clean=mi.Color3f(0.0),
            res=[mi.Color3f(0.0) for _ in range(n_levels)],
            att=[mi.Float(1.0) if grey else mi.Color3f(1.0) for _ in range(n_levels)],
            prev_si=dr.zeros(mi.Interaction3f),
            prev_pdf=mi.Float(1.0),
            prev_delta=mi.Bool(True),
        )
