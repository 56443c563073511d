"""Write assets/meshes/workboat.ply, the small example vessel mesh of the docs and tests.

A 16-unit workboat (dark hull with a raked stem, white deck house, orange wheelhouse, mast)
built from a few convex pieces with trimesh and stored as binary PLY with per-face colours, in
the glTF convention **+y up, +z forward** so that the scene example exercises the axis options.
Run it again to regenerate the file; ``tests/test_vessels_yaml.py`` checks the committed file
equals this geometry.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import trimesh

OUT = Path(__file__).resolve().parents[1] / "assets" / "meshes" / "workboat.ply"

# Vessel frame (x bow, y port, z up) → file frame (+y up, +z forward, +x = up × forward = port):
# file = (y_v, z_v, x_v), a cyclic permutation, so a proper rotation (no mirror).
VESSEL_TO_FILE = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])

HULL_RGB = (45, 48, 55)
HOUSE_RGB = (235, 235, 230)
WHEELHOUSE_RGB = (235, 110, 25)


def workboat_parts() -> list[tuple[trimesh.Trimesh, tuple[int, int, int]]]:
    """The pieces of the workboat in the vessel frame (units: metres at 16 m length)."""
    hull = trimesh.convex.convex_hull(
        np.array(
            [(x, y, z) for x in (-8.0, 4.0) for y in (-2.4, 2.4) for z in (-0.9, 1.5)]
            + [(8.0, 0.0, 1.9), (7.0, 0.0, -0.6)]
        )
    )
    house = trimesh.creation.box(bounds=[[-4.0, -1.7, 1.4], [1.5, 1.7, 3.2]])
    wheelhouse = trimesh.convex.convex_hull(
        np.array(
            [(x, y, z) for x in (-2.5, 1.0) for y in (-1.5, 1.5) for z in (3.1, 4.6)]
            + [(1.8, y, 3.1) for y in (-1.5, 1.5)]
        )
    )
    mast = trimesh.creation.box(bounds=[[-1.6, -0.15, 4.5], [-1.3, 0.15, 7.0]])
    return [(hull, HULL_RGB), (house, HOUSE_RGB), (wheelhouse, WHEELHOUSE_RGB), (mast, HOUSE_RGB)]


def workboat_mesh() -> trimesh.Trimesh:
    """All pieces in the file frame, one mesh with per-face colours."""
    pieces = []
    for mesh, rgb in workboat_parts():
        moved = trimesh.Trimesh(
            np.asarray(mesh.vertices) @ VESSEL_TO_FILE.T, mesh.faces, process=False
        )
        moved.visual = trimesh.visual.ColorVisuals(
            moved, face_colors=np.tile([*rgb, 255], (len(moved.faces), 1))
        )
        pieces.append(moved)
    return trimesh.util.concatenate(pieces)


def main() -> int:
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_bytes(workboat_mesh().export(file_type="ply", encoding="binary"))
    print(f"wrote {OUT} ({OUT.stat().st_size} bytes)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
