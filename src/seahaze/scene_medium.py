"""The haze medium a scene's ``haze`` section describes: the one place that picks its kind."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from .fog_layer import fog_layer_medium
from .haze_field import Bank, Drift, HazeField, Patches
from .medium import HazeMedium, HomogeneousSlab
from .nonuniform import HorizontalView, NonUniformHaze, nonuniform_haze
from .seeds import Stream, stream_seed


def haze_medium(haze: Any, camera_height_m: float | None = None) -> HazeMedium:
    """The medium a scene's ``haze`` section (:class:`seahaze.spec.HazeSpec`) describes: a
    homogeneous slab from :data:`seahaze.medium.HAZE_BOTTOM_M` to ``haze.top_m``, or with
    ``haze.fog_layer`` a :class:`seahaze.fog_layer.FogLayer` whose density is 1 at
    ``camera_height_m`` (m; needed then)."""
    albedo, g = float(haze.albedo), float(haze.g)
    fog = getattr(haze, "fog_layer", None)
    if fog is None:
        return HomogeneousSlab(top=float(haze.top_m), albedo=albedo, g=g)
    if camera_height_m is None:
        raise ValueError("a fog layer's density is set at the camera's height: give it")
    return fog_layer_medium(
        fog.top_m, fog.edge_m, fog.above_ratio, haze.top_m, camera_height_m, albedo, g
    )


def scene_haze_medium(spec: Any, camera: Any, frame: int | None = None) -> HazeMedium:
    """The medium of a whole scene (:class:`seahaze.spec.SceneSpec`) seen by ``camera``
    (:class:`seahaze.camera.Camera`) at ``frame`` of its sequence (None: time 0): the
    vertical profile of :func:`haze_medium`, times ``haze.patches`` and ``haze.bank`` where
    the scene has them (:mod:`seahaze.nonuniform`), drifted to the frame's time; normalised
    at time 0 over the view of the camera the file describes (from the origin), so that in a
    sequence the field only moves. Directions in the scene file are relative to the
    camera's heading (``camera.heading_deg``, as the file gives it: a ship's turning does not
    turn the fog); the bank's edge is measured from where the camera starts."""
    profile = haze_medium(spec.haze, camera.height_m)
    time_s = 0.0
    if frame is not None and spec.sequence is not None:
        time_s = frame / spec.sequence.fps
    field = haze_field(spec, time_s)
    if field is None:
        return profile
    # The level's normalisation is the field's at time 0 over the view of the camera as the
    # file gives it: in a sequence the field then only moves, frame to frame.
    cam = spec.camera
    view = HorizontalView(0.0, 0.0, cam.height_m, cam.heading_deg, cam.fov_deg)
    at_start = replace(field, drift=replace(field.drift, time_s=0.0))
    return NonUniformHaze(profile, field, nonuniform_haze(profile, at_start, view).scale)


def haze_field(spec: Any, time_s: float = 0.0) -> HazeField | None:
    """The patches and bank of a scene's ``haze`` (:mod:`seahaze.haze_field`) at ``time_s``
    (s), in the world frame (directions turned by ``camera.heading_deg``, the patches seeded
    from the scene's seed); None for haze that varies with height alone."""
    haze = spec.haze
    if haze.patches is None and haze.bank is None:
        return None
    heading = float(spec.camera.heading_deg)
    drift = Drift(haze.drift.speed_m_s, heading + haze.drift.toward_deg, time_s)
    patches = None
    if haze.patches is not None:
        p = haze.patches
        seed = stream_seed(spec.render.seed, Stream.HAZE_PATCHES)
        patches = Patches(p.correlation_m, p.anisotropy, p.vertical_m, p.density_ratio, seed)
    bank = None
    if haze.bank is not None:
        b = haze.bank
        start = (0.0, 0.0)  # the camera's starting point: a still camera's, a ship's frame 0
        bank = Bank(b.distance_m, heading + b.bearing_deg, b.edge_m, b.near_ratio, start)
    return HazeField(patches, bank, drift)
