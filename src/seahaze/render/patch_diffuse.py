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
profile's light (``R = 1``). The field is traced at levels at most :data:`LEVEL_SPAN` apart
in extinction; a level between blends the ratios of the two that bracket it
(:func:`blended_ratio`). Measured against the ``reference`` in docs/physics.md ("Drifting
patches' own diffuse field").

Import this module only once a Mitsuba variant is set.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from ..nonuniform import RAY_REACH_M, NonUniformHaze
from .diffuse_ratios import light_nodes, quotient
from .diffuse_table import TableGrid, phase_matrix
from .patch_tracer import Box, BoxFluence, SourcePhotons, source_photons, trace_box
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
BANDS = 2
"""The field's fluence is tallied in this many bands of ``μ`` (``n_mu`` a multiple of it): the
light from above, which a dense column over a point cuts, apart from the light from below."""
SECTORS = 8
"""…and this many sectors of azimuth, the first centred on the sun's travel
(:func:`sun_sector_start`): a patch between a point and the sun cuts the light that travels
away from the sun more than the rest, and the sun's light scattered forward stays within
tens of degrees of its travel. Eight sectors of two bands took about 1 % off the sky's and
the vessels' excess at 300 m against four of four, for the same 16 groups and noise (more
bands changed nothing; docs/physics.md, "Drifting patches' own diffuse field")."""
LEVEL_SPAN = 2.0
"""The field is traced at levels whose extinctions are at most this factor apart (the densest
and the clearest always: 300, 500, 1000, 2000 and 4000 m of the graded levels); a level
between takes its ratios from the two traced levels that bracket it, interpolated in
``ln σ`` (:func:`blended_ratio`), and traces its profile's light alone. The field's tracer
is most of what patches cost; what the interpolation changes against tracing every level is
in docs/benchmarks.md ("How close is physical in drifting patches?")."""
SMOOTHING_CELLS = 2
"""Radius of the box filter over each height's ratios ``R`` (periodic, as the box): the cells'
photon noise averaged over their 5 × 5 neighbourhood. Every camera ray starts in the few cells
about the camera, so their noise moves a whole level: against radius 1, one render's region
error scatters a fifth to a third less, its mean unmoved; radius 3 scattered no less."""


def patch_box(
    medium: NonUniformHaze, camera_xy: tuple[float, float], sigma: float, sector_start: int = 0
) -> Box:
    """The box about a camera at world ``camera_xy`` (m) for a level of extinction ``sigma``
    (1/m): :data:`BOX_REACH` mean free paths to each side (at most :data:`RAY_REACH_M`), its
    first azimuth sector beginning at bin ``sector_start`` (:func:`sun_sector_start`)."""
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
        sector_start,
    )


