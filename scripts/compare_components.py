"""`physical` against Mitsuba `volpath` on the benchmark scene at any visibility, with the sun or
the sky switched off and any phase asymmetry ``g``: which light the physical mode gets wrong.

The benchmark scene (``scenes/benchmark.yaml``, 80×45) is rendered at visibility ``V`` by
``volpath`` (``--batches`` independent batches of 1024 spp, seeds past those of the stored
references) and by ``physical`` (2^20-photon tables, four sampler seeds at 256 spp), both with
the scene's ``sun.scale`` and ``sky.scale`` replaced by ``--sun`` and ``--sky`` and ``haze.g`` by
``--g`` (and the camera's heading by ``--heading``: 150° looks toward the sun; the sky by
``--sky-model``, e.g. ``overcast``, ``twilight`` (with a sun below the horizon) or ``broken``
with ``--cloud-seed`` choosing its cloud layer,
and the sun's elevation by ``--sun-elevation``, the wind by ``--wind``); then both
without haze. It prints, per region (sea, sky, all vessels, and each of the
first three vessels), the relative difference of the region means, physical against volpath,
± the volpath mean's standard error (from its batches).

``--fog-layer TOP,EDGE,ABOVE`` gives the haze a fog layer (``haze.fog_layer``: top and edge
in metres, the density above as a share of the fog's) and ``--height`` the camera's height,
in or above it. ``--patches CORRELATION,ANISOTROPY,VERTICAL,RATIO`` (m, ratio, m, max/min)
and ``--bank DISTANCE,BEARING,EDGE,NEAR`` (m, deg, m, ratio) make it vary across the sea
(``haze.patches``, ``haze.bank``); sea, sky and vessels are then also compared apart where
each pixel's ray holds more haze than the level's mean (``dense``: a density ratio above
1.5, :mod:`seahaze.render.pixel_density`) and less (``thin``: below 1/1.5).

``--cache DIR`` keeps the volpath means there, keyed by the scene, the level and the batch
count, so that a change to ``physical`` is compared again without tracing them again.

``--vessel-light SHARE`` sets the share of the samples of the pass for the haze in front of
vessels (the renderer's own by default; 0 leaves it out; docs/physics.md, "Haze in front of
a vessel"). With ``--pitch`` and ``--fov`` the
camera looks up or down steeply (the haze's light from directions a level view never
samples), and ``--bands N`` splits sky and sea into N row bands.

Usage: python scripts/compare_components.py V [--batches 8] [--g 0.75] [--sun 1] [--sky 1]
       [--sky-model clear|broken|overcast|twilight] [--cloud-seed N] [--sun-elevation DEG]
       [--wind M/S] [--heading DEG] [--pitch DEG] [--fov DEG] [--bands N] [--vessel-light SHARE]
       [--fog-layer TOP,EDGE,ABOVE] [--height M] [--patches C,A,V,R] [--bank D,B,E,N]
       [--cache DIR]
"""

from __future__ import annotations

import argparse
import dataclasses
import hashlib
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
# The benchmark's scene and levels (the reference's haze box is sized for them and ``V``).
from bench_modes import LEVELS, SCENE, region_masks, region_mean_stderr


def volpath_luminance(session, sigma, albedo: float, g: float, batches: int, offset: int):
    """Mean luminance and its standard error over ``batches`` volpath batches of 1024 spp."""
    from seahaze.imaging import luminance
    from seahaze.render import passes
    from seahaze.seeds import RenderPass, render_seed

    session.loaded.set_haze(sigma, albedo, g)
    seed0 = session.loaded.spec.render.seed
    runs = [
        luminance(
            passes.render_radiance(
                session.loaded,
                1024,
                render_seed(seed0, RenderPass.CONVERGED_REFERENCE, 7, offset + b),
            )
        )
        for b in range(batches)
    ]
    return np.mean(runs, 0), np.std(runs, 0, ddof=1) / np.sqrt(batches)


def level_reference(base, v: float, sigma, batches: int, cache: Path | None):
    """The ``reference`` session of scene ``base`` at level ``v`` (extinction ``sigma``, RGB),
    the key its figures are cached under, and the level's ``volpath`` mean luminance and
    standard error over ``batches`` batches (:func:`volpath_luminance`), from ``cache`` when
    there."""
    from seahaze.render.engine import open_session
    from seahaze.spec import with_overrides

    haze = base.haze
    session = open_session(with_overrides(base, mode="reference", levels=sorted({*LEVELS, v})))
    key = f"{session.loaded.spec.model_dump_json()}|{sigma}|{batches}"
    figures = cached(
        cache, key, lambda: volpath_luminance(session, sigma, haze.albedo, haze.g, batches, 200000)
    )
    return session, key, figures


