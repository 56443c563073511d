"""Contrasts, the Koschmieder fit and its standard errors, from per-batch luminance images.

Per target the apparent contrast ``C = (L_target − L_sky) / L_sky`` is measured on luminance;
Koschmieder's law predicts ``C = −exp(−σ d)``, and in a medium of relative density ``ρ``
``C = −exp(−σ ℓ)`` with ``ℓ = ∫ρ ds`` the reduced length of the target's own ray (its distance
in a uniform layer). A target is measured on several pixels whose rays differ a little: the
expected contrast is the mean of ``−exp(−σ ℓ)`` over them (:class:`RayLengths`). Fitting ``σ``
gives the measured visibility ``V = −ln(ε) / σ``. Noise: the total spp is split over
independent batches (different seeds); the standard error of each contrast comes from the
between-batch variance of its pixels, the standard error of the fitted visibility from the
fit (weights ``1/se²``) and, model-free, from a jackknife over the batches.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..visibility import visibility_from_extinction
from .targets import Target, VerifyInputError, sky_pixels, target_pixels

SE_FLOOR = 1e-9
"""Smallest standard error of a contrast in the fit (noise-free modes such as ``asm``)."""


@dataclass(frozen=True)
class RayLengths:
    """Per target, the reduced lengths ``ℓ`` (m) of its measured pixels' rays, padded to a
    rectangle: ``lengths`` (N, P) and ``weights`` (N, P), each row's weights summing to 1 (0 on
    padding). The expected contrast of target ``i`` is ``−Σ_p w_ip exp(−σ ℓ_ip)``."""

    lengths: np.ndarray
    weights: np.ndarray

    @classmethod
    def of(cls, rays: RayLengths | np.ndarray | Sequence[np.ndarray]) -> RayLengths:
        """From one length per target, (N,), or a sequence of per-target arrays of lengths."""
        if isinstance(rays, RayLengths):
            return rays
        if isinstance(rays, np.ndarray) and rays.ndim == 1:
            return cls(rays.astype(np.float64)[:, None], np.ones((len(rays), 1)))
        rows = [np.asarray(r, np.float64).ravel() for r in rays]
        if not rows or min(len(r) for r in rows) == 0:
            raise ValueError("every target needs at least one ray")
        width = max(len(r) for r in rows)
        lengths, weights = np.zeros((len(rows), width)), np.zeros((len(rows), width))
        for i, r in enumerate(rows):
            lengths[i, : len(r)] = r
            weights[i, : len(r)] = 1.0 / len(r)
        return cls(lengths, weights)

    @property
    def mean_m(self) -> np.ndarray:
        """(N,) each target's mean reduced length (m)."""
        return np.sum(self.weights * self.lengths, axis=1)

    def transmittance(self, sigma: float) -> np.ndarray:
        """(N,) each target's mean transmittance ``Σ_p w_p exp(−σ ℓ_p)`` at extinction
        ``sigma`` (1/m): minus its expected contrast."""
        return np.sum(self.weights * np.exp(-sigma * self.lengths), axis=1)

    def optical_depth(self, sigma: float) -> np.ndarray:
        """(N,) ``−ln`` of the mean transmittance: ``σ ℓ`` for a single ray."""
        return -np.log(self.transmittance(sigma))

    def slope(self, sigma: float) -> np.ndarray:
        """(N,) ``d(transmittance)/d ln σ = −σ Σ_p w_p ℓ_p exp(−σ ℓ_p)``."""
        return -sigma * np.sum(self.weights * self.lengths * np.exp(-sigma * self.lengths), axis=1)


@dataclass
class Contrasts:
    """Measured contrasts of the targets of one level."""

    contrast: np.ndarray
    """(N,) ``(L_target - L_sky) / L_sky``."""
    stderr: np.ndarray
    """(N,) standard error of each contrast, from the between-batch pixel variance."""
    target_luminance: np.ndarray
    sky_luminance: np.ndarray
    target_pixels: np.ndarray
    sky_pixels: np.ndarray


def measure_contrasts(luminance: np.ndarray, targets: Sequence[Target]) -> Contrasts:
    """Contrasts from per-batch luminance images ``(B, H, W)`` (B >= 2 independent batches).

    The standard error of a mean over ``N`` pixels and ``B`` batches is
    ``sqrt(mean_pixel(var_batch) / (N B))``: pixels are independent, and pooling the variance
    over the pixels gives ``N (B - 1)`` degrees of freedom. The contrast's error follows to
    first order (target and sky pixels are disjoint, hence independent).
    """
    y = np.asarray(luminance, dtype=np.float64)
    batches = y.shape[0]
    if batches < 2:
        raise VerifyInputError("at least 2 batches are needed to estimate the noise")
    out: dict[str, list[float]] = {k: [] for k in ("c", "se", "lt", "ls", "nt", "ns")}
    for target in targets:
        t_rows, t_cols = target_pixels(target)
        s_rows, s_cols = sky_pixels(target)
        t = y[:, t_rows, t_cols].reshape(batches, -1)
        s = y[:, s_rows][:, :, s_cols].reshape(batches, -1)
        lt, ls = t.mean(), s.mean()
        se_t = math.sqrt(t.var(axis=0, ddof=1).mean() / t.size)
        se_s = math.sqrt(s.var(axis=0, ddof=1).mean() / s.size)
        out["c"].append(lt / ls - 1.0)
        out["se"].append(math.hypot(se_t / ls, lt * se_s / ls**2))
        out["lt"].append(lt)
        out["ls"].append(ls)
        out["nt"].append(t.shape[1])
        out["ns"].append(s.shape[1])
    return Contrasts(
        np.array(out["c"]),
        np.array(out["se"]),
        np.array(out["lt"]),
        np.array(out["ls"]),
        np.array(out["nt"], dtype=int),
        np.array(out["ns"], dtype=int),
    )


