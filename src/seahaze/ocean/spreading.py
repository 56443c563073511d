"""Directional spreading functions ``D(theta; omega)`` of wind waves, normalised so that
``∫_{-pi}^{pi} D d theta = 1`` (1/rad); directions in radians, the direction waves travel toward.

References
    * Longuet-Higgins, M. S., Cartwright, D. E. & Smith, N. D. (1963). Observations of the
      directional spectrum of sea waves using the motions of a floating buoy.
    * Mitsuyasu, H. et al. (1975). Observations of the directional spectrum of ocean waves using
      a cloverleaf buoy. J. Phys. Oceanogr. 5, 750–760; Goda, Y. (2010). Random Seas and Design
      of Maritime Structures, 3rd ed., §2.3 (``s_max = 10`` for wind waves).
    * Tessendorf, J. (2001). Simulating Ocean Water. SIGGRAPH course notes (eq. 23).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import gammaln

SPREADING_S_MAX = 10.0
"""Default peak value of the cos-2s spreading exponent for wind waves (Goda 2010, §2.3)."""

ArrayLike = float | np.ndarray


def cos2s_normalisation(s: ArrayLike) -> np.ndarray:
    """Normalisation ``N(s) = Gamma(s+1) / (2·sqrt(pi)·Gamma(s+1/2))`` (1/rad) of the cos-2s
    spreading, so that ``∫_{-pi}^{pi} N(s)·cos^(2s)(theta/2) d theta = 1``."""
    s = np.asarray(s, dtype=float)
    return np.exp(gammaln(s + 1.0) - gammaln(s + 0.5)) / (2.0 * math.sqrt(math.pi))


def cos2s_spreading(theta: ArrayLike, mean_direction: float, s: ArrayLike) -> np.ndarray:
    """Cos-2s directional spreading ``D = N(s)·cos^(2s)((theta - theta_0)/2)`` (1/rad).

    Longuet-Higgins et al. (1963); unimodal, non-zero everywhere except exactly against the mean
    direction ``theta_0`` (``mean_direction``, radians, direction waves travel toward). Larger
    ``s`` means a narrower spread; the circular standard deviation is about ``sqrt(2/(s+1))`` rad.
    """
    half = 0.5 * (np.asarray(theta, dtype=float) - mean_direction)
    s = np.asarray(s, dtype=float)
    return cos2s_normalisation(s) * np.abs(np.cos(half)) ** (2.0 * s)


def mitsuyasu_spreading_exponent(
    omega: ArrayLike, omega_p: float, s_max: float = SPREADING_S_MAX
) -> np.ndarray:
    """Frequency-dependent cos-2s exponent ``s = s_max·(omega/omega_p)^5`` below the peak and
    ``s_max·(omega/omega_p)^(-2.5)`` above it (Mitsuyasu et al. 1975 as simplified by Goda 2010,
    §2.3; ``s_max = 10`` for wind waves). Waves are most collimated at the peak."""
    ratio = np.asarray(omega, dtype=float) / omega_p
    return np.where(ratio <= 1.0, s_max * ratio**5, s_max * ratio**-2.5)


def cos2_spreading(theta: ArrayLike, mean_direction: float) -> np.ndarray:
    """Cos² spreading ``D = (2/pi)·cos²(theta - theta_0)`` for ``|theta - theta_0| < pi/2``, else 0
    (1/rad). It is Tessendorf's (2001, eq. 23) ``|k̂·ŵ|²`` factor with the waves that travel
    against the wind removed and normalised to unit integral."""
    delta = np.angle(np.exp(1j * (np.asarray(theta, dtype=float) - mean_direction)))
    c = np.cos(delta)
    return np.where(c > 0.0, (2.0 / math.pi) * c * c, 0.0)
