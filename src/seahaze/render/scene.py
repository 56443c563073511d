"""Turn scene geometry into one loaded Mitsuba scene whose haze changes per level.

The scene holds: a perspective camera near the origin, a tiny horizon camera for the ASM
airlight, the ``sunsky`` emitter, the sea and vessel meshes, and a box with a null BSDF whose
interior is the haze medium (a fog attached only to the sensor is unbounded and receives no
light). The box is sized by :func:`seahaze.haze.haze_box_half_width` for the thinnest haze of the
run and at least :data:`BOX_LAYER_WIDTHS` layer thicknesses; vertically it runs from below the
sea surface to the haze top. The medium is changed per level through ``mi.traverse`` (no reload,
no recompilation). The clean pass renders a second Mitsuba scene holding the same surfaces, sun
and sky without the box (``LoadedScene.clean_scene``): rays crossing the box's null surfaces draw
extra random numbers, so a clean pass through an empty box would change its noise with
``haze.top_m``, the levels (the box width) and whether the camera is inside the layer. The
``physical`` mode computes the haze itself and loads the scene without the box.

The sea's BSDF (:func:`sea_surface_bsdf`) blends, by the sea mesh's per-vertex values, a far
and a near water lobe (``blendbsdf`` weighted by the near-roughness weight: each vertex's slope
budget, docs/ocean.md) and then the water with a Lambertian foam whose reflectance is the
vertex's foam reflectance (weighted by its foam fraction); the values are read by
:mod:`seahaze.render.mesh_textures` textures of the sea mesh. Where no shape is attached to a
surface interaction (a BSDF sampled with a bare ``SurfaceInteraction3f``, as the ``physical``
mode's photon table does) the textures evaluate to 0 and the blend is the far water alone,
:func:`water_bsdf_dict` with :attr:`LoadedScene.sea_roughness`.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ..camera import Camera
from ..haze import Extinction, extinction_rgb, haze_box_half_width
from ..medium import HazeMedium
from ..ocean import FOAM_REFLECTANCE
from ..ocean.streaks import STREAK_REFLECTANCE, FoamStreaks, with_streaks
from ..scene_medium import haze_medium
from ..seeds import Stream, stream_seed
from ..spec import SceneSpec
from ..visibility import channel_extinction
from ..world import (
    SEA_FOAM,
    SEA_FOAM_REFLECTANCE,
    SEA_NEAR_ROUGHNESS,
    MeshData,
    SceneGeometry,
    wind_speed,
)
from .fleet import VesselMaterial, bind_paint, fleet_meshes, vessel_materials, vessel_spheres
from .mesh_textures import vertex_textures
from .sky import sky_emitters

SEA_SHAPE = -1
""":attr:`LoadedScene.shape_ids` value of the sea mesh."""
VESSEL_SHAPE = -4
""":attr:`LoadedScene.shape_ids` value of the vessel meshes (the face tells which vessel)."""
HAZE_ID = "haze"
HAZE_BOX_ID = "haze_box"
FAR_CLIP_M = 1.0e7
"""The perspective sensor's far clip (Mitsuba's default of 10 km would cut the far sea)."""
AIRLIGHT_FOV_DEG = 0.5
AIRLIGHT_RES = 8
PHYSICAL_SAMPLER = "multijitter"
"""The ``physical`` mode's sampler: correlated multi-jittered samples (Kensler 2013), stratified
in the pixel and in every dimension of the path, where the other modes keep ``independent``.
It lowers the sea's error at the same cost, because the pixel's many wave facets and the first
bounce's reflection lobe are stratified (docs/benchmarks.md, "Ground-truth noise"). It takes
``a × b`` samples with ``a = ⌊√spp⌋`` (:func:`stratified_spp`)."""
BOX_THIN_GROWTH = 4.0
"""Most the haze box widens for haze thinner than ``σ`` along some horizontal line of sight
in view (:meth:`seahaze.medium.HazeMedium.thinnest_horizontal_mean`): a bank off to one side;
beyond that the reference mode's grid would grow too coarse to follow the field."""
BOX_RUNGS_PER_OCTAVE = 4
"""Widths the haze box takes per doubling when it widens for a thin line of sight (each
2^(1/4) ≈ 1.19 times the last): :func:`_next_box_rung`."""
BOX_LAYER_WIDTHS = 3.0
"""Least half-width of the haze box in thicknesses ``H`` of the layer (``haze.top_m`` minus its
bottom). In dense haze the light reaches the camera by diffusing down through the layer, and
light let in through the box's sides changes that field near the camera by about
``exp(−π W / H)`` (the slowest diffusion mode of a slab), not by ``exp(−σ W)``: with only
``σ W = 8`` a `reference` render at V = 50 m was 3-7x too bright. ``3 H`` keeps it below 1e-4."""


