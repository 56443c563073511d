"""Haze that varies across the sea (issue #31): the patches' and the bank's field, the level
normalisation over the view's horizontal fan, the optical depths against an independent
integration, drift in sequences, and the scene file's rules."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import simpson

from conftest import cli_run, small_spec
from seahaze import fileio
from seahaze.fog_layer import fog_layer_medium
from seahaze.haze_field import Bank, Drift, HazeField, Patches, fractal_noise
from seahaze.medium import HomogeneousSlab
from seahaze.nonuniform import RAY_REACH_M, VIEW_REACH_M, HorizontalView, nonuniform_haze
from seahaze.render.engine import render_scene
from seahaze.sceneio import load_scene
from seahaze.spec import with_overrides

VIEW = HorizontalView(0.0, 0.0, 12.0, 10.0, 60.0)
PATCHES = Patches(250.0, 3.0, 50.0, 20.0, seed=11)
BANK = Bank(1200.0, 10.0, 80.0, 0.2)

SCENE = """\
name: patchy
camera: {{height_m: 12, fov_deg: 60, pitch_deg: -1, resolution: [64, 36]}}
sea: {{quality: low, seed: 4}}
vessels:
  placed:
    - {{class: tug, distance_m: 400, bearing_deg: 5, length_m: 30}}
haze:
  levels: [500, 2000]
  patches: {{correlation_m: 200, density_ratio: 20}}
  bank: {{distance_m: 900, bearing_deg: 0, edge_m: 60}}
