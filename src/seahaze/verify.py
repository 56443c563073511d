"""``seahaze verify``: measure the visibility a rendering mode really produces.

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

Noise: the total ``spp`` is split over independent batches (different seeds). The standard
error of each contrast comes from the between-batch variance of its pixels; the standard error
of the fitted visibility from the fit (weights ``1/se²``) and, model-free, from a jackknife over
the batches.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, get_args

import numpy as np

from . import imaging
from .camera import Camera
from .geometry import MeshData, SceneGeometry, VesselInstance, build_sea
from .spec import RenderSpec, SceneSpec
from .visibility import (
    CONTRAST_THRESHOLD,
    Threshold,
    channel_extinction,
    extinction_coefficient,
    level_name,
    visibility_from_extinction,
)

MODES: tuple[str, ...] = tuple(get_args(RenderSpec.model_fields["mode"].annotation))
"""Rendering modes verify can check: every mode the scene spec allows."""

FOV_DEG = 24.0
"""Horizontal field of view of the calibration camera."""
HORIZON_ROW_FRACTION = 1.0 / 16.0
"""Share of the image rows below the horizon (sea, at least one row); the rest is sky."""
N_TARGETS = 12
"""Targets per level."""
NEAR_FRACTION, FAR_FRACTION = 0.05, 1.5
"""Nearest and farthest target distance, as a fraction of the level's visibility."""
TARGET_WIDTH_DEG = 0.2
"""Angular width of every target at the camera (physically thin: see docs/physics.md)."""
TARGET_TOP_DEG = 0.5
"""Angular height of every target's top above the horizon."""
TARGET_BOTTOM_M = -1.0
"""Targets start below the flat sea surface, so no sky shows under them."""
SIDE_GAP_PX = 1
"""Sky columns skipped between a target's partly covered columns and its side bands."""
COVER_MARGIN_PX = 0.02
"""A pixel counts as fully covered when the target edge is at least this far outside it."""
BOX_OPTICAL_MARGIN = 8.0
"""Optical depth from the farthest target to the side of the haze box (DESIGN.md §4)."""
SKY_MIN_OPTICAL_DEPTH = 5.0
"""Below this optical depth along the sky rays beside the targets, clear sky shows through the
top of the haze layer and the horizon is no longer the haze's own airlight (a note is printed)."""
SE_FLOOR = 1e-9
"""Smallest standard error of a contrast in the fit (noise-free modes such as ``asm``)."""

# Defaults measured on a 2-vCPU machine (docs/physics.md, "Verifying visibility"): 4096 spp give
# a standard error of 0.9 % on V = 1000 m in about two minutes, so 5 % holds the thin targets'
# bias (+1-2 %) plus more than 3 standard errors.
DEFAULT_VISIBILITY_M = 1000.0
DEFAULT_RESOLUTION = (512, 13)
DEFAULT_SPP = 4096
DEFAULT_BATCHES = 16
DEFAULT_TOLERANCE = 0.05


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
    data = base.model_dump(mode="json", by_alias=True)
    data["name"] = "verify"
    data["camera"].update(fov_deg=FOV_DEG, pitch_deg=pitch, resolution=[width, height])
    data["sea"].update(model="flat", quality="low")
    data["vessels"] = {}
    render = data["render"]
    for key, value in (("spp", spp), ("seed", seed), ("mode", mode), ("variant", variant)):
        if value is not None:
            render[key] = value
    render["write_exr"] = False
    try:
        return SceneSpec.model_validate(data)
    except ValueError as err:
        first = err.errors()[0] if hasattr(err, "errors") else None
        where = ".".join(str(p) for p in first["loc"]) if first else ""
        raise VerifyInputError(f"{where}: {first['msg'] if first else err}") from None


def sky_optical_depth(spec: SceneSpec, visibility_m: float) -> float:
    """Optical depth of the haze along the highest sky ray beside the targets (elevation
    :data:`TARGET_TOP_DEG`) from the camera to the top of the layer."""
    sigma = extinction_coefficient(visibility_m, spec.haze.threshold)
    rise = spec.haze.top_m - spec.camera.height_m
    return sigma * rise / math.sin(math.radians(TARGET_TOP_DEG))


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


