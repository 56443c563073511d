"""One scene, rendered: a validated spec in; images, passes, labels and metadata out, in memory.

This is the render layer's entry point for the dataset writer, ``seahaze verify``'s sibling
scripts and the benchmarks. It writes no file: :func:`seahaze.dataset.writer.write_scene` does.

One Mitsuba scene is loaded per scene; the geometry pass, the clean pass and every hazy level
reuse it (only the medium or the integrator's haze parameters change between levels).
"""

from __future__ import annotations

import gc
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .. import annotate, imaging, labels, motion, visible
from ..camera import Camera
from ..medium import HazeMedium
from ..motion_blur import motion_meta, shutter_displacement
from ..scene_medium import scene_haze_medium
from ..seeds import RenderPass, render_seed
from ..spec import SceneSpec
from ..visibility import (
    CLEAN_LEVEL,
    Threshold,
    channel_extinction,
    extinction_coefficient,
    level_name,
)
from ..world import SceneGeometry, build_geometry, frame_camera, layout_vessels, vessel_speeds
from . import passes
from .levels import LevelRenderer
from .passes import Airlight, GeometryPass
from .scene import PHYSICAL_SAMPLER, LoadedScene, build_scene
from .transmission import (
    LevelTransmission,
    RayReach,
    level_transmission,
    ray_reach,
    vessel_rays,
)
from .variant import select_variant

Progress = Callable[[str], None]


def _quiet(_: str) -> None:
    pass


@dataclass
class RenderedLevel:
    """One hazy level of a scene."""

    name: str
    """Folder name, e.g. ``v0300``."""
    visibility_m: float
    sigma_rgb: np.ndarray
    """(3,) extinction per channel (1/m)."""
    radiance: np.ndarray
    """(H, W, 3) float32 linear RGB radiance."""
    airlight: Airlight | None = None
    """The horizon airlight (``asm`` only)."""
    denoised: np.ndarray | None = None
    """(H, W, 3) float32 denoised radiance (``render.denoise: on``), else None."""
    transmission: LevelTransmission | None = None
    """Its exact per-pixel transmittance, optical depth and effective visibility."""

    @property
    def image(self) -> np.ndarray:
        """The radiance its PNG shows: denoised when denoising is on."""
        return self.radiance if self.denoised is None else self.denoised


@dataclass
class SceneRender:
    """Everything one scene's files hold, in memory."""

    name: str
    variant: str
    exposure: float
    """Linear factor from radiance to display values, the same for the clean image and every
    level (:mod:`seahaze.imaging`)."""
    clean: np.ndarray
    """(H, W, 3) float32 linear RGB radiance without haze."""
    levels: list[RenderedLevel]
    geometry: GeometryPass
    """Per-pixel distance (the depth file), instances and ray directions."""
    boxes: list[labels.Box]
    label_text: str
    """The YOLO label file of every level (the same boxes at every level)."""
    meta: dict[str, Any]
    """The scene's ``meta/<scene>.json``."""
    write_exr: bool = True
    timings: dict[str, float] = field(default_factory=dict)
    """Wall-clock seconds per pass (progress and logs only, never written to the dataset)."""
    clean_denoised: np.ndarray | None = None
    """(H, W, 3) float32 denoised clean radiance (``render.denoise: on``), else None."""
    visible_labels: dict[str, str] | None = None
    """Level name (clean first) → the YOLO label file of the vessels seen in its image
    (``labels.write_visible``, :mod:`seahaze.visible`), else None."""
    motion_px: np.ndarray | None = None
    """(H, W, 2) each pixel's displacement over the camera model's shutter time, which the
    PNGs are blurred along (:mod:`seahaze.motion_blur`); None for an instant."""

    @property
    def clean_image(self) -> np.ndarray:
        """The clean radiance its PNG shows: denoised when denoising is on."""
        return self.clean if self.clean_denoised is None else self.clean_denoised


@contextmanager
def _timed(timings: dict[str, float], key: str) -> Iterator[None]:
    start = time.perf_counter()
    try:
        yield
    finally:
        timings[key] = time.perf_counter() - start


