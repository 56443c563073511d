"""The calibration scene of ``seahaze verify``: thin black targets against the horizon sky.

A calibration scene (the sun, sky, haze and camera height of a base scene; a flat sea; no
vessels) gets thin, perfectly black targets standing on the sea at distances from 0.05 V to
1.5 V, one per bearing, each seen against the horizon sky. Per target the apparent contrast

    C = (L_target - L_sky) / L_sky

is measured on luminance, with ``L_target`` the mean over the target's pixels above the
horizon and ``L_sky`` the sky right beside it, left and right, in the same rows (so vertical
and, to first order, horizontal sky gradients cancel). Koschmieder's law predicts
``C = -exp(-sigma d)``. Fitting ``sigma`` to the measured contrasts gives the measured
visibility ``V = -ln(eps) / sigma`` (``eps`` 0.02 Koschmieder, 0.05 MOR), compared with the
label. docs/physics.md ("Verifying visibility") explains the choices and the target-size effect.

Geometry of the calibration view (angles, so that ``--resolution`` only samples it):

* A camera at the base scene's height and heading, :data:`FOV_DEG` wide, pitched up so that the
  horizon falls on a pixel-row boundary near the bottom of the frame: every row above it is
  sky, the few below are sea. A wide, short frame (default 512×13) renders only what is
  measured.
* :data:`N_TARGETS` square black pillars (diffuse reflectance 0) at log-spaced distances, each
  :data:`TARGET_WIDTH_DEG` wide and reaching :data:`TARGET_TOP_DEG` above the horizon, in equal
  slots across the frame.
* Only pixels whose whole footprint lies on the target (or on the sky beside it) are measured:
  the box pixel filter would otherwise mix target and sky at the edges.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..camera import Camera
from ..scene_medium import haze_medium
from ..spec import OverrideError, SceneSpec, VesselsSpec, with_changes
from ..visibility import extinction_coefficient
from ..world import MeshData, VesselInstance
from .defaults import DEFAULT_RESOLUTION, TARGET_WIDTH_DEG

FOV_DEG = 24.0
"""Horizontal field of view of the calibration camera."""
HORIZON_ROW_FRACTION = 1.0 / 16.0
"""Share of the image rows below the horizon (sea, at least one row); the rest is sky."""
N_TARGETS = 12
"""Targets per level."""
NEAR_FRACTION, FAR_FRACTION = 0.05, 1.5
"""Nearest and farthest target distance, as a fraction of the level's visibility."""
TARGET_TOP_DEG = 0.5
"""Angular height of every target's top above the horizon."""
TARGET_BOTTOM_M = -1.0
"""Targets start below the flat sea surface, so no sky shows under them."""
SIDE_GAP_PX = 1
"""Sky columns skipped between a target's partly covered columns and its side bands."""
COVER_MARGIN_PX = 0.02
"""A pixel counts as fully covered when the target edge is at least this far outside it."""
SKY_MIN_OPTICAL_DEPTH = 5.0
"""Below this optical depth along the sky rays beside the targets, clear sky shows through the
top of the haze layer and the horizon is no longer the haze's own airlight (a note is printed)."""


class VerifyInputError(ValueError):
    """Bad verify settings (resolution too coarse, too few batches...); one line for the user."""


@dataclass(frozen=True)
class Target:
    """One black pillar of the calibration scene and the pixels it is measured on."""

    index: int
    distance_m: float
    """Horizontal distance from the camera to the centre of the target's front face (m)."""
    azimuth_deg: float
    """Direction from the camera, counter-clockwise from +x."""
    width_m: float
    """Width and depth of the square pillar (m)."""
    top_m: float
    """Height of the pillar's top above sea level (m)."""
    rows: tuple[int, int]
    """Image rows ``[r0, r1)`` fully on the target and above the horizon."""
    columns: tuple[int, int]
    """Image columns ``[c0, c1)`` fully on the target."""
    sky_left: tuple[int, int]
    """Sky columns ``[c0, c1)`` left of the target, same rows."""
    sky_right: tuple[int, int]
    """Sky columns ``[c0, c1)`` right of the target, same rows."""

    def mesh(self) -> MeshData:
        """The pillar as a closed box mesh in world coordinates."""
        a = math.radians(self.azimuth_deg)
        along = np.array([math.cos(a), math.sin(a)])
        across = np.array([-math.sin(a), math.cos(a)])
        centre = along * (self.distance_m + 0.5 * self.width_m)
        half = 0.5 * self.width_m
        corners_xy = [centre + sa * half * along + sc * half * across for sa, sc in _SQUARE]
        vertices = np.array(
            [[x, y, z] for z in (TARGET_BOTTOM_M, self.top_m) for x, y in corners_xy],
            dtype=np.float32,
        )
        return MeshData(f"vessel{self.index:03d}_target", vertices, _BOX_FACES.copy(), (0, 0, 0))

    def instance(self) -> VesselInstance:
        """The target as a vessel instance, so the render passes treat it like any vessel."""
        height = self.top_m - TARGET_BOTTOM_M
        return VesselInstance(
            self.index, "target", -1, None, self.width_m, self.width_m, height, 0.0, [self.mesh()]
        )


