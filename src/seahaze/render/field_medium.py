"""The ``reference`` mode's medium for haze that varies across the sea: the field, exactly.

A Mitsuba medium written in Python, as Mitsuba's own Python plugins are: a subclass of
``mi.Medium`` whose extinction at a point ``x`` of level ``k`` is

    σ_t(x) = σ_k · c · ρ_v(z) · m(x, y, z)

— the density of :class:`seahaze.nonuniform.NonUniformHaze` (the vertical profile ``ρ_v``, the
drifting patches and bank ``m`` of :mod:`seahaze.haze_field`, the normalisation ``c``),
evaluated in the render kernel from the same formulas, the same lattice hash and the same
seeds. Mitsuba's ``volpath`` samples it by delta tracking against a majorant (Woodcock et al.
1965, "Techniques used in the GEM code for Monte Carlo neutronics calculations"; Mitsuba's
heterogeneous media do the same), which is unbiased for any density below the majorant: the
reference then has no resolution limit and no discretisation error — only Monte Carlo noise.
The grid volume it replaces resolved patches no finer than its cells (docs/benchmarks.md).

The majorant is the field's own bound, not a sampled maximum: fractal value noise lies in
``[−1, 1]``, so patches reach at most ``√R`` (``R`` the density ratio); a bank at most
``max(1, r)``; the vertical profile its largest value over its height. A loose majorant only
costs null collisions (about ``majorant / σ_t`` per real one), never accuracy.

Float32 against the float64 truth: positions and lattice coordinates are float32 in the
kernel (2 mm at 20 km; a lattice coordinate of a few hundred to 1e-5), the hash is the same
64-bit integer arithmetic; ``tests/test_field_medium.py`` holds the kernel's density to the
numpy one's within 1e-4. The field's functions take their float type from their arguments:
:mod:`seahaze.render.field_quadrature` evaluates them in float64.

Import this module only once a Mitsuba variant is set.
"""

from __future__ import annotations

import math
from typing import Any

import drjit as dr
import mitsuba as mi
import numpy as np

from ..haze_field import (
    LATTICE_MULTIPLIERS,
    OCTAVE_SEED_STEP,
    OCTAVES,
    SPLITMIX_FINALISER,
    Bank,
    HazeField,
    Patches,
)
from ..medium import NUMPY, HazeMedium, drjit_ops

MAJORANT_MARGIN = 1.01
"""The majorant's headroom over the field's bound: float32 rounding must never put the
extinction above it (delta tracking would then be biased)."""
PROFILE_SAMPLES = 16385
"""Heights at which the vertical profile's largest value is found (its bound)."""


# -- the field in drjit ----------------------------------------------------------------------
def lattice_value(ix: Any, iy: Any, iz: Any, seed: Any, float_type: Any) -> Any:
    """:func:`seahaze.haze_field.lattice_value` in the kernel: the same 64-bit hash of the
    lattice point (``mi.Int64``) and seed (an int, or a ``mi.UInt64`` kernel parameter), a
    value in ``[−1, 1]`` of ``float_type``."""
    mx, my, mz = LATTICE_MULTIPLIERS
    (shift1, mul1), (shift2, mul2), shift3 = SPLITMIX_FINALISER
    h = mi.UInt64(ix) * mx
    h ^= mi.UInt64(iy) * my
    h ^= mi.UInt64(iz) * mz
    h ^= seed & 0xFFFFFFFFFFFFFFFF if isinstance(seed, int) else seed
    h ^= h >> shift1
    h *= mul1
    h ^= h >> shift2
    h *= mul2
    h ^= h >> shift3
    return float_type(mi.Float64(h >> 11) * (2.0 / 2.0**53) - 1.0)


def value_noise(q: tuple[Any, Any, Any], seed: Any) -> Any:
    """:func:`seahaze.haze_field.value_noise` in the kernel: the lattice values at the eight
    corners of ``q``'s cell blended with the quintic fade (in ``q``'s float type)."""
    return _blend_corners(q, seed)


