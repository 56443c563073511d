"""A fog bank's own diffuse field (``seahaze.render.strip_tracer``, ``render.bank_diffuse``).

* Without a bank (near ratio 1, scale 1) the bank's tally is its profile's, bit for bit, when
  every photon is traced through both: they draw the same random numbers and see the same
  density.
* The profile's field, averaged across the strip, is the diffuse tables' own tracer's
  (``photon_tracer.trace_fluence``, an independent estimator: analog free paths, the first
  flight split, track lengths summed in height) per height and μ band, within their noise.
* Deep inside a thick bank the field is the plane-parallel one of the bank's density.
* The same seed gives the same bytes.
* ``diffuse_air``: a diffuse field that is the same everywhere gives every ray the ratio 1
  whatever the bank does to the ray (``∫ e^{−τ} σρ ds = 1 − e^{−σℓ}`` in both), and a bank
  field twice the profile's gives 2; a field that steps at the edge gives a ray the closed
  form of its sum where the drift has carried the edge.
* The ratios' grid spreads to the pixels bilinearly within a segment, never across one.
* The sea's pre-drawn samples come out in each arriving ray's vertical plane; the renderer
  gives a bank alone and patches alone their diffuse ratios (1 after open sky), and a bank
  with patches none.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import assert_same_plane_parallel_field, eight_way_sea, sun_and_sky_photons
from seahaze.haze_field import Bank, Drift, HazeField
from seahaze.medium import HomogeneousSlab
from seahaze.nonuniform import NonUniformHaze

pytestmark = pytest.mark.usefixtures("mitsuba_variant")

SLAB = HomogeneousSlab(top=300.0, albedo=0.998, g=0.75)


def _strip(near_ratio: float = 0.2, scale: float = 1.0, toward_deg: float = 0.0):
    from seahaze.render.strip_tracer import Strip

    return Strip(
        -1500.0, 1500.0, 10, SLAB.top, 6, 8, 8, toward_deg, 80.0, near_ratio, scale, 3000.0
    )


def test_without_a_bank_the_bank_tally_is_the_profiles_bit_for_bit():
    from seahaze.render.strip_tracer import trace_strip

    photons, sea = sun_and_sky_photons(4096, 1), eight_way_sea()
    got = trace_strip(*photons, sea, [0.004], SLAB, _strip(1.0), 3, 1)
    assert got.bank.sum() > 0.0
    np.testing.assert_array_equal(got.bank, got.profile)
    # And a bank is not its profile: the same photons see another field.
    banked = trace_strip(*photons, sea, [0.004], SLAB, _strip(0.2), 3, 1)
    assert not np.array_equal(banked.bank, banked.profile)
    np.testing.assert_array_equal(banked.profile, got.profile)


def test_the_same_seed_gives_the_same_bytes():
    from seahaze.render.strip_tracer import trace_strip

    photons, sea = sun_and_sky_photons(2048, 2), eight_way_sea()
    runs = [trace_strip(*photons, sea, [0.01], SLAB, _strip(), 7) for _ in "ab"]
    np.testing.assert_array_equal(runs[0].bank, runs[1].bank)
    other = trace_strip(*photons, sea, [0.01], SLAB, _strip(), 8)
    assert not np.array_equal(runs[0].bank, other.bank)


def test_the_profile_field_is_the_diffuse_tables_tracers():
    from seahaze.render.photon_tracer import Slab, trace_fluence
    from seahaze.render.strip_tracer import trace_strip

    sigma = 3.912 / 1000.0
    photons, sea = sun_and_sky_photons(1 << 18, 4), eight_way_sea()
    strip = _strip()
    got = trace_strip(*photons, sea, [sigma], SLAB, strip, 11, 1).profile[0].mean(axis=0)
    slab = Slab(SLAB.top, SLAB.albedo, SLAB.g, 0.0, strip.n_z, strip.n_mu, strip.n_phi, False)
    want = trace_fluence(*photons, sea, [sigma], slab, 12)[0]
    assert_same_plane_parallel_field(got, want, strip.n_mu)


def test_deep_inside_a_thick_bank_the_field_is_the_plane_parallel_one():
    from seahaze.render.photon_tracer import Slab, trace_fluence
    from seahaze.render.strip_tracer import Strip, trace_strip

    sigma, scale = 3.912 / 300.0, 1.3
    photons, sea = sun_and_sky_photons(1 << 18, 5), eight_way_sea()
    # Cells from 3 to 5 km past the edge: ten transport mean free paths of this bank.
    strip = Strip(3000.0, 5000.0, 2, SLAB.top, 6, 8, 8, 0.0, 80.0, 0.2, scale, 3000.0)
    got = trace_strip(*photons, sea, [sigma], SLAB, strip, 13).bank[0]
    slab = Slab(SLAB.top, SLAB.albedo, SLAB.g, 0.0, strip.n_z, strip.n_mu, strip.n_phi, False)
    want = trace_fluence(*photons, sea, [sigma * scale], slab, 14)[0]
    for cell in got:
        np.testing.assert_allclose(cell.sum(axis=1), want.sum(axis=1), rtol=0.015)


def _bank_medium() -> NonUniformHaze:
    bank = Bank(700.0, 20.0, 80.0, 0.25, origin_xy=(30.0, -10.0))
    field = HazeField(bank=bank, drift=Drift(speed_m_s=3.0, toward_deg=200.0, time_s=40.0))
    return NonUniformHaze(SLAB, field, 1.1)


def _rays():
    dirs = np.array(
        [[1.0, 0.3, -0.02], [0.9, 0.4, 0.01], [0.3, 1.0, 0.05], [-1.0, 0.2, -0.01], [1, 0, 0.2]]
    )
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    reach = np.array([750.0, 20000.0, 4000.0, 1200.0, 300.0])
    up = dirs[:, 2] > 0
    reach[up] = np.minimum(reach[up], (SLAB.top - 15.0) / dirs[up, 2])
    return np.array([0.0, 0.0, 15.0]), dirs, reach


def test_a_diffuse_field_the_same_everywhere_gives_ratio_one_and_twice_it_two():
    from seahaze.render.bank_diffuse import SourceTables, bank_strip
    from seahaze.render.diffuse_ratios import ray_sums

    medium = _bank_medium()
    strip = bank_strip(medium, (0.0, 0.0))
    rng = np.random.default_rng(3)
    # One source per direction, the same in every cell (any shape over directions).
    per_dir = rng.random((2, 1, strip.n_dir)) + 0.1
    cells = np.broadcast_to(per_dir, (2, strip.n_s * strip.n_z, strip.n_dir))
    heights = np.broadcast_to(per_dir, (2, strip.n_z, strip.n_dir))
    origin, dirs, reach = _rays()
    starts = np.broadcast_to(origin, dirs.shape)
    # The pixels' view ratios: the field's reduced length over the profile's, exactly.
    field_length = medium.lengths_along(starts, dirs, np.zeros(len(dirs)), reach)
    view = field_length / medium.profile.path_length(origin[2], dirs[:, 2], reach)
    assert np.ptp(view) > 0.5  # rays that see very different amounts of the bank
    sigma = np.array([3.912 / 300.0, 3.912 / 2000.0])
    uniform = SourceTables(medium, strip, cells, heights)
    true, equivalent = ray_sums(medium, uniform, sigma, starts, dirs, reach, view)
    np.testing.assert_allclose(true / equivalent, 1.0, atol=2e-3)
    twice = SourceTables(medium, strip, 2.0 * cells, heights)
    doubled, _ = ray_sums(medium, twice, sigma, starts, dirs, reach, view)
    np.testing.assert_allclose(doubled, 2.0 * true, rtol=1e-12)


def test_ratios_spread_bilinearly_within_a_segment_and_never_across_one():
    from seahaze.render.diffuse_ratios import spread_within_segments

    height, width, step = 37, 50, 4
    rows, cols = np.arange(0, height, step), np.arange(0, width, step)
    # One segment: a linear function of the pixel is reproduced exactly between grid pixels.
    plane = lambda y, x: 0.3 + 0.01 * y - 0.02 * x  # noqa: E731
    grid = plane(rows[:, None], cols[None, :])[None]
    labels = np.full((height, width), -2)
    got = spread_within_segments(grid, labels, step)[0]
    y, x = np.mgrid[:height, :width]
    inside = (y <= rows[-1]) & (x <= cols[-1])  # beyond the last grid pixel: held, not extrapolated
    np.testing.assert_allclose(got[inside], plane(y, x)[inside], rtol=0, atol=1e-12)
    # A vessel (label 0) on the sky: each takes only its own segment's values.
    labels[10:25, 13:31] = 0
    two = np.where(labels[::step, ::step] == 0, 5.0, 1.0)[None]
    spread = spread_within_segments(two, labels, step)[0]
    np.testing.assert_array_equal(spread, np.where(labels == 0, 5.0, 1.0))


def test_a_ray_reads_the_bank_field_where_the_drifted_bank_has_moved_it():
    """A bank of uniform density (near ratio 1) whose field doubles past the edge: a
    horizontal ray's sum is the closed form of ``∫ e^{−σct} σc J(t) dt`` with ``J`` stepping
    where the ray crosses the edge, wherever the drift has carried the edge (1.2 km here)."""
    from seahaze.render.bank_diffuse import SourceTables, bank_strip
    from seahaze.render.diffuse_ratios import ray_sums

    drift = Drift(speed_m_s=30.0, toward_deg=180.0, time_s=40.0)  # the edge 1200 m nearer
    bank = Bank(2500.0, 0.0, 80.0, 1.0)
    medium = NonUniformHaze(SLAB, HazeField(bank=bank, drift=drift), 1.1)
    strip = bank_strip(medium, (0.0, 0.0))
    edges = strip.s_lo + (strip.s_hi - strip.s_lo) * np.arange(strip.n_s + 1) / strip.n_s
    centres = 0.5 * (edges[:-1] + edges[1:])
    past = np.repeat(centres >= 0.0, strip.n_z)  # cells past the edge, as (s, z) rows
    cells = np.where(past[None, :, None], 2.0, 1.0) * np.ones((1, 1, strip.n_dir))
    heights = np.ones((1, strip.n_z, strip.n_dir))
    sources = SourceTables(medium, strip, cells, heights)
    sigma, reach = 3.912 / 4000.0, 6000.0
    origin, ray = np.array([0.0, 0.0, 15.0]), np.array([[1.0, 0.0, 0.0]])
    true, _ = ray_sums(
        medium, sources, np.array([sigma]), origin[None], ray, np.array([reach]), np.ones(1)
    )
    # The step lies on the cells' boundary nearest the edge, 1300 m ahead after the drift.
    step_at = edges[np.argmin(np.abs(edges))] + bank.distance_m - 1200.0
    k = sigma * medium.scale
    want = (1.0 - np.exp(-k * step_at)) + 2.0 * (np.exp(-k * step_at) - np.exp(-k * reach))
    np.testing.assert_allclose(true[0, 0] * sigma, want, rtol=5e-3)


def test_sea_samples_keep_the_plane_of_incidence_and_one_pick_per_column():
    """The sea's pre-drawn samples (in the plane of incidence) come out in each arriving
    direction's own vertical plane, and an (N, K) pick is K columns of (N,) picks."""
    from seahaze.render.photon_tracer import SeaReflectance

    rng = np.random.default_rng(5)
    wo = np.stack(
        [np.cos(np.linspace(0.1, 1.4, 6)), np.zeros(6), np.sin(np.linspace(0.1, 1.4, 6))], 1
    )
    sea = SeaReflectance(np.broadcast_to(wo, (4, 6, 3)).copy(), rng.random((4, 6, 3)))
    d = rng.normal(size=(7, 3))
    d[:, 2] = -np.abs(d[:, 2])
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    pick = rng.integers(0, 6, (7, 3))
    out, weight = sea.samples(d, pick)
    for j in range(3):
        column = sea.samples(d, pick[:, j])
        np.testing.assert_array_equal(out[:, j], column[0])
        np.testing.assert_array_equal(weight[:, j], column[1])
    # Horizontal parts parallel to the arriving direction's, elevations the samples' own.
    cross = out[..., 0] * d[:, None, 1] - out[..., 1] * d[:, None, 0]
    np.testing.assert_allclose(cross, 0.0, atol=1e-12)
    assert np.all(out[..., 0] * d[:, None, 0] + out[..., 1] * d[:, None, 1] > 0.0)
    np.testing.assert_allclose(out[..., 2], wo[pick, 2], rtol=1e-12)


