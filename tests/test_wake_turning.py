"""Wakes of turning vessels (issue 17): the foam band and the Kelvin pattern follow the arc the
vessel sailed (``MovingVessel.to_track_frame``), a straight course keeps exactly its old values,
``foam_region`` still holds every foamy point, a turn to starboard mirrors one to port, and the
sequence's rate of turn reaches the sea (``Course.placement_at``, ``world.moving_vessels``)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from seahaze import vessels
from seahaze.camera import Camera
from seahaze.motion import Course
from seahaze.ocean.base import cell_samples, smoothstep
from seahaze.ocean.wake import (
    FOAM_CUTOFF,
    KNOT_M_S,
    MAX_SWEPT_ANGLE_RAD,
    SWEPT_FADE_RAD,
    MovingVessel,
    ShipWaves,
    wake_foam_decay_s,
)
from seahaze.sceneio import parse_scene_text
from seahaze.world import VesselInstance, frame_layout, moving_vessels

TUG = dict(speed_m_s=9.0 * KNOT_M_S, length_m=30.0, beam_m=10.0, draft_m=4.0)
"""The encounter scene's tug: 9 kn, 30 m; turning at 1.5 deg/s it sails a circle of 177 m."""


def _turning(rate_deg_s: float, x=40.0, y=-70.0, heading_deg=35.0, **hull) -> MovingVessel:
    return MovingVessel(x, y, heading_deg, **(hull or TUG), turn_rate_deg_s=rate_deg_s)