def box_visibility(visibility_m: float, farthest_m: float, threshold: str) -> float:
    """The visibility that makes the haze box wide enough for targets out to ``farthest_m``.

    :func:`seahaze.render.mitsuba_scene.build_scene` sizes the box to ``8 / sigma`` of the
    thinnest level; the targets need ``farthest_m + 8 / sigma`` so that the light field around
    the farthest one is that of an unbounded layer too.
    """
    sigma = extinction_coefficient(visibility_m, threshold)
    half_width = farthest_m + BOX_OPTICAL_MARGIN / sigma
    return visibility_from_extinction(BOX_OPTICAL_MARGIN / half_width, threshold)


# --- measurement ----------------------------------------------------------------------------


@dataclass
class Contrasts:
    """Measured contrasts of the targets of one level."""

    contrast: np.ndarray
    """(N,) ``(L_target - L_sky) / L_sky``."""
    stderr: np.ndarray
    """(N,) standard error of each contrast, from the between-batch pixel variance."""
    target_luminance: np.ndarray
    sky_luminance: np.ndarray
    target_pixels: np.ndarray
    sky_pixels: np.ndarray


def target_pixels(target: Target) -> tuple[slice, slice]:
    """``(rows, columns)`` slices of the target's measured pixels."""
    return slice(*target.rows), slice(*target.columns)


def sky_pixels(target: Target) -> tuple[slice, list[int]]:
    """``(rows, columns)`` of the sky measured beside the target (both sides)."""
    columns = [*range(*target.sky_left), *range(*target.sky_right)]
    return slice(*target.rows), columns


def measure_contrasts(luminance: np.ndarray, targets: Sequence[Target]) -> Contrasts:
    """Contrasts from per-batch luminance images ``(B, H, W)`` (B >= 2 independent batches).

    The standard error of a mean over ``N`` pixels and ``B`` batches is
    ``sqrt(mean_pixel(var_batch) / (N B))``: pixels are independent, and pooling the variance
    over the pixels gives ``N (B - 1)`` degrees of freedom. The contrast's error follows to
    first order (target and sky pixels are disjoint, hence independent).
    """
    y = np.asarray(luminance, dtype=np.float64)
    batches = y.shape[0]
    if batches < 2:
        raise VerifyInputError("at least 2 batches are needed to estimate the noise")
    out: dict[str, list[float]] = {k: [] for k in ("c", "se", "lt", "ls", "nt", "ns")}
    for target in targets:
        t_rows, t_cols = target_pixels(target)
        s_rows, s_cols = sky_pixels(target)
        t = y[:, t_rows, t_cols].reshape(batches, -1)
        s = y[:, s_rows][:, :, s_cols].reshape(batches, -1)
        lt, ls = t.mean(), s.mean()
        se_t = math.sqrt(t.var(axis=0, ddof=1).mean() / t.size)
        se_s = math.sqrt(s.var(axis=0, ddof=1).mean() / s.size)
        out["c"].append(lt / ls - 1.0)
        out["se"].append(math.hypot(se_t / ls, lt * se_s / ls**2))
        out["lt"].append(lt)
        out["ls"].append(ls)
        out["nt"].append(t.shape[1])
        out["ns"].append(s.shape[1])
    return Contrasts(
        np.array(out["c"]),
        np.array(out["se"]),
        np.array(out["lt"]),
        np.array(out["ls"]),
        np.array(out["nt"], dtype=int),
        np.array(out["ns"], dtype=int),
    )


@dataclass(frozen=True)
class Fit:
    """Extinction fitted to measured contrasts: ``C = -exp(-sigma d)``."""

    sigma: float
    """Fitted extinction (1/m); ``nan`` when no target stands out of the noise."""
    sigma_se: float
    """Its standard error from the fit (the contrasts' standard errors as weights)."""
    chi2_per_dof: float
    """Reduced chi-square: about 1 when the model fits within the noise."""
    informative: int
    """Targets whose contrast is at least 3 standard errors from zero."""


