"""Broken cloud: the layer covers N/8 of the sky, the sky's light averages Kasten & Czeplak's
irradiance under N oktas (integrated independently of the model), the Mitsuba emitters built
from it, a broken-cloud scene rendered, and the YAML's errors."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np
import pytest

from seahaze import clouds, overcast
from seahaze.sceneio import SceneFileError, parse_scene_text

SCENES = Path(__file__).resolve().parents[1] / "scenes"


def layer(oktas: float, seed: int = 3) -> clouds.CloudLayer:
    return clouds.CloudLayer(oktas, base_m=1000.0, size_m=800.0, seed=seed)


@pytest.mark.parametrize("oktas", [1, 3, 5, 7])
def test_the_layer_covers_n_eighths_of_its_area(oktas):
    # Straight up, far from where the cut was tabulated and with another seed: the mean cover
    # of 80 x 80 km of layer (100 largest clouds a side), seen at full detail.
    rng = np.random.default_rng(oktas)
    offset = np.array([161_000.0, -137_000.0])
    points = rng.uniform(-40_000.0, 40_000.0, size=(400_000, 2)) + offset
    directions = np.column_stack([points, np.full(len(points), 1000.0)])
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    cover = layer(oktas, seed=oktas + 11).cover(directions)
    assert cover.mean() == pytest.approx(oktas / 8, abs=0.03)
    # Clouds, not a grey veil: most of the layer is wholly cloud or wholly clear.
    assert np.mean((cover > 0.02) & (cover < 0.98)) < 0.2


def test_a_cloud_is_brighter_the_fewer_there_are():
    b = [clouds.cloud_brightness(n) for n in range(1, 9)]
    assert b[-1] == pytest.approx(1.0)  # a full deck is the overcast sky
    assert all(x > y for x, y in itertools.pairwise(b))
    assert clouds.cloud_brightness(1e-4) == pytest.approx(4.0, abs=1e-3)


def sky_irradiance(image: np.ndarray) -> float:
    """∫ L cos θ dω of a latitude–longitude image (grey: channel 0), midpoint rule."""
    rows, columns = image.shape[:2]
    theta = math.pi * np.arange(rows) / (rows - 1)
    weight = np.cos(theta) * np.sin(theta) * (math.pi / (rows - 1)) * (2 * math.pi / columns)
    upper = theta < math.pi / 2
    return float(np.sum(image[upper, :, 0].sum(axis=1) * weight[upper]))


@pytest.mark.parametrize("oktas", [2, 6])
def test_the_broken_sky_averages_kasten_and_czeplaks_irradiance(oktas):
    # A grey clear sky of radiance L and a sun of beam E_b at 40°: G_clear = πL + E_b sin 40°.
    # Over many cloud layers (and suns all over the sky), the mean global irradiance of the
    # broken sky, by quadrature of its image plus the sun's beam it lets through, must be
    # Kasten & Czeplak's share of G_clear. Small clouds (150 m at 1000 m) put many in every
    # sky; the mean of 32 layers then has a standard error of about 1.2 % (measured).
    rows, columns, clear_radiance, beam = 129, 256, 0.1, 3.0
    elevation = math.radians(40.0)
    g_clear = math.pi * clear_radiance + beam * math.sin(elevation)
    deck = overcast.zenith_radiance(np.full(3, g_clear))
    clear = np.full((rows, columns, 3), clear_radiance)
    azimuths = np.linspace(0.0, 2 * math.pi, 64, endpoint=False)
    suns = np.column_stack(
        [
            math.cos(elevation) * np.sin(azimuths),
            math.cos(elevation) * np.cos(azimuths),
            np.full(64, math.sin(elevation)),
        ]
    )
    totals = []
    for seed in range(100, 132):
        cloudy = clouds.CloudLayer(oktas, base_m=1000.0, size_m=150.0, seed=seed)
        sky = sky_irradiance(clouds.broken_sky_radiance(clear, deck, cloudy, turbidity=3.0))
        passed = 1.0 - cloudy.cover(suns).mean()
        totals.append(sky + passed * beam * math.sin(elevation))
    expected = overcast.cloud_transmission(oktas) * g_clear
    assert np.mean(totals) == pytest.approx(expected, rel=0.04)


def test_clouds_are_grey_and_brightest_at_their_thin_edges():
    rows, columns = 129, 256
    clear = np.zeros((rows, columns, 3))
    clear[..., 2] = 1.0  # a pure blue clear sky marks where there is no cloud
    cloudy = layer(5)
    image = clouds.broken_sky_radiance(clear, 2.0, cloudy, turbidity=3.0)
    cover, shade = cloudy.latlong_cover(rows, columns)
    solid = cover > 0.999
    np.testing.assert_allclose(image[solid][:, 0], image[solid][:, 1], rtol=1e-6)
    # No cloud below the horizon: there the image is the clear sky's own.
    np.testing.assert_array_equal(image[rows // 2 + 1 :], clear[rows // 2 + 1 :])
    # Thin edges (just past the cut) brighter than the cores, the shade averaging 1.
    inside = solid[: rows // 3]
    edge = inside & ~np.roll(inside, 2, axis=0) | inside & ~np.roll(inside, -2, axis=0)
    assert shade[: rows // 3][edge].mean() > 1.2 * shade[: rows // 3][inside & ~edge].mean()


def test_clouds_fade_into_the_sky_through_the_air_below_them():
    # Overhead, the air up to a high layer in pure air (T = 1) is the Rayleigh atmosphere's:
    # exp(-0.097) at 550 nm (Bucholtz 1995); a turbid day's aerosol adds (T - 1) times that,
    # mostly below 1.2 km; toward the horizon the path grows as 1/μ.
    assert clouds.air_transmittance(1.0, 1e6, 1.0) == pytest.approx(math.exp(-0.097), rel=1e-6)
    low = clouds.air_transmittance(1.0, 1000.0, 3.0)
    expected = 0.097 * ((1 - math.exp(-1000 / 8400)) + 2 * (1 - math.exp(-1000 / 1200)))
    assert low == pytest.approx(math.exp(-expected), rel=1e-9)
    assert clouds.air_transmittance(0.1, 1000.0, 3.0) == pytest.approx(low**10, rel=1e-9)
    assert clouds.air_transmittance(0.0, 1000.0, 3.0) == 0.0
    # In the sky's image a cloud's contrast against the clear sky fades toward the horizon:
    # overhead the clouds stand out, 1° above the horizon (1/μ = 57) they are all but gone.
    rows, columns = 1025, 64
    clear = np.full((rows, columns, 3), 0.5)
    image = clouds.broken_sky_radiance(clear, 2.0, layer(7), turbidity=3.0)
    contrast = np.abs(image[..., 0] - 0.5).max(axis=1) / 0.5
    assert contrast[:200].max() > 1.0
    one_degree_up = round((89.0 / 180.0) * (rows - 1))
    assert contrast[one_degree_up] < 0.01


def test_far_toward_the_horizon_the_cover_is_its_mean():
    # Where a texel spans more of the layer than the largest clouds, nothing is resolved.
    cloudy = layer(3)
    cover, shade = cloudy.latlong_cover(257, 512)
    assert np.allclose(cover[127], 3 / 8, atol=1e-3) and np.allclose(shade[127], 1.0, atol=1e-3)
    assert cover[:100].std() > 0.3  # within 70° of the zenith: clouds and gaps


def broken_spec(cloud_seed: int | None = None):
    from seahaze.spec import with_changes

    text = (SCENES / "broken_cloud.yaml").read_text()
    spec = parse_scene_text(text, str(SCENES / "broken_cloud.yaml"))
    return (
        spec
        if cloud_seed is None
        else with_changes(spec, {"sky": {"clouds": {"seed": cloud_seed}}})
    )


def test_the_envmap_holds_the_image_with_its_zenith_up_and_azimuth_from_y_to_x(
    mitsuba_variant,
):
    import drjit as dr
    import mitsuba as mi

    from seahaze.render.sky import BROKEN_ROWS, broken_dict

    spec = broken_spec()
    emitter = mi.load_dict(broken_dict(spec))
    image = np.asarray(broken_dict(spec)["bitmap"], np.float64)
    rows, columns = BROKEN_ROWS, 2 * BROKEN_ROWS
    assert image.shape == (rows, columns, 3)
    rng = np.random.default_rng(5)
    i, j = rng.integers(0, rows // 2 - 1, 400), rng.integers(0, columns, 400)
    directions = clouds.latlong_directions(rows, columns)[i, j]
    si = dr.zeros(mi.SurfaceInteraction3f, len(i))
    si.wi = -mi.Vector3f(*(directions[:, k].astype(np.float32) for k in range(3)))
    seen = np.array(emitter.eval(si), np.float64)
    seen = seen if seen.shape[-1] == 3 else seen.T
    np.testing.assert_allclose(seen, image[i, j], rtol=2e-3, atol=1e-6)


def test_a_hidden_sun_is_dark_and_an_out_sun_is_the_clear_days(mitsuba_variant):
    from seahaze.render.sky import cloud_layer, sky_emitters, sun_dict
    from seahaze.world import sun_direction

    outcomes = {}
    for seed in range(12):
        spec = broken_spec(seed)
        sun = sun_dict(spec)
        passed = cloud_layer(spec).sun_transmission(
            sun_direction(spec.sun.elevation_deg, spec.sun.azimuth_deg)
        )
        assert sun["sun_scale"] == pytest.approx(spec.sun.scale * passed)
        outcomes[round(passed)] = spec
    assert set(outcomes) == {0, 1}, "12 seeds at 5 oktas hide the sun and show it"
    emitters = sky_emitters(outcomes[1])
    assert set(emitters) == {"sky", "sun"} and emitters["sun"]["type"] == "directional"
    assert max(emitters["sun"]["irradiance"]["value"]) > 0.5
    assert max(sky_emitters(outcomes[0])["sun"]["irradiance"]["value"]) == 0.0


@pytest.mark.slow
def test_a_broken_cloud_scene_renders_clouds_and_blue_sky(mitsuba_variant):
    from seahaze.render.engine import open_session
    from seahaze.spec import with_overrides

    for mode in ("physical", "asm"):
        spec = with_overrides(broken_spec(), resolution=(96, 54), spp=2, levels=[2000.0])
        session = open_session(with_overrides(spec, mode=mode))
        # asm composites Mitsuba's clean pass, whose scene holds the sun as a directional
        # emitter beside the cloud envmap; physical takes the sun disk and the envmap itself.
        given = session.render_clean() if mode == "asm" else None
        clean, levels = session.level_renderer(given).render_all([3.912 / 2000.0])
        assert np.all(np.isfinite(clean)) and np.all(np.isfinite(levels[0].radiance))
        sky = np.isinf(session.pixels.distance_m)
        sky[sky.shape[0] // 4 :] = False
        # Clear sky is deep blue (B/R about 2.5 in linear RGB); a cloud is grey, a little blue
        # from the air in front of it.
        rgb = clean[sky]
        ratio = rgb[:, 2] / rgb[:, 0]
        grey, blue = ratio < 1.4, ratio > 1.8
        assert grey.mean() > 0.1 and blue.mean() > 0.1, (mode, grey.mean(), blue.mean())


def test_the_cloud_yaml_errors_name_the_field_and_what_is_allowed():
    with pytest.raises(SceneFileError) as err:
        parse_scene_text("sky:\n  clouds:\n    oktas: 3\n", "s.yaml")
    message = str(err.value)
    assert "sky" in message and "broken" in message and "\n" not in message, message
    with pytest.raises(SceneFileError) as err:
        parse_scene_text("sky:\n  model: broken\n  clouds:\n    oktas: 8\n", "s.yaml")
    message = str(err.value)
    assert "sky.clouds.oktas" in message and "7" in message, message
    with pytest.raises(SceneFileError) as err:
        parse_scene_text(
            "haze:\n  top_m: 1500\nsky:\n  model: broken\n  clouds:\n    base_height_m: 900\n",
            "s.yaml",
        )
    message = str(err.value)
    assert "sky.clouds.base_height_m" in message and "haze.top_m" in message, message


def test_a_clear_sky_records_no_clouds():
    spec = parse_scene_text("sky:\n  turbidity: 3\n", "s.yaml")
    assert "clouds" not in spec.sky.model_dump() and "model" not in spec.sky.model_dump()
    assert broken_spec().sky.model_dump()["clouds"]["oktas"] == 5


def test_a_batch_draws_each_scene_its_own_clouds_and_amount():
    from seahaze.batch.plan import plan_scenes
    from seahaze.render.sky import cloud_layer
    from seahaze.spec import with_changes

    template = with_changes(broken_spec(), {"variation": {"cloud_oktas": [2, 6]}})
    assert template.sky.clouds is not None and template.sky.clouds.seed == 4  # pinned
    jobs = plan_scenes([(template, "broken")], count=12, master_seed=3).jobs
    oktas = [job.spec.sky.clouds.oktas for job in jobs]
    assert set(oktas) <= {2, 3, 4, 5, 6} and len(set(oktas)) >= 3, oktas
    layers = {cloud_layer(job.spec).seed for job in jobs}
    assert len(layers) == 12  # the pinned seed gave way: every scene its own layer
    again = plan_scenes([(template, "broken")], count=12, master_seed=3).jobs
    assert [job.spec for job in again] == [job.spec for job in jobs]
    kept = with_changes(template, {"variation": {"resample_clouds": False}})
    kept_jobs = plan_scenes([(kept, "broken")], count=3, master_seed=3).jobs
    assert {cloud_layer(job.spec).seed for job in kept_jobs} == {4}
    # Defaults leave a recorded config as it was before the clouds could vary.
    recorded = parse_scene_text("sky:\n  turbidity: 3\n", "s.yaml").model_dump()["variation"]
    assert "cloud_oktas" not in recorded and "resample_clouds" not in recorded


def test_varying_the_clouds_of_a_clear_sky_is_refused():
    with pytest.raises(SceneFileError) as err:
        parse_scene_text("variation:\n  cloud_oktas: [2, 5]\n", "s.yaml")
    message = str(err.value)
    assert "variation.cloud_oktas" in message and "broken" in message, message
    with pytest.raises(SceneFileError) as err:
        parse_scene_text("sky:\n  model: broken\nvariation:\n  cloud_oktas: [2, 8]\n", "s.yaml")
    assert "variation.cloud_oktas" in str(err.value) and "7" in str(err.value)


def test_a_batch_draws_its_skies_from_the_listed_models():
    from seahaze.batch.plan import plan_scenes

    template = parse_scene_text(
        "variation:\n  sky_models: [clear, broken, overcast]\n  cloud_oktas: [3, 3]\n", "s.yaml"
    )
    jobs = plan_scenes([(template, "skies")], count=15, master_seed=1).jobs
    models = [job.spec.sky.model for job in jobs]
    assert set(models) == {"clear", "broken", "overcast"}, models
    for job in jobs:  # clouds on the broken skies only, with the drawn amount
        clouds = job.spec.sky.clouds
        assert (clouds is not None) == (job.spec.sky.model == "broken")
        assert clouds is None or clouds.oktas == 3
    with pytest.raises(SceneFileError) as err:
        parse_scene_text("variation:\n  sky_models: [clear, hazy]\n", "s.yaml")
    assert "variation.sky_models" in str(err.value) and "'broken'" in str(err.value)
    with pytest.raises(SceneFileError) as err:
        parse_scene_text(
            "haze:\n  top_m: 1500\nvariation:\n  sky_models: [clear, broken]\n", "s.yaml"
        )
    assert "sky.clouds.base_height_m" in str(err.value)


def test_the_wind_rises_with_height_as_the_marine_power_law():
    # Hsu, Meindl & Gilhousen (1994): U(z) = U10 (z / 10 m)^0.11 over the open sea.
    assert clouds.wind_at_height(8.0, 10.0) == pytest.approx(8.0)
    assert clouds.wind_at_height(10.0, 1000.0) == pytest.approx(10.0 * 100.0**0.11)
    assert clouds.wind_at_height(10.0, 1000.0) == pytest.approx(16.6, abs=0.05)


def test_a_drifted_layer_is_the_same_layer_moved():
    still = layer(5)
    moved = clouds.CloudLayer(5, 1000.0, 800.0, 3, offset_m=(350.0, -120.0))
    rng = np.random.default_rng(8)
    points = rng.uniform(-3000.0, 3000.0, size=(500, 2))
    # The direction to each point of the layer, and to where that point was before the drift.
    to_now = np.column_stack([points, np.full(500, 1000.0)])
    before = np.column_stack([points - [350.0, -120.0], np.full(500, 1000.0)])
    to_now /= np.linalg.norm(to_now, axis=1, keepdims=True)
    before /= np.linalg.norm(before, axis=1, keepdims=True)
    np.testing.assert_allclose(moved.cover(to_now), still.cover(before), atol=1e-9)
    assert not np.allclose(moved.cover(to_now), still.cover(to_now))


def test_a_sequence_frame_drifts_its_clouds_with_the_wind_aloft(mitsuba_variant):
    from seahaze.render.engine import open_session
    from seahaze.render.sky import cloud_layer, sun_dict
    from seahaze.spec import with_changes, with_overrides
    from seahaze.world import sun_direction

    spec = broken_spec()
    speed = clouds.wind_at_height(spec.sea.wind_speed, spec.sky.clouds.base_height_m)
    heading = math.radians(spec.sea.direction_deg)
    drifted = cloud_layer(spec, 60.0)
    expected = (60.0 * speed * math.cos(heading), 60.0 * speed * math.sin(heading))
    np.testing.assert_allclose(drifted.offset_m, expected, rtol=1e-12)
    sun = sun_direction(spec.sun.elevation_deg, spec.sun.azimuth_deg)
    passes = [cloud_layer(spec, t).sun_transmission(sun) for t in (0.0, 30.0, 60.0, 90.0, 120.0)]
    assert max(passes) - min(passes) > 0.5, passes  # a cloud crosses the sun in two minutes
    t = 30.0 * int(np.argmin(passes))
    assert sun_dict(spec, t)["sun_scale"] == pytest.approx(min(passes))
    # A frame of a sequence renders its own time's clouds.
    sequence = with_changes(spec, {"sequence": {"frames": 5, "fps": 1.0 / 30.0}})
    small = with_overrides(sequence, resolution=(48, 27), spp=1, levels=[2000.0])
    assert open_session(small, frame=3).loaded.elapsed_s == pytest.approx(90.0)
