"""The ``physical`` haze mode: a Mitsuba integrator made for one homogeneous haze slab.

What a camera path collects, segment by segment (a segment runs from the camera or a surface to
the next surface or out to the sky):

* **Transmittance** over the segment's part inside the slab, analytic: ``exp(−σ ℓ)``.
* **In-scattering** along that part, by one distance sample drawn in proportion to the
  transmittance (so the estimator weight ``∫T ds = (1 − e^{−σℓ})/σ`` is exact and noise comes only
  from the integrand). At the sampled point:

  - *single scattering* of the sun and sky: a direction from the scene's emitter sampling, a
    shadow ray against the vessels and the sea, the analytic transmittance of the slab toward
    the emitter, and the Henyey–Greenstein phase function — no all-or-nothing transmittance
    estimate, which is what makes ``volpath`` so noisy (docs/physics.md);
  - the *diffuse field* (multiply scattered and sea-reflected light) looked up in a table of
    height × direction computed once per level (:mod:`seahaze.render.diffuse_table`).

* **Surfaces** (sea, vessels) are shaded as Mitsuba's ``path`` does — emitter sampling and BSDF
  sampling with multiple importance sampling — except that light from the emitter is attenuated
  by the slab analytically; the BSDF-sampled ray becomes the next segment, so reflections of
  the hazy sky and of vessels in the sea come out naturally.

Light never scatters into a new direction inside the medium on the camera path: all of that is
in the table, which is what keeps the cost near a clean render. The integrator's inputs that
change per level (``σ``, albedo, ``g``, the table) are drjit variables, not literals, so the
kernel is compiled once per scene size and reused at every level.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..haze import HAZE_BOTTOM_M, Extinction, extinction_rgb
from ..spec import SceneSpec
from . import jit_haze
from .diffuse_table import DEFAULT_GRID, DiffuseTable, TableGrid, build_diffuse_table
from .passes import render_radiance
from .scene import LoadedScene, sunsky_dict

DEFAULT_BOUNCES = 3
"""Surface interactions per camera path: sea → sky, vessel → sea → sky. Measured on the
default scene at V = 1000 m, 6 instead of 3 changes the mean by < 0.05 %; 1 loses 0.15 %."""
TABLE_PHOTONS = 1 << 17
"""Photons per level table (half from the sun, half from the sky): ~1 % noise per table bin."""
CAMERA_POINTS = 2
"""Stratified in-scattering points on the camera segment. 2 instead of 1 cuts the per-pixel
noise by a fifth for ~10 % more time; 4 gains little more (default scene, 320×180)."""


def _mi():
    import mitsuba as mi

    return mi


def emitter_photons(
    emitter: Any, count: int, seed: int, top_m: float
) -> tuple[np.ndarray, np.ndarray]:
    """Downward travel directions (n, 3) and horizontal-irradiance weights (n, 3) of photons
    from ``emitter``, sampled with Mitsuba's own emitter sampling."""
    import drjit as dr

    mi = _mi()
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(seed, count)
    it = dr.zeros(mi.Interaction3f, count)
    it.p = mi.Point3f(0.0, 0.0, top_m + 1.0)
    it.t = 0.0
    ds, weight = emitter.sample_direction(it, sampler.next_2d())
    d = np.stack([np.array(ds.d.x), np.array(ds.d.y), np.array(ds.d.z)], axis=1).astype(np.float64)
    w = np.stack([np.array(weight[i]) for i in range(3)], axis=1).astype(np.float64)
    cos_up = np.maximum(d[:, 2], 0.0)
    return -d, w * cos_up[:, None] / count


