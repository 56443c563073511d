"""Floating aids to navigation following the IALA Maritime Buoyage System.

Marks (IALA Recommendation R1001 "The IALA Maritime Buoyage System"): port and starboard
lateral (Region A red can / green cone, Region B swapped colours), cardinal (yellow/black
bands, two black cone topmarks), isolated danger (black with red band, two black spheres),
safe water (red and white vertical stripes, red sphere) and special (yellow, yellow X).

Shape: a cylindrical float of diameter ``length`` (1.0-3.0 m, the usual steel/plastic float
sizes, e.g. the Chinese buoy standard series Φ1.2/1.5/1.8/2.4/3.0 m and Trinity House's
~3 m "Type 2" buoys) carrying either a pillar tower with lantern and topmark (focal height
about 1.2-2.0 × diameter above the float) or a plain can / cone superstructure.
Frame: symmetric about z; x and y are arbitrary. Metres.
"""

from __future__ import annotations

import numpy as np
import trimesh

from seahaze.vessels.geometry import (
    concatenate,
    cone,
    convex_body,
    frustum,
    sphere,
    vertical_cylinder,
)
from seahaze.vessels.materials import BUOY_COLOURS, material_from_srgb8
from seahaze.vessels.model import VesselPart
from seahaze.vessels.parts import PartSet, PrincipalDims, u

__all__ = ["BUOY_MARKS", "build_buoy"]

BUOY_MARKS = (
    "port_lateral",
    "starboard_lateral",
    "cardinal",
    "isolated_danger",
    "safe_water",
    "special",
)
LANTERN = material_from_srgb8("buoy_lantern", (200, 200, 195), 0.3)

# Cardinal colour bands bottom→top and topmark cone directions (+1 point up, -1 down),
# lower cone first: N ▲▲, S ▼▼, E ▲ over ▼ (base to base), W ▼ over ▲ (point to point).
_CARDINALS = {
    "north": (("yellow", "black"), (1, 1)),
    "south": (("black", "yellow"), (-1, -1)),
    "east": (("black", "yellow", "black"), (-1, 1)),
    "west": (("yellow", "black", "yellow"), (1, -1)),
}


def _band_colours(
    mark: str, region_a: bool, rng: np.random.Generator
) -> tuple[tuple[str, ...], str]:
    """Horizontal colour bands (bottom→top) and topmark kind for a mark."""
    port, stbd = ("red", "green") if region_a else ("green", "red")
    if mark == "port_lateral":
        return (port,), f"can:{port}"
    if mark == "starboard_lateral":
        return (stbd,), f"cone:{stbd}"
    if mark == "cardinal":
        name = tuple(_CARDINALS)[int(rng.integers(4))]
        bands, dirs = _CARDINALS[name]
        return bands, f"cardinal:{dirs[0]}:{dirs[1]}"
    if mark == "isolated_danger":
        return ("black", "red", "black"), "spheres:black"
    if mark == "safe_water":
        return ("stripes",), "sphere:red"
    return ("yellow",), "x:yellow"


def _add_topmark(parts: PartSet, kind: str, z: float, size: float) -> float:
    """Add the topmark above ``z``; return its top height (m)."""
    shape, *args = kind.split(":")
    r = 0.5 * size
    if shape == "can":
        parts.add(
            "topmark", vertical_cylinder(0.0, 0.0, 0.8 * r, z, z + size), BUOY_COLOURS[args[0]]
        )
        return z + size
    if shape == "cone":
        parts.add("topmark", cone(0.0, 0.0, r, z, size), BUOY_COLOURS[args[0]])
        return z + size
    if shape == "sphere":
        parts.add("topmark", sphere(0.0, 0.0, z + r, r), BUOY_COLOURS[args[0]])
        return z + size
    if shape == "spheres":
        for k in range(2):
            parts.add("topmark", sphere(0.0, 0.0, z + r + k * 1.3 * size, r), BUOY_COLOURS["black"])
        return z + 2.3 * size
    if shape == "cardinal":
        top = z
        for k, direction in enumerate(int(a) for a in args):
            base = z + k * 1.3 * size + (0.0 if direction > 0 else size)
            parts.add("topmark", cone(0.0, 0.0, r, base, direction * size), BUOY_COLOURS["black"])
            top = max(top, base, base + direction * size)
        return top
    # St Andrew's cross: two thin slabs at ±45° in the x-z plane.
    t = 0.06 * size
    for sign in (-1.0, 1.0):
        c, s = np.cos(np.pi / 4), sign * np.sin(np.pi / 4)
        corners = []
        for a in (-r * 1.2, r * 1.2):
            for b in (-t, t):
                for yy in (-t, t):
                    corners.append((a * c - b * s, yy, z + r * 1.2 + a * s + b * c))
        parts.add("topmark", convex_body(corners), BUOY_COLOURS["yellow"])
    return z + 2.4 * r


