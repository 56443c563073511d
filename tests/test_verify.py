"""`seahaze verify`: the visibility fit, the contrast measurement, the calibration targets and
the command line, each against values computed here independently."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from seahaze import verify
from seahaze.camera import Camera
from seahaze.cli import main
from seahaze.spec import SceneSpec

SCENE = str(Path(__file__).resolve().parents[1] / "scenes" / "default.yaml")
# A small calibration view: the narrowest one the 12 targets fit in.
SMALL_RES = verify.min_resolution(240)


def _camera(resolution=SMALL_RES) -> Camera:
    return Camera.from_spec(verify.calibration_spec(SceneSpec(), resolution).camera)


@pytest.mark.parametrize(("threshold", "eps"), [("koschmieder", 0.02), ("mor", 0.05)])
def test_fit_recovers_visibility_exactly_from_noise_free_contrasts(threshold, eps):
    visibility = 1234.0
    sigma = -math.log(eps) / visibility
    d = np.geomspace(0.05, 1.5, 12) * visibility
    contrast = -np.exp(-sigma * d)
    stderr = np.linspace(0.001, 0.02, 12)  # any weights: exact data fit exactly
    fit = verify.fit_extinction(d, contrast, stderr)
    assert fit.sigma == pytest.approx(sigma, rel=1e-9)
    assert verify.visibility_from_extinction(fit.sigma, threshold) == pytest.approx(
        visibility, rel=1e-9
    )
    assert fit.chi2_per_dof == pytest.approx(0.0, abs=1e-12)
    assert fit.informative == np.sum(-contrast >= 3.0 * stderr) < 12


def test_fit_standard_error_matches_the_scatter_of_noisy_fits():
    # Gaussian noise of known size on every contrast, far targets lost in it: the fit stays
    # unbiased and its reported standard error equals the scatter over repetitions.
    rng = np.random.default_rng(5)
    sigma = 3.912e-3
    d = np.geomspace(0.05, 1.5, 12) * 1000.0
    se = np.full(12, 0.02)
    fits = [
        verify.fit_extinction(d, -np.exp(-sigma * d) + rng.normal(0.0, se), se) for _ in range(300)
    ]
    values = np.array([f.sigma for f in fits])
    reported = np.mean([f.sigma_se for f in fits])
    assert 0.005 < reported / sigma < 0.05  # a real, finite noise level
    assert np.std(values) == pytest.approx(reported, rel=0.15)
    assert abs(values.mean() - sigma) < 4.0 * reported / math.sqrt(len(values))
    assert np.mean([f.chi2_per_dof for f in fits]) == pytest.approx(1.0, abs=0.1)


def test_fit_without_any_target_above_the_noise_gives_nan():
    d = np.array([100.0, 200.0])
    fit = verify.fit_extinction(d, np.array([0.01, -0.01]), np.array([0.02, 0.02]))
    assert math.isnan(fit.sigma) and fit.informative == 0


def test_measured_contrast_and_its_standard_error_on_synthetic_batches():
    # One target (3 x 4 px) with luminance 0.3 beside sky of luminance 1.0, pixel noise 0.1,
    # in 50 batches: C = 0.3 - 1 = -0.7 and se = sqrt((0.1^2/600) + (0.3 * 0.1)^2 / 2400).
    target = verify.Target(0, 100.0, 0.0, 1.0, 20.0, (1, 5), (10, 13), (4, 8), (15, 19))
    rng = np.random.default_rng(0)
    batches = 50
    image = np.ones((batches, 6, 24)) + rng.normal(0.0, 0.1, (batches, 6, 24))
    image[:, 1:5, 10:13] += 0.3 - 1.0
    stats = verify.measure_contrasts(image, [target])
    expected_se = math.sqrt(0.1**2 / 600 + (0.3 * 0.1) ** 2 / 2400)
    assert stats.target_pixels[0] == 12 and stats.sky_pixels[0] == 32
    assert stats.stderr[0] == pytest.approx(expected_se, rel=0.1)
    assert abs(stats.contrast[0] + 0.7) < 4.0 * expected_se


def test_calibration_camera_puts_the_horizon_on_a_row_boundary():
    camera = _camera((512, 13))
    v_h = verify.horizon_row(camera)
    assert v_h == pytest.approx(12.0, abs=1e-9)
    # Independent: the ray through that row boundary is horizontal at every column.
    d = camera.ray_directions(np.array([0.0, 256.0, 511.0]), np.full(3, v_h))
    np.testing.assert_allclose(d[:, 2], 0.0, atol=1e-12)


@pytest.mark.usefixtures("mitsuba_variant")
def test_targets_are_where_they_should_be():
    from seahaze.render import passes
    from seahaze.render.scene import build_scene
    from seahaze.world import SceneGeometry, build_sea

    spec = verify.calibration_spec(SceneSpec(), SMALL_RES)
    camera = Camera.from_spec(spec.camera)
    visibility = 1000.0
    targets = verify.layout_targets(camera, visibility)
    expected = verify.target_fractions() * visibility
    np.testing.assert_allclose([t.distance_m for t in targets], expected)
    sea = build_sea(spec, camera)
    geometry = SceneGeometry(sea.mesh, sea.roughness, sea.surface, [t.instance() for t in targets])
    loaded = build_scene(spec, camera, geometry, [visibility], black_vessels=True)
    geo = passes.render_geometry(loaded)
    v_h = round(verify.horizon_row(camera))
    assert np.all(np.isfinite(geo.distance_m[v_h:]))  # sea (or a target) below the horizon
    for t in targets:
        hit = geo.instance == t.index
        rows = np.nonzero(hit)[0]
        assert hit.sum() >= 4
        # Pixels on the target lie between its front face and its back, straight ahead of it.
        assert np.all(geo.distance_m[hit] >= t.distance_m * 0.9999)
        assert np.all(geo.distance_m[hit] <= t.distance_m + t.width_m)
        azimuth = np.degrees(np.arctan2(geo.directions[hit][:, 1], geo.directions[hit][:, 0]))
        assert np.all(np.abs(azimuth - t.azimuth_deg) <= verify.TARGET_WIDTH_DEG / 2)
        # It stands on the sea: it reaches below the horizon row, and up to 0.5° above it.
        assert rows.max() >= v_h
        top_elevation = np.degrees(np.arcsin(geo.directions[hit][:, 2])).max()
        assert top_elevation <= verify.TARGET_TOP_DEG
        # The measured pixels are on it, and the sky beside it is clear sky.
        r0, r1 = t.rows
        assert r1 == v_h and r1 - r0 >= 1
        assert np.all(geo.instance[r0:r1, slice(*t.columns)] == t.index)
        side = [*range(*t.sky_left), *range(*t.sky_right)]
        assert len(side) >= 2 and np.all(np.isinf(geo.distance_m[r0:r1][:, side]))


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--vis", "300..200"], "reversed"),
        (["--res", "100x10"], "too coarse"),
        (["--batches", "1"], "at least 2"),
        (["--spp", "4", "--batches", "8"], "--spp 4"),
        (["--tolerance", "0"], "--tolerance"),
        (["--target-width", "5"], "--target-width"),
        (["/nonexistent/scene.yaml"], "scene.yaml"),
    ],
)
def test_cli_rejects_bad_input_with_exit_code_2(args, message, capsys, tmp_path):
    assert main(["verify", *args, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "report.json").exists()


@pytest.mark.usefixtures("mitsuba_variant")
def test_asm_end_to_end_recovers_the_label(tmp_path, capsys):
    # ASM composes I = J t + A (1 - t): on a black target J = 0 and on the horizon sky t ~ 0,
    # so C = -t exactly whatever the Monte Carlo noise of A.
    res = "{}x{}".format(*SMALL_RES)
    code = main(
        ["verify", SCENE, "--mode", "asm", "--vis", "500", "--res", res, "--spp", "4", "--batches",
         "2", "--out", str(tmp_path), "--quiet"]
    )  # fmt: skip
    assert code == 0
    report = json.loads((tmp_path / "report.json").read_text())
    (level,) = report["levels"]
    assert level["measured_m"] == pytest.approx(500.0, rel=1e-4)
    for target in level["targets"]:
        assert target["contrast"] == pytest.approx(target["expected"], abs=1e-4)
    assert (tmp_path / "contrast.png").stat().st_size > 10_000
    assert "PASS" in capsys.readouterr().out


@pytest.mark.usefixtures("mitsuba_variant")
def test_reference_end_to_end_is_within_its_noise(tmp_path, capsys):
    # Brute-force volpath at low spp: the measured visibility must agree with the label within
    # four of its own standard errors, and those must be small enough to mean something. With
    # a tolerance of 0.01 % the run must fail (exit code 1).
    code = main(
        ["verify", SCENE, "--vis", "1000", "--res", "512x13", "--spp", "256", "--batches", "8",
         "--tolerance", "0.0001", "--out", str(tmp_path), "--quiet"]
    )  # fmt: skip
    assert code == 1
    (level,) = json.loads((tmp_path / "report.json").read_text())["levels"]
    se = level["stderr_m"]  # the larger of the fit's and the jackknife's
    assert 0.0 < level["stderr_fit_m"] <= se < 80.0
    assert abs(level["measured_m"] - 1000.0) <= 4.0 * level["stderr_fit_m"]
    assert level["informative_targets"] >= 3
    assert "FAIL" in capsys.readouterr().out


def test_denoise_without_the_denoiser_is_refused_before_rendering(tmp_path, capsys) -> None:
    from seahaze.cli import main
    from seahaze.render import denoise

    if denoise.available():
        pytest.skip("pyoidn is installed: the refusal cannot be seen")
    code = main(["verify", "--denoise", "on", "--spp", "16", "--out", str(tmp_path / "v")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "pip install 'seahaze[denoise]'" in err
    assert not (tmp_path / "v").exists()
