"""The twilight sky: the atmosphere's published numbers, its columns against closed forms, the
Earth's shadow's geometry, the fall of the light through civil twilight against measured
illuminance, its colours, the emitter's orientation in the world, and a twilight scene."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.ndimage import median_filter

from conftest import emitter_radiance
from seahaze import twilight
from seahaze.overcast import REC709_LUMINANCE
from seahaze.sceneio import SceneFileError, parse_scene_text

SCENES = Path(__file__).resolve().parents[1] / "scenes"


def test_the_rayleigh_depth_is_hansen_and_travis():
    # 0.0973 at 550 nm for the standard atmosphere (Hansen & Travis 1974, eq. 2.29), and the
    # λ^-4 law's steepness between the spectrum's ends (a little over 4 by dispersion).
    depth = twilight.rayleigh_optical_depth(np.array([550.0, 400.0, 700.0]))
    assert depth[0] == pytest.approx(0.0973, abs=5e-4)
    assert math.log(depth[1] / depth[2]) / math.log(700 / 400) == pytest.approx(4.08, abs=0.03)


@pytest.mark.parametrize("turbidity", [2.5, 3.0, 6.0])
def test_the_aerosol_depth_gives_back_ineichens_linke_turbidity(turbidity):
    # Ineichen (2008) at sea level (p/p0 = 1) with 1.5 cm of water vapour, written out in full.
    tau = twilight.aerosol_optical_depth_550(turbidity)
    linke = 3.91 * math.exp(0.689) * tau + 0.376 * math.log(1.5) + 2 + 0.54 - 0.5 + 0.16
    assert linke == pytest.approx(turbidity)
    assert twilight.aerosol_optical_depth_550(2.0) == 0.0  # water vapour alone explains it


def test_vertical_columns_are_the_profiles_integrals():
    # Straight up from the sea: ∫ e^(-z/H) dz = H (1 - e^(-top/H)), and the ozone triangle's
    # area (half its base).
    columns, lit = twilight.sun_columns(np.array([0.0]), np.array([1.0]))
    top = twilight.ATMOSPHERE_TOP_M
    expected = [
        twilight.RAYLEIGH_SCALE_HEIGHT_M * (1 - math.exp(-top / twilight.RAYLEIGH_SCALE_HEIGHT_M)),
        twilight.AEROSOL_SCALE_HEIGHT_M,
        (twilight.OZONE_LAYER_M[2] - twilight.OZONE_LAYER_M[0]) / 2,
    ]
    np.testing.assert_allclose(columns[:, 0], expected, rtol=2e-3)
    assert lit.all()


def test_a_grazing_column_is_chapmans():
    # Horizontal from 30 km up, between grid points: the air's column is n(z)·H·sqrt(πx/2)
    # with x = r/H (Chapman's grazing incidence, asymptotic; its next term is 1/(8x) ≈ 2e-4).
    z, h = 30_000.0, twilight.RAYLEIGH_SCALE_HEIGHT_M
    x = (twilight.EARTH_RADIUS_M + z) / h
    columns, lit = twilight.sun_columns(np.array([z]), np.array([0.0]))
    expected = math.exp(-z / h) * h * math.sqrt(math.pi * x / 2)
    assert columns[0, 0] == pytest.approx(expected, rel=0.01)
    assert lit.all()


@pytest.mark.parametrize("depression_deg", [1.0, 3.0, 6.0])
def test_the_earths_shadow_stands_at_its_geometric_height_overhead(depression_deg):
    # Straight above the observer the sun's line grazes the sea from R (1/cos h - 1) up:
    # about 1 km at 1°, 9 km at 3° and 35 km at 6°.
    edge = twilight.EARTH_RADIUS_M * (1 / math.cos(math.radians(depression_deg)) - 1)
    altitudes = np.array([0.97 * edge, 1.03 * edge])
    cos_sun = np.full(2, -math.sin(math.radians(depression_deg)))
    _, lit = twilight.sun_columns(altitudes, cos_sun)
    assert lit.tolist() == [False, True]


def _illuminance(sun_elevation_deg: float) -> float:
    return float(
        REC709_LUMINANCE @ twilight.sky_grid(sun_elevation_deg, 3.0).horizontal_irradiance()
    )


def test_civil_twilight_dims_the_sky_as_measured():
    # AMS Glossary of Meteorology, "civil twilight": on a clear evening the horizontal
    # illuminance falls from about 410-585 lux at sunset to about 2-3.5 lux at -6°.
    ratio = _illuminance(-6.0) / _illuminance(0.0)
    assert 2.0 / 585.0 <= ratio <= 3.5 / 410.0, ratio
    falling = [_illuminance(e) for e in (0.0, -1.0, -3.0, -6.0)]
    assert falling == sorted(falling, reverse=True)


def _rgb(sky: twilight.SkyGrid, elevation_deg: float, relative_azimuth_deg: float) -> np.ndarray:
    return sky.radiance(np.radians([elevation_deg]), np.radians([relative_azimuth_deg]))[0]


def test_twilight_colours_blue_zenith_orange_glow_blue_grey_shadow():
    sky = twilight.sky_grid(-3.0, 3.0)
    zenith = _rgb(sky, 90.0, 0.0)
    assert zenith[2] > zenith[1] > zenith[0] > 0
    glow = _rgb(sky, 4.0, 0.0)  # low over the sun
    assert glow[0] > glow[1] > glow[2] > 0 and glow[0] > 2 * glow[2]
    assert REC709_LUMINANCE @ glow > 3 * REC709_LUMINANCE @ _rgb(sky, 4.0, 180.0)
    # Opposite the sun the Earth's shadow lies on the horizon, bluer than the pink band
    # (the Belt of Venus) above it.
    shadow, belt = _rgb(sky, 1.0, 180.0), _rgb(sky, 8.0, 180.0)
    assert shadow[2] / shadow[0] > 1.2 * belt[2] / belt[0]
    assert belt[0] > belt[1] and belt[2] > belt[1]  # pink: red and blue over green


def test_ozone_keeps_the_twilight_zenith_blue():
    # Hulburt (1953): without the Chappuis band's absorption of the long grazing paths the
    # zenith after sunset would be yellowish (more red than blue); with it, blue.
    def blue_over_red(ozone_du: float) -> float:
        up = twilight.spectral_radiance(
            np.array([math.pi / 2]), np.array([0.0]), math.radians(-4.0), 3.0, True, ozone_du
        )
        rgb = _to_rgb(up)
        return float(rgb[0, 2] / rgb[0, 0])

    assert blue_over_red(0.0) < 1.0 < 1.5 < blue_over_red(300.0)


def _to_rgb(spectral: np.ndarray) -> np.ndarray:
    import colour

    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    sun = np.asarray(colour.colorimetry.planck_law(twilight.WAVELENGTHS_NM * 1e-9, 5778.0))
    xyz = (spectral * sun / sun.max()) @ np.asarray(cmfs[twilight.WAVELENGTHS_NM])
    return xyz @ np.asarray(colour.models.RGB_COLOURSPACE_sRGB.matrix_XYZ_to_RGB).T


def twilight_spec(**sun):
    spec = parse_scene_text((SCENES / "twilight.yaml").read_text(), "twilight.yaml")
    return spec.model_copy(update={"sun": spec.sun.model_copy(update=sun)}) if sun else spec


@pytest.mark.usefixtures("mitsuba_variant")
@pytest.mark.parametrize("azimuth_deg", [-25.0, 110.0])
def test_the_glow_lies_under_the_sun_in_the_world(azimuth_deg):
    import mitsuba as mi

    from seahaze.render.sky import sun_dict, twilight_dict

    spec = twilight_spec(azimuth_deg=azimuth_deg)
    emitter = mi.load_dict(twilight_dict(spec))
    e = math.radians(4.0)
    radiance = {}
    for name, turn in (("toward", 0.0), ("side", 90.0), ("away", 180.0)):
        a = math.radians(azimuth_deg + turn)
        radiance[name] = emitter_radiance(
            emitter, (math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e))
        )
    assert radiance["toward"][0] > 2 * radiance["side"][0] > 0
    assert radiance["toward"][0] > 3 * radiance["away"][0] > 0
    assert radiance["toward"][0] > radiance["toward"][2]
    assert np.all(emitter_radiance(emitter, (0.6, 0.0, -0.8)) == 0.0)
    # No sun: its emitter is switched off.
    sun = sun_dict(spec)
    assert sun["sun_scale"] == 0.0 and sun["sky_scale"] == 0.0


@pytest.mark.usefixtures("mitsuba_variant")
def test_dusk_follows_the_day_without_a_jump():
    # The model is scaled to the clear sky's luminance at the lowest daylight sun (0.5°): at
    # sunset its sky gives what the clear sky gives there, less the model's own fall from 0.5°
    # to 0° (checked above against measurements), within the emitter's quadrature.
    import mitsuba as mi

    from seahaze.render.sky import horizontal_irradiance, sunsky_dict, twilight_dict

    dusk = mi.load_dict(twilight_dict(twilight_spec(elevation_deg=0.0)))
    day = twilight_spec().model_copy(
        update={"sky": twilight_spec().sky.model_copy(update={"model": "clear"})}
    )
    day = day.model_copy(update={"sun": day.sun.model_copy(update={"elevation_deg": 0.5})})
    clear = mi.load_dict(sunsky_dict(day, sun=False))
    fall = _illuminance(0.0) / _illuminance(0.5)
    ratio = (REC709_LUMINANCE @ horizontal_irradiance(dusk)) / (
        REC709_LUMINANCE @ horizontal_irradiance(clear)
    )
    assert ratio == pytest.approx(fall, rel=0.02)


@pytest.mark.usefixtures("mitsuba_variant")
def test_a_twilight_scene_renders_without_a_sun_its_glow_on_the_right():
    from seahaze.render.engine import open_session
    from seahaze.spec import with_overrides

    spec = with_overrides(twilight_spec(), resolution=(96, 54), spp=4, levels=[1000.0])
    session = open_session(spec)
    clean, levels = session.level_renderer().render_all([3.912e-3])
    assert np.all(np.isfinite(clean)) and np.all(np.isfinite(levels[0].radiance))
    assert clean.min() >= 0.0
    sky = np.isinf(session.pixels.distance_m)
    sky[sky.shape[0] // 3 :] = False
    # The sun set at azimuth -25°, to the right of a camera looking along +x: the right half
    # of the sky is the brighter and the redder.
    half = clean.shape[1] // 2
    left, right = clean[:, :half][sky[:, :half]], clean[:, half:][sky[:, half:]]
    assert right[:, 0].mean() > left[:, 0].mean()
    assert right[:, 0].mean() / right[:, 2].mean() > left[:, 0].mean() / left[:, 2].mean()
    # The haze is lit by that sky alone: a level is no brighter than a sky of its light.
    assert levels[0].radiance.mean() < 2 * clean[sky].mean()
    # No fireflies on the sea: a set sun's glint lobe, at the horizon, once sent the sea's
    # facets' paths along it (11 % of the sea's pixels over twice their neighbourhood's
    # median at this size; 0.4 % since the lobe follows only a shining sun).
    sea = np.isfinite(session.pixels.distance_m) & (session.pixels.instance < 0)
    grey = clean.mean(axis=2)
    assert np.mean((grey > 2.0 * median_filter(grey, 5))[sea]) < 0.02


@pytest.mark.parametrize(
    ("text", "needle"),
    [
        (
            "sun:\n  elevation_deg: -3\n",
            "'clear' sky takes 0.5..89.5 deg; for this sun set sky.model to twilight",
        ),
        ("sun:\n  elevation_deg: 10\nsky:\n  model: twilight\n", "'twilight' sky takes -6..0 deg"),
        ("sun:\n  elevation_deg: -7\nsky:\n  model: twilight\n", "sun.elevation_deg"),
        (
            "sun:\n  elevation_deg: -2\nsky:\n  model: twilight\n"
            "variation:\n  sky_models: [clear]\n",
            "variation.sky_models: its clear skies need a sun above the horizon (0.5..89.5",
        ),
        (
            "variation:\n  sky_models: [overcast, twilight]\n",
            "its overcast skies need a sun above the horizon",
        ),
        (
            "sun:\n  elevation_deg: -2\nsky:\n  model: twilight\n"
            "variation:\n  sun_elevation_deg: [10, 20]\n",
            "variation.sun_elevation_deg draws daylight suns, but every scene's sky is twilight",
        ),
        (
            "variation:\n  twilight_sun_elevation_deg: [-4, -1]\n",
            "no scene of this batch has a twilight sky",
        ),
        ("variation:\n  twilight_sun_elevation_deg: [-8, -1]\n", "greater than or equal to -6"),
    ],
)
def test_a_sun_that_does_not_fit_the_sky_is_named(text, needle):
    with pytest.raises(SceneFileError) as err:
        parse_scene_text(text, "s.yaml")
    message = str(err.value)
    assert message.startswith("s.yaml") and needle in message and "\n" not in message, message


def test_the_phase_functions_are_normalised_and_hg_has_its_mean_cosine():
    # ∫ P dω = 1 over the sphere for both, and the Henyey–Greenstein mean cosine is g.
    mu = np.linspace(-1.0, 1.0, 200_001)
    rayleigh, aerosol = twilight.phase_functions(mu)
    assert 2 * math.pi * np.trapezoid(rayleigh, mu) == pytest.approx(1.0, rel=1e-6)
    assert 2 * math.pi * np.trapezoid(aerosol, mu) == pytest.approx(1.0, rel=1e-4)
    mean_cosine = 2 * math.pi * np.trapezoid(aerosol * mu, mu)
    assert mean_cosine == pytest.approx(twilight.AEROSOL_ASYMMETRY, rel=1e-3)


BATCH = """
sun:
  elevation_deg: 30
