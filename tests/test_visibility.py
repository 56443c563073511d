"""Visibility physics against published numbers (Koschmieder; WMO MOR; MSVD paper Tables 1–2)."""

import math

import numpy as np
import pytest

from seahaze.visibility import (
    CHANNEL_WAVELENGTHS_NM,
    GRADED_LEVELS_M,
    REGULATION_CLASSES,
    VisSelectionError,
    channel_extinction,
    extinction_coefficient,
    kim_exponent,
    koschmieder_contrast,
    level_name,
    parse_vis_selection,
    regulation_class,
    visibility_from_extinction,
)


def test_koschmieder_constant_is_ln_50():
    # sigma V = -ln(0.02) = 3.912 (Koschmieder, 2 % threshold); the paper's 3.912 / V.
    assert extinction_coefficient(1000.0) == pytest.approx(3.912e-3, abs=1e-6)
    assert extinction_coefficient(1.0) == pytest.approx(math.log(50.0))


def test_mor_constant_is_ln_20():
    # WMO meteorological optical range: 5 % threshold, sigma V = 2.996.
    assert extinction_coefficient(1000.0, "mor") == pytest.approx(2.996e-3, abs=1e-6)


def test_contrast_at_visibility_equals_threshold():
    for threshold, eps in (("koschmieder", 0.02), ("mor", 0.05)):
        assert koschmieder_contrast(800.0, 800.0, threshold) == pytest.approx(-eps)


def test_inverse_round_trips():
    v = np.array([50.0, 300.0, 4000.0, 1e5])
    for v_i in v:
        assert visibility_from_extinction(extinction_coefficient(v_i)) == pytest.approx(v_i)


@pytest.mark.parametrize("bad", [0.0, -5.0, math.inf, math.nan])
def test_extinction_rejects_bad_visibility(bad):
    with pytest.raises(ValueError):
        extinction_coefficient(bad)


@pytest.mark.parametrize(
    ("v_m", "q"),
    # Kim, McArthur & Korevaar (2001), V in km: 0 (≤ 0.5), V − 0.5 (≤ 1), 0.16 V + 0.34 (≤ 6),
    # 1.3 (≤ 50), 1.6 beyond.
    [(50.0, 0.0), (300.0, 0.0), (500.0, 0.0), (800.0, 0.3), (1000.0, 0.5), (2000.0, 0.66),
     (4000.0, 0.98), (6000.0, 1.3), (20e3, 1.3), (50e3, 1.3), (100e3, 1.6)],
)  # fmt: skip
def test_kim_exponent_follows_the_published_pieces(v_m, q):
    assert kim_exponent(v_m) == pytest.approx(q, abs=1e-12)


@pytest.mark.parametrize("edge_m", [500.0, 1000.0, 6000.0])
def test_kim_exponent_is_continuous_where_the_paper_joins_pieces(edge_m):
    below, above = kim_exponent(edge_m * (1 - 1e-9)), kim_exponent(edge_m * (1 + 1e-9))
    assert below == pytest.approx(above, abs=1e-6)


def _srgb_daylight_response() -> tuple[np.ndarray, np.ndarray]:
    """Wavelengths (nm) and the linear-sRGB channels' response to D65 per nm, (n, 3): an
    independent computation from colour-science's CIE 1931 tables and sRGB matrix."""
    import colour

    shape = colour.SpectralShape(360, 830, 1)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(shape)
    d65 = colour.SDS_ILLUMINANTS["D65"].copy().align(shape)
    to_rgb = colour.RGB_COLOURSPACES["sRGB"].matrix_XYZ_to_RGB
    return cmfs.wavelengths, (cmfs.values @ to_rgb.T) * d65.values[:, None]


@pytest.mark.parametrize("q", [0.5, 1.0, 1.3])
def test_channel_wavelengths_match_the_mean_extinction_of_each_srgb_channel(q):
    lam, response = _srgb_daylight_response()
    mean = (response * ((lam / 550.0) ** -q)[:, None]).sum(axis=0) / response.sum(axis=0)
    np.testing.assert_allclose(550.0 * mean ** (-1.0 / q), CHANNEL_WAVELENGTHS_NM, atol=2.0)


@pytest.mark.parametrize("visibility_m", [800.0, 2000.0, 4000.0])
def test_channel_transmittance_matches_the_band_integral(visibility_m):
    # Daylight through haze, integrated over each channel's band, against exp(-sigma_c d) at
    # the channel's wavelength, out to optical depth 2 (13.5 % transmittance at 550 nm).
    lam, response = _srgb_daylight_response()
    q = kim_exponent(visibility_m)
    sigma550 = extinction_coefficient(visibility_m)
    sigma_c = channel_extinction(visibility_m, "koschmieder", "kim")
    for tau550 in (0.25, 1.0, 2.0):
        d = tau550 / sigma550
        spectral = np.exp(-sigma550 * (lam / 550.0) ** -q * d)
        band = (response * spectral[:, None]).sum(axis=0) / response.sum(axis=0)
        np.testing.assert_allclose(np.exp(-sigma_c * d), band, rtol=0.015)


def test_graded_levels_are_the_papers_eleven():
    assert GRADED_LEVELS_M == (300, 400, 500, 800, 1000, 1300, 1600, 2000, 2500, 3000, 4000)
    assert [level_name(v) for v in (300, 4000)] == ["v0300", "v4000"]


@pytest.mark.parametrize(
    ("v", "key"),
    [
        (10, "suspended"),
        (49.9, "suspended"),
        (50, "near_suspension"),
        (199, "near_suspension"),
        (300, "strict"),
        (499, "strict"),
        (500, "restricted"),
        (800, "restricted"),
        (895, "restricted"),
        (1000, "minor"),
        (1999, "minor"),
        (2009, "normal"),
        (3999, "normal"),
        (4000, "clear"),
    ],
)
def test_regulation_classes_follow_table_1(v, key):
    assert regulation_class(v).key == key


def test_regulation_bounds_are_the_papers():
    assert [c.upper_m for c in REGULATION_CLASSES[:-1]] == [50, 200, 500, 1000, 2000, 4000]


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("300..4000", list(map(float, GRADED_LEVELS_M))),
        ("500..1300", [500.0, 800.0, 1000.0, 1300.0]),
        ("1000..1000", [1000.0]),
        ("300,1000,2500", [300.0, 1000.0, 2500.0]),
        ("2500, 300", [300.0, 2500.0]),
        ("50", [50.0]),
        ("100..10000:3", [100.0, 1000.0, 10000.0]),
        ("300..4000:1", [300.0]),
    ],
)
def test_vis_selection_good(text, expected):
    assert parse_vis_selection(text) == expected


def test_vis_log_spacing_is_geometric():
    levels = parse_vis_selection("300..4000:6")
    ratios = np.diff(np.log(levels))
    assert len(levels) == 6 and np.allclose(ratios, ratios[0], rtol=0.02)


@pytest.mark.parametrize(
    "text",
    [
        "",
        "abc",
        "300..abc",
        "4000..300",
        "0..100",
        "-5",
        "0",
        "300,,400",
        "300..4000:0",
        "10..20:50",
        "5000..9000",
        "1..2..3",
        "300;400",
    ],
)
def test_vis_selection_bad(text):
    with pytest.raises(VisSelectionError) as info:
        parse_vis_selection(text)
    assert "\n" not in str(info.value)
