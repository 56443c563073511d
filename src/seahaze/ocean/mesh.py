"""A camera-centred polar sea mesh that reaches far beyond the horizon.

Layout
    One centre vertex plus ``n_rings`` rings of ``n_theta`` vertices (constant angular step
    ``2·pi/n_theta``), triangulated as a fan around the centre and two triangles per ring
    segment: one connected grid with no cracks whose only boundary is the outer ring.

    * Near zone ``0 < r <= fade_end`` (``n_near`` rings): ``r(u) = s·((1 + fade_end/s)^u - 1)``,
      ``u = j/n_near``, with ``s = max(camera height, 0.5 m)``: rings are evenly spaced
      (``≈ s·ln(1 + fade_end/s)/n_near``) below the camera and geometric (spacing proportional to
      ``r + s``) further out, i.e. fine near the camera and coarse far away.
    * Far zone ``fade_end < r <= R`` (``n_far = max(8, n_rings/16)`` rings): geometric. The sea
      is flat there, so the coarse rings cost no accuracy.

Displacement fade
    Far displaced geometry aliases: once the ring spacing exceeds a fraction of the wavelength,
    the sampled waves turn into moiré. Two measures act together. (1) Band limiting: every
    vertex samples the surface through ``displacement_filtered(x, y, spacing)`` with its local
    vertex spacing (the larger of the radial and tangential spacing), which keeps waves longer
    than about 4 spacings and removes those shorter than 2 (FFT: low-pass pyramid of each
    patch; Gerstner: per-component weights). (2) An overall fade: the displacement is
    multiplied by ``w(r) = 1 - smoothstep((ln r - ln r0)/(ln r1 - ln r0))`` with
    ``r1 = fade_end = 2·r0``:
    ``w = 1`` up to ``r0 = fade_start``, 0 beyond ``r1``. ``r0`` is the radius at which the
    radial ring spacing equals ``lambda_p/6`` (six vertices per peak wavelength), so the
    dominant waves are well sampled wherever they are displaced. If the caller gives the pixel
    angle ``delta`` (rad), ``r1`` is further limited to ``2·Hs/delta``, where the largest waves
    (about ``2·Hs`` crest to trough) subtend less than one pixel. Beyond the fade the wave slopes
    belong to the BSDF (Cox–Munk roughness, :mod:`seahaze.ocean.cox_munk`).

Foam and wakes (optional)
    Given a :class:`~seahaze.ocean.whitecaps.FoamField`, every vertex gets a foam fraction
    (``SeaMesh.foam``): the mean of the field over the vertex's cell in rest coordinates (its
    radial × tangential spacing; one sample where the cell is finer than ``lambda_p/16``, up to
    4 × 4 where it is coarser), with the detail the vertex spacing carries. Near the camera
    that is the whitecap pattern itself; far away, where a cell holds several whitecaps or
    none, it is their local coverage, so the far sea keeps distant whitecaps as brighter cells
    and its mean is the coverage law's ``W``. Every vertex also gets the reflectance of its foam
    (``SeaMesh.foam_reflectance``, from the cell's mean foam albedo): fresh on the most
    compressed crests and fading toward the whitecap's edge, Koepke's effective 0.22 on
    average. Given a :class:`~seahaze.ocean.wake.WakeField`, the vessels' wave heights are
    added at the vertices' world positions (band-limited by the vertex spacing, independently of
    the sea's fade so a calm sea shows wakes too; the fine near rings then reach over the wakes,
    :meth:`~seahaze.ocean.wake.WakeField.reach_m`) and their foam — averaged over each vertex's
    footprint, so a wake narrower than the far rings' spacing is neither lost between vertices
    nor smeared over a whole ring — is combined with the whitecaps as independent coverages,
    ``1 - (1 - f_sea)(1 - f_wake)``; wake foam is fresh (reflectance 0.55), its thinning with
    age being in its fraction. Given a :class:`~seahaze.ocean.spindrift.Spindrift` (a gale's
    spray veil), each seen vertex's foam is seen through the veil at its rest position, the
    unseen ones through its mean. What a vertex finally carries is the share of fresh foam
    that gives its foam albedo (:func:`~seahaze.ocean.whitecaps.as_fresh_foam`: faint foam is
    a little fresh foam on water, not a dim layer hiding the water's reflection).

Detail where it is seen (optional)
    Given the camera's view (its heading and the largest horizontal angle of its rays,
    :meth:`~seahaze.camera.Camera.view_azimuth_half_width`), only the vertices within that angle
    plus :data:`VIEW_MARGIN_DEG` get the waves, whitecaps and wakes; over the next
    :data:`VIEW_TAPER_DEG` the displacement and wake heights taper to zero, and beyond, the sea
    behind and beside the camera is flat with the mean whitecap coverage ``W``. The camera never
    sees it directly (the margin covers the horizontal drift of the choppy displacement, at most
    about ``Hs``, a degree at 50 m); it only shows in rays reflected off hulls back past the
    camera, where its mean brightness is what matters. On a 60° view this skips two thirds of the
    per-vertex work; the seen vertices are computed exactly as without a view.

Horizon
    A plane's horizon is at infinity; a disc of radius ``R`` leaves the rays between the
    horizon and the depression ``atan(h/R)`` uncovered (camera height ``h``). With ``n_theta``
    vertices the outer ring is a polygon whose inscribed radius is ``R·cos(pi/n_theta)``. At
    160×90 px and a 60° horizontal field of view a pixel spans 60°/160 = 0.375° (6.5 mrad;
    vertically ``2·atan(tan 30°·90/160)/90 = 0.40°``), so the gap is under one pixel when
    ``R > h/tan(0.375°) = 153·h``: 30.6 km for ``h = 200 m``. The default ``R = 1e5 m`` leaves
    a gap of 0.31 px at 200 m, 0.15 px at 100 m and 0.003 px at 2 m.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np

from .base import OceanSurface, cell_samples, smoothstep
from .spindrift import SPRAY_REFLECTANCE
from .whitecaps import as_fresh_foam, layer_over

if TYPE_CHECKING:
    from .spindrift import Spindrift
    from .wake import WakeField
    from .whitecaps import FoamField

Quality = Literal["low", "medium", "high"]

QUALITY_PRESETS: dict[str, tuple[int, int]] = {
    "low": (256, 195),
    "medium": (512, 488),
    "high": (1024, 976),
}
"""``quality -> (n_theta, n_rings)``: about 0.1 M, 0.5 M and 2 M triangles
(``n_theta·(2·n_rings - 1)``)."""

DEFAULT_RADIUS_M = 1.0e5
"""Default outer radius of the sea disc (m); see the module docstring."""

VERTICES_PER_PEAK_WAVELENGTH = 6.0
"""Radial vertices per peak wavelength required where the displacement is at full strength."""

FADE_RATIO = 2.0
"""``fade_end / fade_start``."""

MIN_FAR_RINGS = 8
MIN_NEAR_SCALE_M = 0.5

VIEW_MARGIN_DEG = 10.0
"""Full detail this far (deg of azimuth) beyond the widest ray of the view."""
VIEW_TAPER_DEG = 10.0
"""Beyond the margin, displacement and wake heights taper to zero over this many degrees."""


@dataclass(frozen=True)
class SeaMesh:
    """A polar sea mesh.

    Attributes:
        vertices: ``(N, 3)`` float32 world positions (m).
        faces: ``(M, 3)`` uint32 vertex indices, counter-clockwise seen from above.
        normals: ``(N, 3)`` float32 area-weighted unit vertex normals.
        ring_radii_m: rest radii of the rings (m), starting with 0 for the centre vertex.
        n_theta: vertices per ring.
        center_xy: world position of the centre (m).
        fade_start_m, fade_end_m: displacement fade radii (m); 0 for a flat sea.
        foam: ``(N,)`` float32 share of the surface per vertex (0–1) covered by fresh foam:
            the foam's albedo over 0.55 (:func:`~seahaze.ocean.whitecaps.as_fresh_foam`), or
            ``None`` when the mesh was built without a foam field and without wakes.
        foam_reflectance: ``(N,)`` float32 visible reflectance of that foam (Lambertian albedo,
            0–1: fresh foam's 0.55), or ``None`` with ``foam``.
        detail: ``(N,)`` weight (0–1) of the waves and wakes at every vertex, 1 inside the
            camera's view (module docstring), or ``None`` when the mesh was built without a
            view (full detail everywhere).
    """

    vertices: np.ndarray
    faces: np.ndarray
    normals: np.ndarray
    ring_radii_m: np.ndarray
    n_theta: int
    center_xy: tuple[float, float]
    fade_start_m: float
    fade_end_m: float
    foam: np.ndarray | None = None
    foam_reflectance: np.ndarray | None = None
    detail: np.ndarray | None = None

    @property
    def radius_m(self) -> float:
        """Outer (circumscribed) radius of the disc (m)."""
        return float(self.ring_radii_m[-1])

    @property
    def vertex_spacing_m(self) -> np.ndarray:
        """``(N,)`` vertex spacing (m) the displacement was band-limited with
        (:func:`ring_spacing`; the centre vertex gets the first ring's radius)."""
        return _vertex_spacing(self.ring_radii_m, self.n_theta)

    @property
    def vertex_fade(self) -> np.ndarray:
        """``(N,)`` displacement fade weight of every vertex at its rest radius."""
        r = np.concatenate([[0.0], np.repeat(self.ring_radii_m[1:], self.n_theta)])
        fade = displacement_fade(r, self.fade_start_m, self.fade_end_m)
        return fade if self.detail is None else fade * self.detail

    def fade_weight(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Displacement weight at world positions (x, y), e.g. to scale a floating object's
        heave consistently with the mesh."""
        r = np.hypot(np.asarray(x) - self.center_xy[0], np.asarray(y) - self.center_xy[1])
        return displacement_fade(r, self.fade_start_m, self.fade_end_m)


def displacement_fade(r: np.ndarray, fade_start_m: float, fade_end_m: float) -> np.ndarray:
    """Weight 1 for ``r <= fade_start_m``, 0 for ``r >= fade_end_m``, a smoothstep in ``ln r``
    between; everything 0 if ``fade_end_m <= 0`` (flat sea)."""
    r = np.asarray(r, dtype=float)
    if fade_end_m <= 0.0:
        return np.zeros_like(r)
    lo, hi = math.log(fade_start_m), math.log(fade_end_m)
    return 1.0 - smoothstep((np.log(np.maximum(r, 1e-9)) - lo) / (hi - lo))


def horizon_gap_angle(camera_height_m: float, radius_m: float, n_theta: int | None = None) -> float:
    """Depression angle (rad) below which every ray from height ``camera_height_m`` hits a flat
    polar disc of circumscribed radius ``radius_m`` (inscribed radius with ``n_theta`` sides)."""
    inscribed = radius_m * (math.cos(math.pi / n_theta) if n_theta else 1.0)
    return math.atan2(camera_height_m, inscribed)


def minimum_radius(camera_height_m: float, max_gap_rad: float) -> float:
    """Smallest disc radius (m) whose horizon gap is below ``max_gap_rad``: ``h/tan(gap)``."""
    return camera_height_m / math.tan(max_gap_rad)


def _near_rings(n_near: int, fade_end_m: float, scale_m: float) -> np.ndarray:
    u = np.arange(1, n_near + 1) / n_near
    return scale_m * np.expm1(u * math.log1p(fade_end_m / scale_m))


def _far_rings(n_far: int, inner_m: float, outer_m: float) -> np.ndarray:
    u = np.arange(1, n_far + 1) / n_far
    return inner_m * (outer_m / inner_m) ** u


def fade_radii(
    surface: OceanSurface,
    n_near: int,
    near_scale_m: float,
    radius_m: float,
    pixel_angle_rad: float | None = None,
) -> tuple[float, float]:
    """``(fade_start, fade_end)`` (m) for ``surface``; ``(0, 0)`` for a flat sea.

    ``fade_start`` solves ``(r + s)·ln(1 + 2r/s)/n_near = lambda_p/6`` (the near-zone ring
    spacing equals a sixth of the peak wavelength); ``fade_end = 2·fade_start``, limited to
    ``2·Hs/pixel_angle`` if the pixel angle is given and to a quarter of the disc radius.
    """
    wavelength = surface.peak_wavelength_m
    hs = surface.significant_wave_height_m
    if not math.isfinite(wavelength) or hs <= 0.0:
        return 0.0, 0.0
    target_spacing = wavelength / VERTICES_PER_PEAK_WAVELENGTH
    start = 10.0 * wavelength
    for _ in range(20):
        log_term = math.log1p(FADE_RATIO * start / near_scale_m)
        start = max(target_spacing * n_near / log_term - near_scale_m, near_scale_m)
    end = FADE_RATIO * start
    if pixel_angle_rad is not None:
        end = min(end, max(2.0 * hs / pixel_angle_rad, 2.0 * near_scale_m))
    end = min(end, 0.25 * radius_m)
    return end / FADE_RATIO, end


def polar_grid_faces(n_theta: int, n_rings: int) -> np.ndarray:
    """Faces ``(n_theta·(2·n_rings - 1), 3)`` uint32 of a centre vertex (index 0) plus
    ``n_rings`` rings of ``n_theta`` vertices (ring ``j >= 1`` starts at ``1 + (j-1)·n_theta``),
    counter-clockwise seen from +z when angles grow counter-clockwise."""
    i = np.arange(n_theta, dtype=np.int64)
    i_next = (i + 1) % n_theta
    fan = np.stack([np.zeros(n_theta, dtype=np.int64), 1 + i, 1 + i_next], axis=1)
    inner_base = 1 + np.arange(n_rings - 1, dtype=np.int64)[:, None] * n_theta
    outer_base = inner_base + n_theta
    a, a1 = inner_base + i, inner_base + i_next
    b, b1 = outer_base + i, outer_base + i_next
    first = np.stack([a, b, b1], axis=-1).reshape(-1, 3)
    second = np.stack([a, b1, a1], axis=-1).reshape(-1, 3)
    quads = np.stack([first, second], axis=1).reshape(-1, 3)
    return np.concatenate([fan, quads]).astype(np.uint32)


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals ``(N, 3)`` float32."""
    v = vertices.astype(np.float64)
    f = faces.astype(np.int64)
    face_n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    n = np.empty_like(v)
    for axis in range(3):
        weights = np.repeat(face_n[:, axis], 3)
        n[:, axis] = np.bincount(f.ravel(), weights=weights, minlength=len(v))
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
    return n.astype(np.float32)


def ring_spacing(radii: np.ndarray, n_theta: int) -> np.ndarray:
    """Vertex spacing (m) of every ring ``j >= 1`` of ``radii`` (which starts with 0): the
    larger of the radial spacing (half the distance between the neighbouring rings) and the
    tangential spacing ``r·2·pi/n_theta``."""
    padded = np.concatenate([radii, [2.0 * radii[-1] - radii[-2]]])
    radial = 0.5 * (padded[2:] - padded[:-2])
    tangential = radii[1:] * (2.0 * math.pi / n_theta)
    return np.maximum(radial, tangential)


def _vertex_spacing(radii: np.ndarray, n_theta: int) -> np.ndarray:
    return np.concatenate([[radii[1]], np.repeat(ring_spacing(radii, n_theta), n_theta)])


def _footprints(radii: np.ndarray, n_theta: int) -> tuple[np.ndarray, np.ndarray]:
    """Radial and tangential extent (m) of every vertex's cell (the centre: the first ring)."""
    padded = np.concatenate([radii, [2.0 * radii[-1] - radii[-2]]])
    radial = 0.5 * (padded[2:] - padded[:-2])
    tangential = radii[1:] * (2.0 * math.pi / n_theta)
    first = radii[1]
    return (
        np.concatenate([[first], np.repeat(radial, n_theta)]),
        np.concatenate([[first], np.repeat(tangential, n_theta)]),
    )


def _displace(
    surface: OceanSurface, x: np.ndarray, y: np.ndarray, spacing: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Band-limited displacement when the surface supports it (``displacement_filtered``),
    plain displacement otherwise."""
    filtered = getattr(surface, "displacement_filtered", None)
    if filtered is not None:
        return filtered(x, y, spacing)
    return surface.displacement(x, y)


def build_sea_mesh_data(
    surface: OceanSurface,
    camera_xy: tuple[float, float] = (0.0, 0.0),
    camera_height_m: float = 10.0,
    quality: Quality = "medium",
    radius_m: float | None = None,
    pixel_angle_rad: float | None = None,
    foam: FoamField | None = None,
    wakes: WakeField | None = None,
    view: tuple[float, float] | None = None,
    spindrift: Spindrift | None = None,
) -> SeaMesh:
    """Build the polar sea mesh around ``camera_xy`` (see the module docstring).

    Args:
        surface: the ocean surface (``displacement`` is evaluated at rest positions).
        camera_xy: horizontal camera position (m); the grid is centred there.
        camera_height_m: camera height above mean sea level (m); sets the near-ring spacing.
        quality: ``"low"`` | ``"medium"`` | ``"high"`` (:data:`QUALITY_PRESETS`).
        radius_m: outer radius (m); default :data:`DEFAULT_RADIUS_M`.
        pixel_angle_rad: angular size of one pixel (rad), if known, to fade sub-pixel waves.
        foam: whitecaps of ``surface`` (:class:`~seahaze.ocean.whitecaps.FoamField`), if any:
            fills ``SeaMesh.foam``.
        wakes: ship waves and foam wakes of moving vessels
            (:class:`~seahaze.ocean.wake.WakeField`), if any.
        view: ``(heading, half_width)`` (rad) of the camera at ``camera_xy``: waves, whitecaps
            and wakes only where they can be seen (module docstring); None: everywhere.
        spindrift: the gale's spray veil over ``foam``
            (:class:`~seahaze.ocean.spindrift.Spindrift`), if any: joins the foam layer
            (:func:`~seahaze.ocean.whitecaps.layer_over`), its mean where nobody looks.
    """
    if quality not in QUALITY_PRESETS:
        raise ValueError(f"quality must be one of {sorted(QUALITY_PRESETS)}, got {quality!r}")
    n_theta, n_rings = QUALITY_PRESETS[quality]
    radius = DEFAULT_RADIUS_M if radius_m is None else float(radius_m)
    n_far = max(MIN_FAR_RINGS, n_rings // 16)
    n_near = n_rings - n_far
    scale = max(float(camera_height_m), MIN_NEAR_SCALE_M)
    fade_start, fade_end = fade_radii(surface, n_near, scale, radius, pixel_angle_rad)

    # The fine near rings reach at least over the wakes (on a calm sea the fade radius is tens
    # of metres, and the far rings, 15-40 % of their radius apart, would lose every wake).
    near_end = fade_end
    if wakes is not None and fade_end > 0.0:
        near_end = min(max(fade_end, wakes.reach_m(camera_xy)), 0.25 * radius)
    if fade_end > 0.0:
        radii = np.concatenate(
            [[0.0], _near_rings(n_near, near_end, scale), _far_rings(n_far, near_end, radius)]
        )
    else:
        radii = np.concatenate([[0.0], _near_rings(n_rings, radius, scale)])

    theta = np.arange(n_theta) * (2.0 * math.pi / n_theta)
    cos_t, sin_t = np.cos(theta), np.sin(theta)
    r = np.concatenate([[0.0], np.repeat(radii[1:], n_theta)])
    x = np.concatenate([[0.0], np.outer(radii[1:], cos_t).ravel()]) + camera_xy[0]
    y = np.concatenate([[0.0], np.outer(radii[1:], sin_t).ravel()]) + camera_xy[1]
    z = np.zeros_like(x)

    spacing = _vertex_spacing(radii, n_theta)
    radial, tangential = _footprints(radii, n_theta)
    azimuth = np.concatenate([[0.0], np.tile(theta, len(radii) - 1)])
    detail = view_detail(azimuth, view)
    seen = slice(None) if detail is None else np.nonzero(detail > 0.0)[0]
    strength = 1.0 if detail is None else detail[seen]
    foam_values, foam_albedo = _unseen_foam(foam, x.size)
    cells = (x[seen], y[seen], azimuth[seen], radial[seen], tangential[seen])
    foam_values[seen], foam_albedo[seen] = _vertex_foam(surface, foam, *cells, spacing[seen])
    if spindrift is not None and spindrift.present:
        veil = np.full_like(x, spindrift.mean_veil)
        veil[seen] = spindrift.veil(x[seen], y[seen], spacing[seen])
        foam_values, foam_albedo = layer_over(foam_values, foam_albedo, veil, SPRAY_REFLECTANCE)
    weight = displacement_fade(r, fade_start, fade_end) * (1.0 if detail is None else detail)
    displaced = np.nonzero(weight > 0.0)[0]
    if displaced.size:
        w = weight[displaced]
        dx, dy, dz = _displace(surface, x[displaced], y[displaced], spacing[displaced])
        x[displaced] += w * dx
        y[displaced] += w * dy
        z[displaced] = w * dz
    if wakes is not None:
        z[seen] += strength * wakes.height(x[seen], y[seen], spacing[seen])
        wake_foam = np.zeros_like(x)
        wake_foam[seen] = wakes.foam_averaged(x[seen], y[seen], *cells[2:])
        # Where both overlap the wake's fresh foam lies on top of the whitecap.
        foam_values, foam_albedo = layer_over(foam_values, foam_albedo, wake_foam)
    foam_values, reflectance = as_fresh_foam(foam_values, foam_albedo)

    vertices = np.stack([x, y, z], axis=1).astype(np.float32)
    faces = polar_grid_faces(n_theta, len(radii) - 1)
    return SeaMesh(
        vertices=vertices,
        faces=faces,
        normals=vertex_normals(vertices, faces),
        ring_radii_m=radii,
        n_theta=n_theta,
        center_xy=(float(camera_xy[0]), float(camera_xy[1])),
        fade_start_m=fade_start,
        fade_end_m=fade_end,
        foam=None if foam is None and wakes is None else foam_values.astype(np.float32),
        foam_reflectance=None
        if foam is None and wakes is None
        else np.clip(reflectance, 0.0, 1.0).astype(np.float32),
        detail=detail,
    )


def view_detail(azimuth_rad: np.ndarray, view: tuple[float, float] | None) -> np.ndarray | None:
    """Weight (0–1) of the waves at vertices of azimuth ``azimuth_rad`` around the camera, for
    a view ``(heading, half_width)`` (rad): 1 within the half-width plus
    :data:`VIEW_MARGIN_DEG`, a smoothstep down to 0 over :data:`VIEW_TAPER_DEG`; None (all 1)
    without a view or when the view with its margins takes in every azimuth."""
    if view is None:
        return None
    heading, half_width = view
    full = half_width + math.radians(VIEW_MARGIN_DEG)
    taper = math.radians(VIEW_TAPER_DEG)
    if full + taper >= math.pi:
        return None
    off = np.abs(np.angle(np.exp(1j * (np.asarray(azimuth_rad) - heading))))
    detail = smoothstep((full + taper - off) / taper)
    detail[0] = 1.0  # the centre vertex, under the camera
    return detail


def _unseen_foam(foam: FoamField | None, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Foam fraction and foam albedo of vertices nobody sees: the whitecaps' mean coverage."""
    if foam is None:
        return np.zeros(n), np.zeros(n)
    return np.full(n, foam.mean_fraction), np.full(n, foam.albedo)


FOAM_FEATURE_PEAK_WAVELENGTHS = 1.0 / 16.0
"""Smallest feature of the whitecap pattern a mesh cell must sample, in peak wavelengths (the
largest FFT patch's grid is ``lambda_p/32``)."""

MAX_FOAM_CELL_SAMPLES = 4
"""Most samples per axis when a vertex's cell is averaged over the whitecap pattern."""


def _vertex_foam(
    surface: OceanSurface,
    foam: FoamField | None,
    x0: np.ndarray,
    y0: np.ndarray,
    azimuth: np.ndarray,
    radial: np.ndarray,
    tangential: np.ndarray,
    spacing: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Foam fraction per vertex and the foam's albedo (fraction × reflectance): their means over
    the vertex's cell (radial × tangential, at rest positions), see the module docstring."""
    if foam is None or foam.mean_fraction == 0.0:
        return np.zeros_like(x0), np.zeros_like(x0)
    if math.isinf(foam.jacobian_threshold):  # a surface that cannot place foam: the mean
        return np.full_like(x0, foam.mean_fraction), np.full_like(x0, foam.albedo)
    feature = FOAM_FEATURE_PEAK_WAVELENGTHS * surface.peak_wavelength_m
    cell = np.maximum(radial, tangential)
    n = np.clip(np.ceil(cell / feature), 1, MAX_FOAM_CELL_SAMPLES).astype(int)
    fraction = np.empty_like(x0)
    albedo = np.empty_like(x0)
    for count in np.unique(n):
        pick = np.nonzero(n == count)[0]
        sx, sy = cell_samples(
            x0[pick], y0[pick], azimuth[pick], radial[pick], tangential[pick], int(count)
        )
        f, reflectance = foam.foam_and_reflectance(sx, sy, spacing[pick][:, None])
        fraction[pick] = f.mean(axis=1)
        albedo[pick] = (f * reflectance).mean(axis=1)
    return fraction, albedo


def build_sea_mesh(
    surface: OceanSurface,
    camera_xy: tuple[float, float] = (0.0, 0.0),
    camera_height_m: float = 10.0,
    quality: Quality = "medium",
    radius_m: float | None = None,
    *,
    pixel_angle_rad: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """``(vertices float32 (N, 3), faces uint32 (M, 3))`` of :func:`build_sea_mesh_data`."""
    mesh = build_sea_mesh_data(
        surface, camera_xy, camera_height_m, quality, radius_m, pixel_angle_rad
    )
    return mesh.vertices, mesh.faces