def _straight_foam(v: MovingVessel, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The turbulent foam as it was computed before turns existed, from the straight frame."""
    xi, eta = v.to_vessel_frame(x, y)
    s = -xi - 0.5 * v.length_m
    half_width = 0.5 * v.beam_m * (1.0 + np.maximum(s, 0.0) / v.beam_m) ** 0.2
    across = np.clip(1.0 - (eta / half_width) ** 2, 0.0, 1.0) ** 2
    age = np.maximum(s, 0.0) / v.speed_m_s
    start = smoothstep(s / (0.1 * v.beam_m))
    return start * across * np.exp(-age / wake_foam_decay_s(v))


def test_a_straight_course_keeps_its_exact_values() -> None:
    """Rate 0 is the straight frame bit for bit; a turn of 1e-9 deg/s (radius 265 million km,
    the arc 0.7 µm off the line 600 m back) differs from it by less than 1e-6 in foam and a
    micrometre in wave height: no cancellation in the bent coordinates of gentle turns."""
    rng = np.random.default_rng(7)
    x, y = rng.uniform(-600.0, 600.0, (2, 200_000))
    straight = _turning(0.0)
    assert straight == MovingVessel(40.0, -70.0, 35.0, **TUG)
    for a, b in zip(straight.to_track_frame(x, y), straight.to_vessel_frame(x, y), strict=True):
        assert a.tobytes() == b.tobytes()
    waves = ShipWaves(straight)
    assert waves.turbulent_foam(x, y).tobytes() == _straight_foam(straight, x, y).tobytes()
    assert waves.turbulent_foam(x, y).max() > 0.5
    gentle = ShipWaves(_turning(1e-9))
    assert np.abs(gentle.turbulent_foam(x, y) - waves.turbulent_foam(x, y)).max() < 1e-6
    assert np.abs(gentle.height(x, y) - waves.height(x, y)).max() < 1e-6
    assert np.abs(waves.height(x, y)).max() > 0.3


@pytest.mark.parametrize("rate", [1.5, -4.0])
def test_the_sailed_track_maps_to_the_centreline(rate: float) -> None:
    """Midships positions the vessel passed through (``Course.pose`` at earlier times) have
    track coordinates ``(-U·dt, 0)``; ahead of midships the frame is the straight one, and the
    two agree across the line through midships and the turn's centre (the arc's side stretches
    distances along the track by R/rho, so a step of 1 µm stays within 15 µm)."""
    u = TUG["speed_m_s"]
    course = Course(vessels.Placement("tug", 40.0, -70.0, 35.0, 30.0, 0.0, 0.0), u, rate)
    vessel = _turning(rate)
    dt = np.linspace(0.5, 0.85 * math.pi * (u / math.radians(abs(rate))) / u, 40)
    past = np.array([course.pose(-t)[:2] for t in dt])
    xi, eta = vessel.to_track_frame(past[:, 0], past[:, 1])
    np.testing.assert_allclose(xi, -u * dt, rtol=1e-9)
    np.testing.assert_allclose(eta, 0.0, atol=1e-9)
    # Across the midships line (straight frame xi = ±1 µm), on both sides of the track.
    h = math.radians(35.0)
    side = np.linspace(-60.0, 60.0, 13)
    for step in (1e-6, -1e-6):
        x = 40.0 + step * math.cos(h) - side * math.sin(h)
        y = -70.0 + step * math.sin(h) + side * math.cos(h)
        xi, eta = vessel.to_track_frame(x, y)
        assert np.all(np.abs(xi) < 15e-6) and np.all(np.sign(xi) == np.sign(step))
        np.testing.assert_allclose(eta, side, atol=1e-6)


@pytest.mark.parametrize("rate", [1.5, -4.0])
def test_the_foam_follows_the_stern_track_not_the_heading(rate: float) -> None:
    """The stern's past positions (``Course.pose`` at earlier times, minus half a length along
    that time's heading) carry the foam of the straight wake's centreline at the same distance
    behind: the same along-track decay, within 1 % (the band is centred on the stern's circle;
    the arc length along it differs from the midships arc by ``L³/24R²``, 0.26 m at R = 66 m);
    where a straight wake would lie, behind along the current heading, the turning wake has
    none once the circle has left the band (20 s back)."""
    u, half_l = TUG["speed_m_s"], 0.5 * TUG["length_m"]
    course = Course(vessels.Placement("tug", 40.0, -70.0, 35.0, 30.0, 0.0, 0.0), u, rate)
    turning, straight = ShipWaves(_turning(rate)), ShipWaves(_turning(0.0))
    radius = u / math.radians(abs(rate))
    # Back to where the fade before the half-circle begins.
    limit = (MAX_SWEPT_ANGLE_RAD - SWEPT_FADE_RAD) * radius - half_l
    dt = np.linspace(0.5, limit / u, 60)
    poses = np.array([course.pose(-t) for t in dt])
    h = np.radians(poses[:, 2])
    stern_x = poses[:, 0] - half_l * np.cos(h)
    stern_y = poses[:, 1] - half_l * np.sin(h)
    on_track = turning.turbulent_foam(stern_x, stern_y)
    h0 = math.radians(35.0)
    behind = half_l + u * dt  # behind midships along the current heading
    line_x, line_y = 40.0 - behind * math.cos(h0), -70.0 - behind * math.sin(h0)
    centreline = straight.turbulent_foam(line_x, line_y)
    np.testing.assert_allclose(on_track, centreline, rtol=0.01)
    assert on_track[-1] < 0.3 * on_track[0]  # it did decay along the arc
    off_track = turning.turbulent_foam(line_x, line_y)
    far = dt >= 20.0
    assert np.all(off_track[far] == 0.0) and np.all(on_track[far] > 0.01)
    assert np.all(off_track <= on_track + 1e-12)


def test_foam_ends_before_the_half_circle_without_an_edge() -> None:
    """Beyond MAX_SWEPT_ANGLE_RAD the track is ambiguous: nothing there; before it the fields
    fade smoothly (a slow speedboat with a deep draft keeps foam all the way round)."""
    hull = dict(speed_m_s=5.0, length_m=10.0, beam_m=4.0, draft_m=3.0)
    vessel = _turning(8.0, 0.0, 0.0, 0.0, **hull)  # R = 35.8 m, foam e-folding 75 m
    waves = ShipWaves(vessel)
    radius = 5.0 / math.radians(8.0)
    phi = np.linspace(0.3, math.pi, 2000)
    x, y = radius * np.sin(-phi), radius - radius * np.cos(phi)  # the midships circle, back
    foam = waves.turbulent_foam(x, y)
    assert np.all(foam[phi > MAX_SWEPT_ANGLE_RAD] == 0.0)
    assert foam[phi < MAX_SWEPT_ANGLE_RAD - SWEPT_FADE_RAD].min() > 0.2
    assert np.abs(np.diff(foam)).max() < 0.01  # no step anywhere along the arc
    assert np.all(np.abs(waves.height(x, y))[phi > MAX_SWEPT_ANGLE_RAD] == 0.0)


TURNS = [
    ("tug +1.5", 1.5, TUG),
    ("tug -4", -4.0, TUG),
    ("trawler +6", 6.0, dict(speed_m_s=8.0 * KNOT_M_S, length_m=25.0, beam_m=7.0, draft_m=3.0)),
    ("speedboat -10", -10.0, dict(speed_m_s=30 * KNOT_M_S, length_m=8.0, beam_m=2.8, draft_m=0.6)),
]


@pytest.mark.parametrize(("rate", "hull"), [t[1:] for t in TURNS], ids=[t[0] for t in TURNS])
def test_foam_region_holds_every_foamy_point_of_a_turning_wake(rate: float, hull: dict) -> None:
    """Dense random points: every one with foam >= FOAM_CUTOFF is in the region, and so is
    every point within the margin of one (the region is tested with the margin's world
    distance); the region stays tight (under 4 times the foamy area) and is bent: the straight
    rectangle's far end, on the current heading, is outside it."""
    vessel = _turning(rate, 0.0, 0.0, 0.0, **hull)
    waves = ShipWaves(vessel)
    radius = vessel.speed_m_s / math.radians(abs(rate))
    reach = 2.2 * radius + 60.0
    rng = np.random.default_rng(11)
    x = rng.uniform(-reach, 0.5 * reach, 600_000)
    y = rng.uniform(-reach, reach, 600_000) * math.copysign(1.0, rate)
    foam = waves.foam(x, y)
    foamy = foam >= FOAM_CUTOFF
    assert foamy.sum() > 500
    region = waves.foam_region(x, y, 0.0)
    assert region[foamy].all()
    assert region.sum() < 4.0 * foamy.sum()
    margin = rng.uniform(0.0, 40.0, foamy.sum())
    angle = rng.uniform(0.0, 2.0 * math.pi, margin.size)
    reach_out = margin * np.sqrt(rng.uniform(0.0, 1.0, margin.size))
    px, py = x[foamy] + reach_out * np.cos(angle), y[foamy] + reach_out * np.sin(angle)
    assert waves.foam_region(px, py, margin).all()
    behind = vessel.speed_m_s * wake_foam_decay_s(vessel) * math.log(1.0 / FOAM_CUTOFF)
    far_end = -0.5 * vessel.length_m - min(behind, 1.5 * radius)
    assert not waves.foam_region(np.array([far_end]), np.zeros(1), 0.0)[0]


