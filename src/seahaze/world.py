"""The world a scene spec describes: the sun's direction, the sea mesh and the placed vessels.

This is the step between the spec and the renderer: plain numpy meshes and materials, no
Mitsuba. World frame: Z up, metres, mean sea level at z = 0, the camera above the origin;
azimuths and headings counter-clockwise from +x seen from above. Seeds for the sea and the layout
derive from ``render.seed`` (:mod:`seahaze.seeds`) unless the spec gives its own, so one master
seed reproduces a whole scene. Explicit vessels with a ``mesh`` are loaded from the user's file
(``sceneio`` has already resolved and checked the path of a scene file).

The sea mesh carries per-vertex attributes for the renderer (``MeshData.attributes``): the
whitecap and wake foam fraction and its reflectance, and the weight of the near-field roughness
lobe (docs/ocean.md, "Rendering the sea"). Explicit vessels move at their ``speed_kn`` (default
0); sampled vessels' speeds are drawn from the layout seed's own sub-stream
(:func:`vessel_speeds`), so adding them shifted no layout.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from . import motion, ocean, vessels
from .camera import Camera
from .seeds import Stream, stream_rng, stream_seed
from .spec import SceneSpec, VesselSampler

SPEED_SUBSTREAM = 1
"""Sub-stream of a layout seed that draws the vessels' speeds: ``SeedSequence([layout seed,
SPEED_SUBSTREAM])``. Fixed forever, like the streams of :mod:`seahaze.seeds`."""

SEA_FOAM = "foam"
SEA_FOAM_REFLECTANCE = "foam_reflectance"
SEA_NEAR_ROUGHNESS = "near_roughness"
"""Names of the sea mesh's per-vertex attributes (``MeshData.attributes``)."""


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
    attributes: dict[str, np.ndarray] = field(default_factory=dict)
    """Per-vertex float32 ``(N,)`` attributes for the renderer (the sea's :data:`SEA_FOAM`,
    :data:`SEA_FOAM_REFLECTANCE`, :data:`SEA_NEAR_ROUGHNESS`)."""
    transmittance: float = 0.0
    """Share of its diffuse light a translucent sheet (a sail) passes through (0: opaque;
    :attr:`seahaze.vessels.materials.Material.transmittance`)."""


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
    speed_m_s: float = 0.0
    """Speed through the water (m/s); a moving vessel makes waves and a foam wake."""
    hull_draft_m: float = 0.0
    """Draft of the displacing hull body (m), for the vessel's waves."""
    pitch_deg: float = 0.0
    """Bow-up pitch to the sea slope (deg; 0 unless ``vessels.follow_slope``)."""
    roll_deg: float = 0.0
    """Port-up roll to the sea slope (deg; 0 unless ``vessels.follow_slope``)."""
    bounds_m: tuple[tuple[float, float, float], tuple[float, float, float]] | None = None
    """Vessel-frame box ``(min xyz, max xyz)`` (m) of the model: with the pose it re-projects
    the vessel's image box."""

    @property
    def track_id(self) -> int:
        """Persistent id of the vessel across a sequence's frames (1-based, as MOTChallenge)."""
        return self.index + 1

    @property
    def speed_kn(self) -> float:
        """:attr:`speed_m_s` in knots."""
        return self.speed_m_s / vessels.KNOT_M_S


