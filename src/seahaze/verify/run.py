"""Running ``seahaze verify``: render the calibration scene per level in batches, measure the
targets' contrasts, fit the visibility and judge it against the label (docs/physics.md,
"Verifying visibility")."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from .. import imaging
from ..camera import Camera
from ..medium import HazeMedium
from ..render.engine import open_session
from ..render.variant import select_variant
from ..seeds import RenderPass, render_seed
from ..spec import RENDER_MODES, SceneSpec, with_overrides
from ..visibility import (
    CONTRAST_THRESHOLD,
    Threshold,
    channel_extinction,
    extinction_coefficient,
    level_name,
)
from ..world import SceneGeometry, Sea, build_sea
from .defaults import (
    DEFAULT_BATCHES,
    DEFAULT_RESOLUTION,
    DEFAULT_SPP,
    DEFAULT_TOLERANCE,
    TARGET_WIDTH_DEG,
)
from .field import (
    calibration_medium,
    coverage,
    optical_depth_ratio,
    target_ray_lengths,
)
from .fit import (
    Contrasts,
    RayLengths,
    fit_extinction,
    jackknife_visibility,
    measure_contrasts,
    visibility_or_nan,
)
from .targets import (
    FOV_DEG,
    N_TARGETS,
    TARGET_TOP_DEG,
    Target,
    VerifyInputError,
    calibration_spec,
    layout_targets,
    sky_optical_depth,
    sky_pixels,
    target_fractions,
    target_pixels,
)

FIELD_SEEN = (
    "the base scene's patches and bank at its first frame, normalised over its own view "
    "(seahaze.verify.field)"
)


def finite_json(data: Any) -> Any:
    """JSON has no NaN or infinity: they become null."""
    if isinstance(data, float):
        return data if math.isfinite(data) else None
    if isinstance(data, dict):
        return {k: finite_json(v) for k, v in data.items()}
    if isinstance(data, list | tuple):
        return [finite_json(v) for v in data]
    return data


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
    """Koschmieder's ``-exp(-σ ℓ)`` of its own rays (the mean over its measured pixels';
    ``-exp(-σ d)`` in a uniform layer)."""
    reduced_m: float = math.nan
    """Mean reduced length ``ℓ = ∫ρ ds`` (m) along the rays of its measured pixels."""
    mean_density: float = math.nan
    """``ℓ / d``: the mean relative density along its rays (> 1 in a dense patch)."""
    tau_measured: float = math.nan
    """``-ln(-C)``: the optical depth its contrast reads (NaN where ``C >= 0``)."""
    tau_expected: float = math.nan
    """``σ ℓ`` (exactly: ``-ln`` of its rays' mean transmittance)."""

    @property
    def z(self) -> float:
        """(measured - expected) / standard error."""
        return (self.contrast - self.expected) / self.stderr if self.stderr > 0 else math.nan

    @property
    def tau_ratio(self) -> float:
        """``tau_measured / tau_expected``: 1 where the target reads its own ray's law."""
        return optical_depth_ratio(self.tau_measured, self.tau_expected)


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
    """Optical depth of the haze along the highest measured sky ray, up to the layer top (in
    haze that varies across the sea: the least over the measured sky rays, to 20 km)."""
    varies_across: bool = False
    """Whether the haze varies across the sea (patches, a bank): the fit is then against
    each target's own reduced length and the coverage below matters."""
    dense_targets: int = 0
    """Targets whose rays' mean density ``ℓ/d`` exceeds :data:`~.field.DENSE_RATIO`."""
    thin_targets: int = 0
    """Targets whose rays' mean density ``ℓ/d`` is below :data:`~.field.THIN_RATIO`."""

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
            targets=[{**asdict(t), "z": t.z, "tau_ratio": t.tau_ratio} for t in self.targets],
        )
        return finite_json(data)


