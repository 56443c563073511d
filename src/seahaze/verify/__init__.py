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

The names below are loaded when first asked for (PEP 562): importing the package, or its light
:mod:`~seahaze.verify.defaults`, does not build the calibration scene's machinery (the world, the
vessels, trimesh), which the ``seahaze`` command's other subcommands would otherwise import at
start-up for their help text.
"""

from __future__ import annotations

import importlib
from typing import Any

_SOURCES: dict[str, tuple[str, ...]] = {
    ".defaults": (
        "DEFAULT_BATCHES",
        "DEFAULT_RESOLUTION",
        "DEFAULT_SPP",
        "DEFAULT_TOLERANCE",
        "DEFAULT_VISIBILITY_M",
        "TARGET_WIDTH_DEG",
    ),
    ".field": (
        "DENSE_RATIO",
        "THIN_RATIO",
        "calibration_medium",
        "coverage",
        "coverage_note",
    ),
    ".fit": (
        "Contrasts",
        "Fit",
        "RayLengths",
        "fit_extinction",
        "jackknife_visibility",
        "measure_contrasts",
    ),
    ".report": (
        "format_report",
        "plot_contrasts",
        "write_outputs",
        "write_strips",
    ),
    ".run": (
        "LevelMeasurement",
        "LevelReport",
        "TargetReport",
        "VerifyReport",
        "VerifySettings",
        "analyse_level",
        "render_level_batches",
        "run_verify",
    ),
    ".targets": (
        "FOV_DEG",
        "N_TARGETS",
        "TARGET_TOP_DEG",
        "Target",
        "VerifyInputError",
        "calibration_spec",
        "horizon_row",
        "layout_targets",
        "min_resolution",
        "sky_pixels",
        "target_fractions",
        "target_pixels",
    ),
    "..visibility": ("visibility_from_extinction",),
}
"""Each submodule (relative to this package) and the names it provides."""

_WHERE = {name: module for module, names in _SOURCES.items() for name in names}

__all__ = sorted(_WHERE)


def __getattr__(name: str) -> Any:
    """``seahaze.verify.NAME``: the name from its submodule, imported on first use."""
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(module, __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_WHERE))
