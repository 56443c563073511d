"""Smoothing an image term within the surfaces it lies on: a box filter that never crosses
from one segment (the sky, the sea, one vessel) to another.

Why
    The vessel-light pass (:mod:`seahaze.render.vessel_light`) estimates a term that is
    smooth over the image within one surface — the glow of haze lit by a hull spreads over
    tens of pixels — but its Monte Carlo estimate is sparse: most probes miss every vessel,
    and the few that meet a sunlit white hull leave single bright pixels at 100 % zoom. A
    box filter of ``(2r + 1)²`` pixels divides that noise's variance by up to ``(2r + 1)²``
    and blurs the term by ``r`` pixels; kept within one segment it never carries the glow of
    the sky onto a hull or of a hull onto the sea behind it, where the term jumps. It is a
    normalised convolution (Knutsson & Westin 1993): the filtered value is the mean over the
    window's pixels of the same segment, so the filter neither gains nor loses the term near
    a segment's edge.

Units: the image's own; radius in pixels.
"""

from __future__ import annotations

import numpy as np

SKY_SEGMENT = -2
"""Segment label of pixels whose centre ray meets no surface."""
SEA_SEGMENT = -1
"""Segment label of pixels whose centre ray meets the sea (vessels are 0, 1, …)."""


def segments(instance: np.ndarray, distance_m: np.ndarray) -> np.ndarray:
    """Per-pixel segment labels (H, W) int32 from the geometry pass: the vessel index where
    ``instance`` ≥ 0, else :data:`SEA_SEGMENT` where the distance is finite, else
    :data:`SKY_SEGMENT`."""
    labels = np.where(np.isfinite(distance_m), SEA_SEGMENT, SKY_SEGMENT)
    return np.where(instance >= 0, instance, labels).astype(np.int32)


def smooth_within_segments(image: np.ndarray, labels: np.ndarray, radius: int) -> np.ndarray:
    """``image`` (H, W, C) with every pixel replaced by the mean of the pixels of its own
    segment (``labels``, (H, W)) in the ``(2 radius + 1)²`` window around it; ``radius`` 0
    returns a copy."""
    from scipy.ndimage import uniform_filter

    if image.shape[:2] != labels.shape:
        raise ValueError(f"image {image.shape[:2]} and labels {labels.shape} differ in size")
    out = np.array(image, dtype=np.float32, copy=True)
    if radius <= 0:
        return out
    size = 2 * radius + 1
    height, width = labels.shape
    for label in np.unique(labels):
        mask = labels == label
        rows, cols = np.nonzero(np.any(mask, axis=1))[0], np.nonzero(np.any(mask, axis=0))[0]
        # The segment's bounding box, widened by the radius: the window never needs more.
        box = (
            slice(max(rows[0] - radius, 0), min(rows[-1] + radius + 1, height)),
            slice(max(cols[0] - radius, 0), min(cols[-1] + radius + 1, width)),
        )
        inside = mask[box]
        # In place where it can be: the sky's and the sea's boxes are most of the image.
        total = np.multiply(image[box], inside[..., None], dtype=np.float32)
        uniform_filter(total, size=(size, size, 1), mode="constant", output=total)
        count = uniform_filter(inside.astype(np.float32), size=size, mode="constant")
        np.divide(total, np.maximum(count, 1e-12)[..., None], out=total)
        np.copyto(out[box], total, where=inside[..., None])
    return out
