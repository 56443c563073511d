"""Where the diffuse tables' photons come from: the sun and the sky, and the sea that reflects them.

The photon tracer (:mod:`seahaze.render.photon_tracer`) starts its photons from the scene's own
emitters, sampled with Mitsuba's emitter sampling above the medium's top, and reflects them off
the sea's own BSDF, pre-sampled once per scene (:func:`sample_sea_reflectance`). Units:
directions are unit travel vectors (Z up), weights horizontal irradiance per photon.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..ocean.whitecaps import FOAM_REFLECTANCE
from .jit_haze import owned_floats
from .photon_tracer import SeaReflectance


def _mi():
    import mitsuba as mi

    return mi


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
        mix_in_foam(wo, w, rng, foam_coverage, foam_reflectance)
    return SeaReflectance(wo.reshape(n_mu, per_bin, 3), w.reshape(n_mu, per_bin, 3))


def mix_in_foam(
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


def sea_bsdf(scene: Any) -> Any:
    """The BSDF of ``scene``'s shape with id ``sea``."""
    for shape in scene.shapes():
        if shape.id() == "sea":
            return shape.bsdf()
    raise ValueError("the scene has no shape with id 'sea'")
