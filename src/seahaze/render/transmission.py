"""Exact per-pixel transmittance, optical depth and effective visibility of a hazy level.

For the ray through a pixel's centre, from the camera to the first surface it meets, at
distance ``d`` (m), the optical depth of level ``k`` is ``τ_k = σ_k ℓ`` with the reduced
length ``ℓ = ∫₀ᵈ ρ ds`` (m) of the haze medium (:meth:`seahaze.medium.HazeMedium.path_length`,
in closed form for every medium of that interface: no Monte Carlo noise), ``σ_k`` the level's
extinction per channel (1/m). Its transmittance is ``T_k = exp(−τ_k)`` (Beer–Lambert).

Effective visibility
    The visibility a uniform haze would need to give the same transmittance over the same
    distance: ``V_eff = −ln(ε)·d / τ`` with ``ε`` the level's contrast threshold (0.02:
    ``−ln ε = 3.912``) and ``τ`` the optical depth at the level's nominal extinction
    ``σ = −ln(ε)/V`` (:mod:`seahaze.visibility`), so ``V_eff = V·d/ℓ``. In a homogeneous slab
    containing the ray ``ℓ = d`` and ``V_eff = V``; a ray climbing out of a fog layer sees
    farther (``V_eff > V``).

The sky and the far sea
    A ray is followed to its surface or for :data:`SKY_REACH_M`, whichever is nearer: a sky
    pixel's ``d``, ``τ``, ``T`` and ``V_eff`` refer to that reach (a ray that leaves the haze
    before then counts the clear air beyond it in ``d``), and so do those of the sea beyond
    it, where every graded level's transmittance is below 3e-9.

Float32
    ``τ`` is stored as it is: ``T`` underflows to 0 in float32 past ``τ ≈ 103`` (a few km in
    the densest levels), where ``τ`` still holds the exact value.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..haze import optical_depth
from ..medium import HazeMedium
from ..nonuniform import RAY_REACH_M
from .passes import GeometryPass

SKY_REACH_M = RAY_REACH_M
"""How far a sky pixel's ray is followed (m): 5 × the clearest graded visibility (4000 m),
where every graded level's transmittance of a horizontal ray is below 3e-9 (the reach of a
haze that varies across the sea too)."""


@dataclass(frozen=True)
class RayReach:
    """The rays of one scene's pixels through its haze medium: shared by every level."""

    distance_m: np.ndarray
    """(H, W) float64 ``d``: the distance to the surface, at most :data:`SKY_REACH_M` (the
    sky's)."""
    reduced_m: np.ndarray
    """(H, W) float64 ``ℓ = ∫₀ᵈ ρ ds`` (m)."""


@dataclass(frozen=True)
class LevelTransmission:
    """One level's per-pixel maps (what ``transmission/<level>/<scene>.exr`` holds)."""

    optical_depth: np.ndarray
    """(H, W, 3) float32 ``τ`` per channel R, G, B (dimensionless)."""
    transmittance: np.ndarray
    """(H, W, 3) float32 ``T = exp(−τ)`` per channel."""
    visibility_eff_m: np.ndarray
    """(H, W) float32 ``V_eff`` (m); ``inf`` where the ray meets no haze."""


def ray_reach(geometry: GeometryPass, medium: HazeMedium) -> RayReach:
    """Distance and reduced length of every pixel-centre ray of ``geometry`` in ``medium``."""
    # Each ray to its surface or SKY_REACH_M, whichever is nearer (the sky's are all SKY_REACH_M).
    distance = np.minimum(geometry.distance_m.astype(np.float64), SKY_REACH_M)
    reduced = medium.ray_path_length(geometry.origin, geometry.directions, distance)
    return RayReach(distance, np.asarray(reduced, np.float64))


def level_transmission(
    reach: RayReach, sigma_rgb: np.ndarray, visibility_m: float
) -> LevelTransmission:
    """The maps of a level of extinction ``sigma_rgb`` (3,) in 1/m and nominal visibility
    ``visibility_m`` (m) for the rays of ``reach``."""
    tau = optical_depth(sigma_rgb, reach.reduced_m)
    with np.errstate(divide="ignore"):
        v_eff = np.where(
            reach.reduced_m > 0.0, visibility_m * reach.distance_m / reach.reduced_m, np.inf
        )
    return LevelTransmission(
        tau.astype(np.float32), np.exp(-tau).astype(np.float32), v_eff.astype(np.float32)
    )


@dataclass(frozen=True)
class VesselRays:
    """One vessel's rays through the medium, shared by every level: the reduced lengths (m)
    of the pixel rays that show it (its instance mask, which its box bounds) and of the
    straight ray from the camera to its centre."""

    shown_reduced_m: np.ndarray
    centre_reduced_m: float

    def entries(self, sigma_per_m: float) -> dict[str, Any]:
        """The vessel's entries at a level of nominal extinction ``sigma_per_m`` (1/m): the
        mean and least transmittance over its pixels (None when no pixel shows it) and the
        optical depth to its centre."""
        t = np.exp(-sigma_per_m * self.shown_reduced_m)
        return {
            "transmittance_mean": float(t.mean()) if t.size else None,
            "transmittance_min": float(t.min()) if t.size else None,
            "optical_depth_centre": float(sigma_per_m * self.centre_reduced_m),
        }


def vessel_rays(
    reach: RayReach,
    instance: np.ndarray,
    vessel_index: int,
    centre_m: np.ndarray,
    camera_m: np.ndarray,
    medium: HazeMedium,
) -> VesselRays:
    """The rays of vessel ``vessel_index`` (its pixels in ``instance``) and of its centre
    ``centre_m`` seen from the camera at ``camera_m`` (world frame, m) in ``medium``."""
    ray = np.asarray(centre_m, np.float64) - np.asarray(camera_m, np.float64)
    distance = float(np.linalg.norm(ray))
    direction = ray / distance if distance > 0.0 else np.array([1.0, 0.0, 0.0])
    to_centre = medium.ray_path_length(camera_m, direction[None, :], np.array([distance]))
    return VesselRays(reach.reduced_m[instance == vessel_index], float(to_centre[0]))
