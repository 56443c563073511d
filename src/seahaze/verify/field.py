"""Verify in haze that varies across the sea (``haze.patches``, ``haze.bank``).

In such a medium Koschmieder's law holds ray by ray: a black target seen against the horizon
sky has the contrast ``C = −exp(−τ)`` of its own ray, ``τ = σ ℓ`` with ``ℓ = ∫ρ ds`` the
reduced length from the camera to the target (:class:`seahaze.nonuniform.NonUniformHaze`,
whose density averages 1 over the view's horizontal fan). Inside a dense patch ``ℓ/d > 1``, in
a clear gap ``ℓ/d < 1``: the targets then read different visibilities, and the fit of ``σ``
against ``ℓ`` instead of ``d`` measures the level's extinction.

Which field: the calibration scene is the base scene's camera on a flat sea, but its camera is
24° wide, and :func:`seahaze.scene_medium.scene_haze_medium` normalises the field over the
camera's own view and seeds the patches from ``render.seed``. The calibration scene therefore
renders the *base scene's* medium (:func:`calibration_medium`): its patches (seeded by the
scene's seed, whatever ``--seed`` renders with), its bank placed from the camera's start, its
normalisation over the scene's own view, at the scene's first frame (time 0 of a drift).
docs/physics.md ("Verifying visibility in haze that varies across the sea").
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..camera import Camera
from ..nonuniform import NonUniformHaze
from ..scene_medium import scene_haze_medium
from ..spec import SceneSpec
from .fit import RayLengths
from .targets import Target, sky_pixels, target_pixels

DENSE_RATIO = 1.15
"""A target whose ray's mean density ``ℓ/d`` exceeds this stands in dense haze (a patch)."""
THIN_RATIO = 0.87
"""A target whose ray's mean density ``ℓ/d`` is below this stands in thin haze (a gap)."""


def calibration_medium(base: SceneSpec) -> NonUniformHaze | None:
    """The base scene's medium at its first frame where it varies across the sea, else None
    (the calibration scene's own medium is then the same: it varies with height alone)."""
    medium = scene_haze_medium(base, Camera.from_spec(base.camera))
    return medium if isinstance(medium, NonUniformHaze) else None


def target_ray_lengths(
    reduced_m: np.ndarray, targets: Sequence[Target]
) -> tuple[RayLengths, np.ndarray]:
    """Per target the reduced lengths of its measured pixels' rays, from the per-pixel
    reduced length ``reduced_m`` (H, W; m) of the geometry pass, and the least reduced length
    (m) over each target's measured sky rays."""
    rays, sky = [], []
    for t in targets:
        rows, cols = target_pixels(t)
        rays.append(np.asarray(reduced_m[rows, cols], np.float64).ravel())
        s_rows, s_cols = sky_pixels(t)
        sky.append(float(np.min(reduced_m[s_rows][:, s_cols])))
    return RayLengths.of(rays), np.array(sky)


def coverage(mean_density: Sequence[float]) -> tuple[int, int]:
    """How many targets stand in dense haze (``ℓ/d`` > :data:`DENSE_RATIO`) and in thin haze
    (< :data:`THIN_RATIO`)."""
    ratios = np.asarray(mean_density, np.float64)
    return int(np.sum(ratios > DENSE_RATIO)), int(np.sum(ratios < THIN_RATIO))


def coverage_note(dense: int, thin: int, count: int) -> str | None:
    """A note when the layout puts every target on one side of the mean density, else None."""
    if dense and thin:
        return None
    sides = [f"dense haze (ℓ/d > {DENSE_RATIO:g})"] if not dense else []
    sides += [f"thin haze (ℓ/d < {THIN_RATIO:g})"] if not thin else []
    return (
        f"no target of {count} in {' nor in '.join(sides)}: this level tests the law on one "
        "side of the field only"
    )


def optical_depth_ratio(measured: float, expected: float) -> float:
    """``τ_measured / τ_expected``, NaN where either is not a positive finite number."""
    if not (math.isfinite(measured) and math.isfinite(expected)) or expected <= 0:
        return math.nan
    return measured / expected
