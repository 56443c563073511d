"""Watertight mesh building blocks for procedural vessels (trimesh + numpy only).

The hull is a *lofted* closed surface: a family of transverse sections (stations) along x,
each a closed loop port-side-down / starboard-side-up, joined by quads and closed by a
transom cap at the stern and a small stem cap at the bow. Every other part is either a
trimesh primitive (box, cylinder, icosphere) or the convex hull of a handful of points, which
is watertight by construction; a sail (:func:`cambered_sail`), a translucent sheet, is the
one open body. Parts made of several bodies are concatenations of disjoint bodies (no vertex
is shared, so each watertight body keeps its own closed edge set).

Frame: x forward (bow at +L/2), y to port, z up, waterline z = 0. Units: metres.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import trimesh

__all__ = [
    "HullForm",
    "box",
    "cambered_sail",
    "concatenate",
    "cone",
    "convex_body",
    "cylinder_between",
    "frustum",
    "loft_hull",
    "prism_from_outline",
    "sphere",
    "tapered_block",
    "vertical_cylinder",
]

FloatArray = np.ndarray
ZFunction = Callable[[FloatArray], FloatArray]


def _smoothstep(t: FloatArray) -> FloatArray:
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


@dataclass(frozen=True)
class HullForm:
    """Parametric monohull: planform, sheer, stem/stern profile and section shape.

    Lengths in metres; ``*_frac`` values are fractions of the stated reference.

    - ``freeboard``: main-deck height above the waterline at midships.
    - ``sheer_fwd`` / ``sheer_aft``: extra deck height (m) at the stem / transom, rising
      quadratically from midships (the classic sheer line).
    - ``forecastle_height`` / ``forecastle_length``: raised deck step at the bow (m).
    - ``parallel_fwd`` / ``parallel_aft``: where the parallel middle body ends, as a fraction of
      the half length forward / aft of midships (0 = no parallel body, as on small craft).
    - ``entrance_exponent`` p, ``bow_roundness`` q: forward half-breadth
      ``b = (1 - u**p) ** (1/q)``; q = 1 gives a pointed stem, q ≈ 2 a rounded tug bow.
    - ``transom_width``: transom breadth as a fraction of the beam.
    - ``stem_rake``: horizontal distance forefoot→stem head as a fraction of L;
      ``stem_exponent`` < 1 gives a near-vertical lower stem and raked upper stem (cargo ships),
      > 1 a long rounded forefoot (planing boats).
    - ``stern_cutup``: fraction of L over which the keel rises toward the transom;
      ``transom_immersion``: transom bottom depth as a fraction of the draft (negative = the
      transom bottom is above the waterline, i.e. a counter stern).
    - ``section_exponent`` n: below-waterline section is a superellipse quarter
      ``(1 - (1-t)**n) ** (1/n)``: n = 1 is a V hull, 2 a round bilge, ≥ 6 a box-like hull.
    - ``bow_flare`` / ``topside_flare``: how much narrower the waterline is than the deck edge
      at the stem / everywhere (fraction of the deck half-breadth).
    """

    length: float
    beam: float
    draft: float
    freeboard: float
    sheer_fwd: float = 0.0
    sheer_aft: float = 0.0
    forecastle_height: float = 0.0
    forecastle_length: float = 0.0
    parallel_fwd: float = 0.0
    parallel_aft: float = 0.0
    entrance_exponent: float = 2.0
    bow_roundness: float = 1.0
    transom_width: float = 0.8
    stern_taper_exponent: float = 2.0
    stem_rake: float = 0.03
    stem_exponent: float = 0.5
    stern_cutup: float = 0.1
    transom_immersion: float = 0.0
    section_exponent: float = 6.0
    bow_flare: float = 0.0
    topside_flare: float = 0.0

    @property
    def half_length(self) -> float:
        """Half the overall length (m): the bow is at +half_length, the transom at -."""
        return 0.5 * self.length

    @property
    def min_half_width(self) -> float:
        """Half-breadth floor at the keel line and stem so no section collapses to a line."""
        return max(0.003 * self.beam, 0.005)

    @property
    def min_section_height(self) -> float:
        """Height of the small stem cap; keeps the bow tip a proper (tiny) face."""
        return 0.04 * (self.freeboard + self.draft)

    def _forward_taper(self, x: FloatArray) -> FloatArray:
        xi = np.asarray(x, dtype=np.float64) / self.half_length
        start = self.parallel_fwd
        return np.clip((xi - start) / max(1.0 - start, 1e-9), 0.0, 1.0)

    def _aft_taper(self, x: FloatArray) -> FloatArray:
        xi = np.asarray(x, dtype=np.float64) / self.half_length
        start = self.parallel_aft
        return np.clip((-xi - start) / max(1.0 - start, 1e-9), 0.0, 1.0)

    def deck_half_beam(self, x: FloatArray) -> FloatArray:
        """Half-breadth of the deck edge at ``x`` (m)."""
        u_f = self._forward_taper(x)
        u_a = self._aft_taper(x)
        fwd = np.clip(1.0 - u_f**self.entrance_exponent, 0.0, 1.0) ** (1.0 / self.bow_roundness)
        aft = 1.0 - (1.0 - self.transom_width) * u_a**self.stern_taper_exponent
        return np.maximum(0.5 * self.beam * fwd * aft, self.min_half_width)

    def deck_z(self, x: FloatArray) -> FloatArray:
        """Deck-edge height above the waterline at ``x`` (m): freeboard + sheer + forecastle."""
        x = np.asarray(x, dtype=np.float64)
        xi = x / self.half_length
        z = (
            self.freeboard
            + self.sheer_fwd * np.clip(xi, 0.0, 1.0) ** 2
            + self.sheer_aft * np.clip(-xi, 0.0, 1.0) ** 2
        )
        if self.forecastle_height > 0.0 and self.forecastle_length > 0.0:
            # A short smooth ramp instead of a vertical step keeps every station a simple loop.
            ramp = min(0.015 * self.length, 0.3 * self.forecastle_length)
            start = self.half_length - self.forecastle_length - ramp
            z = z + self.forecastle_height * _smoothstep((x - start) / ramp)
        return z

    def keel_z(self, x: FloatArray) -> FloatArray:
        """Height of the keel / stem / stern profile at ``x`` (m, negative below water)."""
        x = np.asarray(x, dtype=np.float64)
        z = np.full_like(x, -self.draft)
        rake = max(self.stem_rake * self.length, 1e-6)
        forefoot = self.half_length - rake
        stem_top = float(self.deck_z(np.array([self.half_length]))[0]) - self.min_section_height
        u = np.clip((x - forefoot) / rake, 0.0, 1.0)
        z = z + (stem_top + self.draft) * u**self.stem_exponent
        cutup = max(self.stern_cutup * self.length, 1e-6)
        start = -self.half_length + cutup
        v = np.clip((start - x) / cutup, 0.0, 1.0)
        z = z + (1.0 - self.transom_immersion) * self.draft * v**2
        return np.minimum(z, self.deck_z(x) - self.min_section_height)

    def half_width(self, x: FloatArray, z: FloatArray) -> FloatArray:
        """Half-breadth of the hull surface at station ``x`` and height ``z`` (broadcasting)."""
        x, z = np.broadcast_arrays(np.asarray(x, dtype=np.float64), np.asarray(z, float))
        b_deck = self.deck_half_beam(x)
        flare = self.topside_flare + self.bow_flare * self._forward_taper(x) ** 2
        b_wl = b_deck * (1.0 - np.clip(flare, 0.0, 0.9))
        deck = self.deck_z(x)
        keel = self.keel_z(x)
        above = b_wl + (b_deck - b_wl) * np.clip(z / np.maximum(deck, 1e-9), 0.0, 1.0)
        depth = np.maximum(-keel, 1e-9)
        t = np.clip((z - keel) / depth, 0.0, 1.0)
        n = self.section_exponent
        below = b_wl * (1.0 - (1.0 - t) ** n) ** (1.0 / n)
        hw = np.where(z >= 0.0, above, below)
        return np.maximum(hw, self.min_half_width)

    def x_interval_below(self, z_level: float, margin: float) -> tuple[float, float] | None:
        """Longest x interval where the keel is at least ``margin`` below ``z_level``."""
        xs = np.linspace(-self.half_length, self.half_length, 2001)
        inside = self.keel_z(xs) < z_level - margin
        if not inside.any():
            return None
        idx = np.flatnonzero(inside)
        return float(xs[idx[0]]), float(xs[idx[-1]])


def _station_positions(x0: float, x1: float, count: int) -> FloatArray:
    """Stations clustered toward both ends, where the planform changes fastest."""
    s = np.linspace(0.0, 1.0, count)
    return x0 + (x1 - x0) * (0.5 * s + 0.25 * (1.0 - np.cos(np.pi * s)))


def loft_hull(
    form: HullForm,
    z_low: ZFunction | None = None,
    z_high: ZFunction | None = None,
    *,
    inflate: float = 0.0,
    x_range: tuple[float, float] | None = None,
    n_stations: int = 56,
    n_vertical: int = 10,
) -> trimesh.Trimesh:
    """Loft the hull (or a horizontal band of it) into a closed, consistently wound mesh.

    ``z_low``/``z_high`` bound the band per station (default: keel to deck); ``inflate``
    pushes the surface outward (m) so a paint band can sit just proud of the hull.
    """
    z_low = z_low or form.keel_z
    z_high = z_high or form.deck_z
    x0, x1 = x_range or (-form.half_length, form.half_length)
    xs = _station_positions(x0, x1, n_stations)
    lo = np.asarray(z_low(xs), dtype=np.float64)
    hi = np.maximum(np.asarray(z_high(xs), dtype=np.float64), lo + 1e-3)
    # Denser sampling near the bottom, where the bilge curvature is.
    v = np.linspace(0.0, 1.0, n_vertical) ** 1.5
    z = lo[:, None] + v[None, :] * (hi - lo)[:, None]  # (N, K), bottom → top
    # Clamp after inflating so a negative inflate (an inset deck plate) never crosses y = 0.
    hw = np.maximum(form.half_width(xs[:, None], z) + inflate, 0.5 * form.min_half_width)
    k = n_vertical
    # Loop per station: port side top→bottom, then starboard side bottom→top.
    loop_y = np.concatenate([hw[:, ::-1], -hw], axis=1)
    loop_z = np.concatenate([z[:, ::-1], z], axis=1)
    loop_x = np.repeat(xs[:, None], 2 * k, axis=1)
    ring = np.stack([loop_x, loop_y, loop_z], axis=-1).reshape(-1, 3)
    return _close_loft(ring, n_stations, 2 * k)


def _close_loft(ring: FloatArray, n_stations: int, loop: int) -> trimesh.Trimesh:
    """Join station loops with quads and cap both ends with centroid fans."""
    i = np.arange(n_stations - 1)[:, None]
    j = np.arange(loop)[None, :]
    a = i * loop + j
    b = i * loop + (j + 1) % loop
    c = (i + 1) * loop + (j + 1) % loop
    d = (i + 1) * loop + j
    sides = np.concatenate(
        [np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)]
    )
    first = np.arange(loop)
    last = (n_stations - 1) * loop + np.arange(loop)
    c_first = len(ring)
    c_last = len(ring) + 1
    centres = np.array([ring[first].mean(axis=0), ring[last].mean(axis=0)])
    # Cap windings mirror the side edges so every edge is used once in each direction.
    cap_first = np.stack([np.full(loop, c_first), np.roll(first, -1), first], -1)
    cap_last = np.stack([np.full(loop, c_last), last, np.roll(last, -1)], -1)
    faces = np.concatenate([sides, cap_first, cap_last])
    mesh = trimesh.Trimesh(np.vstack([ring, centres]), faces, process=False)
    if mesh.volume < 0.0:
        mesh.invert()
    return mesh


def box(x0: float, x1: float, y0: float, y1: float, z0: float, z1: float) -> trimesh.Trimesh:
    """Axis-aligned box from its bounds (m)."""
    lo = np.minimum([x0, y0, z0], [x1, y1, z1])
    hi = np.maximum([x0, y0, z0], [x1, y1, z1])
    return trimesh.creation.box(bounds=np.array([lo, hi]))


def boxes(lower: FloatArray, upper: FloatArray) -> trimesh.Trimesh:
    """Many axis-aligned boxes as one mesh: box ``i`` spans ``lower[i]`` to ``upper[i]`` ((n, 3)
    corners, m). Each is :func:`box`'s closed, outward-wound box; they share no vertex, so the
    mesh is watertight however the boxes touch. Built in numpy (a ship's deck carries
    thousands of containers)."""
    lower, upper = np.asarray(lower, np.float64), np.asarray(upper, np.float64)
    unit = trimesh.creation.box(bounds=np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]]))
    corners = np.asarray(unit.vertices)  # in [0, 1]^3
    vertices = lower[:, None, :] + corners[None, :, :] * (upper - lower)[:, None, :]
    offsets = np.arange(len(lower))[:, None, None] * len(corners)
    faces = np.asarray(unit.faces)[None, :, :] + offsets
    return trimesh.Trimesh(vertices.reshape(-1, 3), faces.reshape(-1, 3), process=False)


def convex_body(points: FloatArray | Sequence[Sequence[float]]) -> trimesh.Trimesh:
    """Convex hull of a few points: a watertight, outward-wound body (keels, wedges)."""
    mesh = trimesh.convex.convex_hull(np.asarray(points, dtype=np.float64))
    if mesh.volume < 0.0:
        mesh.invert()
    return mesh


def tapered_block(
    x0: float,
    x1: float,
    half_width: float,
    z0: float,
    z1: float,
    *,
    front_rake: float = 0.0,
    aft_rake: float = 0.0,
    top_inset: float = 0.0,
) -> trimesh.Trimesh:
    """Deckhouse-like block: bottom x∈[x0, x1], top shortened by the rakes and narrowed.

    A raked front (``front_rake`` m set back at the top) is what makes a bridge front or a
    ferry's superstructure read as such from afar.
    """
    top_x0 = min(x0 + aft_rake, x1 - 1e-3)
    top_x1 = max(x1 - front_rake, top_x0 + 1e-3)
    top_w = max(half_width - top_inset, 1e-3)
    pts = [
        (x0, -half_width, z0),
        (x0, half_width, z0),
        (x1, -half_width, z0),
        (x1, half_width, z0),
        (top_x0, -top_w, z1),
        (top_x0, top_w, z1),
        (top_x1, -top_w, z1),
        (top_x1, top_w, z1),
    ]
    return convex_body(np.array(pts))


def _ellipse_ring(cx: float, cy: float, rx: float, ry: float, z: float, n: int) -> FloatArray:
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return np.stack([cx + rx * np.cos(t), cy + ry * np.sin(t), np.full(n, z)], -1)


def prism_from_outline(
    centre_x: float,
    centre_y: float,
    half_length: float,
    half_width: float,
    z0: float,
    z1: float,
    *,
    rake: float = 0.0,
    top_scale: float = 1.0,
    sections: int = 16,
) -> trimesh.Trimesh:
    """Elliptic prism, top shifted aft by ``rake`` (m) and scaled: a funnel casing."""
    bottom = _ellipse_ring(centre_x, centre_y, half_length, half_width, z0, sections)
    top = _ellipse_ring(
        centre_x - rake, centre_y, half_length * top_scale, half_width * top_scale, z1, sections
    )
    return convex_body(np.vstack([bottom, top]))


def frustum(
    centre_x: float,
    centre_y: float,
    r0: float,
    r1: float,
    z0: float,
    z1: float,
    sections: int = 16,
) -> trimesh.Trimesh:
    """Truncated cone (radii r0 at z0, r1 at z1)."""
    return prism_from_outline(
        centre_x, centre_y, r0, r0, z0, z1, top_scale=max(r1, 1e-4) / r0, sections=sections
    )


def vertical_cylinder(
    x: float, y: float, radius: float, z0: float, z1: float, sections: int = 12
) -> trimesh.Trimesh:
    """Upright cylinder at (x, y) from z0 to z1 (masts, stacks, pedestals)."""
    return cylinder_between((x, y, z0), (x, y, z1), radius, sections)


def cylinder_between(
    p0: Sequence[float], p1: Sequence[float], radius: float, sections: int = 10
) -> trimesh.Trimesh:
    """Cylinder along the segment p0→p1 (masts, booms, crane jibs)."""
    return trimesh.creation.cylinder(
        radius=radius, segment=np.array([p0, p1], dtype=np.float64), sections=sections
    )


def cone(
    x: float, y: float, radius: float, z_base: float, height: float, sections: int = 16
) -> trimesh.Trimesh:
    """Cone with its base at ``z_base``; a negative ``height`` points it downward."""
    base = _ellipse_ring(x, y, radius, radius, z_base, sections)
    return convex_body(np.vstack([base, [[x, y, z_base + height]]]))


def sphere(x: float, y: float, z: float, radius: float) -> trimesh.Trimesh:
    """Coarse icosphere (80 faces): plenty for a topmark a few pixels wide."""
    mesh = trimesh.creation.icosphere(subdivisions=1, radius=radius)
    mesh.apply_translation([x, y, z])
    return mesh


SAIL_DIVISIONS = 8
"""Rows of triangles from a sail's foot to its head (and across its foot) in
:func:`cambered_sail`: ``SAIL_DIVISIONS²`` faces."""


def cambered_sail(
    tack: Sequence[float],
    head: Sequence[float],
    clew: Sequence[float],
    depth: float,
    leeward: Sequence[float],
) -> trimesh.Trimesh:
    """A triangular sail as a single sheet with camber: its luff (tack to head) and leech (clew
    to head) lie on the flat triangle, and between them every horizontal chord bows to the
    ``leeward`` side (a direction) by ``depth`` (a share of the chord's length, 0.08-0.15 for
    a trimmed sail) at mid-chord, as a parabola, ``4·depth·c·u(1 - u)`` at the share ``u`` of
    the chord ``c`` from the luff. The belly is what makes a set sail shade from luff to leech
    in a photograph; a flat triangle is one tone. One sheet, seen and lit from both sides: a
    translucent material (:attr:`~seahaze.vessels.materials.Material.transmittance`) lets
    light through it in one crossing, where a closed plate would need two, which the
    renderer's light sampling cannot connect to the sun."""
    tack, head, clew = (np.asarray(p, np.float64) for p in (tack, head, clew))
    normal = np.cross(clew - tack, head - tack)
    normal /= np.linalg.norm(normal)
    if np.dot(normal, np.asarray(leeward, np.float64)) < 0.0:
        normal = -normal
    foot = float(np.linalg.norm(clew - tack))
    n = SAIL_DIVISIONS
    index: dict[tuple[int, int], int] = {}
    vertices = []
    for j in range(n + 1):  # rows up the sail: the share v = j/n of the way to the head
        for i in range(n + 1 - j):  # along the chord: a = i/n of the foot
            a, v = i / n, j / n
            u = a / (1.0 - v) if v < 1.0 else 0.0
            flat = tack + a * (clew - tack) + v * (head - tack)
            belly = 4.0 * depth * foot * (1.0 - v) * u * (1.0 - u)
            index[i, j] = len(vertices)
            vertices.append(flat + belly * normal)
    faces = []
    for j in range(n):
        for i in range(n - j):
            faces.append((index[i, j], index[i + 1, j], index[i, j + 1]))
            if i + 1 <= n - j - 1:
                faces.append((index[i + 1, j], index[i + 1, j + 1], index[i, j + 1]))
    return trimesh.Trimesh(np.asarray(vertices), np.asarray(faces), process=False)


def concatenate(meshes: Sequence[trimesh.Trimesh]) -> trimesh.Trimesh:
    """Join disjoint watertight bodies into one mesh without merging any vertices."""
    if len(meshes) == 1:
        return meshes[0]
    vertices = []
    faces = []
    offset = 0
    for mesh in meshes:
        vertices.append(np.asarray(mesh.vertices))
        faces.append(np.asarray(mesh.faces) + offset)
        offset += len(mesh.vertices)
    return trimesh.Trimesh(np.vstack(vertices), np.vstack(faces), process=False)
