"""Cox–Munk sea-surface slope statistics and the matching microfacet roughness.

Cox & Munk (1954) measured the sun glitter of the open sea and found near-Gaussian slope
distributions with mean square slopes that grow linearly with the wind speed ``U`` (m/s)
measured at 12.5 m (41 ft) above the sea. For a clean surface:

    sigma² = sigma_u² + sigma_c² = 0.003 + 5.12e-3·U            (± 0.004)
    sigma_u² = 3.16e-3·U,   sigma_c² = 0.003 + 1.92e-3·U        (up-wind, cross-wind)

(Cox, C. & Munk, W. (1954). Measurement of the roughness of the sea surface from photographs of
the sun's glitter. J. Opt. Soc. Am. 44(11), 838–850; see also Mobley, Ocean Optics Web Book,
"Cox-Munk sea surface slope statistics").

Mapping to Mitsuba's microfacet ``alpha``
    Mitsuba 3's ``roughdielectric``/``roughconductor`` evaluate the Beckmann distribution as
    ``D(m) = exp(-(m_x²/alpha_u² + m_y²/alpha_v²)/cos²theta) / (pi·alpha_u·alpha_v·cos⁴theta)``
    (``include/mitsuba/render/microfacet.h``); its docs state that for Beckmann ``alpha`` "is
    equal to the root mean square (RMS) slope of the microfacets". In slope space
    (``p = -m_x/m_z``) this density is ``exp(-p²/alpha_u² - q²/alpha_v²)/(pi·alpha_u·alpha_v)``,
    a Gaussian with per-axis variance ``alpha²/2``. Matching Cox–Munk per axis gives

        alpha_u = sqrt(2·sigma_u²),   alpha_v = sqrt(2·sigma_c²),

    and for an isotropic surface (``sigma_u² = sigma_c² = sigma²/2``)

        alpha = sqrt(sigma²)   (= sqrt(2)·per-axis RMS slope = RMS of the slope magnitude).

    At U = 10 m/s: sigma² = 0.0542, alpha = 0.233. GGX (Trowbridge–Reitz) has the same slope
    density at ``p = q = 0`` for the same ``alpha`` (``1/(pi·alpha²)``) but heavier tails and an
    unbounded slope variance; using the same ``alpha`` is the usual approximation, Beckmann is
    the faithful choice for Cox–Munk's Gaussian statistics.

Sub-grid roughness
    When the mesh already resolves part of the slope variance (``sigma²_resolved``, the
    geometric mean square slope of the displaced surface), the microfacets should only carry the
    rest: ``sigma²_sub = max(sigma²_CM - sigma²_resolved, floor)`` (slope variances of
    independent scales add).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

COX_MUNK_HEIGHT_M = 12.5
"""Anemometer height of Cox & Munk's wind speeds (m)."""

MIN_SUBGRID_MEAN_SQUARE_SLOPE = 0.003
"""Floor for the sub-grid mean square slope: Cox–Munk's calm-sea intercept (capillary ripples
never vanish entirely)."""


def mean_square_slope(wind_speed: float) -> float:
    """Total mean square slope ``sigma² = 0.003 + 5.12e-3·U`` of a clean sea surface
    (dimensionless; Cox & Munk 1954). ``wind_speed``: ``U`` in m/s at 12.5 m; in a neutral log
    profile (drag coefficient 1.3e-3) ``U12.5 ≈ 1.02·U10``, a difference well inside the fit's
    ± 0.004 scatter, so passing ``U10`` is acceptable."""
    return 0.003 + 5.12e-3 * max(float(wind_speed), 0.0)


def mean_square_slope_components(wind_speed: float) -> tuple[float, float]:
    """Up-wind and cross-wind mean square slopes ``(3.16e-3·U, 0.003 + 1.92e-3·U)``
    (Cox & Munk 1954, clean surface; ``U`` in m/s at 12.5 m)."""
    u = max(float(wind_speed), 0.0)
    return 3.16e-3 * u, 0.003 + 1.92e-3 * u


