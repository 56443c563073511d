"""Loading a user-supplied vessel mesh (OBJ, PLY, GLB/glTF, STL) into the vessel frame.

Rules (metres; vessel frame x forward, y port, z up, waterline z = 0):

1. **Axes**: ``up_axis`` and ``forward_axis`` name the file's up and bow directions as
   ``"+x" | "-x" | "+y" | "-y" | "+z" | "-z"`` (must be perpendicular). The mesh is rotated
   so forward → +x and up → +z; port (+y) follows from the right-handed frame
   (port = up × forward). Most glTF/GLB exports are ``up_axis="+y"``.
2. **Scale**: ``scale_m`` is the vessel's **overall length in metres after scaling**, measured
   along the forward axis (not a factor), so the file's units do not matter.
3. **Centre**: midships (the centre of the x extent) and the centreline (centre of the y
   extent) go to x = y = 0.
4. **Draft**: the lowest point is put at ``z = -draft``, where ``draft = draft_m`` if given,
   else 10 % of the scaled height (a plausible loaded draft for a model that includes its
   superstructure; pass ``draft_m`` when you know it).
5. **Materials**: one part per material in the file (OBJ ``usemtl`` groups, glTF materials /
   meshes, PLY face colours); colours are converted from sRGB to linear albedo, glTF
   ``roughnessFactor`` is kept. Geometry without colour gets a light-grey paint. A
   ``material`` argument overrides all of them (one part).

User meshes need not be watertight; they are used as given.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import trimesh

from seahaze.vessels.library import CLASS_NAMES
from seahaze.vessels.materials import Material, material_from_srgb8
from seahaze.vessels.model import VesselModel, VesselPart

__all__ = [
    "ASSETS_DIR",
    "DEFAULT_DRAFT_FRACTION",
    "SUPPORTED_FORMATS",
    "axes_rotation",
    "load_user_mesh",
    "mesh_search_dirs",
    "resolve_mesh_path",
]

SUPPORTED_FORMATS = (".obj", ".ply", ".glb", ".gltf", ".stl")
ASSETS_DIR = Path(__file__).resolve().parents[3] / "assets"
"""The repository's ``assets/`` folder (src/seahaze/vessels → repo root), a search place for
relative mesh paths; absent in a non-editable install, where only the other places apply."""
DEFAULT_DRAFT_FRACTION = 0.10
DEFAULT_PAINT = material_from_srgb8("user_default_grey", (170, 170, 170), 0.5)
_MAX_COLOUR_GROUPS = 16

_AXES = {"x": 0, "y": 1, "z": 2}


def _axis_vector(spec: str, what: str) -> np.ndarray:
    match = re.fullmatch(r"\s*([+-]?)([xyzXYZ])\s*", spec)
    if match is None:
        raise ValueError(f"{what} must be one of +x, -x, +y, -y, +z, -z; got {spec!r}")
    vec = np.zeros(3)
    vec[_AXES[match.group(2).lower()]] = -1.0 if match.group(1) == "-" else 1.0
    return vec


def axes_rotation(up_axis: str, forward_axis: str) -> np.ndarray:
    """3×3 rotation taking the file's forward → +x, up → +z (and up × forward → +y)."""
    up = _axis_vector(up_axis, "up_axis")
    forward = _axis_vector(forward_axis, "forward_axis")
    if abs(float(up @ forward)) > 0.5:
        raise ValueError(
            f"up_axis {up_axis!r} and forward_axis {forward_axis!r} must be perpendicular"
        )
    port = np.cross(up, forward)
    return np.vstack([forward, port, up])


def _sanitise(name: str) -> str:
    cleaned = re.sub(r"[^0-9A-Za-z_]+", "_", name).strip("_")
    return cleaned or "part"


