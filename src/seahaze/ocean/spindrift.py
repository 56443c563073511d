"""Spindrift: the spray a gale tears from its breaking crests and blows downwind (Beaufort 8 up).

The sea criteria of the Beaufort scale name it from force 8: "edges of crests begin to break
into spindrift" (8), "crests of waves begin to topple, tumble and roll over; spray may affect
visibility" (9) (WMO-No. 558, *Manual on Marine Meteorological Services*, Beaufort scale).
Spindrift is spume: drops of tens of micrometres to millimetres torn by the wind from the tops
of breaking crests, a process that needs strong winds and grows steeply with them (Monahan,
Spiel & Davidson 1986, "A model of marine aerosol generation via whitecaps and wave
disruption", in *Oceanic Whitecaps*, Reidel, 167–174: spume only above about 9 m/s; Andreas
1998, "A new sea spray generation function for wind speeds up to 32 m s⁻¹", *J. Phys.
Oceanogr.* 28, 2175–2184). Most of it falls back within metres, so what an observer sees is a
white veil streaming from each breaking crest downwind and thinning out.

The model
    The source is the young foam of :class:`~seahaze.ocean.whitecaps.FoamField`: the crests
    that are breaking now. A whitecap's age is read from its reflectance, which decays as
    ``R = R_fresh·exp(−k·u)`` over its counted life ``0 <= u <= 1``
    (:data:`~seahaze.ocean.whitecaps.FOAM_AGE_DECAY`), so ``u = ln(R_fresh/R)/k``; the source
    is the foam fraction weighted by ``1 − u/Y`` over the youngest :data:`YOUNG_SHARE` ``Y``
    of the life (0 beyond): the actively breaking crests, whole at their brightest cores. Its
    mean over a large area is ``W·Y/2`` (:func:`mean_source`).

    The veil at a rest point ``x`` is the source upwind of it, carried downwind and thinning
    out exponentially over :data:`TRAIL_M`:

        v(x) = O(U10) · Σ_k w_k · source(x − s_k·ŵ),  w_k = e^(−s_k/L)·Δs/L,

    ``ŵ`` the direction the wind blows toward (the waves' direction), ``s_k`` the midpoints of
    :data:`TAPS` steps ``Δs`` out to :data:`REACH_TRAILS` trail lengths. The source is read with
    the detail a ``Δs`` step resolves (the foam field's own low-pass), so the steps do not
    print copies of a crest's lace. The filter keeps the mean: over a large area the veil's
    mean is ``O·W·Y/2·Σw`` (:attr:`Spindrift.mean_veil`). ``O(U10)``, the veil's opacity right
    behind a crest, is 0 up to force 8's lower wind (:data:`ONSET_M_S`) and grows linearly to
    :data:`MOST_OPACITY` at force 9's (:data:`FULL_M_S`): a gale's spindrift "begins", a severe
    gale's spray is dense. The trail's length and the opacity are visual choices, not
    measurements: the Beaufort criteria name the spindrift but give neither.

How it is rendered
    As a veil lying on the water: the surface under it is seen through ``1 − v`` and the veil
    reflects ``v·R_s``, ``R_s`` = :data:`SPRAY_REFLECTANCE` (a dense cloud of droplets seen
    obliquely is as white as fresh foam). In the sea mesh it joins the foam layer as the
    wakes' foam does (:func:`~seahaze.ocean.whitecaps.layer_over` with ``R_s``: foam fraction
    ``1 − (1 − f)(1 − v)``, foam albedo ``a·(1 − v) + v·R_s``), so it costs the render
    nothing; a model of the sea as a plane takes its mean (:attr:`Spindrift.mean_veil`) the
    same way.

Limits: the veil has no height (the metre or so it rises above a crest casts no shadow and
shows no parallax), no drops fly above the surface's silhouette, and it follows its crest
rather than drifting on after it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .whitecaps import FOAM_AGE_DECAY, FRESH_FOAM_REFLECTANCE, FoamField

ONSET_M_S = 17.2
"""Wind (m/s at 10 m) at which spindrift begins: force 8's lower limit."""
FULL_M_S = 20.8
"""Wind at which the veil reaches :data:`MOST_OPACITY`: force 9's lower limit."""
MOST_OPACITY = 0.8
"""Opacity of the veil right behind a whole breaking crest at the strongest winds."""
TRAIL_M = 4.0
"""Length (m) over which the veil thins by ``e`` downwind of its crest."""
REACH_TRAILS = 3.0
"""How far downwind a crest's veil reaches, in trail lengths (``e⁻³``: 5 % is cut off)."""
TAPS = 12
"""Steps of the sum upwind of a point (``Δs`` = 1 m)."""
YOUNG_SHARE = 0.5
"""Share of a whitecap's counted life over which it sheds spray: the young, breaking half."""
SPRAY_REFLECTANCE = FRESH_FOAM_REFLECTANCE
"""Visible reflectance of a dense spray veil (Lambertian): fresh foam's 0.55."""

