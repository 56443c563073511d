"""Motion blur of a global shutter: a sequence frame integrated over its exposure.

A camera's frame is not an instant: its sensor integrates the light for the exposure time
``T``. With a global shutter (every pixel exposed over the same ``[t − T/2, t + T/2]``, no
rolling shutter's skew) a point of the scene that moves across the image draws a streak along
its path. Over a short exposure that path is straight, so a frame is the average of the
instant's image shifted along each point's *image displacement* ``Δx = x(t + T/2) − x(t − T/2)``
(pixels): the motion blur of rendering's post-process filters (Potmesil & Chakravarty 1983,
"Modeling motion blur in computer-generated images", *SIGGRAPH* 17(3), 389–399; McGuire et al.
2012, "A reconstruction filter for plausible motion blur", *I3D*, 135–142).

What moves
    * The camera on its platform (:func:`seahaze.world.frame_camera`): a ship's mast sails,
      heaves, pitches and rolls; a shore mast is still. Its rotation moves every distant point
      of the image alike — the blur a hand-held or ship-borne camera shows.
    * Each vessel on its course (:func:`seahaze.world.frame_layout`): translated and turned as
      a rigid body (its heave and pitch on the waves during ``T`` ignored).
    * The sea and the sky are held still in the world: the waves' own motion moves the
      surface by their orbital speed (under 1 m/s at Beaufort 6) and a still camera shows it
      as a fraction of a pixel beyond a few metres.

    Each pixel's displacement is that of the point its centre ray meets (the geometry pass):
    the point is placed at ``t`` and projected through the cameras at ``t ∓ T/2``, a vessel's
    point moved with its vessel, the sky's a direction at infinity.

The filter (a *gather*)
    Each pixel averages the instant's image at :func:`taps` evenly spaced points of its own
    displacement segment, read bilinearly (edges clamped):
    ``I_T(x) = (1/N) Σ_i I(x + Δx(x)·((i + ½)/N − ½))``. This is exact where neighbouring points
    move alike — the camera's rotation, the inside of a vessel, the still sea — and conserves
    light there. At a moving vessel's silhouette it is the usual approximation of a gather: a
    vessel pixel at its edge takes in the background it passes over, but the background does
    not take in the vessel's streak (the streak is drawn inside the silhouette only), and what
    the vessel uncovers during ``T`` is read from the instant's neighbours. A vessel's own
    streak is short (10 m/s at 500 m across a 60° view of 1280 pixels: 0.4 px in 1/60 s); the
    platform's rotation is what blurs (a 5°/s roll: 1.8 px in 1/60 s).

Applied to the PNGs with the rest of the camera model (:mod:`seahaze.camera_model`, before the
lens's blur: the light moves before it passes the lens); the EXRs stay the instant's linear
radiance, and the boxes the instant's (the exposure is centred on the frame's time).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy.ndimage import map_coordinates

from .camera import Camera

MAX_TAPS = 64
"""Most points a pixel averages along its displacement: a streak of more than 64 px is drawn
with gaps of its length over 64 (such a frame is unusable anyway)."""
STILL_PX = 1e-3
"""A pixel whose point moves less than this (pixels) during the exposure keeps its value: its
average would differ by less than a thousandth of its neighbours' difference."""
SKY_DISTANCE_M = 1.0e9
"""Where a ray that meets no surface is placed to project it (m): at infinity for any
platform's motion."""


def taps(displacement_px: np.ndarray) -> int:
    """How many points every pixel averages: two per pixel of the longest displacement (so the
    bilinear reads overlap and a streak has no gaps), at least 1, at most :data:`MAX_TAPS`."""
    longest = float(np.max(np.hypot(displacement_px[..., 0], displacement_px[..., 1]), initial=0))
    return int(min(MAX_TAPS, max(1, math.ceil(2.0 * longest))))


def blur_along_motion(linear: np.ndarray, displacement_px: np.ndarray) -> np.ndarray:
    """``linear`` (H, W, C) averaged over each pixel's displacement ``displacement_px``
    (H, W, 2: along the columns and the rows, pixels) as a global shutter integrates it
    (module docstring, "The filter"); float64."""
    image = np.asarray(linear, np.float64)
    out = image.copy()
    n = taps(displacement_px)
    # Only the pixels that move are averaged (a shore camera's frame: its vessels).
    moving = np.hypot(displacement_px[..., 0], displacement_px[..., 1]) >= STILL_PX
    if n == 1 or not moving.any():
        return out
    rows, cols = np.nonzero(moving)
    dx, dy = displacement_px[rows, cols, 0], displacement_px[rows, cols, 1]
    total = np.zeros((len(rows), image.shape[2]))
    for i in range(n):
        along = (i + 0.5) / n - 0.5
        at = [rows + along * dy, cols + along * dx]
        for c in range(image.shape[2]):
            # Linear interpolation, coordinates beyond the frame clamped to its edge pixels.
            total[:, c] += map_coordinates(image[..., c], at, order=1, mode="nearest")
    out[rows, cols] = total / n
    return out