def _visual_material(mesh: trimesh.Trimesh, name: str) -> Material:
    """Average colour (and roughness if present) of one mesh's visual, as linear albedo."""
    visual = mesh.visual
    roughness = 0.5
    colour = None
    if isinstance(visual, trimesh.visual.TextureVisuals) and visual.material is not None:
        mat = visual.material
        factor = getattr(mat, "roughnessFactor", None)
        if factor is not None:
            roughness = float(np.clip(factor, 0.0, 1.0))
        colour = np.asarray(mat.main_color, dtype=np.float64)[:3]
        name = getattr(mat, "name", None) or name
    elif isinstance(visual, trimesh.visual.ColorVisuals) and visual.defined:
        colours = visual.face_colors if visual.kind == "face" else visual.vertex_colors
        colour = np.asarray(colours, dtype=np.float64)[:, :3].mean(axis=0)
    if colour is None:
        return Material(_sanitise(name), DEFAULT_PAINT.rgb, DEFAULT_PAINT.roughness)
    return material_from_srgb8(_sanitise(name), tuple(round(float(c)) for c in colour), roughness)


def _split_by_face_colour(mesh: trimesh.Trimesh, name: str) -> list[tuple[str, trimesh.Trimesh]]:
    """A PLY/OBJ with per-face colours becomes one sub-mesh per colour (few colours only)."""
    visual = mesh.visual
    if not (isinstance(visual, trimesh.visual.ColorVisuals) and visual.kind == "face"):
        return [(name, mesh)]
    colours = np.asarray(visual.face_colors)[:, :3]
    unique, inverse = np.unique(colours, axis=0, return_inverse=True)
    if len(unique) < 2 or len(unique) > _MAX_COLOUR_GROUPS:
        return [(name, mesh)]
    pieces = []
    for k in range(len(unique)):
        sub = mesh.submesh([np.flatnonzero(inverse.ravel() == k)], append=True)
        pieces.append((f"{name}_{k}", sub))
    return pieces


def _load_geometries(path: Path) -> list[tuple[str, trimesh.Trimesh]]:
    try:
        scene = trimesh.load_scene(str(path))
    except Exception as exc:  # trimesh raises many types for malformed files
        raise ValueError(f"could not read mesh file {path}: {exc}") from exc
    named: list[tuple[str, trimesh.Trimesh]] = []
    # Walk the scene graph so node transforms (glTF) are applied to each geometry.
    for node in scene.graph.nodes_geometry:
        transform, geom_name = scene.graph[node]
        geometry = scene.geometry[geom_name]
        if not isinstance(geometry, trimesh.Trimesh) or len(geometry.faces) == 0:
            continue
        mesh = geometry.copy()
        mesh.apply_transform(transform)
        named.extend(_split_by_face_colour(mesh, str(geom_name)))
    return named


def _nonfinite_vertices(path: Path) -> int:
    """Vertices of the file with a NaN or infinite coordinate, as written: trimesh's processed
    load drops such a vertex and every face that uses it, which would silently change the
    mesh (a PLY face lost) instead of saying the file is damaged."""
    try:
        raw = trimesh.load_scene(str(path), process=False)
    except Exception:  # the processed load already read it; its errors are the ones to show
        return 0
    count = 0
    for geometry in raw.geometry.values():
        vertices = np.asarray(getattr(geometry, "vertices", np.zeros((0, 3))), dtype=np.float64)
        count += int((~np.isfinite(vertices)).any(axis=-1).sum()) if vertices.size else 0
    return count


class SubmergedMeshError(ValueError):
    """A user mesh whose draft is not less than its scaled height: sunk that deep, nothing of
    it stays above the waterline, so it could be neither seen nor labelled."""

    def __init__(self, draft_m: float, height_m: float):
        self.draft_m, self.height_m = draft_m, height_m
        super().__init__(
            f"draft_m {draft_m:g} m sinks the whole mesh (its scaled height is {height_m:.3g} m): "
            f"nothing would stay above the waterline to see or label; allowed: "
            f"0 <= draft_m < {height_m:.3g}"
        )


