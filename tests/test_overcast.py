"""The overcast sky: the CIE gradation and Kasten & Czeplak's cloud transmission (published
laws, integrated independently), the Mitsuba emitter built from them, and an overcast scene
rendered in the physical mode."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy import integrate

from conftest import emitter_radiance
from seahaze import overcast
from seahaze.sceneio import SceneFileError, parse_scene_text

SCENES = Path(__file__).resolve().parents[1] / "scenes"


def test_the_gradation_is_moon_and_spencers():
    assert overcast.gradation(1.0) == pytest.approx(1.0)
    assert overcast.gradation(0.0) == pytest.approx(1.0 / 3.0)
    assert overcast.gradation(math.cos(math.radians(60))) == pytest.approx(2.0 / 3.0)
    assert overcast.gradation(-0.2) == 0.0


def test_horizontal_irradiance_is_seven_pi_ninths_of_the_zenith_radiance():
    # ∫ L cos θ dω over the upper hemisphere, by quadrature in θ (independent of the closed form).
    value, _ = integrate.quad(
        lambda t: overcast.gradation(math.cos(t)) * math.cos(t) * math.sin(t), 0.0, math.pi / 2
    )
    assert 2.0 * math.pi * value == pytest.approx(
        overcast.HORIZONTAL_IRRADIANCE_PER_ZENITH_RADIANCE
    )
    assert pytest.approx(7 * math.pi / 9) == overcast.HORIZONTAL_IRRADIANCE_PER_ZENITH_RADIANCE


def test_kasten_czeplak_cloud_transmission():
    assert overcast.cloud_transmission(0) == 1.0
    assert overcast.cloud_transmission(8) == pytest.approx(0.25)
    assert overcast.cloud_transmission(4) == pytest.approx(1.0 - 0.75 * 0.5**3.4)
    with pytest.raises(ValueError, match=r"0\.\.8"):
        overcast.cloud_transmission(9)


def test_the_zenith_radiance_gives_a_quarter_of_the_clear_days_luminance():
    clear = np.array([0.8, 0.7, 0.6])
    zenith = overcast.zenith_radiance(clear)
    irradiance = zenith * overcast.HORIZONTAL_IRRADIANCE_PER_ZENITH_RADIANCE
    assert irradiance == pytest.approx(0.25 * (0.2126 * 0.8 + 0.7152 * 0.7 + 0.0722 * 0.6))


def test_the_latlong_image_has_its_zenith_on_top_and_is_black_below_the_horizon():
    image = overcast.latlong_radiance(2.0, rows=8, columns=3)
    assert image.shape == (8, 3, 3) and image.dtype == np.float32
    theta = math.pi * np.arange(8) / 7
    np.testing.assert_allclose(image[:, 1, 0], 2.0 * overcast.gradation(np.cos(theta)), rtol=1e-6)
    assert np.all(image[4:] == 0.0) and np.all(image[:, :, 0] == image[:, :, 2])


def overcast_spec():
    text = (SCENES / "overcast.yaml").read_text()
    return parse_scene_text(text, str(SCENES / "overcast.yaml"))


def test_the_emitter_follows_the_gradation_upward_in_the_world(mitsuba_variant):
    import mitsuba as mi

    from seahaze.render.sky import overcast_dict

    emitter = mi.load_dict(overcast_dict(overcast_spec()))
    zenith = emitter_radiance(emitter, (0.0, 0.0, 1.0))
    for mu, azimuth in ((0.5, 0.3), (0.1, 2.0), (0.02, -1.2)):
        s = math.sqrt(1 - mu * mu)
        seen = emitter_radiance(emitter, (s * math.cos(azimuth), s * math.sin(azimuth), mu))
        np.testing.assert_allclose(seen / zenith, overcast.gradation(mu), rtol=1e-4)
    assert np.all(emitter_radiance(emitter, (0.6, 0.0, -0.8)) == 0.0)
    assert zenith[0] == pytest.approx(zenith[2])


def _irradiance_by_sampling(emitter, n: int = 1 << 16) -> np.ndarray:
    import drjit as dr
    import mitsuba as mi

    rng = mi.PCG32(n, 12345)
    sample = mi.Point2f(rng.next_float32(), rng.next_float32())
    ds, weight = emitter.sample_direction(dr.zeros(mi.Interaction3f), sample)
    values = np.array(weight * dr.maximum(ds.d.z, 0.0), np.float64)
    return (values if values.shape[-1] == 3 else values.T).mean(axis=0)


def test_the_overcast_sky_lets_through_a_quarter_of_the_clear_days_light(mitsuba_variant):
    import mitsuba as mi

    from seahaze.render.sky import (
        clear_global_irradiance,
        horizontal_irradiance,
        overcast_dict,
        sunsky_dict,
    )

    spec = overcast_spec()
    sun, sky = spec.sun, spec.sky
    clear = clear_global_irradiance(
        sun.elevation_deg, sun.azimuth_deg, sky.turbidity, sky.ground_albedo
    )
    # The clear sky's own part, by quadrature of its radiance, and the sun's beam on a level
    # surface: the sampled estimate within its noise.
    clear_sky = mi.load_dict(sunsky_dict(spec, sun=False))
    from seahaze.render.sun_disk import disk_irradiance

    beam = disk_irradiance(mi.load_dict(sunsky_dict(spec, sky=False)))
    expected = horizontal_irradiance(clear_sky, 256) + beam * math.sin(
        math.radians(sun.elevation_deg)
    )
    np.testing.assert_allclose(clear, expected, rtol=0.01)
    overcast_sky = mi.load_dict(overcast_dict(spec))
    quarter = 0.25 * float(overcast.REC709_LUMINANCE @ clear)
    np.testing.assert_allclose(horizontal_irradiance(overcast_sky, 256), quarter, rtol=2e-3)
    np.testing.assert_allclose(_irradiance_by_sampling(overcast_sky), quarter, rtol=5e-3)


def test_an_overcast_scene_renders_grey_light_without_a_sun(mitsuba_variant):
    from seahaze.render.engine import open_session
    from seahaze.spec import with_overrides

    spec = with_overrides(overcast_spec(), resolution=(64, 36), spp=4, levels=[1000.0])
    session = open_session(spec)
    clean, levels = session.level_renderer().render_all([3.912e-3])
    assert np.all(np.isfinite(clean)) and np.all(np.isfinite(levels[0].radiance))
    sky = np.isinf(session.pixels.distance_m)
    sky[sky.shape[0] // 3 :] = False  # well above the horizon: no pixel part sea or vessel
    assert sky.any()
    # The clean sky is the grey envmap itself: R = G = B.
    np.testing.assert_allclose(clean[sky][:, 0], clean[sky][:, 2], rtol=1e-4)
    # Grey light through grey haze: over the sky the level is grey but for the little of the
    # sea's blue-green that the haze scatters up (R/B 0.988 measured), and it pulls the sea's
    # own colour toward grey.
    hazy = levels[0].radiance
    assert hazy[sky][:, 0].mean() / hazy[sky][:, 2].mean() == pytest.approx(1.0, abs=0.02)
    sea = np.isfinite(session.pixels.distance_m) & (session.pixels.instance < 0)
    clean_sea, hazy_sea = clean[sea].mean(axis=0), hazy[sea].mean(axis=0)
    assert clean_sea[0] / clean_sea[2] < hazy_sea[0] / hazy_sea[2] < 1.0


def test_an_unknown_sky_model_names_the_field_and_the_choices():
    with pytest.raises(SceneFileError) as err:
        parse_scene_text("sky:\n  model: cloudy\n", "s.yaml")
    message = str(err.value)
    assert message.startswith("s.yaml:2: sky.model") and "'clear'" in message, message
    assert "'overcast'" in message and "\n" not in message
