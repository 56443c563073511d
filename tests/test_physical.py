"""The ``physical`` haze mode against independent computations.

* The diffuse-field table against quadrature: thin haze under a uniform sky over a black sea
  scatters ``J(ω) = σ_s L₀ ∫_down p(ω·ω') dω'`` (single scattering of the sky), for any g.
* The integrator against Mitsuba's ``volpath`` (a wholly independent estimator): sky and sea
  means per channel at V = 300 m and 1000 m, and at 2000 m with Kim's wavelength-dependent
  extinction (Mitsuba's chromatic-medium sampling), within 3 % plus three standard errors.
* Absorbing haze: the sky through the slab is the clean sky times ``exp(−σ_c L)`` in each
  channel (Beer–Lambert, with ``L`` from the camera geometry, not from the integrator).
* Haze in front of a vessel: a dark box seen toward the sun through thin haze against
  ``volpath``, whose haze sees the box; without the vessel-light pass (off by default) the
  open-sea tables make the box 12 % too bright. Its probes aimed at the vessels estimate the
  same correction as probes from the phase function, with less noise.
* Determinism and kernel reuse across levels.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from conftest import box_vessel, load_flat_scene, region_stats, small_spec
from seahaze.haze import hg_phase
from seahaze.medium import HomogeneousSlab
from seahaze.render import passes, physical
from seahaze.render.diffuse_table import TableGrid, build_tables
from seahaze.render.estimator import EstimatorSettings
from seahaze.render.levels import LevelRenderer
from seahaze.render.photon_tracer import SeaReflectance
from seahaze.scene_medium import haze_medium
from seahaze.visibility import channel_extinction

pytestmark = pytest.mark.usefixtures("mitsuba_variant")


def _uniform_sky_photons(n: int, radiance: float, rng: np.random.Generator):
    """Cosine-weighted downward directions; each carries ``π L₀ / n`` of horizontal irradiance."""
    u1, u2 = rng.random(n), rng.random(n)
    r, phi = np.sqrt(u1), 2 * np.pi * u2
    d = np.stack([r * np.cos(phi), r * np.sin(phi), -np.sqrt(1 - u1)], axis=1)
    w = np.full((n, 3), np.pi * radiance / n)
    return d, w


@pytest.mark.parametrize("g", [0.0, 0.75])
def test_table_equals_single_scattering_quadrature_in_thin_haze(g: float) -> None:
    rng = np.random.default_rng(3)
    radiance, sigma, albedo, top = 2.0, 1e-5, 0.9, 300.0  # optical depth 0.003
    sky = _uniform_sky_photons(400_000, radiance, rng)
    no_sun = (np.zeros((0, 3)), np.zeros((0, 3)))
    grid = TableGrid(n_z=4)
    black = SeaReflectance.black()
    medium = HomogeneousSlab(top, albedo, g)
    (table,) = build_tables(no_sun, sky, black, [sigma], medium, 0.0, 1, grid)
    # Quadrature over the downward hemisphere for travel directions ω at bin centres, from
    # straight down through the horizon (where the sky's edge meets the phase peak) to up.
    mu = -1.0 + (np.array([2, 12, 20, 23, 24, 26, 36, 46]) + 0.5) * 2.0 / grid.n_mu
    phi = (7 + 0.5) * np.pi / grid.n_phi
    s_mu = np.sqrt(1 - mu**2)
    omega = np.stack([s_mu * np.cos(phi), s_mu * np.sin(phi), mu], axis=1)
    m = 2000
    mu_q = -(np.arange(m) + 0.5) / m  # uniform in μ' over (-1, 0): equal solid angles
    phi_q = 2 * np.pi * (np.arange(64) + 0.5) / 64
    s = np.sqrt(1 - mu_q**2)[:, None]
    dirs = np.stack(
        np.broadcast_arrays(s * np.cos(phi_q), s * np.sin(phi_q), mu_q[:, None]), axis=-1
    ).reshape(-1, 3)
    d_omega = 2 * np.pi / len(dirs)
    expected = [albedo * sigma * radiance * hg_phase(dirs @ w, g).sum() * d_omega for w in omega]
    got = table.lookup(np.full(len(mu), 150.0), omega)[:, 1]
    # Monte Carlo noise is < 1 %; for g = 0.75 the phase function averaged over a bin blurs
    # the forward peak where it meets the horizon (the sky's edge) by a few per cent.
    np.testing.assert_allclose(got, expected, rtol=0.01 if g == 0.0 else 0.03)


def test_table_is_zero_without_scattering() -> None:
    rng = np.random.default_rng(0)
    sky = _uniform_sky_photons(10_000, 1.0, rng)
    sun = (np.tile([[0.3, 0.0, -0.954]], (1000, 1)), np.full((1000, 3), 1e-3))
    medium = HomogeneousSlab(300.0, albedo=0.0, g=0.7)
    (table,) = build_tables(sun, sky, SeaReflectance.black(), [1e-3], medium, 0.0, 2)
    assert np.all(table.values == 0.0)


class _Scenes:
    """One small scene loaded twice: with Mitsuba's medium (reference) and without (physical)."""

    def __init__(self) -> None:
        self.spec = small_spec(
            camera={"resolution": [48, 27], "fov_deg": 40.0, "pitch_deg": -3.0},
            haze={"levels": [300.0, 1000.0, 2000.0]},
        )
        vessel = box_vessel(0, (400.0, 30.0, 6.0), (40.0, 8.0, 12.0))
        self.reference, _ = load_flat_scene(self.spec, [vessel], (300.0, 1000.0, 2000.0))
        self.physical, _ = load_flat_scene(
            self.spec, [vessel], (300.0, 1000.0, 2000.0), haze_box=False
        )
        self.geo = passes.render_geometry(self.physical)
        self.clean = passes.render_clean(self.physical, 16, 1, 0.998, 0.75)
        # One renderer per mode, as a scene render keeps one for all its levels.
        self.renderers = {
            mode: LevelRenderer(
                mode, loaded, self.geo, self.clean, self.spec.haze, self.spec.render
            )
            for mode, loaded in (("physical", self.physical), ("reference", self.reference))
        }

    def level(self, mode: str, visibility: float, spp: int, seed: int, **haze) -> np.ndarray:
        spec = self.spec.haze.model_copy(update=haze)
        render = self.spec.render.model_copy(update={"spp": spp, "seed": seed})
        sigma = channel_extinction(visibility, spec.threshold, spec.extinction_spectrum)
        return self.renderers[mode].render(sigma, 0, render, spec)


