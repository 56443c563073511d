"""The lights of a scene as Mitsuba emitters: the sun and the sky, clear, broken, overcast or
at twilight.

A clear day is Mitsuba's Hosek–Wilkie ``sunsky``. An overcast day has no sun to see: its sky
is the CIE overcast sky (:mod:`seahaze.overcast`) as an ``envmap``, grey, as bright as the
light a full cloud deck lets through of the clear day's (measured on the clear ``sunsky`` of
the same sun and turbidity, :func:`clear_global_irradiance`). A day of broken cloud
(:mod:`seahaze.clouds`) has both: an ``envmap`` of the clear sky with clouds of the overcast
deck's gradation in it, and the sun, passed or hidden by the cloud in its direction. At
twilight the sun has set: the sky is :mod:`seahaze.twilight`'s, as an ``envmap``. The
``physical`` mode takes the sun and the sky apart (:func:`sun_and_sky_dicts`); the other modes'
scenes hold the emitters of :func:`sky_emitters`, where a clear day's sky carries the sun too.
"""

from __future__ import annotations

from functools import cache, lru_cache

import numpy as np

from .. import clouds, overcast, twilight
from ..seeds import Stream, stream_seed
from ..spec import DAYLIGHT_SUN_DEG, SceneSpec, SkySpec, SunSpec
from ..world import sun_direction, wind_speed

IRRADIANCE_SAMPLES = 1 << 16
"""Directions drawn from the clear ``sunsky`` to measure its global horizontal irradiance: the
estimate's relative standard error is about 0.2 % (the sun's part, drawn uniformly over its
disk, is nearly exact)."""

ENVMAP_ROWS = 512
"""Rows (zenith angles) of the overcast sky's image: 0.35° each, so the gradation, linear in
``cos θ``, is interpolated to better than 1e-5 of the zenith's radiance."""

BROKEN_ROWS = 1024
"""Rows of the broken sky's image (its columns twice as many): texels of 0.18°, about four
pixels of a 1280-pixel-wide 60° view, so a cloud's edge stays an edge."""


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


def sky_emitters(spec: SceneSpec, elapsed_s: float = 0.0) -> dict[str, dict]:
    """The emitters a scene holds for its lights, by scene key: the clear ``sunsky`` with its
    sun, the overcast sky alone, or the broken sky and the sun it lets through, its clouds
    drifted for ``elapsed_s`` (s: a sequence's frame time, :func:`cloud_layer`).

    A Mitsuba scene holds one environment emitter, so a broken sky's sun is a ``directional``
    emitter of the sun disk's irradiance (the ``physical`` mode, which takes its own emitters,
    keeps the disk): the same light, less the disk's half-degree width, which no hazy level's
    scattering or the sea's glint resolves, and which a camera looking into the sun would."""
    if spec.sky.model == "clear":
        return {"sky": sunsky_dict(spec)}
    sun, sky = sun_and_sky_dicts(spec, elapsed_s)
    if spec.sky.model in ("overcast", "twilight"):
        return {"sky": sky}
    return {"sky": sky, "sun": _directional_sun(sun)}


def _directional_sun(sun_dict: dict) -> dict:
    """A ``directional`` emitter of a sun-only ``sunsky``'s disk irradiance and direction."""
    import mitsuba as mi

    from .sun_disk import disk_irradiance

    irradiance = disk_irradiance(mi.load_dict(sun_dict))
    return {
        "type": "directional",
        "direction": [-c for c in sun_dict["sun_direction"]],
        "irradiance": {"type": "rgb", "value": [float(c) for c in irradiance]},
    }


def sun_and_sky_dicts(spec: SceneSpec, elapsed_s: float = 0.0) -> tuple[dict, dict]:
    """The sun alone (:func:`sun_dict`) and the sky alone (:func:`sky_dict`): the ``physical``
    mode samples the sun on its own."""
    return sun_dict(spec, elapsed_s), sky_dict(spec, elapsed_s)


def sun_dict(spec: SceneSpec, elapsed_s: float = 0.0) -> dict:
    """The sun alone, a ``sunsky`` with its sky off. An overcast day's and a twilight's have
    their sun off too: they add nothing; a broken sky's is scaled by the share of its beam the
    cloud in its direction passes, its clouds drifted for ``elapsed_s`` (s)."""
    model = spec.sky.model
    if model == "overcast":
        return sunsky_dict(spec, sun=False, sky=False)
    if model == "twilight":
        # The set sun is switched off, so its direction is never seen; it stands at the
        # horizon, where Mitsuba's sunsky does not warn of a sun below it.
        low, sky = DAYLIGHT_SUN_DEG[0], spec.sky
        return _sunsky(low, spec.sun.azimuth_deg, sky.turbidity, sky.ground_albedo, 0.0, 0.0)
    sun = sunsky_dict(spec, sky=False)
    if model == "broken":
        sun["sun_scale"] *= cloud_layer(spec, elapsed_s).sun_transmission(
            sun_direction(spec.sun.elevation_deg, spec.sun.azimuth_deg)
        )
    return sun


