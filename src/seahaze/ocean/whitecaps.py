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
    counted area must be the effective value (:data:`FOAM_REFLECTANCE`).

    ``W`` is *photographed* coverage: the area brighter than a threshold. Koepke's effective
    reflectance is his model of what that area reflects: fresh foam decaying exponentially
    over a whitecap's counted life, which ends when it no longer stands out, so that the mean is
    ``0.55·(1 - e^-k)/k = 0.22``: ``k = 2.23`` (:data:`FOAM_AGE_DECAY`), and the faintest
    counted whitecap reflects ``0.55·e^-k = 0.059`` (:data:`COUNTED_FOAM_REFLECTANCE`, about a
    tenth of fresh foam). The foam field has no age, so :meth:`FoamField.foam_and_reflectance`
    takes the breaking rank as a proxy: the most compressed crest is the youngest foam, and
    the reflectance falls exponentially with the Jacobian's quantile,
    ``R(q) = 0.55·exp(-k·q/W)``. Over the counted area ``q <= W`` the foam is whole (fraction 1),
    so that area is exactly ``W`` and reflects ``R_eff`` on average — bright white cores
    (reflectance above 0.4 on 14 % of it: the actively breaking part is a small share of all
    whitecaps) fading into grey skirts.

    Beyond it lies residual foam, thinning and fading below the threshold (photographs do not
    count it, but it is there: the area counted grows as the threshold falls, Callaghan & White
    2009): over ``W < q < W·(1 + w)``, ``w`` = :data:`RESIDUAL_FOAM_WIDTH` (0.5), the fraction
    falls from 1 to 0 (a smoothstep) while the reflectance continues its decay, so its foam
    albedo stays below ``0.059``. It adds ``w/2`` of ``W`` to the foam fraction and 5 % to the
    foam albedo (:attr:`FoamField.mean_fraction` = 1.25 ``W``, :attr:`FoamField.albedo` =
    ``W·(R_eff + 0.011)``). (An earlier profile spread ``W`` over a smoothstep from ``W/2`` to
    ``3W/2`` with ``k`` solved over the whole of it: its faint partial rims counted towards
    ``W`` although no photograph would count them.)

Placement (Tessendorf 2001)
    A crest breaks where the choppy horizontal map ``x0 -> x0 + lambda·D(x0)`` compresses the
    surface: its Jacobian ``J`` falls toward 0 (and below 0 the surface folds; Tessendorf 2001,
    §4.3, marks such points as foam). :class:`FoamField` puts foam where ``J`` is smallest, with the
    threshold set so that the covered **world** area fraction equals ``W``: over a periodic patch
    (FFT) or a square of 8 peak wavelengths (Gerstner) the world-area-weighted distribution of ``J``
    is tabulated (weight ``J`` itself: a rest area ``dA0`` covers ``J·dA0`` of the world), and the
    foam fraction is a function of that distribution's quantile ``q(J)``: 1 for ``q <= W``, the
    residual foam's ramp to 0 at ``q = 1.5·W``. Whatever the shape of the distribution the whole
    foam then covers exactly ``W`` of the world area; the edges are soft because ``J`` varies
    smoothly in space. For the FFT ocean only the largest patch (wavelengths from 8 down to 1/8 of
    the peak wavelength) decides where the foam is, so it marks breaking of the dominant waves and
    is not speckle at the scale of the short patches. The short patches shape it: their compression,
    at :data:`DETAIL_WEIGHT` (half) weight, is added to the indicator, ``J_0 + 0.5·Σ_i (J_i - 1)``,
    which breaks the smooth blobs of the coarse grid into the ragged, holed, lacy patches of real
    whitecaps (the short waves riding on a breaking crest break with it). A mesh can only carry a
    patch's detail where its vertex spacing resolves that patch's grid, so each detail level ``l``
    (patches 1..l added) has its own quantile table (in each the whole foam covers exactly ``W``)
    and the foam at a vertex of spacing ``Δ`` blends the levels by
    :func:`~seahaze.ocean.base.lowpass_weight` of four grid spacings of each patch: the full lace
    under the camera, the coarse blobs far away, the coverage ``W`` everywhere. With zero choppiness
    the foam is placed with the Jacobian the surface would have at ``lambda = 1`` (the same crests).