_SQUARE = ((-1, -1), (1, -1), (1, 1), (-1, 1))
# Bottom square 0-3, top square 4-7, counter-clockwise from above; faces wind outward.
_BOX_FACES = np.array(
    [
        [0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7],
        [0, 1, 5], [0, 5, 4], [1, 2, 6], [1, 6, 5],
        [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7],
    ],
    dtype=np.uint32,
)  # fmt: skip


def calibration_spec(
    base: SceneSpec,
    resolution: tuple[int, int] = DEFAULT_RESOLUTION,
    *,
    spp: int | None = None,
    seed: int | None = None,
    mode: str | None = None,
    variant: str | None = None,
) -> SceneSpec:
    """The calibration scene of ``base``: its sun, sky, haze and camera height and heading; a
    flat sea (its optics kept); no vessels; the verify camera (see the module docstring)."""
    width, height = resolution
    horizon_row = height - _rows_below(height)
    tan_half_y = math.tan(math.radians(FOV_DEG) / 2.0) * height / width
    # The horizon (elevation 0) images to the row boundary v with
    # tan(pitch) = (2 v / H - 1) tan(half vertical fov), the same for every column.
    pitch = math.degrees(math.atan((2.0 * horizon_row / height - 1.0) * tan_half_y))
    render = {"spp": spp, "seed": seed, "mode": mode, "variant": variant}
    changes = {
        "name": "verify",
        "camera": {"fov_deg": FOV_DEG, "pitch_deg": pitch, "resolution": [width, height]},
        "sea": {"model": "flat", "quality": "low"},
        "vessels": VesselsSpec().model_dump(mode="json", by_alias=True),
        "render": {**{k: v for k, v in render.items() if v is not None}, "write_exr": False},
    }
    try:
        return with_changes(base, changes)
    except OverrideError as err:
        raise VerifyInputError(str(err)) from None


def sky_optical_depth(spec: SceneSpec, visibility_m: float) -> float:
    """Optical depth of the haze along the highest sky ray beside the targets (elevation
    :data:`TARGET_TOP_DEG`) from the camera out of the medium (:mod:`seahaze.medium`)."""
    sigma = extinction_coefficient(visibility_m, spec.haze.threshold)
    rise = np.array([math.sin(math.radians(TARGET_TOP_DEG))])
    medium = haze_medium(spec.haze, spec.camera.height_m)
    reduced = medium.path_length(spec.camera.height_m, rise, np.array([np.inf]))
    return sigma * float(reduced[0])


def horizon_row(camera: Camera) -> float:
    """Image row coordinate ``v`` of the horizon (elevation 0) for a camera without roll."""
    tan_pitch = math.tan(math.radians(camera.pitch_deg))
    return 0.5 * camera.height * (1.0 + tan_pitch / camera.tan_half_fov_y)


def target_fractions(n: int = N_TARGETS) -> np.ndarray:
    """Target distances as fractions of the visibility: log-spaced from 0.05 to 1.5."""
    return np.geomspace(NEAR_FRACTION, FAR_FRACTION, n)


