"""Which vessels an observer can see in a rendered image: contrast against the local background.

Local-background contrast (Weber contrast, dimensionless)
    ``C = (L_vessel − L_bg) / L_bg`` on relative luminance ``Y`` (linear Rec. 709 weights,
    :func:`seahaze.imaging.luminance`) of one rendered image, the one its PNG shows. It is
    luminance contrast in Weber's form, for a target on a uniform background (CIE S 017:2020,
    International Lighting Vocabulary, "luminance contrast"), and the quantity Koschmieder's
    law is about: an object is seen where ``|C|`` exceeds the observer's threshold ``eps`` —
    0.02 for Koschmieder's visibility, 0.05 for the WMO's meteorological optical range
    (:data:`seahaze.visibility.CONTRAST_THRESHOLD`; Koschmieder 1924; Middleton, *Vision
    through the Atmosphere*, 1952).

    The background is what lies behind the vessel's pixels, read from the pixels beside them.
    Near the horizon a vessel's superstructure stands against the sky and its hull against the
    sea, which can differ ten-fold in luminance (the sea reflects a few percent of the sky; in
    fog both tend to the airlight), and both change with elevation there: one mean over a ring
    around the box is a background no part of the vessel is seen against. What is behind a
    pixel is what lies beside it at the same elevation — sky above the horizon, sea below it,
    their mix on the horizon's own row — so matching elevations compares like with like, sky
    with sky and sea with sea, without deciding which is which. Hence:

    1. Ring: the pixels within :data:`RING_PX` of the vessel's box (the box included) whose
       first surface is no vessel, sky or sea.
    2. Background of a vessel pixel: the mean luminance of the ring pixels at the elevation
       nearest its own (and within half a pixel's angular height of that one): for a level
       camera, its own row beside the vessel.
    3. Parts: the vessel's pixels brighter than their background in ``reference`` — the clean
       image, the vessel's own pattern before haze — and those darker. A white superstructure
       and a dark hull are two targets: averaged together they cancel (a fishing boat 180 m
       away at V = 300 m read about −0.01 over all its pixels while its hull alone, the faint
       line one sees in the image, reads −0.02 to −0.03). Haze only scales and shifts that
       pattern, so the clean image splits it for every level. The split follows the clean
       image's noise too, but in a hazy level what it selects is the vessel's own light,
       scaled down by the transmittance: vessels hidden by fog read ``|C|`` of a few
       thousandths (the default scene at 4 and at 42 spp).
    4. Each part's ``C = (mean Y of its pixels − L_bg) / L_bg``, ``L_bg`` the mean of its
       pixels' backgrounds. The vessel's local contrast is that of the part with the larger
       ``|C|`` — an observer sees the vessel where any part of it stands out — among parts of
       at least :data:`MIN_PART_PX` pixels (a lone pixel is Monte Carlo noise as much as
       signal); if neither has that many, the larger part decides.

    It is measured on the rendered, noisy image. In a clear image, where the sea's noise is
    about 10 % per pixel at 4 samples per pixel, step 3 reads part of that noise as contrast,
    so a vessel matching its background in the clean image can pass 2 % there. Render labels
    near the threshold at the default 42 spp or more.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import imaging
from .labels import Box
from .visibility import CONTRAST_THRESHOLD, Threshold

RING_PX = 3
"""Width (px) of the window around a vessel's box whose non-vessel pixels are its background."""
MIN_PART_PX = 2
"""Fewest pixels of a part for its contrast to count (unless no part has that many)."""

BRIGHTER = "brighter"
DARKER = "darker"


@dataclass(frozen=True)
class LocalContrast:
    """One vessel's contrast against its local background in one image."""

    contrast: float | None
    """``(L_vessel − L_bg) / L_bg`` of its deciding part (dimensionless); None when the vessel
    has no pixel or no non-vessel pixel around it."""
    part: str | None = None
    """``brighter`` or ``darker``: the deciding part, the vessel's pixels brighter or darker
    than their background in the reference (clean) image."""
    sky_share: float | None = None
    """Share of sky pixels (0..1) in the deciding part's background: 0 all sea, 1 all sky."""

    def discernible(self, threshold: Threshold | str) -> bool:
        """Whether ``|contrast|`` exceeds the threshold's ``eps`` (0.02 or 0.05)."""
        eps = CONTRAST_THRESHOLD[Threshold(threshold)]
        return self.contrast is not None and abs(self.contrast) > eps


def pixel_pitch_deg(elevation_deg: np.ndarray) -> float:
    """One pixel's angular height (deg): the largest elevation step between vertically
    adjacent pixel centres (0 for a one-row image)."""
    if elevation_deg.shape[0] < 2:
        return 0.0
    return float(np.abs(np.diff(elevation_deg.astype(np.float64), axis=0)).max())


