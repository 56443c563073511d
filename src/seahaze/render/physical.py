"""The ``physical`` haze mode: seahaze's own renderer for one homogeneous haze slab.

One render pass gives the clean image and every hazy level from the same camera paths
(:mod:`seahaze.render.haze_integrator`); the light scattered more than once, the skylight and
the sea-reflected light come from per-level tables of the slab's diffuse field, traced for all
levels at once (:mod:`seahaze.render.diffuse_table`). This module gathers what both need from
the scene: the sun and sky as separate emitters, the sea's BSDF pre-sampled for photons, and
the passes, grouped so that a long list of levels never needs one huge film.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..haze import Extinction, extinction_rgb
from ..ocean.whitecaps import FOAM_REFLECTANCE
from ..seeds import RenderPass, render_seed
from ..spec import SceneSpec
from .diffuse_table import DEFAULT_GRID, TableGrid, build_tables
from .glint_lobe import GLINT_SHARE
from .haze_integrator import DEFAULT_BOUNCES, make_integrator
from .jit_haze import owned_floats
from .passes import GeometryPass, render_geometry, render_radiance
from .photon_tracer import SeaReflectance
from .scene import SEA_SHAPE, LoadedScene, stratified_spp, sunsky_dict
from .segment_smooth import segments, smooth_within_segments

MIN_TABLE_PHOTONS = 1 << 17
"""Fewest photons per level table (half from the sun, half from the sky)."""
MAX_TABLE_PHOTONS = 1 << 20
"""Most photons per level table: ~4 s for eleven tables on this project's 2-vCPU machine."""
SAMPLES_PER_PHOTON = 32
"""Camera samples (pixels × spp) per table photon, before rounding and the bounds above."""
VESSEL_LIGHT_SHARE = 1 / 14
"""The vessel-light pass's samples per pixel as a share of the main pass's, rounded up (0
leaves the pass out, for comparisons). The pass corrects the haze in front of vessels, which
the open-sea tables light as if no vessel stood there (shaded hulls toward the sun +7.8 %
without it; docs/physics.md, "Haze in front of a vessel"). A fourteenth (3 spp for 42 and
for 32), its probes drawn near and aimed at the vessels and smoothed over
:data:`VESSEL_LIGHT_RADIUS_PX`, leaves no speckle at 100 % zoom (docs/benchmarks.md, "The
vessel-light pass's noise"); 4 spp smoothed over 4 pixels looked the same but cost the
12-image set 3.1× Mitsuba's clean pass, over the 3× it must stay under."""
VESSEL_LIGHT_RADIUS_PX = 6
"""Radius (pixels) of the box filter the vessel-light pass is smoothed with, within each
segment of the image (:mod:`seahaze.render.segment_smooth`): 13 × 13 pixels, its noise
divided by about 13; its bias is in docs/benchmarks.md, "The vessel-light pass's noise"."""
MAX_LEVELS_PER_PASS = 12
"""Most levels one pass renders (its kernel's size grows with the count)."""
FILM_BUDGET_BYTES = 2 << 30
"""Most memory the film of one pass may take; more levels are rendered in several passes,
each from the same camera paths."""


def _mi():
    import mitsuba as mi

    return mi


def table_photons(samples: int) -> int:
    """Photons per level table for a pass of ``samples`` camera samples (pixels × spp): one
    per :data:`SAMPLES_PER_PHOTON` samples, rounded to a power of two and held within
    [:data:`MIN_TABLE_PHOTONS`, :data:`MAX_TABLE_PHOTONS`].

    A table's noise does not average out over pixels: it moves a level's whole brightness. On
    the benchmark scene the region means of a level varied between table seeds by 2.7 % (1σ,
    sea at V = 300 m) with 2^17 photons and by 0.4 % with 2^20 (docs/benchmarks.md, "The
    diffuse tables' noise"). A photon traced through eleven levels costs about nine camera
    samples of an 11-level pass, so one photon per 32 samples keeps the tables near a quarter
    of the pass at dataset size (2^20 photons at 1280×720, 42 spp) and leaves small renders
    (tests, CI regeneration, 320×180) at the floor, where their pixels' own noise is larger.
    """
    wanted = max(samples, 1) / SAMPLES_PER_PHOTON
    rounded = 1 << max(round(math.log2(wanted)), 0)
    return min(max(rounded, MIN_TABLE_PHOTONS), MAX_TABLE_PHOTONS)


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
    dr.eval(ds.d, weight)  # one kernel: read one by one, each component would be another
    d = np.stack([np.array(ds.d.x), np.array(ds.d.y), np.array(ds.d.z)], axis=1).astype(np.float64)
    w = np.stack([np.array(weight[i]) for i in range(3)], axis=1).astype(np.float64)
    cos_up = np.maximum(d[:, 2], 0.0)
    return -d, w * cos_up[:, None] / count