@dataclass
class SceneSession:
    """One scene loaded for rendering: its camera, geometry, Mitsuba scene and geometry pass."""

    spec: SceneSpec
    variant: str
    camera: Camera
    geometry: SceneGeometry
    loaded: LoadedScene
    pixels: GeometryPass
    """Per-pixel distance, instances and ray directions (the depth file and the labels)."""

    def level_renderer(self, clean: np.ndarray | None = None) -> LevelRenderer:
        """The renderer of this scene's hazy levels in the spec's mode (``clean``: the clean
        pass, which ``asm`` composites; the physical mode renders its own)."""
        spec = self.spec
        return LevelRenderer(
            spec.render.mode, self.loaded, self.pixels, clean, spec.haze, spec.render
        )

    def render_clean(self, spp: int | None = None) -> np.ndarray:
        """The haze-free radiance (H, W, 3) at ``spp`` (default the spec's)."""
        haze, render = self.spec.haze, self.spec.render
        return passes.render_clean(self.loaded, spp or render.spp, render.seed, haze.albedo, haze.g)


@contextmanager
def _fresh_registry() -> Iterator[None]:
    """Build a scene's Mitsuba objects with the registry ids a fresh process would give them.

    drjit traces a virtual call over every live instance of a type, and a kernel's hash
    includes the instances' registry ids (a new object takes the lowest free one). So before
    the scene is built, the earlier scene's objects are freed — after drjit's queued kernels
    are done with them, and those in reference cycles by a collection — and while it is
    built no automatic collection runs: one would free some other cyclic temporary at a
    moment set by every thread's allocations, and the scene's next objects would take its id.
    Otherwise a batch scene now and then compiles its render kernel again (render/fleet.py).
    """
    import drjit as dr

    dr.sync_thread()
    gc.collect()
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


def open_session(
    spec: SceneSpec,
    geometry: SceneGeometry | None = None,
    *,
    black_vessels: bool = False,
    reach_m: float = 0.0,
    timings: dict[str, float] | None = None,
    frame: int | None = None,
    medium: HazeMedium | None = None,
) -> SceneSession:
    """Select the variant, build the geometry (unless given), load the Mitsuba scene for the
    spec's levels and mode, and trace the geometry pass.

    ``black_vessels`` and ``reach_m`` are for calibration scenes (:func:`build_scene`);
    ``frame`` is the frame of ``spec.sequence`` whose geometry is built; ``medium`` the haze,
    default the one the spec describes at that frame (a calibration scene renders its base
    scene's field: :mod:`seahaze.verify.field`).
    """
    timings = {} if timings is None else timings
    variant = select_variant(spec.render.variant)
    from .field_quadrature import with_kernel_quadrature  # needs the variant

    camera = frame_camera(spec, frame)
    with _timed(timings, "geometry_build"):
        geometry = build_geometry(spec, camera, frame) if geometry is None else geometry
    # The physical mode computes the haze itself: no Mitsuba medium in its scene.
    with _timed(timings, "scene_load"), _fresh_registry():
        loaded = build_scene(
            spec,
            camera,
            geometry,
            list(spec.haze.levels),
            black_vessels=black_vessels,
            haze_box=spec.render.mode != "physical",
            reach_m=reach_m,
            medium=with_kernel_quadrature(medium or scene_haze_medium(spec, camera, frame)),
        )
    with _timed(timings, "aov"):
        pixels = passes.render_geometry(loaded)
    return SceneSession(spec, variant, camera, geometry, loaded, pixels)