@pytest.fixture(scope="module")
def scenes() -> _Scenes:
    return _Scenes()


@pytest.mark.parametrize(
    ("visibility", "spectrum"),
    [
        pytest.param(300.0, "grey", marks=pytest.mark.slow),
        (1000.0, "grey"),
        pytest.param(2000.0, "kim", marks=pytest.mark.slow),
    ],
)
def test_physical_matches_volpath_on_sky_and_sea(
    scenes: _Scenes, visibility: float, spectrum: str
) -> None:
    sky = np.isinf(scenes.geo.distance_m)
    sea = ~sky & (scenes.geo.instance < 0)
    assert sky.sum() > 200 and sea.sum() > 200

    def region_means(mode: str, spp: int) -> tuple[np.ndarray, np.ndarray]:
        """Sky and sea means per channel, (2, 3), and their standard errors from 4 batches."""
        batches = [
            scenes.level(mode, visibility, spp, seed, extinction_spectrum=spectrum).radiance
            for seed in range(4)
        ]
        return region_stats(batches, sky, sea)

    ref, ref_se = region_means("reference", 256)
    phys, phys_se = region_means("physical", 32)
    allowed = 0.03 * ref + 3.0 * np.hypot(ref_se, phys_se)
    assert np.all(np.abs(phys - ref) <= allowed), (visibility, phys, ref, allowed)