def _mi():
    import mitsuba as mi

    return mi


def sensor_dict(
    camera: Camera,
    width: int,
    height: int,
    fov_deg: float,
    pitch_deg: float,
    inside_haze: bool,
    sampler: str = "independent",
) -> dict:
    """The Mitsuba ``perspective`` sensor dict of ``camera`` at ``width`` × ``height`` pixels,
    ``fov_deg`` wide (horizontally) and pitched by ``pitch_deg``, with a box-filtered RGB film
    and a ``sampler`` of that name; ``inside_haze`` starts its rays in the haze medium."""
    mi = _mi()
    cam = replace(camera, fov_deg=fov_deg, pitch_deg=pitch_deg, width=width, height=height)
    forward, _right, up = cam.basis()
    origin = cam.origin
    sensor: dict[str, Any] = {
        "type": "perspective",
        "fov": fov_deg,
        "fov_axis": "x",
        "near_clip": 0.05,
        "far_clip": FAR_CLIP_M,
        "to_world": mi.ScalarTransform4f().look_at(
            origin=origin.tolist(), target=(origin + forward).tolist(), up=up.tolist()
        ),
        "sampler": {"type": sampler},
        "film": {
            "type": "hdrfilm",
            "width": width,
            "height": height,
            "rfilter": {"type": "box"},
            "pixel_format": "rgb",
        },
    }
    if inside_haze:
        sensor["medium"] = {"type": "ref", "id": HAZE_ID}
    return sensor


def _place_medium_object(scene: dict[str, Any], medium: Any) -> None:
    """Put a medium given as an object (not a plugin dict) where ``scene`` refers to it:
    Mitsuba's dict parser resolves a ``ref`` only to objects it built itself."""
    holders = [(scene[key], "medium") for key in ("sensor", "sensor_airlight")]
    holders.append((scene[HAZE_BOX_ID], "interior"))
    for holder, prop in holders:
        if holder.get(prop) == {"type": "ref", "id": HAZE_ID}:
            holder[prop] = medium


def _mesh(name: str, vertices: np.ndarray, faces: np.ndarray, bsdf: Any) -> Any:
    """A Mitsuba mesh built straight from numpy arrays (no files) with the loaded BSDF
    ``bsdf``. Its per-vertex and per-face values live in the BSDF's textures
    (:mod:`seahaze.render.mesh_textures`), not in mesh attributes."""
    mi = _mi()
    props = mi.Properties()
    props["bsdf"] = bsdf
    m = mi.Mesh(name, vertex_count=len(vertices), face_count=len(faces), props=props)
    params = mi.traverse(m)
    params["vertex_positions"] = np.ascontiguousarray(vertices, dtype=np.float32).ravel()
    params["faces"] = np.ascontiguousarray(faces, dtype=np.uint32).ravel()
    params.update()
    return m


def _sea_mesh(sea: MeshData, bsdf: dict) -> Any:
    return _mesh(sea.name, sea.vertices, sea.faces, _mi().load_dict(bsdf))


def water_bsdf_dict(spec: SceneSpec, roughness: float) -> dict:
    """Fresnel interface (n = ior) over a dark diffuse water body: Mitsuba's rough plastic.

    Beckmann microfacets, because Cox and Munk's sea-surface slopes are Gaussian.
    """
    return {
        "type": "roughplastic",
        "distribution": "beckmann",
        "alpha": roughness,
        "int_ior": spec.sea.ior,
        "ext_ior": 1.000277,
        "nonlinear": False,
        "diffuse_reflectance": {"type": "rgb", "value": list(spec.sea.water_color)},
    }


