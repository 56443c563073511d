"""The camera model of the PNGs (issue 32, "a camera model"): lens blur and veiling glare,
sensor shot and read noise, JPEG compression; seeded, one noise realisation per scene.

Expected values come from the laws the model states, computed here independently: the noise
variance ``S + r²`` electrons (EMVA 1288's linear model), Lindeberg's discrete Gaussian as
``e^{-t} I_n(t)`` (scipy's Bessel function, not the DCT the module uses), the sRGB codes of
colour-science's ``cctf_encoding``, and Pillow's own JPEG round trip.
"""

from __future__ import annotations

import hashlib
import io
import json
from pathlib import Path

import numpy as np
import pytest
import scipy.special
import scipy.stats
from PIL import Image

from conftest import cli_run
from seahaze import camera_model, fileio, imaging
from seahaze.dataset.layout import Layout
from seahaze.dataset.writer import write_scene
from seahaze.render.engine import RenderedLevel, SceneRender
from seahaze.render.passes import GeometryPass
from seahaze.sceneio import SceneFileError, parse_scene_text
from seahaze.seeds import Stream, camera_noise_seed, dither_seed
from seahaze.spec import CameraModelSpec, SceneSpec
from seahaze.visibility import CLEAN_LEVEL

ROOT = Path(__file__).resolve().parents[1]
NOISE_ONLY = {"psf_sigma_px": 0.0}
"""A camera model without blur: the sensor's noise alone (and what the other settings add)."""


def _settings(**fields) -> CameraModelSpec:
    # White balance off unless a test asks for it: the other steps' expected values are the
    # renderer's own colours.
    return CameraModelSpec.model_validate({"white_balance": "off", **fields})


def _code_position(linear: np.ndarray) -> np.ndarray:
    """The sRGB encoding × 255 of linear values in [0, 1] (colour-science)."""
    import colour

    encoded = colour.cctf_encoding(np.clip(np.asarray(linear, dtype=np.float64), 0, 1), "sRGB")
    return encoded * 255.0


# --- sensor noise --------------------------------------------------------------------------


def test_normals_are_standard_normal() -> None:
    normals = camera_model.standard_normals(camera_noise_seed(3, "normals"), 200_001)
    assert normals.shape == (200_001,)
    assert abs(normals.mean()) < 4 / np.sqrt(normals.size)
    assert normals.var() == pytest.approx(1.0, abs=4 * np.sqrt(2 / normals.size))
    assert scipy.stats.kstest(normals, "norm").pvalue > 1e-3


@pytest.mark.parametrize(
    ("value", "full_well_e", "read_noise_e"),
    [(0.6, 10700.0, 1.8), (0.05, 10700.0, 1.8), (0.002, 10700.0, 6.8), (0.3, 500.0, 10.0)],
)
def test_flat_field_noise_is_shot_plus_read_noise(value, full_well_e, read_noise_e) -> None:
    # EMVA 1288's linear model: the variance in electrons is the signal (Poisson) plus the
    # read noise's square; in units of the PNG's white, divided by the full well squared.
    flat = np.full((256, 256, 3), value)
    normals = camera_model.standard_normals(camera_noise_seed(1, f"flat{value}"), flat.size)
    signal = camera_model.sensor_signal(flat, full_well_e, read_noise_e, normals)
    electrons = value * full_well_e
    theory = (electrons + read_noise_e**2) / full_well_e**2
    count = signal.size
    # The sample variance's relative standard error is sqrt(2/(n-1)); allow 4 of them.
    assert signal.var(ddof=1) == pytest.approx(theory, rel=4 * np.sqrt(2 / (count - 1)))
    assert signal.mean() == pytest.approx(value, abs=4 * np.sqrt(theory / count))