@pytest.mark.parametrize("spectrum", ["grey", "kim"])
def test_absorbing_haze_attenuates_the_sky_by_beer_lambert(scenes: _Scenes, spectrum: str) -> None:
    # V = 10 km, so that the upper sky rows see the layer at optical depths below 2; there Kim's
    # q = 1.3 makes blue's extinction 1.43 times red's.
    level = scenes.level(
        "physical", 10000.0, 16, 0, albedo=0.0, extinction_spectrum=spectrum
    ).radiance
    sigma = channel_extinction(10000.0, "koschmieder", spectrum)
    length = scenes.geo.haze_path_length(haze_medium(scenes.spec.haze))
    # Sky pixels whose optical depth is below 2. Each pixel averages 16 random positions over
    # its 0.8° of elevation, across which exp(-σL) changes by up to 15 %: compare row means
    # (48 pixels each) to the pixel-centre law, and the overall mean, channel by channel.
    sky = np.isinf(scenes.geo.distance_m) & (sigma.max() * length < 2.0)
    assert sky.sum() > 100
    expected = scenes.clean * np.exp(-sigma[None, None, :] * length[..., None])
    rows = [r for r in range(sky.shape[0]) if sky[r].all()]
    assert len(rows) >= 3
    np.testing.assert_allclose(level[rows].mean(axis=1), expected[rows].mean(axis=1), rtol=0.015)
    np.testing.assert_allclose(
        level[sky].mean(axis=0) / expected[sky].mean(axis=0), 1.0, atol=0.005
    )


BOX_VISIBILITY = 2000.0
"""The haze of the box-toward-the-sun scenes (m)."""


def _box_toward_the_sun(mode: str, **estimator: float):
    """A dark red box 300 m away, its shaded side toward the camera, which looks toward the
    sun through V = 2000 m, over a rough sea (a flat mirror would show the box again below it,
    a reflection the vessel-light pass leaves to the tables: docs/physics.md, "Haze in front of
    a vessel"): the spec and the scene loaded for ``mode``, its ``render.estimator`` set by
    ``estimator``."""
    spec = small_spec(
        camera={"resolution": [48, 27], "fov_deg": 40.0, "pitch_deg": -2.0},
        sun={"elevation_deg": 25.0, "azimuth_deg": 0.0},
        haze={"levels": [BOX_VISIBILITY]},
        render={"estimator": estimator},
    )
    box = box_vessel(0, (300.0, 0.0, 8.0), (20.0, 80.0, 16.0))
    return spec, load_flat_scene(spec, [box], (BOX_VISIBILITY,), mode == "reference", 0.3)[0]


@pytest.mark.slow
def test_haze_in_front_of_a_vessel_sees_the_vessel() -> None:
    # Forward scattering brings the camera the light of what lies just beyond each point of
    # haze, here the box, not the bright open sky the tables hold.
    visibility = BOX_VISIBILITY
    spec, _ = _box_toward_the_sun("physical")
    scenes = {mode: _box_toward_the_sun(mode)[1] for mode in ("reference", "physical")}
    geo = passes.render_geometry(scenes["physical"])
    clean = passes.render_clean(scenes["physical"], 16, 1, 0.998, 0.75)
    on_box = geo.instance >= 0
    assert on_box.sum() >= 50
    sigma = channel_extinction(visibility, "koschmieder", "grey")

    def box_mean(mode: str, spp: int, loaded=None) -> tuple[np.ndarray, np.ndarray]:
        """The box's mean RGB and its standard error over 4 seeds (``loaded``: the scene,
        default the mode's)."""
        loaded = loaded or scenes[mode]
        renderer = LevelRenderer(mode, loaded, geo, clean, spec.haze, spec.render)
        means = [
            renderer.render(
                sigma, 0, spec.render.model_copy(update={"spp": spp, "seed": seed}), spec.haze
            )
            .radiance[on_box]
            .mean(axis=0)
            for seed in range(4)
        ]
        return np.mean(means, axis=0), np.std(means, axis=0, ddof=1) / 2.0

    ref, ref_se = box_mean("reference", 256)
    assert EstimatorSettings().vessel_light_share > 0.0  # the pass is on by default
    phys, phys_se = box_mean("physical", 32)
    allowed = 0.03 * ref + 3.0 * np.hypot(ref_se, phys_se)
    assert np.all(np.abs(phys - ref) <= allowed), (phys / ref - 1.0, allowed / ref)
    # Without the pass the box is far too bright (measured +12.7 % in every channel).
    _, without_pass = _box_toward_the_sun("physical", vessel_light_share=0.0)
    open_sea, open_sea_se = box_mean("physical", 32, without_pass)
    assert np.all(open_sea - ref > 0.06 * ref + 3.0 * np.hypot(ref_se, open_sea_se))


