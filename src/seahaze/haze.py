"""The haze's optics in numpy: extinction per channel, the phase function, the size of the
rendered haze volume and the atmospheric scattering model.

Where the haze is — its shape and the optical depth along a ray — is the medium's
(:mod:`seahaze.medium`); ``sigma`` from a visibility lives in :mod:`seahaze.visibility`. The
drjit copies of the phase function the ``physical`` kernels trace
(:mod:`seahaze.render.jit_haze`) are tested against these.

Henyey–Greenstein phase function
    ``p(cos θ) = (1 − g²) / (4π (1 + g² − 2 g cos θ)^{3/2})`` per steradian, normalised over the
    sphere; ``θ`` is the angle between the incident and the scattered travel directions, so
    ``g > 0`` scatters forward (Henyey & Greenstein 1941, ApJ 93, 70). Sampling inverts its CDF
    (e.g. Pharr, Jakob & Humphreys, *PBRT* 4th ed., §11.3.1).

The rendered haze volume
    Mitsuba needs a finite medium: a box ``[−W, W]²`` around the camera. Light entering through
    its sides would make far pixels too bright, so ``σ W ≥ 8`` (sides attenuated by ``e⁻⁸``) in
    the channel of least extinction of the thinnest level; a scene that looks at objects out to
    ``reach`` needs ``W = reach + 8/σ`` so the light field around them is that of an unbounded
    layer too.

The atmospheric scattering model (``asm`` mode)
    ``I = J t + A (1 − t)`` with ``t = exp(−τ)`` per channel, ``J`` the clean radiance, ``τ``
    the optical depth of the camera ray up to its surface and ``A`` the horizon airlight
    (Koschmieder 1924; Narasimhan & Nayar 2002, IJCV 48, 233). It ignores the sunlit shading
    that real haze removes along the ray (its bias against ``volpath``: docs/benchmarks.md).
"""

from __future__ import annotations

import numpy as np

FOUR_PI = 4.0 * np.pi
BOX_OPTICAL_HALF_WIDTH = 8.0
"""Least optical depth ``σ W`` from the camera (or the farthest object) to the haze box side."""

Extinction = float | np.ndarray
"""A level's extinction in 1/m: one grey value or (R, G, B) (``haze.extinction_spectrum``)."""


def extinction_rgb(sigma_t: Extinction) -> np.ndarray:
    """Per-channel extinction (3,) in 1/m from one grey value or an (R, G, B) triple."""
    rgb = np.broadcast_to(np.asarray(sigma_t, dtype=float), (3,)).copy()
    if not np.all(np.isfinite(rgb)) or np.any(rgb < 0.0):
        raise ValueError(f"extinction must be finite and non-negative, got {rgb}")
    return rgb


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


def haze_box_half_width(sigma_min: float, reach_m: float = 0.0) -> float:
    """Half-width (m) of the rendered haze box: ``reach + 8/σ`` for the least extinction ``σ``
    (1/m) of the run and objects out to ``reach_m`` (see the module docstring)."""
    return reach_m + BOX_OPTICAL_HALF_WIDTH / float(sigma_min)


def optical_depth(sigma: Extinction, reduced_length_m: np.ndarray) -> np.ndarray:
    """Per-pixel optical depth ``τ_c = σ_c ℓ`` (H, W, 3) of a level of extinction ``sigma``
    (1/m, grey or R, G, B) over the reduced lengths ``ℓ`` (H, W; m) of the pixels' rays in the
    medium (:meth:`seahaze.medium.HazeMedium.path_length`)."""
    return extinction_rgb(sigma)[None, None, :] * reduced_length_m[..., None]


def asm_composite(clean: np.ndarray, tau: np.ndarray, airlight_rgb: np.ndarray) -> np.ndarray:
    """The atmospheric scattering model ``I = J t + A (1 − t)``, ``t = exp(−τ_c)`` per channel,
    for clean radiance ``J`` (H, W, 3), optical depths ``τ`` (H, W, 3, :func:`optical_depth`)
    and airlight ``A`` (3,)."""
    t = np.exp(-tau)
    return (clean * t + airlight_rgb[None, None, :] * (1.0 - t)).astype(np.float32)
