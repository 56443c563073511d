"""A fog bank's own diffuse light, in the ``physical`` mode.

``physical`` renders haze that varies across the sea as each pixel's equivalent profile
(:mod:`seahaze.render.pixel_density`), and reads the diffuse field — everything but the sun's
single scattering — from tables traced in the horizontally homogeneous profile. A bank is not
that: the light inside it and beside it is the bank's, shaped by its edge over kilometres (the
transport mean free path of a fog with ``g ≈ 0.85`` is ``1 / (σ (1 − g))``, 1.7 km at 1 km
visibility). The equivalent profile left the bank's sky 6 % dark at 1000 m and every region
13–19 % dark at 300 m (docs/physics.md, "Haze that varies across the sea in the physical
mode").

This module traces the bank's light (:func:`trace_bank`: the directional fluence of
:mod:`seahaze.render.strip_tracer` per cell of distance past the edge and height, and the
profile's averaged over the strip, where it is horizontally uniform) and serves it to
:mod:`seahaze.render.diffuse_ratios` (:class:`SourceTables`), which gives each pixel its
``diffuse_air`` and ``diffuse_bounce`` ratios. The ratios carry the strip's photon noise: the
tables' horizontally uniform field is one mean over forty-odd cells, the bank's is not
(docs/benchmarks.md, "How close is physical in a fog bank?", states it per region).

Import this module only once a Mitsuba variant is set.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..nonuniform import NonUniformHaze
from .diffuse_ratios import LUMINANCE, light_nodes
from .diffuse_table import TableGrid, phase_matrix
from .photon_sources import emitter_photons
from .photon_tracer import SeaReflectance
from .strip_tracer import Strip, StripFluence, trace_strip

CELL_M = 120.0
"""Width of the strip's cells across the edge (m): the edge's own scale, ``edge_m``, is tens
of metres, but the diffuse field varies over the transport mean free path (km)."""
BEHIND_M = 1500.0
"""The strip starts this far behind the camera or the edge, whichever is nearer the thin side."""
AHEAD_M = 3000.0
"""…and ends this far past the edge or the camera, whichever lies deeper in the bank. Beyond
both ends the field is taken as the last cell's (plane-parallel far from the edge)."""
MARGIN_M = 3000.0
"""Photons enter over the strip widened by this on each side (:class:`Strip`)."""
GRID = TableGrid(n_z=12, n_mu=24, n_phi=24, folded=False)
"""Heights and directions of the strip's cells (azimuths from the bank's normal)."""


def bank_strip(medium: NonUniformHaze, camera_xy: tuple[float, float]) -> Strip:
    """The strip of ``medium``'s bank (its field a bank alone) seen from a camera at world
    ``camera_xy`` (m): from :data:`BEHIND_M` behind the camera or the edge to
    :data:`AHEAD_M` past the other, in cells of about :data:`CELL_M`."""
    bank = medium.field.bank
    if bank is None:
        raise ValueError("bank_strip needs a field with a bank")
    x, y = medium.field.drift.shifted(np.float64(camera_xy[0]), np.float64(camera_xy[1]))
    camera = float(bank.beyond(x, y))
    lo, hi = min(camera, 0.0) - BEHIND_M, max(camera, 0.0) + AHEAD_M
    n_s = max(1, round((hi - lo) / CELL_M))
    return Strip(
        lo,
        hi,
        n_s,
        medium.profile.top,
        GRID.n_z,
        GRID.n_mu,
        GRID.n_phi,
        bank.toward_deg,
        bank.edge_m,
        bank.near_ratio,
        medium.scale,
        MARGIN_M,
    )


def trace_bank(
    medium: NonUniformHaze,
    sun: Any,
    sky: Any,
    sea: SeaReflectance,
    sigma: np.ndarray,
    camera_xy: tuple[float, float],
    photons: int,
    seed: int,
) -> SourceTables:
    """The bank's light (:class:`SourceTables`, from the bank's and its profile's diffuse
    fields, :func:`trace_strip`) at levels of (green) extinction ``sigma`` (L,) in 1/m, lit by
    the Mitsuba emitters ``sun`` and ``sky`` (``photons`` per level, half from each) over the
    sea ``sea``. Levels are traced one after the other (one kernel: the lanes of all levels at
    once would need gigabytes)."""
    strip = bank_strip(medium, camera_xy)
    top = medium.profile.top
    sources = [emitter_photons(e, photons // 2, seed + i, top) for i, e in enumerate((sun, sky))]
    traced = [trace_strip(*sources, sea, [float(k)], medium.profile, strip, seed) for k in sigma]
    bank = np.concatenate([t.bank for t in traced])
    profile = np.concatenate([t.profile for t in traced])
    return SourceTables.of(medium, strip, StripFluence(bank, profile))


@dataclass(frozen=True)
class SourceTables:
    """Per level, the in-scattered luminance per metre and unit density toward the centre of
    every direction bin (``ϖ Σ_b p Φ_b``; ``σ ρ`` times it is ``J``): the bank's per cell
    ``[L, s·z, dir]`` and the profile's per height ``[L, z, dir]`` (its mean across the
    strip, where it is uniform)."""

    medium: NonUniformHaze
    strip: Strip
    bank: np.ndarray
    profile: np.ndarray

    @classmethod
    def of(cls, medium: NonUniformHaze, strip: Strip, fluence: StripFluence) -> SourceTables:
        grid = TableGrid(strip.n_z, strip.n_mu, strip.n_phi, folded=False)
        phase = phase_matrix(float(medium.profile.g), grid).T  # [bin, node]
        lum = fluence.bank @ LUMINANCE  # [L, s, z, dir]
        bank = lum.reshape(len(fluence.bank), -1, strip.n_dir) @ phase
        profile = (fluence.profile.mean(axis=1) @ LUMINANCE) @ phase
        return cls(medium, strip, bank, profile)

    def light(self, k: int, x: Any, y: Any, z: Any, travel: np.ndarray):
        """(N, P) the level ``k``'s source ``J`` (per unit ``σ ρ``) at world points ``x``,
        ``y``, ``z`` (N, P) toward the travel directions ``travel`` (N, 3) of the light that
        reaches each ray's start: the bank's and its profile's."""
        strip = self.strip
        s_cell, z_cell = _cells(self.medium, strip, x, y, z)
        cell = s_cell * strip.n_z + z_cell
        nodes = light_nodes(strip, travel)
        j_bank = sum(w[:, None] * self.bank[k][cell, n[:, None]] for n, w in nodes)
        j_flat = sum(w[:, None] * self.profile[k][z_cell, n[:, None]] for n, w in nodes)
        return j_bank, j_flat


def _cells(medium: NonUniformHaze, strip: Strip, x: Any, y: Any, z: Any):
    """The strip cell (distance past the edge, height) of world points; points beyond either
    end of the strip take its end cell."""
    bank = medium.field.bank
    assert bank is not None
    s = bank.beyond(*medium.field.drift.shifted(x, y))
    i_s = np.clip((s - strip.s_lo) * (strip.n_s / (strip.s_hi - strip.s_lo)), 0, strip.n_s - 1)
    i_z = np.clip(z * (strip.n_z / strip.top_m), 0, strip.n_z - 1)
    return i_s.astype(np.int64), i_z.astype(np.int64)