def local_contrasts(
    radiance: np.ndarray,
    instance: np.ndarray,
    distance_m: np.ndarray,
    elevation_deg: np.ndarray,
    n_vessels: int,
    reference: np.ndarray | None = None,
) -> list[LocalContrast]:
    """The local-background contrast of every vessel ``0..n_vessels-1`` in one image.

    ``radiance`` (H, W, 3) linear RGB; ``instance`` (H, W) vessel index of each pixel's first
    surface (-1 none); ``distance_m`` (H, W), ``inf`` for the sky; ``elevation_deg`` (H, W)
    of each pixel-centre ray; ``reference`` (H, W, 3) the clean radiance whose contrast signs
    split each vessel into brighter and darker parts (default ``radiance`` itself). See the
    module docstring for the definition.
    """
    y = imaging.luminance(radiance)
    y_ref = y if reference is None else imaging.luminance(reference)
    sky = np.isinf(distance_m).astype(np.float64)
    elevation = elevation_deg.astype(np.float64)
    pitch = pixel_pitch_deg(elevation)
    height, width = instance.shape
    out = []
    for vessel in range(n_vessels):
        rows, cols = np.nonzero(instance == vessel)
        if rows.size == 0:
            out.append(LocalContrast(None))
            continue
        # Everything below works in the window: the box grown by RING_PX, within the frame.
        window = (
            slice(max(0, rows.min() - RING_PX), min(height, rows.max() + 1 + RING_PX)),
            slice(max(0, cols.min() - RING_PX), min(width, cols.max() + 1 + RING_PX)),
        )
        mask = instance[window] == vessel
        ring = instance[window] < 0
        if not ring.any():
            out.append(LocalContrast(None))
            continue
        y_win, ref_win, deg = y[window], y_ref[window], elevation[window]
        at, ring_deg = deg[mask], deg[ring]
        bg = _behind(at, ring_deg, y_win[ring], pitch)
        bg_sky = _behind(at, ring_deg, sky[window][ring], pitch)
        brighter = ref_win[mask] > _behind(at, ring_deg, ref_win[ring], pitch)
        parts = []
        for name, chosen in ((BRIGHTER, brighter), (DARKER, ~brighter)):
            l_bg = float(bg[chosen].mean()) if chosen.any() else 0.0
            if l_bg > 0.0:
                contrast = (float(y_win[mask][chosen].mean()) - l_bg) / l_bg
                share = float(bg_sky[chosen].mean())
                parts.append((int(chosen.sum()), LocalContrast(contrast, name, share)))
        out.append(_strongest(parts))
    return out


def _behind(
    vessel_deg: np.ndarray, ring_deg: np.ndarray, ring_y: np.ndarray, pitch: float
) -> np.ndarray:
    """Per vessel pixel, the mean luminance of the ring pixels at the elevation nearest its own
    (those within half a pixel's height of that nearest elevation): a running sum over the
    ring sorted by elevation, so a vessel of 10⁵ pixels needs no pixel-by-ring table."""
    order = np.argsort(ring_deg, kind="stable")
    deg = ring_deg[order]
    running = np.concatenate([[0.0], np.cumsum(ring_y[order])])
    at = np.searchsorted(deg, vessel_deg)
    below = deg[np.clip(at - 1, 0, len(deg) - 1)]
    above = deg[np.clip(at, 0, len(deg) - 1)]
    nearest = np.minimum(np.abs(vessel_deg - below), np.abs(vessel_deg - above))
    # The slack keeps the nearest pixel itself inside after rounding (pitch 0: one row).
    reach = nearest + pitch / 2 + 1e-9
    lo = np.searchsorted(deg, vessel_deg - reach, side="left")
    hi = np.searchsorted(deg, vessel_deg + reach, side="right")
    return (running[hi] - running[lo]) / (hi - lo)


def _strongest(parts: list[tuple[int, LocalContrast]]) -> LocalContrast:
    """The part with the largest ``|C|`` among those of at least MIN_PART_PX pixels; the
    largest part when none has that many (the first listed on a tie)."""
    if not parts:
        return LocalContrast(None)
    big = [part for count, part in parts if count >= MIN_PART_PX]
    if not big:
        return max(parts, key=lambda item: item[0])[1]
    return max(big, key=lambda part: abs(part.contrast or 0.0))


def visible_boxes(
    boxes: list[Box], contrasts: list[LocalContrast], threshold: Threshold | str
) -> list[Box]:
    """The boxes of the vessels discernible in the image (``|C| > eps``), in the same order."""
    return [box for box in boxes if contrasts[box.vessel].discernible(threshold)]
