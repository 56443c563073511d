"""The overcast sky: the CIE overcast luminance distribution, lit as much as cloud lets through.

Most haze and fog days at sea are overcast: the sun is hidden, and the light comes from the
whole cloud deck, brightest overhead and falling toward the horizon.

Luminance distribution (Moon & Spencer 1942; CIE standard overcast sky)
    The radiance of an overcast sky depends on the zenith angle ``θ`` alone:

        L(θ) = L_z · (1 + 2 cos θ) / 3

    — a third of the zenith's at the horizon, the same in every azimuth (Moon, P. & Spencer,
    D. E. (1942). Illumination from a non-uniform sky. *Illuminating Engineering* 37,
    707–726; adopted by the CIE in 1955 as its standard overcast sky, and kept as sky type 16,
    "traditional overcast sky", of ISO 15469:2004 / CIE S 011/E:2003). Integrated over the
    upper hemisphere it gives the horizontal irradiance

        E_h = ∫ L cos θ dω = 2π L_z ∫₀¹ μ (1 + 2μ)/3 dμ = (7π/9) · L_z.

How bright (Kasten & Czeplak 1980)
    Cloud of ``N`` eighths (oktas) passes a fraction of the clear sky's global horizontal
    irradiance ``G_clear`` (sun and sky together, the same sun elevation):

        G(N) / G_clear = 1 − 0.75 · (N/8)^3.4

    — a quarter under a full deck (N = 8), from ten years of hourly data at Hamburg (Kasten, F.
    & Czeplak, G. (1980). Solar and terrestrial radiation dependent on the amount and type of
    cloud. *Solar Energy* 24(2), 177–189). The overcast sky's ``L_z`` is set so that its
    ``E_h`` equals ``G(8)``: ``L_z = 9·G(8) / (7π)``.

Colour
    Cloud droplets (radii ≈ 5–20 µm) scatter all visible wavelengths alike, so the light under
    a full deck is close to the CIE's daylight illuminant D65 (correlated colour temperature
    of overcast skies measured at about 6000–7000 K; Hernández-Andrés, J., Romero, J., Nieves,
    J. L. & Lee, R. L. (2001). Color and spectral analysis of daylight in southern Europe.
    *J. Opt. Soc. Am. A* 18(6), 1325–1335). D65 is the white of linear sRGB, the renderer's
    colour space, so the sky is grey: equal R, G and B, at the luminance of ``G(8)``.

Radiance is in the renderer's units (those of Mitsuba's ``sunsky``, whose ``G_clear`` the
caller measures); angles in radians; below the horizon the sky is black, as ``sunsky``'s is.
"""

from __future__ import annotations

import math

import numpy as np

FULL_DECK_OKTAS = 8
"""Cloud amount of an overcast sky, in eighths of the sky covered (oktas)."""

HORIZONTAL_IRRADIANCE_PER_ZENITH_RADIANCE = 7.0 * math.pi / 9.0
"""``E_h / L_z`` of the CIE overcast sky (sr): the gradation integrated with ``cos θ``."""

REC709_LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
"""Luminance weights of linear sRGB (ITU-R BT.709), the renderer's colour space."""


def gradation(cos_zenith: np.ndarray | float) -> np.ndarray:
    """``L(θ) / L_z`` of the CIE overcast sky for ``cos θ`` (1 at the zenith, 1/3 at the
    horizon); 0 below the horizon (``cos θ < 0``)."""
    mu = np.asarray(cos_zenith, np.float64)
    return np.where(mu >= 0.0, (1.0 + 2.0 * mu) / 3.0, 0.0)


def cloud_transmission(oktas: float) -> float:
    """``G(N) / G_clear``: the share of the clear sky's global horizontal irradiance that
    ``oktas`` eighths of cloud let through (Kasten & Czeplak 1980; 0 ≤ oktas ≤ 8)."""
    if not 0.0 <= oktas <= FULL_DECK_OKTAS:
        raise ValueError(f"cloud amount {oktas} oktas is outside 0..{FULL_DECK_OKTAS}")
    return 1.0 - 0.75 * (oktas / FULL_DECK_OKTAS) ** 3.4


def zenith_radiance(clear_global_rgb: np.ndarray) -> float:
    """``L_z`` of the grey overcast sky (the renderer's radiance units) under which a level
    surface receives the luminance of :func:`cloud_transmission` of a full deck times the clear
    sky's global horizontal irradiance ``clear_global_rgb`` (linear sRGB, sun and sky)."""
    clear_luminance = float(REC709_LUMINANCE @ np.asarray(clear_global_rgb, np.float64))
    overcast = cloud_transmission(FULL_DECK_OKTAS) * clear_luminance
    return overcast / HORIZONTAL_IRRADIANCE_PER_ZENITH_RADIANCE


def latlong_radiance(zenith_rgb: float, rows: int = 512, columns: int = 4) -> np.ndarray:
    """The overcast sky as a latitude–longitude image (rows × columns × 3, float32, grey) of
    radiance ``zenith_rgb · gradation``: row ``i`` at zenith angle ``θ = π i / (rows − 1)``
    (the top row at the zenith, the bottom at the nadir), every column alike (no azimuth
    dependence). This is where Mitsuba's ``envmap`` reads its rows
    (:func:`seahaze.clouds.latlong_directions`)."""
    theta = math.pi * np.arange(rows) / (rows - 1)
    column = zenith_rgb * gradation(np.cos(theta))
    image = np.repeat(column[:, None], columns, axis=1)
    return np.repeat(image[..., None], 3, axis=2).astype(np.float32)
