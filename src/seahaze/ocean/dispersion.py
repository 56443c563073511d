"""Deep-water dispersion of surface gravity waves: ``omega² = g·k`` (linear, Airy).

Units: angular frequency ``omega`` in rad/s, wavenumber ``k`` in rad/m, ``g`` in m/s².
"""

from __future__ import annotations

import numpy as np

GRAVITY = 9.81
"""Gravitational acceleration g (m/s²)."""

ArrayLike = float | np.ndarray


def deep_water_omega(k: ArrayLike, gravity: float = GRAVITY) -> np.ndarray:
    """Angular frequency ``omega = sqrt(g·k)`` (rad/s) of a deep-water gravity wave of wavenumber
    ``k`` (rad/m); linear (Airy) dispersion ``omega² = g·k`` (e.g. Tessendorf 2001, eq. 14)."""
    return np.sqrt(gravity * np.abs(np.asarray(k, dtype=float)))


def deep_water_wavenumber(omega: ArrayLike, gravity: float = GRAVITY) -> np.ndarray:
    """Wavenumber ``k = omega²/g`` (rad/m) of a deep-water wave of angular frequency ``omega``
    (rad/s); the inverse of :func:`deep_water_omega`."""
    omega = np.asarray(omega, dtype=float)
    return omega * omega / gravity


def deep_water_group_velocity(omega: ArrayLike, gravity: float = GRAVITY) -> np.ndarray:
    """Group velocity ``d omega/dk = g/(2·omega)`` (m/s) of deep-water waves; also the Jacobian
    that converts a frequency spectrum into a wavenumber spectrum,
    ``F(k) = S(omega)·d omega/dk``."""
    return gravity / (2.0 * np.asarray(omega, dtype=float))