def sea_surface_bsdf(
    spec: SceneSpec, geometry: SceneGeometry, streaks: FoamStreaks | None = None
) -> dict:
    """The sea shape's BSDF: water of :func:`water_bsdf_dict`, its near and far roughness lobes
    mixed per vertex, under foam where the sea mesh has some (module docstring). The per-vertex
    weights are read by :func:`~seahaze.render.mesh_textures.vertex_textures` textures of the sea
    mesh, not Mitsuba's ``mesh_attribute`` (a virtual call to the shape inside the BSDF's).
    ``streaks`` (:func:`sea_streaks`), where a gale draws them, are blended over it all."""
    sea = geometry.sea
    weights = vertex_textures(sea.faces, sea.attributes)
    water = water_bsdf_dict(spec, geometry.sea_roughness)
    near = geometry.sea_roughness_near
    if near is not None and SEA_NEAR_ROUGHNESS in weights:
        water = {
            "type": "blendbsdf",
            "weight": weights[SEA_NEAR_ROUGHNESS],
            "bsdf_0": water,
            "bsdf_1": water_bsdf_dict(spec, near),
        }
    if SEA_FOAM in weights:
        foam = {"type": "diffuse", "reflectance": weights[SEA_FOAM_REFLECTANCE]}
        water = {"type": "blendbsdf", "weight": weights[SEA_FOAM], "bsdf_0": water, "bsdf_1": foam}
    if streaks is None:
        return water
    # A gale's foam streaks over the water and its whitecaps, read at every shading point.
    from .streak_texture import streak_texture

    return {
        "type": "blendbsdf",
        "weight": streak_texture(streaks),
        "bsdf_0": water,
        "bsdf_1": {"type": "diffuse", "reflectance": STREAK_REFLECTANCE},
    }


def sea_streaks(spec: SceneSpec, elapsed_s: float = 0.0) -> FoamStreaks | None:
    """The scene's foam streaks (:mod:`seahaze.ocean.streaks`): from force 7 on a sea with
    waves and whitecaps, along the waves' direction, seeded as its waves are, drifted to
    ``elapsed_s`` seconds into its sequence; else None."""
    sea = spec.sea
    if sea.model == "flat" or not sea.whitecaps:
        return None
    seed = stream_seed(spec.render.seed, Stream.SEA, sea.seed)
    streaks = FoamStreaks(wind_speed(spec), sea.direction_deg, seed, elapsed_s)
    return streaks if streaks.present else None