@dataclass
class SceneGeometry:
    """Everything the renderer draws, in world coordinates (Z up, metres)."""

    sea: MeshData
    sea_roughness: float
    """Beckmann ``alpha`` of a flat sea with all of the wind's slopes (Cox–Munk, or the
    spec's ``sea.roughness``): the far sea's, and what a flat-sea model of this sea uses."""
    surface: ocean.OceanSurface
    vessels: list[VesselInstance]
    sea_roughness_near: float | None = None
    """Beckmann ``alpha`` where the mesh resolves its waves (the sub-grid slopes only); None
    when the whole sea has :attr:`sea_roughness` (flat sea, or ``sea.roughness`` given)."""
    sea_foam_coverage: float = 0.0
    """Mean share of the sea surface (0–1) covered by fresh foam (``ocean.as_fresh_foam``):
    the whitecaps' mean foam albedo ``FoamField.albedo`` (the coverage ``W`` of the wind and
    the faint residual foam around it) over 0.55, with a gale's spindrift (0 without
    whitecaps)."""
    sea_foam_reflectance: float = ocean.FOAM_REFLECTANCE
    """Reflectance of that foam (fresh foam's 0.55 where there are whitecaps): coverage ×
    reflectance is the mean foam albedo of the sea mesh."""
    camera_xy: tuple[float, float] = (0.0, 0.0)
    """Horizontal camera position (m) the distances are measured from (a ship platform's)."""
    elapsed_s: float = 0.0
    """Time of this frame after a sequence's first (s; 0 for a still): how far a broken sky's
    clouds have drifted."""

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
            if mesh.transmittance > 0.0:  # opaque meshes keep the digests they always had
                h.update(np.float64(mesh.transmittance).tobytes())
            for key in sorted(mesh.attributes):
                h.update(key.encode())
                h.update(np.ascontiguousarray(mesh.attributes[key], np.float32).tobytes())
        near = -1.0 if self.sea_roughness_near is None else self.sea_roughness_near
        foam = [self.sea_foam_coverage, self.sea_foam_reflectance]
        h.update(np.asarray([self.sea_roughness, near, *foam]).tobytes())
        return h.hexdigest()


def wind_speed(spec: SceneSpec) -> float:
    """The scene's wind ``U10`` (m/s at 10 m): ``sea.beaufort``'s when given, else
    ``sea.wind_speed``."""
    sea = spec.sea
    return ocean.beaufort_wind_speed(sea.beaufort) if sea.beaufort is not None else sea.wind_speed


def ocean_params(spec: SceneSpec, elapsed_s: float = 0.0) -> ocean.OceanParams:
    """Ocean generator parameters for a scene (Beaufort force, when given, sets the wind),
    ``elapsed_s`` seconds after ``sea.time_s`` (a sequence's frame time)."""
    sea = spec.sea
    wind = wind_speed(spec)
    return ocean.OceanParams(
        model=sea.model,
        spectrum=sea.spectrum,
        wind_speed=wind,
        fetch_km=sea.fetch_km,
        direction_deg=sea.direction_deg,
        choppiness=sea.choppiness,
        seed=stream_seed(spec.render.seed, Stream.SEA, sea.seed),
        # Adding 0.0 leaves a still scene's time, and so its bytes, exactly as they were.
        time_s=sea.time_s + elapsed_s,
    )


@dataclass(frozen=True)
class Sea:
    """The sea of a scene: its mesh (with per-vertex foam and roughness mix), the roughness of
    its two lobes, its foam coverage and the surface for height queries."""

    mesh: MeshData
    roughness: float
    """Far-sea (flat-sea) Beckmann ``alpha``: :attr:`SceneGeometry.sea_roughness`."""
    surface: ocean.OceanSurface
    roughness_near: float | None = None
    foam_coverage: float = 0.0
    foam_reflectance: float = ocean.FOAM_REFLECTANCE


def sea_whitecaps(spec: SceneSpec, surface: ocean.OceanSurface) -> ocean.FoamField | None:
    """The whitecaps of ``surface`` for the scene's wind (``FoamField``); None on a flat sea or
    with ``sea.whitecaps: false``."""
    if not spec.sea.whitecaps or isinstance(surface, ocean.FlatSurface):
        return None
    return ocean.FoamField(surface, ocean_params(spec).wind_speed)


