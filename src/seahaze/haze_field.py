"""Where sea fog is thick and where it is thin across the sea: patches and banks that drift.

Real sea fog is rarely uniform across the view: radiation and advection fog is patchy on
scales of tens of metres to kilometres, and fog banks with a sharp edge roll in with the wind
(Gultepe et al. (2007), "Fog research: A review of past achievements and future perspectives",
*Pure and Applied Geophysics* 164, 1121–1159; Koračin et al. (2014), "Marine fog: A review",
*Atmospheric Research* 143, 142–175). This module is that horizontal structure as a
dimensionless *modulation* ``m(x, y, z, t) > 0`` of a haze's density (world frame, metres,
seconds); :mod:`seahaze.nonuniform` multiplies a vertical profile by it.

Patches (:class:`Patches`)
    ``m = exp(a·n(q))`` with ``n`` fractal value noise in ``[−1, 1]`` (a sum of
    :data:`OCTAVES` octaves of smoothly interpolated lattice noise, each of half the scale
    and half the weight of the last) and ``a = ln(R)/2`` for a max-to-min density ratio
    ``R``. The noise is read at ``q = (u/L, v·A/L, z/L_z)``: ``u`` along the drift
    direction, ``v`` across it, ``L`` the correlation length along it, ``A ≥ 1`` the
    anisotropy (patches stretched along the wind) and ``L_z`` the vertical correlation
    length. The lattice values come from an integer hash of the lattice point and a seed, so
    the field is the same wherever and in whatever order it is evaluated.

A bank (:class:`Bank`)
    ``m = r + (1 − r)·L((s − D)/w)`` with ``s`` the horizontal distance along the bank's
    bearing from the camera's starting point, ``D`` the distance of its edge, ``w`` the edge's
    width scale (``L`` the logistic step: ``m`` goes 88 % of the way within ``2w`` of the
    edge), and ``r`` the density on the near side relative to inside the bank.

Drift
    In a sequence the whole field moves with the wind: ``m(x, t) = m(x − u t, 0)`` with ``u``
    the drift velocity (m/s), so frames are coherent and a vessel can sail into and out of a
    bank.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

OCTAVES = 3
"""Octaves of the patches' fractal noise."""
OCTAVE_SEED_STEP = 7919
"""Octave ``k`` of the noise hashes with seed ``seed + k·7919`` (a prime: unrelated octaves)."""
LATTICE_MULTIPLIERS = (0x9E3779B97F4A7C15, 0xC2B2AE3D27D4EB4F, 0x165667B19E3779F9)
"""Odd 64-bit multipliers that spread a lattice point's x, y and z over the hash's bits."""
SPLITMIX_FINALISER = ((30, 0xBF58476D1CE4E5B9), (27, 0x94D049BB133111EB), 31)
"""SplitMix64's finaliser (Steele et al. 2014, "Fast splittable pseudorandom number
generators", OOPSLA): xor-shift by 30, multiply, by 27, multiply, by 31."""