class SeaReflector:
    """Reflects photons off the flat sea with the sea's own Mitsuba BSDF, pre-sampled.

    Calling Mitsuba for every flight would cost a kernel launch and a copy each time, so the
    BSDF is sampled once (importance transport, as photons travel from the light) for
    ``n_mu`` incidence angles × ``per_bin`` samples in the plane of incidence. A photon then takes
    a random pre-drawn outgoing direction of its incidence bin, rotated to its own azimuth —
    exact for an isotropic BSDF up to the binning of the incidence angle.
    """

    def __init__(self, bsdf: Any, n_mu: int = 64, per_bin: int = 1024, seed: int = 0):
        import drjit as dr

        mi = _mi()
        self.n_mu, self.per_bin = n_mu, per_bin
        n = n_mu * per_bin
        cos_in = np.repeat((np.arange(n_mu) + 0.5) / n_mu, per_bin)
        sin_in = np.sqrt(1.0 - cos_in**2)
        # Travel direction (sin, 0, -cos): the photon arrives from the -x side, going down.
        si = dr.zeros(mi.SurfaceInteraction3f, n)
        si.n = mi.Normal3f(0.0, 0.0, 1.0)
        si.sh_frame = mi.Frame3f(mi.Vector3f(1, 0, 0), mi.Vector3f(0, 1, 0), mi.Vector3f(0, 0, 1))
        si.t = 0.0
        si.wi = mi.Vector3f(-sin_in, 0.0, cos_in)
        u = np.random.default_rng(seed).random((n, 3))
        ctx = mi.BSDFContext(mi.TransportMode.Importance)
        bs, weight = bsdf.sample(ctx, si, mi.Float(u[:, 0]), mi.Point2f(u[:, 1], u[:, 2]))
        wo = np.stack([np.array(bs.wo.x), np.array(bs.wo.y), np.array(bs.wo.z)], axis=1)
        w = np.stack([np.array(weight[i]) for i in range(3)], axis=1).astype(np.float64)
        w[~np.isfinite(w) | (wo[:, 2] <= 0.0)[:, None].repeat(3, axis=1)] = 0.0
        wo[:, 2] = np.maximum(wo[:, 2], 1e-6)
        self.wo = (wo / np.linalg.norm(wo, axis=1, keepdims=True)).reshape(n_mu, per_bin, 3)
        self.weight = w.reshape(n_mu, per_bin, 3)

    def __call__(self, d: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """Reflected travel directions and RGB weights for downward travel directions ``d``."""
        n = len(d)
        mu_bin = np.clip((-d[:, 2] * self.n_mu).astype(np.int64), 0, self.n_mu - 1)
        pick = rng.integers(0, self.per_bin, n)
        wo = self.wo[mu_bin, pick]
        azimuth = np.arctan2(d[:, 1], d[:, 0])
        c, s = np.cos(azimuth), np.sin(azimuth)
        out = np.stack([c * wo[:, 0] - s * wo[:, 1], s * wo[:, 0] + c * wo[:, 1], wo[:, 2]], axis=1)
        return out, self.weight[mu_bin, pick]


def _sea_bsdf(scene: Any) -> Any:
    for shape in scene.shapes():
        if shape.id() == "sea":
            return shape.bsdf()
    raise ValueError("the scene has no shape with id 'sea'")


def _mis(pdf_a: Any, pdf_b: Any) -> Any:
    """Power heuristic (β = 2) weight of strategy ``a``."""
    import drjit as dr

    a2 = pdf_a * pdf_a
    return dr.detach(dr.select(pdf_a > 0, a2 / (a2 + pdf_b * pdf_b), 0.0))


def make_integrator(
    sun: Any,
    bounces: int = DEFAULT_BOUNCES,
    top_m: float = 300.0,
    camera_points: int = CAMERA_POINTS,
) -> Any:
    """A new haze integrator instance (class defined lazily: it needs a Mitsuba variant).

    ``sun`` is the emitter whose single scattering is computed with shadow rays (the sun part
    of the scene's ``sunsky``); everything else scattered in the haze comes from the table.
    """
    import drjit as dr

    mi = _mi()

    class HazeIntegrator(mi.SamplingIntegrator):
        """Camera paths through one homogeneous slab with analytic transmittance."""

        def __init__(self, props: Any):
            super().__init__(props)
            self.bounces = bounces
            self.camera_points = camera_points
            self.sun = sun
            self.top = top_m
            self.bottom = HAZE_BOTTOM_M
            self.sigma = mi.Color3f(0.0)
            self.albedo = mi.Float(1.0)
            self.g = mi.Float(0.0)
            self.table = mi.Texture3f(
                mi.TensorXf(np.zeros((2, 2, 2, 3), np.float32)),
                use_accel=False,
                filter_mode=dr.FilterMode.Linear,
                wrap_mode=dr.WrapMode.Clamp,
            )
            self.sun_azimuth = mi.Float(0.0)

        def set_level(
            self, sigma: np.ndarray, albedo: float, g: float, table: DiffuseTable
        ) -> None:
            """Point the integrator at a level without changing its compiled kernel; ``sigma``
            is the (R, G, B) extinction in 1/m."""
            self.sigma = mi.Color3f(*(dr.opaque(mi.Float, float(c)) for c in sigma))
            self.albedo = dr.opaque(mi.Float, albedo)
            self.g = dr.opaque(mi.Float, g)
            self.sun_azimuth = dr.opaque(mi.Float, table.sun_azimuth_rad)
            values = mi.TensorXf(np.ascontiguousarray(table.values))
            if self.table.shape == values.shape:
                self.table.set_tensor(values)
            else:
                self.table = mi.Texture3f(
                    values,
                    use_accel=False,
                    filter_mode=dr.FilterMode.Linear,
                    wrap_mode=dr.WrapMode.Clamp,
                )

        # -- slab helpers ---------------------------------------------------------------
        def slab(self, oz: Any, dz: Any) -> tuple[Any, Any]:
            """``[enter, leave]`` ray parameters inside the slab (enter ≥ 0)."""
            return jit_haze.slab_interval(oz, dz, self.bottom, self.top)

        def transmittance_to_infinity(self, p: Any, d: Any) -> Any:
            enter, leave = self.slab(p.z, d.z)
            length = dr.maximum(leave - enter, 0.0)
            return dr.exp(-self.sigma * length)

        def phase(self, cos_theta: Any) -> Any:
            return jit_haze.hg_phase(cos_theta, self.g)

        def diffuse(self, z: Any, travel: Any) -> Any:
            """Table lookup of the diffuse in-scattering toward travel direction ``travel``."""
            phi = dr.atan2(travel.y, travel.x) - self.sun_azimuth
            phi = dr.abs(dr.atan2(dr.sin(phi), dr.cos(phi)))
            pos = mi.Point3f(phi / dr.pi, (travel.z + 1.0) * 0.5, z / self.top)
            value = self.table.eval(pos)
            return mi.Color3f(value[0], value[1], value[2])

        def inscatter(self, scene, sampler, x, ray, sigma_s, active):
            """Radiance scattered toward ``-ray.d`` per metre at ``x``: single + diffuse."""
            it = dr.zeros(mi.Interaction3f)
            it.p = x
            it.t = 0.0
            it.time = ray.time
            it.wavelengths = ray.wavelengths
            ds, em_weight = self.sun.sample_direction(it, sampler.next_2d(active), active)
            shadow = mi.Ray3f(x, ds.d, ray.time, ray.wavelengths)
            visible = active & (ds.pdf > 0) & ~scene.ray_test(shadow, active)
            phase = self.phase(dr.dot(ds.d, ray.d))
            single = em_weight * phase * self.transmittance_to_infinity(x, ds.d)
            return sigma_s * dr.select(visible, single, 0.0) + self.diffuse(x.z, -ray.d)

        # -- the path ---------------------------------------------------------------------
        def sample(self, scene, sampler, ray, medium=None, active=True):
            ray = mi.Ray3f(ray)
            active = mi.Bool(active)
            result = mi.Color3f(0.0)
            beta = mi.Color3f(1.0)
            prev_si = dr.zeros(mi.SurfaceInteraction3f)
            prev_pdf = mi.Float(1.0)
            prev_delta = mi.Bool(True)
            sigma = self.sigma
            sigma_s = self.albedo * sigma
            # Distances are sampled in green (the channel nearest 550 nm); the other channels
            # are reweighted by exp(-(σ_c - σ_g) s), which is 1 for grey haze.
            sigma_g = sigma.y
            ctx = mi.BSDFContext()

            for depth in range(self.bounces + 1):
                si = scene.ray_intersect(ray, active)
                hit = active & si.is_valid()
                t_end = dr.select(si.is_valid(), si.t, dr.inf)
                enter, leave = self.slab(ray.o.z, ray.d.z)
                length = dr.maximum(dr.minimum(leave, t_end) - enter, 0.0)
                transmittance = dr.exp(-sigma * length)
                tau = sigma_g * length
                in_medium = active & (length > 0.0) & (sigma_g > 0.0)

                # In-scattering along the segment: distances ∝ green transmittance, stratified,
                # several on the camera segment where most of the haze is seen.
                one_minus = dr.select(tau < 1e-3, tau * (1.0 - 0.5 * tau), 1.0 - dr.exp(-tau))
                integral = dr.select(
                    tau < 1e-3, length * (1.0 - 0.5 * tau), one_minus / dr.maximum(sigma_g, 1e-30)
                )
                n_points = self.camera_points if depth == 0 else 1
                for k in range(n_points):
                    u = (k + sampler.next_1d(in_medium)) / n_points
                    depth_in = -dr.log(dr.maximum(1.0 - u * one_minus, 1e-30)) / dr.maximum(
                        sigma_g, 1e-30
                    )
                    x = ray(dr.minimum(enter + depth_in, enter + length))
                    inscatter = self.inscatter(scene, sampler, x, ray, sigma_s, in_medium)
                    weight = (integral / n_points) * dr.exp(-(sigma - sigma_g) * depth_in)
                    result += dr.select(in_medium, beta * weight * inscatter, 0.0)

                # The sky (or sun) at the end of an escaping segment, with MIS against the
                # emitter sampling of the surface it left.
                escaped = active & ~si.is_valid()
                emitter = si.emitter(scene, escaped)
                ds_hit = mi.DirectionSample3f(scene, si, prev_si)
                em_pdf = scene.pdf_emitter_direction(prev_si, ds_hit, escaped & ~prev_delta)
                mis_hit = dr.select(prev_delta, 1.0, _mis(prev_pdf, em_pdf))
                le = emitter.eval(si, escaped)
                result += dr.select(escaped, beta * transmittance * le * mis_hit, 0.0)

                if depth == self.bounces:
                    break
                active = hit
                beta *= transmittance

                # Surface: emitter sampling with the slab's transmittance toward the emitter.
                bsdf = si.bsdf(ray)
                smooth = active & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)
                ds_e, em_w = scene.sample_emitter_direction(
                    si, sampler.next_2d(smooth), True, smooth
                )
                wo = si.to_local(ds_e.d)
                value, bsdf_pdf = bsdf.eval_pdf(ctx, si, wo, smooth)
                mis_e = dr.select(ds_e.delta, 1.0, _mis(ds_e.pdf, bsdf_pdf))
                t_e = self.transmittance_to_infinity(si.p, ds_e.d)
                result += dr.select(smooth & (ds_e.pdf > 0), beta * value * em_w * t_e * mis_e, 0.0)

                # Continue along a BSDF sample.
                bs, bsdf_weight = bsdf.sample(
                    ctx, si, sampler.next_1d(active), sampler.next_2d(active), active
                )
                beta *= bsdf_weight
                active &= dr.any(beta != 0.0)
                prev_si = dr.select(active, si, prev_si)
                prev_pdf = dr.select(active, bs.pdf, prev_pdf)
                prev_delta = dr.select(
                    active, mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta), prev_delta
                )
                ray = si.spawn_ray(si.to_world(bs.wo))

            return mi.Spectrum(result), mi.Bool(True), []

        def aov_names(self):
            return []

        def to_string(self):
            return f"HazeIntegrator[bounces={self.bounces}, top={self.top}]"

    return HazeIntegrator(mi.Properties())