def build_sea(
    spec: SceneSpec,
    camera: Camera,
    moving: Sequence[ocean.MovingVessel] = (),
    surface: ocean.OceanSurface | None = None,
    whitecaps: Future[ocean.FoamField | None] | None = None,
) -> Sea:
    """The sea mesh to the horizon with its whitecaps and the waves and wakes of ``moving``
    vessels, its roughness and the surface for height queries (``surface``: reuse one).

    Roughness (docs/ocean.md): with ``sea.roughness`` given, that ``alpha`` everywhere.
    Otherwise the slope budget of every vertex — Cox–Munk's total less what the vertex's
    band-limited, faded displacement resolves — as a mix of a near lobe (the sub-grid slopes
    at the finest spacing) and a far lobe (all slopes, the flat far sea):
    :func:`seahaze.ocean.mesh_roughness`. Foam: :func:`sea_whitecaps` (``whitecaps``: a future
    of it, built elsewhere) on the breaking crests, each vertex holding the whitecaps of its
    cell, plus the wakes' foam. Waves, whitecaps and wakes are computed only where the camera
    can see them (``view`` of :func:`seahaze.ocean.build_sea_mesh_data`).
    """
    params = ocean_params(spec)
    surface = ocean.make_surface(params) if surface is None else surface
    wakes = ocean.WakeField(moving) if moving else None
    foam = sea_whitecaps(spec, surface) if whitecaps is None else whitecaps.result()
    spindrift = None if foam is None else ocean.Spindrift(foam, spec.sea.direction_deg)
    mesh = ocean.build_sea_mesh_data(
        surface,
        camera_xy=(camera.x_m, camera.y_m),
        camera_height_m=camera.height_m,
        quality=spec.sea.quality,
        foam=foam,
        wakes=wakes,
        view=(math.radians(camera.heading_deg), camera.view_azimuth_half_width()),
        spindrift=spindrift,
    )
    attributes: dict[str, np.ndarray] = {}
    if mesh.foam is not None and mesh.foam_reflectance is not None and mesh.foam.max() > 0.0:
        attributes[SEA_FOAM] = mesh.foam
        attributes[SEA_FOAM_REFLECTANCE] = mesh.foam_reflectance
    near: float | None = None
    if spec.sea.roughness is not None:
        roughness = spec.sea.roughness
    else:
        mix = ocean.mesh_roughness(
            params.wind_speed, surface, mesh.vertex_spacing_m, mesh.vertex_fade
        )
        roughness = mix.alpha_far
        if mix.alpha_near < mix.alpha_far and mix.near_weight.max() > 0.0:
            near = mix.alpha_near
            attributes[SEA_NEAR_ROUGHNESS] = mix.near_weight
    sea = MeshData("sea", mesh.vertices, mesh.faces, spec.sea.water_color, roughness, attributes)
    if foam is None:
        return Sea(sea, roughness, surface, near)
    coverage, albedo = foam.mean_fraction, foam.albedo
    if spindrift is not None and spindrift.present:
        veil = spindrift.mean_veil
        coverage, albedo = ocean.layer_over(coverage, albedo, veil, ocean.SPRAY_REFLECTANCE)
    share, reflectance = ocean.as_fresh_foam(coverage, albedo)
    return Sea(sea, roughness, surface, near, share, reflectance)


def vessel_speeds(spec: SceneSpec, placements: Sequence[vessels.Placement]) -> list[float]:
    """Speed through the water (m/s) of every placement (explicit vessels first).

    An explicit vessel moves only if the scene says so: its ``speed_kn``, default 0 (stopped,
    moored or drifting); ValueError if faster than its class allows. A sampled vessel's speed
    is drawn uniformly in its class's service-speed range (buoys 0), one draw per vessel in
    order from the sub-stream :data:`SPEED_SUBSTREAM` of the layout seed (the sampler's
    ``seed`` when given), so the layout itself is unchanged by the draws.
    """
    n_placed = len(spec.vessels.placed)
    sampler = spec.vessels.sample
    layout_seed = stream_seed(spec.render.seed, Stream.LAYOUT, sampler.seed if sampler else None)
    rng = np.random.default_rng(np.random.SeedSequence([layout_seed, SPEED_SUBSTREAM]))
    speeds = []
    for index, placement in enumerate(placements):
        if index >= n_placed:
            speeds.append(vessels.sample_speed_m_s(placement.kind, rng))
            continue
        given = spec.vessels.placed[index].speed_kn or 0.0
        problem = vessels.speed_problem(placement.kind, given)
        if problem is not None:
            raise ValueError(f"vessels.placed[{index}].speed_kn: {problem}")
        speeds.append(given * vessels.KNOT_M_S)
    return speeds


def moving_vessels(instances: Sequence[VesselInstance]) -> list[ocean.MovingVessel]:
    """The vessels under way as the sea sees them; a draftless user mesh: draft = beam / 10."""
    return [
        ocean.MovingVessel(
            v.placement.x,
            v.placement.y,
            v.placement.heading_deg,
            v.speed_m_s,
            v.length_m,
            v.beam_m,
            v.hull_draft_m if v.hull_draft_m > 0.0 else 0.1 * v.beam_m,
            v.placement.turn_rate_deg_s,  # a turning vessel's wake follows its arc
        )
        for v in instances
        if v.speed_m_s > 0.0
    ]


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
            max_image_overlap=sampler.max_image_overlap,
            **_near_enough(sampler),
        )
    return placements


