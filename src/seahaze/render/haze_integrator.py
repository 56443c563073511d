"""The ``physical`` mode's integrator: one set of camera paths for the clean image and every level.

What a camera path collects, segment by segment (a segment runs from the camera or a surface to
the next surface or out to the sky), for each level ``k`` of extinction ``σ_k``:

* **Transmittance** over the segment's part inside the slab, analytic: ``exp(−σ_k ℓ)``.
* **In-scattering** along that part, ``∫ T_k(s) S_k(x(s)) ds`` with the source
  ``S_k = σ_s,k L_sun p(θ) T_k,sun V + J_k``: the sun's single scattering (``V``: whether the
  sun is visible from ``x``) and the diffuse field ``J_k`` (multiple scattering, skylight,
  sea-reflected light) from the level's table (:mod:`seahaze.render.diffuse_table`). Written
  as ``∫ T_k S_k|_{V=1} ds − ∫ T_k σ_s,k L_sun p T_k,sun (1 − V) ds`` (docs/physics.md, "One
  pass for all levels"):

  - the *unshadowed* integral needs no ray: every level draws its own distances in proportion
    to its own transmittance (common random numbers across levels, stratified), so its weight
    ``T_k/p_k = (1 − e^{−σ_k ℓ})/σ_k`` is exact and the noise comes only from how the source
    varies with height;
  - the *shadow correction* — non-zero only where a vessel shades the sun — uses points drawn
    from a mixture of the levels' densities (balance heuristic), each with one shadow ray
    shared by every level.

* **Surfaces** (sea, vessels) are shaded as Mitsuba's ``path`` does — emitter sampling and BSDF
  sampling with multiple importance sampling — with the light from the emitter attenuated by
  each level's slab transmittance; the BSDF-sampled ray becomes the next segment. Unlike
  ``path``, the sun and the sky are sampled apart, one sample each, each weighted against BSDF
  sampling by the power heuristic for its own density (Veach 1997, §9.2, one sample per
  strategy): ``sunsky`` draws one direction from a mixture (61 % sun, 39 % sky on the default
  scene), so a sunlit hull got the sun in only some samples, the largest source of its noise
  (docs/benchmarks.md, "Ground-truth noise"). The sun's aureole in the haze is sampled from
  each surface too (:meth:`sample_aureole`), against the BSDF sample's unshadowed sun. A hull
  facing the sea's sun glint draws most of its next directions toward the glint
  (:meth:`.GlintLobe.continue_path`).

The surfaces a path meets, its BSDF samples and its shadow rays do not depend on the haze, so
they are drawn once: the clean image (the path without haze) and every level come from the
same random numbers, and a pair differs by the haze, not by Monte Carlo noise. The clean
radiance is the integrator's RGB output; level ``k`` is the AOV channels ``k.R, k.G, k.B``.

Every per-level input (``σ``, the mixture, the tables) and ``albedo``, ``g`` are drjit values,
not literals: the kernel is compiled once per number of levels and reused for every scene. The
camera segment is traced unrolled; every later one in a symbolic loop that a packet of lanes
leaves once all its paths have ended (:meth:`sample`; docs/physics.md, "The kernel").
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..haze import HAZE_BOTTOM_M
from . import glint_lobe, jit_haze
from .haze_path import HazePath
from .jit_haze import TINY_OPTICAL_DEPTH
from .sun_disk import disk_irradiance, sun_axis, sun_cone_cos
from .table_texture import TableTexture
from .vessel_light import VesselLight

DEFAULT_BOUNCES = 3
"""Surface interactions per camera path: sea → sky, vessel → sea → sky. Measured on the
default scene at V = 1000 m, 6 instead of 3 changes the mean by < 0.05 %; 1 loses 0.15 %."""
CAMERA_POINTS = 2
"""Stratified in-scattering points on the camera segment (one on later segments)."""


def opaque_scalar(value: float) -> Any:
    """A drjit Float kernel parameter (not a literal baked into the kernel)."""
    import drjit as dr
    import mitsuba as mi

    return dr.opaque(mi.Float, float(value))


def _mis(pdf_a: Any, pdf_b: Any) -> Any:
    """Power heuristic (β = 2) weight of strategy ``a``."""
    import drjit as dr

    a2 = pdf_a * pdf_a
    return dr.detach(dr.select(pdf_a > 0, a2 / (a2 + pdf_b * pdf_b), 0.0))


def _one_minus_exp(tau: Any) -> Any:
    """``1 − e^{−τ}``, accurate for small ``τ`` and 1 for ``τ = ∞``."""
    import drjit as dr

    return dr.select(tau < TINY_OPTICAL_DEPTH, tau * (1.0 - 0.5 * tau), 1.0 - dr.exp(-tau))


def make_integrator(
    sun: Any,
    sky: Any,
    n_levels: int,
    grey: bool,
    top_m: float,
    bounces: int = DEFAULT_BOUNCES,
    camera_points: int = CAMERA_POINTS,
    *,
    wind_speed: float,
    glint_share: float = glint_lobe.GLINT_SHARE,
    vessels_only: bool = False,
) -> Any:
    """A new haze integrator for ``n_levels`` hazy levels (class defined lazily: it needs a
    Mitsuba variant). ``grey`` levels have one extinction for R, G and B (a third of the
    exponentials). ``sun`` is the emitter whose single scattering is computed with shadow rays
    (the sun part of the scene's ``sunsky``); everything else scattered in the haze comes from
    the tables. ``sun`` and ``sky`` (the scene's ``sunsky`` split in two) are the lights the
    surfaces sample, one sample each per surface interaction. ``wind_speed`` (m/s, the sea's)
    sets the width of the sun glint's lobe, of which a hull facing it draws ``glint_share`` of
    its next directions (:mod:`seahaze.render.glint_lobe`). ``vessels_only``: the integrator
    of the vessel-light pass, which renders only each level's correction for the light of the
    vessels in the haze in front of them (:mod:`seahaze.render.vessel_light`; its clean
    radiance is 0).
    """
    import drjit as dr
    import mitsuba as mi

    class HazeIntegrator(mi.SamplingIntegrator):
        """Camera paths through one homogeneous slab: clean RGB plus one AOV triple per level."""

        def __init__(self, props: Any):
            super().__init__(props)
            self.n_levels, self.grey = n_levels, grey
            self.bounces, self.camera_points = bounces, camera_points
            self.vessels_only = vessels_only
            self.sun, self.sky = sun, sky
            # The sun's disk, sampled uniformly here: sunsky's own sampling of it also
            # evaluates the sky's 20-Gaussian density, and its density (a float32 solid angle
            # of 7e-5 sr) is 0.2 % off. Opaque parameters: another sun reuses the kernel.
            self.sun_axis = mi.Vector3f(*(opaque_scalar(c) for c in sun_axis(sun)))
            cos_max = sun_cone_cos()
            self.sun_cos = opaque_scalar(cos_max)
            self.sun_pdf = opaque_scalar(1.0 / (2.0 * np.pi * (1.0 - cos_max)))
            self.sun_irradiance = mi.Color3f(*(opaque_scalar(c) for c in disk_irradiance(sun)))
            # Where the sea's sun glint lies seen from a hull (glint_lobe module).
            self.glint = glint_lobe.GlintLobe(sun_axis(sun), wind_speed, glint_share)
            self.top, self.bottom = top_m, HAZE_BOTTOM_M
            # The vessel-light pass's helper, in that pass's integrator only.
            self.vessels = VesselLight(self) if vessels_only else None
            self.set_levels(
                np.full((n_levels, 3), 1e-3),
                np.full(n_levels, 1.0 / n_levels),
                0.998,
                0.0,
                np.zeros((2, 2, 2, 3 * n_levels), np.float32),
                0.0,
            )

        def set_levels(
            self,
            sigma: np.ndarray,
            mixture: np.ndarray,
            albedo: float,
            g: float,
            tables: np.ndarray,
            sun_azimuth_rad: float,
        ) -> None:
            """Point the integrator at a set of levels without changing its compiled kernel.

            ``sigma`` (L, 3) extinction per level and channel (1/m, > 0), ``mixture`` (L,) the
            distance-sampling weights (sum 1), ``tables`` (n_z, n_mu, n_phi, 3L) the diffuse
            in-scattering of every level, channels ``3k..3k+2`` for level ``k``.
            """
            if sigma.shape != (self.n_levels, 3) or tables.shape[-1] != 3 * self.n_levels:
                raise ValueError(f"this integrator renders {self.n_levels} levels")
            opaque = lambda x: dr.opaque(mi.Float, float(x))  # noqa: E731
            self.sigma = [mi.Color3f(*(opaque(c) for c in row)) for row in sigma]
            # Green's extinction (distances follow it) and, per level, the extinction the
            # transmittances use: green's own for grey levels (one exponential, not three).
            # Green's reciprocal is a parameter too: the diffuse points divide by nothing.
            self.sg = [row.y for row in self.sigma]
            self.inv_sg = [opaque(1.0 / row[1]) for row in sigma]
            self.ext = self.sg if self.grey else self.sigma
            # Every input is an opaque kernel parameter, so another scene or level reuses the
            # compiled kernel; per-level arrays are padded (jit_haze.padded_floats).
            self.sigma_g = jit_haze.padded_floats(sigma[:, 1])
            weights = np.asarray(mixture, np.float64) / np.sum(mixture)
            self.mix_weight = [opaque(w) for w in weights]
            self.mix_start = jit_haze.padded_floats(
                np.concatenate([[0.0], np.cumsum(weights)[:-1]])
            )
            self.mix_width = jit_haze.padded_floats(weights)
            self.mix_bounds = [opaque(b) for b in np.cumsum(weights)[:-1]]
            self.albedo, self.g = opaque(albedo), opaque(g)
            self.sun_cos_az, self.sun_sin_az = (
                opaque(f(sun_azimuth_rad)) for f in (np.cos, np.sin)
            )
            self.table = TableTexture(tables, self.n_levels)

        def sun_cone_direction(self, u: Any) -> Any:
            """The direction uniform in the cone around the sun's axis for uniform ``u`` (2-D):
            the sun's disk and a few float32 steps of rim (sun_disk module)."""
            local = mi.warp.square_to_uniform_cone(u, self.sun_cos)
            return mi.Frame3f(self.sun_axis).to_world(local)

        def sample_sun(self, it: Any, u: Any, active: Any) -> tuple[Any, Any]:
            """A direction uniform in the sun's disk (no visibility test) and its radiance
            over its solid-angle density, as ``Emitter.sample_direction`` returns them."""
            ds = dr.zeros(mi.DirectionSample3f)
            ds.d = self.sun_cone_direction(u)
            ds.pdf = dr.select(active, self.sun_pdf, 0.0)
            ds.delta = mi.Bool(False)
            radiance = self.sun.eval_direction(it, ds, active)
            return ds, dr.select(active, radiance / self.sun_pdf, 0.0)

        # -- slab helpers ---------------------------------------------------------------
        def slab_length(self, p: Any, d: Any, t_end: Any = None) -> tuple[Any, Any]:
            """Entry parameter and length of ``p + s d`` inside the slab, up to ``t_end``."""
            enter, leave = jit_haze.slab_interval(p.z, d.z, self.bottom, self.top)
            if t_end is not None:
                leave = dr.minimum(leave, t_end)
            return enter, dr.maximum(leave - enter, 0.0)

        def transmittance(self, k: int, length: Any) -> Any:
            """Level ``k``'s transmittance over ``length`` metres: a Float for grey levels, RGB
            otherwise. Written as ``exp(−(σ ℓ))``, as :func:`_one_minus_exp` is, so that the
            two share one exponential."""
            return dr.exp(-(self.ext[k] * length))

        def mixture_distance(self, u: Any, length: Any) -> tuple[Any, Any]:
            """A distance in ``[0, length]`` from the levels' mixture for uniform ``u``, and the
            mixture density there. The component is chosen by ``u`` and ``u`` is rescaled
            within it, so stratified ``u`` stratify both the component and the distance."""
            j = mi.UInt32(0)
            for bound in self.mix_bounds:
                j += mi.UInt32(u >= bound)
            start = dr.gather(mi.Float, self.mix_start, j)
            width = dr.gather(mi.Float, self.mix_width, j)
            u_in = dr.clip((u - start) / width, 0.0, 0.99999994)
            sigma = dr.gather(mi.Float, self.sigma_g, j)
            s = -dr.log(dr.maximum(1.0 - u_in * _one_minus_exp(sigma * length), 1e-30)) / sigma
            s = dr.minimum(s, length)
            return s, self.mixture_density(s, length)

        def mixture_density(self, s: Any, length: Any) -> Any:
            """The density (1/m) of :meth:`mixture_distance` at distance ``s``."""
            pdf = mi.Float(0.0)
            for k in range(self.n_levels):
                norm = _one_minus_exp(self.sg[k] * length)
                density = self.sg[k] * dr.exp(-(self.sg[k] * s)) / dr.maximum(norm, 1e-30)
                pdf += self.mix_weight[k] * density
            return pdf

        def sun_source(self, d, travel, active):
            """Whether the sun lights the haze from disk direction ``d``, and its
            single-scattering source toward ``-travel`` per unit extinction: the disk's
            irradiance × phase × albedo (sun_disk module)."""
            lit = active & (d.z > 0.0)
            phase = jit_haze.hg_phase(dr.dot(d, travel), self.g)
            return lit, dr.select(lit, self.sun_irradiance * phase * self.albedo, 0.0)

        def sun_scattered(self, k, near_k, depth, climb, length):
            """Level ``k``'s :func:`jit_haze.sun_scattered_fraction` over ``length`` metres of
            a segment entering the slab ``depth`` metres below its top along the sun, whose
            optical depth toward the sun grows by ``climb`` (``1 − d_z / μ_sun``) per metre;
            ``near_k``: the level's transmittance over that depth, if already known (a Python
            ``None`` computes it)."""
            e_start = self.ext[k] * depth
            near = dr.exp(-e_start) if near_k is None else near_k
            # The same 1 / climb for every level: drjit's value numbering keeps one division.
            return jit_haze.sun_scattered_fraction(
                self.ext[k], near, e_start, climb, 1.0 / climb, length
            )

        def sun_scattered_at(self, k, depth, climb, s):
            """The integrand of :meth:`sun_scattered` at distance ``s`` (1/m): level ``k``'s
            ``σ e^{−σ (depth + climb s)}``, the light scattered there per unit of source."""
            return self.ext[k] * self.transmittance(k, depth + climb * s)

        def aureole_pdf(self, d):
            """Solid-angle density of :meth:`sample_aureole`'s directions."""
            return jit_haze.hg_phase(dr.dot(self.sun_axis, d), self.g)

        def sample_aureole(self, scene, sampler, si, bsdf, ctx, share, p, active, sun):
            """The sun's single scattering in the haze as a light seen from a surface: one
            direction drawn from the phase function around the sun, weighted against BSDF
            sampling by the power heuristic. The aureole is broad and bright (the HG peak is
            125× its side at g = 0.75), and a glossy sea's BSDF samples found it rarely: it was
            most of a level's own noise near the camera (docs/physics.md, "The aureole").
            ``p``: the path (its throughput, transmittances and radiances, updated in place);
            ``share``: the surface's glint share (:meth:`.GlintLobe.share_at`); ``sun``: the sun's
            emitter sample at the surface (direction, slab depth toward it, each level's
            transmittance over that depth), whose direction lights the haze here too, so that
            the levels' transmittances toward the sun are computed once."""
            sun_d, sun_depth, sun_att = sun
            cos_t = jit_haze.hg_sample_cos(sampler.next_1d(active), self.g)
            phi = 2.0 * dr.pi * sampler.next_1d(active)
            axis = (self.sun_axis.x, self.sun_axis.y, self.sun_axis.z)
            d = mi.Vector3f(*jit_haze.rotate_directions(axis, cos_t, phi))
            pdf = self.aureole_pdf(d)
            value, bsdf_pdf = bsdf.eval_pdf(ctx, si, si.to_local(d), active)
            active = active & (pdf > 0.0) & dr.any(value != 0.0)
            ray = si.spawn_ray(d)
            enter, length = self.slab_length(ray.o, d)
            lit, source = self.sun_source(sun_d, d, active & (length > 0.0))
            # A surface in the way (rarely: 2 % of the default scene's rays) hides what lies
            # behind it: tested at one distance from the levels' mixture, whose shadow ray
            # costs a third of finding the nearest hit (docs/physics.md, "The aureole").
            s, s_pdf = self.mixture_distance(sampler.next_1d(active), length)
            ray.maxt = enter + s
            hidden = lit & scene.ray_test(ray, lit)
            mis = _mis(pdf, self.glint.continuation_pdf(share, bsdf_pdf, d))
            weight = p.beta * value * source * mis / dr.maximum(pdf, 1e-30)
            climb = 1.0 - d.z / dr.maximum(sun_d.z, 1e-6)
            for k in range(self.n_levels):
                # The segment enters the slab where the sun's sample left from (or at the
                # bottom, from below it): the depth toward the sun there is the sample's.
                frac = self.sun_scattered(k, sun_att[k], sun_depth, climb, length)
                beyond = self.sun_scattered_at(k, sun_depth, climb, s)
                frac -= dr.select(hidden, beyond / dr.maximum(s_pdf, 1e-30), 0.0)
                p.res[k] += dr.select(lit, p.att[k] * weight * frac, 0.0)

        def inscatter(
            self, scene, sampler, ray, enter, length, weight, att, res, active, sun_mis, shade=True
        ):
            """Add every level's in-scattering along ``ray`` over ``[enter, enter + length]``
            (``weight``: the path throughput, None on the camera segment; ``att``: each level's
            transmittance so far; ``sun_mis``: the weight of the unshadowed sun against
            :meth:`sample_aureole` at the surface the segment left; ``shade``: whether surfaces
            may shade the sun from the segment). See the module docstring."""
            beta = mi.Color3f(1.0) if weight is None else weight
            sun_d = self.sun_cone_direction(sampler.next_2d(active))
            lit, sun = self.sun_source(sun_d, ray.d, active)
            mu_sun = dr.maximum(sun_d.z, 1e-6)
            z_entry = ray.o.z + enter * ray.d.z
            depth, climb = dr.maximum(self.top - z_entry, 0.0) / mu_sun, 1.0 - ray.d.z / mu_sun
            pick = sampler.next_1d(active)
            tables = self.table.toward(-ray.d, self.sun_cos_az, self.sun_sin_az, pick)
            # Stratified, and the same for every level (common random numbers).
            n_points = self.camera_points if weight is None else 1
            us = [(i + sampler.next_1d(active)) / n_points for i in range(n_points)]
            for k in range(self.n_levels):
                # Unshadowed sun: transmittance to the point and on to the sun are both
                # exponential in s, so their product integrates in closed form.
                frac = self.sun_scattered(k, None, depth, climb, length)
                # The diffuse field: distances drawn from the level's own transmittance.
                sg, inv_sg = self.sg[k], self.inv_sg[k]
                mass = _one_minus_exp(sg * length)
                diffuse = mi.Color3f(0.0)
                for u in us:
                    s = dr.minimum(-dr.log(dr.maximum(1.0 - u * mass, 1e-30)) * inv_sg, length)
                    value = tables(k, (z_entry + s * ray.d.z) * (1.0 / self.top))
                    if not self.grey:  # distances follow green; reweight R and B
                        value = value * dr.exp(-(self.sigma[k] - sg) * s)
                    diffuse += value
                source = sun * frac * sun_mis + (mass * inv_sg * (1.0 / n_points)) * diffuse
                res[k] += dr.select(active, att[k] * beta * source, 0.0)
            if not shade:
                return
            # The shadow correction: one shared point and shadow ray.
            s, pdf = self.mixture_distance(sampler.next_1d(active), length)
            x = ray(enter + s)
            shadow = mi.Ray3f(x, sun_d, ray.time, ray.wavelengths)
            shaded = lit & scene.ray_test(shadow, lit)
            scale = beta * sun / dr.maximum(pdf, 1e-30)
            for k in range(self.n_levels):
                lost = self.sun_scattered_at(k, depth, climb, s) * scale
                res[k] -= dr.select(shaded, att[k] * lost, 0.0)

        # -- the path ---------------------------------------------------------------------
        def sample(self, scene, sampler, ray, medium=None, active=True):
            if self.vessels_only:
                return self.vessels.sample(scene, sampler, ray, active)
            path = HazePath.start(mi.Ray3f(ray), mi.Bool(active), self.n_levels, self.grey)
            # The camera segment is unrolled (it takes CAMERA_POINTS in-scattering points);
            # later ones run in a loop that a packet of lanes leaves once all its paths have
            # ended: most end at the sky after one or two segments, and an unrolled kernel
            # paid for every bounce of every lane.
            self.bounce(scene, sampler, path, camera=True)
            path = self.follow(scene, sampler, path)
            aovs = [c for r in path.res for c in (r.x, r.y, r.z)]
            return mi.Spectrum(path.clean), mi.Bool(True), aovs

        def follow(self, scene, sampler, path):
            """Path ``path`` traced on, segment by segment, until it ends."""

            def body(path, sampler):
                self.bounce(scene, sampler, path, camera=False)
                return path, sampler

            path, _ = dr.while_loop(
                (path, sampler), lambda path, sampler: path.active, body, label="haze_path"
            )
            return path

        def bounce(self, scene, sampler, p, camera, hit=None, free=False):
            """One segment of path ``p`` (a :class:`HazePath`, updated in place): the haze along
            it, the sky where it escapes, and at the surface it meets the lights and the next
            direction (up to ``bounces`` surfaces). ``hit``: the segment's end, if already
            found (the surface and its distance); ``free``: the segment runs through the open
            sea's haze of the tables (no surface shades it, and the sun's disk is not its
            light: :meth:`.VesselLight.vessel_light`)."""
            if hit is None:
                si = scene.ray_intersect(p.ray, p.active)
                t_end = dr.select(si.is_valid(), si.t, dr.inf)
            else:
                si, t_end = hit
            enter, length = self.slab_length(p.ray.o, p.ray.d, t_end)
            segment = [self.transmittance(k, length) for k in range(self.n_levels)]
            sun_mis = dr.select(p.prev_delta, 1.0, _mis(p.prev_pdf, self.aureole_pdf(p.ray.d)))
            weight = None if camera else p.beta
            in_haze = p.active & (length > 0.0)
            self.inscatter(
                scene,
                sampler,
                p.ray,
                enter,
                length,
                weight,
                p.att,
                p.res,
                in_haze,
                sun_mis,
                shade=not free,
            )

            # The sky and the sun at the end of an escaping segment, each with MIS against
            # its own emitter sampling at the surface the segment left.
            escaped = p.active & ~si.is_valid()
            ds_hit = mi.DirectionSample3f(scene, si, p.prev_si)
            in_disk = escaped & (dr.dot(p.ray.d, self.sun_axis) >= self.sun_cos)
            sun_pdf = dr.select(in_disk, self.sun_pdf, 0.0)
            seen = mi.Color3f(0.0)
            if not free:
                seen = self.sun.eval(si, in_disk) * dr.select(
                    p.prev_delta, 1.0, _mis(p.prev_pdf, sun_pdf)
                )
            sky_pdf = self.sky.pdf_direction(p.prev_si, ds_hit, escaped & ~p.prev_delta)
            mis_sky = dr.select(p.prev_delta, 1.0, _mis(p.prev_pdf, sky_pdf))
            seen += self.sky.eval(si, escaped) * mis_sky
            sky = dr.select(escaped, p.beta * seen, 0.0)
            p.clean += sky
            for k in range(self.n_levels):
                p.res[k] += p.att[k] * segment[k] * sky
                p.att[k] = p.att[k] * segment[k]
            p.active = p.active & si.is_valid() & (p.depth < self.bounces)
            self.shade(scene, sampler, p, si)
            p.depth += 1

        def shade(self, scene, sampler, p, si):
            """Light path ``p``'s surface ``si`` and turn the path along a BSDF sample: one
            emitter sample from the sun and one from the sky (not one from sunsky's mixture of
            both), each level attenuated toward the emitter, and the aureole."""
            ctx = mi.BSDFContext()
            bsdf = si.bsdf(p.ray)
            active = p.active
            smooth = active & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)
            share = self.glint.share_at(si, bsdf, active)
            sun = None
            for sample_light in (self.sample_sun, self.sky.sample_direction):
                ds_e, em_w = sample_light(si, sampler.next_2d(smooth), smooth)
                drawn = smooth & (ds_e.pdf > 0)
                drawn &= ~scene.ray_test(si.spawn_ray(ds_e.d), drawn)
                value, bsdf_pdf = bsdf.eval_pdf(ctx, si, si.to_local(ds_e.d), drawn)
                mis_e = _mis(ds_e.pdf, self.glint.continuation_pdf(share, bsdf_pdf, ds_e.d))
                direct = dr.select(drawn, p.beta * value * em_w * mis_e, 0.0)
                _, e_length = self.slab_length(si.p, ds_e.d)
                if sun is not None:
                    # Where nothing was drawn the sky's direction may be NaN (its sampler at
                    # the ends of its erfinv): its transmittance would make 0 · NaN = NaN.
                    e_length = dr.select(drawn, e_length, 0.0)
                toward = [self.transmittance(k, e_length) for k in range(self.n_levels)]
                if sun is None:  # the sun's disk sample, drawn or shadowed, for the aureole
                    sun = (ds_e.d, e_length, toward)
                p.clean += direct
                for k in range(self.n_levels):
                    p.res[k] += dr.select(drawn, p.att[k] * toward[k] * direct, 0.0)

            self.sample_aureole(scene, sampler, si, bsdf, ctx, share, p, smooth, sun)

            glint = self.glint
            bs, bsdf_weight, wo, pdf = glint.continue_path(sampler, si, bsdf, ctx, share, active)
            p.beta = dr.select(active, p.beta * bsdf_weight, p.beta)
            active &= dr.any(p.beta != 0.0)
            p.prev_si = dr.select(active, mi.Interaction3f(si), p.prev_si)
            p.prev_pdf = dr.select(active, pdf, p.prev_pdf)
            delta = mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta)
            p.prev_delta = dr.select(active, delta, p.prev_delta)
            p.ray = dr.select(active, si.spawn_ray(wo), p.ray)
            p.active = active

        def aov_names(self):
            return [f"{k}.{c}" for k in range(self.n_levels) for c in "RGB"]

        def to_string(self):
            return f"HazeIntegrator[levels={self.n_levels}, bounces={self.bounces}]"

    return HazeIntegrator(mi.Properties())
