"""The ``physical`` mode's integrators: a shared base and the camera pass.

Import this module only once a Mitsuba variant is set (:func:`seahaze.render.physical.
integrator_classes` does): its classes derive from that variant's ``SamplingIntegrator``, as
Mitsuba's own Python integrators do.

:class:`HazeIntegrator` is what every ``physical`` pass shares: the lights (the sun's disk and
the sky, sampled apart), the levels it renders (:class:`~seahaze.render.pass_levels.PassLevels`,
which asks the haze medium), and the pieces of a camera path — the haze along a segment, the sky
where it escapes, the lights and next direction at a surface. :class:`CameraPass` is the main
pass built from them. The vessel-light pass is another subclass
(:class:`seahaze.render.vessel_light.VesselLightPass`).

What a camera path collects, segment by segment (a segment runs from the camera or a surface to
the next surface or out to the sky), for each level ``k`` of extinction ``σ_k``:

* **Transmittance** over the segment's part inside the medium: ``exp(−σ_k ℓ)``.
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
  each level's transmittance; the BSDF-sampled ray becomes the next segment. Unlike ``path``,
  the sun and the sky are sampled apart, one sample each, each weighted against BSDF sampling
  by the power heuristic for its own density (Veach 1997, §9.2, one sample per strategy):
  ``sunsky`` draws one direction from a mixture of both, so a sunlit hull got the sun in only
  some samples (docs/benchmarks.md, "Ground-truth noise"). The sun's aureole in the haze is
  sampled from each surface too (:meth:`HazeIntegrator.sample_aureole`), against the BSDF
  sample's unshadowed sun. A hull facing the sea's sun glint draws most of its next directions
  toward the glint (:meth:`.GlintLobe.continue_path`).

The surfaces a path meets, its BSDF samples and its shadow rays do not depend on the haze, so
they are drawn once: the clean image (the path without haze) and every level come from the
same random numbers, and a pair differs by the haze, not by Monte Carlo noise. The clean
radiance is the integrator's RGB output; level ``k`` is the AOV channels ``k.R, k.G, k.B``.

Every per-level input (``σ``, the mixture, the tables) and ``albedo``, ``g`` are drjit values,
not literals: the kernel is compiled once per number of levels and reused for every scene.
Every segment, the camera's included, runs in one symbolic loop that a packet of lanes leaves
once all its paths have ended (:meth:`HazeIntegrator.follow`; docs/physics.md, "The kernel"):
the segment's code is in the kernel once, and the camera segment's extra in-scattering points
are a loop of their own (:meth:`HazeIntegrator.diffuse_sums`).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import drjit as dr
import mitsuba as mi
import numpy as np

from ..medium import HazeMedium
from . import glint_lobe, jit_haze
from .estimator import EstimatorSettings
from .haze_path import HazePath
from .pass_levels import PassLevels
from .pixel_density import SMALLEST_RATIO
from .sun_disk import disk_irradiance, sun_axis, sun_cone_cos

if mi.variant() is None:
    raise ImportError(
        "seahaze.render.haze_integrator needs a Mitsuba variant: call "
        "seahaze.render.variant.select_variant() first"
    )
VARIANT = mi.variant()
"""The Mitsuba variant this module's classes derive from."""


def mis_weight(pdf_a: Any, pdf_b: Any) -> Any:
    """Power heuristic (β = 2) weight of strategy ``a`` against ``b`` (Veach 1997, §9.2)."""
    a2 = pdf_a * pdf_a
    return dr.detach(dr.select(pdf_a > 0, a2 / (a2 + pdf_b * pdf_b), 0.0))


def opaque_scalar(value: float) -> Any:
    """A drjit Float kernel parameter (not a literal baked into the kernel)."""
    return dr.opaque(mi.Float, float(value))


@dataclass
class SegmentSun:
    """What a segment's in-scattering drew for the sun, which its shadow correction reuses."""

    ray: Any
    active: Any
    enter: Any
    length: Any
    beta: Any
    sun_d: Any
    lit: Any
    source: Any
    depth: list
    """Per level, the reduced depth toward the sun at the segment's entry."""
    climb: list
    """Per level, how that depth grows per metre of the segment (:meth:`.PassLevels.sun_climb`)."""