def fit_extinction(distance_m: np.ndarray, contrast: np.ndarray, stderr: np.ndarray) -> Fit:
    """Weighted least-squares fit of ``ln|C| = -sigma d`` to measured contrasts.

    Solved on ``C`` itself, ``sum(((C + exp(-sigma d)) / se)^2)`` minimal: to first order the
    same as the log fit with weights ``(C / se)^2``, but without the log's noise bias, and targets
    lost in the noise (``C`` near zero or even positive) need no cut: they carry no weight. The
    start value is the weighted log fit over the targets 3 se clear of zero.
    """
    from scipy.optimize import least_squares

    d = np.asarray(distance_m, float)
    c = np.asarray(contrast, float)
    se = np.maximum(np.asarray(stderr, float), SE_FLOOR)
    clear = (c < 0) & (-c >= 3.0 * se)
    informative = int(clear.sum())
    if informative == 0:
        return Fit(math.nan, math.nan, math.nan, 0)
    w = (c[clear] / se[clear]) ** 2
    y = np.log(-c[clear])
    sigma0 = max(-float(np.sum(w * d[clear] * y) / np.sum(w * d[clear] ** 2)), 1e-12)

    # Fitted in x = ln(sigma): positive by construction and well scaled for every visibility.
    def residual(x: np.ndarray) -> np.ndarray:
        return (c + np.exp(-np.exp(x[0]) * d)) / se

    def jacobian(x: np.ndarray) -> np.ndarray:
        sigma = np.exp(x[0])
        return (-sigma * d * np.exp(-sigma * d) / se)[:, None]

    result = least_squares(
        residual, [math.log(sigma0)], jac=jacobian, xtol=1e-14, ftol=1e-14, gtol=1e-14
    )
    sigma = float(np.exp(result.x[0]))
    jac = jacobian(result.x)[:, 0]
    log_se = 1.0 / math.sqrt(float(jac @ jac)) if np.any(jac) else math.inf
    dof = max(len(c) - 1, 1)
    return Fit(sigma, sigma * log_se, float(np.sum(result.fun**2)) / dof, informative)


# --- one level ------------------------------------------------------------------------------


@dataclass
class TargetReport:
    """One target's measured and expected contrast."""

    index: int
    distance_m: float
    """Mean distance along the rays of its measured pixels (m)."""
    fraction_of_v: float
    width_m: float
    top_m: float
    pixels: int
    sky_pixels: int
    contrast: float
    stderr: float
    expected: float
    """Koschmieder's ``-exp(-sigma d)``."""

    @property
    def z(self) -> float:
        """(measured - expected) / standard error."""
        return (self.contrast - self.expected) / self.stderr if self.stderr > 0 else math.nan


@dataclass
class LevelReport:
    """Everything verify measured at one visibility level."""

    name: str
    visibility_m: float
    sigma_per_m: float
    measured_m: float
    stderr_fit_m: float
    stderr_jackknife_m: float
    chi2_per_dof: float
    informative_targets: int
    tolerance: float
    seconds: float
    targets: list[TargetReport] = field(default_factory=list)
    sky_optical_depth: float = math.inf
    """Optical depth of the haze along the highest measured sky ray, up to the layer top."""

    @property
    def error(self) -> float:
        """Relative error of the measured visibility."""
        return self.measured_m / self.visibility_m - 1.0

    @property
    def stderr_m(self) -> float:
        """The larger of the fit's and the jackknife's standard error (m)."""
        values = [s for s in (self.stderr_fit_m, self.stderr_jackknife_m) if math.isfinite(s)]
        return max(values) if values else math.nan

    @property
    def passed(self) -> bool:
        """Whether the measured visibility is within the tolerance of the label."""
        return math.isfinite(self.measured_m) and abs(self.error) <= self.tolerance

    def to_json(self) -> dict[str, Any]:
        """The level as plain JSON data."""
        data = asdict(self)
        data.update(
            error=self.error,
            stderr_m=self.stderr_m,
            passed=self.passed,
            targets=[{**asdict(t), "z": t.z} for t in self.targets],
        )
        return _finite(data)


@dataclass
class LevelMeasurement:
    """The raw material of a level: targets, distances and per-batch luminance."""

    targets: list[Target]
    distance_m: np.ndarray
    luminance: np.ndarray
    """(B, H, W) per-batch luminance."""
    radiance: np.ndarray
    """(H, W, 3) mean linear radiance over the batches (for the strip image)."""


def _batch_seed(seed: int, level_index: int, batch: int) -> int:
    seq = np.random.SeedSequence([seed, 0x7E51F, level_index, batch])
    return int(seq.generate_state(1, dtype=np.uint32)[0] & 0x7FFFFFFF)