def physical_renderer(base, v: float, settings=None):
    """The ``physical`` session of scene ``base`` at level ``v`` and its renderer with
    ``settings`` (None: the defaults) and the largest diffuse tables."""
    from seahaze.render.engine import open_session
    from seahaze.render.estimator import EstimatorSettings
    from seahaze.render.physical import PhysicalRenderer
    from seahaze.spec import with_overrides

    spec = with_overrides(base, mode="physical", levels=[v])
    session = open_session(spec)
    settings = settings or EstimatorSettings()
    settings = dataclasses.replace(settings, table_photons=settings.max_table_photons)
    return session, PhysicalRenderer(session.loaded, spec, settings)


def physical_luminance(renderer, sigma, haze) -> tuple[np.ndarray, np.ndarray]:
    """The level's and the clean image's mean luminance over four seeds at 256 spp."""
    from seahaze.imaging import luminance

    runs = [renderer.render([sigma], haze.albedo, haze.g, 256, seed) for seed in range(1, 5)]
    level = np.mean([luminance(r.levels[0]) for r in runs], 0)
    return level, np.mean([luminance(r.clean) for r in runs], 0)


def region_error(image, ref, ref_se, mask) -> tuple[float, float]:
    """``image``'s mean over ``mask`` against the reference's, relative, and the reference
    mean's relative standard error."""
    mean = ref[mask].mean()
    return image[mask].mean() / mean - 1.0, region_mean_stderr(ref_se, mask, mean)