def test_camera_points_change_the_draws_not_the_mean_nor_the_kernel() -> None:
    """The camera segment's in-scattering points are a loop of their own whose count is a
    kernel parameter: one point and four give the same level within their noise, different
    numbers for the same seed, and the second count launches no large kernel of its own."""
    import drjit as dr

    spec, loaded = _box_toward_the_sun("physical")
    sigma = channel_extinction(BOX_VISIBILITY, "koschmieder", "grey")
    levels: dict[int, list[np.ndarray]] = {}
    for points in (1, 4):
        settings = EstimatorSettings(camera_points=points, vessel_light_share=0.0)
        renderer = physical.PhysicalRenderer(loaded, spec, settings)
        if points == 4:
            dr.set_flag(dr.JitFlag.KernelHistory, True)
            dr.kernel_history()  # clear
        try:
            levels[points] = [
                renderer.render([sigma], 0.998, 0.75, 16, seed).levels[0] for seed in range(6)
            ]
            history = dr.kernel_history() if points == 4 else []
        finally:
            dr.set_flag(dr.JitFlag.KernelHistory, False)
    one, four = (np.array([image.mean() for image in levels[n]]) for n in (1, 4))
    error = np.hypot(one.std(ddof=1), four.std(ddof=1)) / np.sqrt(len(one))
    assert abs(one.mean() - four.mean()) <= 4.0 * error, (one.mean(), four.mean(), error)
    assert not np.array_equal(levels[1][0], levels[4][0])
    large = [k for k in history if k.get("operation_count", 0) > 5000]
    assert large and all(k.get("cache_hit") for k in large)


def test_aiming_at_the_vessels_keeps_the_vessel_light_and_cuts_its_noise() -> None:
    # The pass's probe points drawn near the box and its directions aimed at it (MIS against
    # the levels' mixture and the phase function) estimate the same correction as points
    # and directions from the mixture and phase function alone, with less noise per pixel.
    spec, loaded = _box_toward_the_sun("physical")
    on_box = passes.render_geometry(loaded).instance >= 0
    grey = channel_extinction(BOX_VISIBILITY, "koschmieder", "grey")
    sigma = np.broadcast_to(grey, (1, 3)).copy()
    # The whole pass at 16 spp, unsmoothed: the estimator itself.
    pass_only = EstimatorSettings(vessel_light_share=1.0, vessel_light_radius_px=0)
    aiming = replace(pass_only, near_share=0.0, aim_share=0.0), pass_only
    results = []
    for settings in aiming:
        renderer = physical.PhysicalRenderer(loaded, spec, settings)
        tables = renderer.tables(sigma, 0.998, 0.75, 1, settings.min_table_photons)
        images = np.stack(
            [
                renderer.vessel_light(sigma, 0.998, 0.75, tables, 16, seed)[..., 3:6]
                for seed in range(6)
            ]
        )
        results.append(images)
    plain, aimed = results
    for region in (np.ones_like(on_box), on_box, ~on_box):
        a, b = plain[:, region].mean(axis=(1, 2)), aimed[:, region].mean(axis=(1, 2))
        error = np.hypot(a.std(ddof=1), b.std(ddof=1)) / np.sqrt(len(a))
        assert abs(a.mean() - b.mean()) <= 4.0 * error, (a.mean(), b.mean(), error)
    assert plain[:, on_box].mean() < 0.0  # the shaded box darkens the haze in front of it
    # Measured: 0.68 of the per-pixel noise (standard deviation over seeds).
    assert aimed.std(axis=0).mean() < 0.85 * plain.std(axis=0).mean()


