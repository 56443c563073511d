"""Factory for ocean surfaces: ``make_surface(params) -> OceanSurface``."""

from __future__ import annotations

from .base import FlatSurface, OceanParams, OceanSurface
from .fft import FFTOcean
from .gerstner import GerstnerOcean


def make_surface(params: OceanParams) -> OceanSurface:
    """Build the surface that ``params`` describe.

    ``model="flat"`` — or a wind below :data:`seahaze.ocean.base.MIN_WIND_SPEED`
    (Beaufort 0) — gives a :class:`FlatSurface`; ``"gerstner"`` a :class:`GerstnerOcean`;
    ``"fft"`` an :class:`FFTOcean`. The result is a deterministic function of ``params``
    (random draws come only from ``numpy.random.default_rng(params.seed)`` and do not depend on
    ``params.time_s``), so a sequence with increasing ``time_s`` animates consistently.
    """
    if params.is_calm:
        return FlatSurface()
    if params.model == "gerstner":
        return GerstnerOcean.from_params(params)
    return FFTOcean.from_params(params)