@dataclass(frozen=True)
class Fit:
    """Extinction fitted to measured contrasts: ``C = -exp(-sigma d)``."""

    sigma: float
    """Fitted extinction (1/m); ``nan`` when no target stands out of the noise."""
    sigma_se: float
    """Its standard error from the fit (the contrasts' standard errors as weights)."""
    chi2_per_dof: float
    """Reduced chi-square: about 1 when the model fits within the noise."""
    informative: int
    """Targets whose contrast is at least 3 standard errors from zero."""


def fit_extinction(
    distance_m: np.ndarray | Sequence[np.ndarray] | RayLengths,
    contrast: np.ndarray,
    stderr: np.ndarray,
) -> Fit:
    """Weighted least-squares fit of ``ln|C| = -sigma d`` to measured contrasts.

    ``distance_m``: per target its distance or reduced length ``ℓ`` (m), (N,), or the reduced
    lengths of each of its measured rays (:class:`RayLengths`), when the model is the mean of
    ``-exp(-sigma ℓ)`` over them. Solved on ``C`` itself, ``sum(((C + exp(-sigma d)) / se)^2)``
    minimal: to first order the same as the log fit with weights ``(C / se)^2``, but without the
    log's noise bias, and targets lost in the noise (``C`` near zero or even positive) need no
    cut: they carry no weight. The start value is the weighted log fit, on each target's mean
    length, over the targets 3 se clear of zero.
    """
    from scipy.optimize import least_squares

    rays = RayLengths.of(distance_m)
    d = rays.mean_m
    c = np.asarray(contrast, float)
    se = np.maximum(np.asarray(stderr, float), SE_FLOOR)
    clear = (c < 0) & (-c >= 3.0 * se)
    informative = int(clear.sum())
    if informative == 0:
        return Fit(math.nan, math.nan, math.nan, 0)
    w = (c[clear] / se[clear]) ** 2
    y = np.log(-c[clear])
    sigma0 = max(-float(np.sum(w * d[clear] * y) / np.sum(w * d[clear] ** 2)), 1e-12)

    # Fitted in x = ln(sigma): positive by construction and well scaled for every visibility.
    def residual(x: np.ndarray) -> np.ndarray:
        return (c + rays.transmittance(float(np.exp(x[0])))) / se

    def jacobian(x: np.ndarray) -> np.ndarray:
        return (rays.slope(float(np.exp(x[0]))) / se)[:, None]

    result = least_squares(
        residual, [math.log(sigma0)], jac=jacobian, xtol=1e-14, ftol=1e-14, gtol=1e-14
    )
    sigma = float(np.exp(result.x[0]))
    jac = jacobian(result.x)[:, 0]
    log_se = 1.0 / math.sqrt(float(jac @ jac)) if np.any(jac) else math.inf
    dof = max(len(c) - 1, 1)
    return Fit(sigma, sigma * log_se, float(np.sum(result.fun**2)) / dof, informative)


def visibility_or_nan(sigma: float, threshold: str) -> float:
    """The visibility (m) of extinction ``sigma``, NaN where the fit found none."""
    return visibility_from_extinction(sigma, threshold) if math.isfinite(sigma) else math.nan


def jackknife_visibility(
    luminance: np.ndarray,
    targets: Sequence[Target],
    distance_m: np.ndarray | Sequence[np.ndarray] | RayLengths,
    threshold: str,
) -> float:
    """Jackknife standard error (m) of the fitted visibility over the batches (needs >= 3)."""
    batches = luminance.shape[0]
    if batches < 3:
        return math.nan
    rays = RayLengths.of(distance_m)
    values = []
    for b in range(batches):
        keep = np.delete(luminance, b, axis=0)
        stats = measure_contrasts(keep, targets)
        fit = fit_extinction(rays, stats.contrast, stats.stderr)
        values.append(visibility_or_nan(fit.sigma, threshold))
    v = np.array(values)
    if not np.all(np.isfinite(v)):
        return math.nan
    return float(math.sqrt((batches - 1) / batches * np.sum((v - v.mean()) ** 2)))