def sky_dict(spec: SceneSpec, elapsed_s: float = 0.0) -> dict:
    """The sky alone: the clear ``sunsky``'s with its sun off, or the ``envmap`` of an overcast
    (:func:`overcast_dict`), broken (:func:`broken_dict`, its clouds drifted for
    ``elapsed_s`` s) or twilight (:func:`twilight_dict`) sky."""
    model = spec.sky.model
    if model == "overcast":
        return overcast_dict(spec)
    if model == "twilight":
        return twilight_dict(spec)
    if model == "broken":
        return broken_dict(spec, cloud_layer(spec, elapsed_s))
    return sunsky_dict(spec, sun=False)


def cloud_layer(spec: SceneSpec, elapsed_s: float = 0.0) -> clouds.CloudLayer:
    """The broken cloud layer of ``spec`` (``sky.clouds``), its seed from the scene's, drifted
    for ``elapsed_s`` (s) with the wind at its base (:func:`seahaze.clouds.wind_at_height` of
    the scene's ``U10``, toward ``sea.direction_deg``)."""
    c = spec.sky.cloud_layer
    seed = stream_seed(spec.render.seed, Stream.CLOUDS, c.seed)
    speed = clouds.wind_at_height(wind_speed(spec), c.base_height_m)
    heading = np.radians(spec.sea.direction_deg)
    drift = (float(speed * elapsed_s * np.cos(heading)), float(speed * elapsed_s * np.sin(heading)))
    return clouds.CloudLayer(c.oktas, c.base_height_m, c.size_m, seed, drift)


def broken_dict(spec: SceneSpec, layer: clouds.CloudLayer | None = None) -> dict:
    """The broken sky of ``spec`` as an ``envmap`` (:func:`seahaze.clouds.broken_sky_radiance`):
    the clear ``sunsky``'s sky radiance at each texel's direction, cloud of the overcast deck's
    gradation where ``layer`` (default: :func:`cloud_layer`, undrifted) covers it; scaled by
    ``sky.scale`` (the clear sky already is)."""
    import mitsuba as mi

    layer = cloud_layer(spec) if layer is None else layer
    return _envmap(mi.Bitmap(_broken_image(spec.sun, spec.sky, layer)))


@lru_cache(maxsize=2)
def _broken_image(sun: SunSpec, sky: SkySpec, layer: clouds.CloudLayer) -> np.ndarray:
    """The broken sky's image (kept for the scene's other builds: the clean pass's scene, the
    ``physical`` mode's emitters; each is a second or two of noise)."""
    clear_sky = _sunsky(
        sun.elevation_deg, sun.azimuth_deg, sky.turbidity, sky.ground_albedo, 0.0, sky.scale
    )
    clear = _latlong_of(clear_sky, BROKEN_ROWS, 2 * BROKEN_ROWS)
    zenith = overcast.zenith_radiance(
        clear_global_irradiance(
            sun.elevation_deg, sun.azimuth_deg, sky.turbidity, sky.ground_albedo
        )
    )
    return clouds.broken_sky_radiance(clear, zenith * sky.scale, layer, sky.turbidity)


def _latlong_of(emitter_dict: dict, rows: int, columns: int) -> np.ndarray:
    """An environment emitter's radiance (linear RGB) at the pixels of a latitude–longitude
    image, in the directions Mitsuba's ``envmap`` reads them
    (:func:`seahaze.clouds.latlong_directions`)."""
    import drjit as dr
    import mitsuba as mi

    emitter = mi.load_dict(emitter_dict)
    directions = clouds.latlong_directions(rows, columns).reshape(-1, 3)
    si = dr.zeros(mi.SurfaceInteraction3f, len(directions))
    si.wi = -mi.Vector3f(*(np.ascontiguousarray(directions[:, k], np.float32) for k in range(3)))
    radiance = np.array(emitter.eval(si), np.float64)
    radiance = radiance if radiance.shape[-1] == 3 else radiance.T
    return radiance.reshape(rows, columns, 3)


def _envmap(bitmap: object) -> dict:
    """An ``envmap`` of a latitude–longitude image whose top row is the zenith, turned so that
    the image's up (Mitsuba's ``envmap`` looks up along its local +y) is the world's +z."""
    import mitsuba as mi

    return {
        "type": "envmap",
        "bitmap": bitmap,
        "to_world": mi.ScalarTransform4f().rotate([1.0, 0.0, 0.0], 90.0),
    }