@dataclass
class PhysicalLevel:
    """What one ``physical`` level produced besides its radiance."""

    table: DiffuseTable
    table_seconds: float


class PhysicalRenderer:
    """Renders hazy levels of one loaded scene; the integrator (and its kernel) is reused."""

    def __init__(
        self,
        loaded: LoadedScene,
        spec: SceneSpec,
        bounces: int = DEFAULT_BOUNCES,
        photons: int = TABLE_PHOTONS,
    ):
        mi = _mi()
        self.loaded = loaded
        # The sun and the sky as separate emitters: the sun's single scattering is computed
        # per pixel with shadow rays, the sky's goes into the table.
        self.sun = mi.load_dict(sunsky_dict(spec, sky=False))
        self.sky = mi.load_dict(sunsky_dict(spec, sun=False))
        self.sun_azimuth_rad = math.radians(spec.sun.azimuth_deg)
        self.integrator = make_integrator(self.sun, bounces, loaded.haze_top_m)
        self.photons = photons
        self._reflect = SeaReflector(_sea_bsdf(loaded.scene))

    def table(
        self,
        sigma: Extinction,
        albedo: float,
        g: float,
        seed: int,
        grid: TableGrid = DEFAULT_GRID,
    ) -> DiffuseTable:
        """The diffuse-field table of one level; ``sigma`` (1/m) grey or per channel (R, G, B).

        Channels of different extinction get a table each, from the same photons (so their
        noise is correlated and the table's colour stays smooth); a grey level needs one.
        """
        rgb = extinction_rgb(sigma)
        top = self.loaded.haze_top_m
        half = self.photons // 2
        sun = emitter_photons(self.sun, half, seed, top)
        sky = emitter_photons(self.sky, half, seed + 1, top)
        tables = {
            value: build_diffuse_table(
                sun, sky, self._reflect, value, albedo, g, top, self.sun_azimuth_rad, seed, grid
            )
            for value in dict.fromkeys(float(c) for c in rgb)
        }
        if len(tables) == 1:
            return next(iter(tables.values()))
        per_channel = [tables[float(c)] for c in rgb]
        values = np.stack([t.values[..., c] for c, t in enumerate(per_channel)], axis=-1)
        return replace(
            per_channel[1],
            values=values,
            flights=max(t.flights for t in per_channel),
        )

    def render(
        self, sigma: Extinction, albedo: float, g: float, spp: int, seed: int
    ) -> tuple[np.ndarray, PhysicalLevel]:
        """Linear RGB radiance (H, W, 3) of one level; ``sigma`` as in :meth:`table`."""
        import time

        start = time.perf_counter()
        table = self.table(sigma, albedo, g, seed)
        table_seconds = time.perf_counter() - start
        self.integrator.set_level(extinction_rgb(sigma), albedo, g, table)
        radiance = render_radiance(self.loaded, spp, seed, integrator=self.integrator)
        return radiance, PhysicalLevel(table, table_seconds)