def sun_sector_start(sources: SourcePhotons) -> int:
    """The azimuth bin of :data:`GRID` at which the box's first sector begins so that it is
    centred on the travel of the sun's photons in ``sources`` (bins over ``[−π, π)`` of the
    azimuth from world +x, as :class:`Box`): the sectors turn with the sun, not with the
    world's axes. 0 when the sun sends no photons (below the horizon)."""
    d, w = sources.d[: sources.n_sun], sources.w[: sources.n_sun].sum(axis=1)
    if len(d) == 0 or not np.any(w > 0):
        return 0
    azimuth = math.atan2(float(w @ d[:, 1]), float(w @ d[:, 0]))
    centre = (azimuth + math.pi) / (2.0 * math.pi) * GRID.n_phi
    return round(centre - 0.5 * GRID.n_phi / SECTORS) % GRID.n_phi


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
    from each) over the sea ``sea``; levels traced one after the other, each in its own box,
    the field's photons only at :func:`traced_levels` (the profile's at every level)."""
    top = medium.profile.top
    sources = source_photons(
        *(emitter_photons(e, photons // 2, seed + i, top) for i, e in enumerate((sun, sky)))
    )
    drift = medium.field.drift
    travelled = drift.speed_m_s * drift.time_s
    traced = traced_levels(sigma)
    start = sun_sector_start(sources)
    boxes, fluences = [], []
    for k, level in enumerate(sigma):
        box = patch_box(medium, camera_xy, float(level), start)
        fluence = trace_box(
            sources,
            sea,
            [float(level)],
            medium.profile,
            medium.field,
            medium.scale,
            travelled,
            box,
            seed,
            with_field=k in traced,
        )
        boxes.append(box)
        fluences.append(fluence)
    return PatchLight.of(medium, sigma, boxes, fluences)


def traced_levels(sigma: np.ndarray) -> list[int]:
    """The indices of the levels of extinction ``sigma`` (L,) whose field is traced: the
    densest, then from each traced level the clearest one at most :data:`LEVEL_SPAN` times
    clearer (at least the next clearer level), down to the clearest."""
    order = [int(i) for i in np.argsort(-np.asarray(sigma), kind="stable")]
    traced = [order[0]]
    at = 0
    while at < len(order) - 1:
        last = float(sigma[order[at]])
        at += 1
        while at < len(order) - 1 and last <= LEVEL_SPAN * float(sigma[order[at + 1]]):
            at += 1
        traced.append(order[at])
    return sorted(traced)


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

    @cached_property
    def by_node(self) -> list[np.ndarray]:
        """Per level, the groups' light toward each direction bin's centre, laid out as
        ``[node, z, group]`` in float32 (each ray's bins read as whole rows; made once)."""
        return [np.ascontiguousarray(p.transpose(2, 0, 1), np.float32) for p in self.profile]

    @classmethod
    def of(
        cls,
        medium: NonUniformHaze,
        sigma: np.ndarray,
        boxes: list[Box],
        fluences: list[BoxFluence],
    ) -> PatchLight:
        """The light of levels of extinction ``sigma`` (L,) from their ``boxes`` and traced
        ``fluences``: a level whose field was not traced takes its ratios from the traced
        levels that bracket it (:func:`blended_ratio`), its profile's light its own."""
        ratios: list[np.ndarray | None] = []
        profiles = []
        for box, fluence in zip(boxes, fluences, strict=True):
            grid = TableGrid(box.n_z, box.n_mu, box.n_phi, folded=False)
            phase = phase_matrix(float(medium.profile.g), grid).T  # [bin, node]
            flat = fluence.profile[0]  # [z, dir], luminance
            one_hot = box.groups()[:, None] == np.arange(box.n_light)[None]  # [dir, group]
            # Each group's light toward every node: [z, group, node].
            profiles.append(np.einsum("zd,dg,dn->zgn", flat, one_hot, phase, optimize=True))
            if fluence.field is None:
                ratios.append(None)
                continue
            scalar = flat @ one_hot  # [z, group]
            field = smooth_periodic(fluence.field[0], SMOOTHING_CELLS)  # [x, y, z, group]
            ratios.append(quotient(field, scalar))
        traced = [k for k, r in enumerate(ratios) if r is not None]
        for k, ratio in enumerate(ratios):
            if ratio is None:
                denser = min((i for i in traced if sigma[i] >= sigma[k]), key=lambda i: sigma[i])
                clearer = max((i for i in traced if sigma[i] <= sigma[k]), key=lambda i: sigma[i])
                near, far = (boxes[denser], ratios[denser]), (boxes[clearer], ratios[clearer])
                t = _log_fraction(sigma[denser], sigma[k], sigma[clearer])
                ratios[k] = blended_ratio(boxes[k], near, far, t)
        return cls(medium, boxes, [r for r in ratios if r is not None], profiles)

    def light(self, k: int, x: Any, y: Any, z: Any, travel: np.ndarray):
        """(N, P) level ``k``'s source ``J`` (per unit ``σ ρ``) at world points ``x``, ``y``,
        ``z`` (N, P) toward the travel directions ``travel`` (N, 3): the patches' and the
        profile's."""
        box = self.boxes[k]
        i_z = np.clip(z * (box.n_z / box.top_m), 0, box.n_z - 1).astype(np.int64)
        i_x, i_y, inside = box_columns(box, x, y)
        # Rows of G values gathered at once; each ray's light per height found first (few),
        # then read at its points (many).
        cells = self.rows[k]
        cell = np.where(inside, (i_x * box.n_xy + i_y) * box.n_z + i_z, len(cells) - 1)
        by_node = self.by_node[k]
        per_height = sum(
            w.astype(np.float32)[:, None, None] * by_node[n] for n, w in light_nodes(box, travel)
        )  # [N, z, G]
        row = np.arange(len(travel))[:, None] * box.n_z + i_z
        # (np.take: numpy's fancy indexing of rows by a 2-D index is several times slower.)
        groups = np.take(per_height.reshape(-1, box.n_light), row, axis=0)  # [N, P, G]
        true = np.einsum("npg,npg->np", np.take(cells, cell, axis=0), groups)
        # The profile's light: each height's groups summed once per ray, then read per point.
        flat = per_height.sum(axis=-1, dtype=np.float64).reshape(-1)[row]
        return true.astype(np.float64), flat


def box_columns(box: Box, x: Any, y: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The column indices of world points ``x``, ``y`` in ``box`` (clipped to its sides) and
    whether each lies inside it."""
    fx = (np.asarray(x) - box.x0) * (box.n_xy / box.side_m)
    fy = (np.asarray(y) - box.y0) * (box.n_xy / box.side_m)
    inside = (fx >= 0) & (fx < box.n_xy) & (fy >= 0) & (fy < box.n_xy)
    i_x = np.clip(fx, 0, box.n_xy - 1).astype(np.int64)
    i_y = np.clip(fy, 0, box.n_xy - 1).astype(np.int64)
    return i_x, i_y, inside


def blended_ratio(
    box: Box,
    near: tuple[Box, np.ndarray],
    far: tuple[Box, np.ndarray],
    t: float,
) -> np.ndarray:
    """The ratios ``[x, y, z, group]`` of a level whose field was not traced, in its own
    ``box``: at each column's centre, ``(1 − t)`` times the denser traced level's ratio
    (``near``: its box and ratios) plus ``t`` times the clearer one's (``far``); where the
    centre lies in only one of their boxes, that box's ratio; in neither, 1. All the boxes
    share their heights and direction groups."""
    centres = box.x0 + (np.arange(box.n_xy) + 0.5) * (box.side_m / box.n_xy)
    across = box.y0 + (np.arange(box.n_xy) + 0.5) * (box.side_m / box.n_xy)
    x, y = np.meshgrid(centres, across, indexing="ij")
    total = np.zeros((box.n_xy, box.n_xy, box.n_z, box.n_light))
    weight = np.zeros((box.n_xy, box.n_xy, 1, 1))
    for (other, ratio), share in ((near, 1.0 - t), (far, t)):
        i_x, i_y, inside = box_columns(other, x, y)
        w = np.where(inside, share, 0.0)[..., None, None]
        total += w * ratio[i_x, i_y]
        weight += w
    return quotient(total, weight)


def _log_fraction(denser: float, sigma: float, clearer: float) -> float:
    """Where extinction ``sigma`` lies between ``denser`` (0) and ``clearer`` (1), in
    ``ln σ``."""
    span = math.log(denser / clearer)
    return math.log(denser / sigma) / span if span > 0.0 else 0.0


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