@pytest.mark.parametrize(("rate", "hull"), [t[1:] for t in TURNS], ids=[t[0] for t in TURNS])
def test_mesh_cells_lose_no_foam_of_a_turning_wake(rate: float, hull: dict) -> None:
    """``foam_averaged`` averages only cells that ``foam_region`` admits: every cell with a
    sample of foam >= FOAM_CUTOFF gets exactly the mean of its samples (the same samples,
    averaged here without the region test), the others less than FOAM_CUTOFF."""
    waves = ShipWaves(_turning(rate, 0.0, 0.0, 0.0, **hull))
    radius = hull["speed_m_s"] / math.radians(abs(rate))
    rng = np.random.default_rng(5)
    n = 20_000
    x = rng.uniform(-2.2 * radius, 0.5 * radius, n)
    y = rng.uniform(-2.2 * radius, 2.2 * radius, n) * math.copysign(1.0, rate)
    azimuth = rng.uniform(0.0, 2.0 * math.pi, n)
    radial, tangential = rng.uniform(0.5, 30.0, (2, n))
    averaged = waves.foam_averaged(x, y, azimuth, radial, tangential)
    count = np.clip(np.ceil(np.maximum(radial, tangential) / waves.foam_feature_m), 1, 16)
    brute, foamy = np.zeros(n), np.zeros(n, dtype=bool)
    for c in np.unique(count):
        pick = count == c
        sx, sy = cell_samples(
            x[pick], y[pick], azimuth[pick], radial[pick], tangential[pick], int(c)
        )
        samples = waves.foam(sx, sy)
        brute[pick], foamy[pick] = samples.mean(axis=1), (samples >= FOAM_CUTOFF).any(axis=1)
    assert (brute > 0.05).sum() > 100
    np.testing.assert_array_equal(averaged[foamy], brute[foamy])
    assert np.all(brute[~foamy] < FOAM_CUTOFF)