def cached(cache: Path | None, key: str, compute):
    """``compute()`` (a tuple of arrays), kept in ``cache`` under a digest of ``key``."""
    if cache is None:
        return compute()
    path = cache / f"{hashlib.blake2b(key.encode(), digest_size=12).hexdigest()}.npz"
    if path.exists():
        with np.load(path) as stored:
            return tuple(stored[f"a{i}"] for i in range(len(stored.files)))
    result = compute()
    cache.mkdir(parents=True, exist_ok=True)
    np.savez(path, **{f"a{i}": a for i, a in enumerate(result)})
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("visibility", type=float, help="V in metres")
    parser.add_argument("--batches", type=int, default=8, help="volpath batches of 1024 spp")
    parser.add_argument("--g", type=float, default=None, help="haze.g (default: the scene's)")
    parser.add_argument("--sun", type=float, default=1.0, help="sun.scale")
    parser.add_argument("--sky", type=float, default=1.0, help="sky.scale")
    parser.add_argument(
        "--sky-model",
        choices=("clear", "broken", "overcast", "twilight"),
        default=None,
        help="sky.model",
    )
    parser.add_argument(
        "--cloud-seed", type=int, default=None, help="sky.clouds.seed of a broken sky"
    )
    parser.add_argument("--sun-elevation", type=float, default=None, help="sun.elevation_deg")
    parser.add_argument(
        "--wind", type=float, default=None, help="sea.wind_speed (m/s), e.g. 19 for a gale's foam"
    )
    parser.add_argument(
        "--heading", type=float, default=None, help="camera.heading_deg (default: the scene's)"
    )
    parser.add_argument("--height", type=float, default=None, help="camera.height_m")
    parser.add_argument(
        "--fog-layer",
        default=None,
        help="haze.fog_layer as TOP,EDGE,ABOVE (m, m, ratio), e.g. 25,3,0.25",
    )
    parser.add_argument(
        "--patches",
        default=None,
        help="haze.patches as CORRELATION,ANISOTROPY,VERTICAL,RATIO, e.g. 400,3,60,30",
    )
    parser.add_argument(
        "--bank", default=None, help="haze.bank as DISTANCE,BEARING,EDGE,NEAR, e.g. 900,0,80,0.2"
    )
    parser.add_argument("--pitch", type=float, default=None, help="camera.pitch_deg")
    parser.add_argument("--fov", type=float, default=None, help="camera.fov_deg")
    parser.add_argument(
        "--bands", type=int, default=0, help="also compare sky and sea in this many row bands"
    )
    parser.add_argument(
        "--vessel-light",
        type=float,
        default=None,
        help="the vessel-light pass's share of the samples (0: off; default: the renderer's)",
    )
    parser.add_argument("--cache", type=Path, default=None, help="keep volpath means here")
    args = parser.parse_args()

    from seahaze.render.estimator import EstimatorSettings
    from seahaze.sceneio import load_scene
    from seahaze.spec import with_changes
    from seahaze.visibility import channel_extinction

    base, _ = load_scene(SCENE)
    changes: dict = {"sun": {"scale": args.sun}, "sky": {"scale": args.sky}}
    if args.sky_model is not None:
        changes["sky"]["model"] = args.sky_model
    if args.cloud_seed is not None:
        changes["sky"]["clouds"] = {"seed": args.cloud_seed}
    if args.sun_elevation is not None:
        changes["sun"]["elevation_deg"] = args.sun_elevation
    if args.wind is not None:
        changes["sea"] = {"wind_speed": args.wind}
    if args.g is not None:
        changes["haze"] = {"g": args.g}
    if args.fog_layer is not None:
        top, edge, above = (float(x) for x in args.fog_layer.split(","))
        fog = {"top_m": top, "edge_m": edge, "above_ratio": above}
        changes.setdefault("haze", {})["fog_layer"] = fog
    if args.patches is not None:
        corr, aniso, vertical, ratio = (float(x) for x in args.patches.split(","))
        patches = {"correlation_m": corr, "anisotropy": aniso, "vertical_m": vertical}
        changes.setdefault("haze", {})["patches"] = patches | {"density_ratio": ratio}
    if args.bank is not None:
        distance, bearing, edge, near = (float(x) for x in args.bank.split(","))
        bank = {"distance_m": distance, "bearing_deg": bearing, "edge_m": edge}
        changes.setdefault("haze", {})["bank"] = bank | {"near_ratio": near}
    camera = {
        key: value
        for key, value in (
            ("height_m", args.height),
            ("heading_deg", args.heading),
            ("pitch_deg", args.pitch),
            ("fov_deg", args.fov),
        )
        if value is not None
    }
    if camera:
        changes["camera"] = camera
    base = with_changes(base, changes)
    haze = base.haze
    v = args.visibility
    sigma = channel_extinction(v, haze.threshold, haze.extinction_spectrum)
    start = time.perf_counter()
    reference, key, (ref, ref_se) = level_reference(base, v, sigma, args.batches, args.cache)
    clean_ref, _ = cached(
        args.cache,
        key + "|clean",
        lambda: volpath_luminance(reference, 0.0, haze.albedo, haze.g, 4, 300000),
    )

    settings = None
    if args.vessel_light is not None:
        settings = EstimatorSettings(vessel_light_share=args.vessel_light)
    session, renderer = physical_renderer(base, v, settings)
    phys, clean = physical_luminance(renderer, sigma, haze)

    pixels = session.pixels
    regions = region_masks(pixels.distance_m, pixels.instance)
    regions |= {f"vessel {i}": pixels.instance == i for i in range(3)}
    rows = np.arange(pixels.instance.shape[0])[:, None] * np.ones_like(pixels.instance)
    if renderer.field is not None:
        from seahaze.render.pixel_density import pixel_density_ratio

        ratio = pixel_density_ratio(renderer.field, renderer.geometry)
        for name in ("sea", "sky", "vessel"):
            regions[f"{name} dense"] = regions[name] & (ratio > 1.5)
            regions[f"{name} thin"] = regions[name] & (ratio < 1 / 1.5)
    for band in np.array_split(np.arange(rows.shape[0]), args.bands) if args.bands else []:
        in_band = np.isin(rows, band)
        for name in ("sky", "sea"):
            regions[f"{name} r{band[0]}-{band[-1]}"] = regions[name] & in_band
    fog = haze.fog_layer
    layer = "" if fog is None else f", fog layer to {fog.top_m:g} m (×{fog.above_ratio:g} above)"
    layer += "" if args.patches is None else f", patches {args.patches}"
    layer += "" if args.bank is None else f", bank {args.bank}"
    print(
        f"V = {v:g} m, g = {haze.g}, sun × {args.sun}, sky × {args.sky} ({base.sky.model}, "
        f"sun at {base.sun.elevation_deg:g}°), camera at {base.camera.height_m:g} m{layer}; "
        f"{time.perf_counter() - start:.0f} s"
    )
    for name, m in regions.items():
        if not m.any():
            continue
        diff, se = region_error(phys, ref, ref_se, m)
        clean_diff = clean[m].mean() / clean_ref[m].mean() - 1.0
        print(
            f"  {name:13s} hazy {100 * diff:+6.2f} ± {100 * se:.2f} %   "
            f"clean {100 * clean_diff:+6.2f} %"
        )


if __name__ == "__main__":
    main()
