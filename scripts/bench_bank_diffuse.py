"""What would a fog bank's own diffuse field fix in the ``physical`` mode?

``physical`` renders a bank as each pixel's equivalent profile, and reads the diffuse field
(everything but the sun's single scattering) from tables traced in a horizontally homogeneous
haze. Against the ``reference`` mode it is 2–20 % off in a bank (docs/physics.md, "Haze that
varies across the sea in the physical mode"), which that section puts down to light that
crosses the bank's edge. This script measures how much of that a diffuse field of the bank
itself would fix, before anyone builds it into the renderer:

1. Photons are traced through the bank (a strip across its edge: the bank varies along one
   horizontal axis), with the tables' sources and sea (the scene's own emitters and sea BSDF
   samples), delta tracking against the bank's densest point, and the collision estimator of
   the directional fluence in cells of distance across the edge × height × direction. The
   same bins of a horizontally homogeneous haze at the level's extinction come from the
   renderer's own photon tracer.
2. Per pixel and level, the camera ray's diffuse in-scattering ``∫ e^{−τ} J ds`` is summed at
   its true points through the bank, and over the pixel's equivalent profile (its ``view``
   ratio) with the homogeneous haze's ``J``; their quotient is the pixel's ``diffuse_air``
   ratio. On the sea the same along the camera ray mirrored in a flat sea (the ``bounce``
   ratio's ray) gives ``diffuse_bounce``. The render's kernels scale the diffuse field of the
   camera segment and of the later segments by them (``PixelRatios.diffuse_air`` and
   ``diffuse_bounce``).
3. ``physical`` with and without the ratios is compared per region with converged ``volpath``
   references, as ``scripts/compare_components.py`` does (its cache is shared).

The tracer here is numpy and is run at a few million photons: its own noise is stated by
running it with two seeds.

Usage: python scripts/bench_bank_diffuse.py [--cases 1000,1000:sky,1000:sun,300,4000]
       [--photons 2097152] [--seeds 5,9] [--cache DIR] [--no-bounce] [--doc]
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_modes import SCENE, region_masks
from bench_passes import replace_section
from compare_components import level_reference, physical_luminance, physical_renderer, region_error
from seahaze.render.diffuse_table import TableGrid, bin_directions, direction_bins

ROOT = Path(__file__).resolve().parents[1]
BANK = {"distance_m": 900.0, "bearing_deg": 0.0, "edge_m": 80.0, "near_ratio": 0.2}
"""The bank of docs/physics.md's comparison (``compare_components.py --bank 900,0,80,0.2``)."""
N_S = 46
"""Cells across the edge."""
GRID = TableGrid(n_z=12, n_mu=24, n_phi=24, folded=False)
"""Heights and directions, the diffuse tables' bins: ``μ`` over [−1, 1], world azimuth over
[−π, π) (its sun azimuth taken as 0: a bank is not symmetric about the sun's vertical
plane)."""
N_Z = GRID.n_z
WINDOW_M = (-1500.0, 3900.0)
"""The strip tallied, across the edge from the camera's start: from 1.5 km behind the camera
to 3 km past the edge (beyond, the field is the bank's plane-parallel one: the last cell's)."""
MARGIN_M = 3000.0
"""Photons start over the window widened by this on each side, and leave at twice it."""
RAY_POINTS = 160
"""Points of each ray's sum, in cells growing quadratically from its start."""
WEIGHT_FLOOR = 1e-2
"""Russian roulette below this fraction of the mean source weight (the renderer's value)."""


@dataclasses.dataclass(frozen=True)
class Strip:
    """The bank's density on a grid over distance across its edge ``s`` and height ``z``."""

    s: np.ndarray
    dz: float
    top: float
    density: np.ndarray

    @property
    def densest(self) -> float:
        """The largest density of the strip (the delta tracking's majorant, per σ)."""
        return float(self.density.max())

    def at(self, s: np.ndarray, z: np.ndarray) -> np.ndarray:
        """The density at distances ``s`` across the edge and heights ``z`` (nearest node)."""
        ds = self.s[1] - self.s[0]
        i = np.clip(np.round((s - self.s[0]) / ds).astype(np.int64), 0, len(self.s) - 1)
        j = np.clip((z / self.dz).astype(np.int64), 0, self.density.shape[1] - 1)
        return self.density[i, j]


