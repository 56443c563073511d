"""The 8-bit sRGB encoding of the PNGs against colour-science's IEC 61966-2-1 encoding."""

from __future__ import annotations

import numpy as np
import pytest

from seahaze import imaging


def _colour_srgb8(linear: np.ndarray) -> np.ndarray:
    """The independent reference: colour-science's sRGB encoding of every value, rounded."""
    import colour

    encoded = colour.cctf_encoding(np.asarray(linear, dtype=np.float64), function="sRGB")
    return np.round(encoded * 255.0).astype(np.uint8)


def test_codes_equal_colour_science_encoding_on_random_radiance() -> None:
    rng = np.random.default_rng(7)
    radiance = (rng.random((90, 160, 3)) ** 3 * 1.3).astype(np.float32)
    exposure = 1.37
    linear = np.clip(radiance * np.float32(exposure), 0.0, 1.0)
    np.testing.assert_array_equal(imaging.to_srgb8(radiance, exposure), _colour_srgb8(linear))


@pytest.mark.parametrize("direction", [-1.0, 0.0, 1.0])
def test_codes_equal_colour_science_encoding_at_and_beside_every_bound(direction: float) -> None:
    bounds, _, _ = imaging.srgb8_bounds()
    values = np.nextafter(bounds, np.float32(direction)) if direction else bounds
    image = np.repeat(values[None, :, None], 3, axis=2)
    codes = imaging.to_srgb8(image, 1.0)[0, :, 0]
    np.testing.assert_array_equal(codes, _colour_srgb8(values))
    # Below a bound the code is k, from the bound on k + 1: every code 0..255 is reached.
    expected = np.arange(255) + (direction >= 0.0)
    np.testing.assert_array_equal(codes, expected)


def test_out_of_range_values_clip() -> None:
    image = np.array([[[np.nan, np.inf, -np.inf], [-1.0, 0.0, 7.0]]], dtype=np.float32)
    np.testing.assert_array_equal(imaging.to_srgb8(image, 1.0), [[[0, 255, 0], [0, 0, 255]]])


def test_decode_is_the_iec_transfer_function_at_published_points() -> None:
    # IEC 61966-2-1: the linear segment up to V = 0.04045 (slope 1/12.92); mid-grey code 128
    # is 0.2158605 linear (a widely tabulated value); white is 1.
    assert imaging.srgb_decode(0.04045) == pytest.approx(0.04045 / 12.92, rel=1e-12)
    assert imaging.srgb_decode(128 / 255) == pytest.approx(0.2158605, abs=1e-7)
    assert imaging.srgb_decode(1.0) == pytest.approx(1.0, abs=1e-15)


def _sky_scene(upper_radiance: float, sun_pixels: int = 0):
    """A 100×50 frame: sky in the top half (its lower rows within the horizon band, radiance
    0.2; the rows above 10° at ``upper_radiance``), sea below; ``sun_pixels`` sky pixels at
    1000 (a sun disk)."""
    rows, columns = 100, 50
    elevation = np.repeat(np.linspace(30.0, -30.0, rows)[:, None], columns, axis=1)
    distance = np.where(elevation > 0.0, np.inf, 500.0)
    y = np.where(elevation > imaging.HORIZON_BAND_DEG, upper_radiance, 0.2)
    y = np.where(elevation > 0.0, y, 0.05)
    y.flat[:sun_pixels] = 1000.0
    return np.repeat(y[..., None], 3, axis=2), distance, elevation


def test_auto_exposure_puts_the_horizon_sky_at_the_key():
    clean, distance, elevation = _sky_scene(upper_radiance=0.15)
    assert imaging.auto_exposure(clean, distance, elevation) == pytest.approx(0.6 / 0.2)
    # A sun disk (1 % of the sky) clips, as a camera's would, and leaves the exposure.
    clean, distance, elevation = _sky_scene(upper_radiance=0.15, sun_pixels=25)
    assert imaging.auto_exposure(clean, distance, elevation) == pytest.approx(0.6 / 0.2)
    # Without sky: the frame's mean at 0.18.
    sea = np.full((10, 10, 3), 0.3)
    flat = np.zeros((10, 10))
    assert imaging.auto_exposure(sea, flat + 100.0, flat - 5.0) == pytest.approx(0.18 / 0.3)


def test_auto_exposure_keeps_a_sky_brighter_above_than_at_its_horizon_from_burning_out():
    # Dusk away from the set sun: the Earth's shadow dark on the horizon, the sky above it
    # three times as bright. Keyed to the horizon alone, two thirds of the sky would be white.
    clean, distance, elevation = _sky_scene(upper_radiance=0.6)
    exposure = imaging.auto_exposure(clean, distance, elevation)
    sky = np.isinf(distance)
    assert np.mean(clean[sky][:, 1] * exposure > 1.0 + 1e-9) <= 1.0 - imaging.SKY_HIGHLIGHT_QUANTILE
    assert exposure == pytest.approx(1.0 / 0.6)