def test_the_renderer_gives_a_bank_or_patches_their_diffuse_ratios_and_both_none():
    from conftest import small_spec
    from seahaze.haze_field import Patches
    from seahaze.render.engine import open_session
    from seahaze.render.physical import PhysicalRenderer

    spec = small_spec(
        camera={"height_m": 12.0, "pitch_deg": -1.0, "fov_deg": 50.0},
        vessels={"placed": [{"class": "tug", "distance_m": 300, "bearing_deg": 4}]},
        haze={"top_m": 300.0, "levels": [800.0]},
        render={"mode": "physical", "spp": 4, "seed": 3},
    )
    sigma = np.array([3.912 / 800.0, 3.912 / 300.0])
    bank = Bank(600.0, 0.0, 80.0, 0.2)
    patches = Patches(300.0, 3.0, 60.0, 5.0, seed=5)
    for field, has in (
        (HazeField(bank=bank), True),
        (HazeField(patches=patches), True),
        (HazeField(patches=patches, bank=bank), False),
    ):
        session = open_session(spec, medium=NonUniformHaze(SLAB, field, 1.0))
        renderer = PhysicalRenderer(session.loaded, spec, geometry=session.pixels)
        ratios = renderer.pixel_ratios(sigma, 1, 1 << 14)
        if not has:
            assert ratios.diffuse_air is None and ratios.diffuse_bounce is None
            continue
        for ratio in (ratios.diffuse_air, ratios.diffuse_bounce):
            assert ratio.shape == (2, *session.pixels.distance_m.shape)
            assert np.all(np.isfinite(ratio)) and np.all(ratio > 0.0)
        sky = ~np.isfinite(session.pixels.distance_m)
        # Open sky has no later segment; the sea's do not stay the tables' light.
        np.testing.assert_array_equal(ratios.diffuse_bounce[:, sky], 1.0)
        assert np.ptp(ratios.diffuse_bounce[:, ~sky]) > 0.0
        assert np.ptp(ratios.diffuse_air) > 0.0
