"""Scattering physics of the haze: phase function and slab geometry.

Every haze formula outside :mod:`seahaze.visibility` (which owns ``sigma`` from ``V``) lives here,
in numpy, so that the table builder, the integrator and the tests share one definition.

Henyey–Greenstein phase function
    ``p(cos θ) = (1 − g²) / (4π (1 + g² − 2 g cos θ)^{3/2})`` per steradian, normalised over the
    sphere; ``θ`` is the angle between the incident and the scattered travel directions, so
    ``g > 0`` scatters forward (Henyey & Greenstein 1941, ApJ 93, 70). Sampling inverts its CDF
    (e.g. Pharr, Jakob & Humphreys, *PBRT* 4th ed., §11.3.1).

Slab geometry
    The haze is a layer ``bottom ≤ z ≤ top`` (metres), horizontally unbounded. A straight ray
    ``o + s·d`` is inside it for ``s`` in one interval; transmittance over a length ``ℓ`` of it is
    ``exp(−σ ℓ)`` (Beer–Lambert).
"""

from __future__ import annotations

import numpy as np

FOUR_PI = 4.0 * np.pi


def hg_phase(cos_theta: np.ndarray | float, g: float) -> np.ndarray:
    """Henyey–Greenstein phase function (1/sr) at the cosine of the scattering angle."""
    cos_theta = np.asarray(cos_theta, dtype=np.float64)
    denom = 1.0 + g * g - 2.0 * g * cos_theta
    return (1.0 - g * g) / (FOUR_PI * denom * np.sqrt(denom))


def hg_sample_cos(u: np.ndarray, g: float) -> np.ndarray:
    """Cosines of scattering angles drawn from the HG phase function for uniforms ``u``."""
    u = np.asarray(u, dtype=np.float64)
    if abs(g) < 1e-3:
        return 1.0 - 2.0 * u
    sq = (1.0 - g * g) / (1.0 - g + 2.0 * g * u)
    return np.clip((1.0 + g * g - sq * sq) / (2.0 * g), -1.0, 1.0)


def rotate_directions(d: np.ndarray, cos_theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Unit vectors at angle ``acos(cos_theta)`` from the unit rows of ``d``, azimuth ``phi``."""
    sin_theta = np.sqrt(np.maximum(0.0, 1.0 - cos_theta * cos_theta))
    # An orthonormal frame around d (Duff et al. 2017, "Building an orthonormal basis, revisited").
    sign = np.where(d[:, 2] >= 0.0, 1.0, -1.0)
    a = -1.0 / (sign + d[:, 2])
    b = d[:, 0] * d[:, 1] * a
    t = np.stack([1.0 + sign * d[:, 0] ** 2 * a, sign * b, -sign * d[:, 0]], axis=1)
    s = np.stack([b, sign + d[:, 1] ** 2 * a, -d[:, 1]], axis=1)
    out = (
        (sin_theta * np.cos(phi))[:, None] * t
        + (sin_theta * np.sin(phi))[:, None] * s
        + cos_theta[:, None] * d
    )
    return out / np.linalg.norm(out, axis=1, keepdims=True)


def slab_interval(
    oz: np.ndarray | float, dz: np.ndarray | float, bottom: float, top: float
) -> tuple[np.ndarray, np.ndarray]:
    """Ray parameters ``[enter, leave]`` (m, ``enter ≥ 0``) of ``o + s·d`` inside the slab.

    ``leave < enter`` means the ray never enters; ``leave`` is ``inf`` for a horizontal ray in
    the slab. Only the z components matter because the slab is horizontally unbounded.
    """
    oz = np.asarray(oz, dtype=np.float64)
    dz = np.asarray(dz, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        s_bottom = (bottom - oz) / dz
        s_top = (top - oz) / dz
    flat = np.abs(dz) < 1e-12
    inside = (oz >= bottom) & (oz <= top)
    enter = np.where(flat, np.where(inside, 0.0, np.inf), np.minimum(s_bottom, s_top))
    leave = np.where(flat, np.where(inside, np.inf, -np.inf), np.maximum(s_bottom, s_top))
    return np.maximum(enter, 0.0), leave
