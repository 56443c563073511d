"""The dithered 8-bit encoding of the PNGs (issue 34: hazy skies showed bands of one code).

The reference values are computed here independently: each float's sRGB code position with
colour-science's IEC 61966-2-1 encoding (``cctf_encoding`` × 255), not seahaze's tables.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from conftest import cli_run
from seahaze import fileio, imaging
from seahaze.dataset.layout import Layout
from seahaze.render.engine import RenderedLevel, SceneRender
from seahaze.render.passes import GeometryPass
from seahaze.seeds import dither_seed
from seahaze.spec import SceneSpec, with_overrides
from seahaze.visibility import CLEAN_LEVEL


def _code_position(linear: np.ndarray) -> np.ndarray:
    """The sRGB encoding × 255 of linear values in [0, 1], by colour-science: the code a
    value would have with infinitely many codes."""
    import colour

    encoded = colour.cctf_encoding(np.asarray(linear, dtype=np.float64), function="sRGB")
    return encoded * 255.0


def _linear_at(position: float) -> float:
    """The linear value whose code position is ``position`` (colour-science's decoding)."""
    import colour

    return float(colour.cctf_decoding(position / 255.0, function="sRGB"))


def _flat(position: float, shape=(256, 256, 3)) -> np.ndarray:
    return np.full(shape, _linear_at(position), dtype=np.float32)


def test_same_seed_gives_the_same_png_bytes(tmp_path) -> None:
    rng = np.random.default_rng(3)
    radiance = (rng.random((90, 160, 3)) * 0.3).astype(np.float32)
    paths = []
    for i in range(2):
        # A fresh seed object each time, as the writer derives it for every image.
        image = imaging.to_srgb8(radiance, 2.0, dither_seed(7, "default", "v0300"))
        paths.append(tmp_path / f"{i}.png")
        fileio.write_png(paths[-1], image)
    assert paths[0].read_bytes() == paths[1].read_bytes()


@pytest.mark.parametrize(
    "other", [(7, "default", "v1000"), (7, "default_00001", "v0300"), (8, "default", "v0300")]
)
def test_another_image_or_seed_gets_other_noise(other) -> None:
    # Halfway between two codes a value goes up or down with chance 1/2: two independent
    # dithers disagree on half the values, the same dither on none.
    flat = _flat(140.5)
    first = imaging.to_srgb8(flat, 1.0, dither_seed(7, "default", "v0300"))
    again = imaging.to_srgb8(flat, 1.0, dither_seed(7, "default", "v0300"))
    second = imaging.to_srgb8(flat, 1.0, dither_seed(*other))
    assert np.array_equal(first, again)
    assert np.mean(first != second) == pytest.approx(0.5, abs=0.01)


@pytest.mark.parametrize("position", [1.5, 37.25, 100.0, 128.71, 140.5, 200.05, 253.5])
def test_mean_of_a_flat_field_is_its_float_code(position) -> None:
    flat = _flat(position)
    exact = float(_code_position(flat[0, 0, 0]))  # the float32 value's own position
    image = imaging.to_srgb8(flat, 1.0, dither_seed(1, "flat", f"{position}"))
    # Triangular noise of ±1 code: every value within 1.5 codes of the float ...
    assert np.abs(image - exact).max() < 1.5
    # ... and their mean is the float position: the noise moves in steps of 1/256 code (a bias
    # of at most 1/512) and the mean of 196,608 values has a standard error of 0.0011.
    assert float(image.mean()) == pytest.approx(exact, abs=0.008)
    # Rounding is off by the distance to the nearest code, up to half a code.
    nearest = imaging.to_srgb8(flat, 1.0)
    assert abs(float(nearest.mean()) - exact) == pytest.approx(abs(exact - round(exact)), abs=1e-3)


@pytest.mark.parametrize("position", [100.0, 100.25, 100.5, 100.75])
def test_grain_is_the_same_at_every_value(position) -> None:
    # Triangular noise: the error's standard deviation is half a code wherever the value lies
    # between codes (random rounding's was 0 at a code and 0.5 halfway, which left stripes of
    # finer grain along a gradient).
    flat = _flat(position)
    image = imaging.to_srgb8(flat, 1.0, dither_seed(1, "grain", f"{position}"))
    error = image - _code_position(flat)
    assert float(error.std()) == pytest.approx(0.5, abs=0.005)


def test_clipped_white_and_black_stay_white_and_black() -> None:
    radiance = np.zeros((64, 64, 3), dtype=np.float32)
    radiance[:32] = 5.0  # a sun glint: clips to white
    radiance[40:, :, 1] = np.nan
    image = imaging.to_srgb8(radiance, 1.0, dither_seed(1, "glint", "clean"))
    assert np.all(image[:32] == 255)
    assert np.all(image[32:] == 0)


@pytest.mark.parametrize("position", [0.01, 254.99])
def test_within_a_code_of_black_or_white_the_clip_pulls_inward(position) -> None:
    # Noise below black or above white is clipped: at most 1/8 of a code (the chance that the
    # noise passes half a code) toward the middle, and never beyond the end code.
    flat = _flat(position)
    exact = float(_code_position(flat[0, 0, 0]))
    image = imaging.to_srgb8(flat, 1.0, dither_seed(1, "end", f"{position}"))
    shift = (float(image.mean()) - exact) * (1.0 if position < 128 else -1.0)
    assert 0.1 < shift < 0.126


def test_dither_breaks_the_bands_of_a_smooth_gradient() -> None:
    # A hazy sky as the issue measured it: 24 codes over 320 rows, render noise far below a
    # code. Rounding turns it into 25 bands, so local means (2×32 px blocks, all channels) are
    # off by up to half a code, a step of one code between bands; the dithered local means
    # follow the float gradient under an even grain.
    rows, cols = 320, 256
    positions = np.linspace(130.2, 154.2, rows)
    linear = np.array([_linear_at(p) for p in positions], dtype=np.float32)
    radiance = np.broadcast_to(linear[:, None, None], (rows, cols, 3)).copy()
    exact = _code_position(radiance)

    def block_errors(image: np.ndarray) -> np.ndarray:
        error = image - exact
        return error.reshape(rows // 2, 2, cols // 32, 32, 3).mean(axis=(1, 3, 4))

    nearest = imaging.to_srgb8(radiance, 1.0)
    dithered = imaging.to_srgb8(radiance, 1.0, dither_seed(5, "sky", "v4000"))
    # Rounding: 25 bands one code apart, blocks off by up to half a code.
    column = nearest[:, 0, 1].astype(int)
    assert len(np.unique(column)) == 25
    assert set(np.diff(column)) == {0, 1}
    assert np.abs(block_errors(nearest)).max() > 0.4
    # Dithered: every 2×32 block's mean within 0.25 code of the float (its standard error is
    # 0.5/sqrt(192) = 0.036) ...
    assert np.abs(block_errors(dithered)).max() < 0.25
    assert np.abs(block_errors(dithered)).mean() < 0.05
    # ... and every row's error has mean ~0 and the same spread: no band, no stripe.
    row_error = (dithered - exact).reshape(rows, -1)
    assert np.abs(row_error.mean(axis=1)).max() < 0.1  # standard error 0.5/sqrt(768) = 0.018
    assert np.all(np.abs(row_error.std(axis=1) - 0.5) < 0.07)  # its standard error: 0.013


def test_without_a_seed_the_codes_are_the_nearest() -> None:
    rng = np.random.default_rng(11)
    linear = (rng.random((40, 50, 3)) ** 2).astype(np.float32)
    position = _code_position(linear)
    np.testing.assert_array_equal(imaging.to_srgb8(linear, 1.0), np.round(position))
    dithered = imaging.to_srgb8(linear, 1.0, dither_seed(2, "noise", "clean"))
    assert np.abs(dithered - position).max() < 1.5


def _scene(meta_render: dict) -> SceneRender:
    """A scene in memory with a smooth sky in its clean image and one level (no render)."""
    height, width = 36, 64
    ramp = np.linspace(0.10, 0.14, height, dtype=np.float32)[:, None, None]
    clean = np.broadcast_to(ramp, (height, width, 3)).copy()
    geometry = GeometryPass(
        distance_m=np.full((height, width), np.inf, dtype=np.float32),
        instance=np.full((height, width), -1, dtype=np.int32),
        directions=np.zeros((height, width, 3), dtype=np.float32),
        origin=np.zeros(3),
    )
    level = RenderedLevel("v0300", 300.0, np.full(3, 0.013), clean * np.float32(1.3))
    meta = {"scene": "ramp", "render": meta_render}
    return SceneRender(
        "ramp", "llvm_ad_rgb", 2.5, clean, [level], geometry, [], "", meta, write_exr=False
    )


def _png(layout: Layout, level: str) -> np.ndarray:
    return _png_at(layout.image(level, "ramp"))


@pytest.mark.parametrize("record", [{"dither": "off"}, {}])
def test_writer_rounds_to_nearest_when_meta_says_off_or_nothing(tmp_path, record) -> None:
    from seahaze.dataset.writer import write_scene

    scene = _scene({"spp": 4, **record})
    write_scene(Layout(tmp_path), scene)
    for level, radiance in ((CLEAN_LEVEL, scene.clean), ("v0300", scene.levels[0].radiance)):
        expected = np.round(_code_position(np.clip(radiance * 2.5, 0, 1))).astype(np.uint8)
        np.testing.assert_array_equal(_png(Layout(tmp_path), level), expected)


def test_writer_dithers_each_image_with_its_own_seed(tmp_path) -> None:
    from seahaze.dataset.writer import write_scene

    record = imaging.dither_meta("on", 41)
    assert record == {"dither": "on", "dither_seed": 41}
    scene = _scene({"spp": 4, **record})
    write_scene(Layout(tmp_path), scene)
    for level, radiance in ((CLEAN_LEVEL, scene.clean), ("v0300", scene.levels[0].radiance)):
        png = _png(Layout(tmp_path), level)
        expected = imaging.to_srgb8(radiance, 2.5, dither_seed(41, "ramp", level))
        np.testing.assert_array_equal(png, expected)
        position = _code_position(np.clip(radiance * np.float32(2.5), 0, 1))
        assert np.abs(png - position).max() < 1.5
        assert np.abs(png - position).mean() > 0.3  # dithered: nearest codes would be < 0.25
    again = tmp_path / "again"
    write_scene(Layout(again), _scene({"spp": 4, **record}))
    for level in (CLEAN_LEVEL, "v0300"):
        first = Layout(tmp_path).image(level, "ramp").read_bytes()
        assert Layout(again).image(level, "ramp").read_bytes() == first


def test_render_dither_field() -> None:
    assert SceneSpec().render.dither == "on"
    # YAML 1.1 reads a bare off as false.
    off = SceneSpec.model_validate({"render": {"dither": False}})
    assert off.render.dither == "off"
    assert with_overrides(SceneSpec(), dither="off").render.dither == "off"
    # The default is left out of a recorded config (configs recorded before the field read
    # the same); off is recorded.
    assert "dither" not in SceneSpec().model_dump(mode="json")["render"]
    assert off.model_dump(mode="json")["render"]["dither"] == "off"
    with pytest.raises(ValueError, match="dither"):
        SceneSpec.model_validate({"render": {"dither": "tpdf"}})
    assert imaging.dither_meta("off", 41) == {"dither": "off"}


def test_rendered_dataset_pngs_are_dithered_as_meta_says(dataset) -> None:
    import json

    meta = json.loads((dataset / "meta" / "default.json").read_text())
    manifest = json.loads((dataset / "dataset.json").read_text())
    seed = manifest["scenes"]["default"]["seed"]
    assert {k: meta["render"].get(k) for k in ("dither", "dither_seed")} == {
        "dither": "on",
        "dither_seed": seed,
    }
    for level in ("clean", "v0300", "v4000"):
        radiance = fileio.read_exr(dataset / "exr" / level / "default.exr")["RGB"]
        png = _png_at(dataset / "images" / level / "default.png")
        expected = imaging.to_srgb8(radiance, meta["exposure"], dither_seed(seed, "default", level))
        np.testing.assert_array_equal(png, expected)


def _png_at(path) -> np.ndarray:
    with Image.open(path) as image:
        return np.asarray(image)


def test_dither_off_on_the_command_line_writes_the_nearest_code(tmp_path) -> None:
    """``--dither off`` overrides the scene's default: meta records it, the card's command
    says it, and every PNG is the nearest code of its EXR (64×36 at 2 spp)."""
    scene = Path(__file__).resolve().parents[1] / "scenes" / "default.yaml"
    out = tmp_path / "off"
    args = ["render", str(scene), "--vis", "300", "--res", "64x36", "--spp", "2"]
    code, _, err = cli_run([*args, "--out", str(out), "--dither", "off", "--quiet"], seconds=120)
    assert code == 0, err
    meta = json.loads((out / "meta" / "default.json").read_text())
    assert meta["render"]["dither"] == "off" and "dither_seed" not in meta["render"]
    # The dataset card's equivalent command carries the switch the scene file does not.
    assert "--mode physical --dither off" in (out / "README.md").read_text()
    for level in ("clean", "v0300"):
        radiance = fileio.read_exr(out / "exr" / level / "default.exr")["RGB"]
        expected = imaging.to_srgb8(radiance, meta["exposure"])
        np.testing.assert_array_equal(_png_at(out / "images" / level / "default.png"), expected)
