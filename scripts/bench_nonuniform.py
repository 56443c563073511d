"""Measure haze that varies across the sea (issue #31): the reference's grid, reference against
asm in transmittance, and the cost of asm's optical-depth quadrature.

Three questions, one scene (a 12 m camera looking over the sea with a few vessels) whose haze
section alone changes: patches (correlation 250 m, anisotropy 3, vertical 50 m, density ratio
20), a bank (edge at 1 km, bearing 20°, edge scale 60 m, near ratio 0.15), and for the box a
bank off to the side (bearing 60°).

Until 2026-11-28 the ``reference`` mode path-traced a grid of the density; it now evaluates
the field exactly (``seahaze.render.field_medium``; scripts/bench_field_medium.py measures it).
The tables in docs/benchmarks.md were measured with the grid; rerun, (b) compares the exact
reference with the grid model, and (a) says what a grid would resolve.

(a) The grid. The reference rendered a Mitsuba ``heterogeneous`` medium
    over the density sampled at the centres of ``GRID_SHAPE`` cells over the
    haze box, trilinearly interpolated and clamped at the outer centres (checked here against
    the extinction of the reference's own Mitsuba medium at random points of a loaded scene).
    For every pixel-centre ray the optical depth through that interpolant, integrated exactly
    (the interpolant is a cubic along a line between the planes of cell centres: two-point
    Gauss–Legendre per piece), is compared with the exact
    ``NonUniformHaze.ray_path_length`` over the same part of the ray (up to the surface or the
    box's wall): relative error for sea and sky pixels at several grid shapes, a fine grid
    nested near the camera and per-level boxes, with the grid's build time and size. The box is
    the one a scene rendering the 11 graded levels gets (its half width from the render's
    ``LoadedScene.box_half_width_m``). Separately: how much light from beyond the box's wall the
    reference lets through unhazed where ``asm`` and the ``transmission/`` maps follow the haze
    on to 20 km.
(b) ``reference`` against ``asm`` where they must agree: transmittance. With the haze's albedo
    set to 0 nothing scatters, so a sky pixel's reference radiance is the sky's times the
    transmittance of its ray through the grid medium (the sky is an emitter at infinity and
    volpath's estimate is unbiased): ``T_ref = I / J`` with ``J`` the clean pass. Compared per
    band of elevation with the mean of the ``transmission/`` map (the exact quadrature, pixel
    centres, what ``asm`` composites with) and of the grid model of (a), at 300, 1000 and
    4000 m, and the bank's 4000 m again with two more seeds. Sea and vessel pixels are left
    out: their lighting passes through the haze too, so their ratio is not a transmittance.
(c) Cost of the exact quadrature in ``asm``: the first level (the path lengths computed) and all
    11 graded levels (cached per scene) at 160×90, 320×180 and 640×360, against the same scene
    with uniform haze and a fog layer, with the process's memory peak over the pass; and the
    same rays with panels sized by the field's scale along each ray (this script's own
    quadrature, against an eight times finer one): whether panels fitted to each ray would
    beat ``nonuniform.py``'s (the horizontal scale across the drift, the vertical scale over
    the ray's climb) at the same accuracy.

Deterministic (fixed seeds; the reference's noise is seeded); only times vary. Writes the
"nonuniform" section of docs/benchmarks.md with ``--doc``.

Usage: python scripts/bench_nonuniform.py [--quick] [--doc]
"""

from __future__ import annotations

import argparse
import itertools
import math
import os
import platform
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_passes import proc_status_mib, replace_section

SCRIPT = "scripts/bench_nonuniform.py"
PATCHY: dict[str, Any] = {
    "patches": {
        "correlation_m": 250.0,
        "anisotropy": 3.0,
        "vertical_m": 50.0,
        "density_ratio": 20.0,
    }
}
BANK: dict[str, Any] = {
    "bank": {"distance_m": 1000.0, "bearing_deg": 20.0, "edge_m": 60.0, "near_ratio": 0.15}
}
BANK_SIDE: dict[str, Any] = {
    "bank": {"distance_m": 1000.0, "bearing_deg": 60.0, "edge_m": 60.0, "near_ratio": 0.15}
}
FOG_LAYER: dict[str, Any] = {"fog_layer": {"top_m": 25.0, "edge_m": 3.0, "above_ratio": 0.25}}
UNIFORM: dict[str, Any] = {}
HAZES = {
    "uniform": UNIFORM,
    "fog layer": FOG_LAYER,
    "patchy": PATCHY,
    "bank": BANK,
    "bank at 60°": BANK_SIDE,
}
"""The haze sections compared (merged into the scene's ``haze``)."""
GRID_SHAPE = (32, 384, 384)
"""The grid of the density the ``reference`` mode path-traced until 2026-11-28 (z, y, x cells
over the haze box); it now evaluates the field exactly (seahaze.render.field_medium, measured
by scripts/bench_field_medium.py). (a) keeps measuring what such grids resolve."""
COARSE_SHAPE = (16, 192, 192)
FINER_SHAPES = ((64, 384, 384), (32, 768, 768))
FINEST_SHAPE = (64, 768, 768)
"""Left out with ``--quick`` (its build takes some 20 s and 151 MB)."""
NEAR_HALF_M = 1000.0
NEAR_SHAPE = (64, 384, 384)
"""A fine grid nested around the camera (half width in m, cells): what (a) tries beside finer
uniform grids, since the large errors are on short rays."""
DISTANCE_BANDS_M = (0.0, 100.0, 300.0, 1000.0, 3000.0, math.inf)
"""Distance bands of sea pixels for GRID_SHAPE's error in (a)."""
BANDS_DEG = (0.0, 1.0, 2.0, 4.0, 8.0, 90.0)
"""Elevation bands of sky pixels in (b)."""
SUBPIXELS = 4
"""Sub-pixel rays per axis for the pixel-area mean in (b)'s check of pixel centres."""
MIN_T = 1e-4
"""(b) leaves out bands where the exact, grid and reference transmittances are all below this."""
B_REPLICATE_SEEDS = (5, 9)
"""Other render seeds of (b)'s bank at 4000 m."""
GAUSS2 = 1.0 / math.sqrt(3.0)