def test_flat_field_code_noise_follows_through_the_srgb_encoding() -> None:
    # End to end (no blur, no dither): the codes' variance is that of the sRGB encoding of the
    # noisy value, by quadrature over the normal distribution, plus rounding's 1/12.
    value, full_well_e, read_noise_e = 0.2, 2000.0, 5.0
    settings = _settings(**NOISE_ONLY, full_well_e=full_well_e, read_noise_e=read_noise_e)
    flat = np.full((256, 256, 3), value, dtype=np.float32)
    codes = camera_model.capture(flat, 1.0, settings, camera_noise_seed(2, "codes"))
    sigma = np.sqrt(value * full_well_e + read_noise_e**2) / full_well_e
    nodes, weights = np.polynomial.hermite_e.hermegauss(40)
    weights = weights / weights.sum()
    positions = _code_position(value + sigma * nodes)
    mean = float(weights @ positions)
    variance = float(weights @ (positions - mean) ** 2) + 1 / 12
    assert codes.var(ddof=1) == pytest.approx(variance, rel=4 * np.sqrt(2 / codes.size))
    assert codes.mean() == pytest.approx(mean, abs=0.02)


def test_a_saturated_pixel_reads_white_without_noise() -> None:
    radiance = np.full((32, 32, 3), 0.5, dtype=np.float32)
    radiance[:8] = 3.0  # a sun glint, above the full well
    settings = _settings(**NOISE_ONLY, full_well_e=300.0, read_noise_e=20.0)
    codes = camera_model.capture(radiance, 1.0, settings, camera_noise_seed(4, "glint"))
    assert np.all(codes[:8] == 255)
    assert codes[8:].std() > 5  # the rest is noisy: 300 electrons at the full well


# --- optics -----------------------------------------------------------------------------------


