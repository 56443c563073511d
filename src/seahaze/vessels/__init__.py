"""Procedural vessel library, user meshes and sea layouts (trimesh + numpy, no renderer).

Vessel frame: x forward (bow toward +x), y to port, z up, waterline z = 0, origin at
midships on the waterline; metres. See :mod:`seahaze.vessels.library` for the class table
with dimension ranges and sources, :mod:`seahaze.vessels.layout` for the placement frame.
"""

from seahaze.vessels.layout import (
    DISTRIBUTIONS,
    ExplicitVessel,
    LayoutError,
    PlacedPart,
    Placement,
    footprint_corners,
    footprints_overlap,
    hull_rotation,
    place_explicit,
    place_on_sea,
    sample_layout,
    vessel_attitude,
)
from seahaze.vessels.library import (
    CLASS_NAMES,
    KNOT_M_S,
    VESSEL_CLASSES,
    VesselClass,
    build_vessel,
    build_vessel_reused,
    class_id,
    clear_model_cache,
    get_class,
    length_problem,
    min_air_draft_m,
    sample_speed_m_s,
    speed_problem,
)
from seahaze.vessels.materials import Material
from seahaze.vessels.model import VesselModel, VesselPart
from seahaze.vessels.user_mesh import (
    SUPPORTED_FORMATS,
    SubmergedMeshError,
    load_user_mesh,
    mesh_search_dirs,
    resolve_mesh_path,
)

__all__ = [
    "CLASS_NAMES",
    "DISTRIBUTIONS",
    "KNOT_M_S",
    "SUPPORTED_FORMATS",
    "VESSEL_CLASSES",
    "ExplicitVessel",
    "LayoutError",
    "Material",
    "PlacedPart",
    "Placement",
    "SubmergedMeshError",
    "VesselClass",
    "VesselModel",
    "VesselPart",
    "build_vessel",
    "build_vessel_reused",
    "class_id",
    "clear_model_cache",
    "footprint_corners",
    "footprints_overlap",
    "get_class",
    "hull_rotation",
    "length_problem",
    "load_user_mesh",
    "mesh_search_dirs",
    "min_air_draft_m",
    "place_explicit",
    "place_on_sea",
    "resolve_mesh_path",
    "sample_layout",
    "sample_speed_m_s",
    "speed_problem",
    "vessel_attitude",
]