def image_displacement(
    geometry: Any,
    cameras: tuple[Camera, Camera],
    vessel_motion: dict[int, tuple[np.ndarray, np.ndarray]] | None = None,
) -> np.ndarray:
    """(H, W, 2) float64: each pixel's displacement (columns, rows; pixels) from the shutter's
    opening to its closing, for the points ``geometry`` (a
    :class:`seahaze.render.passes.GeometryPass`: ray directions, distances, vessel indices)
    sees, seen by ``cameras`` (at the opening, at the closing). ``vessel_motion``: per vessel
    index, the rigid motions (4×4 world matrices) that take its points from the frame's
    instant to the opening and to the closing; other points hold still."""
    origin = np.asarray(geometry.origin, np.float64)
    directions = np.asarray(geometry.directions, np.float64)
    distance = np.asarray(geometry.distance_m, np.float64)
    reach = np.where(np.isfinite(distance), distance, SKY_DISTANCE_M)
    points = origin + directions * reach[..., None]
    moved = [points.copy(), points.copy()]
    for index, motions in (vessel_motion or {}).items():
        mask = geometry.instance == index
        for k, matrix in enumerate(motions):
            moved[k][mask] = _apply(matrix, points[mask])
    uv = []
    for camera, world in zip(cameras, moved, strict=True):
        u, v, _ = camera.project(world.reshape(-1, 3))
        uv.append(np.stack([u, v], axis=-1).reshape(*points.shape[:2], 2))
    return uv[1] - uv[0]


def rigid_motion(
    before: tuple[float, float, float], after: tuple[float, float, float]
) -> np.ndarray:
    """The 4×4 world matrix that moves a vessel from pose ``before`` to pose ``after`` (each
    ``(x, y, heading_deg)``: midships position (m) and bow azimuth): turned about the vertical
    through its midships, then translated."""
    turn = math.radians(after[2] - before[2])
    c, s = math.cos(turn), math.sin(turn)
    rotation = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    matrix = np.eye(4)
    matrix[:3, :3] = rotation
    start, end = np.array([before[0], before[1], 0.0]), np.array([after[0], after[1], 0.0])
    matrix[:3, 3] = end - rotation @ start
    return matrix


def _apply(matrix: np.ndarray, points: np.ndarray) -> np.ndarray:
    return points @ matrix[:3, :3].T + matrix[:3, 3]


def shutter_displacement(
    spec: Any, frame: int | None, geometry: Any, camera: Camera, vessels: Sequence[Any]
) -> np.ndarray | None:
    """Each pixel's displacement (:func:`image_displacement`) over the shutter time of the
    scene's camera model (``render.camera_model.shutter_s``) at ``frame`` of its sequence, for
    the points of the frame's ``geometry`` pass, seen at the frame's instant by ``camera``
    among ``vessels`` (:class:`seahaze.world.VesselInstance`: their indices and placements);
    None for an instant (no camera model, a shutter time of 0, or a still: only a sequence
    moves)."""
    from .world import frame_camera, frame_layout

    settings = spec.render.camera_model
    if settings is None or settings.shutter_s <= 0.0 or frame is None or spec.sequence is None:
        return None
    half = 0.5 * settings.shutter_s
    cameras = (frame_camera(spec, frame, -half), frame_camera(spec, frame, half))
    # The layouts as the frame's geometry was built: from the frame's own camera.
    opening, _ = frame_layout(spec, camera, frame, offset_s=-half)
    closing, _ = frame_layout(spec, camera, frame, offset_s=half)
    motions = {
        v.index: (
            rigid_motion(_pose(v.placement), _pose(opening[v.index])),
            rigid_motion(_pose(v.placement), _pose(closing[v.index])),
        )
        for v in vessels
    }
    return image_displacement(geometry, cameras, motions)


def _pose(placement: Any) -> tuple[float, float, float]:
    return placement.x, placement.y, placement.heading_deg


def motion_meta(displacement_px: np.ndarray) -> dict[str, Any]:
    """``meta``'s record of a frame's motion blur: its longest and median displacement
    (pixels) and the points each pixel averaged."""
    length = np.hypot(displacement_px[..., 0], displacement_px[..., 1])
    return {
        "longest_px": float(np.max(length, initial=0.0)),
        "median_px": float(np.median(length)),
        "taps": taps(displacement_px),
    }
