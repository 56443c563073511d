"""Every vessel of a scene as the same fixed set of Mitsuba meshes, so that every scene of a
batch runs the same compiled kernels.

Why
    drjit compiles a render kernel for the set of shapes and BSDFs a scene holds (their
    virtual calls are traced instance by instance). Sun, sky and sea state are kernel
    parameters, but one Mitsuba mesh and BSDF per vessel part made the kernel differ with the
    number and kinds of vessels: every scene of a varied batch compiled its own, which took far
    longer than rendering it at CI size (docs/benchmarks.md, "Kernel reuse").

How
    Every vessel part joins one mesh per roughness class (:data:`ROUGHNESS_CLASSES`: every
    built-in material's roughness, so built-in vessels are unchanged; a user mesh's roughness
    goes to the nearest class). The part's paint colour becomes a per-vertex attribute,
    :data:`PAINT_ATTRIBUTE`, read by the ``seahaze_vertex_paint`` texture. A class no vessel
    uses holds one small triangle far under the sea, which no ray reaches. Each mesh records
    which vessel every face belongs to (:attr:`FleetMesh.face_vessel`), so the geometry pass
    tells the vessels apart by the hit's primitive index.

    roughplastic asks its diffuse texture for a mean colour once, to weigh sampling its
    specular coat against its diffuse base; the paint texture answers :data:`PAINT_MEAN` for
    every scene. The weight only steers sampling (the estimate stays unbiased); a fixed value
    keeps it out of the kernel.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..world import MeshData, VesselInstance

ROUGHNESS_CLASSES = (0.15, 0.3, 0.35, 0.4, 0.45, 0.5, 0.6, 0.65, 0.7, 0.8, 0.85)
"""Roughness of the vessel meshes: every roughness of the built-in vessels' materials
(:mod:`seahaze.vessels`; a test keeps the two in step)."""
PAINT_ATTRIBUTE = "vertex_paint"
"""Per-vertex linear RGB paint colour of the vessel meshes."""
PAINT_TEXTURE = "seahaze_vertex_paint"
"""Mitsuba plugin name of the texture that reads :data:`PAINT_ATTRIBUTE`."""
PAINT_MEAN = 0.5
"""The mean colour the paint texture reports to roughplastic's sampling weight."""
HIDDEN_DEPTH_M = 1000.0
"""Depth (m) under the sea of the placeholder triangle of an unused class."""
MIN_ALPHA = 0.05
"""Smallest GGX ``alpha`` of a vessel surface (a mirror-smooth coat would only add fireflies)."""


@dataclass(frozen=True)
class FleetMesh:
    """The vessel parts of one roughness class, merged, in world coordinates."""

    name: str
    roughness: float
    vertices: np.ndarray
    """(N, 3) float32."""
    faces: np.ndarray
    """(M, 3) uint32."""
    paint: np.ndarray
    """(N, 3) float32 linear RGB per vertex."""
    face_vessel: np.ndarray
    """(M,) int32 vessel index of every face (-1 for the placeholder)."""


def roughness_class(roughness: float) -> int:
    """Index of the class in :data:`ROUGHNESS_CLASSES` nearest to ``roughness``."""
    return int(np.argmin([abs(roughness - c) for c in ROUGHNESS_CLASSES]))


def fleet_meshes(
    vessels: Sequence[VesselInstance], below_xy: tuple[float, float]
) -> list[FleetMesh]:
    """One :class:`FleetMesh` per roughness class, in class order; an unused class holds a
    placeholder triangle :data:`HIDDEN_DEPTH_M` under ``below_xy`` (m)."""
    groups: list[list[tuple[int, MeshData]]] = [[] for _ in ROUGHNESS_CLASSES]
    for vessel in vessels:
        for part in vessel.parts:
            groups[roughness_class(part.roughness)].append((vessel.index, part))
    return [
        _merge(f"vessels_r{k}", ROUGHNESS_CLASSES[k], parts, below_xy)
        for k, parts in enumerate(groups)
    ]


def _merge(
    name: str, roughness: float, parts: list[tuple[int, MeshData]], below_xy: tuple[float, float]
) -> FleetMesh:
    if not parts:
        x, y = below_xy
        z = -HIDDEN_DEPTH_M
        vertices = np.array([[x, y, z], [x + 0.01, y, z], [x, y + 0.01, z]], np.float32)
        faces = np.array([[0, 1, 2]], np.uint32)
        paint, nobody = np.zeros((3, 3), np.float32), np.full(1, -1, np.int32)
        return FleetMesh(name, roughness, vertices, faces, paint, nobody)
    offsets = np.cumsum([0] + [len(part.vertices) for _, part in parts])
    vertices = np.concatenate([part.vertices for _, part in parts]).astype(np.float32)
    faces = np.concatenate(
        [part.faces.astype(np.int64) + offsets[i] for i, (_, part) in enumerate(parts)]
    ).astype(np.uint32)
    paint = np.concatenate(
        [np.tile(np.asarray(part.rgb, np.float32), (len(part.vertices), 1)) for _, part in parts]
    )
    face_vessel = np.concatenate(
        [np.full(len(part.faces), index, np.int32) for index, part in parts]
    )
    return FleetMesh(name, roughness, vertices, faces, paint, face_vessel)