def sample_sea_reflectance(
    bsdf: Any,
    n_mu: int = 64,
    per_bin: int = 4096,
    seed: int = 0,
    foam_coverage: float = 0.0,
    foam_reflectance: float = FOAM_REFLECTANCE,
) -> SeaReflectance:
    """The sea's Mitsuba BSDF sampled once for photons (importance transport, as photons travel
    from the light): ``n_mu`` incidence angles × ``per_bin`` samples in the plane of incidence.

    Calling Mitsuba for every flight would cost a kernel launch and a copy each time; a photon
    instead takes a pre-drawn sample of its incidence bin, rotated to its own azimuth — exact
    for an isotropic BSDF up to the binning of the incidence angle. Every photon of the direct
    sun arrives in one bin, so that bin's samples are reused by all of them: ``per_bin`` (4096)
    keeps their sampling error on the sun's reflected light near 1.5 % of the glint's spread
    (1024 left about 3 %).

    Whitecaps: a fraction ``foam_coverage`` (``W``, 0–1) of the samples, drawn at random, are
    replaced by a Lambertian reflector of albedo ``foam_reflectance`` (cosine-distributed
    directions, weight = albedo), so a sample's expected weight is
    ``(1 - W)·water + W·foam`` — the sea as a plane seen from far (docs/ocean.md).
    """
    import drjit as dr

    mi = _mi()
    n = n_mu * per_bin
    cos_in = np.repeat((np.arange(n_mu) + 0.5) / n_mu, per_bin)
    sin_in = np.sqrt(1.0 - cos_in**2)
    # Travel direction (sin, 0, -cos): the photon arrives from the -x side, going down.
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.n = mi.Normal3f(0.0, 0.0, 1.0)
    si.sh_frame = mi.Frame3f(mi.Vector3f(1, 0, 0), mi.Vector3f(0, 1, 0), mi.Vector3f(0, 0, 1))
    si.t = 0.0
    # Every input in drjit's own memory: made from numpy, the kernel's loads (and hash) would
    # follow numpy's buffer alignment, and the kernel be compiled again in other processes.
    si.wi = mi.Vector3f(owned_floats(-sin_in), 0.0, owned_floats(cos_in))
    rng = np.random.default_rng(seed)
    u = rng.random((n, 3))
    ctx = mi.BSDFContext(mi.TransportMode.Importance)
    sample1, sample2 = (
        owned_floats(u[:, 0]),
        mi.Point2f(owned_floats(u[:, 1]), owned_floats(u[:, 2])),
    )
    bs, weight = bsdf.sample(ctx, si, sample1, sample2)
    dr.eval(bs.wo, weight)  # one kernel: read one by one, each component would be another
    wo = np.stack([np.array(bs.wo.x), np.array(bs.wo.y), np.array(bs.wo.z)], axis=1)
    w = np.stack([np.array(weight[i]) for i in range(3)], axis=1).astype(np.float64)
    w[~np.isfinite(w) | (wo[:, 2] <= 0.0)[:, None].repeat(3, axis=1)] = 0.0
    wo[:, 2] = np.maximum(wo[:, 2], 1e-6)
    wo = wo / np.linalg.norm(wo, axis=1, keepdims=True)
    if foam_coverage > 0.0:
        _mix_in_foam(wo, w, rng, foam_coverage, foam_reflectance)
    return SeaReflectance(wo.reshape(n_mu, per_bin, 3), w.reshape(n_mu, per_bin, 3))


def _mix_in_foam(
    wo: np.ndarray, w: np.ndarray, rng: np.random.Generator, coverage: float, albedo: float
) -> None:
    """Replace a random fraction ``coverage`` of the samples (in place) by cosine-distributed
    Lambertian ones of weight ``albedo`` (importance sampling makes cos/pdf = 1)."""
    foam = rng.random(len(wo)) < coverage
    r, phi = np.sqrt(rng.random(foam.sum())), 2.0 * np.pi * rng.random(foam.sum())
    wo[foam] = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1.0 - r**2)], axis=1)
    wo[foam, 2] = np.maximum(wo[foam, 2], 1e-6)
    wo[foam] /= np.linalg.norm(wo[foam], axis=1, keepdims=True)
    w[foam] = albedo


def _sea_bsdf(scene: Any) -> Any:
    for shape in scene.shapes():
        if shape.id() == "sea":
            return shape.bsdf()
    raise ValueError("the scene has no shape with id 'sea'")