TAP_SPACING_M = REACH_TRAILS * TRAIL_M / TAPS
"""``Δs`` (m): the steps of the sum, and the finest detail of the source it reads."""
TAP_DISTANCES_M = (np.arange(TAPS) + 0.5) * TAP_SPACING_M
"""``s_k`` (m): how far upwind of a point each step reads the source."""
TAP_WEIGHTS = np.exp(-TAP_DISTANCES_M / TRAIL_M) * (TAP_SPACING_M / TRAIL_M)
"""``w_k``: each step's share of the exponential trail (they sum to about ``1 − e⁻³``)."""


def spindrift_opacity(wind_speed: float) -> float:
    """``O(U10)``: the veil's opacity behind a whole breaking crest at wind ``U10`` (m/s at
    10 m): 0 up to :data:`ONSET_M_S`, linear to :data:`MOST_OPACITY` at :data:`FULL_M_S`."""
    ramp = (float(wind_speed) - ONSET_M_S) / (FULL_M_S - ONSET_M_S)
    return MOST_OPACITY * min(max(ramp, 0.0), 1.0)


def mean_source(coverage: float) -> float:
    """Mean of the source over a large area for whitecap coverage ``W`` (0–1): ``W·Y/2``, the
    counted area's quantiles being uniform over ``[0, W]`` (:mod:`seahaze.ocean.whitecaps`)."""
    return float(coverage) * YOUNG_SHARE / 2.0


def young_foam(fraction: np.ndarray, reflectance: np.ndarray) -> np.ndarray:
    """The source: foam ``fraction`` (0–1) weighted by its youth, read from its
    ``reflectance``: ``1 − u/Y`` at age ``u = ln(R_fresh/R)/k`` (module docstring)."""
    reflectance = np.clip(reflectance, 1e-12, FRESH_FOAM_REFLECTANCE)
    age = np.log(FRESH_FOAM_REFLECTANCE / reflectance) / FOAM_AGE_DECAY
    return fraction * np.clip(1.0 - age / YOUNG_SHARE, 0.0, 1.0)


@dataclass(frozen=True)
class Spindrift:
    """The spindrift of whitecaps ``foam`` under the wind that made them, blowing toward
    ``toward_deg`` (counter-clockwise from +x; the waves' direction): module docstring."""

    foam: FoamField
    toward_deg: float

    @property
    def opacity(self) -> float:
        """``O(U10)`` for the whitecaps' wind (:func:`spindrift_opacity`)."""
        return spindrift_opacity(self.foam.wind_speed)

    @property
    def present(self) -> bool:
        """Whether the wind tears spray from crests that the field can place."""
        return (
            self.opacity > 0.0
            and self.foam.coverage > 0.0
            and not math.isinf(self.foam.jacobian_threshold)
        )

    @property
    def mean_veil(self) -> float:
        """The veil's mean opacity over a large area, ``O·W·Y/2·Σw`` (module docstring)."""
        if not self.present:
            return 0.0
        return self.opacity * mean_source(self.foam.coverage) * float(TAP_WEIGHTS.sum())

    def source(
        self, x0: np.ndarray, y0: np.ndarray, spacing_m: np.ndarray | float | None = None
    ) -> np.ndarray:
        """The young foam (:func:`young_foam`) at rest positions (m), with the detail a mesh
        spacing ``spacing_m`` (m) carries (None: all of it)."""
        fraction, reflectance = self.foam.foam_and_reflectance(x0, y0, spacing_m)
        return young_foam(fraction, reflectance)

    def veil(
        self, x0: np.ndarray, y0: np.ndarray, spacing_m: np.ndarray | float | None = None
    ) -> np.ndarray:
        """The veil's opacity (0–1) at rest positions ``(x0, y0)`` (m; equal shapes), for mesh
        vertices of spacing ``spacing_m`` (m; None: the steps' own :data:`TAP_SPACING_M`)."""
        x0, y0 = np.broadcast_arrays(np.asarray(x0, dtype=float), np.asarray(y0, dtype=float))
        if not self.present:
            return np.zeros(x0.shape)
        spacing = np.maximum(
            np.broadcast_to(TAP_SPACING_M if spacing_m is None else spacing_m, x0.shape),
            TAP_SPACING_M,
        )
        az = math.radians(self.toward_deg)
        along = TAP_DISTANCES_M.reshape((-1,) + (1,) * x0.ndim)
        upwind_x = x0[None] - along * math.cos(az)
        upwind_y = y0[None] - along * math.sin(az)
        source = self.source(upwind_x, upwind_y, np.broadcast_to(spacing, upwind_x.shape))
        weights = TAP_WEIGHTS.reshape(along.shape)
        return np.clip(self.opacity * np.sum(weights * source, axis=0), 0.0, 1.0)
