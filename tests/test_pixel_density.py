"""The ``physical`` mode in haze that varies across the sea: each pixel's equivalent profile.

* The pixel density ratio is the field's reduced length over the profile's along the
  pixel-centre ray, each checked against an independent integration (Simpson's rule on the
  field, the slab's chord in closed form).
* A camera ray, wherever it leaves through its pixel, reads that pixel's ratio: the kernel's
  projection onto the film is the sensor's own.
* End to end: a field of uniform density ratio 2 with nothing scattering renders, in every
  pixel and every segment (camera, sea, vessels, light rays), the slab at twice the extinction;
  a field of ratio 1 renders what the slab renders, scattering included.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import simpson

from conftest import small_spec
from seahaze.haze_field import HazeField, Patches
from seahaze.medium import HomogeneousSlab
from seahaze.nonuniform import RAY_REACH_M, NonUniformHaze

pytestmark = pytest.mark.usefixtures("mitsuba_variant")

SLAB = HomogeneousSlab(top=300.0, albedo=0.998, g=0.75)
PATCHES = Patches(300.0, 3.0, 60.0, 20.0, seed=5)
SPEC = small_spec(
    camera={"height_m": 12.0, "pitch_deg": -1.0, "fov_deg": 50.0},
    vessels={"placed": [{"class": "tug", "distance_m": 300, "bearing_deg": 4, "length_m": 30}]},
    haze={"top_m": 300.0, "levels": [800.0]},
    render={"mode": "physical", "spp": 4, "seed": 3},
)


def _session(medium):
    from seahaze.render.engine import open_session

    return open_session(SPEC, medium=medium)


def test_the_ratio_is_the_fields_reduced_length_over_the_profiles():
    from seahaze.render.pixel_density import pixel_density_ratio

    medium = NonUniformHaze(SLAB, HazeField(PATCHES), 0.9)
    geometry = _session(medium).pixels
    ratio = pixel_density_ratio(medium, geometry)
    rng = np.random.default_rng(1)
    rows = rng.integers(0, ratio.shape[0], 12)
    cols = rng.integers(0, ratio.shape[1], 12)
    origin = geometry.origin.astype(np.float64)
    for row, col in zip(rows, cols, strict=True):
        d = geometry.directions[row, col].astype(np.float64)
        d /= np.linalg.norm(d)
        end = min(float(geometry.distance_m[row, col]), RAY_REACH_M)
        # The slab's chord: from the camera (inside it) to its top, the surface or the reach.
        chord = end if d[2] <= 0 else min(end, (SLAB.top - origin[2]) / d[2])
        s = np.linspace(0.0, chord, 40_001)
        p = origin[None, :] + s[:, None] * d[None, :]
        field = simpson(medium.density_at(p[:, 0], p[:, 1], p[:, 2]), x=s)
        np.testing.assert_allclose(ratio[row, col], field / chord, rtol=1e-4)
    assert ratio.max() > 1.5 * ratio.min()  # the patches show: the ratio varies


def test_the_suns_depth_through_the_field_is_an_independent_integral():
    """The field's reduced length toward the sun from points in view (the kernel's
    quadrature, float32) against Simpson's rule on the numpy field; the profile's is the
    slab's depth in closed form."""
    from seahaze.render.pixel_density import sun_depths

    medium = NonUniformHaze(SLAB, HazeField(PATCHES), 0.9)
    sun = np.array([0.5, -0.3, 0.6])
    sun /= np.linalg.norm(sun)
    rng = np.random.default_rng(4)
    points = np.stack(
        [rng.uniform(-2000, 2000, 10), rng.uniform(0, 3000, 10), rng.uniform(0, 250, 10)], 1
    )
    field, profile = sun_depths(medium, points, sun)
    for k, p in enumerate(points):
        length = (SLAB.top - p[2]) / sun[2]
        s = np.linspace(0.0, length, 20_001)
        q = p[None, :] + s[:, None] * sun[None, :]
        want = simpson(medium.density_at(q[:, 0], q[:, 1], q[:, 2]), x=s)
        np.testing.assert_allclose(field[k], want, rtol=3e-4)
        np.testing.assert_allclose(profile[k], length, rtol=1e-12)
    assert field.max() > 1.3 * field.min() * profile.max() / profile.min()


