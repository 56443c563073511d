"""``seahaze verify``: measure the visibility a rendering mode really produces.

A calibration scene (the sun, sky, haze and camera height of a base scene; a flat sea; no
vessels) gets thin, perfectly black targets standing on the sea at distances from 0.05 V to
1.5 V, each seen against the horizon sky (:mod:`~seahaze.verify.targets`). Per target the
apparent contrast ``C = (L_target − L_sky) / L_sky`` is measured and Koschmieder's law
``C = −exp(−σ d)`` fitted (:mod:`~seahaze.verify.fit`; in haze that varies across the sea
against each target's own reduced length ``ℓ = ∫ρ ds``: :mod:`~seahaze.verify.field`); the
measured visibility ``V = −ln(ε) / σ`` is compared with the label (:mod:`~seahaze.verify.run`)
and reported (:mod:`~seahaze.verify.report`). docs/physics.md ("Verifying visibility") explains
the choices and the target-size effect.
"""

from ..visibility import visibility_from_extinction
from .field import (
    DENSE_RATIO,
    THIN_RATIO,
    calibration_medium,
    coverage,
    coverage_note,
)
from .fit import (
    Contrasts,
    Fit,
    RayLengths,
    fit_extinction,
    jackknife_visibility,
    measure_contrasts,
)
from .report import format_report, plot_contrasts, write_outputs, write_strips
from .run import (
    DEFAULT_BATCHES,
    DEFAULT_RESOLUTION,
    DEFAULT_SPP,
    DEFAULT_TOLERANCE,
    DEFAULT_VISIBILITY_M,
    LevelMeasurement,
    LevelReport,
    TargetReport,
    VerifyReport,
    VerifySettings,
    analyse_level,
    render_level_batches,
    run_verify,
)
from .targets import (
    FOV_DEG,
    N_TARGETS,
    TARGET_TOP_DEG,
    TARGET_WIDTH_DEG,
    Target,
    VerifyInputError,
    calibration_spec,
    horizon_row,
    layout_targets,
    min_resolution,
    sky_pixels,
    target_fractions,
    target_pixels,
)

__all__ = [
    "DEFAULT_BATCHES",
    "DEFAULT_RESOLUTION",
    "DEFAULT_SPP",
    "DEFAULT_TOLERANCE",
    "DEFAULT_VISIBILITY_M",
    "DENSE_RATIO",
    "FOV_DEG",
    "N_TARGETS",
    "TARGET_TOP_DEG",
    "TARGET_WIDTH_DEG",
    "THIN_RATIO",
    "Contrasts",
    "Fit",
    "LevelMeasurement",
    "LevelReport",
    "RayLengths",
    "Target",
    "TargetReport",
    "VerifyInputError",
    "VerifyReport",
    "VerifySettings",
    "analyse_level",
    "calibration_medium",
    "calibration_spec",
    "coverage",
    "coverage_note",
    "fit_extinction",
    "format_report",
    "horizon_row",
    "jackknife_visibility",
    "layout_targets",
    "measure_contrasts",
    "min_resolution",
    "plot_contrasts",
    "render_level_batches",
    "run_verify",
    "sky_pixels",
    "target_fractions",
    "target_pixels",
    "visibility_from_extinction",
    "write_outputs",
    "write_strips",
]
