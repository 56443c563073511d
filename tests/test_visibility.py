"""Visibility physics against published numbers (Koschmieder; WMO MOR; MSVD paper Tables 1–2)."""

import math

import numpy as np
import pytest

from seahaze.visibility import (
    GRADED_LEVELS_M,
    REGULATION_CLASSES,
    VisSelectionError,
    extinction_coefficient,
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
