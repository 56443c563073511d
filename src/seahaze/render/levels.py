"""Hazy levels of one loaded scene in each rendering mode: the one entry point for every caller.

The scene render (:mod:`seahaze.render.engine`), ``seahaze verify`` and the benchmarks all render
levels through :class:`LevelRenderer`, so a mode behaves the same everywhere.

Modes
    ``physical``   seahaze's haze integrator (:mod:`seahaze.render.physical`): the clean image
                   and every level from one set of camera paths, analytic transmittance, the
                   sun's single scattering with shadow rays, the rest of the scattered light
                   from per-level plane-parallel tables. Its scene has no Mitsuba medium
                   (``build_scene(..., haze_box=False)``).
    ``reference``  Mitsuba ``volpath`` through the haze box (:mod:`seahaze.render.passes`).
    ``asm``        The atmospheric scattering model from the clean image, the exact distance
                   and a rendered horizon airlight (:mod:`seahaze.render.passes`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..haze import Extinction
from ..seeds import RenderPass, render_seed
from ..spec import RENDER_MODES, HazeSpec, RenderSpec
from . import passes
from .estimator import settings_from
from .passes import Airlight, GeometryPass
from .physical import PhysicalRenderer
from .scene import LoadedScene


@dataclass
class LevelRender:
    """One hazy level's linear radiance and what the mode measured on the way."""

    radiance: np.ndarray
    """(H, W, 3) float32 linear RGB radiance."""
    airlight: Airlight | None = None
    """The horizon airlight (``asm`` only)."""


class LevelRenderer:
    """Renders the hazy levels of one loaded scene in one mode.

    ``clean`` and ``geometry`` are the scene's clean and geometry passes (the ``asm`` mode
    composites them). What a mode builds once per scene — the ``physical`` mode's integrator,
    its compiled kernel and the pre-sampled sea reflection — is built on the first level and
    reused for the others.
    """

    def __init__(
        self,
        mode: str,
        loaded: LoadedScene,
        geometry: GeometryPass,
        clean: np.ndarray | None,
        haze: HazeSpec,
        render: RenderSpec,
    ):
        if mode not in RENDER_MODES:
            raise ValueError(f"unknown render mode {mode!r}; allowed: {', '.join(RENDER_MODES)}")
        if mode == "asm" and clean is None:
            raise ValueError("the asm mode composites the clean pass: give it")
        if mode == "physical" and (loaded.spec is None or loaded.has_haze_box):
            raise ValueError(
                "the physical mode needs a scene from build_scene(..., haze_box=False): it "
                "computes the haze itself, and a Mitsuba medium would be crossed as a surface"
            )
        self.mode, self.loaded, self.geometry, self.clean = mode, loaded, geometry, clean
        self.haze, self.settings = haze, render
        self._physical: PhysicalRenderer | None = None

    def render(
        self,
        sigma: Extinction,
        level_index: int,
        render: RenderSpec | None = None,
        haze: HazeSpec | None = None,
    ) -> LevelRender:
        """The level of extinction ``sigma`` (1/m, grey or per channel R, G, B); ``level_index``
        picks its random numbers; ``render`` and ``haze`` override the spp, seed, albedo and
        phase function given at construction."""
        render, haze = render or self.settings, haze or self.haze
        loaded = self.loaded
        if self.mode == "reference":
            radiance = passes.render_reference_level(
                loaded, sigma, haze.albedo, haze.g, render.spp, render.seed, level_index
            )
            return LevelRender(radiance)
        if self.mode == "asm":
            airlight = passes.render_airlight(
                loaded, sigma, haze.albedo, haze.g, render.airlight_spp, render.seed, level_index
            )
            # Only the medium's shape enters the optical depth (its optics are the airlight's).
            medium = loaded.medium
            radiance = passes.asm_level(self.clean, self.geometry, sigma, airlight.rgb, medium)
            return LevelRender(radiance, airlight)
        # Physical: one pass from the scene's camera paths (whatever the level index), so a
        # level rendered alone equals its member of a pass over all levels.
        return self.render_all([sigma], render, haze)[1][0]

    def render_all(
        self,
        sigmas: list[Extinction],
        render: RenderSpec | None = None,
        haze: HazeSpec | None = None,
        stage: Callable[[str], None] | None = None,
    ) -> tuple[np.ndarray, list[LevelRender]]:
        """The clean radiance and every level of extinction ``sigmas``: in the physical mode
        from one set of camera paths (the clean radiance is its σ = 0 member); otherwise the
        clean pass given at construction and one render per level. ``stage`` hears each step
        of the physical pass start (progress)."""
        render, haze = render or self.settings, haze or self.haze
        if self.mode != "physical":
            return self.clean, [self.render(s, i, render, haze) for i, s in enumerate(sigmas)]
        if self._physical is None:
            assert self.loaded.spec is not None  # checked in __init__
            spec = self.loaded.spec
            settings = settings_from(spec.render.estimator)
            self._physical = PhysicalRenderer(self.loaded, spec, settings, self.geometry)
        seed = render_seed(render.seed, RenderPass.PHYSICAL_PASS)
        out = self._physical.render(sigmas, haze.albedo, haze.g, render.spp, seed, stage)
        return out.clean, [LevelRender(r) for r in out.levels]


def render_level(
    mode: str,
    loaded: LoadedScene,
    geometry: GeometryPass,
    clean: np.ndarray,
    sigma: Extinction,
    haze: HazeSpec,
    render: RenderSpec,
    level_index: int,
) -> LevelRender:
    """One hazy level by a :class:`LevelRenderer` made for it (one-off callers and tests)."""
    return LevelRenderer(mode, loaded, geometry, clean, haze, render).render(sigma, level_index)
