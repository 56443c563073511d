"""The haze medium: everything a renderer asks about where the haze is and how thick.

Every consumer — the ``physical`` pass and its vessel-light pass, the photon tracer of the
diffuse tables, the ``asm`` composite, the ``reference`` scene's Mitsuba medium, ``verify`` and
the cost model — asks a :class:`HazeMedium` instead of computing with the slab itself, so that
"what is σ here" has one answer and a new kind of haze is one new class (docs/architecture.md,
"Adding a kind of haze").

Levels and the medium
    A pass renders several levels at once. Level ``k`` has the extinction ``σ_k`` (1/m, per
    channel R, G, B) of its visibility (:mod:`seahaze.visibility`); the medium gives its shape,
    a relative density ``ρ(z)`` (dimensionless) that varies with height alone, so the level's
    extinction at ``x`` is ``σ_k ρ(z)``. The optical depth of a ray over ``[0, t]`` is then
    ``τ_k = σ_k ℓ`` with the *reduced length* ``ℓ = ∫₀ᵗ ρ ds`` (m), one number for every
    level: the levels of a pass share their geometry and differ only by ``σ_k``.

A vertical profile is a homogeneous slab in reduced height
    Measure height by the *reduced height* ``h(z) = ∫₀ᶻ ρ dz'`` (m; 0 at the sea). Along a
    straight ray ``dℓ = ρ ds`` and ``dh = ρ dz = d_z dℓ``: in (reduced length, reduced height)
    a ray is a straight line with the same direction cosine, and every medium of this interface
    is the homogeneous slab ``h ≤ H = h(top)`` of extinction ``σ_k``. So the ``physical``
    mode's closed forms (transmittance, in-scattering drawn along reduced length, the sun's
    single scattering with a depth toward the sun ``(H − h)/μ_sun``) and its diffuse tables
    (traced in the slab of height ``H``, looked up at ``h/H``) hold exactly for any profile; a
    point at reduced distance ``ℓ`` is found by :meth:`HazeMedium.distance_at`. A medium that
    also varies horizontally (patches, banks) is not of this kind.

One definition for numpy and drjit
    The formulas are written once against :class:`ArrayOps`, the handful of array operations
    they need; :data:`NUMPY` (float64, for ``asm``, ``verify`` and the tests) and
    :func:`drjit_ops` (float32, traced into the ``physical`` kernels) implement them. Where the
    two must differ (a horizontal ray is ``|d_z| < 1e-12`` in float64 but ``< 1e-7`` for
    float32 directions) the difference is an attribute of the ops, not a second formula.
    ``tests/reference_tracer.py`` keeps its own slab on purpose: an independent check.

The homogeneous slab (:class:`HomogeneousSlab`)
    ``ρ = 1`` for ``bottom ≤ z ≤ top`` (metres), 0 elsewhere, horizontally unbounded. A straight
    ray ``o + s·d`` is inside it for ``s`` in one interval, and transmittance over a length
    ``ℓ`` of it is ``exp(−σ ℓ)`` (Beer–Lambert). Its bottom lies below the sea surface
    (:data:`HAZE_BOTTOM_M`), which hides everything beneath. The sun's single scattering along
    a segment has a closed form there (:func:`sun_scattered_fraction`).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import cache
from typing import Any

import numpy as np

HAZE_BOTTOM_M = -60.0
"""Bottom of the haze layer below sea level (m); the sea surface hides everything beneath it."""
TINY_OPTICAL_DEPTH = 1e-3
"""Below this, ``1 − e^{−τ}`` is evaluated by its series (float32 cancellation)."""
GRID_CELLS = 1024
"""Height cells of the ``reference`` mode's grid volume of a medium's density
(:meth:`HazeMedium.mitsuba_medium`), interpolated linearly between their centres: a profile
that changes over a few cells is smeared over them, and a sharp step at a cell boundary keeps a
ray's optical depth (the ramp is symmetric about it). How close the grid comes to a fog layer
is measured in docs/benchmarks.md ("How closely does the reference's grid volume follow a fog
layer?")."""


@dataclass(frozen=True)
class ArrayOps:
    """The array operations the medium's formulas use, for one array library."""

    exp: Callable[[Any], Any]
    log: Callable[[Any], Any]
    abs: Callable[[Any], Any]
    minimum: Callable[[Any, Any], Any]
    maximum: Callable[[Any, Any], Any]
    select: Callable[[Any, Any, Any], Any]
    divide: Callable[[Any, Any], Any]
    inf: float
    flat_dz: float
    """A ray with ``|d_z|`` below this is horizontal for a layer (the directions' precision)."""


def _numpy_divide(a: Any, b: Any) -> Any:
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.divide(a, b)


NUMPY = ArrayOps(
    exp=np.exp,
    log=np.log,
    abs=np.abs,
    minimum=np.minimum,
    maximum=np.maximum,
    select=np.where,
    divide=_numpy_divide,
    inf=np.inf,
    flat_dz=1e-12,
)
"""numpy, float64: the ``asm`` composite, ``verify`` and tests."""


@cache
def drjit_ops() -> ArrayOps:
    """drjit (the active Mitsuba variant's arrays, float32): traced into the kernels. A
    division is a multiplication by the reciprocal, which drjit's value numbering computes once
    for the several numerators of one denominator."""
    import drjit as dr

    return ArrayOps(
        exp=dr.exp,
        log=dr.log,
        abs=dr.abs,
        minimum=dr.minimum,
        maximum=dr.maximum,
        select=dr.select,
        divide=lambda a, b: a * dr.rcp(b),
        inf=dr.inf,
        flat_dz=1e-7,
    )


def one_minus_exp(tau: Any, ops: ArrayOps) -> Any:
    """``1 − e^{−τ}``, accurate for small ``τ`` (its series below :data:`TINY_OPTICAL_DEPTH`)
    and 1 for ``τ = ∞``."""
    return ops.select(tau < TINY_OPTICAL_DEPTH, tau * (1.0 - 0.5 * tau), 1.0 - ops.exp(-tau))


def transmittance(sigma: Any, length: Any, ops: ArrayOps) -> Any:
    """Beer–Lambert transmittance ``exp(−σ ℓ)`` of extinction ``sigma`` (1/m, per level; grey
    or RGB) over reduced length ``length`` (m). Written as ``exp(−(σ ℓ))``, as
    :func:`one_minus_exp` is, so that the two share one exponential in a kernel."""
    return ops.exp(-(sigma * length))


def distance_in_mass(u: Any, sigma: Any, inv_sigma: Any, mass: Any, length: Any, ops: ArrayOps):
    """The reduced distance in ``[0, length]`` at which a fraction ``u`` (0–1) of a level's
    scattering mass ``mass = 1 − e^{−σ ℓ}`` lies: distances drawn with uniform ``u`` follow the
    level's transmittance, density ``σ e^{−σ s} / mass`` (1/m). ``inv_sigma`` is ``1/σ``."""
    return ops.minimum(-ops.log(ops.maximum(1.0 - u * mass, 1e-30)) * inv_sigma, length)


def sun_scattered_fraction(
    sigma: Any, near: Any, e_start: Any, climb: Any, inv_climb: Any, length: Any, ops: ArrayOps
) -> Any:
    """In a homogeneous slab (so in any medium, in reduced length and height),
    ``σ ∫₀^ℓ e^{−(τ₀ + σ c s)} ds``: per unit of the sun's source, the light scattered toward
    a segment's start by its first ``length`` metres, each point's light attenuated on its way
    from the sun and on to the start. At distance ``s`` the two paths have optical depth
    ``τ₀ + σ c s``: ``τ₀ = e_start`` toward the sun from the start (``near`` = ``e^{−τ₀}``),
    plus ``σ s`` back to the start, less ``σ s d_z / μ_sun`` toward the sun
    (``c = climb = 1 − d_z / μ_sun``, negative where the segment climbs more steeply than the
    sun). In closed form ``(near − e^{−(τ₀ + σ c ℓ)}) / c``, by its series where ``σ c ℓ`` is
    too small for float32. ``inv_climb`` = ``1 / c``, computed once for every level;
    ``sigma`` may be RGB."""
    x = sigma * climb * length
    far = ops.exp(-ops.maximum(e_start + x, 0.0))  # τ at the end is >= 0: never overflows
    series = sigma * near * length * (1.0 - 0.5 * x)
    return ops.select(ops.abs(x) < TINY_OPTICAL_DEPTH, series, (near - far) * inv_climb)


def grid_medium_dict(
    grid: Any, box_min: np.ndarray, box_max: np.ndarray, albedo: float, g: float
) -> dict[str, Any]:
    """A Mitsuba ``heterogeneous`` medium over the ``mi.VolumeGrid`` ``grid`` stretched over the
    box from ``box_min`` to ``box_max`` (world corners, m), trilinear, with single-scattering
    ``albedo`` and a Henyey–Greenstein phase function of asymmetry ``g``.

    The grid is looked up in full float32 arithmetic on every variant (``accel`` off): on a GPU
    Mitsuba would otherwise use the texture units, whose interpolation weights have 8 bits of
    fraction (CUDA Programming Guide, "Texture fetching", linear filtering), so the reference
    would differ from the CPU's beyond float precision."""
    import mitsuba as mi

    box_min, box_max = np.asarray(box_min, np.float64), np.asarray(box_max, np.float64)
    to_world = (
        mi.ScalarTransform4f().translate(box_min.tolist()).scale((box_max - box_min).tolist())
    )
    return {
        "type": "heterogeneous",
        "albedo": albedo,
        "sigma_t": {
            "type": "gridvolume",
            "grid": grid,
            "filter_type": "trilinear",
            "accel": False,
            "to_world": to_world,
        },
        "scale": 1.0,
        "phase": {"type": "hg", "g": g},
    }


class HazeMedium(ABC):
    """What a renderer asks of a haze: its shape as a relative density ``ρ`` (the levels scale
    it by their ``σ_k``), its bounds, reduced lengths along rays, and its single-scattering
    albedo and Henyey–Greenstein asymmetry ``g``. Methods take the arrays' :class:`ArrayOps`;
    positions and lengths are in metres."""

    albedo: float
    """Single-scattering albedo (0–1)."""
    g: float
    """Henyey–Greenstein asymmetry of the phase function (−1–1)."""

    bottom: float
    """Lowest height (m) where ``ρ`` may be non-zero (a field of every medium)."""
    top: float
    """Highest height (m) where ``ρ`` may be non-zero (a field of every medium)."""

    @property
    def bottom_m(self) -> float:
        """:attr:`bottom` (m)."""
        return self.bottom

    @property
    def top_m(self) -> float:
        """:attr:`top` (m)."""
        return self.top

    @property
    @abstractmethod
    def reduced_is_geometric(self) -> bool:
        """Whether ``ρ`` is 1 wherever it is not 0: reduced lengths are lengths, so a
        distance drawn in metres (the vessel-light pass's probes near a vessel) needs no
        conversion."""

    @property
    @abstractmethod
    def reduced_top_m(self) -> float:
        """``H = h(top)`` (m): the height of the homogeneous slab the medium is in reduced
        height (module docstring)."""

    @abstractmethod
    def reduced_height(self, z: Any, ops: ArrayOps) -> Any:
        """The reduced height ``h(z) = ∫₀ᶻ ρ dz'`` (m) of height ``z`` (m)."""

    @abstractmethod
    def distance_at(self, oz: Any, dz: Any, enter: Any, reduced: Any, ops: ArrayOps) -> Any:
        """The ray parameter (m from the ray's origin at height ``oz``, direction z component
        ``dz``) of the point ``reduced`` metres of reduced length past its entry at ``enter``
        (m; :meth:`span`)."""

    @abstractmethod
    def density(self, z: Any, ops: ArrayOps) -> Any:
        """The relative density ``ρ`` (dimensionless) at height ``z`` (m)."""

    @abstractmethod
    def span(self, oz: Any, dz: Any, ops: ArrayOps) -> tuple[Any, Any]:
        """Ray parameters ``[enter, leave]`` (m, ``enter ≥ 0``) of ``o + s·d`` between the
        medium's bounds (only heights matter: ``oz``, ``dz`` are the ray's z components);
        ``leave < enter`` where the ray never enters, ``leave = ∞`` along a horizontal ray
        inside."""

    @abstractmethod
    def reduced_length(self, oz: Any, dz: Any, t_end: Any, ops: ArrayOps) -> tuple[Any, Any]:
        """Where the ray ``o + s·d`` enters the medium (m) and its reduced length ``∫ρ ds`` (m)
        up to ``t_end`` (``∞``: to the end of the medium): a level's optical depth over it
        is ``σ_k`` times that."""

    def depth_toward_sun(self, h: Any, mu_sun: Any, ops: ArrayOps) -> Any:
        """The reduced length (m) from reduced height ``h`` out of the medium's top toward a
        sun of elevation cosine ``mu_sun > 0``: ``(H − h)/μ_sun``."""
        return ops.maximum(self.reduced_top_m - h, 0.0) / mu_sun

    def mitsuba_medium(self, box_min: np.ndarray, box_max: np.ndarray) -> dict[str, Any]:
        """The medium as a Mitsuba plugin dict filling the ``reference`` mode's haze box
        (world corners ``box_min``, ``box_max`` in m; in height the box spans the medium's
        bounds), its extinction 0 until a level sets it (:meth:`mitsuba_level`). Here a
        ``heterogeneous`` medium over a grid volume of the density at :data:`GRID_CELLS`
        heights, which serves any vertical profile; a medium with an exact Mitsuba form may
        override it."""
        import mitsuba as mi

        grid = mi.VolumeGrid(self.density_grid(np.ones(3)))
        return grid_medium_dict(grid, box_min, box_max, self.albedo, self.g)

    def mitsuba_level(self, sigma_rgb: np.ndarray, albedo: float, g: float) -> dict[str, Any]:
        """The Mitsuba scene parameters, by name below the medium's id, that make
        :meth:`mitsuba_medium` the level of extinction ``sigma_rgb`` (1/m, R, G, B) with
        ``albedo`` and ``g`` (a ``σ = 0`` level: no haze)."""
        import mitsuba as mi

        return {
            "sigma_t.data": mi.TensorXf(self.density_grid(np.asarray(sigma_rgb, np.float64))),
            "albedo.value.value": albedo,
            "phase_function.g": g,
        }

    def density_grid(self, rgb: np.ndarray) -> np.ndarray:
        """(cells, 1, 1, 3) float32: the density at the centres of :data:`GRID_CELLS` height
        cells from :attr:`bottom` to :attr:`top`, times ``rgb`` (the grid volume's layout:
        z, y, x, channel)."""
        z = self.bottom + (np.arange(GRID_CELLS) + 0.5) / GRID_CELLS * (self.top - self.bottom)
        rho = np.asarray(self.density(z, NUMPY), np.float64)
        return (rho[:, None] * rgb[None, :]).astype(np.float32).reshape(GRID_CELLS, 1, 1, 3)

    def path_length(self, origin_z: float, dirs_z: np.ndarray, distance_m: np.ndarray):
        """numpy: the reduced length (m) of each ray from a camera at height ``origin_z`` with
        direction z components ``dirs_z`` up to its surface ``distance_m`` (``inf``: the sky).
        The per-pixel optical depth of level ``k`` is ``σ_k`` times it (the ``asm`` mode)."""
        dz = np.asarray(dirs_z, dtype=np.float64)
        oz = np.full_like(dz, float(origin_z))
        _, length = self.reduced_length(oz, dz, np.asarray(distance_m, np.float64), NUMPY)
        return np.maximum(length, 0.0)

    def ray_path_length(
        self, origin: np.ndarray, directions: np.ndarray, distance_m: np.ndarray
    ) -> np.ndarray:
        """numpy: the reduced length (m) of rays from ``origin`` (3,) along unit
        ``directions`` (..., 3) up to ``distance_m`` (...; ``inf``: the sky). A medium of
        height alone needs only heights (:meth:`path_length`); one that varies across the sea
        overrides it."""
        dirs_z = np.asarray(directions)[..., 2]
        return self.path_length(float(origin[2]), dirs_z, distance_m)

    def thinnest_horizontal_mean(self, camera: Any, reach_m: float) -> float:
        """The least mean relative density along the horizontal lines of sight at the
        ``camera``'s height across its view, out to ``reach_m`` (m): how much thinner than
        ``σ`` the haze box's walls may be seen through. 1 for a medium of height alone (its
        density is 1 at the camera's height)."""
        return 1.0

    def with_optics(self, albedo: float, g: float) -> HazeMedium:
        """The same shape with another single-scattering ``albedo`` and asymmetry ``g``
        (a dataclass medium gets this for free; another must override it)."""
        return replace(self, albedo=float(albedo), g=float(g))  # type: ignore[type-var]

    def describe(self) -> dict[str, Any]:
        """The medium as plain data for a dataset's ``meta`` and ``dataset.json``."""
        return {
            "kind": type(self).__name__,
            "albedo": self.albedo,
            "g": self.g,
            "bottom_m": self.bottom,
            "top_m": self.top,
        }


@dataclass(frozen=True)
class HomogeneousSlab(HazeMedium):
    """A homogeneous layer ``bottom ≤ z ≤ top`` (m), horizontally unbounded (see the module
    docstring)."""

    top: float
    albedo: float = 0.998
    g: float = 0.75
    bottom: float = HAZE_BOTTOM_M

    def __post_init__(self) -> None:
        if not self.top > self.bottom:
            raise ValueError(f"the slab's top ({self.top} m) must lie above its bottom")

    @property
    def reduced_is_geometric(self) -> bool:
        return True

    @property
    def reduced_top_m(self) -> float:
        return self.top

    def reduced_height(self, z: Any, ops: ArrayOps) -> Any:
        return z  # ρ = 1 from the bottom (below the sea) to the top: h = z

    def distance_at(self, oz: Any, dz: Any, enter: Any, reduced: Any, ops: ArrayOps) -> Any:
        return enter + reduced

    def density(self, z: Any, ops: ArrayOps) -> Any:
        return ops.select((z >= self.bottom) & (z <= self.top), 1.0, 0.0)

    def span(self, oz: Any, dz: Any, ops: ArrayOps) -> tuple[Any, Any]:
        s_bottom = ops.divide(self.bottom - oz, dz)
        s_top = ops.divide(self.top - oz, dz)
        flat = ops.abs(dz) < ops.flat_dz
        inside = (oz >= self.bottom) & (oz <= self.top)
        inf = ops.inf
        enter = ops.select(flat, ops.select(inside, 0.0, inf), ops.minimum(s_bottom, s_top))
        leave = ops.select(flat, ops.select(inside, inf, -inf), ops.maximum(s_bottom, s_top))
        return ops.maximum(enter, 0.0), leave

    def reduced_length(self, oz: Any, dz: Any, t_end: Any, ops: ArrayOps) -> tuple[Any, Any]:
        enter, leave = self.span(oz, dz, ops)
        if t_end is not None:
            leave = ops.minimum(leave, t_end)
        return enter, ops.maximum(leave - enter, 0.0)

    def mitsuba_medium(self, box_min: np.ndarray, box_max: np.ndarray) -> dict[str, Any]:
        # Exact, and cheaper to trace than a grid volume.
        return {
            "type": "homogeneous",
            # RGB so that the extinction may differ per channel (haze.extinction_spectrum).
            "sigma_t": {"type": "rgb", "value": [0.0, 0.0, 0.0]},
            "albedo": self.albedo,
            "phase": {"type": "hg", "g": self.g},
        }

    def mitsuba_level(self, sigma_rgb: np.ndarray, albedo: float, g: float) -> dict[str, Any]:
        import mitsuba as mi

        return {
            "sigma_t.value.value": mi.Color3f(*(float(c) for c in sigma_rgb)),
            "albedo.value.value": albedo,
            "phase_function.g": g,
        }
