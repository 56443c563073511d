"""The ``physical`` haze mode: seahaze's own renderer of a haze medium's levels.

One render pass gives the clean image and every hazy level from the same camera paths
(:class:`~seahaze.render.haze_integrator.CameraPass`); the light scattered more than once, the
skylight and the sea-reflected light come from per-level tables of the medium's diffuse field,
traced for all levels at once (:mod:`seahaze.render.diffuse_table`); a second, smaller pass
corrects the haze in front of the vessels, which the open-sea tables light as if no vessel
stood there (:class:`~seahaze.render.vessel_light.VesselLightPass`). This module gathers what
the passes need from the scene — the sun and sky as separate emitters, the sea's BSDF
pre-sampled for photons (:mod:`seahaze.render.photon_sources`), the medium — and runs them in
groups of levels, so that a long list of levels never needs one huge film. The estimator's
tuning is one :class:`~seahaze.render.estimator.EstimatorSettings`, passed in.

Haze that varies across the sea (patches, a bank) is rendered as each pixel's equivalent
profile (:mod:`seahaze.render.pixel_density`): the passes and tables see the field's vertical
profile, and each camera path scales it by its pixel's density ratio.
"""

from __future__ import annotations

import importlib
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..haze import Extinction, extinction_rgb
from ..medium import HazeMedium
from ..nonuniform import NonUniformHaze
from ..seeds import RenderPass, render_seed
from ..spec import SceneSpec
from ..world import wind_speed
from .diffuse_table import DEFAULT_GRID, UNFOLDED_GRID, TableGrid, build_tables
from .estimator import DEFAULT_SETTINGS, EstimatorSettings
from .passes import GeometryPass, render_geometry, render_radiance
from .photon_sources import emitter_photons, sample_sea_reflectance, sea_bsdf
from .pixel_density import PixelRatio, PixelRatios, pixel_ratios
from .scene import SEA_SHAPE, LoadedScene, stratified_spp
from .segment_smooth import segments, smooth_within_segments
from .sky import sun_and_sky_dicts
from .sun_disk import sun_axis

FILM_BUDGET_BYTES = 2 << 30
"""Most memory the film of one pass may take; more levels are rendered in several passes,
each from the same camera paths."""