Far field
    Where the mesh does not resolve breaking (the sea outside the view) the expected foam
    fraction is :attr:`FoamField.mean_fraction` (``1.25·W``: the counted whitecaps and their
    residual foam) and its albedo :attr:`FoamField.albedo`, the field's own world-area means, so
    near and far sea agree; a plane model of the sea gives that fraction the reflectance
    :attr:`FoamField.mean_reflectance` (0.185).

Rendering
    A renderer draws the foam of fraction ``f`` and reflectance ``R`` as a share
    ``f·R/R_fresh`` of the surface covered by fresh foam, the water between
    (:func:`as_fresh_foam`), not as a Lambertian of reflectance ``R`` over all of ``f``. The
    area mean of the foam albedo is the same, but a fading whitecap is thinning, patchy foam on
    water whose surface still mirrors the sky: at grazing incidence the water reflects some
    30 % of a bright sky, more than the residual foam's 0.02–0.06, so a whole patch of dim
    Lambertian foam would be darker than the water it covers (dark rims around the whitecaps).

Limits: no foam memory (a patch of foam does not drift or decay after the crest has passed),
no spray in the air (the wind's streaks are :mod:`seahaze.ocean.streaks`, a gale's spindrift
:mod:`seahaze.ocean.spindrift`, both on the surface), coverage from the wind alone
(not from the generated wave steepness).
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from .base import OceanSurface, lowpass_weight
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

RESIDUAL_FOAM_WIDTH = 0.5
"""Width, as a fraction of ``W`` in quantile space, of the residual foam beyond the counted
whitecap area: over it the foam fraction falls from 1 to 0 (a smoothstep) while the reflectance
goes on decaying below the photographic threshold. A visual choice, not a measured one: it keeps
the field smooth (``J`` varies smoothly in space, a hard edge would jump by 1 within a
centimetre); the counted coverage does not depend on it (module docstring)."""


def _counted_life_decay() -> float:
    """``k`` with ``(1 - e^-k)/k = EFFECTIVE_FRACTION``: the mean of ``exp(-k·u)`` over the
    counted life ``0 <= u <= 1`` is Koepke's 0.4, so the counted area reflects ``R_eff``."""
    from scipy.optimize import brentq

    def excess(k: float) -> float:
        return -math.expm1(-k) / k - EFFECTIVE_FRACTION

    return float(brentq(excess, 1e-6, 50.0, xtol=1e-14))


FOAM_AGE_DECAY = _counted_life_decay()
"""``k`` of the foam reflectance ``R(q) = R_fresh·exp(-k·q/W)`` (2.23; module docstring)."""

COUNTED_FOAM_REFLECTANCE = FRESH_FOAM_REFLECTANCE * math.exp(-FOAM_AGE_DECAY)
"""Reflectance of the faintest counted whitecap, at the edge of the area ``W`` (0.059: fresh
foam decayed by ``e^-k``, about a factor 10, Koepke 1984)."""


def _residual_profile(t: np.ndarray) -> np.ndarray:
    """Foam fraction across the residual edge, ``t`` from 0 (the counted area's edge) to 1."""
    t = np.clip(t, 0.0, 1.0)
    return 1.0 - t * t * (3.0 - 2.0 * t)


def residual_foam_albedo(width: float) -> float:
    """``∫ f(u)·R_fresh·exp(-k·u) du`` over the residual edge ``1 <= u <= 1 + width`` (in units
    of ``W``): the foam albedo the residual foam adds per unit of coverage (Gauss-Legendre)."""
    if width <= 0.0:
        return 0.0
    nodes, weights = np.polynomial.legendre.leggauss(32)
    t = 0.5 * (nodes + 1.0)
    u = 1.0 + width * t
    integrand = _residual_profile(t) * np.exp(-FOAM_AGE_DECAY * u)
    return float(FRESH_FOAM_REFLECTANCE * 0.5 * width * np.sum(weights * integrand))


DETAIL_WEIGHT = 0.5
"""Weight of the shorter FFT patches' compression ``J_i - 1`` in the breaking indicator (a
visual choice: 0 gives smooth blobs on the dominant crests, 1 scatters the foam into
speckle of the short waves)."""

DETAIL_GRID_SPACINGS = 4.0
"""A detail patch is carried by mesh vertices spaced at most this many of its grid spacings
(``lowpass_weight`` of that wavelength: full at one grid spacing, none at two)."""

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


