"""A later segment's own density ratio through a fog bank, in the ``physical`` kernels.

``physical`` renders haze that varies across the sea as each pixel's equivalent profile
(:mod:`seahaze.render.pixel_density`), and gave the segments after a surface one ratio per
pixel: on the sea, that of the camera ray mirrored in a flat sea. But the sea's rough lobe and
its water body send paths up at every elevation, and under the thin side of a bank a path that
climbs steeply leaves the haze through the thin column while the mirrored ray runs into the
bank: the sea reflected the bank's haze in every direction (the bank's sea +28 % lit by the sun
alone at 1000 m, docs/physics.md). A bank varies along one horizontal axis through a logistic
edge, a few operations per point, so each later segment's ratio is measured along the segment
itself, at :data:`SEGMENT_POINTS` stratified points of its stretch in the haze:

    r = c Σ ρ_v(z_i) m(x_i) / Σ ρ_v(z_i),

the field's density over the profile's along that stretch, the ratio of their reduced lengths
to quadrature accuracy. The camera segment keeps its pixel's exact ``view`` ratio, the depths
toward the sun their per-level ratios. Patches keep the mirrored ray's ratio: their fractal
noise costs tens of operations per point, and this has not been measured for them.

The bank's constants are kernel parameters: another bank, or another frame of a drifting one,
reuses the kernel. Import this module only once a Mitsuba variant is set.
"""

from __future__ import annotations

import math
from typing import Any

import drjit as dr
import mitsuba as mi

from ..medium import drjit_ops
from ..nonuniform import RAY_REACH_M, NonUniformHaze
from .field_medium import bank_step

SEGMENT_POINTS = 16
"""Points of a later segment's ratio (stratified, one uniform number per segment). The ratio
goes into an exponential, where the noise of too few points biases the transmittance: on the
bank of docs/physics.md at 1000 m, 16 and 64 points give the same region means to 0.01 %, one
point puts the sea 0.8 % higher."""


class BankSegments:
    """The later segments' ratios through the bank of ``medium`` (module docstring)."""

    def __init__(self, medium: NonUniformHaze):
        bank, drift = medium.field.bank, medium.field.drift
        if bank is None or medium.field.patches is not None:
            raise ValueError("BankSegments needs a field that is a bank alone")
        az = math.radians(bank.toward_deg)
        cos, sin = math.cos(az), math.sin(az)
        ux, uy = drift.unit
        travelled = drift.speed_m_s * drift.time_s
        # Metres past the edge of a world point: its distance along the bank's bearing from the
        # camera's start, the field drifted back by ``travelled``, less the edge's distance.
        offset = -((bank.origin_xy[0] + ux * travelled) * cos) - (
            (bank.origin_xy[1] + uy * travelled) * sin
        )
        opaque = lambda v: dr.opaque(mi.Float, float(v))  # noqa: E731
        self.cos, self.sin = opaque(cos), opaque(sin)
        self.offset = opaque(offset - bank.distance_m)
        self.half_inverse_edge = opaque(0.5 / bank.edge_m)
        self.near_ratio = opaque(bank.near_ratio)
        self.scale = opaque(medium.scale)
        self.profile = medium.profile

    @staticmethod
    def suits(medium: Any) -> bool:
        """Whether ``medium`` is haze whose variation across the sea is a bank alone."""
        return (
            isinstance(medium, NonUniformHaze)
            and medium.field.bank is not None
            and medium.field.patches is None
        )

    def modulation(self, x: Any, y: Any) -> Any:
        """The bank's ``m`` at world ``x``, ``y`` (m)."""
        beyond = dr.fma(x, self.cos, dr.fma(y, self.sin, self.offset))
        return bank_step(beyond, self.half_inverse_edge, self.near_ratio)

    def ratio(self, ray: Any, t_end: Any, u: Any, fallback: Any) -> Any:
        """``ℓ_field / ℓ_profile`` of ``ray`` up to ``t_end`` (m; ``∞``: out of the haze, at
        most :data:`~seahaze.nonuniform.RAY_REACH_M`) at points shifted by uniform ``u``;
        ``fallback`` where the ray meets no haze."""
        ops = drjit_ops()
        enter, leave = self.profile.span(ray.o.z, ray.d.z, ops)
        leave = dr.minimum(dr.minimum(leave, t_end), RAY_REACH_M)
        step = dr.maximum(leave - enter, 0.0) * (1.0 / SEGMENT_POINTS)
        field, profile = mi.Float(0.0), mi.Float(0.0)
        for i in range(SEGMENT_POINTS):
            p = ray(dr.fma(u + i, step, enter))
            rho = self.profile.density(p.z, ops)
            field += rho * self.modulation(p.x, p.y)
            profile += rho
        return dr.select(profile > 0.0, self.scale * field / dr.maximum(profile, 1e-30), fallback)