def stratified_spp(spp: int) -> int:
    """The most samples per pixel, at most ``spp``, that Mitsuba's ``multijitter`` sampler
    (:data:`PHYSICAL_SAMPLER`) takes without rounding up: a grid of ``a × b`` with
    ``a = ⌊√n⌋`` and ``b = ⌈n / a⌉`` (32 → 30 as 5 × 6; every square and 1-4 unchanged).
    Rounding down keeps a render within the time its ``spp`` promises."""
    for n in range(max(int(spp), 1), 0, -1):
        a = math.isqrt(n)
        if a * -(-n // a) == n:
            return n
    return 1


_SCENE_COUNT = itertools.count()
"""Keys of the scenes a process builds (:attr:`LoadedScene.paint_owner`)."""


@dataclass
class LoadedScene:
    """A Mitsuba scene plus the handles the render passes need."""

    scene: Any
    params: Any
    camera: Camera
    box_half_width_m: float
    medium: HazeMedium
    """The haze the scene's levels render (its optics are the spec's; each level scales it)."""
    shape_ids: dict[int, int]
    """Mitsuba shape registry id → what it is: the sea -1, the haze box -2, a vessel mesh
    :data:`VESSEL_SHAPE` (its faces' vessels are in :attr:`vessel_faces`)."""
    spec: SceneSpec | None = None
    """The scene spec it was built from (the ``physical`` mode needs the sun and sky)."""
    sea_roughness: float = 0.0
    """Beckmann ``alpha`` (dimensionless) of the sea as a flat surface: all of Cox–Munk's slopes
    for the wind (or the spec's ``sea.roughness``), the far sea's lobe. A model of the sea as a
    plane (the ``physical`` mode's table) reflects with ``water_bsdf_dict(spec, sea_roughness)``."""
    sea_foam_coverage: float = 0.0
    """Mean share (0–1) of the sea surface covered by foam, ``F``: the fresh foam that gives
    the whitecaps' mean foam albedo (the coverage law's ``W`` for the wind at Koepke's 0.22 and
    the faint residual foam around it, over 0.55: 0.42 ``W``; 0 without whitecaps or on a
    flat sea), with a gale's spindrift and streaks. A plane model mixes
    ``(1 - F)·water + F·Lambertian(sea_foam_reflectance)``."""
    elapsed_s: float = 0.0
    """Time of this frame after a sequence's first (s; 0 for a still): the sky's clouds drifted
    that long (``render.sky.cloud_layer``)."""
    sea_foam_reflectance: float = FOAM_REFLECTANCE
    """Mean visible reflectance of that foam, a Lambertian albedo: fresh foam's 0.55 (the
    vertices' own), mixed by area with the streaks' 0.22 where a gale draws them."""
    vessel_faces: dict[int, np.ndarray] = field(default_factory=dict)
    """Shape registry id of each vessel mesh → the vessel index of every face (-1: none)."""
    n_vessels: int = 0
    """Vessels in the scene (indices 0 … n_vessels − 1)."""
    vessel_spheres: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)))
    """A sphere around every vessel, (n_vessels, 4): centre x, y, z and radius (m)."""
    clean_scene: Any = None
    """The same surfaces, sun and sky without the haze box, for the clean pass (None: ``scene``
    has no box and serves)."""
    vessel_materials: list[VesselMaterial] = field(default_factory=list)
    """The vessel meshes' BSDFs and paint textures, shared with other scenes (render/fleet.py)."""
    vessel_paint: list[np.ndarray] = field(default_factory=list)
    """This scene's paint of each vessel mesh, (M, 3) linear RGB per face."""
    paint_owner: int = field(default_factory=lambda: next(_SCENE_COUNT))
    """This scene's key among the scenes a process builds (bind_paint)."""

    def __post_init__(self) -> None:
        self.bind_paint()

    def bind_paint(self) -> None:
        """Point the shared paint textures at this scene's vessels' paint (if another scene
        was bound since): every render of the scene does it first (render/fleet.py)."""
        bind_paint(self.vessel_materials, self.vessel_paint, self.paint_owner)

    @property
    def has_haze_box(self) -> bool:
        """Whether the scene holds the Mitsuba haze medium (not so for the physical mode)."""
        names = self.params.keys()  # iterating the parameters themselves would read values
        return any(name.startswith(f"{HAZE_ID}.") for name in names)

    def set_haze(self, sigma_t: Extinction, albedo: float, g: float) -> None:
        """Change the medium in place (no reload, no recompilation); ``sigma_t`` (1/m) is grey
        or per channel (R, G, B)."""
        rgb = extinction_rgb(sigma_t)
        if not self.has_haze_box:
            if rgb.max() > 0.0:
                raise ValueError("this scene was loaded without a haze box (haze_box=False)")
            return
        for name, value in self.medium.mitsuba_level(rgb, albedo, g).items():
            self.params[f"{HAZE_ID}.{name}"] = value
        self.params.update()