def wind_off_bow(wind_toward_deg: float, heading_deg: float) -> float:
    """Where the wind comes from, degrees off a bow pointing to azimuth ``heading_deg``
    (positive to port, in (−180, 180]), for a wind blowing toward ``wind_toward_deg`` (the
    sea's ``direction_deg``: a wind sea runs with its wind). Azimuths counter-clockwise
    from +x."""
    off = (wind_toward_deg + 180.0 - heading_deg) % 360.0
    return off - 360.0 if off > 180.0 else off


def _near_enough(sampler: VesselSampler) -> dict[str, Any]:
    """The layout's distance cap for the sampler's ``detectable`` share: a vessel of least
    height ``h`` (m above the waterline) subtends ``h / d`` rad at distance ``d`` (level view,
    small angles), so it looks at least ``min_height_mrad`` tall out to
    ``d = 1000 h / min_height_mrad``. None: no cap."""
    rule = sampler.detectable
    if rule is None:
        return {}
    count = math.ceil(rule.share * sampler.count)
    return {
        "near_enough": lambda kind, length: (
            1000.0 * vessels.min_air_draft_m(kind, length) / rule.min_height_mrad
        ),
        "n_near": count,
    }


def frame_layout(
    spec: SceneSpec,
    camera: Camera,
    frame: int | None,
    user_models: dict[int, vessels.VesselModel] | None = None,
    offset_s: float = 0.0,
) -> tuple[list[vessels.Placement], list[float]]:
    """The vessels' placements and speeds (m/s) at ``frame`` of the scene's sequence (None:
    the scene as written, a still), or ``offset_s`` seconds after it (a shutter's opening and
    closing); distances from ``camera``'s position, bearings from the scene's
    ``camera.heading_deg`` (not a rigidly mounted camera's yaw on the swell)."""
    camera = replace(camera, heading_deg=spec.camera.heading_deg)
    placements = layout_vessels(spec, camera, user_models)
    speeds = vessel_speeds(spec, placements)
    if frame is None or spec.sequence is None:
        return placements, speeds
    t = spec.sequence.time_s(frame) + offset_s
    courses = motion.plan_courses(spec, placements, speeds)
    xy = (camera.x_m, camera.y_m)
    return [c.placement_at(t, camera.heading_deg, xy) for c in courses], [
        c.speed_m_s for c in courses
    ]


def frame_camera(spec: SceneSpec, frame: int | None = None, offset_s: float = 0.0) -> Camera:
    """The camera at ``frame`` of the scene's sequence (None: the scene's camera), or
    ``offset_s`` seconds after it.

    On a ``ship`` platform the camera sails with the own ship (:func:`seahaze.motion.own_course`)
    and rides its heave and pitch: the own ship floats on the surface at the frame's time, its
    waterline at the surface height under midships, pitched and rolled to the slope over its
    length and beam (a long hull averages short waves, as the vessels' do); the mast carries the
    camera ``camera.height_m`` above the waterline, and the view's pitch gains the ship's
    pitch and roll projected on the view direction. With ``sequence.camera_mount: level`` the
    camera is roll-stabilised (it keeps ``camera.roll_deg``); with ``rigid`` it is fixed to the
    hull instead: its spec angles hold with the hull level, the hull's rotation
    (:func:`seahaze.vessels.hull_rotation`) turns its whole basis and tilts the mast.
    """
    camera = Camera.from_spec(spec.camera)
    own = motion.own_course(spec)
    if frame is None or spec.sequence is None or own is None:
        return camera
    t = spec.sequence.time_s(frame) + offset_s
    x, y, heading = own.pose(t)
    surface = ocean.make_surface(ocean_params(spec, t))
    length = own.placement.length_m
    beam = motion.OWN_BEAM_FRACTION * length
    h = math.radians(heading)
    fwd, port = np.array([math.cos(h), math.sin(h)]), np.array([-math.sin(h), math.cos(h)])
    centre = np.array([x, y])
    points = centre + np.array(
        [0.5 * length * fwd, -0.5 * length * fwd, 0.5 * beam * port, -0.5 * beam * port, 0.0 * fwd]
    )
    z = np.asarray(surface.height(points[:, 0], points[:, 1]), np.float64)
    pitch = math.atan((z[0] - z[1]) / length)
    roll = math.atan((z[2] - z[3]) / beam)
    if spec.sequence.camera_mount == "rigid":
        rot = vessels.hull_rotation(heading, pitch, roll)
        forward, _, up = replace(camera, heading_deg=camera.heading_deg - heading).basis()
        mx, my, mz = (np.array([x, y, z[4]]) + rot @ np.array([0.0, 0.0, camera.height_m])).tolist()
        return replace(camera.pointing(rot @ forward, rot @ up), x_m=mx, y_m=my, height_m=mz)
    look = math.radians(camera.heading_deg - heading)
    view_pitch = camera.pitch_deg + math.degrees(pitch * math.cos(look) + roll * math.sin(look))
    return replace(
        camera, x_m=x, y_m=y, height_m=camera.height_m + float(z[4]), pitch_deg=view_pitch
    )


