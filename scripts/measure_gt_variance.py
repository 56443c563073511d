"""Where the clean image's Monte Carlo noise comes from, by image region and by light path.

A diagnostic integrator traces the same camera paths as the ``physical`` mode's clean image
(:mod:`seahaze.render.haze_integrator`: emitter sampling of the scene's ``sunsky`` and BSDF
sampling, power-heuristic MIS, the default ``EstimatorSettings.bounces``
bounces) but adds each contribution to one of these disjoint path classes (their sum is the
clean radiance):

``camera``       sky or sun seen directly from the camera;
``d1_nee_sun``   first surface, emitter sample that lands in the sun's disk;
``d1_nee_sky``   first surface, emitter sample in the sky;
``d1_bsdf_sun``  first surface, BSDF sample that escapes into the sun's disk;
``d1_bsdf_sky``  first surface, BSDF sample that escapes into the sky;
``glint``        sun light (disk) reaching a vessel by way of the sea: the sun glint on the water
                 reflected onto a hull (first vertex a vessel, second the sea);
``deep_sun``     any other sun light after two or more surfaces;
``deep_sky``     sky light after two or more surfaces.

With ``split`` the emitter samples draw the sun and the sky separately (one sample each, each
weighted by the power heuristic against BSDF sampling for its own emitter) instead of from
``sunsky``'s own mixture; this is the clean path of the integrator with separate sun and sky
sampling.

Three configurations are rendered at ``--spp`` — ``sunsky``'s mixture with the ``independent``
sampler (the renderer before issue 14), the sun and sky apart with ``independent``, and apart
with ``multijitter`` (the renderer now) — against one converged render (``--ref-spp``, another
seed). Per region (sky, sea, each vessel class) the script prints the rms error relative to the
region's converged mean luminance, in all and per path class (emitter- and BSDF-sampled light
of the same class merged, so that every configuration has the same expectation per class).

Usage: python scripts/measure_gt_variance.py [--res 160x90] [--spp 30] [--ref-spp 1024] [--doc]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DEFAULT = ROOT / "scenes" / "default.yaml"
CLASSES = (
    "camera",
    "d1_nee_sun",
    "d1_nee_sky",
    "d1_bsdf_sun",
    "d1_bsdf_sky",
    "glint",
    "deep_sun",
    "deep_sky",
)
SUN_CONE_DEG = 0.3
"""Half-angle (deg) of the cone counted as the sun's disk (sunsky's disk: 0.268°)."""


def diagnostic_integrator(sun: Any, sky: Any, sea_id: int, sun_dir: np.ndarray, split: bool):
    """A clean-only path tracer that writes each path class (module docstring) to its AOV."""
    import drjit as dr
    import mitsuba as mi

    from seahaze.render.estimator import DEFAULT_SETTINGS
    from seahaze.render.haze_integrator import mis_weight

    bounces = DEFAULT_SETTINGS.bounces

    cos_cone = float(np.cos(np.radians(SUN_CONE_DEG)))
    sun_d = mi.Vector3f(*(float(c) for c in sun_dir))

    class Diagnostic(mi.SamplingIntegrator):
        def __init__(self, props: Any):
            super().__init__(props)

        def sample(self, scene, sampler, ray, medium=None, active=True):
            ray = mi.Ray3f(ray)
            active = mi.Bool(active)
            out = {c: mi.Color3f(0.0) for c in CLASSES}
            beta = mi.Color3f(1.0)
            prev_si = dr.zeros(mi.SurfaceInteraction3f)
            prev_pdf = mi.Float(1.0)
            prev_delta = mi.Bool(True)
            first_vessel = mi.Bool(False)
            second_sea = mi.Bool(False)
            ctx = mi.BSDFContext()

            def add(depth: int, value: Any, in_sun: Any, nee: bool) -> None:
                if depth == 0:
                    out["camera"] += value
                    return
                if depth == 1:
                    kind = "nee" if nee else "bsdf"
                    out[f"d1_{kind}_sun"] += dr.select(in_sun, value, 0.0)
                    out[f"d1_{kind}_sky"] += dr.select(in_sun, 0.0, value)
                    return
                glint = in_sun & first_vessel & second_sea
                out["glint"] += dr.select(glint, value, 0.0)
                out["deep_sun"] += dr.select(in_sun & ~glint, value, 0.0)
                out["deep_sky"] += dr.select(in_sun, 0.0, value)

            for depth in range(bounces + 1):
                si = scene.ray_intersect(ray, active)
                escaped = active & ~si.is_valid()
                in_sun = dr.dot(ray.d, sun_d) >= cos_cone
                if split:
                    mis_hit = mi.Float(1.0)
                    value = mi.Color3f(0.0)
                    for emitter in (sun, sky):
                        ds_hit = mi.DirectionSample3f(scene, si, prev_si)
                        pdf = emitter.pdf_direction(prev_si, ds_hit, escaped & ~prev_delta)
                        w = dr.select(prev_delta, 1.0, mis_weight(prev_pdf, pdf))
                        value += emitter.eval(si, escaped) * w
                    sky_value = dr.select(escaped, beta * value, 0.0)
                else:
                    emitter = si.emitter(scene, escaped)
                    ds_hit = mi.DirectionSample3f(scene, si, prev_si)
                    em_pdf = scene.pdf_emitter_direction(prev_si, ds_hit, escaped & ~prev_delta)
                    mis_hit = dr.select(prev_delta, 1.0, mis_weight(prev_pdf, em_pdf))
                    sky_value = dr.select(escaped, beta * emitter.eval(si, escaped) * mis_hit, 0.0)
                add(depth, sky_value, in_sun, nee=False)
                if depth == bounces:
                    break
                active = active & si.is_valid()
                is_sea = dr.reinterpret_array(mi.UInt32, si.shape) == sea_id
                if depth == 0:
                    first_vessel = active & ~is_sea
                elif depth == 1:
                    second_sea = active & is_sea
                bsdf = si.bsdf(ray)
                smooth = active & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)
                samplers = [(sun, True), (sky, True)] if split else [(None, False)]
                for emitter, own in samplers:
                    if own:
                        ds_e, em_w = emitter.sample_direction(si, sampler.next_2d(smooth), smooth)
                        ray_e = si.spawn_ray(ds_e.d)
                        seen = smooth & (ds_e.pdf > 0) & ~scene.ray_test(ray_e, smooth)
                        em_w = dr.select(seen, em_w, 0.0)
                    else:
                        ds_e, em_w = scene.sample_emitter_direction(
                            si, sampler.next_2d(smooth), True, smooth
                        )
                    value, bsdf_pdf = bsdf.eval_pdf(ctx, si, si.to_local(ds_e.d), smooth)
                    mis_e = dr.select(ds_e.delta, 1.0, mis_weight(ds_e.pdf, bsdf_pdf))
                    direct = dr.select(smooth & (ds_e.pdf > 0), beta * value * em_w * mis_e, 0.0)
                    add(depth + 1, direct, dr.dot(ds_e.d, sun_d) >= cos_cone, nee=True)
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
            total = sum(out.values(), mi.Color3f(0.0))
            aovs = [ch for c in CLASSES for ch in (out[c].x, out[c].y, out[c].z)]
            return mi.Spectrum(total), mi.Bool(True), aovs

        def aov_names(self):
            return [f"{c}.{ch}" for c in CLASSES for ch in "RGB"]

    return Diagnostic(mi.Properties())


def regions(session: Any) -> dict[str, np.ndarray]:
    """Boolean masks (H, W): sky, sea and one per vessel class present."""
    geo = session.pixels
    masks = {"sky": ~np.isfinite(geo.distance_m)}
    masks["sea"] = np.isfinite(geo.distance_m) & (geo.instance < 0)
    for vessel in session.geometry.vessels:
        masks.setdefault(vessel.kind, np.zeros_like(masks["sky"]))
        masks[vessel.kind] |= geo.instance == vessel.index
    return {k: m for k, m in masks.items() if m.any()}


MERGED = {
    "camera": ("camera",),
    "sun, 1st surface": ("d1_nee_sun", "d1_bsdf_sun"),
    "sky, 1st surface": ("d1_nee_sky", "d1_bsdf_sky"),
    "glint onto hull": ("glint",),
    "sun, deeper": ("deep_sun",),
    "sky, deeper": ("deep_sky",),
}
"""Classes whose expectation does not depend on the sampling strategies (an emitter sample and
a BSDF sample of the same light are one class), so one reference serves every configuration."""
CONFIGS = (
    ("sunsky mixture, independent (before)", False, "independent"),
    ("sun + sky apart, independent", True, "independent"),
    ("sun + sky apart, multijitter (now)", True, "multijitter"),
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--res", default="160x90")
    parser.add_argument("--spp", type=int, default=30)
    parser.add_argument("--ref-spp", type=int, default=1024)
    parser.add_argument("--doc", action="store_true", help="write docs/benchmarks.md's section")
    args = parser.parse_args()
    import mitsuba as mi

    from seahaze import imaging
    from seahaze.render.engine import open_session
    from seahaze.render.scene import sensor_dict, shape_registry_id
    from seahaze.render.sky import sun_and_sky_dicts
    from seahaze.sceneio import load_scene
    from seahaze.spec import with_overrides
    from seahaze.world import sun_direction

    width, height = (int(v) for v in args.res.split("x"))
    spec, _ = load_scene(DEFAULT)
    spec = with_overrides(spec, resolution=(width, height))
    session = open_session(spec)
    scene, cam = session.loaded.scene, session.camera
    sea = next(s for s in scene.shapes() if s.id() == "sea")
    sun, sky = (mi.load_dict(d) for d in sun_and_sky_dicts(spec))
    sun_dir = sun_direction(spec.sun.elevation_deg, spec.sun.azimuth_deg)
    masks = regions(session)

    def render(split: bool, sampler: str, spp: int, seed: int) -> tuple[dict, float]:
        integrator = diagnostic_integrator(sun, sky, shape_registry_id(sea), sun_dir, split)
        sensor = mi.load_dict(
            sensor_dict(cam, width, height, cam.fov_deg, cam.pitch_deg, False, sampler)
        )
        mi.render(scene, sensor=sensor, spp=1, seed=0, integrator=integrator)  # compile
        start = time.perf_counter()
        image = np.array(mi.render(scene, sensor=sensor, spp=spp, seed=seed, integrator=integrator))
        seconds = time.perf_counter() - start
        image = image.reshape(height, width, -1).astype(np.float64)
        fine = {
            c: imaging.luminance(image[..., 3 + 3 * i : 6 + 3 * i]) for i, c in enumerate(CLASSES)
        }
        return {m: sum(fine[c] for c in parts) for m, parts in MERGED.items()}, seconds

    ref, ref_seconds = render(True, "independent", args.ref_spp, 1000)
    results = []
    for label, split, sampler in CONFIGS:
        low, seconds = render(split, sampler, args.spp, 1)
        rows = {}
        for name, mask in masks.items():
            mean = float(np.mean(sum(ref.values())[mask]))
            total = sum(low[c] - ref[c] for c in MERGED)[mask]
            rows[name] = {
                "pixels": int(mask.sum()),
                "rel_rms": float(np.sqrt(np.mean(total**2)) / mean),
                "bias": float(np.mean(total) / mean),
                "classes": {
                    c: {
                        "share": float(np.mean(ref[c][mask]) / mean),
                        "rel_rms": float(np.sqrt(np.mean((low[c] - ref[c])[mask] ** 2)) / mean),
                    }
                    for c in MERGED
                },
            }
        results.append({"label": label, "seconds": seconds, "regions": rows})
        print(f"# {label}: {args.spp} spp {seconds:.1f} s (reference {ref_seconds:.1f} s)")
        for name, row in rows.items():
            parts = ", ".join(
                f"{c} {100 * v['rel_rms']:.1f}"
                for c, v in row["classes"].items()
                if v["share"] > 1e-3
            )
            print(
                f"  {name:16s} {row['pixels']:5d} px  rms {100 * row['rel_rms']:5.1f} %  ({parts})"
            )
    OUT.parent.mkdir(exist_ok=True)
    OUT.write_text(json.dumps(results, indent=2))
    if args.doc:
        write_section(results, args)


OUT = ROOT / "out" / "gt_variance.json"


def write_section(results: list[dict], args: argparse.Namespace) -> None:
    """The "where the noise comes from" part of docs/benchmarks.md."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from bench_passes import replace_section

    names = list(results[0]["regions"])
    lines = [
        "## Where the clean image's noise comes from (scripts/measure_gt_variance.py)",
        "",
        f"Default scene, {args.res}, {args.spp} spp, clean image, against {args.ref_spp} spp "
        "(another seed): per region, the rms per-pixel error of the luminance relative to the "
        "region's converged mean, for the old and the new sampling.",
        "",
        "| region (pixels) | " + " | ".join(r["label"] for r in results) + " |",
        "|---|" + "---|" * len(results),
    ]
    for name in names:
        cells = [f"{100 * r['regions'][name]['rel_rms']:.1f} %" for r in results]
        pixels = results[0]["regions"][name]["pixels"]
        lines.append(f"| {name} ({pixels}) | " + " | ".join(cells) + " |")
    lines += [
        "",
        "By light path (before → now): the class's share of the region's converged luminance "
        "and the rms error it contributes (relative to the region's mean):",
        "",
        "| region | " + " | ".join(MERGED) + " |",
        "|---|" + "---|" * len(MERGED),
    ]
    first, last = results[0]["regions"], results[-1]["regions"]
    for name in names:
        cells = []
        for c in MERGED:
            share = first[name]["classes"][c]["share"]
            a, b = first[name]["classes"][c]["rel_rms"], last[name]["classes"][c]["rel_rms"]
            cells.append(f"{100 * share:.0f} %: {100 * a:.1f} → {100 * b:.1f}")
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    replace_section("gt-variance", "\n".join(lines), "scripts/measure_gt_variance.py")


if __name__ == "__main__":
    sys.exit(main())