def bank_strip(medium: Any, normal: np.ndarray, s0: float, s1: float, top: float) -> Strip:
    """The medium's density on a 2 m × 5 m grid along the bank's normal through the world's
    origin (the camera's start in the benchmark scene), from ``s0`` to ``s1`` metres."""
    s = np.arange(s0, s1 + 2.0, 2.0)
    nz = round(top / 5.0)
    z = (np.arange(nz) + 0.5) * top / nz
    grid_s, grid_z = np.meshgrid(s, z, indexing="ij")
    density = medium.density_at(grid_s * normal[0], grid_s * normal[1], grid_z)
    return Strip(s, top / nz, top, density)


def bank_normal() -> np.ndarray:
    """The bank's horizontal normal (world x, y): its bearing from the camera's start."""
    bearing = np.radians(BANK["bearing_deg"])
    return np.array([np.cos(bearing), np.sin(bearing)])


def direction_bin(d: np.ndarray) -> np.ndarray:
    """The :data:`GRID` direction bin of unit travel directions ``d`` (N, 3)."""
    mu, phi = direction_bins(d, 0.0, GRID.n_mu, GRID.n_phi, GRID.folded)
    return mu * GRID.n_phi + phi


def trace_strip(
    strip: Strip,
    sigma: float,
    optics: tuple,
    photons: tuple,
    sea: Any,
    normal: np.ndarray,
    seed: int,
) -> np.ndarray:
    """Directional fluence ``Φ[s, z, dir, rgb]`` (W m⁻²) of the bank's diffuse field: the
    sun's first flight untallied (the kernels' direct light), the sky's tallied from the top."""
    from seahaze.haze import hg_sample_cos, rotate_directions

    albedo, g = optics
    (sun_d, sun_w), (sky_d, sky_w) = photons
    rng = np.random.default_rng(seed)
    lo, hi = WINDOW_M
    span = hi - lo + 2.0 * MARGIN_M
    ds, dz = (hi - lo) / N_S, strip.top / N_Z
    majorant = sigma * strip.densest
    tally = np.zeros(N_S * N_Z * GRID.n_dir * 3)
    d = np.concatenate([sun_d, sky_d])
    # A photon's horizontal irradiance spread over the launch span: power per metre of edge.
    w = np.concatenate([sun_w, sky_w]) * span
    direct = np.arange(len(d)) < len(sun_d)
    s = lo - MARGIN_M + span * rng.random(len(d))
    z = np.full(len(d), strip.top)
    floor = WEIGHT_FLOOR * float(np.concatenate([sun_w, sky_w]).max(axis=1).mean()) * span
    while len(s):
        free = -np.log1p(-rng.random(len(s))) / majorant
        up = d[:, 2]
        with np.errstate(divide="ignore"):
            wall = np.where(up > 0, (strip.top - z) / up, np.where(up < 0, -z / up, np.inf))
        collide = free < wall
        step = np.minimum(free, wall)
        s = s + step * (d[:, :2] @ normal)
        z = np.clip(z + step * up, 0.0, strip.top)
        # Every tentative collision scores w / σ̄: its expectation is the track length.
        score = collide & ~direct & (s >= lo) & (s < hi)
        if score.any():
            cell = ((s[score] - lo) / ds).astype(np.int64) * N_Z + np.minimum(
                (z[score] / dz).astype(np.int64), N_Z - 1
            )
            key = (cell * GRID.n_dir + direction_bin(d[score]))[:, None] * 3 + np.arange(3)
            tally += np.bincount(key.ravel(), (w[score] / majorant).ravel(), tally.size)
        real = collide & (rng.random(len(s)) * strip.densest < strip.at(s, z))
        n_real = int(real.sum())
        if n_real:
            turn = (hg_sample_cos(rng.random(n_real), g), 2.0 * np.pi * rng.random(n_real))
            d[real] = rotate_directions(d[real], *turn)
            w[real] *= albedo
            direct[real] = False
        at_sea = ~collide & (up < 0)
        if at_sea.any():
            d[at_sea], sea_w = sea.reflect(d[at_sea], rng)
            w[at_sea] *= sea_w
            z[at_sea] = 0.0
            direct[at_sea] = False
        keep = (collide | at_sea) & (s > lo - 2 * MARGIN_M) & (s < hi + 2 * MARGIN_M)
        brightest = w.max(axis=1)
        low = brightest < floor
        survive = ~low | (rng.random(len(s)) * floor < brightest)
        lift = np.where(low & survive, floor / np.maximum(brightest, 1e-300), 1.0)
        w = w * lift[:, None]
        keep &= survive & (d[:, 2] != 0.0)
        s, z, d, w, direct = s[keep], z[keep], d[keep], w[keep], direct[keep]
    return tally.reshape(N_S, N_Z, GRID.n_dir, 3) / (ds * dz)