class HazeIntegrator(mi.SamplingIntegrator):
    """What every ``physical`` pass shares (see the module docstring): clean RGB plus one AOV
    triple per level."""

    def __init__(
        self,
        sun: Any,
        sky: Any,
        medium: HazeMedium,
        n_levels: int,
        grey: bool,
        wind_speed: float,
        settings: EstimatorSettings,
    ):
        """``sun`` is the emitter whose single scattering is computed with shadow rays (the
        sun part of the scene's ``sunsky``); everything else scattered in the haze comes from
        the tables. ``sun`` and ``sky`` (the scene's ``sunsky`` split in two) are the lights
        the surfaces sample, one sample each per surface interaction. ``medium``: the haze;
        ``n_levels`` the levels rendered at once, ``grey`` when each has one extinction for R,
        G and B (a third of the exponentials). ``wind_speed`` (m/s, the sea's) sets the width
        of the sun glint's lobe (:mod:`seahaze.render.glint_lobe`). ``settings``: the
        estimator's tuning."""
        super().__init__(mi.Properties())
        self.settings, self.medium = settings, medium
        self.n_levels, self.grey = n_levels, grey
        self.sun, self.sky = sun, sky
        # The sun's disk, sampled uniformly here: sunsky's own sampling of it also evaluates
        # the sky's 20-Gaussian density, and its density (a float32 solid angle of 7e-5 sr)
        # is 0.2 % off. Opaque parameters: another sun reuses the kernel.
        self.sun_axis = mi.Vector3f(*(opaque_scalar(c) for c in sun_axis(sun)))
        cos_max = sun_cone_cos()
        self.sun_cos = opaque_scalar(cos_max)
        self.sun_pdf = opaque_scalar(1.0 / (2.0 * np.pi * (1.0 - cos_max)))
        irradiance = disk_irradiance(sun)
        self.sun_irradiance = mi.Color3f(*(opaque_scalar(c) for c in irradiance))
        # Where the sea's sun glint lies seen from a hull (glint_lobe module); none from a
        # sun that gives no light.
        shining = bool(np.max(irradiance) > 0.0)
        self.glint = glint_lobe.GlintLobe(sun_axis(sun), wind_speed, settings.glint_share, shining)
        self.levels = PassLevels(medium, n_levels, grey)
        self.pixel_ratio: Any = None
        self.segments: Any = None
        # A parameter: another count reuses the kernel.
        self.camera_points = dr.opaque(mi.UInt32, settings.camera_points)

    def set_pixel_ratio(self, pixel_ratio: Any, segments: Any = None) -> None:
        """Render each pixel's equivalent profile (:mod:`seahaze.render.pixel_density`):
        ``pixel_ratio`` is a :class:`~seahaze.render.pixel_density.PixelRatio` of the frame,
        or None for haze that varies with height alone. The medium is then the field's
        vertical profile. ``segments``: a
        :class:`~seahaze.render.segment_ratio.BankSegments` that measures each later
        segment's own ratio, or None (the pixel's ``bounce``)."""
        self.pixel_ratio = pixel_ratio
        self.segments = None if pixel_ratio is None else segments

    @contextmanager
    def camera_path(self, ray: Any, active: Any) -> Iterator[None]:
        """Trace a camera path of ray ``ray`` inside this block: the levels see the density
        ratios of its pixel where the pass renders haze that varies across the sea
        (:meth:`set_pixel_ratio`; every segment of the path sees the pixel's equivalent
        profile), and none after it (the next trace sets its own)."""
        pixel = None if self.pixel_ratio is None else self.pixel_ratio.at(ray, active)
        self.levels.start(pixel)
        try:
            yield
        finally:
            self.levels.start(None)

    def aov_names(self) -> list[str]:
        return [f"{k}.{c}" for k in range(self.n_levels) for c in "RGB"]

    def to_string(self) -> str:
        return f"{type(self).__name__}[levels={self.n_levels}, bounces={self.settings.bounces}]"

    # -- the sun ----------------------------------------------------------------------------
    def sun_cone_direction(self, u: Any) -> Any:
        """The direction uniform in the cone around the sun's axis for uniform ``u`` (2-D):
        the sun's disk and a few float32 steps of rim (sun_disk module)."""
        local = mi.warp.square_to_uniform_cone(u, self.sun_cos)
        return mi.Frame3f(self.sun_axis).to_world(local)

    def sample_sun(self, it: Any, u: Any, active: Any) -> tuple[Any, Any]:
        """A direction uniform in the sun's disk (no visibility test) and its radiance over
        its solid-angle density, as ``Emitter.sample_direction`` returns them."""
        ds = dr.zeros(mi.DirectionSample3f)
        ds.d = self.sun_cone_direction(u)
        ds.pdf = dr.select(active, self.sun_pdf, 0.0)
        ds.delta = mi.Bool(False)
        radiance = self.sun.eval_direction(it, ds, active)
        return ds, dr.select(active, radiance / self.sun_pdf, 0.0)

    def sun_source(self, d: Any, travel: Any, active: Any) -> tuple[Any, Any]:
        """Whether the sun lights the haze from disk direction ``d``, and its
        single-scattering source toward ``-travel`` per unit extinction: the disk's
        irradiance × phase × albedo (sun_disk module)."""
        lit = active & (d.z > 0.0)
        phase = jit_haze.hg_phase(dr.dot(d, travel), self.levels.g)
        return lit, dr.select(lit, self.sun_irradiance * phase * self.levels.albedo, 0.0)

    def aureole_pdf(self, d: Any) -> Any:
        """Solid-angle density of :meth:`sample_aureole`'s directions."""
        return jit_haze.hg_phase(dr.dot(self.sun_axis, d), self.levels.g)

    def sample_aureole(self, scene, sampler, si, bsdf, ctx, share, p, active, sun) -> None:
        """The sun's single scattering in the haze as a light seen from a surface: one
        direction drawn from the phase function around the sun, weighted against BSDF
        sampling by the power heuristic. The aureole is broad and bright (the HG peak is
        125× its side at g = 0.75), and a glossy sea's BSDF samples found it rarely
        (docs/physics.md, "The aureole"). ``p``: the path (its throughput, transmittances and
        radiances, updated in place); ``share``: the surface's glint share
        (:meth:`.GlintLobe.share_at`); ``sun``: the sun's emitter sample at the surface
        (direction, reduced depth toward it, each level's transmittance over that depth),
        whose direction lights the haze here too, so that the levels' transmittances toward
        the sun are computed once. In haze that varies across the sea its segment sees the
        column above the surface (:meth:`.PassLevels.follow_light`), where the sun's light
        comes down, not the later segments' mirrored ray."""
        levels = self.levels
        levels.follow_light()
        sun_d, sun_depth, sun_att = sun
        cos_t = jit_haze.hg_sample_cos(sampler.next_1d(active), levels.g)
        phi = 2.0 * dr.pi * sampler.next_1d(active)
        axis = (self.sun_axis.x, self.sun_axis.y, self.sun_axis.z)
        d = mi.Vector3f(*jit_haze.rotate_directions(axis, cos_t, phi))
        pdf = self.aureole_pdf(d)
        value, bsdf_pdf = bsdf.eval_pdf(ctx, si, si.to_local(d), active)
        active = active & (pdf > 0.0) & dr.any(value != 0.0)
        ray = si.spawn_ray(d)
        enter, length = levels.segment(ray.o, d)
        lit, source = self.sun_source(sun_d, d, active & (length > 0.0))
        # A surface in the way (rarely: a few per cent of rays) hides what lies behind it:
        # tested at one distance from the levels' mixture, whose shadow ray costs a third of
        # finding the nearest hit (docs/physics.md, "The aureole").
        s, s_pdf = levels.mixture_distance(sampler.next_1d(active), length)
        ray.maxt = levels.distance_at(ray, enter, s)
        hidden = lit & scene.ray_test(ray, lit)
        mis = mis_weight(pdf, self.glint.continuation_pdf(share, bsdf_pdf, d))
        weight = p.beta * value * source * mis / dr.maximum(pdf, 1e-30)
        climb = levels.sun_climb(d.z, dr.maximum(sun_d.z, 1e-6))
        for k in range(self.n_levels):
            # The segment enters the medium where the sun's sample left from (or at the
            # bottom, from below it): the depth toward the sun there is the sample's.
            frac = levels.sun_scattered(k, sun_att[k], sun_depth, climb[k], length)
            beyond = levels.sun_scattered_at(k, sun_depth, climb[k], s)
            frac -= dr.select(hidden, beyond / dr.maximum(s_pdf, 1e-30), 0.0)
            p.res[k] += dr.select(lit, p.att[k] * weight * frac, 0.0)

    # -- the haze along a segment -----------------------------------------------------------
    def inscatter(self, sampler, ray, enter, length, beta, n_points, att, res, active, sun_mis):
        """Add every level's unshadowed in-scattering along ``ray`` over ``[enter, enter +
        length]`` and return what the sun's part drew, for :meth:`shadow_correction`.
        ``beta``: the path throughput; ``n_points``: the stratified points the diffuse field
        is read at (a UInt32); ``att``: each level's transmittance so far; ``sun_mis``: the
        weight of the unshadowed sun against :meth:`sample_aureole` at the surface the segment
        left. See the module docstring."""
        levels = self.levels
        sun_d = self.sun_cone_direction(sampler.next_2d(active))
        lit, sun = self.sun_source(sun_d, ray.d, active)
        mu_sun = dr.maximum(sun_d.z, 1e-6)
        # In reduced height the medium is a homogeneous slab (seahaze.medium): the segment
        # climbs d_z per metre of reduced length from its entry's reduced height.
        h_entry = levels.reduced_height(ray.o.z + enter * ray.d.z)
        depth = levels.depth_toward_sun(h_entry, mu_sun)
        climb = levels.sun_climb(ray.d.z, mu_sun)
        pick = sampler.next_1d(active)
        tables = levels.table.toward(-ray.d, levels.sun_cos_az, levels.sun_sin_az, pick)
        mass = [levels.mass(k, length) for k in range(self.n_levels)]
        diffuse = self.diffuse_sums(
            sampler, tables, h_entry, ray.d.z, mass, length, n_points, active
        )
        per_point = 1.0 / mi.Float(n_points)
        for k in range(self.n_levels):
            # Unshadowed sun: transmittance to the point and on to the sun are both
            # exponential in s, so their product integrates in closed form.
            frac = levels.sun_scattered(k, None, depth[k], climb[k], length)
            scale = levels.diffuse_scale(k)
            spread = diffuse[k] if scale is None else diffuse[k] * scale
            source = sun * frac * sun_mis + (mass[k] * levels.inv_sg[k] * per_point) * spread
            res[k] += dr.select(active, att[k] * beta * source, 0.0)
        return SegmentSun(ray, active, enter, length, beta, sun_d, lit, sun, depth, climb)

    def diffuse_sums(self, sampler, tables, h_entry, dz, mass, length, n_points, active):
        """Each level's diffuse field (``tables``, :meth:`.TableTexture.toward`) summed over
        ``n_points`` points of a segment entering the medium at reduced height ``h_entry`` and
        climbing ``dz`` per metre over reduced ``length``: every level draws its distances in
        proportion to its own transmittance (``mass``: :meth:`.PassLevels.mass` per level),
        from the same stratified numbers (common random numbers). A symbolic loop, so that the
        camera segment's several points and a later segment's one share the kernel's code."""
        levels = self.levels
        inv_top = levels.inv_reduced_top()
        count = mi.Float(n_points)

        def body(i, sampler, sums):
            u = (mi.Float(i) + sampler.next_1d(active)) / count
            for k in range(self.n_levels):
                s = levels.own_distance(k, u, mass[k], length)
                value = tables(k, (h_entry + s * dz) * inv_top)
                if not self.grey:  # distances follow green; reweight R and B
                    value = value * dr.exp(-(levels.sigma[k] - levels.sg[k]) * s)
                sums[k] = sums[k] + value
            return i + 1, sampler, sums

        start = (mi.UInt32(0), sampler, [mi.Color3f(0.0) for _ in range(self.n_levels)])
        _, _, sums = dr.while_loop(
            start, lambda i, sampler, sums: i < n_points, body, label="haze_points"
        )
        return sums

    def shadow_correction(self, scene, sampler, along: SegmentSun, att, res) -> None:
        """Take from every level the sun's light that surfaces shade along the segment
        :meth:`inscatter` lit unshadowed: one point from the levels' mixture and one shadow
        ray shared by every level."""
        levels, ray = self.levels, along.ray
        s, pdf = levels.mixture_distance(sampler.next_1d(along.active), along.length)
        x = ray(levels.distance_at(ray, along.enter, s))
        shadow = mi.Ray3f(x, along.sun_d, ray.time, ray.wavelengths)
        shaded = along.lit & scene.ray_test(shadow, along.lit)
        scale = along.beta * along.source / dr.maximum(pdf, 1e-30)
        for k in range(self.n_levels):
            lost = levels.sun_scattered_at(k, along.depth[k], along.climb[k], s) * scale
            res[k] -= dr.select(shaded, att[k] * lost, 0.0)

    def haze_along(self, sampler, p: HazePath, t_end: Any, n_points: Any):
        """Each level's transmittance over path ``p``'s segment up to ``t_end`` (not yet
        applied to ``p``) and the segment's unshadowed in-scattering, read at ``n_points``
        points, added to ``p``; returns both the transmittances and what the sun's part drew
        (:meth:`inscatter`). Where the pass measures later segments' own ratios through a
        bank (:meth:`set_pixel_ratio`), this one's is measured here."""
        levels = self.levels
        levels.follow_segment(p.depth == 0)
        if self.segments is not None:
            u = sampler.next_1d(p.active)
            own = self.segments.ratio(p.ray, t_end, u, levels.ratio[0])
            levels.follow_own_ratio(p.depth == 0, dr.maximum(own, SMALLEST_RATIO))
        enter, length = levels.segment(p.ray.o, p.ray.d, t_end)
        segment = [levels.transmittance(k, length) for k in range(self.n_levels)]
        sun_mis = dr.select(p.prev_delta, 1.0, mis_weight(p.prev_pdf, self.aureole_pdf(p.ray.d)))
        in_haze = p.active & (length > 0.0)
        along = self.inscatter(
            sampler, p.ray, enter, length, p.beta, n_points, p.att, p.res, in_haze, sun_mis
        )
        return segment, along

    # -- where a segment ends ---------------------------------------------------------------
    def trace(self, scene: Any, p: HazePath) -> tuple[Any, Any]:
        """The surface path ``p``'s segment ends at and its distance (``∞``: the sky)."""
        si = scene.ray_intersect(p.ray, p.active)
        return si, dr.select(si.is_valid(), si.t, dr.inf)

    def sun_seen(self, si: Any, p: HazePath) -> Any:
        """The sun's disk where ``p``'s segment escapes into it, with MIS against the sun's
        sampling at the surface the segment left."""
        escaped = p.active & ~si.is_valid()
        in_disk = escaped & (dr.dot(p.ray.d, self.sun_axis) >= self.sun_cos)
        sun_pdf = dr.select(in_disk, self.sun_pdf, 0.0)
        mis = dr.select(p.prev_delta, 1.0, mis_weight(p.prev_pdf, sun_pdf))
        return self.sun.eval(si, in_disk) * mis

    def escape(self, scene: Any, p: HazePath, si: Any, segment: list, seen: Any) -> None:
        """The sky at the end of ``p``'s segment where it escapes (MIS against the sky's
        sampling at the surface the segment left) plus ``seen``, the sun's disk if the pass
        shows it, through each level's transmittance ``segment``; then the transmittances
        move on to the segment's end."""
        escaped = p.active & ~si.is_valid()
        ds_hit = mi.DirectionSample3f(scene, si, p.prev_si)
        sky_pdf = self.sky.pdf_direction(p.prev_si, ds_hit, escaped & ~p.prev_delta)
        mis_sky = dr.select(p.prev_delta, 1.0, mis_weight(p.prev_pdf, sky_pdf))
        seen += self.sky.eval(si, escaped) * mis_sky
        sky = dr.select(escaped, p.beta * seen, 0.0)
        p.clean += sky
        for k in range(self.n_levels):
            p.res[k] += p.att[k] * segment[k] * sky
            p.att[k] = p.att[k] * segment[k]

    def turn(self, scene: Any, sampler: Any, p: HazePath, si: Any) -> None:
        """Shade path ``p`` at ``si`` and turn it there, while it has surfaces left."""
        p.active = p.active & si.is_valid() & (p.depth < self.settings.bounces)
        self.shade(scene, sampler, p, si)
        p.depth += 1

    def bounce(self, scene: Any, sampler: Any, p: HazePath) -> None:
        """One segment of path ``p`` (updated in place): the haze along it, the sky and sun
        where it escapes, and at the surface it meets the lights and the next direction (up
        to ``settings.bounces`` surfaces). The segment that leaves the camera reads the
        diffuse field at ``settings.camera_points`` points, a later one at one."""
        si, t_end = self.trace(scene, p)
        n_points = dr.select(p.depth == 0, self.camera_points, 1)
        segment, along = self.haze_along(sampler, p, t_end, n_points)
        self.shadow_correction(scene, sampler, along, p.att, p.res)
        self.escape(scene, p, si, segment, self.sun_seen(si, p))
        self.turn(scene, sampler, p, si)

    def follow(self, scene: Any, sampler: Any, path: HazePath) -> HazePath:
        """Path ``path`` traced on, segment by segment, until it ends: in a loop that a
        packet of lanes leaves once all its paths have ended (most end at the sky after one
        or two segments; an unrolled kernel paid for every bounce of every lane). The camera
        segment runs in it too: one copy of a segment's code, half the kernel to compile."""

        def body(path, sampler):
            self.bounce(scene, sampler, path)
            return path, sampler

        path, _ = dr.while_loop(
            (path, sampler), lambda path, sampler: path.active, body, label="haze_path"
        )
        return path

    # -- a surface --------------------------------------------------------------------------
    def shade(self, scene: Any, sampler: Any, p: HazePath, si: Any) -> None:
        """Light path ``p``'s surface ``si`` and turn the path along a BSDF sample: one
        emitter sample from the sun and one from the sky (not one from sunsky's mixture of
        both), each level attenuated toward the emitter, and the aureole."""
        levels = self.levels
        levels.follow_segment(mi.Bool(False))  # what leaves a surface sees the haze around it
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
            mis_e = mis_weight(ds_e.pdf, self.glint.continuation_pdf(share, bsdf_pdf, ds_e.d))
            direct = dr.select(drawn, p.beta * value * em_w * mis_e, 0.0)
            _, e_length = levels.light_segment(si.p, ds_e.d)
            if sun is not None:
                # Where nothing was drawn the sky's direction may be NaN (its sampler at the
                # ends of its erfinv): its transmittance would make 0 · NaN = NaN.
                e_length = dr.select(drawn, e_length, 0.0)
            toward = [levels.transmittance(k, e_length) for k in range(self.n_levels)]
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


class CameraPass(HazeIntegrator):
    """The main ``physical`` pass: camera paths for the clean image and every level."""

    def sample(self, scene, sampler, ray, medium=None, active=True):
        with self.camera_path(ray, mi.Bool(active)):
            path = HazePath.start(mi.Ray3f(ray), mi.Bool(active), self.n_levels, self.grey)
            path = self.follow(scene, sampler, path)
        aovs = [c for r in path.res for c in (r.x, r.y, r.z)]
        return mi.Spectrum(path.clean), mi.Bool(True), aovs