@dataclass(frozen=True)
class Drift:
    """The field's motion: ``speed_m_s`` toward ``toward_deg`` (world azimuth from +x toward
    +y, degrees), and the time ``time_s`` (s) at which the field is read."""

    speed_m_s: float = 0.0
    toward_deg: float = 0.0
    time_s: float = 0.0

    @property
    def unit(self) -> tuple[float, float]:
        """The drift direction as a unit vector (x, y)."""
        az = math.radians(self.toward_deg)
        return math.cos(az), math.sin(az)

    def shifted(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Where the air now at ``(x, y)`` was at time 0 (m)."""
        ux, uy = self.unit
        travelled = self.speed_m_s * self.time_s
        return x - ux * travelled, y - uy * travelled


@dataclass(frozen=True)
class Patches:
    """Fractal patches of denser and thinner fog (module docstring)."""

    correlation_m: float
    """``L``: correlation length along the drift direction (m)."""
    anisotropy: float
    """``A ≥ 1``: how many times shorter the patches are across the drift direction."""
    vertical_m: float
    """``L_z``: vertical correlation length (m)."""
    density_ratio: float
    """``R ≥ 1``: the densest point's density over the thinnest's."""
    seed: int

    def modulation(self, x: np.ndarray, y: np.ndarray, z: np.ndarray, along: tuple[float, float]):
        """``m`` at world points ``(x, y, z)`` (m, at time 0), patches stretched along the unit
        vector ``along`` (x, y)."""
        ux, uy = along
        u = x * ux + y * uy
        v = -x * uy + y * ux
        q = (
            u / self.correlation_m,
            v * self.anisotropy / self.correlation_m,
            np.asarray(z, np.float64) / self.vertical_m,
        )
        amplitude = 0.5 * math.log(self.density_ratio)
        return np.exp(amplitude * fractal_noise(*q, seed=self.seed))


@dataclass(frozen=True)
class Bank:
    """A fog bank whose edge lies across a bearing (module docstring)."""

    distance_m: float
    """``D``: horizontal distance of the edge from the camera's starting point (m)."""
    toward_deg: float
    """World azimuth (deg, from +x toward +y) from the camera's starting point into the bank."""
    edge_m: float
    """``w``: width scale of the edge (m)."""
    near_ratio: float
    """``r``: density on the camera's side of the edge relative to inside the bank."""
    origin_xy: tuple[float, float] = (0.0, 0.0)
    """The camera's starting point (m)."""

    def beyond(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Metres past the edge of world points ``(x, y)`` (m, at time 0): their distance along
        the bearing from the camera's starting point less ``D`` (negative: the camera's side)."""
        az = math.radians(self.toward_deg)
        s = (x - self.origin_xy[0]) * math.cos(az) + (y - self.origin_xy[1]) * math.sin(az)
        return s - self.distance_m

    def modulation(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """``m`` at world points ``(x, y)`` (m, at time 0)."""
        step = 0.5 * (1.0 + np.tanh(0.5 * self.beyond(x, y) / self.edge_m))  # logistic
        return self.near_ratio + (1.0 - self.near_ratio) * step


@dataclass(frozen=True)
class HazeField:
    """The modulation of a haze's density: patches and/or a bank, drifting."""

    patches: Patches | None = None
    bank: Bank | None = None
    drift: Drift = Drift()

    def modulation(self, x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
        """``m(x, y, z)`` at the drift's time (dimensionless, > 0), float64."""
        x0, y0 = self.drift.shifted(np.asarray(x, np.float64), np.asarray(y, np.float64))
        m = np.ones(np.broadcast_shapes(np.shape(x0), np.shape(z)))
        if self.patches is not None:
            m = m * self.patches.modulation(x0, y0, z, self.drift.unit)
        if self.bank is not None:
            m = m * self.bank.modulation(x0, y0)
        return m

    def smallest_scale_m(self) -> float:
        """The shortest length over which ``m`` changes (m), horizontally or vertically."""
        return min(self.scales_m())

    def scales_m(self) -> tuple[float, float]:
        """The shortest horizontal and vertical lengths over which ``m`` changes (m): what a
        quadrature must resolve (the finest octave of the patches across the drift and in
        height, the bank's edge)."""
        horizontal = vertical = math.inf
        if self.patches is not None:
            finest = 2.0 ** (OCTAVES - 1)
            p = self.patches
            horizontal = p.correlation_m / p.anisotropy / finest
            vertical = p.vertical_m / finest
        if self.bank is not None:
            horizontal = min(horizontal, self.bank.edge_m)
        return horizontal, vertical


def fractal_noise(qx: np.ndarray, qy: np.ndarray, qz: np.ndarray, seed: int) -> np.ndarray:
    """Fractal value noise in ``[−1, 1]`` at lattice coordinates ``q`` (module docstring)."""
    total = np.zeros(np.broadcast_shapes(np.shape(qx), np.shape(qy), np.shape(qz)))
    weight_sum = 0.0
    for octave in range(OCTAVES):
        scale, weight = 2.0**octave, 0.5**octave
        octave_seed = seed + OCTAVE_SEED_STEP * octave
        total += weight * value_noise(qx * scale, qy * scale, qz * scale, octave_seed)
        weight_sum += weight
    return total / weight_sum


def value_noise(qx: np.ndarray, qy: np.ndarray, qz: np.ndarray, seed: int) -> np.ndarray:
    """Value noise in ``[−1, 1]``: hashed lattice values blended with the quintic fade
    ``6t⁵ − 15t⁴ + 10t³`` (continuous first and second derivatives)."""
    q = [np.asarray(c, np.float64) for c in (qx, qy, qz)]
    base = [np.floor(c) for c in q]
    fade = [_fade(c - b) for c, b in zip(q, base, strict=True)]
    cells = [b.astype(np.int64) for b in base]
    # On a lattice plane of z (the clouds' and the streaks' 2-D noise) the four corners above
    # weigh exactly 0: leaving them out halves the hashing and changes no bit.
    corners = 4 if not np.any(fade[2]) else 8
    out = 0.0
    for corner in range(corners):
        offsets = [(corner >> axis) & 1 for axis in range(3)]
        weight = 1.0
        for f, o in zip(fade, offsets, strict=True):
            weight = weight * (f if o else 1.0 - f)
        ix, iy, iz = (c + o for c, o in zip(cells, offsets, strict=True))
        out = out + weight * lattice_value(ix, iy, iz, seed)
    return out


def lattice_value(ix: np.ndarray, iy: np.ndarray, iz: np.ndarray, seed: int) -> np.ndarray:
    """A value in ``[−1, 1]`` for each integer lattice point, from a 64-bit integer hash
    (SplitMix64's finaliser) of the point and ``seed``: the same everywhere, every time."""
    mx, my, mz = (np.uint64(m) for m in LATTICE_MULTIPLIERS)
    (shift1, mul1), (shift2, mul2), shift3 = SPLITMIX_FINALISER
    with np.errstate(over="ignore"):
        # The same bits seen as unsigned (a view: no copy of the coordinates).
        h = np.asarray(ix, np.int64).view(np.uint64) * mx
        h ^= np.asarray(iy, np.int64).view(np.uint64) * my
        h ^= np.asarray(iz, np.int64).view(np.uint64) * mz
        h ^= np.uint64(seed & 0xFFFFFFFFFFFFFFFF)
        h ^= h >> np.uint64(shift1)
        h *= np.uint64(mul1)
        h ^= h >> np.uint64(shift2)
        h *= np.uint64(mul2)
        h ^= h >> np.uint64(shift3)
    return (h >> np.uint64(11)).astype(np.float64) * (2.0 / 2.0**53) - 1.0


def _fade(t: np.ndarray) -> np.ndarray:
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