def load_user_mesh(
    path: str | Path,
    kind: str,
    scale_m: float,
    up_axis: str = "+z",
    forward_axis: str = "+x",
    material: Material | None = None,
    *,
    draft_m: float | None = None,
) -> VesselModel:
    """Load a vessel mesh and bring it into the vessel frame (rules in the module docstring).

    ``kind`` is the class label it is annotated with (one of :data:`CLASS_NAMES`);
    ``scale_m`` the overall length (m) after scaling. Raises FileNotFoundError for a missing
    file and ValueError for an unsupported format, an unreadable or empty mesh, bad axes,
    an unknown kind or a non-positive scale/draft, and :class:`SubmergedMeshError` (a
    ValueError) for a draft that sinks the whole mesh.
    """
    path = Path(path)
    if kind not in CLASS_NAMES:
        raise ValueError(f"unknown vessel kind {kind!r}; allowed kinds: {', '.join(CLASS_NAMES)}")
    if not path.is_file():
        raise FileNotFoundError(f"user mesh not found: {path}")
    if path.suffix.lower() not in SUPPORTED_FORMATS:
        raise ValueError(
            f"unsupported mesh format {path.suffix!r} for {path}; supported: "
            f"{', '.join(SUPPORTED_FORMATS)}"
        )
    if not scale_m > 0:
        raise ValueError(f"scale_m (overall length in metres) must be > 0, got {scale_m}")
    if draft_m is not None and not draft_m >= 0:
        raise ValueError(f"draft_m must be >= 0, got {draft_m}")
    rotation = axes_rotation(up_axis, forward_axis)
    geometries = _load_geometries(path)
    if not geometries:
        raise ValueError(f"mesh file {path} contains no triangles")

    bad = _nonfinite_vertices(path)
    if bad:
        raise ValueError(
            f"mesh {path} has {bad} vertex(es) with a NaN or infinite coordinate; allowed: "
            "finite coordinates"
        )
    all_vertices = np.vstack([np.asarray(m.vertices) for _, m in geometries]) @ rotation.T
    lo, hi = all_vertices.min(axis=0), all_vertices.max(axis=0)
    extent = hi - lo
    if extent[0] <= 0:
        raise ValueError(f"mesh {path} has zero extent along forward_axis {forward_axis!r}")
    factor = scale_m / extent[0]
    height = extent[2] * factor
    draft = DEFAULT_DRAFT_FRACTION * height if draft_m is None else float(draft_m)
    if draft >= height:
        raise SubmergedMeshError(draft, height)
    shift = -np.array([0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), lo[2]]) * factor
    shift[2] -= draft

    parts: list[VesselPart] = []
    used: set[str] = set()
    for name, mesh in geometries:
        vertices = (np.asarray(mesh.vertices) @ rotation.T) * factor + shift
        part_name = _unique(_sanitise(name), used)
        mat = material or _visual_material(mesh, part_name)
        moved = trimesh.Trimesh(vertices, np.asarray(mesh.faces), process=False)
        parts.append(VesselPart(part_name, moved, mat))
    if material is not None:  # one material asked for: one part
        merged = trimesh.util.concatenate([p.mesh for p in parts])
        parts = [VesselPart("hull", merged, material)]
    return VesselModel(
        kind=kind,
        length_m=float(scale_m),
        beam_m=float(extent[1] * factor),
        draft_m=float(draft),
        air_draft_m=float(height - draft),
        parts=parts,
    )


def mesh_search_dirs(scene_dir: str | Path | None = None) -> list[Path]:
    """Where a relative mesh path is looked up, in order: the scene file's folder (or the
    working directory for a scene without a file), then the repository's ``assets/``."""
    first = Path(scene_dir) if scene_dir is not None else Path.cwd()
    return [first.resolve(), ASSETS_DIR]


def resolve_mesh_path(path: str | Path, search_dirs: list[Path]) -> Path | None:
    """The absolute file ``path`` names: itself when absolute, else the first existing
    ``dir / path`` of ``search_dirs``; None when there is no such file."""
    path = Path(path).expanduser()
    candidates = [path] if path.is_absolute() else [d / path for d in search_dirs]
    return next((c.resolve() for c in candidates if c.is_file()), None)


def _unique(name: str, used: set[str]) -> str:
    candidate, k = name, 1
    while candidate in used:
        k += 1
        candidate = f"{name}_{k}"
    used.add(candidate)
    return candidate
