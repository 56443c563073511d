"""The polar sea mesh: size, topology (no holes), and horizon coverage at 160×90 px."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from seahaze.camera import Camera
from seahaze.ocean import (
    FRESH_FOAM_REFLECTANCE,
    FlatSurface,
    FoamField,
    OceanParams,
    build_sea_mesh,
    build_sea_mesh_data,
    horizon_gap_angle,
    make_surface,
    ocean_params_for_beaufort,
)
from seahaze.ocean.mesh import (
    DEFAULT_RADIUS_M,
    QUALITY_PRESETS,
    VIEW_MARGIN_DEG,
    VIEW_TAPER_DEG,
)

WIDTH, HEIGHT_PX, HFOV_DEG = 160, 90, 60.0
PIXEL_ANGLE = math.radians(HFOV_DEG) / WIDTH  # 0.375°, the smaller of the two pixel angles


def _camera_rays(pitch_deg: float) -> np.ndarray:
    """Unit ray directions ``(H, W, 3)`` through the pixel centres of a pinhole camera with a
    60° horizontal field of view, yaw 0 (looking along +x), Z up."""
    pitch = math.radians(pitch_deg)
    forward = np.array([math.cos(pitch), 0.0, math.sin(pitch)])
    right = np.array([0.0, -1.0, 0.0])
    up = np.cross(right, forward)
    tan_h = math.tan(math.radians(HFOV_DEG) / 2.0)
    tan_v = tan_h * HEIGHT_PX / WIDTH
    u = ((np.arange(WIDTH) + 0.5) / WIDTH * 2.0 - 1.0) * tan_h
    v = (1.0 - (np.arange(HEIGHT_PX) + 0.5) / HEIGHT_PX * 2.0) * tan_v
    d = forward + u[None, :, None] * right + v[:, None, None] * up
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


@pytest.mark.parametrize(("quality", "budget"), [("low", 100_000), ("medium", 500_000)])
def test_sizes_and_dtypes(quality: str, budget: int) -> None:
    vertices, faces = build_sea_mesh(FlatSurface(), camera_height_m=10.0, quality=quality)
    assert vertices.dtype == np.float32 and vertices.shape[1] == 3
    assert faces.dtype == np.uint32 and faces.shape[1] == 3
    assert 0.9 * budget < len(faces) <= budget
    assert faces.max() == len(vertices) - 1
    n_theta, n_rings = QUALITY_PRESETS[quality]
    assert len(vertices) == 1 + n_theta * n_rings
    assert np.hypot(vertices[:, 0], vertices[:, 1]).max() == pytest.approx(DEFAULT_RADIUS_M)


def test_high_quality_budget() -> None:
    n_theta, n_rings = QUALITY_PRESETS["high"]
    assert 1_800_000 < n_theta * (2 * n_rings - 1) <= 2_000_000


def test_gap_below_horizon_is_under_one_pixel() -> None:
    """atan(h / R_inscribed) < 1 px for every camera height 2–200 m (R = 1e5 m)."""
    for quality, (n_theta, _) in QUALITY_PRESETS.items():
        for h in (2.0, 5.0, 20.0, 100.0, 200.0):
            assert horizon_gap_angle(h, DEFAULT_RADIUS_M, n_theta) < PIXEL_ANGLE, (quality, h)


@pytest.fixture(scope="module")
def moderate_sea_meshes() -> dict[float, object]:
    surface = make_surface(ocean_params_for_beaufort(5, choppiness=1.0, seed=2))
    return {
        h: build_sea_mesh_data(surface, camera_xy=(120.0, -40.0), camera_height_m=h, quality="low")
        for h in (5.0, 20.0, 100.0)
    }


@pytest.mark.parametrize("camera_height", [5.0, 20.0, 100.0])
def test_mesh_is_a_single_graph_over_the_disc(moderate_sea_meshes, camera_height) -> None:
    """No holes: the displaced mesh is one connected disc whose only boundary edges are the
    outer ring, and its projection onto XY has no flipped or degenerate triangle, so it covers
    the outer polygon exactly once (a height field over the disc)."""
    mesh = moderate_sea_meshes[camera_height]
    v = mesh.vertices.astype(np.float64)
    f = mesh.faces.astype(np.int64)
    edges = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    unique, counts = np.unique(edges, axis=0, return_counts=True)
    assert counts.max() == 2
    boundary = unique[counts == 1]
    outer_start = len(v) - mesh.n_theta
    assert len(boundary) == mesh.n_theta
    assert np.all(boundary >= outer_start)
    assert len(v) - len(unique) + len(f) == 1  # Euler characteristic of a disc
    graph = coo_matrix((np.ones(len(unique)), (unique[:, 0], unique[:, 1])), shape=(len(v), len(v)))
    assert connected_components(graph, directed=False)[0] == 1
    # Displaced coordinates relative to the centre, to keep float32 rounding out of the areas.
    xy = v[:, :2] - np.array(mesh.center_xy)
    a, b, c = xy[f[:, 0]], xy[f[:, 1]], xy[f[:, 2]]
    signed = 0.5 * (
        (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    )
    assert signed.min() > 0.0
    # The near field really is displaced, the far field flat, the camera above the crests.
    assert np.abs(v[:, 2]).max() > 0.5
    far = np.hypot(*xy.T) > mesh.fade_end_m * 1.0001
    assert np.all(v[far, 2] == 0.0)
    assert v[:, 2].max() < camera_height


@pytest.mark.parametrize("camera_height", [5.0, 20.0, 100.0])
@pytest.mark.parametrize("pitch_deg", [-10.0, -5.0, -2.0, 0.0, 2.5, 5.0])
def test_every_ray_below_the_horizon_hits_the_mesh(
    moderate_sea_meshes, camera_height, pitch_deg
) -> None:
    """Every pixel ray at least one pixel below the horizon meets the plane z = 0 inside the
    disc's inscribed radius. Since the mesh is a height field over the whole disc (previous
    test), flat beyond the fade radius and below the camera, such a ray - which starts above
    the surface and ends below it inside the disc - must cross it. Rays less than one pixel
    below the horizon may miss only within the gap of ``test_gap_below_horizon...``."""
    mesh = moderate_sea_meshes[camera_height]
    rays = _camera_rays(pitch_deg).reshape(-1, 3)
    depression = -np.arcsin(rays[:, 2])
    below = depression >= PIXEL_ANGLE
    if pitch_deg <= 0.0:
        assert below.sum() > WIDTH * HEIGHT_PX * 0.4
    t = camera_height / -rays[below, 2]
    reach = t * np.hypot(rays[below, 0], rays[below, 1])
    inscribed = mesh.radius_m * math.cos(math.pi / mesh.n_theta)
    assert reach.max() < inscribed
    hit_xy = (
        np.array(mesh.center_xy)
        + reach[:, None] * rays[below, :2] / np.hypot(rays[below, 0], rays[below, 1])[:, None]
    )
    assert np.all(np.hypot(*(hit_xy - np.array(mesh.center_xy)).T) < inscribed)


def test_fade_and_vertex_normals() -> None:
    surface = make_surface(OceanParams(wind_speed=8.0, seed=0))
    mesh = build_sea_mesh_data(surface, camera_height_m=10.0, quality="low")
    assert 0.0 < mesh.fade_start_m < mesh.fade_end_m < DEFAULT_RADIUS_M / 4.0
    # Six vertices per peak wavelength (radially) where the displacement is at full strength.
    spacing = np.interp(mesh.fade_start_m, mesh.ring_radii_m[1:], np.diff(mesh.ring_radii_m))
    assert spacing == pytest.approx(surface.peak_wavelength_m / 6.0, rel=0.05)
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, rtol=1e-5)
    assert mesh.normals[:, 2].min() > 0.0
    assert mesh.fade_weight(np.array([0.0]), np.array([0.0]))[0] == 1.0
    assert mesh.fade_weight(np.array([mesh.fade_end_m]), np.array([0.0]))[0] == 0.0
    # A pixel angle fades sub-pixel waves earlier.
    coarse = build_sea_mesh_data(surface, camera_height_m=10.0, quality="low", pixel_angle_rad=0.05)
    assert coarse.fade_end_m < mesh.fade_end_m


def test_flat_sea_mesh_is_planar() -> None:
    vertices, _ = build_sea_mesh(FlatSurface(), camera_height_m=2.0, quality="low")
    assert np.all(vertices[:, 2] == 0.0)


@pytest.mark.parametrize("pitch_deg", [0.0, -2.0, -30.0, 15.0])
def test_view_half_width_bounds_every_pixel_ray(pitch_deg: float) -> None:
    """The camera's view half-width is the largest azimuth of its rays: every pixel-centre ray
    lies within it, a border ray reaches it, and at zero pitch it is half the horizontal field
    of view exactly (the pinhole's edge rays all have azimuth ``atan(tan(fov/2))``)."""
    camera = Camera(15.0, HFOV_DEG, pitch_deg, 40.0, WIDTH, HEIGHT_PX)
    half = camera.view_azimuth_half_width()
    d = camera.pixel_center_directions().reshape(-1, 3)
    off = np.abs(np.angle(np.exp(1j * (np.arctan2(d[:, 1], d[:, 0]) - math.radians(40.0)))))
    assert off.max() <= half + 1e-9
    assert off.max() > half - math.radians(1.0)
    if pitch_deg == 0.0:
        assert half == pytest.approx(math.radians(HFOV_DEG / 2.0), abs=1e-12)


def test_a_view_holding_the_nadir_sees_every_azimuth() -> None:
    assert Camera(15.0, HFOV_DEG, -80.0, 0.0, WIDTH, HEIGHT_PX).view_azimuth_half_width() == (
        pytest.approx(math.pi)
    )


def test_the_sea_outside_the_view_is_flat_with_the_mean_whitecaps() -> None:
    """With a view, the vertices the camera can see are the same as without one (positions,
    foam), and the sea beyond the view's margins is flat and carries the mean coverage."""
    surface = make_surface(ocean_params_for_beaufort(6, choppiness=1.0, seed=5))
    foam = FoamField(surface, 12.0)
    heading = math.radians(30.0)
    args = dict(camera_xy=(10.0, 20.0), camera_height_m=15.0, quality="low", foam=foam)
    full = build_sea_mesh_data(surface, **args)
    viewed = build_sea_mesh_data(surface, **args, view=(heading, math.radians(35.0)))
    n_theta = full.n_theta
    azimuth = np.concatenate([[0.0], np.tile(np.arange(n_theta) * 2 * math.pi / n_theta, 195)])
    off = np.degrees(np.abs(np.angle(np.exp(1j * (azimuth - heading)))))
    inside = off <= 35.0 + VIEW_MARGIN_DEG
    outside = off >= 35.0 + VIEW_MARGIN_DEG + VIEW_TAPER_DEG
    assert inside.sum() > 0.2 * inside.size and outside.sum() > 0.5 * outside.size
    np.testing.assert_array_equal(viewed.vertices[inside], full.vertices[inside])
    np.testing.assert_array_equal(viewed.foam[inside], full.foam[inside])
    assert np.all(viewed.vertices[outside, 2] == 0.0)
    share = foam.albedo / FRESH_FOAM_REFLECTANCE  # the mean foam, as a share of fresh foam
    np.testing.assert_allclose(viewed.foam[outside], share, rtol=1e-6)
    assert np.abs(full.vertices[outside, 2]).max() > 0.5  # the full mesh had waves there
