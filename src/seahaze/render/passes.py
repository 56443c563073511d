"""Render passes over one loaded scene: geometry (distance, instances), clean, hazy levels.

Passes return linear radiance and per-pixel geometry as numpy arrays; they write no files.

Hazy levels of the yardstick modes (the ``physical`` mode is :mod:`seahaze.render.physical`)
    ``reference``  Mitsuba ``volpath`` through the haze box: unbiased, slow, noisy at low spp.
    ``asm``        The atmospheric scattering model (:func:`seahaze.haze.asm_composite`) with the
                   exact optical depth of each pixel's ray in the medium and the level's horizon
                   airlight: a ``volpath`` render of a narrow horizontal view at the camera
                   height, where the haze is optically thick at every level.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..haze import Extinction, asm_composite, optical_depth
from ..medium import HazeMedium
from ..seeds import RenderPass, render_seed
from .scene import VESSEL_SHAPE, LoadedScene, stratified_spp
from .wavefront import render_film

GEOMETRY_MAX_CROSSINGS = 16
"""Surfaces a pixel ray walks through: the haze box (twice at most) and vessels behind vessels."""


@dataclass
class GeometryPass:
    """Per-pixel geometry at pixel centres, from rays that pass through the haze box."""

    distance_m: np.ndarray
    """(H, W) float32 distance along the ray to the first surface (m), ``inf`` for the sky."""
    instance: np.ndarray
    """(H, W) int32 vessel index of the first surface, -1 for sea and sky."""
    directions: np.ndarray
    """(H, W, 3) float32 unit ray directions in the world frame."""
    origin: np.ndarray
    """(3,) camera position (m)."""
    footprint_px: np.ndarray | None = None
    """Per vessel, the pixels whose ray meets it anywhere before the sea: its unoccluded size."""

    def elevation_deg(self) -> np.ndarray:
        """(H, W) elevation of every pixel-centre ray above the horizontal (deg)."""
        return np.degrees(np.arcsin(np.clip(self.directions[..., 2], -1.0, 1.0)))

    def haze_path_length(self, medium: HazeMedium) -> np.ndarray:
        """(H, W) reduced length (m) of each pixel-centre ray in ``medium`` up to its surface
        (:meth:`seahaze.medium.HazeMedium.path_length`): a level's per-pixel optical depth is
        its extinction times this."""
        return medium.ray_path_length(self.origin, self.directions, self.distance_m)


def render_geometry(loaded: LoadedScene) -> GeometryPass:
    """Trace one ray per pixel centre, passing through the haze box's null surface.

    Mitsuba's ``aov`` integrator stops at null shapes, so the rays are traced here with
    ``scene.ray_intersect`` and continued past the haze box.
    """
    import drjit as dr
    import mitsuba as mi

    from .jit_haze import owned_floats, owned_indices

    cam = loaded.camera
    sensor = loaded.scene.sensors()[0]
    width, height = cam.width, cam.height
    idx = dr.arange(mi.UInt32, width * height)
    px = mi.Point2f((mi.Float(idx % width) + 0.5) / width, (mi.Float(idx // width) + 0.5) / height)
    ray, _ = sensor.sample_ray(0.0, 0.5, px, mi.Point2f(0.5, 0.5))
    # Rays start on the near-clip plane; distances are measured from the camera centre.
    origin = cam.origin
    directions = np.stack([np.array(ray.d.x), np.array(ray.d.y), np.array(ray.d.z)], axis=-1)

    # Map Mitsuba shape ids to what they are (-1 sea, -2 haze box, VESSEL_SHAPE a vessel mesh,
    # whose face then tells the vessel) with a sorted lookup table.
    keys = np.array(sorted(loaded.shape_ids), dtype=np.int64)
    values = np.array([loaded.shape_ids[k] for k in keys], dtype=np.int32)
    n_vessels = loaded.n_vessels
    n = width * height
    hit_point = np.full((n, 3), np.nan)
    first = np.full(n, -1, dtype=np.int32)
    pending = np.ones(n, dtype=bool)  # first surface not found yet
    travelled = np.zeros(n, dtype=np.float32)  # along the camera ray to the current origin
    footprint: list[np.ndarray] = []
    # The pixels still walking through the box and vessels: all at first, then only those
    # (a few percent), each crossing tracing just them instead of every pixel again.
    walking = np.arange(n)
    current = mi.Ray3f(ray)
    for _ in range(GEOMETRY_MAX_CROSSINGS):
        si = loaded.scene.ray_intersect(current)
        # Evaluate every field in one kernel: read lazily, each field (and the next spawned
        # ray) would re-trace the whole chain of crossings, quadratic in their number.
        dr.eval(si)
        m = len(walking)  # the rays traced: these, and a repeated one where m is 1
        valid = np.array(si.is_valid())[:m]
        sid = np.array(dr.reinterpret_array(mi.UInt32, si.shape))[:m].astype(np.int64)
        owner = np.where(valid, values[np.clip(np.searchsorted(keys, sid), 0, len(keys) - 1)], -3)
        owner = _vessel_owners(loaded, owner, sid, np.array(si.prim_index)[:m])
        p = np.stack([np.array(si.p.x), np.array(si.p.y), np.array(si.p.z)], axis=-1)[:m]
        found = pending[walking] & valid & (owner != -2)
        hit_point[walking[found]] = p[found]
        first[walking[found]] = owner[found]
        pending[walking] &= valid & (owner == -2)
        behind = owner >= 0
        footprint.append(walking[behind] * max(n_vessels, 1) + owner[behind])
        # Keep walking through the haze box and vessels; stop at the sea or the sky.
        going_on = valid & ((owner == -2) | behind)
        if not going_on.any():
            break
        # Continue on the same line just past this hit. si.spawn_ray would push the origin off
        # the line along the surface normal by ~1e-4 |p| (0.2 m on the top of a 2 km haze box
        # seen from above it), moving the sea hit by metres at grazing angles. The step along
        # the ray keeps the new origin past the surface despite float32 rounding of |p|.
        step = np.array(si.t * (1.0 + 1e-5) + 1e-3)[:m]
        travelled[walking] += step
        walking = walking[going_on]
        # The walking rays gathered from the camera's by index, every array in drjit's own
        # memory: one compiled kernel for any number of them (jit_haze.owned_floats).
        index = owned_indices(walking)
        d = dr.gather(mi.Vector3f, ray.d, index)
        far = owned_floats(np.resize(travelled[walking], dr.width(index)))
        current = mi.Ray3f(dr.gather(mi.Point3f, ray.o, index) + d * far, d)
    distance = np.linalg.norm(hit_point - origin, axis=-1)
    distance = np.where(np.isfinite(distance), distance, np.inf).astype(np.float32)
    pairs = np.unique(np.concatenate(footprint)) if footprint else np.zeros(0, np.int64)
    footprint_px = np.bincount(pairs % max(n_vessels, 1), minlength=n_vessels)[:n_vessels]
    return GeometryPass(
        distance.reshape(height, width),
        np.where(first >= 0, first, -1).astype(np.int32).reshape(height, width),
        directions.reshape(height, width, 3).astype(np.float32),
        origin,
        footprint_px.astype(np.int64),
    )


def _vessel_owners(
    loaded: LoadedScene, owner: np.ndarray, sid: np.ndarray, prim: np.ndarray
) -> np.ndarray:
    """``owner`` with each hit on a vessel mesh replaced by the vessel index of its face."""
    owner = owner.copy()
    for key, face_vessel in loaded.vessel_faces.items():
        on = (sid == key) & (owner == VESSEL_SHAPE)
        owner[on] = face_vessel[prim[on]]
    return owner


def render_radiance(
    loaded: LoadedScene,
    spp: int,
    seed: int,
    sensor_index: int = 0,
    integrator: Any = None,
    *,
    clean: bool = False,
    clip: bool = True,
    stratified: bool = False,
) -> np.ndarray:
    """Render linear RGB radiance (H, W, 3) float32 with the scene's current medium, by the
    scene's integrator or ``integrator`` (the physical mode's); ``clean`` renders the scene
    without the haze box (:attr:`LoadedScene.clean_scene`); ``clip=False`` keeps negative
    values (a correction, not a radiance); ``stratified`` draws from seahaze's multi-jittered
    sampler (:func:`seahaze.render.wavefront.render_film`; Python integrators only)."""
    scene = loaded.clean_scene if clean and loaded.clean_scene is not None else loaded.scene
    loaded.bind_paint()
    if not loaded.has_haze_box and sensor_index == 0:
        spp = stratified_spp(spp)  # the physical scene's multijitter sampler: no rounding up
    integrator = integrator if integrator is not None else scene.integrator()
    sensor = scene.sensors()[sensor_index]
    image = render_film(scene, sensor, integrator, spp, seed, stratified=stratified)
    # Mitsuba 3.9's sunsky gives the sun a negative blue radiance below about 3 deg elevation
    # (RGB -58 for +3819 red: its reddened colour lies outside the sRGB gamut), so the sun, its
    # glint and sunlit pixels can come out negative in blue. Clipping at zero is the gamut clip
    # (light is never negative); NaN stays NaN for the tests to catch.
    return np.maximum(image, 0.0) if clip else image


def render_clean(loaded: LoadedScene, spp: int, seed: int, albedo: float, g: float) -> np.ndarray:
    """Haze-free radiance: the scene's surfaces, sun and sky without the haze box, so the clean
    image of ``reference`` and ``asm`` is the same whatever the haze settings (``albedo`` and
    ``g`` are kept for callers; the medium is emptied too)."""
    loaded.set_haze(0.0, albedo, g)
    return render_radiance(loaded, spp, render_seed(seed, RenderPass.CLEAN), clean=True)


def render_reference_level(
    loaded: LoadedScene,
    sigma: Extinction,
    albedo: float,
    g: float,
    spp: int,
    seed: int,
    level_index: int,
) -> np.ndarray:
    """Hazy radiance by brute-force volumetric path tracing (``volpath``)."""
    loaded.set_haze(sigma, albedo, g)
    pass_seed = render_seed(seed, RenderPass.REFERENCE_LEVEL, level_index)
    return render_radiance(loaded, spp, pass_seed)


@dataclass(frozen=True)
class Airlight:
    """The horizon airlight of one level (linear RGB radiance) and its Monte Carlo standard
    error."""

    rgb: np.ndarray
    stderr: np.ndarray


AIRLIGHT_BATCHES = 4


def render_airlight(
    loaded: LoadedScene,
    sigma: Extinction,
    albedo: float,
    g: float,
    spp: int,
    seed: int,
    level_index: int,
) -> Airlight:
    """Mean radiance of a narrow horizontal view in the haze, from independent batches."""
    loaded.set_haze(sigma, albedo, g)
    per_batch = max(1, spp // AIRLIGHT_BATCHES)
    means = np.stack(
        [
            render_radiance(
                loaded,
                per_batch,
                render_seed(seed, RenderPass.AIRLIGHT, level_index, b),
                sensor_index=1,
            )
            .reshape(-1, 3)
            .mean(axis=0)
            for b in range(AIRLIGHT_BATCHES)
        ]
    )
    return Airlight(means.mean(axis=0), means.std(axis=0, ddof=1) / np.sqrt(AIRLIGHT_BATCHES))


def asm_level(
    clean: np.ndarray,
    geometry: GeometryPass,
    sigma: Extinction,
    airlight_rgb: np.ndarray,
    medium: HazeMedium,
) -> np.ndarray:
    """Hazy radiance by the atmospheric scattering model from the clean radiance, the exact
    per-pixel optical depth in ``medium`` of the geometry pass's rays and the level's
    airlight."""
    tau = optical_depth(sigma, geometry.haze_path_length(medium))
    return asm_composite(clean, tau, airlight_rgb)
