"""Drifting patches' own diffuse light on a pixel's segments, in the ``physical`` mode.

``physical`` renders haze that varies across the sea as each pixel's equivalent profile
(:mod:`seahaze.render.pixel_density`) and reads the diffuse field from tables traced in the
horizontally homogeneous profile. Dense patches are not lit like that: a patch shields its
own inside from every side, so the diffuse light is weakest exactly where the haze is densest
and scatters most. With the tables' field `physical` was too bright in patches of density
ratio 30 by 1.6–3.4 % at 1000 m and 7–14 % at 300 m (docs/physics.md, "Haze that varies
across the sea in the physical mode").

This module traces the patches' own light for the ``diffuse_air`` and ``diffuse_bounce``
ratios of :mod:`seahaze.render.diffuse_ratios`. The photons of
:mod:`seahaze.render.patch_tracer`, traced through a periodic box of the field around the
camera, give per cell the field's fluence in a few direction groups ``G`` (:data:`BANDS`
bands of ``μ`` × :data:`SECTORS` sectors of azimuth) over the profile's at the cell's height,

    R_G(x, y, z) = Φ_G(x, y, z) / Φ_v,G(z),

and the light a point scatters toward a ray is the profile's with each group's share scaled
by its ratio, ``J(x, ω) = Σ_G R_G(x) J_v,G(z, ω)``, ``J_v,G`` the in-scattered light of the
profile's directional fluence in the group's bins. A 3-D field tallied per direction bin
would leave a few photons per cell and bin; what a patch changes is mostly how much light
reaches a point from above and from the sun's side, which a few groups hold. The box's half
side is :data:`BOX_REACH` mean free paths of the level (a camera ray's haze light comes from
its first few), cut in :data:`BOX_CELLS` columns a side; outside it the field takes the
profile's light (``R = 1``). Measured against the ``reference`` in docs/physics.md ("Drifting
patches' own diffuse field").

Import this module only once a Mitsuba variant is set.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from ..nonuniform import RAY_REACH_M, NonUniformHaze
from .diffuse_ratios import LUMINANCE, light_nodes
from .diffuse_table import TableGrid, phase_matrix
from .patch_tracer import Box, BoxFluence, trace_box
from .photon_sources import emitter_photons
from .photon_tracer import SeaReflectance

BOX_REACH = 4.0
"""The box's half side in mean free paths of the level's extinction, ``1/σ``: a horizontal ray
at the level's mean density keeps ``e^{−4}`` of its light by the box's edge. A box twice as
wide, with as many photons, spread them over four times the columns (noisier, and no closer)."""
BOX_CELLS = 64
"""Columns along each side of the box (cells of ``σ/8``: 10 m at 300 m, 130 m at 4000 m)."""
GRID = TableGrid(n_z=12, n_mu=24, n_phi=24, folded=False)
"""Heights of the box's cells and the profile's direction bins (azimuths from world +x)."""
BANDS = 4
"""The field's fluence is tallied in this many bands of ``μ`` (``n_mu`` a multiple of it):
under a dense column the light from above is cut more than the light that travels along the
sea."""
SECTORS = 4
"""…and this many sectors of azimuth: a patch between a point and the sun cuts the light that
travels away from the sun more than the rest."""
SMOOTHING_CELLS = 1
"""Radius of the box filter over each height's ratios ``R`` (periodic, as the box): the cells'
photon noise averaged over their neighbours."""


def patch_box(medium: NonUniformHaze, camera_xy: tuple[float, float], sigma: float) -> Box:
    """The box about a camera at world ``camera_xy`` (m) for a level of extinction ``sigma``
    (1/m): :data:`BOX_REACH` mean free paths to each side (at most :data:`RAY_REACH_M`)."""
    half = min(BOX_REACH / sigma, RAY_REACH_M)
    return Box(
        camera_xy[0] - half,
        camera_xy[1] - half,
        2.0 * half,
        BOX_CELLS,
        medium.profile.top,
        GRID.n_z,
        GRID.n_mu,
        GRID.n_phi,
        BANDS,
        SECTORS,
    )


def trace_patches(
    medium: NonUniformHaze,
    sun: Any,
    sky: Any,
    sea: SeaReflectance,
    sigma: np.ndarray,
    camera_xy: tuple[float, float],
    photons: int,
    seed: int,
) -> PatchLight:
    """The patches' light (:class:`PatchLight`) at levels of (green) extinction ``sigma``
    (L,) in 1/m, lit by the Mitsuba emitters ``sun`` and ``sky`` (``photons`` per level, half
    from each) over the sea ``sea``; levels traced one after the other, each in its own box."""
    top = medium.profile.top
    sources = [emitter_photons(e, photons // 2, seed + i, top) for i, e in enumerate((sun, sky))]
    drift = medium.field.drift
    travelled = drift.speed_m_s * drift.time_s
    boxes, fluences = [], []
    for level in sigma:
        box = patch_box(medium, camera_xy, float(level))
        fluence = trace_box(
            *sources,
            sea,
            [float(level)],
            medium.profile,
            medium.field,
            medium.scale,
            travelled,
            box,
            seed,
        )
        boxes.append(box)
        fluences.append(fluence)
    return PatchLight.of(medium, boxes, fluences)


@dataclass(frozen=True)
class PatchLight:
    """Per level, the box, the field's fluence over the profile's per cell and direction
    group ``R [x, y, z, G]``, and each group's share of the profile's in-scattered luminance
    per metre and unit density toward the centre of every direction bin ``[z, G, node]``
    (``ϖ Σ_{b in G} p Φ_b``)."""

    medium: NonUniformHaze
    boxes: list[Box]
    ratio: list[np.ndarray]
    profile: list[np.ndarray]

    @cached_property
    def rows(self) -> list[np.ndarray]:
        """Per level, the ratios as rows of G values per cell, in float32, and one more row of
        ones for points outside the box (what :meth:`light` gathers; made once, read by
        every ray sum of the frame)."""
        return [
            np.concatenate([r.reshape(-1, box.n_light), np.ones((1, box.n_light))]).astype(
                np.float32
            )
            for r, box in zip(self.ratio, self.boxes, strict=True)
        ]

    @classmethod
    def of(cls, medium: NonUniformHaze, boxes: list[Box], fluences: list[BoxFluence]) -> PatchLight:
        ratios, profiles = [], []
        for box, fluence in zip(boxes, fluences, strict=True):
            grid = TableGrid(box.n_z, box.n_mu, box.n_phi, folded=False)
            phase = phase_matrix(float(medium.profile.g), grid).T  # [bin, node]
            field = fluence.field[0] @ LUMINANCE  # [x, y, z, group]
            flat = fluence.profile[0] @ LUMINANCE  # [z, dir]
            one_hot = box.groups()[:, None] == np.arange(box.n_light)[None]  # [dir, group]
            scalar = flat @ one_hot  # [z, group]
            field = smooth_periodic(field, SMOOTHING_CELLS)
            fine = scalar > 0.0
            ratios.append(np.where(fine, field / np.where(fine, scalar, 1.0), 1.0))
            # Each group's light toward every node: [z, group, node].
            profiles.append(np.einsum("zd,dg,dn->zgn", flat, one_hot, phase))
        return cls(medium, boxes, ratios, profiles)

    def light(self, k: int, x: Any, y: Any, z: Any, travel: np.ndarray):
        """(N, P) level ``k``'s source ``J`` (per unit ``σ ρ``) at world points ``x``, ``y``,
        ``z`` (N, P) toward the travel directions ``travel`` (N, 3): the patches' and the
        profile's."""
        box = self.boxes[k]
        i_z = np.clip(z * (box.n_z / box.top_m), 0, box.n_z - 1).astype(np.int64)
        fx = (x - box.x0) * (box.n_xy / box.side_m)
        fy = (y - box.y0) * (box.n_xy / box.side_m)
        inside = (fx >= 0) & (fx < box.n_xy) & (fy >= 0) & (fy < box.n_xy)
        i_x = np.clip(fx, 0, box.n_xy - 1).astype(np.int64)
        i_y = np.clip(fy, 0, box.n_xy - 1).astype(np.int64)
        # Rows of G values gathered at once; each ray's light per height found first (few),
        # then read at its points (many).
        cells = self.rows[k]
        cell = np.where(inside, (i_x * box.n_xy + i_y) * box.n_z + i_z, len(cells) - 1)
        nodes = light_nodes(box, travel)
        per_height = sum(
            w[:, None, None] * self.profile[k][:, :, n].transpose(2, 0, 1) for n, w in nodes
        ).astype(np.float32)  # [N, z, G]
        row = np.arange(len(travel))[:, None] * box.n_z + i_z
        groups = per_height.reshape(-1, box.n_light)[row]  # [N, P, G]
        true = np.einsum("npg,npg->np", cells[cell], groups)
        return true.astype(np.float64), groups.sum(axis=-1, dtype=np.float64)


def smooth_periodic(cube: np.ndarray, radius: int) -> np.ndarray:
    """``cube`` [x, y, …] averaged over the (2 radius + 1)² columns about each, wrapping
    around the box's sides."""
    if radius <= 0:
        return cube
    total = np.zeros_like(cube)
    for dx in range(-radius, radius + 1):
        for dy in range(-radius, radius + 1):
            total += np.roll(cube, (dx, dy), axis=(0, 1))
    return total / (2 * radius + 1) ** 2