@dataclass
class PhysicalPass:
    """What one physical pass produced: the clean radiance and each level's, linear RGB."""

    clean: np.ndarray
    """(H, W, 3) float32."""
    levels: list[np.ndarray]
    """(H, W, 3) float32 per level, in the order asked for."""
    table_seconds: float = 0.0


class PhysicalRenderer:
    """Renders the clean image and hazy levels of one loaded scene in shared passes; the
    integrators (and their kernels) are kept per level count and reused."""

    def __init__(
        self,
        loaded: LoadedScene,
        spec: SceneSpec,
        bounces: int = DEFAULT_BOUNCES,
        photons: int | None = None,
        glint_share: float = GLINT_SHARE,
        geometry: GeometryPass | None = None,
    ):
        """``photons``: per level table, or None for :func:`table_photons` of each pass's
        sample count. ``glint_share``: the share of a hull's next directions drawn toward the
        sea's sun glint (:mod:`~seahaze.render.glint_lobe`; 0 for BSDF sampling alone, as
        benchmarks and tests compare). ``geometry``: the scene's geometry pass, whose
        segments (sky, sea, each vessel) bound the vessel-light pass's smoothing (None:
        traced when that pass first needs it)."""
        mi = _mi()
        self.loaded = loaded
        # The sun and the sky as separate emitters: the sun's single scattering is computed
        # per pixel with shadow rays, the sky's goes into the table.
        self.sun = mi.load_dict(sunsky_dict(spec, sky=False))
        self.sky = mi.load_dict(sunsky_dict(spec, sun=False))
        self.sun_azimuth_rad = math.radians(spec.sun.azimuth_deg)
        self.wind_speed = spec.sea.wind_speed  # the width of the sun glint seen from a hull
        self.bounces, self.photons, self.glint_share = bounces, photons, glint_share
        self._sea = sample_sea_reflectance(
            _sea_bsdf(loaded.scene),
            foam_coverage=loaded.sea_foam_coverage,
            foam_reflectance=loaded.sea_foam_reflectance,
        )
        self._integrators: dict[tuple[int, bool, bool], Any] = {}
        self._geometry = geometry
        # Every surface but the sea is a vessel (scene.build_scene registers them).
        self.sea_id = next(key for key, kind in loaded.shape_ids.items() if kind == SEA_SHAPE)

    def tables(
        self,
        sigma: np.ndarray,
        albedo: float,
        g: float,
        seed: int,
        photons: int = MIN_TABLE_PHOTONS,
        grid: TableGrid = DEFAULT_GRID,
    ) -> np.ndarray:
        """The diffuse-field tables of levels with extinction ``sigma`` (L, 3) in 1/m, as one
        (n_z, n_mu, n_phi, 3L) array, from ``photons`` photons each. Each distinct extinction
        is traced once (a grey level needs one table, a per-channel one three), all from the
        same source photons."""
        top = self.loaded.haze_top_m
        half = photons // 2
        sun = emitter_photons(self.sun, half, seed, top)
        sky = emitter_photons(self.sky, half, seed + 1, top)
        distinct = list(dict.fromkeys(float(c) for c in sigma.ravel()))
        traced = build_tables(
            sun, sky, self._sea, distinct, albedo, g, top, self.sun_azimuth_rad, seed, grid
        )
        by_sigma = dict(zip(distinct, traced, strict=True))
        channels = [by_sigma[float(sigma[k, c])].values[..., c] for k, c in np.ndindex(sigma.shape)]
        return np.stack(channels, axis=-1)

    def render(
        self, sigmas: list[Extinction], albedo: float, g: float, spp: int, seed: int
    ) -> PhysicalPass:
        """The clean radiance and that of every level of extinction ``sigmas`` (1/m, grey or
        per channel R, G, B; each > 0), all from the camera paths of ``seed``.

        Levels are rendered in groups (:func:`levels_per_pass`); every group replays the same
        camera paths, so the clean image and every level share their random numbers.
        """
        import time

        sigma = np.stack([extinction_rgb(s) for s in sigmas]) if sigmas else np.zeros((0, 3))
        if np.any(sigma <= 0.0):
            raise ValueError("every hazy level needs a positive extinction")
        cam = self.loaded.camera
        start = time.perf_counter()
        photons = self.photons or table_photons(cam.width * cam.height * spp)
        tables = self.tables(sigma, albedo, g, seed, photons) if len(sigma) else None
        table_seconds = time.perf_counter() - start
        group = levels_per_pass(cam.width, cam.height, len(sigma))
        clean: np.ndarray | None = None
        levels: list[np.ndarray] = []
        for first in range(0, max(len(sigma), 1), group):
            part = slice(first, first + group)
            n = len(sigma[part])
            if n == 0:  # no hazy level: a clean pass through a one-level integrator
                n, part_sigma, part_tables = 1, np.full((1, 3), 1e-6), None
            else:
                part_sigma = sigma[part]
                part_tables = tables[..., 3 * first : 3 * (first + n)]
            grey = bool(np.all(part_sigma == part_sigma[:, 1:2]))
            integrator = self._integrator(n, grey)
            if part_tables is None:
                grid = DEFAULT_GRID
                part_tables = np.zeros((grid.n_z, grid.n_mu, grid.n_phi, 3), np.float32)
            integrator.set_levels(
                part_sigma, np.full(n, 1.0 / n), albedo, g, part_tables, self.sun_azimuth_rad
            )
            image = render_radiance(self.loaded, stratified_spp(spp), seed, integrator=integrator)
            if clean is None:
                clean = image[..., :3].copy()
            if len(sigma):
                if VESSEL_LIGHT_SHARE > 0.0:
                    image += self._vessel_light(
                        n, grey, part_sigma, albedo, g, part_tables, spp, seed
                    )
                # Light is never negative: render_radiance's gamut clip, after the correction.
                levels += [np.maximum(image[..., 3 + 3 * k : 6 + 3 * k], 0.0) for k in range(n)]
        assert clean is not None
        return PhysicalPass(clean, levels, table_seconds)

    def _vessel_light(
        self,
        n: int,
        grey: bool,
        sigma: np.ndarray,
        albedo: float,
        g: float,
        tables: np.ndarray,
        spp: int,
        seed: int,
    ) -> np.ndarray:
        """The second pass for ``n`` levels (``grey``: one extinction for R, G and B) of
        extinction ``sigma`` (L, 3) with their ``tables``: what each level gains from the light
        vessels send into the haze in front of them (:meth:`.VesselLight.vessel_light`;
        negative where a vessel is darker than the open sea and sky it hides), at
        :func:`vessel_light_spp` of ``spp``, smoothed within the image's segments (sky, sea,
        each vessel) over :data:`VESSEL_LIGHT_RADIUS_PX`."""
        integrator = self._integrator(n, grey, vessels_only=True)
        integrator.set_levels(sigma, np.full(n, 1.0 / n), albedo, g, tables, self.sun_azimuth_rad)
        integrator.vessels.set_vessels(self.sea_id, self.loaded.vessel_spheres)
        pass_seed = render_seed(seed, RenderPass.VESSEL_LIGHT)
        samples = vessel_light_spp(spp)
        image = render_radiance(self.loaded, samples, pass_seed, integrator=integrator, clip=False)
        if self._geometry is None:
            self._geometry = render_geometry(self.loaded)
        labels = segments(self._geometry.instance, self._geometry.distance_m)
        # The clean channels (the first three) are 0 in this pass: only the levels' smoothed.
        image[..., 3:] = smooth_within_segments(image[..., 3:], labels, VESSEL_LIGHT_RADIUS_PX)
        return image

    def _integrator(self, n_levels: int, grey: bool, vessels_only: bool = False) -> Any:
        key = (n_levels, grey, vessels_only)
        if key not in self._integrators:
            top = self.loaded.haze_top_m
            self._integrators[key] = make_integrator(
                self.sun,
                self.sky,
                n_levels,
                grey,
                top,
                self.bounces,
                wind_speed=self.wind_speed,
                glint_share=self.glint_share,
                vessels_only=vessels_only,
            )
        return self._integrators[key]


def vessel_light_spp(spp: int) -> int:
    """Samples per pixel of the vessel-light pass for ``spp`` of the main pass: the share
    :data:`VESSEL_LIGHT_SHARE` of them, rounded up, as the ``multijitter`` sampler takes them
    (a share of 0 leaves the pass out, for comparisons)."""
    return stratified_spp(max(1, math.ceil(spp * VESSEL_LIGHT_SHARE - 1e-9)))


def levels_per_pass(width: int, height: int, n_levels: int) -> int:
    """How many levels one pass renders: all of them up to :data:`MAX_LEVELS_PER_PASS`, fewer
    where the film (RGB, weight and 3 channels per level, float32, with a developed copy) would
    pass :data:`FILM_BUDGET_BYTES`."""
    per_level = 2 * 3 * 4 * width * height
    fit = (FILM_BUDGET_BYTES - 2 * 4 * 4 * width * height) // per_level
    return int(max(1, min(max(n_levels, 1), MAX_LEVELS_PER_PASS, fit)))
