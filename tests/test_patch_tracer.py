"""Drifting patches' own diffuse field (``seahaze.render.patch_tracer``, ``render.patch_diffuse``).

* Without patches (scale 1) the field's tally, summed over a height's columns, is the
  profile's summed over each direction group, to the integer: both families draw the same
  random numbers and see the same density; the cells' ratios then average 1 and the groups'
  light adds up to the profile's.
* The profile's field is the diffuse tables' own tracer's (``photon_tracer.trace_fluence``, an
  independent estimator) per height and μ band, within their noise; a uniform field of density
  1.3 is the tables' field at 1.3 times the extinction, in every column: the box is periodic,
  so no side of it is dark (a sun at 35° would leave the side it shines from without light
  from beyond it).
* In patches, the field is darkest under the most haze: a cell's fluence ratio falls with the
  optical depth of the column above it (the haze shields it from the light from above), a
  structure two seeds share; a drifting field's light follows the columns where its haze has
  drifted to, not where it lay before.
* The azimuth sectors turn with the sun: the first is centred on its photons' travel.
* The same seed gives the same bytes.
* The light a ray reads is the profile's times the cell's ratio, the profile's outside the
  box; with every ratio 1 a ray's ``diffuse_air`` sum equals its equivalent profile's.
* The field is traced at levels at most ``LEVEL_SPAN`` apart in extinction (300, 500, 1000,
  2000 and 4000 m of the graded levels); a level between takes, at each column's centre, the
  two bracketing levels' ratios interpolated in ``ln σ`` (the clearer one's alone where the
  denser level's smaller box does not reach), and its own profile's light.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import assert_same_plane_parallel_field, eight_way_sea, sun_and_sky_photons
from seahaze.haze_field import HazeField, Patches
from seahaze.medium import HomogeneousSlab
from seahaze.nonuniform import NonUniformHaze

pytestmark = pytest.mark.usefixtures("mitsuba_variant")

SLAB = HomogeneousSlab(top=300.0, albedo=0.998, g=0.75)
PATCHES = Patches(400.0, 3.0, 60.0, 30.0, seed=5)


def _box(side: float = 3000.0, n_xy: int = 16, n_z: int = 6, sector_start: int = 0):
    from seahaze.render.patch_tracer import Box

    return Box(-0.5 * side, -0.3 * side, side, n_xy, SLAB.top, n_z, 8, 8, 4, 2, sector_start)


def _trace(field: HazeField, sigma: float, scale: float, box, photons, seed: int):
    from seahaze.render.patch_tracer import source_photons, trace_box

    sources = source_photons(*photons)
    return trace_box(sources, eight_way_sea(), [sigma], SLAB, field, scale, 0.0, box, seed)


@pytest.mark.parametrize("sector_start", [0, 3])
def test_without_patches_the_fields_tally_is_the_profiles_to_the_integer(sector_start):
    # Sectors that begin at bin 3 wrap around the azimuths' seam: the tracer's groups must
    # still be Box.groups'.
    box = _box(sector_start=sector_start)
    got = _trace(HazeField(), 0.004, 1.0, box, sun_and_sky_photons(4096, 1), 3)
    # Per height and direction group (band of μ × sector of azimuth: the profile's direction
    # bins summed over each group, as Box.groups assigns them).
    per_height = got.field[0].sum(axis=(0, 1)) / box.n_xy**2
    assert np.all(per_height > 0.0)
    one_hot = box.groups()[:, None] == np.arange(box.n_light)[None]
    groups = got.profile[0] @ one_hot
    np.testing.assert_allclose(per_height, groups, rtol=1e-12)
    # So the cells' ratios average 1 in every height and group (smoothing wraps around the
    # box, keeping the mean), and the groups' light adds up to the profile's whole light.
    from seahaze.render.diffuse_table import TableGrid, phase_matrix
    from seahaze.render.patch_diffuse import PatchLight

    medium = NonUniformHaze(SLAB, HazeField(), 1.0)
    light = PatchLight.of(medium, np.array([0.004]), [box], [got])
    np.testing.assert_allclose(light.ratio[0].mean(axis=(0, 1)), 1.0, rtol=1e-9)
    phase = phase_matrix(SLAB.g, TableGrid(box.n_z, box.n_mu, box.n_phi, folded=False)).T
    whole = got.profile[0] @ phase
    np.testing.assert_allclose(light.profile[0].sum(axis=1), whole, rtol=1e-9)
    # Patches are not the profile: the same photons see another field.
    patchy = _trace(HazeField(patches=PATCHES), 0.004, 1.0, box, sun_and_sky_photons(4096, 1), 3)
    assert np.max(np.abs(patchy.field[0].sum(axis=(0, 1)) / box.n_xy**2 - per_height)) > 0.0


@pytest.mark.parametrize("sun_azimuth_deg", [-30.0, 0.0, 100.0, 179.0, -172.0])
def test_the_first_sector_is_centred_on_the_suns_travel(sun_azimuth_deg):
    from seahaze.render.patch_diffuse import GRID, SECTORS, patch_box, sun_sector_start
    from seahaze.render.patch_tracer import SourcePhotons

    az = np.radians(sun_azimuth_deg)
    sun = np.tile([0.8 * np.cos(az), 0.8 * np.sin(az), -0.6], (5, 1))
    sky = np.array([[0.0, 0.6, -0.8], [-0.6, 0.0, -0.8]])
    sources = SourcePhotons(np.concatenate([sun, sky]), np.full((7, 3), 0.1), 5, 1.0)
    start = sun_sector_start(sources)
    # The first sector's centre, as an azimuth: bins span [−π, π) from world +x.
    per = GRID.n_phi // SECTORS
    centre = -np.pi + (start + 0.5 * per) * 2.0 * np.pi / GRID.n_phi
    off = np.degrees(np.angle(np.exp(1j * (centre - az))))
    assert abs(off) <= 0.5 * 360.0 / GRID.n_phi + 1e-9
    # The box files the sun's own direction bin under the first sector of its band.
    box = patch_box(NonUniformHaze(SLAB, HazeField(patches=PATCHES), 1.0), (0.0, 0.0), 0.004, start)
    phi_bin = int((az + np.pi) / (2.0 * np.pi) * GRID.n_phi) % GRID.n_phi
    mu_bin = int((-0.6 + 1.0) * 0.5 * GRID.n_mu)
    assert box.groups()[mu_bin * GRID.n_phi + phi_bin] % SECTORS == 0
    # A sun below the horizon sends no photons: the sectors stay where the bins begin.
    assert sun_sector_start(SourcePhotons(sky, np.full((2, 3), 0.1), 0, 1.0)) == 0


def test_the_same_seed_gives_the_same_bytes():
    field = HazeField(patches=PATCHES)
    runs = [_trace(field, 0.01, 1.0, _box(), sun_and_sky_photons(2048, 2), 7) for _ in "ab"]
    np.testing.assert_array_equal(runs[0].field, runs[1].field)
    np.testing.assert_array_equal(runs[0].profile, runs[1].profile)
    other = _trace(field, 0.01, 1.0, _box(), sun_and_sky_photons(2048, 2), 8)
    assert not np.array_equal(runs[0].field, other.field)


def _tables_tracer(photons, sigma: float, box, seed: int) -> np.ndarray:
    """The diffuse tables' tracer's directional fluence ``[z, dir]``, in luminance (the
    box's)."""
    from seahaze.render.diffuse_ratios import LUMINANCE
    from seahaze.render.photon_tracer import Slab, trace_fluence

    slab = Slab(SLAB.top, SLAB.albedo, SLAB.g, 0.0, box.n_z, box.n_mu, box.n_phi, False)
    return trace_fluence(*photons, eight_way_sea(), [sigma], slab, seed)[0] @ LUMINANCE


def test_the_profile_field_is_the_diffuse_tables_tracers():
    sigma = 3.912 / 1000.0
    photons, box = sun_and_sky_photons(1 << 18, 4), _box()
    got = _trace(HazeField(), sigma, 1.0, box, photons, 11).profile[0]
    want = _tables_tracer(photons, sigma, box, 12)
    assert_same_plane_parallel_field(got[..., None], want[..., None], box.n_mu)


def test_a_uniform_field_is_the_plane_parallel_one_in_every_column():
    sigma, scale = 3.912 / 1000.0, 1.3
    photons, box = sun_and_sky_photons(1 << 18, 5), _box(n_xy=4)
    got = _trace(HazeField(), sigma, scale, box, photons, 13).field[0].sum(axis=3)
    want = _tables_tracer(photons, sigma * scale, box, 14).sum(axis=1)
    for column in got.reshape(-1, box.n_z):
        np.testing.assert_allclose(column, want, rtol=0.04)
    # The columns the sun's side would leave dark in a closed box hold what the rest do.
    by_column = got.sum(axis=2)
    np.testing.assert_allclose(by_column, by_column.mean(), rtol=0.03)


_DENSE_BOX = dict(side=1200.0, n_xy=24, n_z=6)
"""A box at 300 m: cells of 50 m, patches 400 m × 133 m across."""


def _lowest_ratio(field: HazeField, travelled_m: float, seed: int) -> np.ndarray:
    """The lowest height's fluence ratio per column (smoothed over its neighbours) at 300 m,
    flattened, traced with ``seed``."""
    from seahaze.render.patch_diffuse import smooth_periodic
    from seahaze.render.patch_tracer import source_photons, trace_box

    box, photons = _box(**_DENSE_BOX), sun_and_sky_photons(1 << 17, seed)
    sources = source_photons(*photons)
    traced = trace_box(
        sources, eight_way_sea(), [3.912 / 300.0], SLAB, field, 1.0, travelled_m, box, seed
    )
    lowest = smooth_periodic(traced.field[0].sum(axis=-1), 1)[..., 0]
    return (lowest / traced.profile[0, 0].sum()).ravel()


def _column_haze(medium: NonUniformHaze) -> np.ndarray:
    """The haze in each column of the box (the density summed over heights), flattened."""
    box = _box(**_DENSE_BOX)
    centres = (np.arange(box.n_xy) + 0.5) * box.side_m / box.n_xy
    x, y = np.meshgrid(box.x0 + centres, box.y0 + centres, indexing="ij")
    heights = np.arange(5.0, SLAB.top, 10.0)
    return sum(medium.density_at(x, y, np.full_like(x, h)) for h in heights).ravel()


def test_in_patches_the_field_is_darkest_under_the_most_haze():
    medium = NonUniformHaze(SLAB, HazeField(patches=PATCHES), 1.0)
    a, b = (_lowest_ratio(medium.field, 0.0, seed) for seed in (21, 22))
    assert np.corrcoef(a, b)[0, 1] > 0.5  # a structure both seeds find, not noise
    assert np.corrcoef(0.5 * (a + b), _column_haze(medium))[0, 1] < -0.5
    assert np.ptp(0.5 * (a + b)) > 0.1  # and it is not a small one


def test_a_ray_reads_the_profiles_light_times_its_cells_ratio():
    from seahaze.render.diffuse_ratios import ray_sums
    from seahaze.render.patch_diffuse import PatchLight

    medium = NonUniformHaze(SLAB, HazeField(patches=PATCHES), 1.0)
    box = _box(side=2000.0, n_xy=8)
    rng = np.random.default_rng(9)
    # Each group's light, the same toward every direction (whatever bins a ray reads).
    per_group = rng.random((box.n_z, box.n_light)) + 0.1
    profile = np.repeat(per_group[..., None], box.n_dir, axis=2)
    ratio = rng.random((box.n_xy, box.n_xy, box.n_z, box.n_light)) + 0.5
    light = PatchLight(medium, [box], [ratio], [profile])
    # A point in cell (2, 5, 1) and one beyond the box's side.
    cell = box.side_m / box.n_xy
    x = np.array([[box.x0 + 2.5 * cell, box.x0 - 10.0]])
    y = np.array([[box.y0 + 5.5 * cell, box.y0 + 5.5 * cell]])
    z = np.array([[1.5 * SLAB.top / box.n_z] * 2])
    true, flat = light.light(0, x, y, z, np.array([[0.0, 0.0, -1.0]]))
    group = per_group[1]
    # (Read in float32: its sums hold 1e-6.)
    np.testing.assert_allclose(flat[0], group.sum(), rtol=1e-6)
    np.testing.assert_allclose(true[0], [group @ ratio[2, 5, 1], group.sum()], rtol=1e-6)
    # Every ratio 1 and the light the same at every height: each ray's sum through the
    # patches is its equivalent profile's (``∫ e^{−τ} σρ ds = 1 − e^{−σℓ}`` in both).
    same = np.broadcast_to(profile[0], profile.shape)  # the same at every height
    ones = PatchLight(medium, [box], [np.ones_like(ratio)], [same])
    dirs = np.array([[1.0, 0.0, 0.0], [0.6, 0.8, 0.05], [0.0, -1.0, 0.2]])
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    starts = np.tile([0.0, 0.0, 15.0], (3, 1))
    reach = np.array([900.0, 1500.0, (SLAB.top - 15.0) / dirs[2, 2]])
    length = medium.lengths_along(starts, dirs, np.zeros(3), reach)
    view = length / medium.profile.path_length(15.0, dirs[:, 2], reach)
    assert np.ptp(view) > 0.1
    sigma = np.array([3.912 / 300.0])
    got, equivalent = ray_sums(medium, ones, sigma, starts, dirs, reach, view)
    np.testing.assert_allclose(got / equivalent, 1.0, atol=3e-3)


def test_a_drifted_field_is_shielded_where_its_haze_has_drifted_to():
    """The box reads the field drifted by ``travelled_m`` along the drift: the light under
    the haze follows the drifted field's columns (``NonUniformHaze.density_at`` drifts them
    too), not where the same patches lay before they drifted 300 m."""
    from seahaze.haze_field import Drift

    drift = Drift(speed_m_s=10.0, toward_deg=90.0, time_s=30.0)
    moving = NonUniformHaze(SLAB, HazeField(patches=PATCHES, drift=drift), 1.0)
    still = NonUniformHaze(SLAB, HazeField(patches=PATCHES), 1.0)
    lowest = 0.5 * sum(_lowest_ratio(moving.field, 300.0, seed) for seed in (23, 24))
    drifted = np.corrcoef(lowest, _column_haze(moving))[0, 1]
    before = np.corrcoef(lowest, _column_haze(still))[0, 1]
    assert drifted < -0.3 and before > drifted + 0.4


def test_the_field_is_traced_at_levels_at_most_a_span_apart():
    from seahaze.render.patch_diffuse import LEVEL_SPAN, traced_levels
    from seahaze.visibility import GRADED_LEVELS_M

    graded = np.array(GRADED_LEVELS_M, float)
    sigma = 3.912 / graded
    traced = traced_levels(sigma)
    assert LEVEL_SPAN == 2.0
    assert [int(graded[k]) for k in traced] == [300, 500, 1000, 2000, 4000]
    # In any order of levels the same ones, the densest and the clearest among them.
    shuffled = np.random.default_rng(2).permutation(len(sigma))
    assert sorted(graded[shuffled][traced_levels(sigma[shuffled])]) == list(graded[traced])
    # Levels further apart than the span are each traced; one level alone is.
    assert traced_levels(np.array([0.02, 0.004, 0.001])) == [0, 1, 2]
    assert traced_levels(np.array([0.01])) == [0]


def _patch_light(sigma: np.ndarray, traced: list[int]):
    """A PatchLight of levels ``sigma`` in their own boxes, its ratios read from random
    fluences, the field's only at levels ``traced``."""
    from seahaze.render.patch_diffuse import PatchLight, patch_box
    from seahaze.render.patch_tracer import BoxFluence

    medium = NonUniformHaze(SLAB, HazeField(patches=PATCHES), 1.0)
    boxes = [patch_box(medium, (120.0, -40.0), float(s)) for s in sigma]
    rng = np.random.default_rng(4)
    fluences = []
    for k, box in enumerate(boxes):
        field = rng.random((1, box.n_xy, box.n_xy, box.n_z, box.n_light)) + 0.5
        profile = rng.random((1, box.n_z, box.n_dir)) + 0.5
        fluences.append(BoxFluence(field if k in traced else None, profile))
    return PatchLight.of(medium, sigma, boxes, fluences), boxes


def test_a_level_between_traced_ones_blends_their_ratios_in_log_extinction():
    sigma = 3.912 / np.array([300.0, 400.0, 600.0])
    light, boxes = _patch_light(sigma, [0, 2])
    t = np.log(sigma[0] / sigma[1]) / np.log(sigma[0] / sigma[2])
    assert 0.41 < t < 0.42  # (in σ itself it would be 0.5)
    mid, near, far = boxes[1], boxes[0], boxes[2]
    assert near.side_m < mid.side_m < far.side_m
    # Each column's centre looked up in the two traced boxes by hand.
    size = mid.side_m / mid.n_xy
    for i, j in [(mid.n_xy // 2, mid.n_xy // 2 + 3), (1, 2), (mid.n_xy - 1, 0)]:
        x, y = mid.x0 + (i + 0.5) * size, mid.y0 + (j + 0.5) * size
        values, weights = [], []
        for box, ratio, share in ((near, light.ratio[0], 1.0 - t), (far, light.ratio[2], t)):
            u, v = (x - box.x0) / box.side_m * box.n_xy, (y - box.y0) / box.side_m * box.n_xy
            if 0.0 <= u < box.n_xy and 0.0 <= v < box.n_xy:
                values.append(share * ratio[int(u), int(v)])
                weights.append(share)
        # The centre column lies in both boxes; the corners only in the clearer one's.
        assert len(weights) == (2 if (i, j) == (mid.n_xy // 2, mid.n_xy // 2 + 3) else 1)
        np.testing.assert_allclose(light.ratio[1][i, j], sum(values) / sum(weights), rtol=1e-12)
    # The traced levels keep their own ratios; the blended level its own profile's light.
    traced, _ = _patch_light(sigma, [0, 1, 2])
    for k in (0, 2):
        np.testing.assert_array_equal(light.ratio[k], traced.ratio[k])
    np.testing.assert_array_equal(light.profile[1], traced.profile[1])
    assert not np.allclose(light.ratio[1], traced.ratio[1])