def test_a_camera_ray_reads_the_ratio_of_its_own_pixel():
    import drjit as dr
    import mitsuba as mi

    from seahaze.render.pixel_density import PixelRatio, PixelRatios

    session = _session(None)
    sensor = session.loaded.scene.sensors()[0]
    height, width = session.pixels.distance_m.shape
    index = np.arange(height * width, dtype=np.float64).reshape(height, width)
    # +1: a ratio of 0 would be clamped; the ratios told apart by their offsets.
    suns = np.stack([index + 2.0, index + 3.0])
    bounced = np.stack([index + 6.0, index + 7.0])
    diffuse = np.stack([index + 8.0, index + 9.0])
    ratios = PixelRatios(index + 1.0, suns, index + 4.0, index + 5.0, bounced, diffuse, diffuse + 2)
    rng = np.random.default_rng(2)
    pixel = rng.integers(0, height * width, 4000)
    # Anywhere inside the pixel, its corners excepted (a float32 step from the next one).
    jitter = rng.uniform(0.01, 0.99, (2, pixel.size))
    x = (pixel % width + jitter[0]) / width
    y = (pixel // width + jitter[1]) / height
    film = mi.Point2f(mi.Float(x), mi.Float(y))
    ray, _ = sensor.sample_ray(0.0, 0.5, film, mi.Point2f(0.5, 0.5))
    view, sun_air, surface, bounce, sun_bounce, air, later = PixelRatio(sensor, ratios).at(
        ray, mi.Bool(True)
    )
    read = [view, *sun_air, surface, bounce, *sun_bounce, *air, *later]
    got = [np.asarray(r, np.float64) for r in read]
    for offset, ratio in enumerate(got, start=1):
        np.testing.assert_array_equal(ratio - offset, pixel)
    assert dr.width(ray.d) == pixel.size
    # Without diffuse ratios, none are read.
    plain = PixelRatio(sensor, PixelRatios(index + 1.0, suns, index + 4.0, index + 5.0, bounced))
    assert plain.at(ray, mi.Bool(True))[5:] == (None, None)


def _renderer(medium, settings=None):
    from seahaze.render.estimator import EstimatorSettings
    from seahaze.render.physical import PhysicalRenderer

    session = _session(medium)
    settings = settings or EstimatorSettings()
    return PhysicalRenderer(session.loaded, SPEC, settings, geometry=session.pixels)


@pytest.mark.slow
def test_a_field_twice_as_dense_everywhere_is_the_slab_at_twice_the_extinction():
    """With the slab's diffuse field at 2σ, every pass of the field at σ is the slab's at
    2σ: transmittances of every segment (camera, sea, vessels, rays toward the lights),
    distances drawn in reduced length and the points they map to, the sun's depth and the
    tables' heights — all scaled by the ratio. Same random numbers, so equal to rounding.
    The vessel-light pass is left out: its near-vessel probes need a geometric medium."""
    from seahaze.render.estimator import EstimatorSettings

    settings = EstimatorSettings(vessel_light_share=0.0)
    sigma = 3.912 / 1500.0
    slab = _renderer(SLAB, settings)
    field = _renderer(NonUniformHaze(SLAB, HazeField(), 2.0), settings)
    # The tables hold the source per metre, σ J: the slab's at 2σ, per unit σ of the field.
    field.tables = lambda s, *args, **kw: 0.5 * slab.tables(2.0 * s, *args, **kw)
    got = field.render([sigma], 0.998, 0.75, 4, seed=9)
    want = slab.render([2.0 * sigma], 0.998, 0.75, 4, seed=9)
    np.testing.assert_array_equal(got.clean, want.clean)
    np.testing.assert_allclose(got.levels[0], want.levels[0], rtol=1e-4, atol=1e-6)
    # Haze there was: the level is not the clean image, nor the level at σ.
    once = slab.render([sigma], 0.998, 0.75, 4, seed=9)
    assert np.abs(got.levels[0] / once.levels[0] - 1.0).mean() > 0.05


def test_a_field_of_ratio_one_renders_what_the_slab_renders():
    """Everything as the slab, the vessel-light pass included (without its near-vessel
    probes: the same light, other noise)."""
    sigma = 3.912 / 800.0
    field = _renderer(NonUniformHaze(SLAB, HazeField(), 1.0)).render([sigma], 0.998, 0.75, 4, 9)
    slab = _renderer(SLAB).render([sigma], 0.998, 0.75, 4, 9)
    np.testing.assert_array_equal(field.clean, slab.clean)
    assert abs(field.levels[0].mean() / slab.levels[0].mean() - 1.0) < 0.01


def test_the_diffuse_ratios_scale_the_diffuse_field_of_their_own_segments():
    """A level is linear in its diffuse field: with the same random numbers, the camera
    segment's ``diffuse_air`` ratio at 0, 1 and 2 gives levels in arithmetic progression, and
    a ratio of 1 renders what no ratio renders, bit for bit. ``diffuse_bounce`` scales only
    the segments after a surface: pixels of open sky (no surface on any path) do not see it,
    the sea does. (The vessel-light pass, which reads them too, is left out: it corrects
    every pixel near a vessel, open sky included.)"""
    import dataclasses

    from seahaze.render.estimator import EstimatorSettings

    sigma = 3.912 / 800.0
    settings = EstimatorSettings(vessel_light_share=0.0)
    renderer = _renderer(NonUniformHaze(SLAB, HazeField(), 1.0), settings)
    plain = renderer.render([sigma], 0.998, 0.75, 4, 9).levels[0]
    own_ratios = renderer.pixel_ratios

    def render_with(air: float, later: float) -> np.ndarray:
        def ratios(levels, *rest):
            base = own_ratios(levels, *rest)
            ones = np.ones_like(base.sun_air)
            return dataclasses.replace(base, diffuse_air=air * ones, diffuse_bounce=later * ones)

        renderer.pixel_ratios = ratios
        return renderer.render([sigma], 0.998, 0.75, 4, 9).levels[0]

    once, none, twice = (render_with(air, 1.0) for air in (1.0, 0.0, 2.0))
    np.testing.assert_array_equal(once, plain)
    diffuse = once - none
    np.testing.assert_allclose(twice - once, diffuse, rtol=1e-4, atol=1e-6)
    assert diffuse.mean() > 0.05 * once.mean()  # the haze's diffuse light is no trace
    dark_sea = render_with(1.0, 0.0)
    distance = renderer.geometry.distance_m
    open_sky = np.isinf(distance)
    open_sky[1:] &= open_sky[:-1]
    open_sky[:-1] &= open_sky[1:]  # rows whose neighbours are sky too
    np.testing.assert_array_equal(dark_sea[open_sky], once[open_sky])
    sea = np.isfinite(distance) & (renderer.geometry.instance < 0)
    assert np.all(dark_sea[sea].mean(0) < once[sea].mean(0))


def test_a_levels_sun_ratio_gives_the_fields_mean_transmittance_toward_the_sun():
    """Whatever the depths, the level's ratio makes the profile's depths give the field's
    mean transmittance toward the sun over the ray's points, weighted by the light each
    sends to the camera (ρ Δs e^{−σℓ}), also where the transmittances underflow float64."""
    from seahaze.render.pixel_density import level_sun_ratio

    rng = np.random.default_rng(8)
    mass = rng.uniform(0.1, 40.0, (50, 24))
    profile = rng.uniform(100.0, 700.0, (50, 24))
    field = profile * rng.lognormal(0.0, 0.8, (50, 24))
    for sigma in (3.912 / 4000, 3.912 / 1000, 3.912 / 300, 0.5):
        r = level_sun_ratio(sigma, mass, field, profile)
        travelled = np.cumsum(mass, -1) - 0.5 * mass
        log_w = np.log(mass) - sigma * travelled
        want = np.logaddexp.reduce(log_w - sigma * field, axis=-1)
        got = np.logaddexp.reduce(log_w - sigma * r[:, None] * profile, axis=-1)
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9)
        assert np.all(r > 0.0)