def haze_box_width(
    medium: HazeMedium, camera: Camera, sigma_min: float, reach_m: float = 0.0
) -> float:
    """Half width (m) of the haze box around ``camera`` for levels whose clearest extinction is
    ``sigma_min`` (1/m) and objects out to ``reach_m``: 8 optical depths to the wall
    (:func:`seahaze.haze.haze_box_half_width`), along the thinnest horizontal line of sight in
    view where ``medium`` is thinner than its mean there (a bank off to one side), then at most
    :data:`BOX_THIN_GROWTH` times wider and on the ladder of :func:`_next_box_rung`; and at least
    :data:`BOX_LAYER_WIDTHS` layer thicknesses."""
    half_width = haze_box_half_width(sigma_min, reach_m)
    thinnest = medium.thinnest_horizontal_mean(camera, half_width)
    widened = haze_box_half_width(sigma_min * max(thinnest, 1.0 / BOX_THIN_GROWTH), reach_m)
    if widened > half_width:
        widened = _next_box_rung(widened, half_width)
    return max(half_width, widened, BOX_LAYER_WIDTHS * (medium.top_m - medium.bottom_m))


def _next_box_rung(widened: float, base: float) -> float:
    """``widened`` rounded up to the next of :data:`BOX_RUNGS_PER_OCTAVE` widths per doubling
    of ``base``. Mitsuba's grid volume writes its box into the render kernels as constants, so
    a box that followed a drifting bank exactly would compile them again for every frame; on
    the ladder, frames (and scenes) whose banks need about the same width share them. A box
    wider than needed only costs the grid's cells some resolution."""
    rung = math.ceil(BOX_RUNGS_PER_OCTAVE * math.log2(widened / base) - 1e-9)
    return base * 2.0 ** (rung / BOX_RUNGS_PER_OCTAVE)


def _box_corners(
    camera: Camera, half_width: float, bottom: float, top: float
) -> tuple[np.ndarray, np.ndarray]:
    """World corners (m) of the haze box around the camera: ``half_width`` to each side,
    from the medium's ``bottom`` to its ``top``."""
    centre = np.array([camera.x_m, camera.y_m])
    low = np.array([*(centre - half_width), bottom])
    return low, np.array([*(centre + half_width), top])


def shape_registry_id(shape: Any) -> int:
    """The integer id Mitsuba's intersection records use for ``shape``."""
    mi = _mi()
    import drjit as dr

    ptr = mi.ShapePtr(shape)
    return int(dr.reinterpret_array(mi.UInt32, ptr)[0]) if dr.is_jit_v(ptr) else id(shape)