def planar_value_noise(qx: Any, qy: Any, seed: Any) -> Any:
    """:func:`value_noise` on the lattice plane ``z = 0`` (the streaks' 2-D noise): the four
    corners that weigh anything, as :func:`seahaze.haze_field.value_noise` takes them there,
    half the hashing of the eight."""
    return _blend_corners((qx, qy), seed)


def _blend_corners(q: tuple[Any, ...], seed: Any) -> Any:
    """The lattice values at the corners of ``q``'s cell (2 or 3 axes; a missing ``z`` is the
    lattice plane 0) blended with the quintic fade, in ``q``'s float type."""
    float_type = type(q[0])
    base = [dr.floor(c) for c in q]
    fade = [_fade(c - b) for c, b in zip(q, base, strict=True)]
    cells = [mi.Int64(b) for b in base]
    out = float_type(0.0)
    for corner in range(1 << len(q)):
        offsets = [(corner >> axis) & 1 for axis in range(len(q))]
        weight = float_type(1.0)
        for f, o in zip(fade, offsets, strict=True):
            weight = weight * (f if o else 1.0 - f)
        index = [c + o for c, o in zip(cells, offsets, strict=True)]
        index += [mi.Int64(0)] * (3 - len(index))
        out = dr.fma(weight, lattice_value(*index, seed, float_type), out)
    return out


def fractal_noise(q: tuple[Any, Any, Any], seed: Any) -> Any:
    """:func:`seahaze.haze_field.fractal_noise` in the kernel, in ``[−1, 1]``."""
    total, weight_sum = type(q[0])(0.0), 0.0
    for octave in range(OCTAVES):
        scale, weight = 2.0**octave, 0.5**octave
        scaled = tuple(c * scale for c in q)
        total += weight * value_noise(scaled, seed + OCTAVE_SEED_STEP * octave)
        weight_sum += weight
    return total * (1.0 / weight_sum)


def patches_modulation(
    patches: Patches, x: Any, y: Any, z: Any, along: tuple[float, float], seed: Any = None
):
    """:meth:`seahaze.haze_field.Patches.modulation` in the kernel; ``seed`` (default the
    patches' own, a literal) may be a ``mi.UInt64`` kernel parameter."""
    ux, uy = along
    u = x * ux + y * uy
    v = y * ux - x * uy
    q = (
        u * (1.0 / patches.correlation_m),
        v * (patches.anisotropy / patches.correlation_m),
        z * (1.0 / patches.vertical_m),
    )
    amplitude = 0.5 * math.log(patches.density_ratio)
    return dr.exp(amplitude * fractal_noise(q, patches.seed if seed is None else seed))


def bank_modulation(bank: Bank, x: Any, y: Any) -> Any:
    """:meth:`seahaze.haze_field.Bank.modulation` in the kernel."""
    az = math.radians(bank.toward_deg)
    s = (x - bank.origin_xy[0]) * math.cos(az) + (y - bank.origin_xy[1]) * math.sin(az)
    return bank_step(s - bank.distance_m, 0.5 / bank.edge_m, bank.near_ratio)


def bank_step(beyond: Any, half_inverse_edge: Any, near_ratio: Any) -> Any:
    """A bank's ``m`` at ``beyond`` metres past its edge (negative: on the camera's side):
    ``r + (1 − r)·L``, the logistic ``L`` written with ``tanh``; its width and ``r`` may be
    Python numbers or kernel parameters."""
    step = 0.5 * (1.0 + dr.tanh(beyond * half_inverse_edge))
    return near_ratio + (1.0 - near_ratio) * step


def field_modulation(field: HazeField, p: Any, travelled: Any, seed: Any = None) -> Any:
    """``m`` at world points ``p`` (``mi.Point3f``, or any triple of float arrays with
    ``.x``, ``.y``, ``.z``) with the field moved ``travelled`` metres along its drift (a
    kernel parameter: every frame of a sequence shares the kernel); ``seed`` as in
    :func:`patches_modulation`."""
    ux, uy = field.drift.unit
    x, y = p.x - ux * travelled, p.y - uy * travelled
    m = type(p.z)(1.0)
    if field.patches is not None:
        m *= patches_modulation(field.patches, x, y, p.z, field.drift.unit, seed)
    if field.bank is not None:
        m *= bank_modulation(field.bank, x, y)
    return m


