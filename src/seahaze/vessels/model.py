"""Vessel model containers shared by the procedural library and the user-mesh loader.

Vessel frame (all models): x forward (bow toward +x), y to port, z up, origin at midships on
the design waterline (z = 0), hull extending below to ``-draft_m``. Units: metres.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import trimesh

from seahaze.vessels.materials import Material

__all__ = ["VesselModel", "VesselPart"]


@dataclass
class VesselPart:
    """One named mesh with one material, in the vessel frame (metres)."""

    name: str
    mesh: trimesh.Trimesh
    material: Material


@dataclass
class VesselModel:
    """A vessel made of parts, with its principal dimensions.

    ``length_m``/``beam_m`` are overall length and breadth, ``draft_m`` the depth of the lowest
    point below the waterline and ``air_draft_m`` the height of the highest point above it.
    ``hull_draft_m`` is the draft of the hull body that displaces water (without a sailboat's
    fin keel); None means ``draft_m``. It sets the vessel's wave making.
    """

    kind: str
    length_m: float
    beam_m: float
    draft_m: float
    air_draft_m: float
    parts: list[VesselPart] = field(default_factory=list)
    hull_draft_m: float | None = None

    @property
    def displacing_draft_m(self) -> float:
        """Draft of the hull body (m): :attr:`hull_draft_m`, else :attr:`draft_m`."""
        return self.draft_m if self.hull_draft_m is None else self.hull_draft_m

    def bounds(self) -> np.ndarray:
        """Axis-aligned bounds of all parts as ``[[xmin, ymin, zmin], [xmax, ymax, zmax]]``."""
        if not self.parts:
            raise ValueError(f"vessel {self.kind!r} has no parts")
        corners = np.vstack([part.mesh.bounds for part in self.parts])
        return np.array([corners.min(axis=0), corners.max(axis=0)])

    def part(self, name: str) -> VesselPart:
        """Return the part called ``name`` (KeyError listing the names if absent)."""
        for part in self.parts:
            if part.name == name:
                return part
        raise KeyError(f"no part {name!r}; parts: {[p.name for p in self.parts]}")

    @property
    def part_names(self) -> list[str]:
        """Part names in order (the order :func:`place_on_sea` returns them in)."""
        return [part.name for part in self.parts]
