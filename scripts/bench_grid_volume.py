"""How closely the ``reference`` mode's grid volume follows a fog layer's density profile.

The reference fills its haze box with a grid volume of the medium's density at
``seahaze.medium.GRID_CELLS`` heights, interpolated linearly (Mitsuba's trilinear filter; the
profile does not vary horizontally). For a few fog layers this measures, on a fine grid of
heights, the largest pointwise error of that interpolation (relative to the fog's density) and
the largest error of the optical depth of a vertical column from the sea up to any height
(relative to the whole column's): what a ray through the grid gets wrong. Writes the
"grid-volume" section of docs/benchmarks.md with ``--doc``.

Usage: python scripts/bench_grid_volume.py [--doc]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_passes import replace_section

CASES = (
    (300.0, 80.0, 1.0),
    (300.0, 80.0, 8.0),
    (300.0, 25.0, 3.0),
    (5000.0, 80.0, 1.0),
    (5000.0, 300.0, 10.0),
)
"""(haze top, fog top, edge) in metres; above_ratio 0.1, camera at 12 m."""
FINE = 2_000_001


def errors(top: float, fog_top: float, edge: float) -> tuple[float, float]:
    """(largest pointwise error / fog density, largest column optical-depth error / column's)."""
    from seahaze.fog_layer import fog_layer_medium
    from seahaze.medium import GRID_CELLS, NUMPY

    medium = fog_layer_medium(fog_top, edge, 0.1, top, 12.0)
    centres = medium.bottom + (np.arange(GRID_CELLS) + 0.5) / GRID_CELLS * (top - medium.bottom)
    z = np.linspace(medium.bottom, top, FINE)
    exact = medium.density(z, NUMPY)
    grid = np.interp(z, centres, medium.density(centres, NUMPY))  # clamped at the ends
    column = np.cumsum(exact) * (z[1] - z[0])
    gridded = np.cumsum(grid) * (z[1] - z[0])
    above_sea = z > 0.0
    point = float(np.abs(grid - exact).max() / exact.max())
    depth = float(np.abs(gridded - column)[above_sea].max() / column[-1])
    return point, depth


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--doc", action="store_true", help="write docs/benchmarks.md's section")
    args = parser.parse_args()
    from seahaze.medium import GRID_CELLS

    lines = [
        "## The reference's grid volume against a fog layer (scripts/bench_grid_volume.py)",
        "",
        f"{GRID_CELLS} cells from 60 m below the sea to the haze top, linear interpolation; "
        "fog layers with above_ratio 0.1, camera at 12 m.",
        "",
        "| haze top (m) | fog top (m) | edge (m) | cell (m) | density, largest error | "
        "column optical depth, largest error |",
        "|---|---|---|---|---|---|",
    ]
    for top, fog_top, edge in CASES:
        point, depth = errors(top, fog_top, edge)
        cell = (top + 60.0) / GRID_CELLS
        lines.append(
            f"| {top:g} | {fog_top:g} | {edge:g} | {cell:.2f} | {point:.2e} | {depth:.2e} |"
        )
    print("\n".join(lines))
    if args.doc:
        replace_section("grid-volume", "\n".join(lines), "scripts/bench_grid_volume.py")


if __name__ == "__main__":
    main()
