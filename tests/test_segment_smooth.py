"""Smoothing within segments (src/seahaze/render/segment_smooth.py): a normalised box filter
that keeps each segment's own values, leaves linear ramps alone and divides white noise's
standard deviation by the window's side."""

from __future__ import annotations

import numpy as np
import pytest

from seahaze.render.segment_smooth import (
    SEA_SEGMENT,
    SKY_SEGMENT,
    segments,
    smooth_within_segments,
)


def test_segments_are_the_vessels_the_sea_and_the_sky() -> None:
    instance = np.array([[-1, -1, 0], [2, -1, -1]])
    distance = np.array([[np.inf, 50.0, 80.0], [120.0, 3000.0, np.inf]])
    np.testing.assert_array_equal(
        segments(instance, distance),
        [[SKY_SEGMENT, SEA_SEGMENT, 0], [2, SEA_SEGMENT, SKY_SEGMENT]],
    )


def test_a_segment_never_takes_another_segments_values() -> None:
    # Three segments of different constant values, with ragged borders: every pixel keeps
    # its own segment's value exactly, however close to the border.
    rng = np.random.default_rng(0)
    labels = rng.integers(-2, 1, size=(40, 60)).astype(np.int32)
    value = {-2: 0.3, -1: -1.5, 0: 7.0}
    image = np.stack([np.vectorize(value.get)(labels)] * 3, axis=-1).astype(np.float32)
    out = smooth_within_segments(image, labels, 3)
    np.testing.assert_allclose(out, image, rtol=1e-6)


def test_a_linear_ramp_is_unchanged_away_from_the_edges() -> None:
    # The mean of a symmetric window of a linear function is its value at the centre.
    rows, cols = np.mgrid[0:50, 0:70].astype(np.float32)
    image = np.stack([2.0 * rows - 0.5 * cols, cols, np.ones_like(rows)], axis=-1)
    labels = np.full((50, 70), SEA_SEGMENT, np.int32)
    labels[:, 40:] = SKY_SEGMENT
    radius = 4
    out = smooth_within_segments(image, labels, radius)
    interior = (slice(radius, 50 - radius), slice(radius, 40 - radius))
    np.testing.assert_allclose(out[interior], image[interior], atol=1e-3)


def test_white_noise_falls_by_the_windows_side() -> None:
    # Independent pixels: the mean of (2r + 1)² of them has 1 / (2r + 1) of their deviation.
    rng = np.random.default_rng(1)
    image = rng.normal(size=(400, 400, 1)).astype(np.float32)
    labels = np.zeros((400, 400), np.int32)
    for radius in (1, 2, 4):
        out = smooth_within_segments(image, labels, radius)
        inner = out[radius:-radius, radius:-radius]
        assert inner.std() == pytest.approx(image.std() / (2 * radius + 1), rel=0.03)


def test_radius_zero_is_a_copy_and_sizes_must_agree() -> None:
    image = np.arange(24, dtype=np.float32).reshape(2, 4, 3)
    labels = np.zeros((2, 4), np.int32)
    out = smooth_within_segments(image, labels, 0)
    np.testing.assert_array_equal(out, image)
    assert out is not image
    with pytest.raises(ValueError, match="differ in size"):
        smooth_within_segments(image, np.zeros((4, 2), np.int32), 1)
