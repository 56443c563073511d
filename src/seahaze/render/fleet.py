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
    goes to the nearest class). The part's paint colour becomes a colour per face, read by the
    paint texture (:class:`seahaze.render.mesh_textures.FacePaint`) from an array it holds. A
    class no vessel uses holds one small triangle far under the sea, which no ray reaches. Each
    mesh records which vessel every face belongs to (:attr:`FleetMesh.face_vessel`), so the
    geometry pass tells the vessels apart by the hit's primitive index. Translucent sheets
    (sails, :attr:`~seahaze.vessels.materials.Material.transmittance` above 0) join one more
    mesh after the roughness classes, :data:`CLOTH_CLASS`, whose BSDF passes light through.

    drjit traces a BSDF virtual call once per BSDF; identical traces are compiled once. A paint
    read from the mesh (a per-vertex attribute) was a virtual call to the shape nested inside
    each BSDF's, whose table lies at a place of its own in each trace: the eleven classes'
    roughplastic code was compiled eleven times at every BSDF call of a kernel (a third of the
    ``physical`` mode's kernels). Read from the texture's own array it is traced the same for
    every class and compiled once (docs/benchmarks.md, "What does a new image size or sample
    count compile?").

    The BSDFs and their textures are kept from scene to scene (:func:`vessel_materials`), so a
    texture holds the paint of the scene that last bound it: every render of a scene binds its
    own first (:meth:`seahaze.render.scene.LoadedScene.bind_paint`).

    roughplastic asks its diffuse texture for a mean colour once, to weigh sampling its
    specular coat against its diffuse base; the paint texture answers
    :data:`~seahaze.render.mesh_textures.PAINT_MEAN` for every scene. The weight only steers
    sampling (the estimate stays unbiased); a fixed value keeps it out of the kernel.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..vessels.materials import SAIL_CLOTH, SAILCLOTH_TRANSMITTANCE
from ..world import MeshData, VesselInstance
from .mesh_textures import face_paint

ROUGHNESS_CLASSES = (0.15, 0.3, 0.35, 0.4, 0.45, 0.5, 0.6, 0.65, 0.7, 0.8, 0.85)
"""Roughness of the vessel meshes: every roughness of the built-in vessels' materials
(:mod:`seahaze.vessels`; a test keeps the two in step)."""
CLOTH_CLASS = (SAIL_CLOTH[0].roughness, SAILCLOTH_TRANSMITTANCE)
"""Roughness and transmittance of the translucent sheets' mesh (sails), the last class: every
translucent built-in material's (a test keeps them in step)."""
MATERIAL_CLASSES = (*((r, 0.0) for r in ROUGHNESS_CLASSES), CLOTH_CLASS)
"""Roughness and transmittance of every vessel mesh, in order: the opaque roughness classes,
then the cloth."""
HIDDEN_DEPTH_M = 1000.0
"""Depth (m) under the sea of the placeholder triangle of an unused class."""
MIN_ALPHA = 0.05
"""Smallest GGX ``alpha`` of a vessel surface (a mirror-smooth coat would only add fireflies)."""


@dataclass(frozen=True)
class FleetMesh:
    """The vessel parts of one class (:data:`MATERIAL_CLASSES`), merged, in world
    coordinates."""

    name: str
    roughness: float
    transmittance: float
    """0 for painted steel; the cloth class's sheets pass this share of their light."""
    vertices: np.ndarray
    """(N, 3) float32."""
    faces: np.ndarray
    """(M, 3) uint32."""
    paint: np.ndarray
    """(M, 3) float32 linear RGB paint per face."""
    face_vessel: np.ndarray
    """(M,) int32 vessel index of every face (-1 for the placeholder)."""


def roughness_class(roughness: float) -> int:
    """Index of the class in :data:`ROUGHNESS_CLASSES` nearest to ``roughness``."""
    return int(np.argmin([abs(roughness - c) for c in ROUGHNESS_CLASSES]))


def material_class(part: MeshData) -> int:
    """Index in :data:`MATERIAL_CLASSES` of the mesh ``part`` joins: the cloth for a
    translucent sheet, else its nearest roughness class."""
    if part.transmittance > 0.0:
        return len(ROUGHNESS_CLASSES)
    return roughness_class(part.roughness)


def fleet_meshes(
    vessels: Sequence[VesselInstance], below_xy: tuple[float, float]
) -> list[FleetMesh]:
    """One :class:`FleetMesh` per class of :data:`MATERIAL_CLASSES`, in class order; an unused
    class holds a placeholder triangle :data:`HIDDEN_DEPTH_M` under ``below_xy`` (m)."""
    groups: list[list[tuple[int, MeshData]]] = [[] for _ in MATERIAL_CLASSES]
    for vessel in vessels:
        for part in vessel.parts:
            groups[material_class(part)].append((vessel.index, part))
    names = [f"vessels_r{k}" for k in range(len(ROUGHNESS_CLASSES))] + ["vessels_cloth"]
    return [
        _merge(name, MATERIAL_CLASSES[k], parts, below_xy)
        for k, (name, parts) in enumerate(zip(names, groups, strict=True))
    ]


def _merge(
    name: str,
    material: tuple[float, float],
    parts: list[tuple[int, MeshData]],
    below_xy: tuple[float, float],
) -> FleetMesh:
    roughness, transmittance = material
    if not parts:
        x, y = below_xy
        z = -HIDDEN_DEPTH_M
        vertices = np.array([[x, y, z], [x + 0.01, y, z], [x, y + 0.01, z]], np.float32)
        faces = np.array([[0, 1, 2]], np.uint32)
        paint, nobody = np.zeros((1, 3), np.float32), np.full(1, -1, np.int32)
        return FleetMesh(name, roughness, transmittance, vertices, faces, paint, nobody)
    offsets = np.cumsum([0] + [len(part.vertices) for _, part in parts])
    vertices = np.concatenate([part.vertices for _, part in parts]).astype(np.float32)
    faces = np.concatenate(
        [part.faces.astype(np.int64) + offsets[i] for i, (_, part) in enumerate(parts)]
    ).astype(np.uint32)
    paint = np.concatenate(
        [np.tile(np.asarray(part.rgb, np.float32), (len(part.faces), 1)) for _, part in parts]
    )
    face_vessel = np.concatenate(
        [np.full(len(part.faces), index, np.int32) for index, part in parts]
    )
    return FleetMesh(name, roughness, transmittance, vertices, faces, paint, face_vessel)


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


def vessel_bsdf(roughness: float, paint: Any = None, transmittance: float = 0.0) -> dict:
    """Painted steel — a dielectric varnish (GGX ``alpha`` = roughness, at least
    :data:`MIN_ALPHA`) over the paint texture ``paint`` (a
    :class:`~seahaze.render.mesh_textures.FacePaint`) — or, without
    one, a surface that reflects nothing (``seahaze verify``'s black targets: painted steel of
    zero paint still reflects the sky off its varnish).

    With ``transmittance`` above 0, cloth: Mitsuba's thin principled BSDF (Burley 2015,
    "Extending the Disney BRDF to a BSDF with integrated subsurface scattering", SIGGRAPH
    course notes), a two-sided sheet whose diffuse light, of albedo ``paint``, goes
    ``transmittance`` through to the other side and the rest back (its ``diff_trans`` is twice
    that share), with a rough dielectric reflection (GGX, of Disney roughness ``roughness``)
    on both faces."""
    if paint is None:
        return {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}}
    if transmittance > 0.0:
        return {
            "type": "principledthin",
            "base_color": paint,
            "roughness": roughness,
            "diff_trans": 2.0 * transmittance,
            "spec_trans": 0.0,
        }
    return {
        "type": "roughplastic",
        "distribution": "ggx",
        "alpha": max(MIN_ALPHA, roughness),
        "diffuse_reflectance": paint,
    }


@dataclass(frozen=True)
class VesselMaterial:
    """The loaded BSDF of one roughness class and its paint texture (None: black)."""

    bsdf: Any
    paint: Any


_LOADED: dict[tuple[str, float, float, bool], VesselMaterial] = {}
"""The vessel materials of the last scene, by (variant, roughness, transmittance, black): kept
for the next."""


def kept_bsdf_keys() -> list[tuple[str, float, float, bool]]:
    """The keys (variant, roughness, transmittance, black) of the vessel BSDFs kept loaded from
    the last scene (:func:`vessel_materials`)."""
    return list(_LOADED)


def vessel_materials(
    classes: Sequence[tuple[float, float]], black: bool = False
) -> list[VesselMaterial]:
    """The loaded materials of :func:`vessel_bsdf` for ``classes`` (roughness and
    transmittance of each, as :data:`MATERIAL_CLASSES`), the same objects as the previous
    scene's where it had them.

    Loading a roughplastic tabulates its coat's transmittance (a kernel launch), the same for
    every scene (docs/benchmarks.md, "Design measurements"). Only the
    last scene's BSDFs are kept: drjit traces a virtual call over every live BSDF, so a BSDF
    kept from an earlier, different set would join this scene's kernel (module docstring).
    """
    import mitsuba as mi

    keys = [(mi.variant(), float(r), float(t), bool(black)) for r, t in classes]
    for stale in set(_LOADED) - set(keys):
        del _LOADED[stale]
    for key in keys:
        if key not in _LOADED:
            _, roughness, transmittance, _ = key
            paint = None if black else face_paint()
            bsdf = mi.load_dict(vessel_bsdf(roughness, paint, transmittance))
            _LOADED[key] = VesselMaterial(bsdf, paint)
    return [_LOADED[key] for key in keys]


def bind_paint(
    materials: Sequence[VesselMaterial], paints: Sequence[np.ndarray], owner: int
) -> None:
    """Point each material's paint texture at the per-face colours ``paints`` (one (M, 3) array
    per material) of the scene ``owner`` (any key naming it), unless they already hold them."""
    for material, paint in zip(materials, paints, strict=True):
        if material.paint is not None and material.paint.owner != owner:
            material.paint.set_faces(paint, owner)