def test_the_seas_bounce_ratio_is_its_mirrored_rays():
    from seahaze.render.pixel_density import mirror_ratio

    medium = NonUniformHaze(SLAB, HazeField(PATCHES), 1.1)
    rng = np.random.default_rng(3)
    points = np.stack([rng.uniform(-500, 500, 6), rng.uniform(100, 2000, 6), np.zeros(6)], 1)
    dirs = np.stack([rng.uniform(-0.3, 0.3, 6), np.ones(6), -rng.uniform(0.02, 0.1, 6)], 1)
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    got = mirror_ratio(medium, points, dirs)
    for k in range(6):
        up = dirs[k] * np.array([1.0, 1.0, -1.0])
        length = min(SLAB.top / up[2], RAY_REACH_M)
        s = np.linspace(0.0, length, 40_001)
        q = points[k] + s[:, None] * up
        field = simpson(medium.density_at(q[:, 0], q[:, 1], q[:, 2]), x=s)
        np.testing.assert_allclose(got[k], field / length, rtol=3e-4)


def test_the_seas_sun_bounce_ratio_is_its_mirrored_rays_sun_ratio():
    """On a sea pixel, each level's ``sun_bounce`` is the sun ratio of the camera ray
    mirrored in a flat sea: rebuilt here from the mirrored ray's 24 points, each point's depth
    toward the sun by Simpson's rule through the field (the profile's in closed form); on a
    vessel pixel it is ``sun_surface``. A field that is the profile times c gives c."""
    from seahaze.render.pixel_density import AIR_POINTS, AIR_REACH_M, level_sun_ratio
    from seahaze.render.pixel_density import pixel_ratios as ratios_of
    from seahaze.world import sun_direction

    medium = NonUniformHaze(SLAB, HazeField(PATCHES), 1.1)
    geometry = _session(medium).pixels
    sun = sun_direction(SPEC.sun.elevation_deg, SPEC.sun.azimuth_deg)
    sigmas = np.array([3.912 / 300.0, 3.912 / 4000.0])
    got = ratios_of(medium, geometry, sun, sigmas)
    assert got.view.size <= 320 * 180  # one grid point per pixel: no spreading
    vessel = geometry.instance >= 0
    np.testing.assert_array_equal(
        got.sun_bounce[:, vessel], got.sun_surface[None, vessel].repeat(2, 0)
    )
    sea = np.argwhere(np.isfinite(geometry.distance_m) & ~vessel)
    origin = geometry.origin.astype(np.float64)
    for row, col in sea[np.random.default_rng(4).choice(len(sea), 3, replace=False)]:
        d = geometry.directions[row, col].astype(np.float64)
        p = origin + float(geometry.distance_m[row, col]) * d
        up = d * np.array([1.0, 1.0, -1.0])
        reach = min((SLAB.top - p[2]) / up[2], RAY_REACH_M, AIR_REACH_M)
        edges = (np.arange(AIR_POINTS + 1) / AIR_POINTS) ** 2
        s = 0.5 * (edges[:-1] + edges[1:]) * reach
        points = p + s[:, None] * up
        mass = medium.density_at(points[:, 0], points[:, 1], points[:, 2]) * np.diff(edges) * reach
        field, profile = [], []
        for q in points:
            length = (SLAB.top - q[2]) / sun[2]
            t = np.linspace(0.0, length, 20_001)
            ray = q + t[:, None] * sun
            field.append(simpson(medium.density_at(ray[:, 0], ray[:, 1], ray[:, 2]), x=t))
            profile.append(length)
        for k, sigma in enumerate(sigmas):
            want = level_sun_ratio(sigma, mass, np.array(field), np.array(profile))
            np.testing.assert_allclose(got.sun_bounce[k, row, col], want, rtol=1e-3)
    assert not np.allclose(got.sun_bounce[:, ~vessel], got.sun_surface[None, ~vessel])
    uniform = ratios_of(NonUniformHaze(SLAB, HazeField(), 1.7), geometry, sun, sigmas)
    np.testing.assert_allclose(uniform.sun_bounce, 1.7, rtol=1e-6)