def render_scene(
    spec: SceneSpec, name: str, progress: Progress = _quiet, frame: int | None = None
) -> SceneRender:
    """Render one scene: geometry, clean and every level of ``spec.haze.levels``.

    ``frame``: render that frame of ``spec.sequence`` (its meta then carries the frame, its
    time and every vessel's track id and pose); None renders the scene as written.
    """
    timings: dict[str, float] = {}
    progress(f"{name}: building the sea, vessels and scene")
    session = open_session(spec, timings=timings, frame=frame)
    n_vessels = len(session.geometry.vessels)
    progress(f"{name}: scene loaded ({session.variant}, {n_vessels} vessels)")
    haze, mode = spec.haze, spec.render.mode
    sigmas = [channel_extinction(v, haze.threshold, haze.extinction_spectrum) for v in haze.levels]
    names = [level_name(v) for v in haze.levels]
    if mode == "physical":
        # One set of camera paths for the clean image and every level.
        with _timed(timings, "pass"):
            stage = lambda step: progress(f"{name}: {step}")  # noqa: E731
            clean, levels = session.level_renderer().render_all(sigmas, stage=stage)
        progress(f"{name}: clean + {len(levels)} levels in one pass, {timings['pass']:.1f} s")
    else:
        with _timed(timings, "clean"):
            clean = session.render_clean()
        progress(f"{name}: clean pass {timings['clean']:.1f} s")
        renderer = session.level_renderer(clean)
        levels = []
        for i, (key, sigma) in enumerate(zip(names, sigmas, strict=True)):
            with _timed(timings, f"level_{key}"):
                levels.append(renderer.render(sigma, i))
            progress(f"{name}: {key} ({mode}) {timings[f'level_{key}']:.1f} s")
    rendered = [
        RenderedLevel(key, v, sigma, level.radiance, level.airlight)
        for key, v, sigma, level in zip(names, haze.levels, sigmas, levels, strict=True)
    ]
    clean_denoised = None
    if spec.render.denoise == "on":
        with _timed(timings, "denoise"):
            clean_denoised = _denoise_all(session, clean, rendered)
        progress(f"{name}: denoised {1 + len(rendered)} images, {timings['denoise']:.1f} s")
    scene = _assemble(session, name, clean, rendered, timings, clean_denoised)
    if frame is not None and spec.sequence is not None:
        scene.meta = sequence_meta(scene.meta, session.geometry, spec, frame, session.camera)
        # The camera model's shutter: what moved during the frame's exposure.
        scene.motion_px = shutter_displacement(
            spec, frame, scene.geometry, session.camera, session.geometry.vessels
        )
        if scene.motion_px is not None:
            model = scene.meta["render"]["camera_model"]
            model["motion_blur"] = motion_meta(scene.motion_px)
    return scene


def sequence_meta(
    meta: dict[str, Any], geometry: SceneGeometry, spec: SceneSpec, frame: int, camera: Camera
) -> dict[str, Any]:
    """A frame's ``meta`` with its place in the sequence and each vessel's track id and pose
    (position in m, heading, pitch and roll in deg, vessel-frame bounds in m): enough to
    re-project the vessel and check its box. A still scene's meta has none of these keys."""
    sequence = spec.sequence
    assert sequence is not None
    by_index = {v.index: v for v in geometry.vessels}
    # The courses again (a fraction of a second) for the encounter each vessel is in.
    placements = layout_vessels(spec, Camera.from_spec(spec.camera))
    courses = motion.plan_courses(spec, placements, vessel_speeds(spec, placements))
    out_vessels = []
    for entry in meta["vessels"]:
        v = by_index[entry["index"]]
        p = v.placement
        pose = {
            "position_m": [p.x, p.y, v.waterline_z],
            "heading_deg": p.heading_deg,
            "pitch_deg": v.pitch_deg,
            "roll_deg": v.roll_deg,
            "bounds_m": [list(b) for b in v.bounds_m] if v.bounds_m is not None else None,
        }
        encounter = courses[v.index].encounter
        out_vessels.append({"track_id": v.track_id, **entry, "pose": pose, "encounter": encounter})
    return {
        **meta,
        # A ship platform's camera moves, heaves and pitches: position_m is the frame's, and
        # the view's pitch is recorded beside the scene's.
        "camera": {
            **meta["camera"],
            "pitch_used_deg": camera.pitch_deg,
            "roll_used_deg": camera.roll_deg,
            "heading_used_deg": camera.heading_deg,
        },
        "sequence": {
            **sequence.model_dump(mode="json"),
            "frame": frame,
            "time_s": sequence.time_s(frame),
            "sea_time_s": spec.sea.time_s + sequence.time_s(frame),
        },
        "vessels": out_vessels,
    }


def scene_exposure(session: SceneSession, clean: np.ndarray) -> float:
    """The linear exposure of a scene from its clean radiance (``render.exposure``)."""
    spec, geo = session.spec, session.pixels
    if spec.render.exposure != "auto":
        return float(spec.render.exposure)
    return imaging.auto_exposure(clean, geo.distance_m, geo.elevation_deg())