def overcast_dict(spec: SceneSpec) -> dict:
    """The CIE overcast sky of ``spec`` as an ``envmap``: its latitude–longitude image's top
    row at the zenith, turned so that the image's up (Mitsuba's ``envmap`` looks up along its
    local +y) is the world's +z; scaled by ``sky.scale``."""
    import mitsuba as mi

    clear = clear_global_irradiance(
        spec.sun.elevation_deg, spec.sun.azimuth_deg, spec.sky.turbidity, spec.sky.ground_albedo
    )
    zenith = overcast.zenith_radiance(clear) * spec.sky.scale
    return _envmap(mi.Bitmap(overcast.latlong_radiance(zenith, ENVMAP_ROWS)))


def twilight_dict(spec: SceneSpec) -> dict:
    """The twilight sky of ``spec`` (the sun below the horizon) as an ``envmap``: the
    single-scattering sky of :mod:`seahaze.twilight` at each texel's direction, in the
    renderer's units (:func:`twilight_scale`), scaled by ``sky.scale``."""
    import mitsuba as mi

    image = _twilight_image(spec.sun.elevation_deg, spec.sun.azimuth_deg, spec.sky.turbidity)
    scale = twilight_scale(spec.sky.turbidity, spec.sky.ground_albedo) * spec.sky.scale
    return _envmap(mi.Bitmap((image * scale).astype(np.float32)))


@lru_cache(maxsize=2)
def _twilight_image(elevation_deg: float, azimuth_deg: float, turbidity: float) -> np.ndarray:
    """The twilight sky's latitude–longitude image in the model's units, negative (out of
    sRGB's gamut: the deepest red at the horizon) clipped to 0."""
    directions = clouds.latlong_directions(ENVMAP_ROWS, 2 * ENVMAP_ROWS)
    elevation = np.arcsin(np.clip(directions[..., 2], -1.0, 1.0))
    relative = np.arctan2(directions[..., 1], directions[..., 0]) - np.radians(azimuth_deg)
    sky = twilight.sky_grid(elevation_deg, turbidity)
    return np.maximum(sky.radiance(elevation, relative), 0.0)


@cache
def twilight_scale(turbidity: float, ground_albedo: float) -> float:
    """The renderer's units per unit of :mod:`seahaze.twilight`'s radiance: the factor that
    gives its sky, with the sun at Hosek–Wilkie's lowest (0.5°), the clear ``sunsky``'s sky
    luminance on a level surface there, so that dusk follows the day without a jump."""
    import mitsuba as mi

    low = DAYLIGHT_SUN_DEG[0]
    clear = horizontal_irradiance(
        mi.load_dict(_sunsky(low, 0.0, turbidity, ground_albedo, 0.0, 1.0))
    )
    model = twilight.irradiance_rgb(low, turbidity)
    return float(overcast.REC709_LUMINANCE @ clear / (overcast.REC709_LUMINANCE @ model))


ILLUMINANT_GRID = 128
"""Zenith-cosine rows of the quadrature of :func:`illuminant_rgb` (twice as many azimuths)."""


def illuminant_rgb(spec: SceneSpec) -> np.ndarray:
    """The colour and strength of the scene's daylight: the horizontal irradiance (linear RGB)
    of its sun (the disk's, times the sine of its elevation) and its sky (midpoint quadrature of
    the sky emitter's radiance in ``cos θ`` and azimuth), as the emitters of
    :func:`sun_and_sky_dicts` give them: what a camera white-balances to."""
    import mitsuba as mi

    from .sun_disk import disk_irradiance

    sun_dict, sky_dict = sun_and_sky_dicts(spec)
    beam = disk_irradiance(mi.load_dict(sun_dict)) * max(
        np.sin(np.radians(spec.sun.elevation_deg)), 0.0
    )
    return beam + horizontal_irradiance(mi.load_dict(sky_dict))


def horizontal_irradiance(emitter: object, n: int = ILLUMINANT_GRID) -> np.ndarray:
    """``∫ L cos θ dω`` (linear RGB) of an environment emitter over the upper hemisphere:
    the midpoint rule on ``n`` zenith cosines × ``2n`` azimuths, independent of the emitter's
    own sampling."""
    import drjit as dr
    import mitsuba as mi

    mu = (np.arange(n) + 0.5) / n
    phi = 2.0 * np.pi * (np.arange(2 * n) + 0.5) / (2 * n)
    m, p = (a.ravel() for a in np.meshgrid(mu, phi, indexing="ij"))
    s = np.sqrt(1.0 - m * m)
    si = dr.zeros(mi.SurfaceInteraction3f, len(m))
    si.wi = -mi.Vector3f(s * np.cos(p), s * np.sin(p), m)
    radiance = np.array(emitter.eval(si), np.float64)  # type: ignore[attr-defined]
    radiance = radiance if radiance.shape[-1] == 3 else radiance.T
    return 2.0 * np.pi * (radiance * m[:, None]).mean(axis=0)


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