@pytest.mark.parametrize(("rate", "hull"), [t[1:] for t in TURNS], ids=[t[0] for t in TURNS])
def test_a_turn_to_starboard_mirrors_a_turn_to_port(rate: float, hull: dict) -> None:
    """Track coordinates and wake foam at (x, y) for rate r equal those at (x, -y) for rate -r
    with eta negated (heading along +x, so the mirror is y -> -y). The waves mirror to the
    float32 grid's precision inside the grid (at its last row the field is cut one row further
    out on one side than on the other); the breaking foam to 1 %: the solved slope grid is
    itself symmetric only to 4e-4 in slope (the speedboat's), which the steep foam ramp
    amplifies."""
    port_vessel = _turning(rate, 0.0, 0.0, 0.0, **hull)
    port, starboard = ShipWaves(port_vessel), ShipWaves(_turning(-rate, 0.0, 0.0, 0.0, **hull))
    radius = hull["speed_m_s"] / math.radians(abs(rate))
    x, y = np.random.default_rng(2).uniform(-2.5 * radius, 2.5 * radius, (2, 300_000))
    xi, eta = port_vessel.to_track_frame(x, y)
    xi_m, eta_m = starboard.vessel.to_track_frame(x, -y)
    np.testing.assert_allclose(xi_m, xi, rtol=1e-12)
    np.testing.assert_allclose(eta_m, -eta, rtol=1e-12, atol=1e-9)
    a, b = port.turbulent_foam(x, y), starboard.turbulent_foam(x, -y)
    assert a.max() > 0.5
    np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-15)
    grid = np.abs(eta) < -port.origin[1] - 2.0 * port.spacing_m
    ha, hb = port.height(x, y)[grid], starboard.height(x, -y)[grid]
    assert np.abs(ha).max() > 0.1
    assert np.abs(ha - hb).max() < 1e-5 * np.abs(ha).max()
    fa, fb = port.foam(x, y)[grid], starboard.foam(x, -y)[grid]
    assert np.abs(fa - fb).max() < 0.01


def test_a_turn_rate_must_be_finite() -> None:
    for bad in (math.nan, math.inf, -math.inf):
        with pytest.raises(ValueError, match="turn rate"):
            MovingVessel(0.0, 0.0, 0.0, **TUG, turn_rate_deg_s=bad)


def test_the_sequence_turn_rate_reaches_the_sea() -> None:
    """A sequence frame's placements carry their course's rate of turn and the sea's vessels
    get it; a still scene's placements keep 0."""
    spec = parse_scene_text(
        """\
camera: {height_m: 12, resolution: [64, 36]}
vessels:
  placed:
    - {class: passenger_ferry, distance_m: 260, bearing_deg: 3, heading_deg: 175,
       length_m: 60, speed_kn: 20}
    - {class: tug, distance_m: 150, bearing_deg: -10, heading_deg: 60, length_m: 25,
       speed_kn: 10, turn_rate_deg_s: -2}
sequence: {frames: 3, fps: 2}
""",
        "turning.yaml",
    )
    camera = Camera.from_spec(spec.camera)
    placements, speeds = frame_layout(spec, camera, 1)
    assert [p.turn_rate_deg_s for p in placements] == [0.0, -2.0]
    still, _ = frame_layout(spec, camera, None)
    assert [p.turn_rate_deg_s for p in still] == [0.0, 0.0]
    instances = [
        VesselInstance(i, p.kind, 0, p, p.length_m, 8.0, 10.0, 0.0, [], speed, 2.0)
        for i, (p, speed) in enumerate(zip(placements, speeds, strict=True))
    ]
    sea = moving_vessels(instances)
    assert [v.turn_rate_deg_s for v in sea] == [0.0, -2.0]
    assert sea[1].curvature_per_m == pytest.approx(math.radians(-2.0) / (10 * KNOT_M_S))