def scene_spec(
    haze: dict[str, Any],
    *,
    width: int,
    height: int,
    levels: list[float],
    mode: str = "asm",
    spp: int = 16,
    albedo: float = 0.998,
    sea_quality: str = "low",
) -> Any:
    """The benchmark scene with ``haze`` merged into its haze section (module docstring)."""
    from seahaze.spec import SceneSpec

    return SceneSpec.model_validate(
        {
            "name": "nonuniform",
            "camera": {
                "height_m": 12.0,
                "fov_deg": 60.0,
                "pitch_deg": -1.0,
                "heading_deg": 0.0,
                "resolution": [width, height],
            },
            "sun": {"elevation_deg": 25.0, "azimuth_deg": 140.0},
            "sky": {"turbidity": 3.0},
            "sea": {
                "model": "fft",
                "spectrum": "jonswap",
                "wind_speed": 6.0,
                "direction_deg": 20.0,
                "quality": sea_quality,
                "seed": 4,
            },
            "vessels": {
                "placed": [
                    {
                        "class": "fishing_boat",
                        "distance_m": 250.0,
                        "bearing_deg": -12.0,
                        "heading_deg": 60.0,
                        "length_m": 18.0,
                    },
                    {
                        "class": "tug",
                        "distance_m": 550.0,
                        "bearing_deg": 10.0,
                        "heading_deg": 200.0,
                        "length_m": 30.0,
                    },
                    {
                        "class": "container_ship",
                        "distance_m": 1500.0,
                        "bearing_deg": 4.0,
                        "heading_deg": 170.0,
                        "length_m": 220.0,
                    },
                    {
                        "class": "tanker",
                        "distance_m": 3000.0,
                        "bearing_deg": -16.0,
                        "heading_deg": 10.0,
                        "length_m": 240.0,
                    },
                ]
            },
            "haze": {"levels": levels, "albedo": albedo, "g": 0.75, "top_m": 300.0, **haze},
            "render": {"mode": mode, "spp": spp, "seed": 3},
        }
    )


def graded_levels() -> list[float]:
    """The 11 graded visibilities (m): the levels of a default render, which size its box."""
    from seahaze.visibility import GRADED_LEVELS_M

    return [float(v) for v in GRADED_LEVELS_M]


def sigma_of(visibility_m: float) -> float:
    """Koschmieder extinction (1/m) of a visibility: the scene's grey haze."""
    from seahaze.visibility import Threshold, extinction_coefficient

    return float(extinction_coefficient(visibility_m, Threshold.KOSCHMIEDER))


