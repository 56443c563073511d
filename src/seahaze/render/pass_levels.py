"""The levels of one ``physical`` pass as kernel parameters, and the medium asked for each.

A pass renders ``L`` levels of one :class:`~seahaze.medium.HazeMedium` at once; level ``k``
scales the medium by its extinction ``σ_k``. :class:`PassLevels` holds what the kernels read per
level — ``σ_k``, the mixture the shared in-scattering points are drawn from, the diffuse tables
— as opaque drjit values, so that another scene or set of levels reuses the compiled kernel,
and answers the integrators' per-level questions (transmittance, distances drawn in proportion
to it, the sun's single scattering along a segment) through the medium's formulas.

Every answer is given in reduced length and reduced height, where any medium of
:class:`~seahaze.medium.HazeMedium` (a vertical profile) is a homogeneous slab, so the closed
forms hold for every profile (:mod:`seahaze.medium`); the medium maps reduced heights and
distances back to points.

In haze that varies across the sea a pass renders each pixel's equivalent profile
(:mod:`seahaze.render.pixel_density`): :meth:`PassLevels.start` gives it, per lane, the
density ratios of the camera path's pixel, and every answer is the profile's scaled by them.
Along the camera segment reduced lengths and heights are the profile's times the ``view``
ratio ``r`` (a reduced distance divided by it to find its point) and each level's depths
toward the sun times its own ``sun_air`` ratio; along the later segments, which leave a
surface, lengths are times the ``bounce`` ratio and depths toward the sun times each level's
``sun_bounce``; the rays from a surface toward the lights and the aureole's segment are
times ``sun_surface``; the diffuse field of a segment is times the pixel's ``diffuse_air``
or ``diffuse_bounce`` ratio where it has them. None,
as for every other haze, leaves the kernels exactly as they were: the per-level depths toward
the sun are then one value.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..medium import (
    HazeMedium,
    distance_in_mass,
    drjit_ops,
    one_minus_exp,
    sun_scattered_fraction,
    transmittance,
)
from . import jit_haze
from .table_texture import TableTexture


class PassLevels:
    """The levels of one pass (see the module docstring). ``grey`` levels have one
    extinction for R, G and B: their transmittances are one exponential, not three."""

    def __init__(self, medium: HazeMedium, n_levels: int, grey: bool):
        self.medium, self.n_levels, self.grey = medium, n_levels, grey
        self.ops = drjit_ops()
        self.pixel: Any = None
        """Per lane, the ``view``, per-level ``sun_air``, ``sun_surface``, ``bounce``,
        per-level ``sun_bounce`` density ratios and per-level ``diffuse_air`` and
        ``diffuse_bounce`` factors (or None) of the camera path's pixel (drjit Floats), or
        None: the medium's
        profile as it is (module docstring). Set by the pass before it traces
        (:meth:`start`)."""
        self.ratio: Any = None
        """The ratios of the segment being followed: along it, and per level toward the sun
        from it."""
        self.set(
            np.full((n_levels, 3), 1e-3),
            np.full(n_levels, 1.0 / n_levels),
            0.998,
            0.0,
            np.zeros((2, 2, 2, 3 * n_levels), np.float32),
            0.0,
        )

    def set(
        self,
        sigma: np.ndarray,
        mixture: np.ndarray,
        albedo: float,
        g: float,
        tables: np.ndarray,
        sun_azimuth_rad: float,
        folded: bool = True,
    ) -> None:
        """Point the kernels at a set of levels without changing them.

        ``sigma`` (L, 3) extinction per level and channel (1/m, > 0), ``mixture`` (L,) the
        distance-sampling weights (sum 1), ``albedo`` and ``g`` the medium's, ``tables``
        (n_z, n_mu, n_phi, 3L) the diffuse in-scattering of every level, channels
        ``3k..3k+2`` for level ``k``; ``sun_azimuth_rad`` orients the tables' azimuth, which
        ``folded`` says is folded about the sun's vertical plane (or spans the whole circle).
        """
        import drjit as dr
        import mitsuba as mi

        if sigma.shape != (self.n_levels, 3) or tables.shape[-1] != 3 * self.n_levels:
            raise ValueError(f"this pass renders {self.n_levels} levels")
        opaque = lambda x: dr.opaque(mi.Float, float(x))  # noqa: E731
        self.sigma = [mi.Color3f(*(opaque(c) for c in row)) for row in sigma]
        # Green's extinction (distances follow it) and, per level, the extinction the
        # transmittances use: green's own for grey levels (one exponential, not three).
        # Green's reciprocal is a parameter too: the diffuse points divide by nothing.
        self.sg = [row.y for row in self.sigma]
        self.inv_sg = [opaque(1.0 / row[1]) for row in sigma]
        self.ext = self.sg if self.grey else self.sigma
        # Per-level arrays are padded (jit_haze.padded_floats): one kernel for any count.
        self.sigma_g = jit_haze.padded_floats(sigma[:, 1])
        weights = np.asarray(mixture, np.float64) / np.sum(mixture)
        self.mix_weight = [opaque(w) for w in weights]
        self.mix_start = jit_haze.padded_floats(np.concatenate([[0.0], np.cumsum(weights)[:-1]]))
        self.mix_width = jit_haze.padded_floats(weights)
        self.mix_bounds = [opaque(b) for b in np.cumsum(weights)[:-1]]
        self.albedo, self.g = opaque(albedo), opaque(g)
        self.sun_cos_az, self.sun_sin_az = (opaque(f(sun_azimuth_rad)) for f in (np.cos, np.sin))
        self.table = TableTexture(tables, self.n_levels, folded)

    def start(self, pixel: Any) -> None:
        """Point the kernels at a camera path of a pixel with ratios ``pixel`` (``view``,
        the levels' ``sun_air``, ``sun_surface``, ``bounce``, the levels' ``sun_bounce``,
        ``diffuse_air`` and ``diffuse_bounce``: :meth:`.PixelRatio.at`; None: no scaling),
        its camera segment first."""
        self.pixel = pixel
        self.ratio = None if pixel is None else (pixel[0], pixel[1], pixel[5])

    def follow_segment(self, first: Any) -> None:
        """Point the kernels at the path's next segment: the camera's where ``first``, else
        one that leaves a surface (module docstring)."""
        if self.pixel is not None:
            view, sun_air, _, bounce, sun_bounce, diffuse_air, diffuse_bounce = self.pixel
            select = self.ops.select
            pairs = lambda a, b: [select(first, x, y) for x, y in zip(a, b, strict=True)]  # noqa: E731
            diffuse = None
            if diffuse_air is not None:
                # Without later segments' ratios, they keep the tables' light (a factor 1).
                later = diffuse_bounce or [1.0] * len(diffuse_air)
                diffuse = pairs(diffuse_air, later)
            self.ratio = (select(first, view, bounce), pairs(sun_air, sun_bounce), diffuse)

    def follow_light(self) -> None:
        """Point the kernels at a segment from a surface toward the sun's side of the sky
        (the aureole's): where the pass renders pixels' equivalent profiles, through the
        column above the pixel's surface (its ``sun_surface`` ratio, along it and toward the
        sun)."""
        if self.pixel is not None:
            surface = self.pixel[2]
            self.ratio = (surface, [surface] * self.n_levels, None)

    # -- where the medium is along a ray ----------------------------------------------------
    def segment(self, p: Any, d: Any, t_end: Any = None) -> tuple[Any, Any]:
        """Where ``p + s d`` enters the medium and its reduced length up to ``t_end`` (m)."""
        enter, length = self.medium.reduced_length(p.z, d.z, t_end, self.ops)
        return enter, length if self.ratio is None else length * self.ratio[0]

    def light_segment(self, p: Any, d: Any) -> tuple[Any, Any]:
        """As :meth:`segment`, for a ray from a surface toward a light: where the pass
        renders pixels' equivalent profiles, through the column above the pixel's surface
        (its ``sun_surface`` ratio)."""
        enter, length = self.medium.reduced_length(p.z, d.z, None, self.ops)
        return enter, length if self.pixel is None else length * self.pixel[2]

    def follow_own_ratio(self, first: Any, ratio: Any) -> None:
        """Give a segment that leaves a surface (not ``first``) the ratio ``ratio`` measured
        along it (:mod:`seahaze.render.segment_ratio`) instead of its pixel's ``bounce``;
        call after :meth:`follow_segment`."""
        if self.ratio is not None:
            along, suns, diffuse = self.ratio
            self.ratio = (self.ops.select(first, along, ratio), suns, diffuse)

    def diffuse_scale(self, k: int) -> Any:
        """Level ``k``'s factor on the diffuse field along the segment being followed: the
        pixel's ``diffuse_air`` or ``diffuse_bounce`` ratio where the frame has them, else
        None (the tables as they are)."""
        if self.ratio is None or self.ratio[2] is None:
            return None
        return self.ratio[2][k]

    def transmittance(self, k: int, length: Any) -> Any:
        """Level ``k``'s transmittance over reduced length ``length``: a Float for grey
        levels, RGB otherwise."""
        return transmittance(self.ext[k], length, self.ops)

    def reduced_height(self, z: Any) -> Any:
        """The reduced height (m) of height ``z``."""
        h = self.medium.reduced_height(z, self.ops)
        return h if self.ratio is None else h * self.ratio[0]

    def inv_reduced_top(self) -> Any:
        """``1/H``, the reciprocal of the reduced height of the medium's top (1/m): where a
        reduced height lies on the diffuse tables' height axis."""
        inv_top = 1.0 / self.medium.reduced_top_m
        return inv_top if self.ratio is None else inv_top / self.ratio[0]

    def distance_at(self, ray: Any, enter: Any, reduced: Any) -> Any:
        """The parameter (m) along ``ray`` of the point ``reduced`` metres of reduced length
        past its entry into the medium at ``enter``."""
        if self.ratio is not None:
            reduced = reduced / self.ratio[0]
        return self.medium.distance_at(ray.o.z, ray.d.z, enter, reduced, self.ops)

    def depth_toward_sun(self, h: Any, mu_sun: Any) -> list:
        """Per level, the reduced length (m) from reduced height ``h`` out of the medium
        toward the sun (one value for every level but where pixels' equivalent profiles give
        each level its own sun ratio)."""
        if self.ratio is None:
            return [self.medium.depth_toward_sun(h, mu_sun, self.ops)] * self.n_levels
        view, suns, _ = self.ratio
        depth = self.medium.depth_toward_sun(h / view, mu_sun, self.ops)
        return [depth * sun for sun in suns]

    def sun_climb(self, dz: Any, mu_sun: Any) -> list:
        """Per level, how a segment's depth toward the sun grows per metre of its reduced
        length: ``1 − d_z / μ_sun`` (back to the segment's start, less the climb toward the
        sun), the climb scaled by ``r_s / r`` where the pass renders pixels' equivalent
        profiles."""
        if self.ratio is None:
            return [1.0 - dz / mu_sun] * self.n_levels
        view, suns, _ = self.ratio
        slope = dz / mu_sun / view
        return [1.0 - slope * sun for sun in suns]

    # -- distances along a segment ----------------------------------------------------------
    def mass(self, k: int, length: Any) -> Any:
        """Level ``k``'s scattering mass ``1 − e^{−σ ℓ}`` (green) over ``length``."""
        return one_minus_exp(self.sg[k] * length, self.ops)

    def own_distance(self, k: int, u: Any, mass: Any, length: Any) -> Any:
        """A distance drawn in proportion to level ``k``'s own (green) transmittance for
        uniform ``u``; ``mass``: :meth:`mass` over ``length``."""
        return distance_in_mass(u, self.sg[k], self.inv_sg[k], mass, length, self.ops)

    def mixture_distance(self, u: Any, length: Any) -> tuple[Any, Any]:
        """A distance in ``[0, length]`` from the levels' mixture for uniform ``u``, and the
        mixture density there. The component is chosen by ``u`` and ``u`` is rescaled within
        it, so stratified ``u`` stratify both the component and the distance."""
        import drjit as dr
        import mitsuba as mi

        j = mi.UInt32(0)
        for bound in self.mix_bounds:
            j += mi.UInt32(u >= bound)
        start = dr.gather(mi.Float, self.mix_start, j)
        width = dr.gather(mi.Float, self.mix_width, j)
        u_in = dr.clip((u - start) / width, 0.0, 0.99999994)
        sigma = dr.gather(mi.Float, self.sigma_g, j)
        mass = one_minus_exp(sigma * length, self.ops)
        s = -dr.log(dr.maximum(1.0 - u_in * mass, 1e-30)) / sigma
        s = dr.minimum(s, length)
        return s, self.mixture_density(s, length)

    def mixture_density(self, s: Any, length: Any) -> Any:
        """The density (1/m) of :meth:`mixture_distance` at distance ``s``."""
        import drjit as dr
        import mitsuba as mi

        pdf = mi.Float(0.0)
        for k in range(self.n_levels):
            norm = self.mass(k, length)
            density = self.sg[k] * dr.exp(-(self.sg[k] * s)) / dr.maximum(norm, 1e-30)
            pdf += self.mix_weight[k] * density
        return pdf

    # -- the sun's single scattering along a segment ----------------------------------------
    def sun_scattered(self, k: int, near_k: Any, depth: Any, climb: Any, length: Any) -> Any:
        """Level ``k``'s sun-scattered fraction over ``length`` metres of a segment entering
        the medium ``depth`` metres (reduced) below its top along the sun, whose depth toward
        the sun grows by ``climb`` (``1 − d_z / μ_sun``) per metre
        (:func:`seahaze.medium.sun_scattered_fraction`, exact in reduced length); ``near_k``: the
        level's transmittance over that depth, if already known (None computes it)."""
        import drjit as dr

        e_start = self.ext[k] * depth
        near = dr.exp(-e_start) if near_k is None else near_k
        # The same 1 / climb for every level: drjit's value numbering keeps one division.
        return sun_scattered_fraction(
            self.ext[k], near, e_start, climb, 1.0 / climb, length, self.ops
        )

    def sun_scattered_at(self, k: int, depth: Any, climb: Any, s: Any) -> Any:
        """The integrand of :meth:`sun_scattered` at distance ``s`` (1/m): level ``k``'s
        ``σ e^{−σ (depth + climb s)}``, the light scattered there per unit of source."""
        return self.ext[k] * self.transmittance(k, depth + climb * s)