def render_level_batches(
    spec: SceneSpec,
    sea: tuple[MeshData, float, Any],
    visibility_m: float,
    level_index: int,
    batches: int,
    width_deg: float = TARGET_WIDTH_DEG,
) -> LevelMeasurement:
    """Render the calibration scene of one level ``batches`` times with independent seeds."""
    from .render import passes
    from .render.mitsuba_scene import build_scene

    camera = Camera.from_spec(spec.camera)
    haze = spec.haze
    targets = layout_targets(camera, visibility_m, width_deg=width_deg)
    mesh, roughness, surface = sea
    geometry = SceneGeometry(mesh, roughness, surface, [t.instance() for t in targets])
    farthest = max(t.distance_m for t in targets) + max(t.width_m for t in targets)
    box_v = box_visibility(visibility_m, farthest, haze.threshold)
    # The physical mode computes the haze itself: its scene has no Mitsuba medium.
    loaded = build_scene(
        spec,
        camera,
        geometry,
        [visibility_m, box_v],
        black_vessels=True,
        haze_box=spec.render.mode != "physical",
    )
    geo = passes.render_geometry(loaded)
    distances = _check_target_pixels(geo, targets)
    sigma = channel_extinction(visibility_m, haze.threshold, haze.extinction_spectrum)
    spp = max(1, spec.render.spp // batches)
    clean = passes.render_clean(loaded, spp, spec.render.seed, haze.albedo, haze.g)
    lum, total = [], np.zeros((camera.height, camera.width, 3))
    for b in range(batches):
        render = spec.render.model_copy(
            update={"spp": spp, "seed": _batch_seed(spec.render.seed, level_index, b)}
        )
        level = passes.render_level(
            spec.render.mode, loaded, geo, clean, sigma, haze, render, level_index
        )
        lum.append(imaging.luminance(level.radiance))
        total += level.radiance
    return LevelMeasurement(targets, distances, np.stack(lum), (total / batches).astype(np.float32))


def _check_target_pixels(geo: Any, targets: Sequence[Target]) -> np.ndarray:
    """Mean ray distance (m) to each target over its measured pixels; raises RuntimeError if a
    measured pixel's centre ray does not hit its target, or a sky pixel is not sky."""
    distances = []
    for t in targets:
        rows, cols = target_pixels(t)
        s_rows, s_cols = sky_pixels(t)
        if not np.all(geo.instance[rows, cols] == t.index):
            raise RuntimeError(f"target {t.index}: measured pixels miss the target")
        if not np.all(np.isinf(geo.distance_m[s_rows][:, s_cols])):
            raise RuntimeError(f"target {t.index}: the sky beside it is not clear sky")
        distances.append(float(np.mean(geo.distance_m[rows, cols], dtype=np.float64)))
    return np.array(distances)


def analyse_level(
    name: str,
    visibility_m: float,
    threshold: str,
    measurement: LevelMeasurement,
    tolerance: float,
    seconds: float = 0.0,
    sky_optical_depth: float = math.inf,
) -> LevelReport:
    """Contrasts, fit and jackknife of one level's batches."""
    sigma = extinction_coefficient(visibility_m, threshold)
    d = measurement.distance_m
    stats = measure_contrasts(measurement.luminance, measurement.targets)
    fit = fit_extinction(d, stats.contrast, stats.stderr)
    measured = _visibility(fit.sigma, threshold)
    stderr_fit = measured * fit.sigma_se / fit.sigma if math.isfinite(measured) else math.nan
    jack = jackknife_visibility(measurement.luminance, measurement.targets, d, threshold)
    targets = [
        TargetReport(
            t.index,
            float(d[i]),
            float(d[i] / visibility_m),
            t.width_m,
            t.top_m,
            int(stats.target_pixels[i]),
            int(stats.sky_pixels[i]),
            float(stats.contrast[i]),
            float(stats.stderr[i]),
            float(-math.exp(-sigma * d[i])),
        )
        for i, t in enumerate(measurement.targets)
    ]
    return LevelReport(
        name,
        visibility_m,
        sigma,
        measured,
        stderr_fit,
        jack,
        fit.chi2_per_dof,
        fit.informative,
        tolerance,
        seconds,
        targets,
        sky_optical_depth,
    )


def _visibility(sigma: float, threshold: str) -> float:
    return visibility_from_extinction(sigma, threshold) if math.isfinite(sigma) else math.nan


def jackknife_visibility(
    luminance: np.ndarray, targets: Sequence[Target], distance_m: np.ndarray, threshold: str
) -> float:
    """Jackknife standard error (m) of the fitted visibility over the batches (needs >= 3)."""
    batches = luminance.shape[0]
    if batches < 3:
        return math.nan
    values = []
    for b in range(batches):
        keep = np.delete(luminance, b, axis=0)
        stats = measure_contrasts(keep, targets)
        values.append(
            _visibility(fit_extinction(distance_m, stats.contrast, stats.stderr).sigma, threshold)
        )
    v = np.array(values)
    if not np.all(np.isfinite(v)):
        return math.nan
    return float(math.sqrt((batches - 1) / batches * np.sum((v - v.mean()) ** 2)))


# --- the whole run --------------------------------------------------------------------------


@dataclass
class VerifyReport:
    """A verify run: settings and one report per level."""

    config: dict[str, Any]
    levels: list[LevelReport]
    seconds: float

    @property
    def passed(self) -> bool:
        """Whether every level passed."""
        return all(level.passed for level in self.levels)


def run_verify(
    base: SceneSpec,
    visibilities_m: Sequence[float],
    *,
    mode: str = "reference",
    spp: int = DEFAULT_SPP,
    resolution: tuple[int, int] = DEFAULT_RESOLUTION,
    batches: int = DEFAULT_BATCHES,
    tolerance: float = DEFAULT_TOLERANCE,
    seed: int | None = None,
    variant: str | None = None,
    target_width_deg: float = TARGET_WIDTH_DEG,
    progress: Callable[[str], None] = lambda _msg: None,
    keep: dict[str, LevelMeasurement] | None = None,
) -> VerifyReport:
    """Render and measure the calibration scene at every visibility; see the module docstring.

    Raises :class:`VerifyInputError` for settings that cannot work. ``keep``, when given,
    receives each level's raw measurement by level name (for images and tests).
    """
    from .render.variant import select_variant

    if mode not in MODES:
        raise VerifyInputError(f"--mode {mode!r}: allowed {', '.join(MODES)}")
    if batches < 2:
        raise VerifyInputError(f"--batches {batches}: at least 2 are needed to measure noise")
    if spp < batches:
        raise VerifyInputError(f"--spp {spp}: must be >= --batches ({batches})")
    if not 0.0 < tolerance < 1.0:
        raise VerifyInputError(f"--tolerance {tolerance:g}: must be within (0, 1)")
    if not visibilities_m:
        raise VerifyInputError("no visibility level to verify")
    if base.camera.height_m >= base.haze.top_m:
        raise VerifyInputError(
            f"camera.height_m {base.camera.height_m:g} is not below haze.top_m "
            f"{base.haze.top_m:g}: the targets must be seen from inside the haze layer"
        )
    spec = calibration_spec(base, resolution, spp=spp, seed=seed, mode=mode, variant=variant)
    camera = Camera.from_spec(spec.camera)
    if not 0.0 < target_width_deg <= 0.5 * FOV_DEG / N_TARGETS:
        raise VerifyInputError(
            f"--target-width {target_width_deg:g}: must be within (0, {FOV_DEG / N_TARGETS / 2:g}]°"
        )
    for v in visibilities_m:
        layout_targets(
            camera, v, width_deg=target_width_deg
        )  # fail on a too coarse resolution before any rendering
    start = time.perf_counter()
    used_variant = select_variant(spec.render.variant)
    sea = build_sea(spec, camera)
    threshold = spec.haze.threshold
    levels = []
    for i, v in enumerate(visibilities_m):
        t0 = time.perf_counter()
        name = level_name(v)
        measurement = render_level_batches(spec, sea, v, i, batches, target_width_deg)
        tau = sky_optical_depth(spec, v)
        seconds = time.perf_counter() - t0
        report = analyse_level(name, v, threshold, measurement, tolerance, seconds, tau)
        if keep is not None:
            keep[name] = measurement
        levels.append(report)
        progress(
            f"{name}: V measured {report.measured_m:.0f} m ({report.error:+.1%}) "
            f"in {report.seconds:.1f} s"
        )
    targets = layout_targets(camera, visibilities_m[0], width_deg=target_width_deg)
    config = {
        "mode": mode,
        "variant": used_variant,
        "spp": spec.render.spp,
        "batches": batches,
        "spp_per_batch": spec.render.spp // batches,
        "resolution": list(resolution),
        "seed": spec.render.seed,
        "tolerance": tolerance,
        "threshold": str(threshold),
        "contrast_threshold": CONTRAST_THRESHOLD[Threshold(threshold)],
        "camera": spec.camera.model_dump(mode="json"),
        "sun": spec.sun.model_dump(mode="json"),
        "sky": spec.sky.model_dump(mode="json"),
        "haze": spec.haze.model_dump(mode="json", exclude={"levels"}),
        "sea": {"model": "flat", "roughness": sea[1]},
        "targets": {
            "count": len(targets),
            "fractions_of_v": target_fractions(len(targets)).tolist(),
            "width_deg": target_width_deg,
            "top_above_horizon_deg": TARGET_TOP_DEG,
            "pixels_each": [
                (t.rows[1] - t.rows[0]) * (t.columns[1] - t.columns[0]) for t in targets
            ],
        },
    }
    return VerifyReport(config, levels, time.perf_counter() - start)


# --- output ---------------------------------------------------------------------------------


def _finite(data: Any) -> Any:
    """JSON has no NaN or infinity: they become null."""
    if isinstance(data, float):
        return data if math.isfinite(data) else None
    if isinstance(data, dict):
        return {k: _finite(v) for k, v in data.items()}
    if isinstance(data, list | tuple):
        return [_finite(v) for v in data]
    return data


def format_report(report: VerifyReport) -> str:
    """The report as a plain-text table: per level the targets, then a summary."""
    cfg = report.config
    lines = [
        f"seahaze verify: mode {cfg['mode']}, {cfg['resolution'][0]}x{cfg['resolution'][1]}, "
        f"{cfg['batches']} batches x {cfg['spp_per_batch']} spp, {cfg['variant']}, "
        f"threshold {cfg['threshold']} ({cfg['contrast_threshold']:g})"
    ]
    for level in report.levels:
        lines += [
            "",
            f"{level.name}: V = {level.visibility_m:g} m, sigma = {level.sigma_per_m:.4e} /m",
            f"  {'target':>6} {'d (m)':>8} {'d/V':>5} {'px':>4} {'C measured':>19} "
            f"{'C expected':>10} {'z':>6}",
        ]
        for t in level.targets:
            lines.append(
                f"  {t.index:>6} {t.distance_m:>8.1f} {t.fraction_of_v:>5.2f} {t.pixels:>4} "
                f"{t.contrast:>9.4f} ± {t.stderr:<7.4f} {t.expected:>10.4f} {t.z:>6.1f}"
            )
        lines.append(
            f"  V measured {level.measured_m:.1f} m ± {level.stderr_fit_m:.1f} (fit) "
            f"± {level.stderr_jackknife_m:.1f} (jackknife); error {level.error:+.2%}, "
            f"chi2/dof {level.chi2_per_dof:.2f}, {level.informative_targets} targets > 3 se"
        )
    lines += [
        "",
        f"{'level':<7} {'V label':>8} {'V measured':>11} {'± se':>7} {'error':>8} "
        f"{'± se':>7} {'tol':>6}  result",
    ]
    for level in report.levels:
        rel_se = level.stderr_m / level.visibility_m
        lines.append(
            f"{level.name:<7} {level.visibility_m:>8g} {level.measured_m:>11.1f} "
            f"{level.stderr_m:>7.1f} {level.error:>+8.2%} {rel_se:>7.2%} "
            f"{level.tolerance:>6.1%}  {'PASS' if level.passed else 'FAIL'}"
        )
        if level.sky_optical_depth < SKY_MIN_OPTICAL_DEPTH:
            lines.append(
                f"  note: the sky beside the targets is only {level.sky_optical_depth:.1f} optical "
                "depths deep in the haze layer: clear sky shows through its top, so Koschmieder's "
                "horizon (the haze's own airlight) is not there to measure against"
            )
        if math.isfinite(rel_se) and 3.0 * rel_se > level.tolerance:
            lines.append(
                f"  note: 3 standard errors ({3 * rel_se:.1%}) exceed the tolerance: the noise "
                "decides this result; raise --spp"
            )
    lines.append(
        f"{'PASS' if report.passed else 'FAIL'}: {sum(lv.passed for lv in report.levels)}/"
        f"{len(report.levels)} levels within tolerance, {report.seconds:.1f} s"
    )
    return "\n".join(lines)


def write_outputs(
    report: VerifyReport, out: Path, measurements: dict[str, LevelMeasurement] | None = None
) -> list[Path]:
    """Write ``report.json``, ``contrast.png`` (plot) and, given the measurements,
    ``strips.png`` (the rendered calibration views) into ``out``; returns the paths."""
    out.mkdir(parents=True, exist_ok=True)
    written = [out / "report.json", out / "contrast.png"]
    data = {
        "config": report.config,
        "passed": report.passed,
        "seconds": report.seconds,
        "levels": [level.to_json() for level in report.levels],
    }
    with imaging.atomic_target(written[0]) as tmp:
        tmp.write_text(json.dumps(_finite(data), indent=2) + "\n")
    plot_contrasts(report, written[1])
    if measurements:
        written.append(out / "strips.png")
        write_strips(measurements, written[2])
    return written


def plot_contrasts(report: VerifyReport, path: Path) -> None:
    """Measured ``|C|`` against distance per level, with Koschmieder's and the fitted curve."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = len(report.levels)
    cols = min(n, 3)
    rows = math.ceil(n / cols)
    fig, axes = plt.subplots(
        rows, cols, figsize=(5.0 * cols, 3.8 * rows), squeeze=False, layout="constrained"
    )
    eps = report.config["contrast_threshold"]
    for ax, level in zip(axes.flat, report.levels, strict=False):
        d = np.array([t.distance_m for t in level.targets])
        c = -np.array([t.contrast for t in level.targets])
        se = np.array([t.stderr for t in level.targets])
        x = np.linspace(0.0, 1.6 * level.visibility_m, 200)
        ax.plot(x, np.exp(-level.sigma_per_m * x), "k-", lw=1, label="exp(-σd), label V")
        if math.isfinite(level.measured_m):
            sigma_fit = -math.log(eps) / level.measured_m
            ax.plot(x, np.exp(-sigma_fit * x), "C1--", lw=1, label="fit")
        ok = c > se
        ax.errorbar(d[ok], c[ok], yerr=se[ok], fmt="o", ms=4, color="C0", label="measured |C|")
        if np.any(~ok):
            ax.plot(
                d[~ok],
                np.maximum(c[~ok], 0) + 2 * se[~ok],
                "v",
                color="C0",
                alpha=0.5,
                label="< noise (2 se)",
            )
        ax.axhline(eps, color="0.6", lw=0.8, ls=":")
        ax.axvline(level.visibility_m, color="0.6", lw=0.8, ls=":")
        ax.set_yscale("log")
        ax.set_ylim(max(1e-4, 0.2 * eps * math.exp(-0.5 * 3.9)), 1.5)
        ax.set_xlabel("distance d (m)")
        ax.set_ylabel("|C|")
        verdict = "PASS" if level.passed else "FAIL"
        ax.set_title(
            f"{level.name}: V {level.measured_m:.0f} ± {level.stderr_m:.0f} m "
            f"({level.error:+.1%}) {verdict}",
            fontsize=10,
        )
        ax.legend(fontsize=7, loc="lower left")
        ax.grid(alpha=0.3, which="both")
    for ax in list(axes.flat)[n:]:
        ax.axis("off")
    cfg = report.config
    fig.suptitle(
        f"seahaze verify ({cfg['mode']}, {cfg['spp']} spp, {cfg['resolution'][0]}x"
        f"{cfg['resolution'][1]})",
        fontsize=11,
    )
    with imaging.atomic_target(path) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)


def write_strips(measurements: dict[str, LevelMeasurement], path: Path, scale: int = 3) -> None:
    """The mean rendered view of every level, stacked top to bottom, exposed so that the sky
    beside the targets maps to :data:`seahaze.imaging.AUTO_KEY`."""
    images = []
    for m in measurements.values():
        rows, cols = sky_pixels(m.targets[len(m.targets) // 2])
        sky = float(np.mean(imaging.luminance(m.radiance[rows][:, cols])))
        exposure = imaging.AUTO_KEY / sky if sky > 0 else 1.0
        image = imaging.to_srgb8(m.radiance, exposure)
        image = np.repeat(np.repeat(image, scale, axis=0), scale, axis=1)
        images += [image, np.full((4, image.shape[1], 3), 255, np.uint8)]
    imaging.write_png(path, np.concatenate(images[:-1], axis=0))