def build_scene(
    spec: SceneSpec,
    camera: Camera,
    geometry: SceneGeometry,
    visibilities_m: list[float],
    *,
    black_vessels: bool = False,
    haze_box: bool = True,
    reach_m: float = 0.0,
    medium: HazeMedium | None = None,
) -> LoadedScene:
    """Load the Mitsuba scene for ``spec`` with a haze box wide enough for ``visibilities_m``
    and objects out to ``reach_m`` (:func:`seahaze.haze.haze_box_half_width`).

    ``black_vessels`` gives every vessel a black diffuse surface instead of painted steel (the
    black calibration targets of ``seahaze verify``). ``haze_box=False`` leaves the Mitsuba
    medium out: the ``physical`` mode computes the haze analytically in its own integrator and
    needs only the surfaces, sun and sky. ``medium``: the haze, default the one ``spec.haze``
    describes (:func:`seahaze.scene_medium.haze_medium`).
    """
    mi = _mi()
    haze = spec.haze
    medium = medium or haze_medium(haze, camera.height_m)
    # The sun and sky, built once for this scene and the clean pass's (a broken sky's image and
    # its sun's disk irradiance are each a second's work).
    lights = sky_emitters(spec, geometry.elapsed_s)
    top, bottom = medium.top_m, medium.bottom_m
    sigma_min = min(
        channel_extinction(v, haze.threshold, haze.extinction_spectrum).min()
        for v in visibilities_m or [1.0e4]
    )
    half_width = haze_box_width(medium, camera, sigma_min, reach_m)
    inside = camera.height_m < top and haze_box
    integrator = {"type": "volpath", "max_depth": spec.render.max_depth, "rr_depth": 8}
    haze_plugin = medium.mitsuba_medium(*_box_corners(camera, half_width, bottom, top))
    scene: dict[str, Any] = {
        "type": "scene",
        "integrator": integrator,
        HAZE_ID: haze_plugin,
        "sensor": sensor_dict(
            camera,
            camera.width,
            camera.height,
            camera.fov_deg,
            camera.pitch_deg,
            inside,
            "independent" if haze_box else PHYSICAL_SAMPLER,
        ),
        # The asm airlight is the haze's own horizon radiance. From a camera above the haze top
        # a level view sees only clear sky (the same A at every level), so the airlight view
        # then looks from mid-layer, below the camera.
        "sensor_airlight": sensor_dict(
            replace(camera, height_m=camera.height_m if camera.height_m < top else 0.5 * top),
            AIRLIGHT_RES,
            AIRLIGHT_RES,
            AIRLIGHT_FOV_DEG,
            0.0,
            haze_box,
        ),
        **lights,
        HAZE_BOX_ID: {
            "type": "cube",
            "to_world": mi.ScalarTransform4f()
            .translate([camera.x_m, camera.y_m, 0.5 * (top + bottom)])
            .scale([half_width, half_width, 0.5 * (top - bottom)]),
            "bsdf": {"type": "null"},
            "interior": {"type": "ref", "id": HAZE_ID},
        },
    }
    if not haze_box:
        del scene[HAZE_BOX_ID], scene[HAZE_ID]
    elif not isinstance(haze_plugin, dict):
        _place_medium_object(scene, haze_plugin)
    # The vessels as the same fixed set of meshes in every scene (render/fleet.py): one
    # compiled kernel serves every scene of a batch. Their BSDFs, kept from scene to scene,
    # are loaded before the sea's, so that they hold the lowest registry ids in every process
    # and the ids of every scene's BSDFs (which its kernel is traced over) are those of a
    # fresh process rendering that scene alone.
    fleet = fleet_meshes(geometry.vessels, (camera.x_m, camera.y_m))
    materials = vessel_materials(
        [(part.roughness, part.transmittance) for part in fleet], black_vessels
    )
    streaks = sea_streaks(spec, geometry.elapsed_s)
    surfaces = {"sea": _sea_mesh(geometry.sea, sea_surface_bsdf(spec, geometry, streaks))}
    for part, material in zip(fleet, materials, strict=True):
        surfaces[part.name] = _mesh(part.name, part.vertices, part.faces, material.bsdf)
    scene.update(surfaces)
    clean_scene = None
    if haze_box:
        # The clean pass's scene: the same mesh objects (shared, not copied), no box, no medium.
        sensor = sensor_dict(
            camera, camera.width, camera.height, camera.fov_deg, camera.pitch_deg, False
        )
        clean = {"type": "scene", "integrator": integrator, "sensor": sensor}
        clean_scene = mi.load_dict({**clean, **lights, **surfaces})
    loaded = mi.load_dict(scene)
    if haze_box and not isinstance(haze_plugin, dict):
        haze_plugin.set_id(HAZE_ID)  # the parser named it after the last property it filled
    params = mi.traverse(loaded)
    shape_ids: dict[int, int] = {}
    vessel_faces: dict[int, np.ndarray] = {}
    faces_of = {part.name: part.face_vessel for part in fleet}
    for shape in loaded.shapes():
        sid, key = shape.id(), shape_registry_id(shape)
        if sid in faces_of:
            shape_ids[key], vessel_faces[key] = VESSEL_SHAPE, faces_of[sid]
        else:
            shape_ids[key] = -2 if sid == HAZE_BOX_ID else SEA_SHAPE
    # The plane model of the sea (the physical mode's tables) takes the streaks' mean too.
    foam = with_streaks(geometry.sea_foam_coverage, geometry.sea_foam_reflectance, streaks)
    return LoadedScene(
        loaded,
        params,
        camera,
        half_width,
        medium,
        shape_ids,
        spec,
        vessel_faces=vessel_faces,
        n_vessels=len(geometry.vessels),
        vessel_spheres=vessel_spheres(fleet, len(geometry.vessels)),
        sea_roughness=geometry.sea_roughness,
        sea_foam_coverage=foam[0],
        sea_foam_reflectance=foam[1],
        elapsed_s=geometry.elapsed_s,
        clean_scene=clean_scene,
        vessel_materials=materials,
        vessel_paint=[part.paint for part in fleet],
    )