def build_vessels(
    spec: SceneSpec, camera: Camera, surface: ocean.OceanSurface, frame: int | None = None
) -> list[VesselInstance]:
    """Vessel meshes placed on the sea; each vessel's waterline follows the surface height.

    With ``vessels.follow_slope`` each hull also pitches and rolls to the sea slope between its
    bow and stern and between its sides (finite differences of the surface height), so a ship
    longer than the waves bridges them instead of following every ripple. ``frame``: the
    vessels where their courses (:mod:`seahaze.motion`) put them at that frame's time; the
    models are built once per sequence (:func:`seahaze.vessels.build_vessel_reused`).
    """
    user_models = load_user_meshes(spec)
    rng = stream_rng(spec.render.seed, Stream.VESSELS)
    instances = []
    placements, speeds = frame_layout(spec, camera, frame, user_models)
    for index, placement in enumerate(placements):
        # Explicit vessels come first in the layout, so index i < len(placed) is placed[i].
        model = user_models.get(index)
        if model is None:
            # A sailboat trims its sails to the wind; nothing else depends on it.
            wind = (
                wind_off_bow(spec.sea.direction_deg, placement.heading_deg)
                if placement.kind == "sailboat"
                else None
            )
            model = vessels.build_vessel_reused(placement.kind, placement.length_m, rng, wind)
        parts = vessels.place_on_sea(
            model, placement, surface.height, follow_slope=spec.vessels.follow_slope
        )
        waterline, pitch, roll = vessels.vessel_attitude(
            model, placement, surface.height, follow_slope=spec.vessels.follow_slope
        )
        meshes = [
            MeshData(
                f"vessel{index:03d}_{name}",
                np.asarray(v, np.float32),
                np.asarray(f, np.uint32),
                tuple(mat.rgb),
                mat.roughness,
                transmittance=mat.transmittance,
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
                speeds[index],
                model.displacing_draft_m,
                math.degrees(pitch),
                math.degrees(roll),
                _bounds(model),
            )
        )
    return instances


def _bounds(
    model: vessels.VesselModel,
) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    low, high = np.asarray(model.bounds(), np.float64)
    return (
        (float(low[0]), float(low[1]), float(low[2])),
        (float(high[0]), float(high[1]), float(high[2])),
    )


def build_geometry(spec: SceneSpec, camera: Camera, frame: int | None = None) -> SceneGeometry:
    """Sea and vessels for a scene: the vessels first (the sea needs their wakes), floating on
    the wave surface (their waterline ignores their own wakes).

    ``frame``: that frame of ``spec.sequence``, the sea advanced to its time and the vessels
    moved along their courses; None (or a scene without sequence): the scene as written.
    """
    elapsed = spec.sequence.time_s(frame) if frame is not None and spec.sequence else 0.0
    surface = ocean.make_surface(ocean_params(spec, elapsed))
    # The whitecaps depend on the surface alone: built on a second thread meanwhile (numpy's
    # sorts and SciPy's FFTs release the GIL).
    with ThreadPoolExecutor(max_workers=1) as pool:
        whitecaps = pool.submit(sea_whitecaps, spec, surface)
        instances = build_vessels(spec, camera, surface, frame)
        moving = moving_vessels(instances) if spec.vessels.wakes else []
        sea = build_sea(spec, camera, moving, surface, whitecaps)
    return SceneGeometry(
        sea.mesh,
        sea.roughness,
        surface,
        instances,
        sea_roughness_near=sea.roughness_near,
        sea_foam_coverage=sea.foam_coverage,
        sea_foam_reflectance=sea.foam_reflectance,
        camera_xy=(camera.x_m, camera.y_m),
        elapsed_s=elapsed,
    )