render: {{mode: {mode}, spp: 1, seed: 3}}
"""


def _medium(profile=None, field=None):
    profile = profile or HomogeneousSlab(top=300.0, albedo=0.998, g=0.75)
    return nonuniform_haze(profile, field or HazeField(PATCHES, BANK), VIEW)


def test_the_field_is_deterministic_and_seeded():
    q = np.random.default_rng(0).uniform(-50, 50, (3, 1000))
    a, b = fractal_noise(*q, seed=5), fractal_noise(*q, seed=5)
    assert np.array_equal(a, b) and np.all(np.abs(a) <= 1.0)
    assert np.mean(np.abs(a - fractal_noise(*q, seed=6))) > 0.1
    # Lattice points of the coarsest octave carry the hashed values: the field is continuous.
    near = fractal_noise(q[0] + 1e-7, q[1], q[2], seed=5)
    assert np.max(np.abs(near - a)) < 1e-4


def test_patches_span_their_density_ratio():
    """``m = exp(a n)`` with ``a = ln(R)/2`` and ``|n| ≤ 1``: max/min ≤ R, and a large sample
    comes within a factor of 2 of it."""
    xy = np.random.default_rng(1).uniform(-5000, 5000, (2, 200_000))
    m = PATCHES.modulation(xy[0], xy[1], np.full(200_000, 10.0), (1.0, 0.0))
    ratio = m.max() / m.min()
    assert PATCHES.density_ratio / 2 < ratio <= PATCHES.density_ratio * (1 + 1e-9)


def test_patches_are_stretched_along_the_drift():
    """The correlation of ``m`` at lag ``L`` along the drift is higher than at lag ``L`` across
    it (``A = 3``), measured on a sample."""
    rng = np.random.default_rng(2)
    x, y = rng.uniform(-20_000, 20_000, (2, 100_000))
    z = np.full_like(x, 10.0)

    def corr(dx: float, dy: float) -> float:
        a = PATCHES.modulation(x, y, z, (1.0, 0.0))
        b = PATCHES.modulation(x + dx, y + dy, z, (1.0, 0.0))
        return float(np.corrcoef(np.log(a), np.log(b))[0, 1])

    lag = PATCHES.correlation_m / 2
    assert corr(lag, 0.0) > corr(0.0, lag) + 0.2


def test_the_bank_edge_is_where_it_is_said():
    """At the edge the modulation is halfway between its near and inside values; ``2w``
    either side it is 88 % of the way (the logistic's value at ±2: 0.881)."""
    az = math.radians(BANK.toward_deg)
    along = np.array([BANK.distance_m, BANK.distance_m + 2 * BANK.edge_m, 0.0, 10_000.0])
    m = BANK.modulation(along * math.cos(az), along * math.sin(az))
    r = BANK.near_ratio
    assert m[0] == pytest.approx((1 + r) / 2, rel=1e-12)
    assert (m[1] - r) / (1 - r) == pytest.approx(1 / (1 + math.exp(-2)), rel=1e-12)
    assert m[2] == pytest.approx(r, abs=1e-6) and m[3] == pytest.approx(1.0, abs=1e-12)


def test_drift_moves_the_whole_field():
    """``m(x, t) = m(x − u t, 0)``: a frame later the field is the same, moved downwind."""
    drift = Drift(4.0, 30.0, 0.0)
    later = Drift(4.0, 30.0, 12.5)
    x, y = np.random.default_rng(3).uniform(-3000, 3000, (2, 500))
    z = np.full_like(x, 20.0)
    ux, uy = drift.unit
    moved = HazeField(PATCHES, BANK, later).modulation(x + ux * 50.0, y + uy * 50.0, z)
    assert np.allclose(moved, HazeField(PATCHES, BANK, drift).modulation(x, y, z), rtol=1e-12)


def test_a_level_is_the_mean_over_the_views_horizontal_fan():
    """The normalised density averages 1 over the horizontal lines of sight at camera height
    across the view out to VIEW_REACH_M: checked by a finer grid than the normaliser's."""
    medium = _medium()
    az = np.radians(VIEW.heading_deg + VIEW.fov_deg * ((np.arange(257) + 0.5) / 257 - 0.5))
    r = (np.arange(8000) + 0.5) / 8000 * VIEW_REACH_M
    x, y = r * np.cos(az)[:, None], r * np.sin(az)[:, None]
    mean = medium.density_at(x, y, np.full_like(x, VIEW.height_m)).mean()
    assert mean == pytest.approx(1.0, rel=2e-3)


@pytest.mark.parametrize("quadrature", ["numpy", "kernel"])
@pytest.mark.parametrize("profile", ["slab", "fog layer"])
def test_optical_depths_equal_a_finer_integration(profile, quadrature, request):
    """Reduced lengths of rays up, down and level (sea, sky, into and out of the bank and a
    fog layer) against Simpson's rule on a far finer grid, to 1e-4: summed by numpy and by
    the render's drjit kernel (seahaze.render.field_quadrature), on a drifted field."""
    base = (
        HomogeneousSlab(top=300.0, albedo=0.998, g=0.75)
        if profile == "slab"
        else fog_layer_medium(25.0, 3.0, 0.25, 300.0, 40.0)
    )
    medium = _medium(base, HazeField(PATCHES, BANK, Drift(7.0, 35.0, 12.0)))
    if quadrature == "kernel":
        request.getfixturevalue("mitsuba_variant")
        from seahaze.render.field_quadrature import with_kernel_quadrature

        medium = with_kernel_quadrature(medium)
        assert medium.quadrature is not None
    origin = np.array([0.0, 0.0, 40.0 if profile == "fog layer" else 12.0])
    rng = np.random.default_rng(4)
    az = np.radians(rng.uniform(-20, 40, 12))
    dz = np.array([-0.05, -0.02, -0.005, 0.0, 0.003, 0.01, 0.05, 0.2, -0.01, 0.0, 0.02, -0.1])
    d = np.stack([np.cos(az), np.sin(az), np.zeros(12)], -1)
    d[:, :2] *= np.sqrt(1 - dz**2)[:, None]
    d[:, 2] = dz
    distance = np.array([800, 1500, 2400, 3000, np.inf, np.inf, np.inf, 500, 5000, 900, 40, 200])
    got = medium.ray_path_length(origin, d, distance)
    for k in range(12):
        end = min(distance[k], RAY_REACH_M)
        if d[k, 2] > 0:  # the ray leaves the haze at its top
            end = min(end, (medium.top_m - origin[2]) / d[k, 2])
        # Composite Simpson on 0.1 m steps (at most 200,001 points): another rule, far finer.
        s = np.linspace(0.0, end, min(200_001, int(end / 0.1) // 2 * 2 + 1))
        p = origin + s[:, None] * d[k]
        want = simpson(medium.density_at(p[:, 0], p[:, 1], p[:, 2]), x=s)
        assert got[k] == pytest.approx(want, rel=1e-4, abs=1e-6), k


@pytest.mark.slow
def test_a_patchy_bank_scene_renders_with_exact_maps(tmp_path):
    """scene → asm render: the transmission maps hold the quadrature's optical depths, and the
    hazy image is the atmospheric scattering model of its own transmittance."""
    path = tmp_path / "patchy.yaml"
    path.write_text(SCENE.format(mode="asm"))
    spec, name = load_scene(path)
    scene = render_scene(spec, name)
    medium_meta = scene.meta["haze"]["medium"]
    assert medium_meta["kind"] == "NonUniformHaze" and "bank" in medium_meta
    geo = scene.geometry
    for level in scene.levels:
        tau = level.transmission.optical_depth[..., 1]
        # Pixels with more and less haze than the level's mean along their rays: the field
        # is not uniform in this view.
        surface = np.isfinite(geo.distance_m)
        v_eff = level.transmission.visibility_eff_m[surface]
        assert v_eff.min() < level.visibility_m and v_eff.max() > 2 * level.visibility_m
        t = np.exp(-tau.astype(np.float64))
        airlight = level.airlight.rgb[1]
        want = scene.clean[..., 1] * t + airlight * (1 - t)
        np.testing.assert_allclose(level.radiance[..., 1], want, rtol=2e-4, atol=1e-6)


@pytest.mark.slow
def test_the_physical_mode_renders_haze_that_varies_across(tmp_path):
    """``physical`` renders each pixel's equivalent profile (render.pixel_density): from the
    command line it writes the dataset, and what the haze does to each pixel (hazy minus
    clean) follows the same per-pixel optical depths as ``asm``'s exact composite."""
    path = tmp_path / "patchy.yaml"
    path.write_text(SCENE.format(mode="physical"))
    out = tmp_path / "o"
    code, _, stderr = cli_run(["render", str(path), "--out", str(out), "--quiet"], seconds=120)
    assert code == 0, stderr
    assert len(list((out / "transmission").glob("*/*.exr"))) == 2
    spec, name = load_scene(path)
    physical = render_scene(spec, name)
    composite = render_scene(with_overrides(spec, mode="asm"), name)
    for ours, exact in zip(physical.levels, composite.levels, strict=True):
        change = (ours.radiance - physical.clean)[..., 1].ravel()
        want = (exact.radiance - composite.clean)[..., 1].ravel()
        assert np.corrcoef(change, want)[0, 1] > 0.9


@pytest.mark.parametrize(
    ("block", "says"),
    [
        ("patches: {correlation_m: 5}", "correlation_m"),
        ("patches: {density_ratio: 1000}", "density_ratio"),
        ("bank: {distance_m: 900, bearing_deg: 150}", "bearing_deg"),
        ("bank: {distance_m: 10}", "distance_m"),
        ("bank: {bearing_deg: 0}", "distance_m"),
        ("drift: {speed_m_s: -1}", "speed_m_s"),
    ],
)
def test_bad_haze_fields_get_located_one_line_errors(tmp_path, block, says):
    text = SCENE.format(mode="asm").replace(
        "  patches: {correlation_m: 200, density_ratio: 20}\n"
        "  bank: {distance_m: 900, bearing_deg: 0, edge_m: 60}\n",
        f"  {block}\n",
    )
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    code, _, stderr = cli_run(["validate", str(path)])
    assert code == 2 and says in stderr and f"{path}:" in stderr and "Traceback" not in stderr


def test_uniform_scenes_record_the_config_they_did():
    """A scene without patches or a bank records the same haze config as before they
    existed (no new keys), so its datasets resume unchanged."""
    spec, _ = load_scene(Path(__file__).resolve().parents[1] / "scenes" / "default.yaml")
    assert set(spec.haze.model_dump(mode="json")) == {
        "levels",
        "threshold",
        "extinction_spectrum",
        "albedo",
        "g",
        "top_m",
        "fog_layer",
    }


BANK_SEQUENCE = """\
name: bankseq
camera: {height_m: 12, pitch_deg: -2, fov_deg: 40, resolution: [64, 36]}
sea: {quality: low, seed: 99}
vessels:
  placed:
    - {class: tug, distance_m: 300, bearing_deg: 0, heading_deg: 90, length_m: 25}
haze:
  levels: [1000]
  bank: {distance_m: 700, bearing_deg: 0, edge_m: 40, near_ratio: 0.1}
  drift: {speed_m_s: 25, toward_deg: 180}
sequence: {frames: 3, fps: 0.25}
render: {mode: asm, spp: 1, seed: 3}
"""


@pytest.mark.slow
@pytest.mark.parametrize("mode", ["asm", "physical"])
def test_a_bank_rolling_in_darkens_the_view_frame_by_frame(tmp_path, mode):
    """A bank drifting toward the camera at 25 m/s (edge at 700, 600, 500 m at 0, 4, 8 s): the
    sequence renders end to end, every frame's field is the first one's moved (one density
    scale, the field's time in meta), so the optical depth over the view grows frame by frame
    and the tug at 300 m, in the clear, keeps almost its own. In both modes that render it
    frame by frame from the field: asm and physical (each frame's pixel ratios)."""
    path = tmp_path / "bankseq.yaml"
    path.write_text(BANK_SEQUENCE.replace("mode: asm", f"mode: {mode}"))
    out = tmp_path / "out"
    code, _, err = cli_run(["render", str(path), "--out", str(out), "--quiet"], seconds=120)
    assert code == 0, err
    names = sorted(p.stem for p in (out / "meta").glob("*.json"))
    metas = [json.loads((out / "meta" / f"{n}.json").read_text()) for n in names]
    media = [m["haze"]["medium"] for m in metas]
    assert [m["drift"]["time_s"] for m in media] == [0.0, 4.0, 8.0]
    assert len({m["density_scale"] for m in media}) == 1
    tau = [fileio.read_exr(out / "transmission" / "v1000" / f"{n}.exr")["tau"] for n in names]
    means = [float(t.mean()) for t in tau]
    assert means[0] < means[1] < means[2]
    tug = [m["vessels"][0]["levels"]["v1000"]["optical_depth_centre"] for m in metas]
    assert tug[0] <= tug[1] <= tug[2] < tug[0] * 1.05


def test_a_drifting_banks_frames_share_the_haze_box_and_so_its_kernels(tmp_path):
    """Mitsuba's grid volume writes the haze box into the render kernels: the box widens for the
    bank's thin side on a ladder of widths (2^(1/4) apart), so frames whose banks need about the
    same width get the same box and run the same kernels, while each box still reaches 8
    optical depths along its thinnest line of sight. Uniform haze keeps its exact width."""
    from seahaze.camera import Camera
    from seahaze.haze import haze_box_half_width
    from seahaze.render.scene import haze_box_width
    from seahaze.scene_medium import scene_haze_medium
    from seahaze.visibility import extinction_coefficient

    path = tmp_path / "bankseq.yaml"
    path.write_text(BANK_SEQUENCE)
    spec, _ = load_scene(path)
    camera = Camera.from_spec(spec.camera)
    sigma = extinction_coefficient(1000.0)
    widths, exact = [], []
    for frame in range(3):
        medium = scene_haze_medium(spec, camera, frame)
        base = haze_box_half_width(sigma)
        thinnest = medium.thinnest_horizontal_mean(camera, base)
        assert thinnest < 1.0  # the bank's near side is thinner than the mean
        exact.append(haze_box_half_width(sigma * thinnest))
        widths.append(haze_box_width(medium, camera, sigma))
    assert widths[1] == widths[2]
    for width, needed in zip(widths, exact, strict=True):
        assert needed <= width < needed * 2.0**0.25
        rung = 4.0 * np.log2(width / haze_box_half_width(sigma))
        assert abs(rung - round(rung)) < 1e-9
    uniform = scene_haze_medium(small_spec(), camera)
    assert haze_box_width(uniform, camera, sigma) == max(
        haze_box_half_width(sigma), 3.0 * (uniform.top_m - uniform.bottom_m)
    )
