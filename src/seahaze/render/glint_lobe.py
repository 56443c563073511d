"""The sea's sun glint seen from a hull: the lobe a hull draws its next directions from.

A sea facet reflects the sun toward a point above the sea when its normal bisects the
directions to the sun and to that point. Seen from a hull, the glint of a wind-roughened sea is
therefore spread around the sun's mirror image in the mean sea plane,
``m = (s_x, s_y, −s_z)`` (Z up, ``s`` the unit vector toward the sun): a facet tilted by a small
angle ``δ`` turns the reflected ray by ``2δ``. Cox & Munk's (1954) slopes are near-Gaussian with a
total mean square slope ``σ² = 0.003 + 5.12e-3·U`` (:mod:`seahaze.ocean.cox_munk`), ``σ²/2`` per
axis, so the reflected directions spread with a variance of ``4·σ²/2 = 2σ²`` (rad²) per axis.

The lobe is a von Mises–Fisher distribution on the unit sphere around ``m`` (Fisher, R. A.
(1953). Dispersion on a sphere. Proc. R. Soc. Lond. A 217, 295–305):
``p(ω) = κ e^{κ (m·ω − 1)} / (2π (1 − e^{−2κ}))`` per steradian, whose per-axis angular variance
near the mode is ``1/κ``; matching it gives ``κ = 1/(2σ²)`` (:func:`lobe_kappa`): 12.9 at
7 m/s, 6.1 at 15 m/s, 167 on a calm sea. The glint is a caustic, bright and a few tenths of a
steradian wide, that a hull's cosine-weighted BSDF samples find only now and then; the
``physical`` integrator draws :data:`GLINT_SHARE` of a facing hull's next directions from this
lobe and weighs every direction by the mixture's density, so the estimate stays unbiased
whatever the lobe's shape (docs/physics.md, "The glint on the hulls").
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..ocean.cox_munk import mean_square_slope

GLINT_SHARE = 0.7
"""Share of a facing surface's continuation directions drawn from the lobe (measured: the
hulls' noise fell from 0.3 to 0.7 and little beyond; docs/benchmarks.md)."""


def mirror_axis(sun_axis: np.ndarray) -> np.ndarray:
    """Unit direction (3,) of the sun's mirror image in a flat sea (Z up): the centre of the
    glint seen from above the sea. ``sun_axis``: unit vector toward the sun."""
    axis = np.asarray(sun_axis, np.float64) * (1.0, 1.0, -1.0)
    return axis / np.linalg.norm(axis)


def lobe_kappa(wind_speed: float) -> float:
    """The lobe's concentration ``κ = 1/(2σ²)`` for a wind of ``wind_speed`` m/s (module
    docstring), ``σ²`` Cox & Munk's total mean square slope."""
    return 1.0 / (2.0 * mean_square_slope(wind_speed))


def lobe_share(sun_axis: np.ndarray, share: float = GLINT_SHARE) -> float:
    """The share of directions drawn from the lobe: ``share`` while the sun is above the
    horizon, 0 when it is not (a sun below the sea plane makes no glint)."""
    return float(share) if float(sun_axis[2]) > 0.0 else 0.0


def lobe_sample(axis: Any, kappa: Any, u: Any) -> Any:
    """A direction (world, drjit ``Vector3f``) drawn from the lobe around ``axis`` for a
    uniform 2-D sample ``u``."""
    import mitsuba as mi

    return mi.Frame3f(axis).to_world(mi.warp.square_to_von_mises_fisher(u, kappa))


def lobe_pdf(axis: Any, kappa: Any, d: Any) -> Any:
    """The lobe's density (per steradian) of the world direction ``d``."""
    import mitsuba as mi

    return mi.warp.square_to_von_mises_fisher_pdf(mi.Frame3f(axis).to_local(d), kappa)