def beckmann_alpha(mean_square_slope_total: float) -> float:
    """Isotropic Beckmann ``alpha`` for Mitsuba from a total mean square slope
    ``sigma² = sigma_x² + sigma_y²``: ``alpha = sqrt(sigma²)`` (see module docstring)."""
    return math.sqrt(max(mean_square_slope_total, 0.0))


def cox_munk_alpha(wind_speed: float) -> float:
    """Isotropic Beckmann/GGX ``alpha`` of a clean wind-roughened sea:
    ``sqrt(0.003 + 5.12e-3·U)`` (``U`` in m/s at 12.5 m). 0.233 at 10 m/s."""
    return beckmann_alpha(mean_square_slope(wind_speed))


def cox_munk_anisotropic_alpha(wind_speed: float) -> tuple[float, float]:
    """Anisotropic Beckmann ``(alpha_u, alpha_v)`` = ``(sqrt(2·sigma_u²), sqrt(2·sigma_c²))`` with
    ``u`` along the wind (Mitsuba's ``alpha_u`` follows the surface tangent, which the caller must
    align with the wind direction)."""
    up, cross = mean_square_slope_components(wind_speed)
    return math.sqrt(2.0 * up), math.sqrt(2.0 * cross)


class _HasMeanSquareSlope(Protocol):
    @property
    def mean_square_slope(self) -> float: ...


def sub_grid_roughness(
    wind_speed: float,
    resolved: float | _HasMeanSquareSlope = 0.0,
    floor: float = MIN_SUBGRID_MEAN_SQUARE_SLOPE,
) -> float:
    """Isotropic Beckmann ``alpha`` for the slopes the geometry does not resolve.

    ``alpha = sqrt(max(sigma²_CM(U) - sigma²_resolved, floor))`` where ``sigma²_CM`` is
    :func:`mean_square_slope` (``U`` in m/s at 12.5 m; U10 is close enough) and
    ``sigma²_resolved`` is either a number (mean of ``|grad z|²`` of the displaced geometry) or
    an ocean surface, whose ``mean_square_slope`` (every wave the generator resolves) is used.

    Note that the mesh shows those waves only near the camera (the displacement is band-limited
    by the vertex spacing and faded to flat beyond ``fade_end``): with a single material the
    near field is right and the far, flat field too smooth by ``sigma²_resolved``; passing 0
    gives the opposite (far field right, near field too rough).
    """
    resolved_mss = float(getattr(resolved, "mean_square_slope", resolved))
    remaining = mean_square_slope(wind_speed) - max(resolved_mss, 0.0)
    return beckmann_alpha(max(remaining, floor))


class _ResolvesSlopes(Protocol):
    def mean_square_slope_filtered(self, spacing_m: float) -> float: ...


@dataclass(frozen=True)
class SlopeBudget:
    """How Cox–Munk's total mean square slope is shared between geometry and microfacets.

    Attributes:
        total: Cox–Munk ``sigma²(U)`` (dimensionless).
        resolved: slope variance of the displaced geometry at the given vertex spacing.
        sub_grid: slope variance left to the microfacets, ``max(total - resolved, floor)``.
        alpha: isotropic Beckmann ``alpha = sqrt(sub_grid)`` for Mitsuba.
    """

    total: float
    resolved: float
    sub_grid: float
    alpha: float

    @property
    def closes(self) -> bool:
        """True when ``resolved + sub_grid == total`` (the floor did not act)."""
        return math.isclose(self.resolved + self.sub_grid, self.total, rel_tol=1e-12)


def slope_budget(
    wind_speed: float,
    surface: _ResolvesSlopes,
    spacing_m: float = 0.0,
    floor: float = MIN_SUBGRID_MEAN_SQUARE_SLOPE,
) -> SlopeBudget:
    """Split Cox–Munk's total mean square slope (``U`` in m/s, 10 m ≈ 12.5 m) into the part a
    mesh of vertex spacing ``spacing_m`` (m) resolves (``surface.mean_square_slope_filtered``,
    the band-limited displacement the mesh samples there) and the sub-grid rest for the BSDF.

    Slope variances of independent scales add (Cox & Munk 1954 measured the total over all
    scales), so ``resolved + sub_grid = total`` whenever ``resolved <= total - floor``. Near the
    camera ``spacing_m`` is the local vertex spacing; where the mesh is faded flat, ``resolved``
    is 0 and the microfacets carry everything (``alpha`` = :func:`cox_munk_alpha`).
    """
    total = mean_square_slope(wind_speed)
    resolved = max(float(surface.mean_square_slope_filtered(spacing_m)), 0.0)
    sub = max(total - resolved, floor)
    return SlopeBudget(total, resolved, sub, beckmann_alpha(sub))