@dataclass
class LevelMeasurement:
    """The raw material of a level: targets, distances and per-batch luminance."""

    targets: list[Target]
    distance_m: np.ndarray
    """Mean distance (m) along each target's measured rays."""
    rays: RayLengths
    """Reduced length (m) in the medium of each target's measured rays: a ray's optical depth
    is ``σ`` times it (:mod:`seahaze.medium`; its distance in a uniform layer)."""
    luminance: np.ndarray
    """(B, H, W) per-batch luminance."""
    radiance: np.ndarray
    """(H, W, 3) mean linear radiance over the batches (for the strip image)."""
    sky_reduced_m: float = math.inf
    """Least reduced length (m) over the measured sky rays (to 20 km)."""
    varies_across: bool = False
    """Whether the medium varies across the sea (:mod:`seahaze.verify.field`)."""

    @property
    def reduced_m(self) -> np.ndarray:
        """(N,) mean reduced length (m) along each target's measured rays."""
        return self.rays.mean_m


def render_level_batches(
    spec: SceneSpec,
    sea: Sea,
    visibility_m: float,
    level_index: int,
    batches: int,
    width_deg: float = TARGET_WIDTH_DEG,
    denoise: bool = False,
    medium: HazeMedium | None = None,
) -> LevelMeasurement:
    """Render the calibration scene of one level ``batches`` times with independent seeds;
    ``denoise``: each batch's radiance through the denoiser, as a dataset's PNGs; ``medium``:
    the haze to render (the base scene's, where it varies across the sea:
    :func:`seahaze.verify.field.calibration_medium`), default the one ``spec`` describes."""
    camera = Camera.from_spec(spec.camera)
    haze = spec.haze
    targets = layout_targets(camera, visibility_m, width_deg=width_deg)
    mesh, roughness, surface = sea.mesh, sea.roughness, sea.surface
    geometry = SceneGeometry(mesh, roughness, surface, [t.instance() for t in targets])
    farthest = max(t.distance_m for t in targets) + max(t.width_m for t in targets)
    # The haze box reaches past the farthest target, so the light around it is an unbounded
    # layer's (the physical mode needs no box).
    level_spec = with_overrides(spec, levels=[visibility_m])
    session = open_session(
        level_spec, geometry, black_vessels=True, reach_m=farthest, medium=medium
    )
    distances = _check_target_pixels(session.pixels, targets)
    # Exact per-pixel reduced lengths (NonUniformHaze.ray_path_length across the sea).
    per_pixel = session.pixels.haze_path_length(session.loaded.medium)
    rays, sky = target_ray_lengths(per_pixel, targets)
    sigma = channel_extinction(visibility_m, haze.threshold, haze.extinction_spectrum)
    spp = max(1, spec.render.spp // batches)
    clean = session.render_clean(spp)
    renderer = session.level_renderer(clean)
    features, exposure = None, 1.0
    if denoise:
        from ..render import denoise as oidn

        seed = render_seed(spec.render.seed, RenderPass.DENOISE_FEATURES, level_index)
        features = oidn.feature_buffers(session.loaded, seed)
        geo = session.pixels
        exposure = imaging.auto_exposure(clean, geo.distance_m, geo.elevation_deg())
    lum, total = [], np.zeros((camera.height, camera.width, 3))
    for b in range(batches):
        seed = render_seed(spec.render.seed, RenderPass.VERIFY, level_index, b)
        render = spec.render.model_copy(update={"spp": spp, "seed": seed})
        radiance = renderer.render(sigma, level_index, render).radiance
        if features is not None:
            radiance = oidn.denoise(radiance, features, exposure)
        lum.append(imaging.luminance(radiance))
        total += radiance
    luminance = np.stack(lum)
    radiance = (total / batches).astype(np.float32)
    return LevelMeasurement(
        targets, distances, rays, luminance, radiance, float(sky.min()), medium is not None
    )


def _check_target_pixels(geo: Any, targets: Sequence[Target]) -> np.ndarray:
    """Mean ray distance (m) to each target over its measured pixels; raises RuntimeError if a
    measured pixel's centre ray does not hit its target, or a sky pixel is not sky."""
    for t in targets:
        rows, cols = target_pixels(t)
        s_rows, s_cols = sky_pixels(t)
        if not np.all(geo.instance[rows, cols] == t.index):
            raise RuntimeError(f"target {t.index}: measured pixels miss the target")
        if not np.all(np.isinf(geo.distance_m[s_rows][:, s_cols])):
            raise RuntimeError(f"target {t.index}: the sky beside it is not clear sky")
    return _mean_over_targets(geo.distance_m, targets)


def _mean_over_targets(values: np.ndarray, targets: Sequence[Target]) -> np.ndarray:
    """The mean of per-pixel ``values`` (H, W) over each target's measured pixels."""
    means = []
    for t in targets:
        rows, cols = target_pixels(t)
        means.append(float(np.mean(values[rows, cols], dtype=np.float64)))
    return np.array(means)


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
    # Koschmieder's law in the medium: a black target's contrast is −exp(−σ ℓ), ℓ the reduced
    # length of its own ray (its distance in a uniform layer), averaged over its pixels' rays.
    rays = measurement.rays
    stats = measure_contrasts(measurement.luminance, measurement.targets)
    fit = fit_extinction(rays, stats.contrast, stats.stderr)
    measured = visibility_or_nan(fit.sigma, threshold)
    stderr_fit = measured * fit.sigma_se / fit.sigma if math.isfinite(measured) else math.nan
    jack = jackknife_visibility(measurement.luminance, measurement.targets, rays, threshold)
    targets = _target_reports(measurement, stats, sigma, visibility_m)
    dense, thin = coverage([t.mean_density for t in targets])
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
        measurement.varies_across,
        dense,
        thin,
    )