def homogeneous_fluence(
    sigma: float, optics: tuple, photons: tuple, sea: Any, top: float, seed: int
) -> np.ndarray:
    """``Φ[s, z, dir, rgb]`` of the horizontally homogeneous haze at ``sigma``, in the strip's
    bins, from the renderer's own photon tracer (the same at every ``s``)."""
    from seahaze.render.photon_tracer import Slab, trace_fluence

    slab = Slab(top, optics[0], optics[1], 0.0, GRID.n_z, GRID.n_mu, GRID.n_phi, GRID.folded)
    fluence = trace_fluence(*photons, sea, [sigma], slab, seed)[0]
    return np.broadcast_to(fluence, (N_S, *fluence.shape))


def phase_toward(travel: np.ndarray, g: float, sub: int = 3) -> np.ndarray:
    """``P[ray, dir]``: the HG phase value (1/sr) from each direction bin (averaged over
    ``sub × sub`` points of it) into the travel directions ``travel`` (N, 3)."""
    from seahaze.haze import hg_phase

    points = bin_directions(GRID, sub, mirror=False).reshape(GRID.n_dir, -1, 3)
    return np.stack([hg_phase(travel @ p.T, g).mean(axis=1) for p in points], axis=1)


def ray_diffuse(fluence, strip, density_of, sigma, albedo, phase, origins, dirs, reach, lo):
    """Per ray: the points' distances and widths (m), ``J`` toward the ray's start (per metre)
    and the optical depth to each point, through ``density_of(s, z)``."""
    edges = (np.arange(RAY_POINTS + 1) / RAY_POINTS) ** 2
    along = 0.5 * (edges[:-1] + edges[1:])[None] * reach[:, None]
    width = np.diff(edges)[None] * reach[:, None]
    p = origins[:, None, :] + along[..., None] * dirs[:, None, :]
    s = p[..., :2] @ bank_normal()
    z = np.clip(p[..., 2], 0.0, strip.top)
    rho = density_of(s.ravel(), z.ravel()).reshape(s.shape)
    ds = (WINDOW_M[1] - lo) / N_S
    cell = np.clip(((s - lo) / ds).astype(np.int64), 0, N_S - 1) * N_Z + np.clip(
        (z / (strip.top / N_Z)).astype(np.int64), 0, N_Z - 1
    )
    luminance = np.array([0.2126, 0.7152, 0.0722])
    per_cell = phase @ (fluence @ luminance).reshape(N_S * N_Z, -1).T  # (ray, cell)
    j = albedo * sigma * rho * per_cell[np.arange(len(dirs))[:, None], cell]
    depth = np.cumsum(sigma * rho * width, axis=1) - 0.5 * sigma * rho * width
    return along, width, j, depth


def diffuse_ratio(bank, homogeneous, strip, sigma, albedo, g, origins, dirs, reach, r_eq):
    """``diffuse`` ratio per ray: ``∫ e^{−τ} J ds`` at its true points through the bank over
    the same in the pixel's equivalent profile (extinction ``σ r``, the homogeneous ``J``
    times ``r``)."""
    phase = phase_toward(-dirs, g)
    lo = WINDOW_M[0]
    _, width, j_bank, depth = ray_diffuse(
        bank, strip, strip.at, sigma, albedo, phase, origins, dirs, reach, lo
    )
    ones = lambda s, z: np.ones_like(s)  # noqa: E731
    along, _, j_mean, _ = ray_diffuse(
        homogeneous, strip, ones, sigma, albedo, phase, origins, dirs, reach, lo
    )
    true = np.sum(np.exp(-depth) * j_bank * width, axis=1)
    r = r_eq[:, None]
    equivalent = np.sum(np.exp(-sigma * r * along) * r * j_mean * width, axis=1)
    return np.where(equivalent > 1e-30, true / np.maximum(equivalent, 1e-30), 1.0)