def _impulse_response(settings: CameraModelSpec, size: int = 257) -> np.ndarray:
    image = np.zeros((size, size, 3))
    image[size // 2, size // 2] = 1.0
    return camera_model.blur(image, settings)[..., 0]


def _second_moment(response: np.ndarray, axis: int) -> float:
    offsets = np.arange(response.shape[axis]) - response.shape[axis] // 2
    profile = response.sum(axis=1 - axis)
    return float(profile @ offsets**2 / profile.sum())


@pytest.mark.parametrize("sigma", [0.3, 0.6, 1.5, 4.0])
def test_psf_conserves_energy_and_its_second_moment_is_sigma_squared(sigma) -> None:
    response = _impulse_response(_settings(psf_sigma_px=sigma))
    assert response.sum() == pytest.approx(1.0, abs=1e-12)
    assert response.min() > -1e-15
    for axis in (0, 1):
        assert _second_moment(response, axis) == pytest.approx(sigma**2, rel=1e-9)


@pytest.mark.parametrize("sigma", [0.6, 4.0])
def test_psf_core_is_lindebergs_discrete_gaussian(sigma) -> None:
    # T(n, t) = e^{-t} I_n(t) with t = sigma², from the Bessel function; separable.
    response = _impulse_response(_settings(psf_sigma_px=sigma), size=65)
    n = np.arange(65) - 32
    kernel = scipy.special.ive(np.abs(n), sigma**2)
    np.testing.assert_allclose(response, np.outer(kernel, kernel), atol=1e-13)


def test_psf_halo_adds_its_share_of_a_wide_gaussian() -> None:
    # A mixture's second moment is the share-weighted second moments of its parts.
    core, halo, share = 0.7, 20.0, 0.04
    settings = _settings(psf_sigma_px=core, halo_fraction=share, halo_sigma_px=halo)
    response = _impulse_response(settings)
    assert response.sum() == pytest.approx(1.0, abs=1e-12)
    expected = (1 - share) * core**2 + share * halo**2
    for axis in (0, 1):
        assert _second_moment(response, axis) == pytest.approx(expected, rel=1e-6)
    # The light within 5 px is each part's share of its kernel's mass there: nearly all the
    # core's, a small part of the halo's.
    centre = response[128 - 5 : 128 + 6, 128 - 5 : 128 + 6].sum()

    def inside(sigma: float) -> float:
        return float(scipy.special.ive(np.arange(-5, 6), sigma**2).sum() ** 2)

    assert centre == pytest.approx((1 - share) * inside(core) + share * inside(halo), rel=1e-12)
    assert 1 - centre > 0.9 * share


def test_blur_keeps_a_flat_field_flat_and_loses_no_light_at_the_edges() -> None:
    settings = _settings(psf_sigma_px=1.2, halo_fraction=0.05, halo_sigma_px=15.0)
    flat = np.full((36, 64, 3), 0.37)
    np.testing.assert_allclose(camera_model.blur(flat, settings), flat, rtol=1e-12)
    image = np.random.default_rng(5).random((36, 64, 3)) ** 3
    blurred = camera_model.blur(image, settings)
    np.testing.assert_allclose(blurred.sum(axis=(0, 1)), image.sum(axis=(0, 1)), rtol=1e-12)


def test_blur_ignores_nan_and_does_not_spread_it() -> None:
    image = np.full((16, 16, 3), 0.2, dtype=np.float32)
    image[3, 4] = np.nan
    blurred = camera_model.blur(image, _settings(psf_sigma_px=1.0))
    assert np.all(np.isfinite(blurred))
    assert blurred[12, 12, 0] == pytest.approx(float(np.float32(0.2)), abs=1e-12)


# --- JPEG ---------------------------------------------------------------------------------------


def _pillow_jpeg(codes: np.ndarray, quality: int) -> np.ndarray:
    """Pillow's JPEG round trip of ``codes``, written out here."""
    buffer = io.BytesIO()
    Image.fromarray(codes).save(buffer, "JPEG", quality=quality, subsampling="4:2:0")
    return np.asarray(Image.open(io.BytesIO(buffer.getvalue())).convert("RGB"))


def test_jpeg_option_changes_the_pixels_and_round_trips_to_a_png(tmp_path) -> None:
    rng = np.random.default_rng(8)
    radiance = (rng.random((36, 64, 3)) * 0.4).astype(np.float32)
    plain = _settings(**NOISE_ONLY, full_well_e=None)
    jpeg = _settings(**NOISE_ONLY, full_well_e=None, jpeg_quality=75)
    seed = camera_noise_seed(1, "jpeg")
    before = camera_model.capture(radiance, 1.0, plain, seed)
    after = camera_model.capture(radiance, 1.0, jpeg, seed)
    np.testing.assert_array_equal(before, imaging.to_srgb8(radiance, 1.0))
    np.testing.assert_array_equal(after, _pillow_jpeg(before, 75))
    assert np.mean(after != before) > 0.5
    path = tmp_path / "x.png"
    fileio.write_png(path, after)
    with Image.open(path) as image:
        assert image.format == "PNG"
        np.testing.assert_array_equal(np.asarray(image), after)


# --- the writer: seeds, determinism, common random numbers, EXRs -------------------------------


def _scene(render: dict, name: str = "flat", clean_value: float = 0.12) -> SceneRender:
    """A scene in memory (no render): a flat clean image and one level, exposure 1."""
    height, width = 36, 64
    clean = np.full((height, width, 3), clean_value, dtype=np.float32)
    geometry = GeometryPass(
        distance_m=np.full((height, width), np.inf, dtype=np.float32),
        instance=np.full((height, width), -1, dtype=np.int32),
        directions=np.zeros((height, width, 3), dtype=np.float32),
        origin=np.zeros(3),
    )
    level = RenderedLevel("v0300", 300.0, np.full(3, 0.013), np.full_like(clean, 0.3))
    meta = {"scene": name, "render": render}
    return SceneRender(name, "llvm_ad_rgb", 1.0, clean, [level], geometry, [], "", meta)


def _record(seed: int = 11, dither: str = "off", **fields) -> dict:
    settings = _settings(**fields)
    return {**imaging.dither_meta(dither, seed), **camera_model.camera_model_meta(settings, seed)}


def _png(layout: Layout, level: str, name: str = "flat") -> np.ndarray:
    with Image.open(layout.image(level, name)) as image:
        return np.asarray(image)


def test_existing_seed_streams_keep_their_values() -> None:
    # The dither's seed as it was derived before the camera's stream was added, written out.
    def key(name: str) -> int:
        return int.from_bytes(hashlib.sha256(name.encode()).digest()[:16], "little")

    expected = np.random.SeedSequence([7, 13, key("default"), key("v0300")])
    got = dither_seed(7, "default", "v0300")
    np.testing.assert_array_equal(got.generate_state(8), expected.generate_state(8))
    assert [int(s) for s in Stream] == [1, 2, 3, 4, 11, 12, 13, 14, 15, 16]
    camera = np.random.SeedSequence([7, int(Stream.CAMERA_NOISE), key("default")])
    np.testing.assert_array_equal(
        camera_noise_seed(7, "default").generate_state(8), camera.generate_state(8)
    )


def test_clean_and_levels_share_one_noise_realisation(tmp_path) -> None:
    # Common random numbers: each pixel's normal is the same in the clean image and every
    # level, so their standardised residuals agree; another scene's are independent.
    full_well_e, read_noise_e = 400.0, 4.0
    record = _record(**NOISE_ONLY, full_well_e=full_well_e, read_noise_e=read_noise_e)
    for name in ("flat", "other"):
        write_scene(Layout(tmp_path), _scene(record, name))

    def residual(level: str, name: str, value: float) -> np.ndarray:
        decoded = imaging.srgb_decode(_png(Layout(tmp_path), level, name) / 255.0)
        sigma = np.sqrt(value * full_well_e + read_noise_e**2) / full_well_e
        return ((decoded - value) / sigma).ravel()

    clean = residual(CLEAN_LEVEL, "flat", 0.12)
    level = residual("v0300", "flat", 0.3)
    other = residual(CLEAN_LEVEL, "other", 0.12)
    # Only the 8-bit rounding (0.06–0.1 of a sigma here) tells the two levels' noise apart.
    assert np.corrcoef(clean, level)[0, 1] > 0.99
    assert abs(np.corrcoef(clean, other)[0, 1]) < 4 / np.sqrt(clean.size)


def test_same_seed_same_bytes_and_another_seed_other_bytes(tmp_path) -> None:
    fields = {"full_well_e": 2000.0, "halo_fraction": 0.02, "jpeg_quality": 90}
    for folder, seed in (("a", 11), ("b", 11), ("c", 12)):
        write_scene(Layout(tmp_path / folder), _scene(_record(seed, "on", **fields)))
    for level in (CLEAN_LEVEL, "v0300"):
        a, b, c = (Layout(tmp_path / f).image(level, "flat").read_bytes() for f in "abc")
        assert a == b
        assert a != c


def test_writer_png_is_png_pixels_and_the_exr_stays_linear(tmp_path) -> None:
    record = _record(11, "on", psf_sigma_px=0.8, full_well_e=3000.0, jpeg_quality=85)
    scene = _scene(record)
    write_scene(Layout(tmp_path), scene)
    for level, radiance in ((CLEAN_LEVEL, scene.clean), ("v0300", scene.levels[0].radiance)):
        expected = camera_model.png_pixels(radiance, 1.0, record, "flat", level)
        np.testing.assert_array_equal(_png(Layout(tmp_path), level), expected)
        exr = fileio.read_exr(Layout(tmp_path).exr(level, "flat"))["RGB"]
        np.testing.assert_array_equal(exr, radiance)


def test_without_a_camera_model_the_png_is_the_encoding_alone(tmp_path) -> None:
    # The PNG of a render before the camera model existed: exposure, sRGB and the dither.
    record = imaging.dither_meta("on", 11)
    scene = _scene(record)
    write_scene(Layout(tmp_path), scene)
    expected = imaging.to_srgb8(scene.clean, 1.0, dither_seed(11, "flat", CLEAN_LEVEL))
    np.testing.assert_array_equal(_png(Layout(tmp_path), CLEAN_LEVEL), expected)
    assert camera_model.camera_model_meta(None, 11) == {}
    assert camera_model.settings_from_meta(record) is None


# --- the scene file --------------------------------------------------------------------------


def test_camera_model_field_defaults_and_record() -> None:
    assert SceneSpec().render.camera_model is None
    # Off, the recorded config has no key (configs recorded before it read the same).
    assert "camera_model" not in SceneSpec().model_dump(mode="json")["render"]
    spec = parse_scene_text("render:\n  camera_model: {}\n")
    settings = spec.render.camera_model
    assert settings == CameraModelSpec()
    recorded = spec.model_dump(mode="json")["render"]["camera_model"]
    assert recorded == settings.model_dump(mode="json")
    meta = camera_model.camera_model_meta(settings, 9, np.array([2.0, 1.0, 0.5]))
    assert meta["camera_model"]["noise_seed"] == 9
    assert meta["camera_model"]["white_balance_gains"] == [0.5, 1.0, 2.0]
    assert camera_model.settings_from_meta(meta) == settings
    with pytest.raises(ValueError, match="scene's light"):
        camera_model.camera_model_meta(settings, 9)


BAD_CAMERAS = [
    # (yaml, field, words the message must contain)
    ("{psf_sigma_px: -1}", "render.camera_model.psf_sigma_px", ["greater than or equal", "0"]),
    ("{jpeg_quality: 100}", "render.camera_model.jpeg_quality", ["less than or equal to 95"]),
    ("{full_well_e: 10}", "render.camera_model.full_well_e", ["greater than or equal to 100"]),
    ("{read_noise_e: lots}", "render.camera_model.read_noise_e", ["number"]),
    ("{halo_fraction: 0.9}", "render.camera_model.halo_fraction", ["less than or equal to 0.5"]),
    ("{full_well: 5000}", "render.camera_model.full_well", ["unknown key", "full_well_e"]),
    ("sharp", "render.camera_model", ["dictionary"]),
]


@pytest.mark.parametrize(("value", "field", "words"), BAD_CAMERAS)
def test_bad_camera_model_is_one_located_line(value, field, words) -> None:
    with pytest.raises(SceneFileError) as info:
        parse_scene_text(f"render:\n  seed: 3\n  camera_model: {value}\n", "cam.yaml")
    problem = info.value.problems[0]
    assert (problem.file, problem.line, problem.field) == ("cam.yaml", 3, field)
    assert "\n" not in problem.message
    for word in words:
        assert word in problem.message, problem.message


# --- a real render --------------------------------------------------------------------------


def test_rendered_camera_model_changes_only_the_pngs(tmp_path) -> None:
    """The default scene twice in one dataset (64×36, 2 spp, one level), as written and with a
    camera model: the same EXRs; the PNGs are the camera's of those EXRs, meta and the card say
    so, and the scene without it has the PNGs of the encoding alone."""
    text = (ROOT / "scenes" / "default.yaml").read_text()
    plain, camera = tmp_path / "plain.yaml", tmp_path / "camera.yaml"
    plain.write_text(text.replace("name: default", "name: plain"))
    with_camera = "render:\n  camera_model: {halo_fraction: 0.02, jpeg_quality: 90}\n"
    camera_text = text.replace("name: default", "name: camera").replace("render:\n", with_camera)
    camera.write_text(camera_text)
    out = tmp_path / "out"
    args = ["render", str(plain), str(camera), "--vis", "300", "--res", "64x36", "--spp", "2"]
    code, _, err = cli_run([*args, "--out", str(out), "--quiet"], seconds=240)
    assert code == 0, err
    manifest = json.loads((out / "dataset.json").read_text())
    assert "camera_model" not in manifest["scenes"]["plain"]["config"]["render"]
    assert manifest["scenes"]["camera"]["config"]["render"]["camera_model"]["jpeg_quality"] == 90
    card = (out / "README.md").read_text()
    assert "camera model (1 of 2 scenes; clean and every level alike" in card
    assert "jpeg_quality 90" in card
    for level in (CLEAN_LEVEL, "v0300"):
        exr = {n: (out / "exr" / level / f"{n}.exr").read_bytes() for n in ("plain", "camera")}
        assert exr["plain"] == exr["camera"]
        radiance = fileio.read_exr(out / "exr" / level / "camera.exr")["RGB"]
        for name in ("plain", "camera"):
            meta = json.loads((out / "meta" / f"{name}.json").read_text())
            with Image.open(out / "images" / level / f"{name}.png") as image:
                png = np.asarray(image)
            expected = camera_model.png_pixels(
                radiance, meta["exposure"], meta["render"], name, level
            )
            np.testing.assert_array_equal(png, expected)
            if name == "plain":
                assert "camera_model" not in meta["render"]
                dither = dither_seed(meta["render"]["dither_seed"], name, level)
                np.testing.assert_array_equal(
                    png, imaging.to_srgb8(radiance, meta["exposure"], dither)
                )


# --- white balance ---------------------------------------------------------------------------


def test_white_balance_makes_the_lights_own_colour_grey() -> None:
    # A white card lit by daylight of colour E reflects E/π: balanced, every channel reads
    # the same code; unbalanced, the warm light stays warm.
    light = np.array([0.77, 0.70, 0.62])  # the default scene's sun and sky (measured below)
    card = np.broadcast_to(0.5 * light / light[1], (8, 8, 3)).astype(np.float32)
    noise = camera_noise_seed(1, "card")
    balanced = camera_model.capture(
        card,
        1.0,
        _settings(psf_sigma_px=0.0, full_well_e=None),
        noise,
        None,
        camera_model.white_balance_gains(light),
    )
    assert np.all(balanced == balanced[..., 1:2])
    raw = camera_model.capture(card, 1.0, _settings(psf_sigma_px=0.0, full_well_e=None), noise)
    assert raw[0, 0, 0] > raw[0, 0, 1] > raw[0, 0, 2]
    # The writer's route: the gains recorded in meta, read back by png_pixels.
    settings = CameraModelSpec(psf_sigma_px=0.0, full_well_e=None)
    record = {
        **imaging.dither_meta("off", 3),
        **camera_model.camera_model_meta(settings, 3, light),
    }
    written = camera_model.png_pixels(card, 1.0, record, "card", CLEAN_LEVEL)
    assert np.all(written == written[..., 1:2])
    with pytest.raises(ValueError, match="three positive"):
        camera_model.white_balance_gains(np.array([1.0, 0.0, 1.0]))


def test_the_illuminant_is_the_clear_days_global_irradiance(mitsuba_variant) -> None:
    # By quadrature of the emitters (illuminant_rgb) and by the clear sky's own sampling
    # (clear_global_irradiance, which the overcast sky is scaled from): two routes, one light.
    from seahaze.render.sky import clear_global_irradiance, illuminant_rgb

    spec = parse_scene_text((ROOT / "scenes" / "default.yaml").read_text())
    sun, sky = spec.sun, spec.sky
    sampled = clear_global_irradiance(
        sun.elevation_deg, sun.azimuth_deg, sky.turbidity, sky.ground_albedo
    )
    np.testing.assert_allclose(illuminant_rgb(spec), sampled, rtol=5e-3)
    overcast = parse_scene_text((ROOT / "scenes" / "overcast.yaml").read_text())
    gains = camera_model.white_balance_gains(illuminant_rgb(overcast))
    np.testing.assert_allclose(gains, 1.0, rtol=1e-6)  # grey light needs no balance
    # The scene's meta carries the gains the PNGs were balanced with.
    from seahaze.render.engine import render_meta
    from seahaze.spec import with_changes

    balanced = with_changes(spec, {"render": {"camera_model": {}}})
    record = render_meta(balanced)["camera_model"]
    np.testing.assert_allclose(record["white_balance_gains"], sampled[1] / sampled, rtol=5e-3)
    off = with_changes(spec, {"render": {"camera_model": {"white_balance": "off"}}})
    assert "white_balance_gains" not in render_meta(off)["camera_model"]