def field_bound(field: HazeField) -> float:
    """The largest ``m`` can be: ``√R`` for patches (the noise is in ``[−1, 1]``),
    ``max(1, r)`` for a bank."""
    bound = 1.0
    if field.patches is not None:
        bound *= math.sqrt(field.patches.density_ratio)
    if field.bank is not None:
        bound *= max(1.0, field.bank.near_ratio)
    return bound


def profile_bound(profile: HazeMedium) -> float:
    """The vertical profile's largest density, over :data:`PROFILE_SAMPLES` heights."""
    z = np.linspace(profile.bottom, profile.top, PROFILE_SAMPLES)
    return float(np.max(profile.density(z, NUMPY)))


# -- the Mitsuba medium ----------------------------------------------------------------------
class FieldMedium(mi.Medium):
    """The haze ``medium`` (a :class:`seahaze.nonuniform.NonUniformHaze`) over the box from
    ``box_min`` to ``box_max`` (world corners, m), its extinction 0 until a level sets it
    through the scene parameters ``sigma_t`` (1/m, R, G, B: the level's, before the
    normalisation), ``albedo`` and ``phase_function.g``."""

    def __init__(self, medium: Any, box_min: np.ndarray, box_max: np.ndarray):
        # The phase function goes in through the properties: Mitsuba's integrators read the
        # base class's member, not a Python override of phase_function() (without it the
        # medium scattered isotropically).
        props = mi.Properties()
        props["phase"] = mi.load_dict({"type": "hg", "g": medium.g})
        super().__init__(props)
        self.m_is_homogeneous = False
        self.m_has_spectral_extinction = True
        self.haze = medium
        self.box = mi.ScalarBoundingBox3f([float(c) for c in box_min], [float(c) for c in box_max])
        self.peak = (
            medium.scale
            * profile_bound(medium.profile)
            * field_bound(medium.field)
            * MAJORANT_MARGIN
        )
        # Kernel parameters, not literals: every level, and every frame, reuses the kernel.
        self.sigma_t = dr.opaque(mi.Color3f, 0.0)
        self.albedo = dr.opaque(mi.Float, medium.albedo)
        drift = medium.field.drift
        self.travelled = dr.opaque(mi.Float, drift.speed_m_s * drift.time_s)

    def density(self, p: Any) -> Any:
        """The medium's relative density ``c ρ_v(z) m(x, y, z)`` at world points ``p``."""
        vertical = self.haze.profile.density(p.z, drjit_ops())
        return self.haze.scale * vertical * field_modulation(self.haze.field, p, self.travelled)

    def get_majorant(self, mei: Any, active: Any = True) -> Any:
        return mi.UnpolarizedSpectrum(self.sigma_t * self.peak)

    def get_scattering_coefficients(self, mei: Any, active: Any = True) -> tuple[Any, Any, Any]:
        sigma_t = mi.UnpolarizedSpectrum(self.sigma_t * self.density(mei.p))
        return sigma_t * self.albedo, self.get_majorant(mei, active) - sigma_t, sigma_t

    def intersect_aabb(self, ray: Any) -> tuple[Any, Any, Any]:
        return mi.BoundingBox3f(self.box.min, self.box.max).ray_intersect(ray)

    def traverse(self, callback: Any) -> None:
        flags = mi.ParamFlags.NonDifferentiable
        callback.put("sigma_t", self.sigma_t, flags)
        callback.put("albedo", self.albedo, flags)
        callback.put("phase_function", self.phase_function(), flags)

    def parameters_changed(self, keys: Any = None) -> None:
        dr.make_opaque(self.sigma_t, self.albedo)

    def to_string(self) -> str:
        return f"FieldMedium[peak={self.peak:.4g}, box={self.box}]"


def _fade(t: Any) -> Any:
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
