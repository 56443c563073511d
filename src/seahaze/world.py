"""The world a scene spec describes: the sun's direction, the sea mesh and the placed vessels.

This is the step between the spec and the renderer: plain numpy meshes and materials, no
Mitsuba. World frame: Z up, metres, mean sea level at z = 0, the camera above the origin;
azimuths and headings counter-clockwise from +x seen from above. Seeds for the sea and the layout
derive from ``render.seed`` (:mod:`seahaze.seeds`) unless the spec gives its own, so one master
seed reproduces a whole scene. Explicit vessels with a ``mesh`` are loaded from the user's file
(``sceneio`` has already resolved and checked the path of a scene file).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from . import ocean, vessels
from .camera import Camera
from .seeds import Stream, stream_rng, stream_seed
from .spec import SceneSpec


def sun_direction(elevation_deg: float, azimuth_deg: float) -> np.ndarray:
    """Unit vector toward the sun (world frame, Z up, azimuth counter-clockwise from +x)."""
    e, a = math.radians(elevation_deg), math.radians(azimuth_deg)
    return np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])


@dataclass
class MeshData:
    """A triangle mesh in world coordinates with a simple painted material."""

    name: str
    vertices: np.ndarray
    faces: np.ndarray
    rgb: tuple[float, float, float] = (0.5, 0.5, 0.5)
    roughness: float = 0.5


@dataclass
class VesselInstance:
    """One vessel placed in the world."""

    index: int
    kind: str
    class_id: int
    placement: vessels.Placement
    length_m: float
    beam_m: float
    air_draft_m: float
    waterline_z: float
    parts: list[MeshData] = field(default_factory=list)


@dataclass
class SceneGeometry:
    """Everything the renderer draws, in world coordinates (Z up, metres)."""

    sea: MeshData
    sea_roughness: float
    surface: ocean.OceanSurface
    vessels: list[VesselInstance]

    def digest(self) -> str:
        """SHA-256 of every mesh and material: two worlds with the same digest render the same
        images (converged references record it, so a changed generator makes them stale)."""
        import hashlib

        h = hashlib.sha256()
        meshes = [self.sea, *(part for v in self.vessels for part in v.parts)]
        for mesh in meshes:
            h.update(mesh.name.encode())
            h.update(np.ascontiguousarray(mesh.vertices, np.float32).tobytes())
            h.update(np.ascontiguousarray(mesh.faces, np.uint32).tobytes())
            h.update(np.asarray([*mesh.rgb, mesh.roughness], np.float64).tobytes())
        h.update(np.float64(self.sea_roughness).tobytes())
        return h.hexdigest()


def ocean_params(spec: SceneSpec) -> ocean.OceanParams:
    """Ocean generator parameters for a scene (Beaufort force, when given, sets the wind)."""
    sea = spec.sea
    wind = ocean.beaufort_wind_speed(sea.beaufort) if sea.beaufort is not None else sea.wind_speed
    return ocean.OceanParams(
        model=sea.model,
        spectrum=sea.spectrum,
        wind_speed=wind,
        fetch_km=sea.fetch_km,
        direction_deg=sea.direction_deg,
        choppiness=sea.choppiness,
        seed=stream_seed(spec.render.seed, Stream.SEA, sea.seed),
        time_s=sea.time_s,
    )


def build_sea(spec: SceneSpec, camera: Camera) -> tuple[MeshData, float, ocean.OceanSurface]:
    """The sea mesh to the horizon, its microfacet roughness and the surface for height queries."""
    params = ocean_params(spec)
    surface = ocean.make_surface(params)
    vertices, faces = ocean.build_sea_mesh(
        surface, camera_height_m=camera.height_m, quality=spec.sea.quality
    )[:2]
    # Full Cox–Munk roughness: most of the frame is the far sea, where the mesh is faded flat and
    # every wave is sub-grid; near the camera this counts the resolved waves twice (slightly rough).
    roughness = (
        spec.sea.roughness
        if spec.sea.roughness is not None
        else ocean.cox_munk_alpha(params.wind_speed)
    )
    return MeshData("sea", vertices, faces, spec.sea.water_color, roughness), roughness, surface


def load_user_meshes(spec: SceneSpec) -> dict[int, vessels.VesselModel]:
    """The user meshes of the explicit vessels, by index in ``spec.vessels.placed``.

    Relative paths are looked up in the working directory, then the repository's ``assets/``
    (a scene read by :func:`seahaze.sceneio.load_scene` holds absolute paths already). Raises
    FileNotFoundError or ValueError (from :func:`seahaze.vessels.load_user_mesh`).
    """
    models = {}
    for index, placed in enumerate(spec.vessels.placed):
        mesh = placed.mesh
        if mesh is None:
            continue
        path = vessels.resolve_mesh_path(mesh.path, vessels.mesh_search_dirs())
        if path is None:
            raise FileNotFoundError(f"user mesh not found: {mesh.path}")
        models[index] = vessels.load_user_mesh(
            path,
            placed.kind,
            mesh.scale_m,
            mesh.up_axis,
            mesh.forward_axis,
            draft_m=mesh.draft_m,
        )
    return models


def layout_vessels(
    spec: SceneSpec, camera: Camera, user_models: dict[int, vessels.VesselModel] | None = None
) -> list[vessels.Placement]:
    """Where the vessels go: explicit ones first, then sampled ones (never overlapping).

    ``user_models`` (from :func:`load_user_meshes`) give the explicit user-mesh vessels their
    real length and beam, so their footprints are right.
    """
    user_models = load_user_meshes(spec) if user_models is None else user_models
    rng = stream_rng(spec.render.seed, Stream.LAYOUT)
    items = [
        vessels.ExplicitVessel(
            p.kind,
            p.distance_m,
            p.bearing_deg,
            p.heading_deg,
            user_models[i].length_m if i in user_models else p.length_m,
            user_models[i].beam_m if i in user_models else None,
        )
        for i, p in enumerate(spec.vessels.placed)
    ]
    placements = vessels.place_explicit(items, camera.heading_deg, rng) if items else []
    sampler = spec.vessels.sample
    if sampler is not None and sampler.count > 0:
        rng = stream_rng(spec.render.seed, Stream.LAYOUT, sampler.seed)
        weights = sampler.classes or dict.fromkeys(vessels.CLASS_NAMES, 1.0)
        # The spec gives a half-width; the layout takes the full width of the bearing range.
        spread = (
            2.0 * sampler.bearing_spread_deg
            if sampler.bearing_spread_deg is not None
            else camera.fov_deg
        )
        placements += vessels.sample_layout(
            count=sampler.count,
            class_weights=weights,
            distance_range_m=sampler.distance_m,
            distribution=sampler.distribution,
            bearing_spread_deg=spread,
            min_separation_m=sampler.min_separation_m,
            camera_heading_deg=camera.heading_deg,
            rng=rng,
            horizontal_fov_deg=camera.fov_deg,
            existing=placements,
        )
    return placements


def build_vessels(
    spec: SceneSpec, camera: Camera, surface: ocean.OceanSurface
) -> list[VesselInstance]:
    """Vessel meshes placed on the sea; each vessel's waterline follows the surface height.

    With ``vessels.follow_slope`` each hull also pitches and rolls to the sea slope between its
    bow and stern and between its sides (finite differences of the surface height), so a ship
    longer than the waves bridges them instead of following every ripple.
    """
    user_models = load_user_meshes(spec)
    rng = stream_rng(spec.render.seed, Stream.VESSELS)
    instances = []
    for index, placement in enumerate(layout_vessels(spec, camera, user_models)):
        # Explicit vessels come first in the layout, so index i < len(placed) is placed[i].
        model = user_models.get(index)
        if model is None:
            model = vessels.build_vessel(placement.kind, placement.length_m, rng)
        parts = vessels.place_on_sea(
            model, placement, surface.height, follow_slope=spec.vessels.follow_slope
        )
        waterline = float(surface.height(np.array([placement.x]), np.array([placement.y]))[0])
        meshes = [
            MeshData(
                f"vessel{index:03d}_{name}",
                np.asarray(v, np.float32),
                np.asarray(f, np.uint32),
                tuple(mat.rgb),
                mat.roughness,
            )
            for name, v, f, mat in parts
        ]
        instances.append(
            VesselInstance(
                index,
                placement.kind,
                vessels.CLASS_NAMES.index(placement.kind),
                placement,
                model.length_m,
                model.beam_m,
                model.air_draft_m,
                waterline,
                meshes,
            )
        )
    return instances


def build_geometry(spec: SceneSpec, camera: Camera) -> SceneGeometry:
    """Sea and vessels for a scene."""
    sea, roughness, surface = build_sea(spec, camera)
    return SceneGeometry(sea, roughness, surface, build_vessels(spec, camera, surface))
