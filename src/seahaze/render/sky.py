"""The lights of a scene as Mitsuba emitters: the sun and the sky, clear or overcast.

A clear day is Mitsuba's Hosek–Wilkie ``sunsky``. An overcast day has no sun to see: its sky
is the CIE overcast sky (:mod:`seahaze.overcast`) as an ``envmap``, grey, as bright as the
light a full cloud deck lets through of the clear day's (measured on the clear ``sunsky`` of
the same sun and turbidity, :func:`clear_global_irradiance`). The ``physical`` mode takes the
sun and the sky apart (:func:`sun_and_sky_dicts`); the other modes' scenes hold the sky of
:func:`sky_dict`, which for a clear day carries the sun too.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from .. import overcast
from ..spec import SceneSpec
from ..world import sun_direction

IRRADIANCE_SAMPLES = 1 << 16
"""Directions drawn from the clear ``sunsky`` to measure its global horizontal irradiance: the
estimate's relative standard error is about 0.2 % (the sun's part, drawn uniformly over its
disk, is nearly exact)."""

ENVMAP_ROWS = 512
"""Rows (zenith angles) of the overcast sky's image: 0.35° each, so the gradation, linear in
``cos θ``, is interpolated to better than 1e-5 of the zenith's radiance."""


def sunsky_dict(spec: SceneSpec, sun: bool = True, sky: bool = True) -> dict:
    """The Hosek–Wilkie ``sunsky`` emitter of ``spec``'s sun and turbidity; ``sun``/``sky``
    False switch a part off."""
    return _sunsky(
        spec.sun.elevation_deg,
        spec.sun.azimuth_deg,
        spec.sky.turbidity,
        spec.sky.ground_albedo,
        spec.sun.scale if sun else 0.0,
        spec.sky.scale if sky else 0.0,
    )


def _sunsky(
    elevation_deg: float,
    azimuth_deg: float,
    turbidity: float,
    ground_albedo: float,
    sun_scale: float,
    sky_scale: float,
) -> dict:
    """Mitsuba's ``sunsky`` plugin dict for this sun, turbidity and ground albedo, its sun and
    sky parts scaled by ``sun_scale`` and ``sky_scale``."""
    return {
        "type": "sunsky",
        "sun_direction": sun_direction(elevation_deg, azimuth_deg).tolist(),
        "turbidity": turbidity,
        "albedo": ground_albedo,
        "sun_scale": sun_scale,
        "sky_scale": sky_scale,
    }


def sky_dict(spec: SceneSpec) -> dict:
    """The emitter a scene holds for its lights: the clear ``sunsky`` with its sun, or the
    overcast sky alone."""
    return overcast_dict(spec) if spec.sky.model == "overcast" else sunsky_dict(spec)


def sun_and_sky_dicts(spec: SceneSpec) -> tuple[dict, dict]:
    """The sun alone and the sky alone (the ``physical`` mode samples the sun on its own). An
    overcast day's sun is a ``sunsky`` with both parts off: it adds nothing."""
    if spec.sky.model == "overcast":
        return sunsky_dict(spec, sun=False, sky=False), overcast_dict(spec)
    return sunsky_dict(spec, sky=False), sunsky_dict(spec, sun=False)


def overcast_dict(spec: SceneSpec) -> dict:
    """The CIE overcast sky of ``spec`` as an ``envmap``: its latitude–longitude image's top
    row at the zenith, turned so that the image's up (Mitsuba's ``envmap`` looks up along its
    local +y) is the world's +z; scaled by ``sky.scale``."""
    import mitsuba as mi

    clear = clear_global_irradiance(
        spec.sun.elevation_deg, spec.sun.azimuth_deg, spec.sky.turbidity, spec.sky.ground_albedo
    )
    zenith = overcast.zenith_radiance(clear) * spec.sky.scale
    image = overcast.latlong_radiance(zenith, ENVMAP_ROWS)
    return {
        "type": "envmap",
        "bitmap": mi.Bitmap(image),
        "to_world": mi.ScalarTransform4f().rotate([1.0, 0.0, 0.0], 90.0),
    }


@cache
def clear_global_irradiance(
    elevation_deg: float, azimuth_deg: float, turbidity: float, ground_albedo: float
) -> np.ndarray:
    """Global horizontal irradiance (linear RGB, the renderer's units) of the clear ``sunsky``
    of this sun and turbidity at physical scale: sun and sky, ``E = ∫ L cos θ dω``, each part
    estimated from :data:`IRRADIANCE_SAMPLES` directions the emitter draws itself (fixed
    random numbers, so the same on every call)."""
    import drjit as dr
    import mitsuba as mi

    origin = dr.zeros(mi.Interaction3f)
    rng = mi.PCG32(IRRADIANCE_SAMPLES)
    sample = mi.Point2f(rng.next_float32(), rng.next_float32())
    total = np.zeros(3)
    for sun, sky in ((1.0, 0.0), (0.0, 1.0)):
        emitter = mi.load_dict(
            _sunsky(elevation_deg, azimuth_deg, turbidity, ground_albedo, sun, sky)
        )
        ds, weight = emitter.sample_direction(origin, sample)
        per_sample = np.array(weight * dr.maximum(ds.d.z, 0.0), np.float64)
        total += (per_sample if per_sample.shape[-1] == 3 else per_sample.T).mean(axis=0)
    return total
