"""Whitecaps: how much of the sea is foam at a given wind, where the foam sits, how bright it is.

Coverage (Monahan & O'Muircheartaigh 1980)
    The fraction of the sea surface covered by whitecaps grows as a power of the wind speed
    ``U10`` (m/s at 10 m):

        W = 3.84e-6 · U10^3.41          (fraction, 0–1)

    — about 1 % at 10 m/s and 4 % at 15 m/s (Monahan, E. C. & O'Muircheartaigh, I. G. (1980).
    Optimal power-law description of oceanic whitecap coverage dependence on wind speed.
    *J. Phys. Oceanogr.* 10(12), 2094–2099). It is a fit to open-ocean photographic data;
    whitecaps appear from about 3 m/s (Beaufort 3, "scattered white horses"), and the data
    behind it reach about 20 m/s. Individual observations scatter by an order of magnitude
    around it (water temperature, fetch, wind history, surfactants; Anguelova & Webster 2006,
    *J. Geophys. Res.* 111, C03017), so the law is a climatological mean. Outside
    :data:`WHITECAP_LAW_RANGE_M_S` the value is an extrapolation; it is clipped to 1.

Reflectance (Koepke 1984)
    Fresh, dense foam reflects about 55 % of visible light, nearly independently of wavelength
    (Whitlock, Bartlett & Gurganus 1982, *Geophys. Res. Lett.* 9(6), 719–722). A whitecap
    thins and fades within seconds, so averaged over its lifetime and area it reflects much
    less: Koepke's *effective* reflectance is ``R_eff = 0.22 ± 0.11`` in the visible (Koepke, P.
    (1984). Effective reflectance of oceanic whitecaps. *Appl. Opt.* 23(11), 1816–1824). The
    coverage ``W`` counts young and decaying whitecaps together, so the mean reflectance of the
    foam-covered area must be the effective value (:data:`FOAM_REFLECTANCE`).

    Inside that area the reflectance is not uniform: the actively breaking front is fresh foam
    (:data:`FRESH_FOAM_REFLECTANCE`), the foam left behind thins as it ages. The foam field has
    no age, so :meth:`FoamField.foam_and_reflectance` takes the breaking rank as a proxy: the
    most compressed crest is the youngest foam, and the reflectance falls exponentially with the
    Jacobian's quantile, ``R(q) = 0.55·exp(-k·q/W)``, with ``k`` (:data:`FOAM_AGE_DECAY`, 2.18)
    set so that the foam-weighted mean over a whitecap is exactly ``R_eff = 0.22`` — Koepke's
    own model of the effective reflectance, a fresh reflectance decaying exponentially over a
    whitecap's life, with the quantile standing in for the age. The result: bright white cores
    (reflectance above 0.4 on 15 % of the covered area: the actively breaking part is a small
    share of all whitecaps) fading into grey skirts, while the sea's mean albedo gain stays
    ``W·R_eff``.

Placement (Tessendorf 2001)
    A crest breaks where the choppy horizontal map ``x0 -> x0 + lambda·D(x0)`` compresses the
    surface: its Jacobian ``J`` falls toward 0 (and below 0 the surface folds; Tessendorf 2001,
    §4.3, marks such points as foam). :class:`FoamField` puts foam where ``J`` is smallest, with
    the threshold set so that the covered **world** area fraction equals ``W``: over a periodic
    patch (FFT) or a square of 8 peak wavelengths (Gerstner) the world-area-weighted
    distribution of ``J`` is tabulated (weight ``J`` itself: a rest area ``dA0`` covers
    ``J·dA0`` of the world), and the foam fraction is a smoothstep in that distribution's
    quantile ``q(J)``: 1 for ``q < W - h``, 0 for ``q > W + h``, ``h = W/2``. Whatever the
    shape of the distribution the mean foam fraction of the world area is then exactly ``W``;
    the edges are soft because ``J`` varies smoothly in space. For the FFT ocean only the
    largest patch (wavelengths from 8 down to 1/8 of the peak wavelength) sets ``J``, so foam
    marks breaking of the dominant waves and is not speckle at the scale of the short patches.
    With zero choppiness the foam is placed with the Jacobian the surface would have at
    ``lambda = 1`` (the same crests).

Far field
    Beyond the mesh's fade radius breaking cannot be resolved; there the expected foam fraction
    is the coverage itself, :attr:`FoamField.mean_fraction` (``W``), and the mean reflectance of
    the sea gains ``W·R_eff``.

Limits: no foam memory (a patch of foam does not drift or decay after the crest has passed),
no spray or streaks, coverage from the wind alone (not from the generated wave steepness).
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from .base import OceanSurface
from .fft import FFTOcean, sample_periodic_bilinear
from .gerstner import GerstnerOcean

MONAHAN_COEFFICIENT = 3.84e-6
"""Coefficient of the whitecap coverage law ``W = a·U10^b`` (fraction; U10 in m/s)."""

MONAHAN_EXPONENT = 3.41
"""Exponent of the whitecap coverage law (Monahan & O'Muircheartaigh 1980)."""

WHITECAP_LAW_RANGE_M_S = (3.0, 20.0)
"""Approximate range of U10 (m/s) over which whitecaps are observed and the law was fitted."""

FOAM_REFLECTANCE = 0.22
"""Effective visible reflectance of whitecaps (Koepke 1984; ± 0.11), to be used with the total
coverage ``W``."""

FRESH_FOAM_REFLECTANCE = 0.55
"""Visible reflectance of fresh, dense foam (Whitlock et al. 1982, as used by Koepke 1984)."""

EFFECTIVE_FRACTION = FOAM_REFLECTANCE / FRESH_FOAM_REFLECTANCE
"""Koepke's ratio of the effective to the fresh reflectance (0.4)."""

EDGE_SOFTNESS = 0.5
"""Half-width of the foam edge ramp in quantile space, as a fraction of ``W``."""


def _foam_profile(u: np.ndarray) -> np.ndarray:
    """Foam fraction as a function of ``u = q/W`` (the quantile in units of the coverage): 1 up
    to ``1 - EDGE_SOFTNESS``, a smoothstep down to 0 at ``1 + EDGE_SOFTNESS``."""
    t = np.clip((u - (1.0 - EDGE_SOFTNESS)) / (2.0 * EDGE_SOFTNESS), 0.0, 1.0)
    return 1.0 - t * t * (3.0 - 2.0 * t)


def _age_decay_constant() -> float:
    """``k`` with ``∫f(u)·exp(-k·u) du / ∫f(u) du = EFFECTIVE_FRACTION`` (``f`` the foam
    profile): the foam-weighted mean reflectance of a whitecap is then ``R_eff``."""
    from scipy.optimize import brentq

    nodes, weights = np.polynomial.legendre.leggauss(64)
    end = 1.0 + EDGE_SOFTNESS
    u = 0.5 * end * (nodes + 1.0)
    w = 0.5 * end * weights * _foam_profile(u)

    def excess(k: float) -> float:
        return float(np.sum(w * np.exp(-k * u)) / np.sum(w)) - EFFECTIVE_FRACTION

    return float(brentq(excess, 1e-6, 50.0, xtol=1e-12))


FOAM_AGE_DECAY = _age_decay_constant()
"""``k`` of the foam reflectance ``R(q) = R_fresh·exp(-k·q/W)`` (2.18; module docstring)."""

GERSTNER_SAMPLE_PEAK_WAVELENGTHS = 8.0
"""Side of the square (in peak wavelengths) over which a Gerstner surface's Jacobian
distribution is tabulated."""

SAMPLE_RESOLUTION = 256
"""Samples per side of the Gerstner tabulation grid."""


def whitecap_coverage(u10: ArrayLike) -> np.ndarray | float:
    """Fraction of the sea surface covered by whitecaps, ``W = 3.84e-6·U10^3.41`` (0–1).

    ``u10``: wind speed (m/s) 10 m above the sea (scalar or array). Monahan &
    O'Muircheartaigh (1980); 0.0099 at 10 m/s, 0.039 at 15 m/s. Negative winds give 0; the value
    is clipped to 1 (reached near 39 m/s, far outside :data:`WHITECAP_LAW_RANGE_M_S`).
    """
    u = np.maximum(np.asarray(u10, dtype=float), 0.0)
    w = np.minimum(MONAHAN_COEFFICIENT * u**MONAHAN_EXPONENT, 1.0)
    return float(w) if w.ndim == 0 else w


def whitecap_albedo(u10: ArrayLike) -> np.ndarray | float:
    """Mean visible reflectance added by whitecaps to a sea of wind ``u10`` (m/s at 10 m):
    ``W(U10)·R_eff`` (Koepke 1984), e.g. 0.0022 at 10 m/s."""
    return whitecap_coverage(u10) * FOAM_REFLECTANCE


class _BreakingIndicator(Protocol):
    def __call__(self, x: np.ndarray, y: np.ndarray) -> np.ndarray: ...


class FoamField:
    """Foam fraction in [0, 1] at rest positions of a surface (see the module docstring).

    Args:
        surface: the ocean surface (its ``time_s`` and choppiness are used).
        wind_speed: U10 (m/s) that sets the coverage :func:`whitecap_coverage`.
        coverage: override the coverage fraction (0–1), e.g. for tests or a measured value.

    Deterministic: everything derives from the surface (no random numbers).
    """

    def __init__(
        self, surface: OceanSurface, wind_speed: float, coverage: float | None = None
    ) -> None:
        self.wind_speed = float(wind_speed)
        w = whitecap_coverage(self.wind_speed) if coverage is None else float(coverage)
        if not 0.0 <= w <= 1.0:
            raise ValueError("coverage must be in [0, 1]")
        self.coverage = float(w)
        self._indicator = _breaking_indicator(surface)
        if self._indicator is None or self.coverage == 0.0:
            self._indicator = None
            self._j_sorted = np.zeros(1)
            self._q_sorted = np.zeros(1)
            return
        assert isinstance(surface, FFTOcean | GerstnerOcean)
        j_sample, world_weight = _tabulation_sample(surface, self._indicator)
        order = np.argsort(j_sample, kind="stable")
        self._j_sorted = j_sample[order]
        weights = np.maximum(world_weight[order], 0.0)
        cumulative = np.cumsum(weights)
        # Quantile at the middle of each sample's weight (a continuous, increasing map).
        self._q_sorted = (cumulative - 0.5 * weights) / cumulative[-1]
        half_width = EDGE_SOFTNESS * min(self.coverage, 1.0 - self.coverage)
        self._q_lo = self.coverage - half_width
        self._q_hi = self.coverage + half_width

    @property
    def mean_fraction(self) -> float:
        """Expected foam fraction of a large area (the coverage ``W``): what a renderer should
        use where the mesh cannot resolve breaking (beyond the fade radius)."""
        return self.coverage

    @property
    def jacobian_threshold(self) -> float:
        """Jacobian value below which more than half of a point is foam (``q(J) = W``)."""
        if self._indicator is None:
            return -math.inf
        return float(np.interp(self.coverage, self._q_sorted, self._j_sorted))

    def breaking_jacobian(self, x0: np.ndarray, y0: np.ndarray) -> np.ndarray:
        """The Jacobian that places foam, at rest positions (m)."""
        if self._indicator is None:
            return np.ones(np.broadcast(np.asarray(x0), np.asarray(y0)).shape)
        return self._indicator(np.asarray(x0, dtype=float), np.asarray(y0, dtype=float))

    def __call__(self, x0: np.ndarray, y0: np.ndarray) -> np.ndarray:
        """Foam fraction (0–1) at rest positions ``(x0, y0)`` (m), any equal shapes."""
        return self.foam_and_reflectance(x0, y0)[0]

    def foam_and_reflectance(self, x0: np.ndarray, y0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Foam fraction (0–1) and the visible reflectance of that foam at rest positions (m).

        The reflectance is ``R_fresh·exp(-k·q/W)`` (module docstring): 0.55 on the most
        compressed crests, fading toward the whitecap's edge; its foam-weighted mean over the
        sea is :data:`FOAM_REFLECTANCE`. Where there is no foam it is still defined (the value
        the foam would have there).
        """
        shape = np.broadcast(np.asarray(x0), np.asarray(y0)).shape
        if self._indicator is None:
            return np.zeros(shape), np.full(shape, FOAM_REFLECTANCE)
        q = np.interp(self.breaking_jacobian(x0, y0), self._j_sorted, self._q_sorted)
        reflectance = FRESH_FOAM_REFLECTANCE * np.exp(-FOAM_AGE_DECAY * q / self.coverage)
        if self._q_hi <= self._q_lo:
            fraction = (q <= self.coverage).astype(float)
        else:
            t = np.clip((q - self._q_lo) / (self._q_hi - self._q_lo), 0.0, 1.0)
            fraction = 1.0 - t * t * (3.0 - 2.0 * t)
        return fraction.reshape(shape), reflectance.reshape(shape)


def foam_fraction(
    surface: OceanSurface, x0: np.ndarray, y0: np.ndarray, wind_speed: float
) -> np.ndarray:
    """Foam fraction (0–1) at rest positions (m) of ``surface`` for wind ``wind_speed`` (m/s at
    10 m); builds a :class:`FoamField` (reuse one for many calls)."""
    return FoamField(surface, wind_speed)(x0, y0)


def _breaking_indicator(surface: OceanSurface) -> _BreakingIndicator | None:
    """A function ``(x0, y0) -> J`` whose low values mark breaking crests; ``None`` if the
    surface cannot break (flat)."""
    if isinstance(surface, FFTOcean):
        lam = surface.choppiness if surface.choppiness > 0.0 else 1.0
        patch = surface.cascades[0]
        jac = surface.patch_jacobian(0, lam)

        def fft_indicator(x: np.ndarray, y: np.ndarray) -> np.ndarray:
            return sample_periodic_bilinear(jac[None], patch.size_m, x, y)[0]

        return fft_indicator
    if isinstance(surface, GerstnerOcean):
        probe = surface
        if surface.choppiness <= 0.0:
            probe = GerstnerOcean(
                surface.omega,
                surface.direction,
                surface.amplitude,
                surface.phase,
                1.0,
                surface.time_s,
                surface.peak_wavelength_m,
                surface.gravity,
                warn=False,
            )
        return probe.jacobian
    return None


def _tabulation_sample(
    surface: FFTOcean | GerstnerOcean, indicator: _BreakingIndicator
) -> tuple[np.ndarray, np.ndarray]:
    """Breaking Jacobian and world-area weight (the surface's own Jacobian) at a deterministic
    set of rest positions covering the surface's statistics."""
    if isinstance(surface, FFTOcean):
        # Nodes and the midpoints between them: the indicator is bilinear between nodes,
        # which lifts its minima, so the nodes alone would over-represent low values.
        patch = surface.cascades[0]
        nodes = np.arange(2 * patch.resolution) * (0.5 * patch.spacing_m)
    else:
        side = GERSTNER_SAMPLE_PEAK_WAVELENGTHS * surface.peak_wavelength_m
        nodes = (np.arange(SAMPLE_RESOLUTION) + 0.5) * (side / SAMPLE_RESOLUTION)
    x, y = (a.ravel() for a in np.meshgrid(nodes, nodes))
    if surface.choppiness <= 0.0:
        return indicator(x, y), np.ones_like(x)
    if isinstance(surface, GerstnerOcean):  # the indicator is the surface's own Jacobian
        jac = surface.jacobian(x, y)
        return jac, jac
    return indicator(x, y), surface.jacobian(x, y)