def _denoise_all(session: SceneSession, clean: np.ndarray, levels: list[RenderedLevel]) -> Any:
    """Denoise the clean image and every level (in place on ``levels``) with one set of
    feature buffers and the scene's exposure; returns the denoised clean radiance."""
    from . import denoise

    seed = render_seed(session.spec.render.seed, RenderPass.DENOISE_FEATURES)
    features = denoise.feature_buffers(session.loaded, seed)
    exposure = scene_exposure(session, clean)
    for level in levels:
        level.denoised = denoise.denoise(level.radiance, features, exposure)
    return denoise.denoise(clean, features, exposure)


def _assemble(
    session: SceneSession,
    name: str,
    clean: np.ndarray,
    levels: list[RenderedLevel],
    timings: dict[str, float],
    clean_denoised: np.ndarray | None = None,
) -> SceneRender:
    """Exposure, labels and metadata of the rendered passes. The exposure comes from the
    rendered clean radiance; the contrasts from the images the PNGs show (denoised or not)."""
    spec, camera, geometry, geo = session.spec, session.camera, session.geometry, session.pixels
    elevation = geo.elevation_deg()
    exposure = scene_exposure(session, clean)
    clean_radiance = clean
    clean = clean if clean_denoised is None else clean_denoised
    boxes = labels.boxes_from_instances(
        geo.instance,
        [v.class_id for v in geometry.vessels],
        geo.footprint_px,
        spec.labels.min_box_px,
        spec.labels.min_visible_fraction,
    )
    n_vessels = len(geometry.vessels)
    clean_horizon = annotate.horizon_luminance(clean, geo.distance_m, elevation)
    contrasts: annotate.LevelContrasts = {
        CLEAN_LEVEL: (
            np.inf,
            annotate.apparent_contrasts(clean, geo.instance, n_vessels, clean_horizon),
        )
    }
    # The same images for the contrast against each vessel's local background; the clean
    # image splits every vessel into its brighter and darker parts (seahaze.visible).
    local = {
        name: visible.local_contrasts(
            image, geo.instance, geo.distance_m, elevation, n_vessels, reference=clean
        )
        for name, image in [(CLEAN_LEVEL, clean), *((lv.name, lv.image) for lv in levels)]
    }
    reach = ray_reach(geo, session.loaded.medium)
    level_meta = []
    for level in levels:
        level.transmission = level_transmission(reach, level.sigma_rgb, level.visibility_m)
        horizon = annotate.horizon_luminance(level.image, geo.distance_m, elevation)
        if horizon is None and level.airlight is not None:
            horizon = float(imaging.luminance(level.airlight.rgb))
        contrasts[level.name] = (
            level.visibility_m,
            annotate.apparent_contrasts(level.image, geo.instance, n_vessels, horizon),
        )
        entry: dict[str, Any] = {
            "name": level.name,
            "visibility_m": level.visibility_m,
            "sigma_per_m": extinction_coefficient(level.visibility_m, spec.haze.threshold),
            "sigma_rgb_per_m": level.sigma_rgb.tolist(),
            "horizon_luminance": horizon,
            # The ray through the image's centre pixel (render.transmission).
            "visibility_eff_centre_m": float(
                level.transmission.visibility_eff_m[camera.height // 2, camera.width // 2]
            ),
        }
        if level.airlight is not None:
            entry["airlight_rgb"] = level.airlight.rgb.tolist()
            entry["airlight_stderr_rgb"] = level.airlight.stderr.tolist()
        level_meta.append(entry)
    meta = {
        "scene": name,
        "variant": session.variant,
        "mode": spec.render.mode,
        "exposure": exposure,
        "camera": {**spec.camera.model_dump(mode="json"), "position_m": camera.origin.tolist()},
        "sun": spec.sun.model_dump(mode="json"),
        "sky": spec.sky.model_dump(mode="json"),
        "sea": {
            **spec.sea.model_dump(mode="json"),
            "roughness_used": geometry.sea_roughness,
            "triangles": len(geometry.sea.faces),
        },
        "haze": {
            **spec.haze.model_dump(mode="json", exclude={"levels"}),
            "medium": session.loaded.medium.describe(),
            "box_half_width_m": session.loaded.box_half_width_m,
        },
        "levels": level_meta,
        "vessels": _with_transmission(
            annotate.vessel_meta(
                geometry, boxes, geo.footprint_px, contrasts, local, spec.haze.threshold
            ),
            levels,
            reach,
            geo,
            session.loaded.medium,
            spec.haze.threshold,
        ),
        "render": render_meta(spec),
    }
    return SceneRender(
        name,
        session.variant,
        exposure,
        clean_radiance,
        levels,
        geo,
        boxes,
        labels.yolo_text(boxes, camera.width, camera.height),
        meta,
        spec.render.write_exr,
        timings,
        clean_denoised,
        _visible_labels(spec, boxes, local, camera),
    )


def _with_transmission(
    vessels: list[dict[str, Any]],
    levels: list[RenderedLevel],
    reach: RayReach,
    geo: GeometryPass,
    medium: HazeMedium,
    threshold: Threshold | str,
) -> list[dict[str, Any]]:
    """``meta``'s vessels with, per hazy level, the transmittance over the pixels that show
    each vessel and the optical depth to its centre (the middle of its air draft above its
    waterline), at the level's nominal extinction (:class:`VesselRays`: each vessel's rays
    are traced once for every level)."""
    sigmas = {level.name: extinction_coefficient(level.visibility_m, threshold) for level in levels}
    for entry in vessels:
        x, y, waterline = entry["position_m"]
        centre = np.array([x, y, waterline + 0.5 * entry["air_draft_m"]])
        rays = vessel_rays(reach, geo.instance, entry["index"], centre, geo.origin, medium)
        for name, sigma in sigmas.items():
            entry["levels"][name].update(rays.entries(sigma))
    return vessels


def _visible_labels(
    spec: SceneSpec, boxes: list[labels.Box], local: annotate.LevelLocalContrasts, camera: Camera
) -> dict[str, str] | None:
    """Per level the YOLO text of the boxes of the vessels discernible in its image, with
    ``labels.write_visible``; else None."""
    if not spec.labels.write_visible:
        return None
    return {
        name: labels.yolo_text(
            visible.visible_boxes(boxes, contrasts, spec.haze.threshold),
            camera.width,
            camera.height,
        )
        for name, contrasts in local.items()
    }


def _illuminant(spec: SceneSpec) -> np.ndarray | None:
    """The scene's daylight (:func:`.sky.illuminant_rgb`) where its camera model balances its
    white to it, else None (nothing to measure)."""
    from .sky import illuminant_rgb

    model = spec.render.camera_model
    return illuminant_rgb(spec) if model and model.white_balance == "illuminant" else None


def render_meta(spec: SceneSpec) -> dict[str, Any]:
    """``meta``'s ``render`` entry: the samples actually taken, the ``physical`` mode's
    estimator settings and vessel-light pass (its samples per pixel and smoothing radius),
    what the denoiser did, how the PNGs are dithered and the camera model they went through."""
    from ..camera_model import camera_model_meta
    from . import denoise
    from .estimator import settings_from
    from .physical import stratified_spp, vessel_light_spp

    physical = spec.render.mode == "physical"
    entry: dict[str, Any] = {
        "spp": spec.render.spp,
        "spp_used": stratified_spp(spec.render.spp) if physical else spec.render.spp,
        "sampler": PHYSICAL_SAMPLER if physical else "independent",
        "denoise": spec.render.denoise,
        # How the writer quantises the PNGs (imaging.png_dither reads it back).
        **imaging.dither_meta(spec.render.dither, spec.render.seed),
        # The writer's camera model (camera_model.png_pixels reads it back); none: no key.
        **camera_model_meta(spec.render.camera_model, spec.render.seed, _illuminant(spec)),
    }
    settings = settings_from(spec.render.estimator)
    if physical:
        entry["estimator"] = settings.record()
    if physical and settings.vessel_light_share > 0.0:
        entry["vessel_light"] = {
            "spp": vessel_light_spp(spec.render.spp, settings),
            "smoothing_radius_px": settings.vessel_light_radius_px,
        }
    if spec.render.denoise == "on":
        entry["denoiser"] = {
            "library": "Intel Open Image Denoise (pyoidn)",
            "version": denoise.library_version(),
            "filter": "RT",
            "quality": denoise.QUALITY,
            "features": f"albedo, normal (Mitsuba aov, {denoise.AUX_SPP} spp)",
            "applied_to": "clean and every level PNG; EXRs undenoised",
        }
    return entry
