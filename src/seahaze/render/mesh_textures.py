"""Textures that read one mesh's own values by index, with no virtual call to the shape.

Mitsuba's ``mesh_attribute`` texture asks the hit's shape for its attribute: a virtual call over
every shape of the scene, nested inside the BSDF's own virtual call. drjit traces a nested call
with its dispatch table at a place of its own in each trace, so BSDFs that differ only in their
values no longer trace alike and are compiled once per BSDF at every BSDF call of a kernel;
and every nested call adds its dispatch over all the scene's shapes (docs/benchmarks.md, "What
does a new image size or sample count compile?"). These textures hold the values of the one
mesh they are attached to and gather them at the hit's face:

* :class:`VertexValues` — a per-vertex scalar (the sea's foam, foam reflectance and near-lobe
  weight), interpolated over the hit's triangle with its barycentric coordinates as Mitsuba's
  meshes do (``(1 − b₁ − b₂)·v₀ + b₁·v₁ + b₂·v₂``, with ``(b₁, b₂)`` the interaction's ``uv`` on
  a mesh without texture coordinates); the textures of one mesh share one copy of its faces;
* :class:`FacePaint` — a colour per face (the vessels' paint, constant over each part).

An interaction with no shape (a BSDF sampled on its own, as :mod:`.photon_sources` does) reads
0, as ``mesh_attribute`` does. The classes derive from the active variant's ``Texture``:
:func:`vertex_textures` and :func:`face_paint` build them for it. Their arrays live in drjit's own
memory (:func:`seahaze.render.jit_haze.owned_floats`), so a kernel's hash does not follow
numpy's buffers from scene to scene.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .jit_haze import owned_floats, owned_indices

VERTEX_VALUES = "seahaze_vertex_values"
"""Mitsuba plugin name of :class:`VertexValues`."""
FACE_PAINT = "seahaze_face_paint"
"""Mitsuba plugin name of :class:`FacePaint`."""
PAINT_MEAN = 0.5
"""The mean colour :class:`FacePaint` reports (roughplastic weighs its sampling by it once):
a fixed value keeps the scene's paint out of the kernel; it only steers sampling."""

_CLASSES: dict[str, dict[str, type]] = {}
"""Per variant: plugin name → class."""


def vertex_textures(faces: np.ndarray, values: dict[str, np.ndarray]) -> dict[str, Any]:
    """A loaded :class:`VertexValues` per entry of ``values`` ((N,) per vertex) of a mesh with
    ``faces`` (M, 3), all reading one copy of the faces: the same gathers, which drjit's value
    numbering can merge where a BSDF reads several of them at one hit."""
    import mitsuba as mi

    shared = owned_indices(_padded(np.asarray(faces, np.uint32)))
    textures = {}
    for name, per_vertex in values.items():
        texture = mi.load_dict({"type": _registered(VERTEX_VALUES)})
        texture.set_mesh(shared, per_vertex)
        textures[name] = texture
    return textures


def face_paint() -> Any:
    """A loaded :class:`FacePaint` holding no paint yet (:meth:`FacePaint.set_faces`)."""
    import mitsuba as mi

    return mi.load_dict({"type": _registered(FACE_PAINT)})


def _registered(name: str) -> str:
    """Register this module's textures with the active variant (once); returns ``name``."""
    import mitsuba as mi

    variant = mi.variant()
    if variant not in _CLASSES:
        classes = _make_classes(mi)
        for plugin, cls in classes.items():
            mi.register_texture(plugin, lambda props, cls=cls: cls(props))
        _CLASSES[variant] = classes
    return name


def _padded(values: np.ndarray) -> np.ndarray:
    """``values`` flattened with two trailing zeros: an array a gather reads stays an array
    even for a one-face mesh (a one-element array would be a scalar, another kernel)."""
    flat = np.ascontiguousarray(np.ravel(values))
    return np.concatenate([flat, np.zeros(2, flat.dtype)])


def _make_classes(mi: Any) -> dict[str, type]:
    import drjit as dr

    def has_shape(si: Any, active: Any) -> Any:
        return active & (dr.reinterpret_array(mi.UInt32, si.shape) != 0)

    class VertexValues(mi.Texture):
        """A per-vertex scalar of one mesh at the hit, interpolated (module docstring)."""

        def set_mesh(self, faces: Any, values: np.ndarray) -> None:
            """The mesh's vertex indices ``faces`` (a drjit UInt32 array, three per face, as
            :func:`vertex_textures` uploads them) and ``values`` (N,) per vertex."""
            self.faces = faces
            self.values = owned_floats(_padded(values))
            self.mean_value = float(np.mean(values)) if len(values) else 0.0

        def eval_1(self, si: Any, active: Any = True) -> Any:
            valid = has_shape(si, active)
            first = si.prim_index * 3
            corners = [dr.gather(mi.UInt32, self.faces, first + k, valid) for k in range(3)]
            v0, v1, v2 = (dr.gather(mi.Float, self.values, i, valid) for i in corners)
            b1, b2 = si.uv.x, si.uv.y
            return dr.select(valid, (1.0 - b1 - b2) * v0 + b1 * v1 + b2 * v2, 0.0)

        def eval(self, si: Any, active: Any = True) -> Any:
            return mi.Color3f(self.eval_1(si, active))

        def mean(self) -> float:
            return self.mean_value

        def to_string(self) -> str:
            return "VertexValues[]"

    class FacePaint(mi.Texture):
        """The paint of the hit's face, linear RGB (module docstring)."""

        def __init__(self, props: Any) -> None:
            super().__init__(props)
            self.set_faces(np.zeros((1, 3), np.float32), None)

        def set_faces(self, rgb: np.ndarray, owner: int | None) -> None:
            """The colours (M, 3) of the mesh's faces, of the scene keyed ``owner``."""
            rgb = np.asarray(rgb, np.float32).reshape(-1, 3)
            self.channels = [owned_floats(_padded(rgb[:, c])) for c in range(3)]
            self.owner = owner

        def eval(self, si: Any, active: Any = True) -> Any:
            valid = has_shape(si, active)
            face = si.prim_index
            return mi.Color3f(*(dr.gather(mi.Float, c, face, valid) for c in self.channels))

        def eval_1(self, si: Any, active: Any = True) -> Any:
            rgb = self.eval(si, active)
            return (rgb.x + rgb.y + rgb.z) / 3.0

        def mean(self) -> float:
            return PAINT_MEAN

        def to_string(self) -> str:
            return "FacePaint[]"

    return {VERTEX_VALUES: VertexValues, FACE_PAINT: FacePaint}