def _striped_frustum(
    r0: float, r1: float, z0: float, z1: float, sectors: int = 8
) -> tuple[trimesh.Trimesh, trimesh.Trimesh]:
    """Frustum split into alternating vertical sectors (safe-water red/white stripes)."""
    bodies: list[list[trimesh.Trimesh]] = [[], []]
    for k in range(sectors):
        t = np.linspace(2 * np.pi * k / sectors, 2 * np.pi * (k + 1) / sectors, 4)
        pts = [(0.0, 0.0, z0), (0.0, 0.0, z1)]
        pts += [(r0 * np.cos(a), r0 * np.sin(a), z0) for a in t]
        pts += [(r1 * np.cos(a), r1 * np.sin(a), z1) for a in t]
        bodies[k % 2].append(convex_body(pts))
    return concatenate(bodies[0]), concatenate(bodies[1])


def _add_banded(
    parts: PartSet, name: str, bands: tuple[str, ...], r0: float, r1: float, z0: float, z1: float
) -> None:
    """A frustum painted in horizontal bands (bottom→top), one part per colour."""
    if bands == ("stripes",):
        red, white = _striped_frustum(r0, r1, z0, z1)
        parts.add(f"{name}_red", red, BUOY_COLOURS["red"])
        parts.add(f"{name}_white", white, BUOY_COLOURS["white"])
        return
    n = len(bands)
    for k, colour in enumerate(bands):
        za = z0 + (z1 - z0) * k / n
        zb = z0 + (z1 - z0) * (k + 1) / n
        ra = r0 + (r1 - r0) * k / n
        rb = r0 + (r1 - r0) * (k + 1) / n
        # Bands overlap by 1 cm so no sky shows through the seam; separate bodies anyway.
        parts.add(
            f"{name}_{colour}",
            frustum(0.0, 0.0, ra, rb, za - (0.01 if k else 0.0), zb),
            BUOY_COLOURS[colour],
        )


def build_buoy(d: PrincipalDims, rng: np.random.Generator) -> list[VesselPart]:
    """IALA buoy of float diameter ``d.length``; float height ``d.depth``, immersion
    ``d.draft``."""
    diameter = d.length
    mark = BUOY_MARKS[int(rng.integers(len(BUOY_MARKS)))]
    region_a = rng.random() < 0.5
    bands, topmark = _band_colours(mark, region_a, rng)
    float_colour = "red" if bands == ("stripes",) else bands[0]
    parts = PartSet()
    z_float_top = d.depth - d.draft
    parts.add(
        "float",
        frustum(0.0, 0.0, 0.5 * diameter, 0.47 * diameter, -d.draft, z_float_top, sections=20),
        BUOY_COLOURS[float_colour],
    )
    pillar = mark not in ("port_lateral", "starboard_lateral") or rng.random() < 0.6
    size = max(0.3, u(rng, 0.22, 0.3) * diameter)
    if pillar:
        tower_h = u(rng, 1.2, 2.0) * diameter
        r1 = u(rng, 0.12, 0.16) * diameter
        _add_banded(
            parts,
            "tower",
            bands,
            u(rng, 0.3, 0.36) * diameter,
            r1,
            z_float_top - 0.05,
            z_float_top + tower_h,
        )
        z = z_float_top + tower_h
        lantern_h = 0.25 * diameter
        parts.add(
            "lantern",
            vertical_cylinder(0.0, 0.0, max(0.08, 0.07 * diameter), z - 0.02, z + lantern_h),
            LANTERN,
        )
        z += lantern_h
        parts.add(
            "topmark_pole",
            vertical_cylinder(0.0, 0.0, 0.03, z - 0.02, z + 0.3 * size),
            BUOY_COLOURS["black"],
        )
        _add_topmark(parts, topmark, z + 0.3 * size, size)
    else:
        colour = BUOY_COLOURS[float_colour]
        if mark == "port_lateral":
            parts.add(
                "body",
                vertical_cylinder(
                    0.0,
                    0.0,
                    0.4 * diameter,
                    z_float_top - 0.05,
                    z_float_top + u(rng, 0.8, 1.0) * diameter,
                    sections=20,
                ),
                colour,
            )
        else:
            parts.add(
                "body",
                cone(
                    0.0,
                    0.0,
                    0.45 * diameter,
                    z_float_top - 0.05,
                    u(rng, 0.9, 1.1) * diameter,
                    sections=20,
                ),
                colour,
            )
    return parts.to_parts()