def _target_reports(
    measurement: LevelMeasurement, stats: Contrasts, sigma: float, visibility_m: float
) -> list[TargetReport]:
    """Per target its distance, reduced length, measured and expected contrast and optical
    depth at extinction ``sigma`` (1/m)."""
    rays = measurement.rays
    expected_tau = rays.optical_depth(sigma)
    reports = []
    for i, t in enumerate(measurement.targets):
        d, reduced = float(measurement.distance_m[i]), float(rays.mean_m[i])
        c = float(stats.contrast[i])
        reports.append(
            TargetReport(
                t.index,
                d,
                d / visibility_m,
                t.width_m,
                t.top_m,
                int(stats.target_pixels[i]),
                int(stats.sky_pixels[i]),
                c,
                float(stats.stderr[i]),
                -math.exp(-float(expected_tau[i])),
                reduced,
                reduced / d,
                -math.log(-c) if c < 0 else math.nan,
                float(expected_tau[i]),
            )
        )
    return reports


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


@dataclass(frozen=True)
class VerifySettings:
    """How ``seahaze verify`` renders and judges (the ``seahaze verify`` flags)."""

    mode: str = "reference"
    """Rendering mode to verify (:data:`seahaze.spec.RENDER_MODES`)."""
    spp: int = DEFAULT_SPP
    """Samples per pixel in all, split evenly over the batches."""
    resolution: tuple[int, int] = DEFAULT_RESOLUTION
    batches: int = DEFAULT_BATCHES
    """Independent render batches (seeds) that measure the noise, at least 2."""
    tolerance: float = DEFAULT_TOLERANCE
    """Largest accepted relative error of the measured visibility."""
    seed: int | None = None
    """Master seed; None keeps the base scene's ``render.seed``."""
    variant: str | None = None
    """Mitsuba variant; None keeps the base scene's."""
    target_width_deg: float = TARGET_WIDTH_DEG
    denoise: bool = False
    """Denoise every batch's level as ``render.denoise: on`` does (needs ``pyoidn``)."""

    def check(self) -> None:
        """Raise :class:`VerifyInputError` for settings that cannot work."""
        if self.mode not in RENDER_MODES:
            raise VerifyInputError(f"--mode {self.mode!r}: allowed {', '.join(RENDER_MODES)}")
        if self.batches < 2:
            raise VerifyInputError(
                f"--batches {self.batches}: at least 2 are needed to measure noise"
            )
        if self.spp < self.batches:
            raise VerifyInputError(f"--spp {self.spp}: must be >= --batches ({self.batches})")
        if not 0.0 < self.tolerance < 1.0:
            raise VerifyInputError(f"--tolerance {self.tolerance:g}: must be within (0, 1)")
        if not 0.0 < self.target_width_deg <= 0.5 * FOV_DEG / N_TARGETS:
            raise VerifyInputError(
                f"--target-width {self.target_width_deg:g}: must be within "
                f"(0, {FOV_DEG / N_TARGETS / 2:g}]°"
            )