class _Level:
    """One detail level of a foam field: its breaking indicator, the world-area quantile table
    of that indicator, and the wavelength below which a mesh cannot carry its detail."""

    def __init__(
        self,
        indicator: _BreakingIndicator,
        sample_x: np.ndarray,
        sample_y: np.ndarray,
        world_weight: np.ndarray,
        detail_wavelength_m: float,
    ) -> None:
        self.indicator = indicator
        self.detail_wavelength_m = detail_wavelength_m
        j_sample = indicator(sample_x, sample_y)
        order = np.argsort(j_sample, kind="stable")
        self.j_sorted = j_sample[order]
        weights = np.maximum(world_weight[order], 0.0)
        cumulative = np.cumsum(weights)
        # Quantile at the middle of each sample's weight (a continuous, increasing map).
        self.q_sorted = (cumulative - 0.5 * weights) / cumulative[-1]

    def quantile(self, x0: np.ndarray, y0: np.ndarray) -> np.ndarray:
        return np.interp(self.indicator(x0, y0), self.j_sorted, self.q_sorted)


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
        # Residual foam beyond the counted area, within the quantile range [W, 1].
        self._residual_q = min(RESIDUAL_FOAM_WIDTH * self.coverage, 1.0 - self.coverage)
        indicators = _breaking_indicators(surface)
        self._levels: list[_Level] = []
        if not indicators or self.coverage == 0.0:
            return
        assert isinstance(surface, FFTOcean | GerstnerOcean)
        x, y, world_weight = _tabulation_sample(surface)
        for indicator, wavelength in indicators:
            self._levels.append(_Level(indicator, x, y, world_weight, wavelength))

    @property
    def mean_fraction(self) -> float:
        """Expected foam fraction of a large area: the counted whitecaps ``W`` plus the residual
        foam's mean fraction (``W + W·RESIDUAL_FOAM_WIDTH/2``: a smoothstep ramp averages 1/2).
        What a renderer should use where the mesh does not resolve breaking."""
        return self.coverage + 0.5 * self._residual_q

    @property
    def albedo(self) -> float:
        """Mean foam albedo (fraction × reflectance) of a large area: ``W·R_eff`` of the counted
        whitecaps (:func:`whitecap_albedo`) plus the faint residual foam's."""
        if self.coverage == 0.0:
            return 0.0
        width = self._residual_q / self.coverage
        return self.coverage * (FOAM_REFLECTANCE + residual_foam_albedo(width))

    @property
    def mean_reflectance(self) -> float:
        """Foam-weighted mean reflectance of the foam, ``albedo / mean_fraction`` (a little below
        Koepke's 0.22, which is the counted whitecaps' alone): the Lambertian albedo a model of
        the sea as a plane gives its foam fraction :attr:`mean_fraction`."""
        if self.mean_fraction == 0.0:
            return FOAM_REFLECTANCE
        return self.albedo / self.mean_fraction

    @property
    def jacobian_threshold(self) -> float:
        """Indicator value (full detail) below which more than half of a point is foam (the
        middle of the residual edge, ``q = W + W·RESIDUAL_FOAM_WIDTH/2``)."""
        if not self._levels:
            return -math.inf
        finest = self._levels[-1]
        return float(np.interp(self.mean_fraction, finest.q_sorted, finest.j_sorted))

    @property
    def counted_jacobian(self) -> float:
        """Indicator value (full detail) at the edge of the counted whitecaps (``q = W``): below
        it the foam is whole and brighter than :data:`COUNTED_FOAM_REFLECTANCE`."""
        if not self._levels:
            return -math.inf
        finest = self._levels[-1]
        return float(np.interp(self.coverage, finest.q_sorted, finest.j_sorted))

    def breaking_jacobian(self, x0: np.ndarray, y0: np.ndarray) -> np.ndarray:
        """The breaking indicator that places foam (full detail), at rest positions (m): the
        largest patch's Jacobian plus the detail of the shorter ones."""
        if not self._levels:
            return np.ones(np.broadcast(np.asarray(x0), np.asarray(y0)).shape)
        return self._levels[-1].indicator(np.asarray(x0, dtype=float), np.asarray(y0, dtype=float))

    def __call__(
        self, x0: np.ndarray, y0: np.ndarray, spacing_m: np.ndarray | float | None = None
    ) -> np.ndarray:
        """Foam fraction (0–1) at rest positions ``(x0, y0)`` (m), any equal shapes; with a
        mesh vertex spacing ``spacing_m`` (m) only the detail that spacing carries."""
        return self.foam_and_reflectance(x0, y0, spacing_m)[0]

    def foam_and_reflectance(
        self, x0: np.ndarray, y0: np.ndarray, spacing_m: np.ndarray | float | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Foam fraction (0–1) and the visible reflectance of that foam at rest positions (m).

        The reflectance is ``R_fresh·exp(-k·q/W)`` (module docstring): 0.55 on the most
        compressed crests, fading to :data:`COUNTED_FOAM_REFLECTANCE` at the counted whitecap's
        edge and below it over the residual foam; its mean over the counted whitecaps is
        :data:`FOAM_REFLECTANCE`, over all the foam :attr:`mean_reflectance`. Where there is no
        foam it is still defined (the value the foam would have there). ``spacing_m``: a mesh's
        vertex spacing (m), which blends the detail levels (module docstring); None gives the
        full detail.
        """
        x0, y0 = np.broadcast_arrays(np.asarray(x0, dtype=float), np.asarray(y0, dtype=float))
        shape = x0.shape
        if not self._levels:
            return np.zeros(shape), np.full(shape, FOAM_REFLECTANCE)
        fraction = np.zeros(shape)
        albedo = np.zeros(shape)
        q = None
        for level, weight in zip(self._levels, self._level_weights(spacing_m, shape), strict=True):
            if not np.any(weight > 0.0):
                q = None
                continue
            q = level.quantile(x0, y0)
            f = self._profile(q)
            fraction += weight * f
            albedo += (
                weight * f * FRESH_FOAM_REFLECTANCE * np.exp(-FOAM_AGE_DECAY * q / self.coverage)
            )
        reflectance = np.where(
            fraction > 0.0, albedo / np.maximum(fraction, 1e-300), FOAM_REFLECTANCE
        )
        if len(self._levels) == 1 or spacing_m is None:  # one level: exact where no foam too
            if q is None:  # the loop's last quantile is the finest level's, if it ran
                q = self._levels[-1].quantile(x0, y0)
            reflectance = FRESH_FOAM_REFLECTANCE * np.exp(-FOAM_AGE_DECAY * q / self.coverage)
        return fraction, reflectance

    def _profile(self, q: np.ndarray) -> np.ndarray:
        """Foam fraction at quantile ``q``: whole foam over the counted area ``q <= W``, the
        residual foam's ramp beyond."""
        if self._residual_q <= 0.0:
            return (q <= self.coverage).astype(float)
        return _residual_profile((q - self.coverage) / self._residual_q)

    def _level_weights(
        self, spacing_m: np.ndarray | float | None, shape: tuple[int, ...]
    ) -> list[np.ndarray]:
        """Weights (summing to 1) of the detail levels at a vertex spacing: level ``l`` gets
        ``beta_l - beta_(l+1)``, ``beta_l`` the low-pass weight of its finest patch's detail."""
        n = len(self._levels)
        if spacing_m is None:
            return [np.zeros(shape)] * (n - 1) + [np.ones(shape)]
        spacing = np.broadcast_to(np.asarray(spacing_m, dtype=float), shape)
        betas = [np.ones(shape)]
        for level in self._levels[1:]:
            betas.append(np.minimum(betas[-1], lowpass_weight(level.detail_wavelength_m, spacing)))
        betas.append(np.zeros(shape))
        return [betas[i] - betas[i + 1] for i in range(n)]


def layer_over(
    fraction: np.ndarray | float,
    albedo: np.ndarray | float,
    cover: np.ndarray | float,
    reflectance: float = FRESH_FOAM_REFLECTANCE,
) -> tuple[np.ndarray | float, np.ndarray | float]:
    """Foam ``fraction`` (0–1) and foam ``albedo`` (fraction × reflectance) of a surface under a
    layer that covers a share ``cover`` (0–1) of it with ``reflectance`` (a wake's fresh foam,
    a gale's spray veil), the two independent: ``1 − (1 − f)(1 − c)`` and ``a·(1 − c) + c·R``.
    Arrays or scalars (a mesh's vertices, or a plane's means)."""
    return 1.0 - (1.0 - fraction) * (1.0 - cover), albedo * (1.0 - cover) + cover * reflectance


def as_fresh_foam(
    fraction: np.ndarray | float, albedo: np.ndarray | float
) -> tuple[np.ndarray | float, np.ndarray | float]:
    """Foam of ``fraction`` (0–1) and albedo (fraction × reflectance) as a renderer draws it: a
    share ``albedo / R_fresh`` of the surface covered by fresh foam
    (:data:`FRESH_FOAM_REFLECTANCE`), the water between (module docstring, *Rendering*).
    Returns that share and the fresh reflectance (arrays or scalars, as given)."""
    share = np.minimum(np.asarray(albedo, dtype=float) / FRESH_FOAM_REFLECTANCE, fraction)
    reflectance = np.full_like(share, FRESH_FOAM_REFLECTANCE)
    if np.ndim(share) == 0:
        return float(share), float(reflectance)
    return share, reflectance


def foam_fraction(
    surface: OceanSurface, x0: np.ndarray, y0: np.ndarray, wind_speed: float
) -> np.ndarray:
    """Foam fraction (0–1) at rest positions (m) of ``surface`` for wind ``wind_speed`` (m/s at
    10 m); builds a :class:`FoamField` (reuse one for many calls)."""
    return FoamField(surface, wind_speed)(x0, y0)


def _breaking_indicators(surface: OceanSurface) -> list[tuple[_BreakingIndicator, float]]:
    """The breaking indicators ``(x0, y0) -> J`` of the detail levels, coarsest first, each with
    the wavelength (m) below which a mesh cannot carry its detail (0 for the first); empty if
    the surface cannot break (flat). Low values mark breaking crests."""
    if isinstance(surface, FFTOcean):
        lam = surface.choppiness if surface.choppiness > 0.0 else 1.0
        sampled = _PatchSamples(
            [surface.patch_jacobian(i, lam) for i in range(len(surface.cascades))],
            [c.size_m for c in surface.cascades],
        )
        levels: list[tuple[_BreakingIndicator, float]] = []
        for count in range(1, len(surface.cascades) + 1):

            def fft_indicator(x: np.ndarray, y: np.ndarray, count: int = count) -> np.ndarray:
                patches = sampled(x, y, count)
                total = patches[0]
                for patch in patches[1:count]:
                    total = total + DETAIL_WEIGHT * (patch - 1.0)
                return total

            cascade = surface.cascades[count - 1]
            wavelength = 0.0 if count == 1 else DETAIL_GRID_SPACINGS * cascade.spacing_m
            levels.append((fft_indicator, wavelength))
        return levels
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
        return [(probe.jacobian, 0.0)]
    return []


class _PatchSamples:
    """The patches' Jacobians sampled at a set of rest positions, kept for the last positions
    asked: every detail level's indicator adds one patch to the coarser level's, and the
    levels are evaluated one after another at the same positions (a foam field's tabulation
    sample, a mesh's vertices), so each patch is sampled there once, not once per level."""

    def __init__(self, grids: list[np.ndarray], sizes_m: list[float]) -> None:
        self.grids, self.sizes_m = grids, sizes_m
        self._at: tuple[np.ndarray, np.ndarray] | None = None
        self._values: list[np.ndarray] = []

    def __call__(self, x: np.ndarray, y: np.ndarray, count: int) -> list[np.ndarray]:
        """The first ``count`` patches' Jacobians at ``(x, y)`` (m)."""
        if self._at is None or self._at[0] is not x or self._at[1] is not y:
            self._at, self._values = (x, y), []  # holding x, y: their ids stay theirs
        for k in range(len(self._values), count):
            grid = self.grids[k][None]
            self._values.append(sample_periodic_bilinear(grid, self.sizes_m[k], x, y)[0])
        return self._values[:count]


def _tabulation_sample(
    surface: FFTOcean | GerstnerOcean,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A deterministic set of rest positions covering the surface's statistics, and the world
    area each stands for (the surface's own Jacobian: ``dA0`` covers ``J·dA0``)."""
    if isinstance(surface, FFTOcean):
        # Nodes and the midpoints between them: the indicator is bilinear between nodes,
        # which lifts its minima, so the nodes alone would over-represent low values. The
        # shorter patches, of incommensurate periods, are sampled at scattered phases.
        patch = surface.cascades[0]
        nodes = np.arange(2 * patch.resolution) * (0.5 * patch.spacing_m)
    else:
        side = GERSTNER_SAMPLE_PEAK_WAVELENGTHS * surface.peak_wavelength_m
        nodes = (np.arange(SAMPLE_RESOLUTION) + 0.5) * (side / SAMPLE_RESOLUTION)
    x, y = (a.ravel() for a in np.meshgrid(nodes, nodes))
    if surface.choppiness <= 0.0:
        return x, y, np.ones_like(x)
    return x, y, surface.jacobian(x, y)