def frame_ratios(
    renderer: Any, own: Any, sigma: float, photons: int, seed: int, bounce: bool = True
) -> Any:
    """The renderer's :class:`PixelRatios` at level ``sigma`` (green, 1/m), from ``own`` (its
    own ``pixel_ratios``), with the bank's ``diffuse_air`` and ``diffuse_bounce`` added
    (without ``bounce``, ``diffuse_bounce`` 1: the later segments keep the tables' light)."""
    from seahaze.render.photon_sources import emitter_photons

    field, optics = renderer.field, (renderer.field.albedo, renderer.field.g)
    ratios = own(np.array([sigma]))
    geometry, top = renderer.geometry, field.top
    downward = lambda p: (p[0][p[0][:, 2] < -1e-6], p[1][p[0][:, 2] < -1e-6])  # noqa: E731
    sources = tuple(
        downward(emitter_photons(e, photons // 2, seed + i, top))
        for i, e in enumerate((renderer.sun, renderer.sky))
    )
    strip = bank_strip(
        field,
        bank_normal(),
        WINDOW_M[0] - 2 * MARGIN_M - 10.0,
        WINDOW_M[1] + 2 * MARGIN_M + 10.0,
        top,
    )
    bank = trace_strip(strip, sigma, optics, sources, renderer.sea, bank_normal(), seed)
    mean = homogeneous_fluence(sigma, optics, sources, renderer.sea, top, seed)
    height, width = geometry.distance_m.shape
    dirs = geometry.directions.reshape(-1, 3).astype(np.float64)
    distance = geometry.distance_m.reshape(-1).astype(np.float64)
    origins = np.broadcast_to(np.asarray(geometry.origin, np.float64), dirs.shape)
    reach = np.minimum(distance, 20000.0)
    up = dirs[:, 2] > 0.0
    reach[up] = np.minimum(reach[up], (top - origins[up, 2]) / dirs[up, 2])
    common = (bank, mean, strip, sigma, optics[0], optics[1])
    air = diffuse_ratio(*common, origins, dirs, reach, ratios.view.reshape(-1))
    later = np.ones_like(air)
    sea = np.isfinite(distance) & (geometry.instance.reshape(-1) < 0)
    if bounce and sea.any():
        points = origins[sea] + distance[sea, None] * dirs[sea]
        mirrored = dirs[sea] * np.array([1.0, 1.0, -1.0])
        reach = np.minimum((top - points[:, 2]) / np.maximum(mirrored[:, 2], 1e-9), 20000.0)
        r_mirror = ratios.bounce.reshape(-1)[sea]
        later[sea] = diffuse_ratio(*common, points, mirrored, reach, r_mirror)
    shape = (1, height, width)
    return dataclasses.replace(
        ratios, diffuse_air=air.reshape(shape), diffuse_bounce=later.reshape(shape)
    )


def region_errors(renderer, session, sigma_rgb, haze, reference) -> dict:
    """Per region: ``physical``'s mean over four seeds at 256 spp against the reference
    (``(mean, standard error)``), relative, and the reference's relative standard error."""
    image, _ = physical_luminance(renderer, sigma_rgb, haze)
    pixels = session.pixels
    return {
        name: region_error(image, *reference, mask)
        for name, mask in region_masks(pixels.distance_m, pixels.instance).items()
    }


def measure(
    case: str, photons: int, seeds: list[int], cache: Path | None, bounce: bool = True
) -> dict:
    """One case (``V`` or ``V:sky`` / ``V:sun``: that light alone): the regions' errors
    without the ratios and with them at each seed of the bank's tracer."""
    from seahaze.sceneio import load_scene
    from seahaze.spec import with_changes
    from seahaze.visibility import channel_extinction

    v_text, _, light = case.partition(":")
    v = float(v_text)
    scales = {"sun": 1.0 if light != "sky" else 0.0, "sky": 1.0 if light != "sun" else 0.0}
    base, _ = load_scene(SCENE)
    changes = {"sun": {"scale": scales["sun"]}, "sky": {"scale": scales["sky"]}}
    base = with_changes(base, changes | {"haze": {"bank": dict(BANK)}})
    haze = base.haze
    sigma = channel_extinction(v, haze.threshold, haze.extinction_spectrum)
    # The references of compare_components.py (the same key: its cache is shared).
    batches = 8 if v == 1000.0 else 4
    _, _, reference = level_reference(base, v, sigma, batches, cache)
    session, renderer = physical_renderer(base, v)
    result = {"without": region_errors(renderer, session, sigma, haze, reference)}
    green = float(sigma[1])
    own = renderer.pixel_ratios
    for seed in seeds:
        start = time.perf_counter()
        ratios = frame_ratios(renderer, own, green, photons, seed, bounce)
        traced = time.perf_counter() - start
        # The renderer asks for its pixels' ratios: these, with the bank's diffuse ones.
        renderer.pixel_ratios = lambda levels, ratios=ratios: ratios
        result[f"seed {seed}"] = region_errors(renderer, session, sigma, haze, reference)
        result[f"seed {seed}"]["traced_s"] = (traced, 0.0)
    return result


def table(results: dict, photons: int, bounce: bool = True) -> str:
    """The results as docs/benchmarks.md's table, its caption saying how they were made."""
    import platform

    lines = [
        "## A bank's own diffuse field in the physical mode (scripts/bench_bank_diffuse.py)",
        "",
        f"Machine: {platform.machine()}, `llvm_ad_rgb`. Benchmark scene (80×45), bank "
        f"{BANK['distance_m']:g} m ahead, bearing {BANK['bearing_deg']:g}°, edge "
        f"{BANK['edge_m']:g} m, near side {BANK['near_ratio']:g}; `physical` 4 × 256 spp against "
        "the `volpath` references of compare_components.py (± their standard error); the "
        f"bank's tracer {photons:,} photons per seed"
        + ("" if bounce else "; `diffuse_bounce` left at 1 (the camera segment's alone)")
        + ". Per cent, physical against the reference.",
        "",
        "| V (m), light | ratios | sea | sky | vessels | bank traced in (s) |",
        "|---|---|---|---|---|---|",
    ]
    for case, rows in results.items():
        v, _, light = case.partition(":")
        label = f"{v}, {light or 'sun and sky'}" + (" alone" if light else "")
        for name, regions in rows.items():
            cells = [
                f"{100 * regions[r][0]:+.2f} ± {100 * regions[r][1]:.2f}"
                for r in ("sea", "sky", "vessel")
            ]
            traced = f"{regions['traced_s'][0]:.0f}" if "traced_s" in regions else "—"
            lines.append(f"| {label} | {name} | {' | '.join(cells)} | {traced} |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument(
        "--cases",
        default="1000,1000:sky,1000:sun,300,4000",
        help="visibilities (m), each alone or with :sky or :sun for that light alone",
    )
    parser.add_argument("--photons", type=int, default=2**21, help="the bank tracer's photons")
    parser.add_argument("--seeds", default="5,9", help="the bank tracer's seeds, one run each")
    parser.add_argument(
        "--cache",
        type=Path,
        default=ROOT / "out" / "compare-cache",
        help="where the volpath references are kept (compare_components.py's --cache)",
    )
    parser.add_argument(
        "--no-bounce",
        action="store_true",
        help="leave diffuse_bounce at 1 (only the camera segment's diffuse field is scaled)",
    )
    parser.add_argument("--doc", action="store_true", help="write the table into docs/")
    args = parser.parse_args()
    seeds = [int(x) for x in args.seeds.split(",")]
    results = {}
    for case in args.cases.split(","):
        results[case] = measure(case, args.photons, seeds, args.cache, not args.no_bounce)
        print(table({case: results[case]}, args.photons).split("|---|")[-1], flush=True)
    text = table(results, args.photons, not args.no_bounce)
    print(text)
    if args.doc:
        replace_section("bank-diffuse", text, "scripts/bench_bank_diffuse.py")


if __name__ == "__main__":
    main()