def run_verify(
    base: SceneSpec,
    visibilities_m: Sequence[float],
    settings: VerifySettings | None = None,
    *,
    progress: Callable[[str], None] = lambda _msg: None,
    keep: dict[str, LevelMeasurement] | None = None,
) -> VerifyReport:
    """Render and measure the calibration scene of ``base`` at every visibility.

    Raises :class:`VerifyInputError` for settings that cannot work. ``keep``, when given,
    receives each level's raw measurement by level name (for images and tests).
    """
    settings = settings or VerifySettings()
    settings.check()
    if not visibilities_m:
        raise VerifyInputError("no visibility level to verify")
    if base.camera.height_m >= base.haze.top_m:
        raise VerifyInputError(
            f"camera.height_m {base.camera.height_m:g} is not below haze.top_m "
            f"{base.haze.top_m:g}: the targets must be seen from inside the haze layer"
        )
    spec = calibration_spec(
        base,
        settings.resolution,
        spp=settings.spp,
        seed=settings.seed,
        mode=settings.mode,
        variant=settings.variant,
    )
    camera = Camera.from_spec(spec.camera)
    width = settings.target_width_deg
    for v in visibilities_m:
        layout_targets(camera, v, width_deg=width)  # a too coarse resolution fails before rendering
    start = time.perf_counter()
    used_variant = select_variant(spec.render.variant)
    sea = build_sea(spec, camera)
    # Haze across the sea: the base scene's field, not one normalised over the 24° camera.
    medium = calibration_medium(base)
    threshold = spec.haze.threshold
    levels = []
    for i, v in enumerate(visibilities_m):
        t0 = time.perf_counter()
        name = level_name(v)
        measurement = render_level_batches(
            spec, sea, v, i, settings.batches, width, settings.denoise, medium
        )
        tau = sky_optical_depth(spec, v)
        if medium is not None:
            tau = extinction_coefficient(v, threshold) * measurement.sky_reduced_m
        seconds = time.perf_counter() - t0
        report = analyse_level(name, v, threshold, measurement, settings.tolerance, seconds, tau)
        if keep is not None:
            keep[name] = measurement
        levels.append(report)
        progress(
            f"{name}: V measured {report.measured_m:.0f} m ({report.error:+.1%}) "
            f"in {report.seconds:.1f} s"
        )
    config = _run_config(spec, settings, used_variant, sea.roughness, visibilities_m[0])
    if medium is not None:
        config["medium"] = {**medium.describe(), "field": FIELD_SEEN}
    return VerifyReport(config, levels, time.perf_counter() - start)


def _run_config(
    spec: SceneSpec,
    settings: VerifySettings,
    variant: str,
    sea_roughness: float,
    first_visibility_m: float,
) -> dict[str, Any]:
    """The settings a report records (``report.json``'s ``config``)."""
    camera = Camera.from_spec(spec.camera)
    targets = layout_targets(camera, first_visibility_m, width_deg=settings.target_width_deg)
    threshold = spec.haze.threshold
    return {
        "mode": settings.mode,
        "variant": variant,
        "spp": spec.render.spp,
        "batches": settings.batches,
        "denoise": "on" if settings.denoise else "off",
        "spp_per_batch": spec.render.spp // settings.batches,
        "resolution": list(settings.resolution),
        "seed": spec.render.seed,
        "tolerance": settings.tolerance,
        "threshold": str(threshold),
        "contrast_threshold": CONTRAST_THRESHOLD[Threshold(threshold)],
        "camera": spec.camera.model_dump(mode="json"),
        "sun": spec.sun.model_dump(mode="json"),
        "sky": spec.sky.model_dump(mode="json"),
        "haze": spec.haze.model_dump(mode="json", exclude={"levels"}),
        "sea": {"model": "flat", "roughness": sea_roughness},
        "targets": {
            "count": len(targets),
            "fractions_of_v": target_fractions(len(targets)).tolist(),
            "width_deg": settings.target_width_deg,
            "top_above_horizon_deg": TARGET_TOP_DEG,
            "pixels_each": [
                (t.rows[1] - t.rows[0]) * (t.columns[1] - t.columns[0]) for t in targets
            ],
        },
    }