def test_physical_is_deterministic_and_reuses_its_kernel(scenes: _Scenes) -> None:
    import drjit as dr

    a = scenes.level("physical", 1000.0, 4, 9).radiance
    # Per-channel extinction has its own integrator (three tables per level): compile it once.
    scenes.level("physical", 4000.0, 4, 9, extinction_spectrum="kim")
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    dr.kernel_history()  # clear
    b = scenes.level("physical", 300.0, 4, 9).radiance  # another level: new σ and table
    # Another per-channel extinction is a value, not a new kernel.
    scenes.level("physical", 2000.0, 4, 9, extinction_spectrum="kim")
    history = dr.kernel_history()
    dr.set_flag(dr.JitFlag.KernelHistory, False)
    c = scenes.level("physical", 1000.0, 4, 9).radiance
    np.testing.assert_array_equal(a, c)
    assert not np.array_equal(a, b)
    # The render and photon-tracer kernels (thousands of operations, seconds to compile) must
    # be reused; small helper kernels (~1k operations) may be traced afresh for a new level set.
    launched = [
        k
        for k in history
        if k.get("type") == dr.KernelType.JIT and k.get("operation_count", 0) > 5000
    ]
    assert launched and all(k.get("cache_hit") for k in launched), [
        (k.get("operation_count"), k.get("hash")) for k in launched if not k.get("cache_hit")
    ]


def test_glint_lobe_takes_the_wind_of_a_beaufort_sea() -> None:
    # A sea given by its Beaufort force (6: 10.8-13.8 m/s, the scale's midpoint) has its
    # glint as wide as that wind makes it, not as sea.wind_speed's default 7 m/s.
    from seahaze.ocean import beaufort_wind_speed

    spec = small_spec(sea={"beaufort": 6})
    loaded, _ = load_flat_scene(spec, haze_box=False)
    renderer = physical.PhysicalRenderer(loaded, spec)
    assert renderer.wind_speed == pytest.approx(beaufort_wind_speed(6))
    assert renderer.wind_speed > 10.0


def test_table_sea_mixes_in_foam_by_its_coverage() -> None:
    """The photon table's sea is ``(1 - W)·water + W·Lambertian(ρ)``: all foam gives weight ρ
    and a cosine law (mean cos θ = 2/3); a partial cover adds its share to the water's mean
    reflectance (independently: the water-only sampling of the same BSDF)."""
    import mitsuba as mi

    from seahaze.render.photon_sources import sample_sea_reflectance

    water = mi.load_dict({"type": "roughdielectric", "alpha": 0.1, "int_ior": 1.333})
    rho = 0.22
    foam = sample_sea_reflectance(water, n_mu=4, per_bin=20000, foam_coverage=1.0)
    assert np.allclose(foam.weight, rho)
    assert foam.wo[..., 2].mean() == pytest.approx(2.0 / 3.0, abs=0.005)
    bare = sample_sea_reflectance(water, n_mu=4, per_bin=20000).weight[..., 1].mean(axis=1)
    mixed = sample_sea_reflectance(water, n_mu=4, per_bin=20000, seed=1, foam_coverage=0.3)
    expected = 0.7 * bare + 0.3 * rho
    assert np.allclose(mixed.weight[..., 1].mean(axis=1), expected, rtol=0.05, atol=0.004)
