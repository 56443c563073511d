"""A layer of sea fog with thinner haze above it: the haze medium of ``haze.fog_layer``.

Advection sea fog lies under a temperature inversion: dense from the sea up to a top of some
50–400 m, thin above it, with a transition a few metres to tens of metres thick (e.g. Koračin,
Dorman, Lewis, Hudson, Wilcox & Torregrosa (2014), "Marine fog: A review", *Atmospheric
Research* 143, 142–175). A camera on a mast may sit above the fog and see the vessels' masts
rise out of it.

The profile
    Relative density ``ρ(z) = c·(a + (1 − a)·L((t − z)/w))`` for ``bottom ≤ z ≤ top`` (m), 0
    elsewhere: ``t`` the fog top, ``w`` the edge's thickness scale (the density is within 12 %
    of its fog and above-fog values 2 ``w`` below and above ``t``), ``a`` the density above the
    fog relative to the fog, ``L(x) = 1/(1 + e^{−x})`` the logistic step, and ``c`` the
    normalisation that makes ``ρ = 1`` at the camera's height. So a level's extinction ``σ_k =
    3.912/V_k`` is the extinction along the horizontal line of sight at the camera's height,
    and the visibility label keeps its meaning there (docs/physics.md, "A fog layer").

Reduced height and its inverse
    ``h(z) = ∫₀ᶻ ρ = c·[a z + (1 − a)·w·(sp(t/w) − sp((t − z)/w))]`` with the softplus
    ``sp(x) = ln(1 + eˣ)``, in closed form; :mod:`seahaze.medium` explains why that is all the
    ``physical`` mode needs. Its inverse has no closed form: Newton's method from the inverse of
    the sharp-edged profile. ``h`` is concave (the density falls with height), so after one
    step every iterate lies below the root and climbs to it monotonically; after
    :data:`NEWTON_STEPS` steps tests/test_fog_layer.py holds the inverse to 1e-9 m in float64
    and 2 mm in float32.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .medium import HAZE_BOTTOM_M, NUMPY, ArrayOps, HazeMedium, HomogeneousSlab

NEWTON_STEPS = 6
"""Newton steps of the reduced height's inverse."""


def _softplus(x: Any, ops: ArrayOps) -> Any:
    """``ln(1 + eˣ)`` without overflow."""
    return ops.maximum(x, 0.0) + ops.log(1.0 + ops.exp(-ops.abs(x)))


def _logistic(x: Any, ops: ArrayOps) -> Any:
    """``1/(1 + e^{−x})`` without overflow."""
    e = ops.exp(-ops.abs(x))
    return ops.select(x >= 0.0, 1.0 / (1.0 + e), e / (1.0 + e))


