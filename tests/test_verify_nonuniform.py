"""`seahaze verify` in haze that varies across the sea: each black target reads the contrast
``-exp(-σ ℓ)`` of its own rays, ``ℓ = ∫ρ ds``, and the fit against ``ℓ`` measures the level;
checked against a Simpson integral of the medium's density along the targets' rays, computed
here from the camera and the targets' geometry."""

from __future__ import annotations

import contextlib
import io
import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import simpson

from seahaze import verify
from seahaze.camera import Camera
from seahaze.cli import main
from seahaze.scene_medium import scene_haze_medium
from seahaze.sceneio import load_scene
from seahaze.visibility import extinction_coefficient

SCENES = Path(__file__).resolve().parents[1] / "scenes"
PATCHY = SCENES / "patchy.yaml"
# The narrowest calibration view the 12 targets fit in: 240x8, 4 pixels on every target.
SMALL_RES = verify.min_resolution(240)
LEVELS = (500.0, 2000.0)


def _simpson_lengths(camera: Camera, target: verify.Target, medium) -> np.ndarray:
    """The reduced length (m) of each of ``target``'s measured pixel-centre rays: from the
    camera to its front face (a vertical plane ``distance_m`` out along its bearing),
    integrated by composite Simpson on steps of at most 0.1 m."""
    rows, cols = verify.target_pixels(target)
    v, u = np.mgrid[rows, cols] + 0.5
    directions = camera.ray_directions(u.ravel(), v.ravel())
    a = math.radians(target.azimuth_deg)
    along = np.array([math.cos(a), math.sin(a), 0.0])
    lengths = []
    for d in directions:
        end = target.distance_m / float(d @ along)
        s = np.linspace(0.0, end, int(end / 0.1) // 2 * 2 + 3)
        p = camera.origin + s[:, None] * d
        lengths.append(simpson(medium.density_at(p[:, 0], p[:, 1], p[:, 2]), x=s))
    return np.array(lengths)


@pytest.fixture(scope="module")
def patchy_asm(tmp_path_factory, mitsuba_variant):
    """``seahaze verify scenes/patchy.yaml --mode asm`` at two levels, tiny: its report and
    printed table."""
    out = tmp_path_factory.mktemp("verify_patchy")
    vis = ",".join(f"{v:g}" for v in LEVELS)
    res = "{}x{}".format(*SMALL_RES)
    text = io.StringIO()
    with contextlib.redirect_stdout(text):
        code = main(
            ["verify", str(PATCHY), "--mode", "asm", "--vis", vis, "--res", res, "--spp", "4",
             "--batches", "2", "--out", str(out), "--quiet"]
        )  # fmt: skip
    return code, json.loads((out / "report.json").read_text()), text.getvalue()


@pytest.mark.slow
def test_asm_fit_recovers_each_level_exactly_against_the_reduced_length(patchy_asm):
    # asm composites I = J t + A (1 - t) with t = exp(-σ ℓ) per pixel: on a black target
    # J = 0 and on the horizon sky t ~ 0, so C = -t and the fit of σ against each target's own
    # rays is exact to float precision. Against the distance d (the uniform law), or against
    # the mean ℓ of a target's rays, it is not (−17 % and 5e-6 at 500 m).
    code, report, _ = patchy_asm
    assert code == 0 and report["passed"]
    assert [lv["visibility_m"] for lv in report["levels"]] == list(LEVELS)
    for level in report["levels"]:
        assert level["measured_m"] == pytest.approx(level["visibility_m"], rel=1e-6)
        assert level["sigma_per_m"] == pytest.approx(3.912 / level["visibility_m"], rel=1e-3)
        assert level["varies_across"] is True
    assert report["config"]["medium"]["kind"] == "NonUniformHaze"


@pytest.mark.slow
def test_each_target_reads_its_own_rays_optical_depth(patchy_asm):
    # Independent: the base scene's medium (normalised over the scene's own 60° view, patches
    # seeded by its render.seed) integrated by Simpson along the measured pixels' rays. The
    # calibration camera's 24° view would normalise the field 1.4 % denser: this fails then.
    _, report, _ = patchy_asm
    base, _ = load_scene(PATCHY)
    medium = scene_haze_medium(base, Camera.from_spec(base.camera))
    spec = verify.calibration_spec(base, SMALL_RES)
    camera = Camera.from_spec(spec.camera)
    for level in report["levels"]:
        visibility = level["visibility_m"]
        sigma = extinction_coefficient(visibility, "koschmieder")
        targets = verify.layout_targets(camera, visibility)
        reported = level["targets"]
        ratios = np.array([t["mean_density"] for t in reported])
        # The two ends of the field: the target in the densest haze and the one in the thinnest.
        for i in (int(np.argmax(ratios)), int(np.argmin(ratios))):
            lengths = _simpson_lengths(camera, targets[i], medium)
            tau = -math.log(float(np.mean(np.exp(-sigma * lengths))))
            t = reported[i]
            assert t["reduced_m"] == pytest.approx(lengths.mean(), rel=1e-4)
            assert t["tau_expected"] == pytest.approx(tau, rel=1e-4)
            assert t["tau_measured"] == pytest.approx(tau, rel=1e-4)
            assert t["mean_density"] == pytest.approx(t["reduced_m"] / t["distance_m"], rel=1e-12)
        for t in reported:
            assert t["tau_measured"] == pytest.approx(t["tau_expected"], rel=1e-4)
            assert t["tau_ratio"] == pytest.approx(1.0, abs=1e-4)
            assert t["expected"] == pytest.approx(-math.exp(-t["tau_expected"]), rel=1e-12)
        # The field is not uniform along the targets' rays: some denser, some thinner.
        assert ratios.max() > 1.1 and ratios.min() < 0.9


@pytest.mark.slow
def test_dense_and_thin_targets_are_counted_and_printed(patchy_asm):
    _, report, text = patchy_asm
    for level in report["levels"]:
        ratios = np.array([t["mean_density"] for t in level["targets"]])
        assert level["dense_targets"] == np.sum(ratios > 1.15)
        assert level["thin_targets"] == np.sum(ratios < 0.87)
    at_500 = report["levels"][0]
    # At 500 m the 12 targets (25-750 m) stand in patches and in gaps alike.
    assert at_500["dense_targets"] >= 2 and at_500["thin_targets"] >= 2
    assert f"{at_500['dense_targets']} of 12 targets in dense haze" in text
    assert "no target in" not in text


def test_the_coverage_note_names_the_missing_side():
    assert verify.coverage([1.3, 0.5, 1.0, 1.16]) == (2, 1)
    assert verify.coverage_note(2, 1, 4) is None
    note = verify.coverage_note(0, 12, 12)
    assert note is not None and "no target of 12 in dense haze (ℓ/d > 1.15):" in note
    note = verify.coverage_note(3, 0, 12)
    assert note is not None and "thin haze (ℓ/d < 0.87)" in note and "dense haze" not in note


def test_fit_over_each_targets_rays_is_exact_where_the_mean_length_is_not():
    # Two rays per target, 20 % apart: the mean of exp(-σℓ) over them is not exp(-σ mean ℓ).
    sigma = 3.912e-3
    rays = [np.array([0.9, 1.1]) * d for d in np.geomspace(50.0, 1500.0, 12)]
    contrast = -np.array([np.mean(np.exp(-sigma * r)) for r in rays])
    stderr = np.full(12, 1e-3)
    fit = verify.fit_extinction(rays, contrast, stderr)
    assert fit.sigma == pytest.approx(sigma, rel=1e-9)
    on_means = verify.fit_extinction(np.array([r.mean() for r in rays]), contrast, stderr)
    assert abs(on_means.sigma / sigma - 1.0) > 1e-3


def test_physical_mode_measures_varying_haze(tmp_path):
    """``physical`` renders patches as each pixel's equivalent profile (render.pixel_density):
    verify runs it and reports every target against its own rays' optical depth."""
    res = "{}x{}".format(*SMALL_RES)
    out = tmp_path / "v"
    code = main(
        ["verify", str(PATCHY), "--mode", "physical", "--vis", "2000", "--res", res,
         "--spp", "4", "--batches", "2", "--out", str(out), "--quiet"]
    )  # fmt: skip
    report = json.loads((out / "report.json").read_text())
    assert code in (0, 1) and report["config"]["mode"] == "physical"
    (level,) = report["levels"]
    assert level["varies_across"] is True and len(level["targets"]) == 12
    # Measured against each target's own rays, not against a uniform haze's σ d.
    ratios = [t["mean_density"] for t in level["targets"]]
    assert max(ratios) > 1.1 * min(ratios)
