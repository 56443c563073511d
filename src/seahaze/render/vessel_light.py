"""Haze in front of a vessel: the light a vessel sends into the haze the camera looks through.

The ``physical`` mode's diffuse tables hold the field of the open sea (no vessel stands in
it). With a forward-peaked phase function most of the light a point of haze scatters toward the
camera comes from close to the direction the camera looks; just in front of a vessel that is
the vessel, not the open haze and sky it hides. A shaded hull seen toward the sun is then
darker than the open-sea field makes it, a sunlit white hull brighter. It is the adjacency
effect of remote sensing, where the light of neighbouring ground is scattered into the line of
sight (Tanré, Herman & Deschamps 1981, *Applied Optics* 20, 3676).

:class:`VesselLight` is the correction, a helper the haze integrator
(:mod:`seahaze.render.haze_integrator`) holds and renders as a pass of its own; the estimator,
what it leaves out and why a separate pass are in docs/physics.md, "Haze in front of a vessel".
Units: metres, radiance in the scene's units, extinction in 1/m.
"""

from __future__ import annotations

from typing import Any

from . import jit_haze
from .haze_path import HazePath


class VesselLight:
    """The vessel-light pass of haze integrator ``haze``, whose slab and level helpers
    (``mixture_distance``, ``slab_length``, ``transmittance``, ``ext``, ``albedo``, ``g``) and
    path machinery (``shade``, ``bounce``, ``follow``) it uses."""

    def __init__(self, haze: Any):
        self.haze = haze
        self.set_sea(0)

    def set_sea(self, sea_id: int) -> None:
        """The registry id of the scene's sea shape: every other surface is a vessel, whose
        light the haze in front of it scatters (:meth:`vessel_light`). A kernel parameter,
        so another scene reuses the compiled kernel."""
        import drjit as dr
        import mitsuba as mi

        self.sea_id = dr.opaque(mi.UInt32, int(sea_id))

    def sample(self, scene, sampler, ray, active):
        """The correction pass: :meth:`vessel_light` along the camera segment, for every
        level (no clean radiance)."""
        import drjit as dr
        import mitsuba as mi

        si = scene.ray_intersect(ray, active)
        t_end = dr.select(si.is_valid(), si.t, dr.inf)
        enter, length = self.haze.slab_length(ray.o, ray.d, t_end)
        res = [dr.zeros(mi.Color3f) for _ in range(self.haze.n_levels)]
        self.vessel_light(scene, sampler, ray, enter, length, res, active & (length > 0.0))
        aovs = [c for r in res for c in (r.x, r.y, r.z)]
        return mi.Spectrum(0.0), mi.Bool(True), aovs

    def vessel_light(self, scene, sampler, ray, enter, length, res, active):
        """Correct the camera segment's diffuse in-scattering for the vessels: the tables'
        field is that of the open sea, but haze in front of a vessel sees the vessel.

        One point ``x`` on the segment (from the levels' mixture) and one direction from
        the phase function around the ray; where that direction meets a vessel, two short
        paths leave the hit: one shading the vessel (the light that really arrives at
        ``x``), and one going on through the vessel as if it were not there, to the sea or
        the sky of the open-sea field (the light the table assumed; not the sun's disk,
        whose single scattering is computed with shadow rays). Each level gains the
        difference, weighted by its scattering at ``x``. With a forward-peaked phase
        function most of the light scattered toward the camera just in front of a vessel
        came from the vessel: a shaded hull against the bright haze toward the sun is
        darker than the open-sea field makes it (docs/physics.md, "Haze in front of a
        vessel"; one probe per sample: two on fewer samples cost more for the same noise)."""
        import drjit as dr
        import mitsuba as mi

        haze = self.haze
        s, pdf = haze.mixture_distance(sampler.next_1d(active), length)
        cos_t = jit_haze.hg_sample_cos(sampler.next_1d(active), haze.g)
        phi = 2.0 * dr.pi * sampler.next_1d(active)
        axis = (ray.d.x, ray.d.y, ray.d.z)
        d = mi.Vector3f(*jit_haze.rotate_directions(axis, cos_t, phi))
        probe = mi.Ray3f(ray(enter + s), d, ray.time, ray.wavelengths)
        si = scene.ray_intersect(probe, active)
        on_vessel = active & self.is_vessel(si)
        _, to_vessel = haze.slab_length(probe.o, d, si.t)
        scale = haze.albedo / dr.maximum(pdf, 1e-30)
        start = [
            dr.select(on_vessel, haze.ext[k] * haze.transmittance(k, s + to_vessel), 0.0) * scale
            for k in range(haze.n_levels)
        ]

        # Once, and only for packets where a lane met a vessel (few do): a loop that a
        # packet with no active lane skips, where a masked block costs every lane.
        def body(res, pending, sampler):
            seen = HazePath.start(probe, pending, haze.n_levels, haze.grey)
            seen.att, seen.depth = list(start), mi.UInt32(1)
            haze.shade(scene, sampler, seen, si)
            seen.depth += 1
            seen = haze.follow(scene, sampler, seen)
            end, beyond = self.past_vessels(scene, si, d, pending)
            assumed = HazePath.start(mi.Ray3f(si.p, d), pending, haze.n_levels, haze.grey)
            assumed.att, assumed.depth = list(start), mi.UInt32(1)
            haze.bounce(scene, sampler, assumed, camera=False, hit=(end, beyond), free=True)
            assumed = haze.follow(scene, sampler, assumed)
            res = [
                r + dr.select(pending, a - b, 0.0)
                for r, a, b in zip(res, seen.res, assumed.res, strict=True)
            ]
            return res, mi.Bool(False), sampler

        res[:], _, _ = dr.while_loop(
            (res, on_vessel, sampler),
            lambda res, pending, sampler: pending,
            body,
            label="vessel_light",
        )

    def is_vessel(self, si):
        """Whether ``si`` lies on a vessel (a valid hit that is not the sea)."""
        import drjit as dr
        import mitsuba as mi

        return si.is_valid() & (dr.reinterpret_array(mi.UInt32, si.shape) != self.sea_id)

    def past_vessels(self, scene, si, d, active):
        """The first surface along ``d`` beyond ``si`` that is not a vessel (the sea, or
        nothing) and its distance from ``si``: the open sea behind a vessel."""
        import drjit as dr
        import mitsuba as mi

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
