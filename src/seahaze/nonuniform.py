"""Haze that varies across the sea: a vertical profile times patches and a bank.

The medium (:class:`NonUniformHaze`) has the relative density
``ρ(x, y, z) = c · ρ_v(z) · m(x, y, z)``: ``ρ_v`` a vertical profile of
:mod:`seahaze.medium` (a homogeneous slab or a fog layer, 1 at the camera's height), ``m`` the
drifting patches and bank of :mod:`seahaze.haze_field`, and ``c`` the normalisation that keeps
a level's meaning.

What a level means
    ``c`` makes the mean of ``ρ`` over the *view's horizontal fan* equal 1: the horizontal
    lines of sight at the camera's height across the image's horizontal field of view, from
    the camera out to :data:`VIEW_REACH_M`, averaged over azimuth and distance alike. So a
    level's ``σ = 3.912/V`` is the mean extinction along the horizontal line of sight at
    camera height over the view, and a patchy or banked scene at ``V`` holds as much haze in
    view as the uniform one (docs/physics.md, "Haze that varies across the sea").

Optical depths
    Along a ray the reduced length ``ℓ = ∫ ρ ds`` has no closed form: it is integrated by
    composite three-point Gauss–Legendre quadrature over the part of the ray between the
    profile's bottom and top, in panels no longer than the field's horizontal scale, nor than
    its vertical scale and a quarter of a fog edge's thickness over the ray's climb per metre
    (:meth:`seahaze.haze_field.HazeField.scales_m`): deterministic, no Monte Carlo noise
    (``asm``, the ``transmission/`` maps and ``meta``). ``tests/test_nonuniform.py`` holds it
    to Simpson's rule on 0.1 m steps within 1e-4. Here numpy sums the points; a render sums
    the same panels in one drjit kernel (:attr:`NonUniformHaze.quadrature`,
    :mod:`seahaze.render.field_quadrature`), held to the same rule.

Modes
    ``asm`` composites with these per-pixel optical depths; ``reference`` path-traces the
    field itself, evaluated exactly in the render kernel
    (:class:`seahaze.render.field_medium.FieldMedium`: no grid, only Monte Carlo noise). The
    ``physical`` mode's estimators rest on a density that varies with height alone: it renders
    each pixel's equivalent profile, :attr:`NonUniformHaze.profile` scaled by the pixel's
    density ratio (:mod:`seahaze.render.pixel_density`).
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass, replace
from dataclasses import field as dataclass_field
from typing import Any, Protocol

import numpy as np

from .haze_field import HazeField
from .medium import NUMPY, ArrayOps, HazeMedium

RAY_REACH_M = 20_000.0
"""How far a ray is followed (m; the sky's rays end here): every graded level's transmittance
of a horizontal ray is below 3e-9 by then (as :data:`seahaze.render.transmission.SKY_REACH_M`)."""
VIEW_REACH_M = 4000.0
"""How far the view's horizontal fan reaches for the normalisation (m): the clearest graded
visibility."""
FAN_AZIMUTHS = 64
"""Azimuths of the view's horizontal fan (midpoints across the field of view)."""
GAUSS_NODES = np.array([-math.sqrt(0.6), 0.0, math.sqrt(0.6)])
GAUSS_WEIGHTS = np.array([5.0, 8.0, 5.0]) / 9.0
MAX_POINTS_PER_CHUNK = 1 << 20
"""Quadrature points evaluated at once (about 0.3 GB of temporaries)."""


class PointDensity(Protocol):
    """``ρ = c ρ_v(z) m(x, y, z)`` (float64, the points' shape) of a :class:`NonUniformHaze` at
    world points ``x``, ``y``, ``z`` (m, arrays of one shape)."""

    def __call__(
        self, medium: NonUniformHaze, x: np.ndarray, y: np.ndarray, z: np.ndarray
    ) -> np.ndarray: ...


class RayQuadrature(Protocol):
    """Sums a :class:`NonUniformHaze`'s quadrature: ``∫ c ρ_v m ds`` (m, (N,) float64) along
    each ray ``origins + s·directions`` ((N, 3), unit directions) over ``s`` from ``enter`` to
    ``enter + length`` (m, (N,)), in ``panels`` (N,) equal panels of the three
    Gauss–Legendre nodes :data:`GAUSS_NODES` (0 panels: 0)."""

    def __call__(
        self,
        medium: NonUniformHaze,
        origins: np.ndarray,
        directions: np.ndarray,
        enter: np.ndarray,
        length: np.ndarray,
        panels: np.ndarray,
    ) -> np.ndarray: ...


@dataclass(frozen=True)
class HorizontalView:
    """The camera's horizontal fan: its position (m) and the azimuths it sees (deg)."""

    x_m: float
    y_m: float
    height_m: float
    heading_deg: float
    fov_deg: float


@dataclass(frozen=True)
class NonUniformHaze(HazeMedium):
    """``c · ρ_v(z) · m(x, y, z)`` (module docstring). Vertical questions (bounds, optics)
    are the profile's; ``reduced_length`` and friends, which assume a density that varies
    with height alone, are not available (the ``physical`` mode asks the profile, per pixel:
    :mod:`seahaze.render.pixel_density`)."""

    profile: HazeMedium
    field: HazeField
    scale: float = 1.0
    # The last rays' path lengths (not part of the medium's identity).
    _lengths_cache: dict[str, np.ndarray] = dataclass_field(
        default_factory=dict, compare=False, repr=False
    )
    quadrature: RayQuadrature | None = dataclass_field(default=None, compare=False, repr=False)
    """What sums the quadrature's points (:class:`RayQuadrature`); None: numpy, here. The
    render layer passes its drjit kernel (:mod:`seahaze.render.field_quadrature`)."""
    point_density: PointDensity | None = dataclass_field(default=None, compare=False, repr=False)
    """What evaluates :meth:`density_at` (:class:`PointDensity`); None: numpy, here. The
    render layer passes its drjit kernel, the same formulas in float64 (its diffuse ratios
    read millions of points a frame)."""

    @property
    def albedo(self) -> float:  # type: ignore[override]
        return self.profile.albedo

    @property
    def g(self) -> float:  # type: ignore[override]
        return self.profile.g

    @property
    def bottom(self) -> float:  # type: ignore[override]
        return self.profile.bottom

    @property
    def top(self) -> float:  # type: ignore[override]
        return self.profile.top

    def with_optics(self, albedo: float, g: float) -> HazeMedium:
        # The same density: the cached path lengths still hold.
        return replace(self, profile=self.profile.with_optics(albedo, g))

    # -- the density and optical depths ------------------------------------------------------
    def density_at(self, x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
        """``ρ`` at world points (m), float64."""
        if self.point_density is not None:
            return self.point_density(self, x, y, z)
        vertical = np.asarray(self.profile.density(np.asarray(z, np.float64), NUMPY))
        return self.scale * vertical * self.field.modulation(x, y, z)

    def ray_path_length(
        self, origin: np.ndarray, directions: np.ndarray, distance_m: np.ndarray
    ) -> np.ndarray:
        """``∫₀ᵈ ρ ds`` (m) of rays from ``origin`` (3,) along unit ``directions`` (..., 3) to
        ``distance_m`` (...; at most :data:`RAY_REACH_M`, the sky's ``inf`` included):
        composite Gauss–Legendre (module docstring). The last results are kept: every level
        of a scene asks for the same rays."""
        origin = np.asarray(origin, np.float64)
        directions = np.asarray(directions, np.float64)
        shape = directions.shape[:-1]
        dist = np.minimum(np.broadcast_to(np.asarray(distance_m, np.float64), shape), RAY_REACH_M)
        key = _digest(origin, directions, dist)
        if key not in self._lengths_cache:
            if len(self._lengths_cache) > 4:
                self._lengths_cache.clear()
            self._lengths_cache[key] = self._path_lengths(origin, directions, dist)
        return self._lengths_cache[key].copy()

    def _path_lengths(
        self, origin: np.ndarray, directions: np.ndarray, distance_m: np.ndarray
    ) -> np.ndarray:
        shape = directions.shape[:-1]
        d = directions.reshape(-1, 3)
        dist = distance_m.reshape(-1)
        oz = np.full(len(d), float(origin[2]))
        enter, leave = self.profile.span(oz, d[:, 2], NUMPY)
        leave = np.minimum(leave, dist)
        length = np.maximum(leave - enter, 0.0)
        origins = np.broadcast_to(np.asarray(origin, np.float64), d.shape)
        return self.lengths_along(origins, d, enter, length).reshape(shape)

    def lengths_along(
        self, origins: np.ndarray, directions: np.ndarray, enter: np.ndarray, length: np.ndarray
    ) -> np.ndarray:
        """``∫ ρ ds`` (m, (N,) float64) along each ray ``origins + s·directions`` ((N, 3),
        unit directions) over ``s`` from ``enter`` to ``enter + length`` (m, (N,)): the
        module's quadrature (:meth:`panel_counts` panels of three Gauss–Legendre nodes),
        summed by :attr:`quadrature`, or here by numpy."""
        counts = self.panel_counts(length, directions[:, 2])
        if self.quadrature is not None:
            return self.quadrature(self, origins, directions, enter, length, counts)
        out = np.zeros(len(directions))
        # Rays grouped by their panel count: one array shape per group.
        for count in np.unique(counts[counts > 0]):
            rays = np.flatnonzero(counts == count)
            per_chunk = max(1, MAX_POINTS_PER_CHUNK // (3 * int(count)))
            for start in range(0, len(rays), per_chunk):
                chosen = rays[start : start + per_chunk]
                out[chosen] = self._integrate(
                    origins[chosen], directions[chosen], enter[chosen], length[chosen], count
                )
        return out

    def panel_counts(self, length: np.ndarray, dz: np.ndarray) -> np.ndarray:
        """How many panels the quadrature takes over ``length`` (m) of rays with direction z
        components ``dz``: enough that none is longer than :meth:`panel_length`, rounded up
        to a power of two (few distinct counts; on average about 1.4 times the least, which
        keeps the quadrature within 1e-4 of the field's integral); 0 for no length."""
        least = np.ceil(np.asarray(length, np.float64) / self.panel_length(dz))
        return np.where(least > 0, 2 ** np.ceil(np.log2(np.maximum(least, 1))), 0).astype(np.int64)

    def panel_length(self, dz: np.ndarray) -> np.ndarray:
        """Longest panel along a ray with direction z component ``dz`` (m): the field's
        horizontal scale, its vertical scale and a quarter of a fog layer's edge over the
        height the ray climbs per metre."""
        horizontal, vertical = self.field.scales_m()
        edge = getattr(self.profile, "edge", math.inf)  # a fog layer's top edge (m)
        climb = np.maximum(np.abs(dz), 1e-12)
        panel = np.minimum(horizontal, np.minimum(vertical, 0.25 * edge) / climb)
        return np.minimum(panel, VIEW_REACH_M / 8.0)

    def _integrate(
        self,
        origins: np.ndarray,
        d: np.ndarray,
        enter: np.ndarray,
        length: np.ndarray,
        panels: int,
    ) -> np.ndarray:
        """Composite 3-point Gauss–Legendre over ``panels`` equal panels of each ray's
        ``[enter, enter + length]``."""
        width = length / panels  # (rays,)
        mids = (np.arange(panels) + 0.5)[None, :] * width[:, None]  # (rays, panels)
        s = enter[:, None, None] + mids[..., None] + 0.5 * width[:, None, None] * GAUSS_NODES
        p = origins[:, None, None, :] + s[..., None] * d[:, None, None, :]
        rho = self.density_at(p[..., 0], p[..., 1], p[..., 2])
        return 0.5 * width * np.einsum("rpk,k->r", rho, GAUSS_WEIGHTS)

    def path_length(self, origin_z: float, dirs_z: np.ndarray, distance_m: np.ndarray):
        raise NotImplementedError(
            "a haze that varies across the sea needs whole rays: use ray_path_length"
        )

    def thinnest_horizontal_mean(self, camera: Any, reach_m: float) -> float:
        view = HorizontalView(
            camera.x_m, camera.y_m, camera.height_m, camera.heading_deg, camera.fov_deg
        )
        means = fan_means(self, view, reach_m)
        return float(means.min())

    # -- the reference mode's Mitsuba medium ---------------------------------------------------
    def mitsuba_medium(self, box_min: np.ndarray, box_max: np.ndarray) -> Any:
        """The field itself as a Mitsuba medium over the haze box (world corners ``box_min``,
        ``box_max``, m): :class:`seahaze.render.field_medium.FieldMedium`, evaluated exactly
        in the render kernel (no grid); its extinction 0 until a level sets it."""
        from .render.field_medium import FieldMedium

        return FieldMedium(self, box_min, box_max)

    def mitsuba_level(self, sigma_rgb: np.ndarray, albedo: float, g: float) -> dict[str, Any]:
        import mitsuba as mi

        return {
            "sigma_t": mi.Color3f(*(float(c) for c in sigma_rgb)),
            "albedo": albedo,
            "phase_function.g": g,
        }

    def density_grid_over(
        self, box_min: np.ndarray, box_max: np.ndarray, shape: tuple[int, int, int]
    ) -> np.ndarray:
        """(z, y, x) float32: the density at the centres of ``shape`` cells over the box from
        ``box_min`` to ``box_max`` (world corners, m): what a grid volume of the field would
        hold (``scripts/bench_nonuniform.py`` measures such grids' error)."""
        axes = [
            lo + (np.arange(n) + 0.5) / n * (hi - lo)
            for lo, hi, n in zip(box_min[::-1], box_max[::-1], shape, strict=True)
        ]
        grid = np.empty(shape, np.float32)
        for k, z in enumerate(axes[0]):  # a slab of cells at a time: bounded memory
            y, x = np.meshgrid(axes[1], axes[2], indexing="ij")
            grid[k] = self.density_at(x, y, np.full_like(x, z))
        return grid

    def describe(self) -> dict[str, Any]:
        field = self.field
        out = {**self.profile.describe(), "kind": "NonUniformHaze", "density_scale": self.scale}
        out["profile"] = type(self.profile).__name__
        if field.patches is not None:
            p = field.patches
            out["patches"] = {
                "correlation_m": p.correlation_m,
                "anisotropy": p.anisotropy,
                "vertical_m": p.vertical_m,
                "density_ratio": p.density_ratio,
                "seed": p.seed,
            }
        if field.bank is not None:
            b = field.bank
            out["bank"] = {
                "distance_m": b.distance_m,
                "toward_deg": b.toward_deg,
                "edge_m": b.edge_m,
                "near_ratio": b.near_ratio,
                "origin_xy_m": list(b.origin_xy),
            }
        out["drift"] = {
            "speed_m_s": field.drift.speed_m_s,
            "toward_deg": field.drift.toward_deg,
            "time_s": field.drift.time_s,
        }
        return out

    # -- what a density of height alone would answer: not this medium's ----------------------
    @property
    def reduced_is_geometric(self) -> bool:
        return False

    @property
    def reduced_top_m(self) -> float:
        raise NotImplementedError(_PHYSICAL)

    def reduced_height(self, z: Any, ops: ArrayOps) -> Any:
        raise NotImplementedError(_PHYSICAL)

    def distance_at(self, oz: Any, dz: Any, enter: Any, reduced: Any, ops: ArrayOps) -> Any:
        raise NotImplementedError(_PHYSICAL)

    def density(self, z: Any, ops: ArrayOps) -> Any:
        raise NotImplementedError("the density varies across the sea: use density_at")

    def span(self, oz: Any, dz: Any, ops: ArrayOps) -> tuple[Any, Any]:
        return self.profile.span(oz, dz, ops)

    def reduced_length(self, oz: Any, dz: Any, t_end: Any, ops: ArrayOps) -> tuple[Any, Any]:
        raise NotImplementedError(_PHYSICAL)


_PHYSICAL = "the density varies across the sea: ask the profile, scaled per pixel"


def _digest(*arrays: np.ndarray) -> str:
    """A key for the rays of :meth:`NonUniformHaze.ray_path_length`'s cache."""
    h = hashlib.blake2b(digest_size=16)
    for a in arrays:
        h.update(np.ascontiguousarray(a).tobytes())
        h.update(str(a.shape).encode())
    return h.hexdigest()


def fan_mean(medium: NonUniformHaze, view: HorizontalView) -> float:
    """The mean of ``medium``'s density over the view's horizontal fan (module docstring):
    midpoints of :data:`FAN_AZIMUTHS` azimuths × distance steps no longer than half the
    field's smallest scale, out to :data:`VIEW_REACH_M`."""
    return float(np.mean(fan_means(medium, view, VIEW_REACH_M)))


def fan_means(medium: NonUniformHaze, view: HorizontalView, reach_m: float) -> np.ndarray:
    """The mean density along each of :data:`FAN_AZIMUTHS` horizontal lines of sight at the
    view's height across its field of view, out to ``reach_m`` (midpoint rule, steps no
    longer than half the field's smallest scale)."""
    across = (np.arange(FAN_AZIMUTHS) + 0.5) / FAN_AZIMUTHS - 0.5
    azimuths = view.heading_deg + view.fov_deg * across
    steps = max(512, math.ceil(reach_m / (0.5 * medium.field.smallest_scale_m())))
    r = (np.arange(steps) + 0.5) / steps * reach_m
    az = np.radians(azimuths)[:, None]
    x, y = view.x_m + r * np.cos(az), view.y_m + r * np.sin(az)
    z = np.full_like(x, view.height_m)
    return np.mean(medium.density_at(x, y, z), axis=1)


def nonuniform_haze(profile: HazeMedium, field: HazeField, view: HorizontalView) -> NonUniformHaze:
    """The medium whose mean density over ``view``'s horizontal fan is 1."""
    raw = NonUniformHaze(profile, field, 1.0)
    return NonUniformHaze(profile, field, 1.0 / fan_mean(raw, view))
