"""The physical estimator's settings: validated, overridable from scene YAML, recorded in meta."""

from __future__ import annotations

import dataclasses

import pytest

from seahaze.render.estimator import DEFAULT_SETTINGS, EstimatorSettings, settings_from
from seahaze.sceneio import SceneFileError, parse_scene_text
from seahaze.spec import EstimatorSpec


def test_settings_are_frozen_and_checked() -> None:
    with pytest.raises(dataclasses.FrozenInstanceError):
        DEFAULT_SETTINGS.glint_share = 0.1  # type: ignore[misc]
    for bad in ({"glint_share": 1.5}, {"aim_share": -0.1}, {"bounces": 2.5}, {"camera_points": 0}):
        with pytest.raises(ValueError, match=f"estimator.{next(iter(bad))}"):
            EstimatorSettings(**bad)
    with pytest.raises(ValueError, match="max_table_photons"):
        EstimatorSettings(min_table_photons=1 << 18, max_table_photons=1 << 17)


def test_the_vessel_light_spp_is_the_share_rounded_up() -> None:
    assert DEFAULT_SETTINGS.vessel_light_spp(42) == 3  # 42/14 = 3
    assert DEFAULT_SETTINGS.vessel_light_spp(32) == 3  # 2.29, rounded up
    assert DEFAULT_SETTINGS.vessel_light_spp(1) == 1
    assert EstimatorSettings(vessel_light_share=0.0).vessel_light_spp(42) == 0
    assert EstimatorSettings(table_photons=4096).photons_for(10**9) == 4096


def test_a_scene_overrides_only_the_fields_it_names() -> None:
    spec = parse_scene_text("render:\n  estimator:\n    glint_share: 0.3\n    bounces: 5\n")
    settings = settings_from(spec.render.estimator)
    assert (settings.glint_share, settings.bounces) == (0.3, 5)
    unchanged = dataclasses.replace(settings, glint_share=0.7, bounces=3)
    assert unchanged == DEFAULT_SETTINGS
    assert settings_from(EstimatorSpec()) == DEFAULT_SETTINGS
    with pytest.raises(ValueError, match="unknown estimator settings: speed"):
        settings_from({"speed": 2})


def test_bad_estimator_values_name_the_file_line_and_allowed_values() -> None:
    text = "render:\n  spp: 8\n  estimator:\n    glint_share: 1.5\n    colour: red\n"
    with pytest.raises(SceneFileError) as err:
        parse_scene_text(text, file="s.yaml")
    lines = str(err.value).splitlines()
    assert any(line.startswith("s.yaml:4: render.estimator.glint_share") for line in lines)
    assert any("1" in line and "glint_share" in line for line in lines)
    assert any(line.startswith("s.yaml:5: render.estimator") and "colour" in line for line in lines)


def test_meta_records_the_settings_a_physical_render_used() -> None:
    from seahaze.render.engine import render_meta

    spec = parse_scene_text("render:\n  spp: 42\n  estimator:\n    vessel_light_radius_px: 4\n")
    meta = render_meta(spec)
    assert meta["estimator"] == dataclasses.asdict(
        dataclasses.replace(DEFAULT_SETTINGS, vessel_light_radius_px=4)
    )
    assert meta["vessel_light"] == {"spp": 3, "smoothing_radius_px": 4}  # 42 / 14
    asm = parse_scene_text("render:\n  mode: asm\n")
    assert "estimator" not in render_meta(asm)


@pytest.mark.parametrize(
    "text",
    ["sequence:\n  frames: true\n", "render:\n  spp: false\n", "camera:\n  height_m: true\n"],
)
def test_true_or_false_is_not_taken_for_a_number(text: str) -> None:
    # YAML's booleans once passed as 1/0 (`sequence.frames: true` rendered one frame).
    with pytest.raises(SceneFileError, match=r"s\.yaml:2: .*a number is needed here, not true"):
        parse_scene_text(text, file="s.yaml")
    # A boolean where one is asked for, and denoise's bare on/off, still read as before.
    spec = parse_scene_text("render:\n  denoise: off\n  write_exr: false\n")
    assert spec.render.denoise == "off" and spec.render.write_exr is False


def test_a_sequence_may_not_run_the_sea_clock_past_its_limit() -> None:
    # A tiny --fps once sent the sea to t = 1e300 s without a word.
    from seahaze.spec import OverrideError, SceneSpec, with_overrides

    with pytest.raises(SceneFileError, match=r"q\.yaml:1: .*past the sea's limit of 1e\+06 s"):
        parse_scene_text("sequence:\n  frames: 5\n  fps: 1.0e-300\n", file="q.yaml")
    with pytest.raises(OverrideError, match=r"^sequence: 3 frames at 1e-300 fps end at sea time"):
        with_overrides(SceneSpec(), frames=3, fps=1e-300)
    with_overrides(SceneSpec(), frames=3, fps=1e-5)  # 2e5 s: within the limit
