"""Haze in front of a vessel: the light a vessel sends into the haze the camera looks through.

The ``physical`` mode's diffuse tables hold the field of the open sea (no vessel stands in
it). With a forward-peaked phase function most of the light a point of haze scatters toward the
camera comes from close to the direction the camera looks; just in front of a vessel that is
the vessel, not the open haze and sky it hides. A shaded hull seen toward the sun is then
darker than the open-sea field makes it, a sunlit white hull brighter. It is the adjacency
effect of remote sensing, where the light of neighbouring ground is scattered into the line of
sight (Tanré, Herman & Deschamps 1981, *Applied Optics* 20, 3676).

:class:`VesselLightPass` is the correction, an integrator of its own on the ``physical``
passes' shared base (:class:`seahaze.render.haze_integrator.HazeIntegrator`). Import this
module once a Mitsuba variant is set, as that one. Its probes are
drawn near the vessels and aimed at them (each strategy mixed with the plain one by the balance
heuristic), because most probes from the phase function alone miss every vessel and the few
that meet a sunlit hull speckle the sky; :mod:`seahaze.render.physical` then smooths the pass
within each segment of the image (:mod:`seahaze.render.segment_smooth`). The estimator, what
it leaves out and why a separate pass are in docs/physics.md, "Haze in front of a vessel".
Units: metres, radiance in the scene's units, extinction in 1/m.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import drjit as dr
import mitsuba as mi
import numpy as np

from . import jit_haze
from .haze_integrator import HazeIntegrator
from .haze_path import HazePath


class VesselLightPass(HazeIntegrator):
    """The vessel-light pass: each level's correction for the light the vessels send into the
    haze in front of them (see the module docstring; its clean radiance is 0). Built from the
    shared base's pieces: the lights and shading at the vessel, and the open-sea segment the
    tables assumed (:meth:`open_sea_bounce`)."""

    def __init__(self, *args: Any, **kwargs: Any):
        """As :class:`~seahaze.render.haze_integrator.HazeIntegrator`; the vessels are set
        with :meth:`set_vessels`."""
        super().__init__(*args, **kwargs)
        self.set_vessels(0, np.zeros((0, 4)))

    def set_vessels(self, sea_id: int, spheres: np.ndarray) -> None:
        """The registry id of the scene's sea shape (every other surface is a vessel, whose
        light the haze in front of it scatters: :meth:`vessel_light`) and a sphere around
        every vessel, (n, 4) centre x, y, z and radius in metres, at which probes are aimed.
        Kernel parameters, so another scene (another fleet) reuses the compiled kernel."""
        self.sea_id = dr.opaque(mi.UInt32, int(sea_id))
        rows = np.asarray(spheres, np.float64).reshape(-1, 4)
        self.count = dr.opaque(mi.UInt32, len(rows))
        # At least two rows (a one-element array would be a scalar, another kernel).
        padded = np.concatenate([rows, np.zeros((2, 4))])
        self.centre = [jit_haze.owned_floats(padded[:, axis]) for axis in range(3)]
        self.radius = jit_haze.owned_floats(padded[:, 3])

    def sample(self, scene, sampler, ray, medium=None, active=True):
        """The correction pass: :meth:`vessel_light` along the camera segment, for every
        level (no clean radiance)."""
        with self.camera_path(ray, mi.Bool(active)):
            si = scene.ray_intersect(ray, active)
            t_end = dr.select(si.is_valid(), si.t, dr.inf)
            enter, length = self.levels.segment(ray.o, ray.d, t_end)
            res = [dr.zeros(mi.Color3f) for _ in range(self.n_levels)]
            self.vessel_light(scene, sampler, ray, enter, length, res, active & (length > 0.0))
        aovs = [c for r in res for c in (r.x, r.y, r.z)]
        return mi.Spectrum(0.0), mi.Bool(True), aovs

    def vessel_light(self, scene, sampler, ray, enter, length, res, active):
        """Correct the camera segment's diffuse in-scattering for the vessels: the tables'
        field is that of the open sea, but haze in front of a vessel sees the vessel.

        One point ``x`` on the segment (:meth:`probe_point`) and one direction from it
        (:meth:`probe_direction`); where that direction meets a vessel, two short
        paths leave the hit: one shading the vessel (the light that really arrives at
        ``x``), and one going on through the vessel as if it were not there, to the sea or
        the sky of the open-sea field (the light the table assumed; not the sun's disk,
        whose single scattering is computed with shadow rays). Each level gains the
        difference, weighted by its scattering at ``x`` and the phase function over the
        probe's density. With a forward-peaked phase function most of the light scattered
        toward the camera just in front of a vessel came from the vessel: a shaded hull
        against the bright haze toward the sun is darker than the open-sea field makes it
        (docs/physics.md, "Haze in front of a vessel")."""
        levels = self.levels
        s, pdf = self.probe_point(ray, enter, length, sampler, active)
        x = ray(levels.distance_at(ray, enter, s))
        d, phase_weight = self.probe_direction(x, ray.d, sampler, active)
        probe = mi.Ray3f(x, d, ray.time, ray.wavelengths)
        si = scene.ray_intersect(probe, active)
        on_vessel = active & self.is_vessel(si)
        _, to_vessel = levels.segment(probe.o, d, si.t)
        scale = levels.albedo * phase_weight / dr.maximum(pdf, 1e-30)
        start = [
            dr.select(on_vessel, levels.ext[k] * levels.transmittance(k, s + to_vessel), 0.0)
            * scale
            for k in range(self.n_levels)
        ]
        # Only one of the two paths goes on past its first vertex, each with probability ½
        # and twice the weight (unbiased): following them is most of the pass's time, and a
        # packet runs the loop while any of its lanes goes on.
        go_seen = sampler.next_1d(on_vessel) < 0.5
        end, beyond = self.past_vessels(scene, si, d, on_vessel)

        def first(seen: bool) -> HazePath:
            """The seen (at the vessel) or assumed (from it on through the open sea) path
            before its first vertex."""
            ray = probe if seen else mi.Ray3f(si.p, d)
            path = HazePath.start(ray, on_vessel, self.n_levels, self.grey)
            path.att, path.depth = list(start), mi.UInt32(1)
            return path

        vertex = _FirstVertices(si, end, beyond, go_seen)
        state = (dr.select(go_seen, first(False), first(True)), mi.UInt32(0), res, sampler)

        def body(p, step, res, sampler):
            self.probe_step(scene, sampler, p, vertex, step)
            weight = vertex.weight(step)
            # The step's light, whether or not the path goes on (it may have escaped).
            res = [r + weight * o for r, o in zip(res, p.res, strict=True)]
            p.res = [dr.zeros(mi.Color3f) for _ in range(self.n_levels)]
            # After the first path's vertex, the second path starts at its own.
            p = dr.select(step == 0, dr.select(go_seen, first(True), first(False)), p)
            return p, dr.minimum(step + 1, 2), res, sampler

        def going(p, step, res, sampler):
            return on_vessel & ((step == 0) | p.active)

        _, _, res[:], _ = dr.while_loop(state, going, body, label="vessel_light")

    def probe_point(self, ray, enter, length, sampler, active):
        """A distance ``s`` along the camera segment (from ``enter``, ``length`` long) and
        its density (1/m).

        Two strategies, one drawn per sample and weighted by the balance heuristic
        (one-sample MIS, Veach & Guibas 1995): the levels' mixture (``mixture_distance``,
        where the haze scatters), and a Cauchy density centred where the ray passes closest
        to one vessel, its width the larger of that distance and the vessel's radius
        (equiangular sampling, Kulla & Fajardo 2012, widened to the vessel's size): the
        haze close in front of a vessel, which sees it large, is where its light is
        scattered toward the camera. The vessel is drawn in proportion to
        :meth:`along_ray`'s weight."""
        levels = self.levels
        u = sampler.next_1d(active)
        # The mixture alone where no probe is drawn near a vessel (no loop over the vessels)
        # and in a medium whose reduced lengths are not lengths: the near strategy draws
        # metres from the ray's closest approach to a vessel.
        geometric = self.medium.reduced_is_geometric and self.pixel_ratio is None
        if self.settings.near_share <= 0.0 or not geometric:
            return levels.mixture_distance(u, length)
        total, chosen, u = self.draw(lambda i: self.along_ray(i, ray, enter, length)[3], u, active)
        near_share = dr.select(total > 0.0, self.settings.near_share, 0.0)
        near = u < near_share
        u = dr.select(near, u / near_share, (u - near_share) / (1.0 - near_share))
        u = dr.clip(u, 0.0, 0.99999994)
        s_mix, _ = levels.mixture_distance(u, length)
        closest, width, angles, _ = self.along_ray(chosen, ray, enter, length)
        s_near = closest + width * dr.tan(angles[0] + u * (angles[1] - angles[0]))
        s = dr.clip(dr.select(near, s_near, s_mix), 0.0, length)

        def near_density(i):
            closest, width, angles, w = self.along_ray(i, ray, enter, length)
            span = dr.maximum(angles[1] - angles[0], 1e-30)
            return w * width / (span * (width * width + dr.square(s - closest)))

        near_pdf = self.total(near_density, active) / dr.maximum(total, 1e-30)
        return s, (1.0 - near_share) * levels.mixture_density(s, length) + near_share * near_pdf

    def along_ray(self, i, ray, enter, length):
        """Vessel ``i`` seen along the camera segment: the distance from the segment's start
        where the ray passes closest to its centre, the Cauchy width (m; that closest
        distance or its radius, the larger), the angles (rad) of the segment's ends seen
        from the centre, and its weight for :meth:`probe_point`: the angle the segment
        spans (over π) times the square of radius over closest distance (1 where the ray
        goes through the sphere)."""
        centre = mi.Point3f(*(dr.gather(mi.Float, c, i) for c in self.centre))
        radius = dr.gather(mi.Float, self.radius, i)
        to = centre - ray(enter)
        closest = dr.dot(to, ray.d)
        miss = dr.sqrt(dr.maximum(dr.squared_norm(to) - closest * closest, 0.0))
        width = dr.maximum(dr.maximum(miss, radius), 1e-3)
        angles = (dr.atan(-closest / width), dr.atan((length - closest) / width))
        reach = dr.square(radius / width)
        w = (angles[1] - angles[0]) / dr.pi * reach
        return closest, width, angles, dr.select(radius > 0.0, w, 0.0)

    def probe_direction(self, x, ray_d, sampler, active):
        """A probe direction from ``x`` and the phase function toward the camera over its
        density (``f(ω)/p(ω)``, 1/sr over 1/sr).

        Two strategies, one drawn per sample and weighted by the balance heuristic: the
        phase function around the ray ``ray_d``, and a direction uniform in the cone of one
        vessel's bounding sphere, drawn in proportion to :meth:`cone`'s weight."""
        g = self.levels.g
        u_pick = sampler.next_1d(active)
        u = sampler.next_2d(active)
        cos_hg = jit_haze.hg_sample_cos(u.x, g)
        around = (ray_d.x, ray_d.y, ray_d.z)
        phased = mi.Vector3f(*jit_haze.rotate_directions(around, cos_hg, 2.0 * dr.pi * u.y))
        if self.settings.aim_share <= 0.0:  # the phase function alone: its own density, no loop
            return phased, mi.Float(1.0)
        total, chosen, u_pick = self.draw(lambda i: self.cone(i, x, ray_d)[2], u_pick, active)
        aim_share = dr.select(total > 0.0, self.settings.aim_share, 0.0)
        aimed = u_pick < aim_share
        axis, one_minus, _ = self.cone(chosen, x, ray_d)
        m = u.x * one_minus
        sin_t = dr.sqrt(dr.maximum(m * (2.0 - m), 0.0))
        sin_p, cos_p = dr.sincos(2.0 * dr.pi * u.y)
        toward = mi.Frame3f(axis).to_world(mi.Vector3f(sin_t * cos_p, sin_t * sin_p, 1.0 - m))
        d = dr.select(aimed, toward, phased)
        phase = jit_haze.hg_phase(dr.dot(d, ray_d), g)

        def aimed_density(i):
            axis, one_minus, w = self.cone(i, x, ray_d)
            # 1 − cos between d and the axis as half the squared chord: exact for small cones.
            within = 0.5 * dr.squared_norm(d - axis) <= one_minus
            return dr.select(within, w / (2.0 * dr.pi * one_minus), 0.0)

        aim_pdf = self.total(aimed_density, active) / dr.maximum(total, 1e-30)
        density = (1.0 - aim_share) * phase + aim_share * aim_pdf
        return d, phase / dr.maximum(density, 1e-30)

    def cone(self, i, x, ray_d):
        """Vessel ``i``'s bounding sphere seen from ``x``: the unit direction to its centre,
        ``1 − cos`` of the cone's half-angle (2 from inside the sphere: every direction), and
        its weight for :meth:`probe_direction`, solid angle (sr) times the phase function
        (1/sr) at the cone's edge nearest the camera ray ``ray_d`` (its axis, where the ray is
        inside the cone)."""
        centre = mi.Point3f(*(dr.gather(mi.Float, c, i) for c in self.centre))
        radius = dr.gather(mi.Float, self.radius, i)
        to = centre - x
        dist2 = dr.maximum(dr.squared_norm(to), 1e-12)
        axis = to * dr.rsqrt(dist2)
        sin2 = radius * radius / dist2
        inside = sin2 >= 1.0
        cos_a = dr.sqrt(dr.maximum(1.0 - sin2, 0.0))
        # 1 − cos α as sin²α / (1 + cos α): no float32 cancellation for a distant hull.
        one_minus = dr.select(inside, 2.0, sin2 / (1.0 + cos_a))
        cos_t = dr.dot(axis, ray_d)
        sin_t = dr.sqrt(dr.maximum(1.0 - cos_t * cos_t, 0.0))
        sin_a = dr.sqrt(dr.minimum(sin2, 1.0))
        edge = dr.select(inside | (cos_t >= cos_a), 1.0, cos_t * cos_a + sin_t * sin_a)
        weight = 2.0 * dr.pi * one_minus * jit_haze.hg_phase(edge, self.levels.g)
        return axis, one_minus, dr.select(radius > 0.0, weight, 0.0)

    def draw(self, weigh, u, active):
        """The total of ``weigh(i)`` over the vessels, one vessel drawn in proportion to it,
        and ``u`` rescaled to [0, 1). One pass: each vessel replaces the choice with its
        share of the weight so far, and ``u`` is rescaled within the branch it took, so one
        number serves the draw and the next decision."""

        def body(i, total, chosen, u):
            w = weigh(i)
            total = total + w
            share = dr.select(total > 0.0, w / total, 0.0)
            take = u < share
            chosen = dr.select(take, i, chosen)
            u = dr.select(take, u / share, (u - share) / dr.maximum(1.0 - share, 1e-30))
            return i + 1, total, chosen, dr.clip(u, 0.0, 0.99999994)

        start = (mi.UInt32(0), mi.Float(0.0), mi.UInt32(0), mi.Float(u))
        _, total, chosen, u = dr.while_loop(
            start, lambda i, total, chosen, u: active & (i < self.count), body
        )
        return total, chosen, u

    def total(self, term, active):
        """The sum of ``term(i)`` over the vessels."""
        _, total = dr.while_loop(
            (mi.UInt32(0), mi.Float(0.0)),
            lambda i, total: active & (i < self.count),
            lambda i, total: (i + 1, total + term(i)),
        )
        return total

    def is_vessel(self, si):
        """Whether ``si`` lies on a vessel (a valid hit that is not the sea)."""
        return si.is_valid() & (dr.reinterpret_array(mi.UInt32, si.shape) != self.sea_id)

    def past_vessels(self, scene, si, d, active):
        """The first surface along ``d`` beyond ``si`` that is not a vessel (the sea, or
        nothing) and its distance from ``si``: the open sea behind a vessel."""

        def body(o, t, going, count):
            nxt = scene.ray_intersect(mi.Ray3f(o, d), going)
            through = going & self.is_vessel(nxt)
            t = dr.select(through, t + nxt.t, t)
            o = dr.select(through, nxt.spawn_ray(d).o, o)
            return o, t, through & (count < 15), count + 1

        start = (si.spawn_ray(d).o, mi.Float(0.0), mi.Bool(active), mi.UInt32(0))
        o, t, _, _ = dr.while_loop(start, lambda o, t, going, count: going, body)
        end = scene.ray_intersect(mi.Ray3f(o, d), active)
        return end, dr.select(end.is_valid(), t + end.t, dr.inf)

    def probe_step(self, scene, sampler, p: HazePath, vertex: _FirstVertices, step) -> None:
        """One step of :meth:`vessel_light`'s loop for path ``p``: at ``step`` 0 and 1 the
        first vertices of the seen and the assumed path (in the order :class:`_FirstVertices`
        gives), then the continued path's later segments as the main pass's
        :meth:`~seahaze.render.haze_integrator.HazeIntegrator.bounce`. The seen path's first
        vertex is the vessel itself (no haze before it: the probe's weight holds it); the
        assumed path's runs through the open sea's haze that the tables assumed, to the first
        surface that is not a vessel, with no surface shading the sun and not the sun's disk
        as its light (its single scattering is computed with shadow rays)."""
        seen, assumed = vertex.seen_at(step), vertex.assumed_at(step)
        later = p.active & (step >= 2)
        traced = scene.ray_intersect(p.ray, later)
        si = dr.select(seen, vertex.vessel, dr.select(assumed, vertex.open_sea, traced))
        t_end = dr.select(traced.is_valid(), traced.t, dr.inf)
        t_end = dr.select(seen, 0.0, dr.select(assumed, vertex.open_sea_t, t_end))
        segment, along = self.haze_along(sampler, p, t_end, mi.UInt32(1))
        along.lit &= later
        self.shadow_correction(scene, sampler, along, p.att, p.res)
        sun = self.sun_seen(si, p)
        self.escape(scene, p, si, segment, dr.select(later, sun, 0.0))
        self.turn(scene, sampler, p, si)


@dataclass
class _FirstVertices:
    """Where :meth:`VesselLightPass.vessel_light`'s two paths meet their first surface, and
    in which order its loop takes them: the one that stops after its first vertex first."""

    vessel: Any
    """The vessel the probe met: the seen path's first vertex."""
    open_sea: Any
    """The first surface beyond it that is not a vessel (or none: the sky): the assumed
    path's."""
    open_sea_t: Any
    """Its distance from the vessel (m; ``inf``: the sky)."""
    go_seen: Any
    """Whether the seen path goes on past its first vertex (else the assumed one)."""

    def seen_at(self, step: Any) -> Any:
        return ((step == 0) & ~self.go_seen) | ((step == 1) & self.go_seen)

    def assumed_at(self, step: Any) -> Any:
        return ((step == 0) & self.go_seen) | ((step == 1) & ~self.go_seen)

    def weight(self, step: Any) -> Any:
        """What step ``step``'s light counts for: +1 at the seen vertex, −1 at the assumed
        one, then ±2 for the continued path (the seen one's + or the assumed one's −)."""
        sign = dr.select(self.seen_at(step) | ((step >= 2) & self.go_seen), 1.0, -1.0)
        return dr.select(step >= 2, 2.0 * sign, sign)