SPACING_SAMPLES = 32
"""Vertex spacings (log-spaced) at which :func:`mesh_roughness` evaluates the resolved slope
variance; it is interpolated in ``log(spacing)`` between them."""


@dataclass(frozen=True)
class MeshRoughness:
    """The slope budget of every vertex of a sea mesh, as two Beckmann lobes and a mix.

    One Mitsuba BSDF has one ``alpha``, but the mesh resolves different slopes at different
    distances (its displacement is band-limited by the vertex spacing and faded to flat far
    away). A blend ``(1 - n)·lobe(alpha_far) + n·lobe(alpha_near)`` of two Beckmann lobes has
    the mean square slope ``(1 - n)·alpha_far² + n·alpha_near²`` (a mixture's second moment is
    the weighted sum of its parts'), so the per-vertex weight

        n = (sigma²_CM - sigma²_sub) / (sigma²_CM - alpha_near²),
        sigma²_sub = max(sigma²_CM - w²·sigma²_resolved(spacing), floor)

    (``w`` the displacement fade, slopes scale with it) gives every vertex exactly the
    microfacet slope variance its own slope budget leaves: the near sea is not counted twice,
    the flat far sea carries all of Cox–Munk. The mixture is not itself Gaussian (its kurtosis
    is slightly higher), which matters only in the transition zone.

    Attributes:
        alpha_near: ``alpha`` of the finest, fully displaced vertices (sub-grid slopes only).
        alpha_far: ``alpha`` of a flat sea, :func:`cox_munk_alpha` (all slopes).
        near_weight: ``(N,)`` weight ``n`` of the near lobe per vertex, in [0, 1].
    """

    alpha_near: float
    alpha_far: float
    near_weight: np.ndarray

    def sub_grid_mean_square_slope(self) -> np.ndarray:
        """``(N,)`` microfacet mean square slope per vertex of the two-lobe mixture."""
        n = self.near_weight.astype(float)
        return n * self.alpha_near**2 + (1.0 - n) * self.alpha_far**2


def mesh_roughness(
    wind_speed: float,
    surface: _ResolvesSlopes,
    spacing_m: np.ndarray,
    fade: np.ndarray,
    floor: float = MIN_SUBGRID_MEAN_SQUARE_SLOPE,
) -> MeshRoughness:
    """The two-lobe roughness of a sea mesh (:class:`MeshRoughness`) from its vertices'
    spacing ``spacing_m`` (m) and displacement fade weight ``fade`` (0–1), for a wind of
    ``wind_speed`` (m/s at 10 m)."""
    spacing = np.asarray(spacing_m, dtype=float)
    weight = np.asarray(fade, dtype=float)
    total = mean_square_slope(wind_speed)
    resolved = np.zeros_like(spacing)
    shown = weight > 0.0
    if np.any(shown):
        lo, hi = float(spacing[shown].min()), float(spacing[shown].max())
        grid = np.geomspace(lo, max(hi, lo * (1.0 + 1e-9)), SPACING_SAMPLES)
        table = np.array([max(surface.mean_square_slope_filtered(float(d)), 0.0) for d in grid])
        resolved[shown] = weight[shown] ** 2 * np.interp(
            np.log(spacing[shown]), np.log(grid), table
        )
    sub = np.maximum(total - resolved, floor)
    near = float(min(sub.min(), total)) if sub.size else total
    span = total - near
    mix = (total - sub) / span if span > 0.0 else np.zeros_like(sub)
    return MeshRoughness(
        beckmann_alpha(near),
        beckmann_alpha(total),
        np.clip(mix, 0.0, 1.0).astype(np.float32),
    )