@dataclass(frozen=True)
class FogLayer(HazeMedium):
    """Fog from below the sea up to ``fog_top`` (m) with a soft edge of scale ``edge`` (m),
    ``above`` (0–1) of its density above it up to ``top`` (m); ``scale`` normalises the
    density to 1 at the camera's height (:func:`fog_layer_medium`)."""

    fog_top: float
    edge: float
    above: float
    top: float
    scale: float = 1.0
    albedo: float = 0.998
    g: float = 0.75
    bottom: float = HAZE_BOTTOM_M

    def __post_init__(self) -> None:
        if not (self.bottom < self.fog_top < self.top and self.edge > 0.0):
            raise ValueError("a fog layer needs bottom < fog top < top and an edge > 0")
        if not 0.0 < self.above <= 1.0 or not self.scale > 0.0:
            raise ValueError("a fog layer needs 0 < above <= 1 and a positive scale")

    @property
    def reduced_is_geometric(self) -> bool:
        return False

    @property
    def reduced_top_m(self) -> float:
        return float(self.reduced_height(np.float64(self.top), NUMPY))

    def _profile(self, z: Any, ops: ArrayOps) -> Any:
        x = (self.fog_top - z) * (1.0 / self.edge)
        return self.scale * (self.above + (1.0 - self.above) * _logistic(x, ops))

    def density(self, z: Any, ops: ArrayOps) -> Any:
        inside = (z >= self.bottom) & (z <= self.top)
        return ops.select(inside, self._profile(z, ops), 0.0)

    def reduced_height(self, z: Any, ops: ArrayOps) -> Any:
        z = ops.minimum(ops.maximum(z, self.bottom), self.top)
        w, t = self.edge, self.fog_top
        step = _softplus(t / w, ops) - _softplus((t - z) * (1.0 / w), ops)
        return self.scale * (self.above * z + (1.0 - self.above) * w * step)

    def height_of(self, h: Any, ops: ArrayOps) -> Any:
        """The height (m) of reduced height ``h`` (the inverse of :meth:`reduced_height`)."""
        # The sharp-edged profile's inverse as the first guess.
        h_top = self.scale * self.fog_top
        sharp = ops.select(h <= h_top, h, h_top + (h - h_top) * (1.0 / self.above))
        z = ops.minimum(ops.maximum(sharp * (1.0 / self.scale), self.bottom), self.top)
        for _ in range(NEWTON_STEPS):
            z = z - (self.reduced_height(z, ops) - h) / self._profile(z, ops)
            z = ops.minimum(ops.maximum(z, self.bottom), self.top)
        return z

    def span(self, oz: Any, dz: Any, ops: ArrayOps) -> tuple[Any, Any]:
        return HomogeneousSlab(self.top, bottom=self.bottom).span(oz, dz, ops)

    def reduced_length(self, oz: Any, dz: Any, t_end: Any, ops: ArrayOps) -> tuple[Any, Any]:
        enter, leave = self.span(oz, dz, ops)
        stop = leave if t_end is None else ops.minimum(leave, t_end)
        length = ops.maximum(stop - enter, 0.0)  # metres in the medium (inf: never leaves)
        inside = length > 0.0
        start = ops.select(inside, enter, 0.0)
        z0 = oz + start * dz
        z1 = ops.select(ops.abs(dz) < ops.flat_dz, z0, oz + (start + length) * dz)
        climbed = ops.divide(self.reduced_height(z1, ops) - self.reduced_height(z0, ops), dz)
        # Where the ray barely changes height the difference of reduced heights cancels: the
        # density at its middle times its length is exact to second order there.
        level = self.density(0.5 * (z0 + z1), ops) * length
        flat = ops.abs(z1 - z0) < 1e-2 * self.edge
        return enter, ops.select(inside, ops.select(flat, level, climbed), 0.0)

    def distance_at(self, oz: Any, dz: Any, enter: Any, reduced: Any, ops: ArrayOps) -> Any:
        z0 = oz + enter * dz
        z = self.height_of(self.reduced_height(z0, ops) + dz * reduced, ops)
        climbed = ops.divide(z - oz, dz)
        level = enter + ops.divide(reduced, self.density(z0, ops))
        flat = ops.abs(dz * reduced) < 1e-2 * self.edge * self.scale * self.above
        return ops.select(flat, level, climbed)

    def describe(self) -> dict[str, Any]:
        return {
            **super().describe(),
            "fog_top_m": self.fog_top,
            "edge_m": self.edge,
            "above_ratio": self.above,
            "density_scale": self.scale,
        }


def fog_layer_medium(
    fog_top_m: float,
    edge_m: float,
    above_ratio: float,
    top_m: float,
    camera_height_m: float,
    albedo: float = 0.998,
    g: float = 0.75,
) -> FogLayer:
    """The fog layer whose density is 1 at the camera's height (module docstring)."""
    raw = FogLayer(fog_top_m, edge_m, above_ratio, top_m, 1.0, albedo, g)
    at_camera = raw.density(np.float64(min(max(camera_height_m, 0.0), top_m)), NUMPY)
    scale = 1.0 / float(at_camera) if at_camera > 0.0 else 1.0 / above_ratio
    if not math.isfinite(scale):
        raise ValueError("the fog layer's density at the camera's height is not finite")
    return FogLayer(fog_top_m, edge_m, above_ratio, top_m, scale, albedo, g)