def layout_targets(
    camera: Camera,
    visibility_m: float,
    n: int = N_TARGETS,
    width_deg: float = TARGET_WIDTH_DEG,
) -> list[Target]:
    """Targets at ``target_fractions(n) * visibility_m``, near to far from left to right.

    Each sits in its own slot of ``W / n`` columns; the pixels it is measured on are found by
    projecting its front face. Raises :class:`VerifyInputError` when the resolution is too
    coarse to give every target at least one fully covered pixel and sky on both sides.
    """
    v_h = horizon_row(camera)
    slot = camera.width / n
    targets = []
    for i, fraction in enumerate(target_fractions(n)):
        distance = float(fraction * visibility_m)
        # Centred on a pixel centre, a target 2 px wide always covers one column fully.
        u_centre = math.floor((i + 0.5) * slot) + 0.5
        # The ray through the slot centre on the horizon row is horizontal: its azimuth is the
        # target's bearing.
        d = camera.ray_directions(np.array(u_centre), np.array(v_h))
        azimuth = math.degrees(math.atan2(d[1], d[0]))
        width = 2.0 * distance * math.tan(math.radians(width_deg) / 2.0)
        top = camera.height_m + distance * math.tan(math.radians(TARGET_TOP_DEG))
        probe = Target(i, distance, azimuth, width, top, (0, 0), (0, 0), (0, 0), (0, 0))
        rows, columns, touched = _covered_pixels(camera, probe, v_h)
        slot_start, slot_end = math.ceil(i * slot), math.floor((i + 1) * slot)
        half_free = min(slot_end - touched[1] - SIDE_GAP_PX, touched[0] - SIDE_GAP_PX - slot_start)
        if rows[1] <= rows[0] or columns[1] <= columns[0] or half_free < 1:
            min_width, min_height = min_resolution(camera.width, width_deg)
            raise VerifyInputError(
                f"resolution {camera.width}x{camera.height} is too coarse for the calibration "
                f"targets ({n} across {FOV_DEG:g}°, each {width_deg:g}° wide and "
                f"{TARGET_TOP_DEG:g}° tall): use at least {min_width} columns and, at "
                f"{max(camera.width, min_width)} columns, {min_height} rows"
            )
        left = (touched[0] - SIDE_GAP_PX - half_free, touched[0] - SIDE_GAP_PX)
        right = (touched[1] + SIDE_GAP_PX, touched[1] + SIDE_GAP_PX + half_free)
        targets.append(Target(i, distance, azimuth, width, top, rows, columns, left, right))
    return targets


def min_resolution(width: int, width_deg: float = TARGET_WIDTH_DEG) -> tuple[int, int]:
    """The smallest resolution that shows every target: the width that puts 2 px across a
    target (so one column is fully covered), and at ``width`` (or that minimum) the rows for
    the targets' full height and one row of sky above."""
    min_width = math.ceil(2.0 * FOV_DEG / min(width_deg, TARGET_WIDTH_DEG))
    width = max(width, min_width)
    # The targets' tops plus one row of clear sky above them.
    rows_above = math.ceil(TARGET_TOP_DEG * width / FOV_DEG) + 1
    height = rows_above + 1
    while height - _rows_below(height) < rows_above:
        height += 1
    return min_width, max(height, 8)  # the scene schema allows no fewer than 8 rows


def _rows_below(height: int) -> int:
    return max(1, round(height * HORIZON_ROW_FRACTION))


def _covered_pixels(
    camera: Camera, target: Target, v_h: float
) -> tuple[tuple[int, int], tuple[int, int], tuple[int, int]]:
    """Rows and columns fully covered by the target's front face above the horizon, and the
    columns it touches at all."""
    a = math.radians(target.azimuth_deg)
    along = np.array([math.cos(a), math.sin(a), 0.0])
    across = np.array([-math.sin(a), math.cos(a), 0.0])
    half = 0.5 * target.width_m
    points = np.array(
        [
            along * target.distance_m + side * half * across + np.array([0.0, 0.0, z])
            for side in (1.0, -1.0)  # left edge first (the image's u grows to the right)
            for z in (camera.height_m, target.top_m)
        ]
    )
    u, v, _ = camera.project(points)
    u_left, u_right = max(u[0], u[1]), min(u[2], u[3])
    v_top = max(v[1], v[3])
    m = COVER_MARGIN_PX
    columns = (math.ceil(u_left + m), math.floor(u_right - m))
    # The horizon lies on a row boundary by construction (up to rounding).
    rows = (math.ceil(v_top + m), math.floor(v_h + 1e-6))
    touched = (math.floor(min(u[0], u[1]) - m), math.ceil(max(u[2], u[3]) + m))
    return rows, columns, touched


def target_pixels(target: Target) -> tuple[slice, slice]:
    """``(rows, columns)`` slices of the target's measured pixels."""
    return slice(*target.rows), slice(*target.columns)


def sky_pixels(target: Target) -> tuple[slice, list[int]]:
    """``(rows, columns)`` of the sky measured beside the target (both sides)."""
    columns = [*range(*target.sky_left), *range(*target.sky_right)]
    return slice(*target.rows), columns