def vessel_spheres(fleet: Sequence[FleetMesh], n_vessels: int) -> np.ndarray:
    """A sphere around every vessel, (``n_vessels``, 4): centre x, y, z and radius (m).

    The centre is that of the vessel's bounding box, the radius its farthest vertex from it:
    a bound the vessel-light pass aims its probes at (:mod:`seahaze.render.vessel_light`). A
    vessel with no face (none of the built-in ones) gets radius 0."""
    spheres = np.zeros((n_vessels, 4), np.float64)
    for vessel in range(n_vessels):
        points = [part.vertices[part.faces[part.face_vessel == vessel].ravel()] for part in fleet]
        points = np.concatenate(points).astype(np.float64)
        if len(points) == 0:
            continue
        centre = 0.5 * (points.min(axis=0) + points.max(axis=0))
        spheres[vessel, :3] = centre
        spheres[vessel, 3] = np.sqrt(np.max(np.sum((points - centre) ** 2, axis=1)))
    return spheres


def vessel_bsdf(roughness: float, black: bool = False) -> dict:
    """Painted steel — a dielectric varnish (GGX ``alpha`` = roughness, at least
    :data:`MIN_ALPHA`) over the per-vertex paint — or, with ``black``, a surface that reflects
    nothing (``seahaze verify``'s black targets: painted steel of zero paint still reflects the
    sky off its varnish)."""
    if black:
        return {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}}
    register_paint_texture()
    return {
        "type": "roughplastic",
        "distribution": "ggx",
        "alpha": max(MIN_ALPHA, roughness),
        "diffuse_reflectance": {"type": PAINT_TEXTURE},
    }


_LOADED: dict[tuple[str, float, bool], Any] = {}
"""The vessel BSDFs of the last scene, by (variant, roughness, black): kept for the next."""


def kept_bsdf_keys() -> list[tuple[str, float, bool]]:
    """The keys (kind, roughness, black) of the vessel BSDFs kept loaded from the last scene
    (:func:`loaded_vessel_bsdfs`)."""
    return list(_LOADED)


def loaded_vessel_bsdfs(roughnesses: Sequence[float], black: bool = False) -> list[Any]:
    """The loaded Mitsuba BSDFs of :func:`vessel_bsdf` for ``roughnesses``, the same objects
    as the previous scene's where it had them.

    Loading a roughplastic tabulates its coat's transmittance (a kernel launch), the same for
    every scene (docs/benchmarks.md, "Design measurements"). Only the
    last scene's BSDFs are kept: drjit traces a virtual call over every live BSDF, so a BSDF
    kept from an earlier, different set would join this scene's kernel (module docstring).
    """
    import mitsuba as mi

    keys = [(mi.variant(), float(r), bool(black)) for r in roughnesses]
    for stale in set(_LOADED) - set(keys):
        del _LOADED[stale]
    for key in keys:
        if key not in _LOADED:
            _LOADED[key] = mi.load_dict(vessel_bsdf(key[1], key[2]))
    return [_LOADED[key] for key in keys]


_REGISTERED: set[str] = set()


def register_paint_texture() -> None:
    """Register the ``seahaze_vertex_paint`` texture with the current Mitsuba variant (once)."""
    import mitsuba as mi

    variant = mi.variant()
    if variant in _REGISTERED:
        return

    class VertexPaint(mi.Texture):
        """The shape's :data:`PAINT_ATTRIBUTE` at the hit, linear RGB."""

        def eval(self, si: Any, active: Any = True) -> Any:
            return si.shape.eval_attribute_3(PAINT_ATTRIBUTE, si, active)

        def eval_1(self, si: Any, active: Any = True) -> Any:
            rgb = self.eval(si, active)
            return (rgb.x + rgb.y + rgb.z) / 3.0

        def mean(self) -> float:
            return PAINT_MEAN

        def to_string(self) -> str:
            return "VertexPaint[]"

    mi.register_texture(PAINT_TEXTURE, lambda props: VertexPaint(props))
    _REGISTERED.add(variant)
