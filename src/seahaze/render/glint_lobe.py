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
``physical`` integrator draws a share of a facing hull's next directions from this lobe
(``EstimatorSettings.glint_share``, :mod:`seahaze.render.estimator`) and weighs every
direction by the mixture's density, so the estimate stays unbiased whatever the lobe's shape
(docs/physics.md, "The glint on the hulls").
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..ocean.cox_munk import mean_square_slope


def mirror_axis(sun_axis: np.ndarray) -> np.ndarray:
    """Unit direction (3,) of the sun's mirror image in a flat sea (Z up): the centre of the
    glint seen from above the sea. ``sun_axis``: unit vector toward the sun."""
    axis = np.asarray(sun_axis, np.float64) * (1.0, 1.0, -1.0)
    return axis / np.linalg.norm(axis)


def lobe_kappa(wind_speed: float) -> float:
    """The lobe's concentration ``κ = 1/(2σ²)`` for a wind of ``wind_speed`` m/s (module
    docstring), ``σ²`` Cox & Munk's total mean square slope."""
    return 1.0 / (2.0 * mean_square_slope(wind_speed))


def lobe_share(sun_axis: np.ndarray, share: float, shining: bool = True) -> float:
    """The share of directions drawn from the lobe: ``share`` while the sun is above the
    horizon and ``shining``, 0 when it is not (a sun below the sea plane, switched off under
    an overcast or twilight sky, or hidden by a cloud makes no glint; drawn toward it, a
    sun's mirror image near the horizon would send the sea's own facets' paths along the
    horizon for nothing, and their rare hits make fireflies)."""
    return float(share) if float(sun_axis[2]) > 0.0 and shining else 0.0


def lobe_sample(axis: Any, kappa: Any, u: Any) -> Any:
    """A direction (world, drjit ``Vector3f``) drawn from the lobe around ``axis`` for a
    uniform 2-D sample ``u``."""
    import mitsuba as mi

    return mi.Frame3f(axis).to_world(mi.warp.square_to_von_mises_fisher(u, kappa))


def lobe_pdf(axis: Any, kappa: Any, d: Any) -> Any:
    """The lobe's density (per steradian) of the world direction ``d``."""
    import mitsuba as mi

    return mi.warp.square_to_von_mises_fisher_pdf(mi.Frame3f(axis).to_local(d), kappa)


class GlintLobe:
    """The glint lobe of one sun and sea as a ``physical`` integrator uses it: which surfaces
    draw from it, the density of their continuation mixture, and the draw itself. Every
    parameter is an opaque drjit value: another sun or sea reuses the compiled kernel."""

    def __init__(self, sun_axis: np.ndarray, wind_speed: float, share: float, shining: bool = True):
        """``sun_axis``: unit vector toward the sun; ``wind_speed`` (m/s): the sea's, which
        sets the lobe's width; ``share``: of a facing surface's next directions;
        ``shining``: whether the sun gives any light (:func:`lobe_share`)."""
        import drjit as dr
        import mitsuba as mi

        opaque = lambda x: dr.opaque(mi.Float, float(x))  # noqa: E731
        self.axis = mi.Vector3f(*map(opaque, mirror_axis(sun_axis)))
        self.share = opaque(lobe_share(sun_axis, share, shining))
        self.kappa = opaque(lobe_kappa(wind_speed))

    def share_at(self, si: Any, bsdf: Any, active: Any) -> Any:
        """The share of ``si``'s continuation directions drawn toward the glint: the lobe's
        share on a surface with no delta lobe that can send the path toward the sun's mirror
        image, 0 elsewhere (the sea itself: its normals point up, the glint down). An opaque
        surface can where the side the path arrives on faces the mirror image (a closed body
        is always seen from outside its normal; a sheet may be seen from either face); a
        translucent sheet (a sail) can from either side, through itself."""
        import drjit as dr
        import mitsuba as mi

        flags = bsdf.flags()
        seen_side = dr.select(mi.Frame3f.cos_theta(si.wi) < 0.0, -1.0, 1.0)
        through = mi.has_flag(flags, mi.BSDFFlags.DiffuseTransmission)
        facing = through | (seen_side * dr.dot(si.n, self.axis) > 0.0)
        guided = active & facing & ~mi.has_flag(flags, mi.BSDFFlags.Delta)
        return dr.select(guided, self.share, 0.0)

    def continuation_pdf(self, share: Any, bsdf_pdf: Any, d: Any) -> Any:
        """Solid-angle density of world direction ``d`` under a surface's continuation
        mixture: the BSDF's density ``bsdf_pdf`` and the lobe's, ``share`` of it. The lights'
        MIS weights are taken against this density, not the BSDF's alone, so that the weights
        of a direction still sum to one (Veach 1997, §9.2)."""
        return (1.0 - share) * bsdf_pdf + share * lobe_pdf(self.axis, self.kappa, d)

    def continue_path(
        self, sampler: Any, si: Any, bsdf: Any, ctx: Any, share: Any, active: Any
    ) -> tuple[Any, Any, Any, Any]:
        """The next direction of a path leaving ``si``: the BSDF sample ``bs``, the path's
        weight ``f cos / pdf``, the direction (world) and its density, from a one-sample
        mixture (Veach 1997, §9.2.4) of BSDF sampling and, with probability ``share``
        (:meth:`share_at`), the lobe.

        One 1-D and one 2-D number, as BSDF sampling alone takes: the 1-D one picks the
        strategy and is rescaled for the BSDF, the 2-D one drives the one picked. Where
        ``share`` is 0 (the sea) the path is the BSDF's, bit for bit."""
        import drjit as dr

        u, u2 = sampler.next_1d(active), sampler.next_2d(active)
        guided = share > 0.0
        pick = guided & (u < share)
        u_bsdf = dr.select(guided, (u - share) / (1.0 - share), u)
        bs, weight = bsdf.sample(ctx, si, dr.clip(u_bsdf, 0.0, 0.99999994), u2, active)
        wo = dr.select(pick, lobe_sample(self.axis, self.kappa, u2), si.to_world(bs.wo))
        value, bsdf_pdf = bsdf.eval_pdf(ctx, si, si.to_local(wo), guided)
        pdf = self.continuation_pdf(share, bsdf_pdf, wo)
        weight = dr.select(guided, value / dr.maximum(pdf, 1e-30), weight)
        return bs, weight, wo, dr.select(guided, pdf, bs.pdf)