variation:
  sun_elevation_deg: [10, 50]
  sky_models: [clear, twilight]
"""


def _drawn(text: str, count: int = 16):
    from seahaze.batch import plan_scenes

    spec = parse_scene_text(text, "dusk.yaml")
    jobs = plan_scenes([(spec, "dusk")], count).jobs
    assert [j.spec for j in jobs] == [j.spec for j in plan_scenes([(spec, "dusk")], count).jobs]
    return [(j.spec.sky.model, j.spec.sun.elevation_deg) for j in jobs]


def test_a_batch_draws_twilight_scenes_each_with_a_sun_of_its_sky():
    drawn = _drawn(BATCH + "  twilight_sun_elevation_deg: [-4, -1]\n")
    assert {m for m, _ in drawn} == {"clear", "twilight"}
    for model, elevation in drawn:
        low, high = (-4.0, -1.0) if model == "twilight" else (10.0, 50.0)
        assert low <= elevation <= high, (model, elevation)
    # Without a twilight range the twilight scenes span civil twilight.
    dusk = [e for m, e in _drawn(BATCH, 24) if m == "twilight"]
    assert dusk and all(-6.0 <= e <= 0.0 for e in dusk) and len(set(dusk)) == len(dusk)


def test_a_twilight_template_keeps_its_sun_or_draws_one_from_its_range():
    template = "sun:\n  elevation_deg: -2.5\nsky:\n  model: twilight\n"
    assert {e for _, e in _drawn(template + "variation:\n  wind_speed: [3, 9]\n", 4)} == {-2.5}
    ranged = _drawn(template + "variation:\n  twilight_sun_elevation_deg: [-5, -3]\n", 8)
    assert all(m == "twilight" and -5.0 <= e <= -3.0 for m, e in ranged)
    assert len({e for _, e in ranged}) == 8


def test_planck_peaks_where_wien_says():
    # Wien's displacement law: λ_max = b/T, b = 2.897771955e-3 m K (CODATA 2018): 501.5 nm at
    # the sun's 5778 K.
    wavelengths = np.linspace(400.0, 600.0, 20_001)
    peak = wavelengths[np.argmax(twilight.planck_radiance(wavelengths, 5778.0))]
    assert peak == pytest.approx(2.897771955e-3 / 5778.0 * 1e9, abs=0.02)


def test_the_spectrum_turns_into_srgb_as_colour_science_computes_it():
    # Mitsuba's CIE 1931 tables and XYZ-to-sRGB matrix against colour-science's, through an
    # independent sum (the test's own): the renderer's colours are the CIE's. colour-science
    # rounds the sRGB matrix to four digits, which moves the small, cancelling entries by up
    # to 2e-4 (of entries up to 1.8).
    spectra = np.eye(len(twilight.WAVELENGTHS_NM))
    np.testing.assert_allclose(twilight.spectrum_to_rgb(), _to_rgb(spectra), rtol=2e-3, atol=5e-4)