# -- the pixel rays and the box -------------------------------------------------------------------
@dataclass(frozen=True)
class Rays:
    """A scene's pixel-centre rays, flattened, and its haze box (world frame, m)."""

    origin: np.ndarray
    directions: np.ndarray
    """(N, 3) float64, unit."""
    distance: np.ndarray
    """(N,) distance to the surface; ``inf`` for the sky."""
    box_min: np.ndarray
    box_max: np.ndarray

    @property
    def sky(self) -> np.ndarray:
        """(N,) True for sky pixels."""
        return ~np.isfinite(self.distance)

    def exits(self, box_min: np.ndarray, box_max: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Where each ray leaves the box ``box_min``..``box_max`` (m): (through a side, through
        the top or bottom); ``inf`` where it does not."""
        d, o = self.directions, self.origin
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.where(d > 0, (box_max - o) / d, np.where(d < 0, (box_min - o) / d, np.inf))
        return np.minimum(t[:, 0], t[:, 1]), t[:, 2]


def session_rays(session: Any) -> Rays:
    """The rays and box of an open scene session (:func:`seahaze.render.engine.open_session`):
    the box is ``LoadedScene.box_half_width_m`` to each side of the camera, from the medium's
    bottom to its top (docs/physics.md, "The haze layer")."""
    geo, cam, loaded = session.pixels, session.camera, session.loaded
    return rays_in_box(geo, (cam.x_m, cam.y_m), loaded.box_half_width_m, loaded.medium)


def rays_in_box(geo: Any, centre_xy: tuple[float, float], half_width: float, medium: Any) -> Rays:
    """:class:`Rays` of a geometry pass with the haze box ``half_width`` (m) around
    ``centre_xy`` from ``medium``'s bottom to its top."""
    d = geo.directions.reshape(-1, 3).astype(np.float64)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    cx, cy = centre_xy
    return Rays(
        np.asarray(geo.origin, np.float64),
        d,
        geo.distance_m.reshape(-1).astype(np.float64),
        np.array([cx - half_width, cy - half_width, medium.bottom_m]),
        np.array([cx + half_width, cy + half_width, medium.top_m]),
    )


# -- the grid's trilinear interpolant, as Mitsuba's gridvolume evaluates it -----------------------
def trilinear(grid: np.ndarray, box_min: np.ndarray, cell: np.ndarray, p: np.ndarray) -> np.ndarray:
    """The trilinear interpolant at points ``p`` (N, 3; m) of the (z, y, x) ``grid`` of values at
    the centres of cells of size ``cell`` (x, y, z; m) from ``box_min``, clamped to the outer
    centres (drjit's texture convention, which Mitsuba's ``gridvolume`` uses)."""
    n = np.array(grid.shape[::-1])
    u = np.clip((p - box_min) / cell - 0.5, 0.0, n - 1)
    i0 = np.minimum(np.floor(u).astype(np.int64), np.maximum(n - 2, 0))
    f = u - i0
    flat = grid.reshape(-1)
    out = np.zeros(len(p))
    for corner in range(8):
        o = [(corner >> axis) & 1 for axis in range(3)]
        w = np.ones(len(p))
        for axis in range(3):
            w *= f[:, axis] if o[axis] else 1.0 - f[:, axis]
        index = ((i0[:, 2] + o[2]) * n[1] + i0[:, 1] + o[1]) * n[0] + i0[:, 0] + o[0]
        out += w * flat[index]
    return out


def grid_medium(medium: Any, rays: Rays, sigma: float) -> Any:
    """A Mitsuba ``heterogeneous`` medium over ``medium``'s density at GRID_SHAPE cells over
    the rays' haze box, at extinction ``sigma`` (the reference's medium until 2026-11-28)."""
    import mitsuba as mi

    from seahaze.medium import grid_medium_dict

    grid = medium.density_grid_over(rays.box_min, rays.box_max, GRID_SHAPE)
    volume = mi.VolumeGrid((grid[..., None] * np.float32(sigma)).astype(np.float32))
    return mi.load_dict(grid_medium_dict(volume, rays.box_min, rays.box_max, 0.0, 0.75))


def check_against_mitsuba(points: int = 20_000) -> dict[str, float]:
    """The grid model against a Mitsuba grid medium of it: the patchy scene's box at the
    clearest graded level, Mitsuba's extinction at random points of its haze box
    (``Medium.get_scattering_coefficients``) against σ times :func:`trilinear` of
    ``density_grid_over`` the box at GRID_SHAPE; and its majorant against σ times the grid's
    largest value (delta tracking is unbiased only with a majorant at least the largest)."""
    import drjit as dr
    import mitsuba as mi

    from seahaze.render.engine import open_session

    spec = scene_spec(PATCHY, width=64, height=36, levels=graded_levels(), mode="reference")
    session = open_session(spec)
    rays = session_rays(session)
    sigma = sigma_of(max(graded_levels()))
    medium = grid_medium(session.loaded.medium, rays, sigma)
    rng = np.random.default_rng(0)
    p = rng.uniform(rays.box_min, rays.box_max, (points, 3))
    mei = dr.zeros(mi.MediumInteraction3f, points)
    mei.p = mi.Point3f(p[:, 0], p[:, 1], p[:, 2])
    mei.medium = mi.MediumPtr(medium)
    got = np.array(medium.get_scattering_coefficients(mei, True)[2])[0]
    grid = session.loaded.medium.density_grid_over(rays.box_min, rays.box_max, GRID_SHAPE)
    cell = (rays.box_max - rays.box_min) / np.array(GRID_SHAPE[::-1])
    want = sigma * trilinear(grid, rays.box_min, cell, p)
    majorant = float(np.array(medium.get_majorant(mei))[0][0])
    return {
        "sigma_t": float(np.max(np.abs(got - want) / want)),
        "majorant": majorant / (sigma * float(grid.max())) - 1.0,
    }


def grid_path_lengths(
    grid: np.ndarray,
    box_min: np.ndarray,
    box_max: np.ndarray,
    origin: np.ndarray,
    directions: np.ndarray,
    t_end: np.ndarray,
    points_per_chunk: int = 1 << 21,
) -> np.ndarray:
    """``∫₀^t_end`` of the grid's trilinear interpolant along each ray (m), exactly: along a
    line the interpolant is a cubic between consecutive planes of cell centres, so two-point
    Gauss–Legendre on each piece is exact (up to rounding)."""
    cell = (box_max - box_min) / np.array(grid.shape[::-1])
    pieces = np.sum(np.abs(directions) * t_end[:, None] / cell, axis=1) + 3.0
    out = np.zeros(len(directions))
    start = 0
    while start < len(directions):
        stop = start + max(1, int(np.searchsorted(np.cumsum(pieces[start:]), points_per_chunk)))
        out[start:stop] = _grid_chunk(
            grid, box_min, cell, origin, directions[start:stop], t_end[start:stop]
        )
        start = stop
    return out


def _grid_chunk(
    grid: np.ndarray,
    box_min: np.ndarray,
    cell: np.ndarray,
    origin: np.ndarray,
    d: np.ndarray,
    t_end: np.ndarray,
) -> np.ndarray:
    """:func:`grid_path_lengths` for one chunk of rays."""
    count = len(d)
    n = np.array(grid.shape[::-1])
    rays, params = [np.arange(count), np.arange(count)], [np.zeros(count), t_end]
    for axis in range(3):
        # The planes of cell centres this axis crosses between 0 and t_end: a ray's pieces
        # end there (beyond the outer centres the interpolant is clamped, so no more breaks).
        a, b = origin[axis], origin[axis] + d[:, axis] * t_end
        first = np.ceil((np.minimum(a, b) - box_min[axis]) / cell[axis] - 0.5).astype(np.int64)
        last = np.floor((np.maximum(a, b) - box_min[axis]) / cell[axis] - 0.5).astype(np.int64)
        first, last = np.maximum(first, 0), np.minimum(last, n[axis] - 1)
        crossings = np.where(np.abs(d[:, axis]) > 1e-15, np.maximum(last - first + 1, 0), 0)
        total = int(crossings.sum())
        if total == 0:
            continue
        ray = np.repeat(np.arange(count), crossings)
        offset = np.repeat(np.cumsum(crossings) - crossings, crossings)
        index = np.arange(total) - offset + np.repeat(first, crossings)
        plane = box_min[axis] + (index + 0.5) * cell[axis]
        rays.append(ray)
        params.append((plane - origin[axis]) / d[ray, axis])
    ray, s = np.concatenate(rays), np.concatenate(params)
    order = np.lexsort((s, ray))
    ray, s = ray[order], s[order]
    same = ray[:-1] == ray[1:]
    lo, hi, owner = s[:-1][same], s[1:][same], ray[:-1][same]
    mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    values = np.zeros(len(mid))
    for node in (-GAUSS2, GAUSS2):
        p = origin[None, :] + (mid + node * half)[:, None] * d[owner]
        values += trilinear(grid, box_min, cell, p)
    return np.bincount(owner, weights=values * half, minlength=count)


@contextmanager
def timed(into: dict[str, float], key: str) -> Iterator[None]:
    """Wall seconds of the block into ``into[key]``."""
    start = time.perf_counter()
    try:
        yield
    finally:
        into[key] = time.perf_counter() - start


def reset_peak() -> float:
    """Reset the process's resident high-water mark (Linux ``clear_refs``) and return the
    resident memory now (MiB), so that ``VmHWM`` afterwards is the peak of what follows."""
    with suppress(OSError):  # not permitted: the peak is then the process's own
        Path("/proc/self/clear_refs").write_text("5")
    return proc_status_mib("VmRSS")


def error_stats(relative: np.ndarray) -> str:
    """``median / 95th percentile / max`` of ``|relative|`` as percentages."""
    a = np.abs(relative)
    if a.size == 0:
        return "—"
    return " / ".join(f"{100.0 * v:.2f} %" for v in (np.median(a), np.percentile(a, 95), a.max()))


# -- (a) the reference's grid ---------------------------------------------------------------------
@dataclass
class GridCase:
    """One scene's rays and their exact reduced lengths, in the box and in full."""

    name: str
    rays: Rays
    medium: Any
    t_end: np.ndarray
    """(N,) where each ray stops in the box: its surface or the box's wall or top."""
    exact_in_box: np.ndarray
    full: np.ndarray
    """(N,) the reduced length asm and the transmission maps use (to 20 km)."""
    through_side: np.ndarray
    """(N,) True where the ray leaves through the box's side before its surface or the top."""
    by_distance: list[dict] | None = None
    """GRID_SHAPE's error on sea pixels by distance (:func:`distance_stats`)."""


def grid_case(name: str, haze: dict[str, Any], res: tuple[int, int]) -> GridCase:
    """Open the scene with the graded levels' box and integrate its rays exactly."""
    from seahaze.render.engine import open_session

    session = open_session(scene_spec(haze, width=res[0], height=res[1], levels=graded_levels()))
    rays = session_rays(session)
    medium = session.loaded.medium
    side, vertical = rays.exits(rays.box_min, rays.box_max)
    surface = np.where(rays.sky, np.inf, rays.distance)
    through_side = side < np.minimum(vertical, surface)
    t_end = np.minimum(np.minimum(side, vertical), surface)
    full = session.pixels.haze_path_length(medium).reshape(-1)
    exact_in_box = full.copy()
    if through_side.any():
        exact_in_box[through_side] = medium.ray_path_length(
            rays.origin, rays.directions[through_side], side[through_side]
        )
    return GridCase(name, rays, medium, t_end, exact_in_box, full, through_side)


def grid_row(case: GridCase, label: str, lengths: np.ndarray, extra: dict[str, Any]) -> dict:
    """A table row: the relative error of ``lengths`` against the exact reduced lengths in the
    box for sea and sky pixels, and the largest transmittance error over the graded levels."""
    rel = (lengths - case.exact_in_box) / case.exact_in_box
    worst, worst_level = 0.0, 0.0
    for v in graded_levels():
        s = sigma_of(v)
        dt = float(np.max(np.abs(np.exp(-s * lengths) - np.exp(-s * case.exact_in_box))))
        if dt > worst:
            worst, worst_level = dt, v
    sky = case.rays.sky
    return {
        "scene": case.name,
        "grid": label,
        "sea": error_stats(rel[~sky]),
        "sky": error_stats(rel[sky]),
        "sea_bias": float(np.mean(rel[~sky])),
        "dT": worst,
        "dT_level": worst_level,
        **extra,
    }


def grid_rows(case: GridCase, shapes: list[tuple[int, int, int]]) -> list[dict]:
    """(a) for one scene: uniform grids of ``shapes`` over its box, then
    :data:`GRID_SHAPE` with a fine grid nested around the camera."""

    rays, medium = case.rays, case.medium
    rows = []
    kept: tuple[np.ndarray, np.ndarray] | None = None
    for shape in shapes:
        times: dict[str, float] = {}
        with timed(times, "build"):
            grid = medium.density_grid_over(rays.box_min, rays.box_max, shape)
        cell = (rays.box_max - rays.box_min) / np.array(shape[::-1])
        lengths = grid_path_lengths(
            grid, rays.box_min, rays.box_max, rays.origin, rays.directions, case.t_end
        )
        label = f"`{shape}`" + (" (GRID_SHAPE)" if shape == GRID_SHAPE else "")
        extra = {
            "cell": f"{cell[0]:.1f} × {cell[2]:.1f}",
            "build_s": times["build"],
            "mib": grid.nbytes / 2**20,
        }
        rows.append(grid_row(case, label, lengths, extra))
        if shape == GRID_SHAPE:
            kept = (grid, lengths)
            case.by_distance = distance_stats(case, lengths)
    if kept is not None:
        rows.append(nested_row(case, *kept))
    return rows


def distance_stats(case: GridCase, lengths: np.ndarray) -> list[dict]:
    """The grid's relative error on sea pixels by band of distance: short rays see only the
    few cells around the camera."""
    rel = (lengths - case.exact_in_box) / case.exact_in_box
    distance = case.rays.distance
    rows = []
    for lo, hi in itertools.pairwise(DISTANCE_BANDS_M):
        band = (distance >= lo) & (distance < hi)
        if band.any():
            rows.append(
                {
                    "band": f"{lo:g}–{hi:g} m" if math.isfinite(hi) else f"≥ {lo:g} m",
                    "pixels": int(band.sum()),
                    "stats": error_stats(rel[band]),
                    "bias": float(np.mean(rel[band])),
                }
            )
    return rows


def nested_row(case: GridCase, outer: np.ndarray, outer_lengths: np.ndarray) -> dict:
    """GRID_SHAPE over the box plus a :data:`NEAR_SHAPE` grid over :data:`NEAR_HALF_M` around
    the camera (full height): inside the small box the fine grid, outside it the coarse one."""
    rays, medium = case.rays, case.medium
    centre = 0.5 * (rays.box_min[:2] + rays.box_max[:2])
    near_min = np.array([*(centre - NEAR_HALF_M), rays.box_min[2]])
    near_max = np.array([*(centre + NEAR_HALF_M), rays.box_max[2]])
    times: dict[str, float] = {}
    with timed(times, "build"):
        near = medium.density_grid_over(near_min, near_max, NEAR_SHAPE)
    side, vertical = rays.exits(near_min, near_max)
    t_near = np.minimum(np.minimum(side, vertical), case.t_end)
    inside = grid_path_lengths(near, near_min, near_max, rays.origin, rays.directions, t_near)
    outer_near = grid_path_lengths(
        outer, rays.box_min, rays.box_max, rays.origin, rays.directions, t_near
    )
    lengths = outer_lengths - outer_near + inside
    cell = (near_max - near_min) / np.array(NEAR_SHAPE[::-1])
    label = f"GRID_SHAPE + `{NEAR_SHAPE}` over ±{NEAR_HALF_M:g} m"
    extra = {
        "cell": f"{cell[0]:.1f} × {cell[2]:.1f} near",
        "build_s": times["build"],
        "mib": near.nbytes / 2**20,
    }
    return grid_row(case, label, lengths, extra)


def level_box_rows(case: GridCase, levels: list[float]) -> list[dict]:
    """Each level's own box (``haze_box_half_width`` of its σ, at least three layer
    thicknesses: the rule the reference applies to a run's clearest level) against the run's,
    at GRID_SHAPE: the largest error of the transmittance against the exact one to 20 km (grid
    and wall together)."""
    from seahaze.haze import haze_box_half_width
    from seahaze.render.scene import BOX_LAYER_WIDTHS

    rays, medium = case.rays, case.medium
    centre = 0.5 * (rays.box_min[:2] + rays.box_max[:2])
    surface = np.where(rays.sky, np.inf, rays.distance)
    layer = rays.box_max[2] - rays.box_min[2]
    run_grid = medium.density_grid_over(rays.box_min, rays.box_max, GRID_SHAPE)
    run_lengths = grid_path_lengths(
        run_grid, rays.box_min, rays.box_max, rays.origin, rays.directions, case.t_end
    )
    rows = []
    for v in levels:
        s = sigma_of(v)
        half = max(haze_box_half_width(s), BOX_LAYER_WIDTHS * layer)
        box_min = np.array([*(centre - half), rays.box_min[2]])
        box_max = np.array([*(centre + half), rays.box_max[2]])
        side, vertical = rays.exits(box_min, box_max)
        t_end = np.minimum(np.minimum(side, vertical), surface)
        grid = medium.density_grid_over(box_min, box_max, GRID_SHAPE)
        own = grid_path_lengths(grid, box_min, box_max, rays.origin, rays.directions, t_end)
        exact = np.exp(-s * case.full)
        rows.append(
            {
                "level": v,
                "half": half,
                "cell": 2.0 * half / GRID_SHAPE[2],
                "run": float(np.max(np.abs(np.exp(-s * run_lengths) - exact))),
                "own": float(np.max(np.abs(np.exp(-s * own) - exact))),
            }
        )
    return rows


def wall_row(case: GridCase) -> dict:
    """How much of the world beyond the box's wall the reference shows unhazed at the clearest
    graded level, where the exact transmittance follows the haze on to 20 km."""
    s = sigma_of(max(graded_levels()))
    cut = case.through_side
    at_wall = np.exp(-s * case.exact_in_box[cut])
    beyond = at_wall - np.exp(-s * case.full[cut])
    return {
        "scene": case.name,
        "rays": int(cut.sum()),
        "of": len(cut),
        "half": float(0.5 * (case.rays.box_max[0] - case.rays.box_min[0])),
        "scale": float(case.medium.describe().get("density_scale", 1.0)),
        "T_wall": float(at_wall.max()) if at_wall.size else 0.0,
        "dT": float(beyond.max()) if beyond.size else 0.0,
    }


def grid_memory_mib() -> dict[str, float]:
    """Resident memory (MiB) that loading the patchy scene's medium at GRID_SHAPE into Mitsuba
    adds (the density grid, its RGB copy, Mitsuba's volume), and its build time."""
    from seahaze.render.engine import open_session

    session = open_session(scene_spec(PATCHY, width=64, height=36, levels=graded_levels()))
    rays, medium = session_rays(session), session.loaded.medium
    before = reset_peak()
    start = time.perf_counter()
    loaded = grid_medium(medium, rays, 1.0)
    seconds = time.perf_counter() - start
    after = proc_status_mib("VmRSS")
    del loaded
    return {"resident": after - before, "peak": proc_status_mib("VmHWM") - before, "s": seconds}


# -- (b) reference against asm in transmittance ----------------------------------------------------
def transmittance_rows(
    name: str,
    haze: dict[str, Any],
    res: tuple[int, int],
    spp: int,
    levels: list[float],
    seed: int | None = None,
) -> list[dict]:
    """(b) for one scene: per level and band of elevation, the mean transmittance of the sky
    pixels by the reference (albedo 0, ``I / J``), by the exact map and by the grid model;
    ``seed`` another render seed (which also seeds the patches: for the bank only)."""
    from seahaze.render.engine import render_scene
    from seahaze.scene_medium import scene_haze_medium
    from seahaze.spec import with_overrides
    from seahaze.world import frame_camera

    spec = scene_spec(
        haze, width=res[0], height=res[1], levels=levels, mode="reference", spp=spp, albedo=0.0
    )
    if seed is not None:
        spec = with_overrides(spec, seed=seed)
        name = f"{name} (seed {seed})"
    scene = render_scene(spec, "nonuniform_b")
    camera = frame_camera(spec, None)
    medium = scene_haze_medium(spec, camera)
    geo = scene.geometry
    half_width = scene.meta["haze"]["box_half_width_m"]
    rays = rays_in_box(geo, (camera.x_m, camera.y_m), half_width, medium)
    sky = rays.sky
    side, vertical = rays.exits(rays.box_min, rays.box_max)
    t_end = np.minimum(side, vertical)[sky]
    grid = medium.density_grid_over(rays.box_min, rays.box_max, GRID_SHAPE)
    at_centre = grid_path_lengths(
        grid, rays.box_min, rays.box_max, rays.origin, rays.directions[sky], t_end
    )
    over_area = subpixel_grid_lengths(grid, rays, camera, geo.directions.shape[:2])
    # (By far the largest term in the lowest band, measured: see whole_sky_pixels.)
    whole = whole_sky_pixels(rays.sky.reshape(geo.distance_m.shape)).reshape(-1)[sky]
    elevation = geo.elevation_deg().reshape(-1)[sky]
    clean = scene.clean[..., 1].reshape(-1)[sky].astype(np.float64)
    rows = []
    for level in scene.levels:
        s = sigma_of(level.visibility_m)
        exact = level.transmission.transmittance[..., 1].reshape(-1)[sky].astype(np.float64)
        ref = level.radiance[..., 1].reshape(-1)[sky].astype(np.float64) / clean
        grid_t = np.exp(-s * at_centre)
        area_t = np.exp(-s * over_area).mean(axis=1)
        for lo, hi in itertools.pairwise(BANDS_DEG):
            band = (elevation >= lo) & (elevation < hi) & whole
            if not band.any():
                continue
            if max(exact[band].mean(), area_t[band].mean(), ref[band].mean()) < MIN_T:
                continue
            # The reference's standard error: each pixel's estimate is a mean of spp binary
            # outcomes (albedo 0: a path escapes or is absorbed) of probability T, the grid
            # model's (what the reference converges to, (a)).
            var = np.sum(area_t[band] * (1.0 - area_t[band])) / spp
            rows.append(
                {
                    "scene": name,
                    "level": level.visibility_m,
                    "band": f"{lo:g}–{hi:g}°",
                    "pixels": int(band.sum()),
                    "exact": float(exact[band].mean()),
                    "grid": float(grid_t[band].mean()),
                    "area": float(area_t[band].mean()) - float(grid_t[band].mean()),
                    "ref": float(ref[band].mean()),
                    "se": float(math.sqrt(var) / band.sum()),
                    # The pixels' scatter about the grid model over the binomial variance:
                    # near 1 where the model and the noise model hold.
                    "scatter": float(np.sum((ref[band] - area_t[band]) ** 2) / var)
                    if var > 0
                    else float("nan"),
                }
            )
    return rows


def whole_sky_pixels(sky: np.ndarray) -> np.ndarray:
    """Sky pixels (H, W) whose eight neighbours are sky too: a pixel at a vessel's or the
    horizon's edge has part of its area on a surface, much nearer than the sky, and its level
    over its clean value is not the sky's transmittance."""
    h, w = sky.shape
    padded = np.pad(sky, 1, constant_values=True)
    inner = np.ones((h, w), bool)
    for dy in range(3):
        for dx in range(3):
            inner &= padded[dy : dy + h, dx : dx + w]
    return inner


def subpixel_grid_lengths(
    grid: np.ndarray, rays: Rays, camera: Any, shape: tuple[int, int]
) -> np.ndarray:
    """The grid model's reduced lengths (m) of :data:`SUBPIXELS`² rays spread evenly over each
    sky pixel (a box filter, as the reference's film): (sky pixels, SUBPIXELS²). A level's
    pixel-area transmittance is the mean of their ``exp(−σ ℓ)``."""
    forward = camera.basis()[0]
    h, w = shape
    image = (
        rays.directions.reshape(h, w, 3) / (rays.directions.reshape(h, w, 3) @ forward)[..., None]
    )
    # A pinhole's directions, scaled to the image plane at unit distance, are affine in the
    # pixel coordinates: one column step and one row step.
    step_x = (image[:, -1] - image[:, 0]).mean(axis=0) / (w - 1)
    step_y = (image[-1] - image[0]).mean(axis=0) / (h - 1)
    sky = rays.sky
    centre = image.reshape(-1, 3)[sky]
    offsets = (np.arange(SUBPIXELS) + 0.5) / SUBPIXELS - 0.5
    lengths = []
    for oy in offsets:
        for ox in offsets:
            d = centre + ox * step_x + oy * step_y
            d /= np.linalg.norm(d, axis=1, keepdims=True)
            sub = Rays(rays.origin, d, np.full(len(d), np.inf), rays.box_min, rays.box_max)
            side, vertical = sub.exits(rays.box_min, rays.box_max)
            t_end = np.minimum(side, vertical)
            # A sub-ray below the horizontal meets the sea, not the sky: it stays a sky ray
            # here (a few pixels at the horizon, whose band is 0–1°).
            lengths.append(
                grid_path_lengths(grid, rays.box_min, rays.box_max, rays.origin, d, t_end)
            )
    return np.stack(lengths, axis=-1)


# -- (c) cost of the quadrature -------------------------------------------------------------------
def cost_row(name: str, haze: dict[str, Any], res: tuple[int, int]) -> dict:
    """(c) for one scene at one size: the first asm level (quadrature included), all 11
    graded levels, and the process's memory peak over them."""
    from seahaze.render import passes
    from seahaze.render.engine import open_session
    from seahaze.scene_medium import scene_haze_medium

    levels = graded_levels()
    spec = scene_spec(haze, width=res[0], height=res[1], levels=levels)
    times: dict[str, float] = {}
    session = open_session(spec, timings=times)
    geo = session.pixels
    # A fresh medium: nothing cached; the clean image and airlight do not change the cost.
    medium = scene_haze_medium(spec, session.camera)
    clean = np.zeros((res[1], res[0], 3), np.float32)
    airlight = np.ones(3)
    before = reset_peak()
    per_level = []
    for v in levels:
        start = time.perf_counter()
        passes.asm_level(clean, geo, sigma_of(v), airlight, medium)
        per_level.append(time.perf_counter() - start)
    return {
        "scene": name,
        "res": f"{res[0]}×{res[1]}",
        "first": per_level[0],
        "all": sum(per_level),
        "peak": proc_status_mib("VmHWM") - before,
        "scene_load": times["scene_load"],
    }


def ray_scaled_quadrature(medium: Any, rays: Rays, refine: int = 1) -> np.ndarray:
    """The reduced lengths of ``rays`` by composite three-point Gauss–Legendre with panels one
    finest lattice step of the patches *along each ray* long (``1/|(d_u/ℓ_u, d_v/ℓ_v,
    d_z/ℓ_z)|``, ``ℓ`` the finest octave's spacing along the drift, across it and up), and no
    longer than a bank's edge (``refine`` times shorter: the yardstick). What the module's
    panels, the smallest scale in any direction, would be if sized per ray."""
    from seahaze.haze_field import OCTAVES
    from seahaze.medium import NUMPY
    from seahaze.nonuniform import RAY_REACH_M

    nodes = np.array([-math.sqrt(0.6), 0.0, math.sqrt(0.6)])
    weights = np.array([5.0, 8.0, 5.0]) / 9.0

    field = medium.field
    finest = 2.0 ** (OCTAVES - 1)
    d = rays.directions
    rate = np.zeros(len(d))
    if field.patches is not None:
        p = field.patches
        ux, uy = field.drift.unit
        du, dv = d[:, 0] * ux + d[:, 1] * uy, -d[:, 0] * uy + d[:, 1] * ux
        rate = finest * np.sqrt(
            (du / p.correlation_m) ** 2
            + (dv * p.anisotropy / p.correlation_m) ** 2
            + (d[:, 2] / p.vertical_m) ** 2
        )
    if field.bank is not None:
        rate = np.maximum(rate, 1.0 / field.bank.edge_m)
    panel = 1.0 / (refine * np.maximum(rate, 1e-12))
    surface = np.minimum(np.where(rays.sky, np.inf, rays.distance), RAY_REACH_M)
    enter, leave = medium.span(np.full(len(d), rays.origin[2]), d[:, 2], NUMPY)
    length = np.maximum(np.minimum(leave, surface) - enter, 0.0)
    panels = np.maximum(np.ceil(length / panel).astype(np.int64), 1)
    out = np.zeros(len(d))
    start = 0
    while start < len(d):  # rays in chunks of about 2^20 panels: bounded memory
        stop = start + max(1, int(np.searchsorted(np.cumsum(panels[start:]), 1 << 20)))
        count = panels[start:stop]
        ray = np.repeat(np.arange(start, stop), count)
        k = np.arange(len(ray)) - np.repeat(np.cumsum(count) - count, count)
        width = (length / panels)[ray]
        s = enter[ray, None] + (k + 0.5)[:, None] * width[:, None] + 0.5 * width[:, None] * nodes
        pts = rays.origin + s[..., None] * d[ray][:, None, :]
        rho = medium.density_at(pts[..., 0], pts[..., 1], pts[..., 2])
        out[start:stop] = np.bincount(
            ray - start, weights=0.5 * width * (rho @ weights), minlength=stop - start
        )
        start = stop
    return out


def panel_row(name: str, haze: dict[str, Any], res: tuple[int, int]) -> dict:
    """The module's quadrature against per-ray panels (:func:`ray_scaled_quadrature`) and
    half of them, all against per-ray panels eight times finer."""
    from seahaze.render.engine import open_session
    from seahaze.scene_medium import scene_haze_medium

    spec = scene_spec(haze, width=res[0], height=res[1], levels=graded_levels())
    session = open_session(spec)
    rays = session_rays(session)
    times: dict[str, float] = {}
    medium = scene_haze_medium(spec, session.camera)
    surface = np.where(rays.sky, np.inf, rays.distance)
    with timed(times, "module"):
        module = medium.ray_path_length(rays.origin, rays.directions, surface)
    with timed(times, "per_ray"):
        per_ray = ray_scaled_quadrature(medium, rays)
    with timed(times, "per_ray_2"):
        per_ray_2 = ray_scaled_quadrature(medium, rays, refine=2)
    fine = ray_scaled_quadrature(medium, rays, refine=8)
    return {
        "scene": name,
        "res": f"{res[0]}×{res[1]}",
        "module_s": times["module"],
        "per_ray_s": times["per_ray"],
        "module_err": float(np.max(np.abs(module - fine) / fine)),
        "per_ray_err": float(np.max(np.abs(per_ray - fine) / fine)),
        "per_ray_2_s": times["per_ray_2"],
        "per_ray_2_err": float(np.max(np.abs(per_ray_2 - fine) / fine)),
    }


# -- the section ----------------------------------------------------------------------------------
def section(results: dict[str, Any], quick: bool) -> list[str]:
    """The markdown of the benchmarks.md block."""

    a_res, b, check = results["a_res"], results["b"], results["mitsuba_check"]
    lines = [
        f"## Haze that varies across the sea: the reference's grid, reference vs asm, cost "
        f"({SCRIPT}{' --quick' if quick else ''})",
        "",
        f"Machine: {platform.machine()}, {len(os.sched_getaffinity(0))} vCPU (shared); "
        f"variant `{results['variant']}`. Scene: 12 m camera, 60° × 34°, pitch −1°, "
        "sea and 4 vessels; patchy: correlation 250 m, anisotropy 3, vertical 50 m, density "
        "ratio 20; bank: edge at 1000 m, bearing 20°, edge 60 m, near ratio 0.15; "
        '"bank at 60°" the same at bearing 60°. The box of a render of the 11 graded levels: '
        f"half width {results['half_width']:.0f} m, −60 … 300 m.",
        "",
        f"**(a) The grid against the exact optical depth** ({a_res[0]}×{a_res[1]} pixel-centre "
        "rays, up to the surface or the box's wall). Trilinear model checked against Mitsuba's "
        "medium in the patchy scene (20,000 random points of the box, 4000 m): extinction "
        f"within {check['sigma_t']:.1e} (relative, float32), majorant − σ·max(grid) "
        f"{check['majorant']:+.1e} (relative). "
        "|relative error| of `∫ρ ds` as median / 95th percentile / max; sea bias the mean "
        "signed error over sea pixels; max |ΔT| the largest transmittance error at any graded "
        "level (that level).",
        "",
        "| scene | grid (z, y, x) | cell x,y × z (m) | build (s) | float32 (MiB) | sea | "
        "sea bias | sky | max \\|ΔT\\| |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in results["a"]:
        lines.append(
            f"| {r['scene']} | {r['grid']} | {r['cell']} | {r['build_s']:.1f} | {r['mib']:.0f} | "
            f"{r['sea']} | {100.0 * r['sea_bias']:+.1f} % | {r['sky']} | {r['dT']:.4f} "
            f"({r['dT_level']:g} m) |"
        )
    for scene, rows in results["by_distance"].items():
        lines += [
            "",
            f"`GRID_SHAPE`, {scene}, sea pixels by distance:",
            "",
            "| distance | pixels | median / 95th pct / max | bias |",
            "|---|---|---|---|",
        ]
        for r in rows:
            lines.append(
                f"| {r['band']} | {r['pixels']} | {r['stats']} | {100.0 * r['bias']:+.1f} % |"
            )
    mem = results["memory"]
    lines += [
        "",
        f"Loading the patchy medium at `{GRID_SHAPE}` into Mitsuba (the density grid, its RGB "
        f"copy, Mitsuba's volume): {mem['s']:.1f} s, resident +{mem['resident']:.0f} MiB, "
        f"peak +{mem['peak']:.0f} MiB.",
        "",
        "Each level's own box at `GRID_SHAPE` (half width from its σ, at least 3 layer "
        "thicknesses) against the run's box, patchy: largest |ΔT| against the exact "
        "transmittance to 20 km (grid and wall together).",
        "",
        "| level (m) | own half width (m) | own cell (m) | \\|ΔT\\|, run's box | "
        "\\|ΔT\\|, own box |",
        "|---|---|---|---|---|",
    ]
    for r in results["levels"]:
        lines.append(
            f"| {r['level']:g} | {r['half']:.0f} | {r['cell']:.1f} | {r['run']:.4f} | "
            f"{r['own']:.4f} |"
        )
    lines += [
        "",
        "The box's wall at the clearest level (4000 m): rays that leave through the side "
        "before their surface or the top, the largest transmittance at the wall (the share of "
        "the world beyond it the reference shows unhazed) and the largest excess over the "
        "exact transmittance to 20 km.",
        "",
        "| scene | density scale c | rays through the side | max T at the wall | "
        "max T_box − T_exact |",
        "|---|---|---|---|---|",
    ]
    for r in results["walls"]:
        lines.append(
            f"| {r['scene']} | {r['scale']:.2f} | {r['rays']} of {r['of']} | "
            f"{r['T_wall']:.2e} | {r['dT']:.2e} |"
        )
    lines += [
        "",
        f"**(b) Reference against asm: transmittance of the sky** ({b['res'][0]}×{b['res'][1]}, "
        f"{b['spp']} spp, `reference` with albedo 0: `T_ref = I/J`). Mean over the sky pixels "
        "of each band of elevation: the exact map (pixel centres: what asm composites with), "
        "the grid model of (a) at pixel centres, the grid model's pixel-area mean minus its "
        f"centre value ({SUBPIXELS}×{SUBPIXELS} sub-rays), and the reference ± its standard "
        "error (binomial, from the grid model's area mean); z = (reference − grid area mean) / "
        "se. Sky pixels with a surface among their 8 neighbours are left out (part of their "
        f"area is a vessel or the sea), and bands where all three are below {MIN_T:g}.",
        "",
        "| scene | level (m) | band | pixels | T exact (asm) | T grid | area − centre | "
        "T reference | z vs grid |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in b["rows"]:
        area = r["grid"] + r["area"]
        z = f"{(r['ref'] - area) / r['se']:+.1f}" if r["se"] > 0 else "—"
        lines.append(
            f"| {r['scene']} | {r['level']:g} | {r['band']} | {r['pixels']} | "
            f"{r['exact']:.5f} | {r['grid']:.5f} | {r['area']:+.5f} | "
            f"{r['ref']:.5f} ± {r['se']:.5f} | {z} |"
        )
    lines += [
        "",
        "**(c) Cost of asm's quadrature.** First level (path lengths computed), all 11 graded "
        "levels (cached per scene), the process's memory peak over them above what it held "
        "before, and the scene load (geometry pass excluded; the airlight's grid medium "
        "included).",
        "",
        "| scene | size | first level (s) | 11 levels (s) | peak (MiB) | scene load (s) |",
        "|---|---|---|---|---|---|",
    ]
    for r in results["c"]:
        lines.append(
            f"| {r['scene']} | {r['res']} | {r['first']:.2f} | {r['all']:.2f} | "
            f"{r['peak']:.0f} | {r['scene_load']:.1f} |"
        )
    lines += [
        "",
        "Panels per ray: the module's quadrature (panels of the horizontal scale across the "
        "drift, and of the vertical scale over the ray's climb) against panels of one and of "
        "half the finest lattice step along each ray (its direction against the drift and "
        "the height), all against the latter eight times finer (largest relative error).",
        "",
        "| scene | size | module (s) | module's error | per-ray panels (s) | error | "
        "half per-ray panels (s) | error |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in results["panels"]:
        lines.append(
            f"| {r['scene']} | {r['res']} | {r['module_s']:.1f} | {r['module_err']:.1e} | "
            f"{r['per_ray_s']:.1f} | {r['per_ray_err']:.1e} | {r['per_ray_2_s']:.1f} | "
            f"{r['per_ray_2_err']:.1e} |"
        )
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smaller sizes, fewer samples")
    parser.add_argument("--doc", action="store_true", help="write docs/benchmarks.md's section")
    args = parser.parse_args()
    from seahaze.render.variant import select_variant

    quick = args.quick
    a_res = (160, 90) if quick else (320, 180)
    b_res, b_spp = (160, 90), 16 if quick else 64
    c_sizes = [(160, 90), (320, 180)] if quick else [(160, 90), (320, 180), (640, 360)]
    shapes = [COARSE_SHAPE, GRID_SHAPE, *FINER_SHAPES] + ([] if quick else [FINEST_SHAPE])
    results: dict[str, Any] = {"a_res": a_res, "variant": select_variant("auto")}
    started = time.perf_counter()

    def say(text: str) -> None:
        print(f"[{time.perf_counter() - started:6.0f} s] {text}", flush=True)

    results["mitsuba_check"] = check_against_mitsuba()
    results["a"], results["walls"] = [], []
    for name in ("patchy", "bank", "bank at 60°"):
        case = grid_case(name, HAZES[name], a_res)
        results["half_width"] = float(0.5 * (case.rays.box_max[0] - case.rays.box_min[0]))
        results["walls"].append(wall_row(case))
        if name != "bank at 60°":
            results["a"] += grid_rows(case, shapes)
            results.setdefault("by_distance", {})[name] = case.by_distance or []
        if name == "patchy":
            results["levels"] = level_box_rows(case, [300.0, 1000.0, 4000.0])
        say(f"(a) {name} done")
    results["memory"] = grid_memory_mib()
    rows = []
    for name in ("patchy", "bank"):
        rows += transmittance_rows(name, HAZES[name], b_res, b_spp, [300.0, 1000.0, 4000.0])
        say(f"(b) {name} done")
    # Replicates of the clearest level with other seeds: the bank's field does not depend on
    # the seed (the patches' does), so they show the reference's spread about the same model.
    for seed in B_REPLICATE_SEEDS:
        rows += transmittance_rows("bank", BANK, b_res, b_spp, [4000.0], seed)
    say("(b) replicates done")
    results["b"] = {"res": b_res, "spp": b_spp, "rows": rows}
    results["c"] = []
    for res in c_sizes:
        for name in ("uniform", "fog layer", "patchy", "bank"):
            results["c"].append(cost_row(name, HAZES[name], res))
            say(f"(c) {name} {res} done")
    results["panels"] = [panel_row(name, HAZES[name], c_sizes[1]) for name in ("patchy", "bank")]
    say("panels done")
    lines = section(results, quick)
    print("\n".join(lines))
    if args.doc:
        replace_section("nonuniform", "\n".join(lines), SCRIPT)


if __name__ == "__main__":
    main()