def integrator_classes() -> tuple[type, type]:
    """The main pass's and the vessel-light pass's integrator classes for the active Mitsuba
    variant. They derive from the variant's ``SamplingIntegrator``, so their modules are
    imported once a variant is set, and imported again if the process changes variant."""
    import mitsuba as mi

    from . import haze_integrator, vessel_light

    if mi.variant() != haze_integrator.VARIANT:
        importlib.reload(haze_integrator)
        importlib.reload(vessel_light)
    return haze_integrator.CameraPass, vessel_light.VesselLightPass


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
        settings: EstimatorSettings = DEFAULT_SETTINGS,
        geometry: GeometryPass | None = None,
    ):
        """``loaded``: the scene, built without a Mitsuba medium, whose ``medium`` is the haze
        rendered; ``spec``: its spec (the sun, the sky, the sea's wind); ``settings``: the
        estimator's tuning; ``geometry``: the scene's geometry pass, whose segments (sky, sea,
        each vessel) bound the vessel-light pass's smoothing (None: traced when that pass
        first needs it)."""
        import mitsuba as mi

        self.loaded, self.settings = loaded, settings
        # Haze that varies across the sea: the passes render its vertical profile, scaled
        # per pixel (pixel_density module); the ratios are the frame's, found when rendered.
        self.field = loaded.medium if isinstance(loaded.medium, NonUniformHaze) else None
        self.medium = loaded.medium if self.field is None else self.field.profile
        self.pixel_ratio: PixelRatio | None = None
        self._ratios: dict[tuple, PixelRatios] = {}
        # A bank alone: the segments after a surface measure their own ratio through it.
        self.segments: Any = None
        if self.field is not None:
            from .segment_ratio import BankSegments  # a Mitsuba variant is set by now

            self.segments = BankSegments(self.field) if BankSegments.suits(self.field) else None
        # The sun and the sky as separate emitters: the sun's single scattering is computed
        # per pixel with shadow rays, the sky's goes into the table.
        sun, sky = sun_and_sky_dicts(spec, loaded.elapsed_s)
        self.sun, self.sky = mi.load_dict(sun), mi.load_dict(sky)
        self.sun_azimuth_rad = math.radians(spec.sun.azimuth_deg)
        # A broken-cloud sky has no mirror symmetry about the sun's vertical plane: its tables
        # span the whole circle of azimuths (folded, the clouds on one side would be averaged
        # with the sky on the other: 2-3 % too little skylight in the haze, measured).
        self.grid = UNFOLDED_GRID if spec.sky.model == "broken" else DEFAULT_GRID
        # The width of the sun glint seen from a hull: the sea's own wind (a Beaufort force
        # when the scene gives one, as the sea's spectrum and roughness take it).
        self.wind_speed = wind_speed(spec)
        self.sea = sample_sea_reflectance(
            sea_bsdf(loaded.scene),
            foam_coverage=loaded.sea_foam_coverage,
            foam_reflectance=loaded.sea_foam_reflectance,
        )
        self.integrators: dict[tuple, Any] = {}
        self.geometry = geometry
        # Every surface but the sea is a vessel (scene.build_scene registers them).
        self.sea_id = next(key for key, kind in loaded.shape_ids.items() if kind == SEA_SHAPE)

    def tables(
        self,
        sigma: np.ndarray,
        albedo: float,
        g: float,
        seed: int,
        photons: int | None = None,
        grid: TableGrid | None = None,
    ) -> np.ndarray:
        """The diffuse-field tables of levels with extinction ``sigma`` (L, 3) in 1/m of the
        medium with ``albedo`` and ``g``, as one (n_z, n_mu, n_phi, 3L) array, from
        ``photons`` photons each (None: the settings' fewest), on ``grid`` (None: the sky's,
        :attr:`grid`). Each distinct extinction is traced once (a grey level needs one table,
        a per-channel one three), all from the same source photons."""
        photons = photons or self.settings.min_table_photons
        medium = self.medium.with_optics(albedo, g)
        top = medium.top_m
        half = photons // 2
        sun = emitter_photons(self.sun, half, seed, top)
        sky = emitter_photons(self.sky, half, seed + 1, top)
        distinct = list(dict.fromkeys(float(c) for c in sigma.ravel()))
        azimuth = self.sun_azimuth_rad
        grid = grid or self.grid
        traced = build_tables(sun, sky, self.sea, distinct, medium, azimuth, seed, grid)
        by_sigma = dict(zip(distinct, traced, strict=True))
        channels = [by_sigma[float(sigma[k, c])].values[..., c] for k, c in np.ndindex(sigma.shape)]
        return np.stack(channels, axis=-1)

    def render(
        self,
        sigmas: list[Extinction],
        albedo: float,
        g: float,
        spp: int,
        seed: int,
        stage: Callable[[str], None] | None = None,
    ) -> PhysicalPass:
        """The clean radiance and that of every level of extinction ``sigmas`` (1/m, grey or
        per channel R, G, B; each > 0) of the medium with ``albedo`` and ``g``, all from the
        camera paths of ``seed``. ``stage`` is told when each step starts (tables, each
        group's camera and vessel-light passes): progress for people, nothing else.

        Levels are rendered in groups (:func:`levels_per_pass`); every group replays the same
        camera paths, so the clean image and every level share their random numbers.
        """
        sigma = np.stack([extinction_rgb(s) for s in sigmas]) if sigmas else np.zeros((0, 3))
        if np.any(sigma <= 0.0):
            raise ValueError("every hazy level needs a positive extinction")
        cam = self.loaded.camera
        start = time.perf_counter()
        say = stage or (lambda _message: None)
        photons = self.settings.photons_for(cam.width * cam.height * spp)
        if len(sigma):
            say(f"diffuse tables ({photons:,} photons)")
        tables = self.tables(sigma, albedo, g, seed, photons) if len(sigma) else None
        table_seconds = time.perf_counter() - start
        ratios = None
        if self.field is not None:
            say("pixel density ratios")
            green = sigma[:, 1] if len(sigma) else np.full(1, 1e-6)
            ratios = self.pixel_ratios(green, seed, self.settings.bank_photons_for(photons))
        sensor = self.loaded.scene.sensors()[0]
        most = self.settings.max_levels_per_pass
        group = levels_per_pass(cam.width, cam.height, len(sigma), most)
        groups = -(-max(len(sigma), 1) // group)
        clean: np.ndarray | None = None
        levels: list[np.ndarray] = []
        for first in range(0, max(len(sigma), 1), group):
            of = f" {first // group + 1}/{groups}" if groups > 1 else ""
            part = slice(first, first + group)
            n = len(sigma[part])
            if n == 0:  # no hazy level: a clean pass through a one-level integrator
                n, part_sigma, part_tables = 1, np.full((1, 3), 1e-6), None
            else:
                part_sigma = sigma[part]
                part_tables = tables[..., 3 * first : 3 * (first + n)]
            if part_tables is None:
                grid = self.grid
                part_tables = np.zeros((grid.n_z, grid.n_mu, grid.n_phi, 3), np.float32)
            if ratios is not None:
                self.pixel_ratio = PixelRatio(sensor, ratios.levels(slice(first, first + n)))
            camera_pass = self.integrator("camera", part_sigma, albedo, g, part_tables)
            say(f"camera pass{of}, {stratified_spp(spp)} spp")
            image = render_radiance(
                self.loaded, stratified_spp(spp), seed, integrator=camera_pass, stratified=True
            )
            if clean is None:
                clean = image[..., :3].copy()
            if len(sigma):
                if self.settings.vessel_light_share > 0.0:
                    say(f"vessel-light pass{of}")
                    image += self.vessel_light(part_sigma, albedo, g, part_tables, spp, seed)
                # Light is never negative: render_radiance's gamut clip, after the correction.
                levels += [np.maximum(image[..., 3 + 3 * k : 6 + 3 * k], 0.0) for k in range(n)]
        assert clean is not None
        return PhysicalPass(clean, levels, table_seconds)

    def pixel_ratios(
        self, sigma: np.ndarray, seed: int = 0, bank_photons: int | None = None
    ) -> PixelRatios:
        """Each pixel's density ratios in the scene's field (:func:`pixel_ratios`) for levels
        of (green) extinction ``sigma`` (L,) in 1/m, from the geometry pass's pixel-centre rays
        and the sun's direction; in a bank alone or patches alone with the ``diffuse_air`` and
        ``diffuse_bounce`` ratios too (:meth:`own_diffuse`, the field's light traced from
        ``seed`` with ``bank_photons`` per level; None: the settings' for the fewest table
        photons). Kept for the frame's next render of the same levels and seed."""
        assert self.field is not None
        key = (tuple(float(x) for x in sigma), seed, bank_photons)
        if key not in self._ratios:
            if self.geometry is None:
                self.geometry = render_geometry(self.loaded)
            sun = sun_axis(self.sun)
            levels = np.asarray(key[0])
            ratios = pixel_ratios(self.field, self.geometry, sun, levels)
            field = self.field.field
            if (field.bank is None) != (field.patches is None):  # a bank or patches alone
                photons = bank_photons or self.settings.bank_photons_for(0)
                air, bounce = self.own_diffuse(ratios, levels, seed, photons)
                ratios = replace(ratios, diffuse_air=air, diffuse_bounce=bounce)
            self._ratios[key] = ratios
        return self._ratios[key]

    def own_diffuse(
        self, ratios: PixelRatios, sigma: np.ndarray, seed: int, photons: int
    ) -> tuple[np.ndarray, np.ndarray]:
        """(L, H, W) each pixel's ``diffuse_air`` and ``diffuse_bounce`` ratios
        (:mod:`seahaze.render.diffuse_ratios`) in the scene's bank alone
        (:mod:`seahaze.render.bank_diffuse`) or patches alone
        (:mod:`seahaze.render.patch_diffuse`) at levels of (green) extinction ``sigma``, the
        field's light traced with ``photons`` per level from ``seed``."""
        from . import bank_diffuse, diffuse_ratios, patch_diffuse  # a variant is set by now

        assert self.field is not None and self.geometry is not None
        origin = (float(self.geometry.origin[0]), float(self.geometry.origin[1]))
        # A bank's later segments measure their own ratio; patches' take the pixel's bounce.
        trace, later = (
            (bank_diffuse.trace_bank, None)
            if self.segments is not None
            else (patch_diffuse.trace_patches, ratios.bounce)
        )
        sources = trace(self.field, self.sun, self.sky, self.sea, sigma, origin, photons, seed)
        return diffuse_ratios.diffuse_ratios(
            self.field, self.geometry, ratios.view, sources, sigma, self.sea, later
        )

    def vessel_light(
        self,
        sigma: np.ndarray,
        albedo: float,
        g: float,
        tables: np.ndarray,
        spp: int,
        seed: int,
    ) -> np.ndarray:
        """The vessel-light pass for levels of extinction ``sigma`` (L, 3) with their
        ``tables``, as an (H, W, 3 + 3L) image whose first three (clean) channels are 0: what
        each level gains from the light vessels send into the haze in front of them
        (:meth:`.VesselLightPass.vessel_light`; negative where a vessel is darker than the
        open sea and sky it hides), at :func:`vessel_light_spp` of the main pass's ``spp``,
        smoothed within the image's segments (sky, sea, each vessel) over the settings'
        ``vessel_light_radius_px``. Its samples come from ``seed``'s vessel-light stream."""
        integrator = self.integrator("vessel_light", sigma, albedo, g, tables)
        integrator.set_vessels(self.sea_id, self.loaded.vessel_spheres)
        pass_seed = render_seed(seed, RenderPass.VESSEL_LIGHT)
        samples = vessel_light_spp(spp, self.settings)
        image = render_radiance(
            self.loaded, samples, pass_seed, integrator=integrator, clip=False, stratified=True
        )
        if self.geometry is None:
            self.geometry = render_geometry(self.loaded)
        labels = segments(self.geometry.instance, self.geometry.distance_m)
        # The clean channels (the first three) are 0 in this pass: only the levels' smoothed.
        radius = self.settings.vessel_light_radius_px
        image[..., 3:] = smooth_within_segments(image[..., 3:], labels, radius)
        return image

    def integrator(
        self, kind: str, sigma: np.ndarray, albedo: float, g: float, tables: np.ndarray
    ) -> Any:
        """The ``kind`` (``camera`` or ``vessel_light``) pass's integrator for levels of
        extinction ``sigma`` (L, 3) with their ``tables``, pointed at them. One integrator,
        and so one compiled kernel, per kind, level count, greyness and medium shape (and
        whether it renders pixels' equivalent profiles)."""
        n = len(sigma)
        grey = bool(np.all(sigma == sigma[:, 1:2]))
        medium: HazeMedium = self.medium.with_optics(albedo, g)
        key = (kind, n, grey, medium.with_optics(0.0, 0.0), self.field is not None)
        key += (self.segments is not None,)
        if key not in self.integrators:
            camera, vessel_light = integrator_classes()
            cls = {"camera": camera, "vessel_light": vessel_light}[kind]
            self.integrators[key] = cls(
                self.sun, self.sky, medium, n, grey, self.wind_speed, self.settings
            )
        integrator = self.integrators[key]
        integrator.set_pixel_ratio(self.pixel_ratio, self.segments)
        integrator.levels.set(
            sigma, np.full(n, 1.0 / n), albedo, g, tables, self.sun_azimuth_rad, self.grid.folded
        )
        return integrator


def vessel_light_spp(spp: int, settings: EstimatorSettings = DEFAULT_SETTINGS) -> int:
    """Samples per pixel of the vessel-light pass for ``spp`` of the main pass: the settings'
    share of them, rounded up, as the ``multijitter`` sampler takes them."""
    return stratified_spp(max(1, settings.vessel_light_spp(spp)))


def levels_per_pass(
    width: int, height: int, n_levels: int, most: int = DEFAULT_SETTINGS.max_levels_per_pass
) -> int:
    """How many levels one pass renders: all of them up to ``most``, fewer where the film
    (RGB, weight and 3 channels per level, float32, with a developed copy) would pass
    :data:`FILM_BUDGET_BYTES`."""
    per_level = 2 * 3 * 4 * width * height
    fit = (FILM_BUDGET_BYTES - 2 * 4 * 4 * width * height) // per_level
    return int(max(1, min(max(n_levels, 1), most, fit)))
