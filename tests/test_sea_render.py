"""The sea in the renders: whitecap and wake foam, the per-vertex roughness mix, vessel speeds,
and the sea's appearance measured on rendered images against published laws.

Two measurements on small renders carry the physics (docs/ocean.md, "Rendering the sea"):

* **Sun glitter follows Cox–Munk.** A sun-only render looking down at the glitter, inverted
  with Cox & Munk's own glitter equation, gives the mean square slope the image shows. It must
  grow with the wind and equal Cox–Munk's total (the geometry's resolved slopes plus the BSDF's
  sub-grid ones), which also checks that the resolved waves are not counted twice.
* **Whitecap fraction follows Monahan & O'Muircheartaigh.** Renders with and without the foam
  and with a white Lambertian sea give every pixel's foam albedo; its mean over the sea area
  the mesh resolves (each pixel weighted by its area on the sea), divided by Koepke's effective
  whitecap reflectance, is the whitecap fraction the image shows.
"""

from __future__ import annotations

import itertools
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from seahaze import annotate, ocean
from seahaze.camera import Camera
from seahaze.ocean.base import lowpass_weight
from seahaze.sceneio import SceneFileError, load_scene
from seahaze.spec import SceneSpec
from seahaze.vessels import KNOT_M_S, VESSEL_CLASSES
from seahaze.world import (
    SEA_FOAM,
    SEA_FOAM_REFLECTANCE,
    SEA_NEAR_ROUGHNESS,
    build_geometry,
    layout_vessels,
    sun_direction,
    vessel_speeds,
)

LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


def _spec(**sections: dict) -> SceneSpec:
    data: dict[str, dict] = {
        "camera": {"resolution": [64, 36], "height_m": 12.0},
        "sea": {"model": "fft", "quality": "low", "wind_speed": 12.0, "seed": 3},
        "haze": {"levels": [1000.0]},
        "render": {"spp": 4, "mode": "reference"},
    }
    for key, value in sections.items():
        data.setdefault(key, {}).update(value)
    return SceneSpec.model_validate(data)


TUG = {"class": "tug", "distance_m": 200.0, "bearing_deg": 0.0, "heading_deg": 120.0}


# ----------------------------------------------------------------------------- spec and data
def test_speed_kn_beyond_the_class_is_a_located_one_line_error(tmp_path: Path) -> None:
    scene = tmp_path / "fast.yaml"
    scene.write_text(
        "vessels:\n"
        "  placed:\n"
        "    - {class: tanker, distance_m: 900, speed_kn: 30}\n"
        "    - {class: buoy, distance_m: 300, speed_kn: 2}\n"
        "    - {class: tug, distance_m: 500, speed_kn: 13}\n"
    )
    with pytest.raises(SceneFileError) as err:
        load_scene(scene)
    where = f"{scene}:3: vessels.placed[0].speed_kn: "
    buoy = f"{scene}:4: vessels.placed[1].speed_kn: "
    assert str(err.value).splitlines() == [
        where + "tanker speed 30 kn is outside the tanker range; allowed: 0 (stopped) to 16 kn",
        buoy + "a buoy is moored: speed 2 kn; allowed: 0",
    ]
    scene.write_text("vessels:\n  placed:\n    - {class: tug, distance_m: 500, speed_kn: -1}\n")
    with pytest.raises(SceneFileError) as err:
        load_scene(scene)
    (line,) = str(err.value).splitlines()
    assert line.startswith(f"{scene}:3: vessels.placed[0].speed_kn: ")
    assert line.endswith("(allowed: >= 0 and <= 40, in kn)")
    with pytest.raises(ValueError, match=r"vessels.placed\[0\].speed_kn: tanker speed 30 kn"):
        spec = _spec(vessels={"placed": [{**TUG, "class": "tanker", "distance_m": 900.0}]})
        fast = spec.model_copy(
            update={
                "vessels": spec.vessels.model_copy(
                    update={"placed": [spec.vessels.placed[0].model_copy(update={"speed_kn": 30})]}
                )
            }
        )
        build_geometry(fast, Camera.from_spec(fast.camera))


def test_placed_vessels_keep_their_speed_and_sampled_ones_draw_in_their_class_range() -> None:
    spec = _spec(
        vessels={
            "placed": [TUG, {**TUG, "distance_m": 600.0, "speed_kn": 9.5}],
            "sample": {"count": 12, "distance_m": [300.0, 5000.0], "seed": 8},
        }
    )
    camera = Camera.from_spec(spec.camera)
    placements = layout_vessels(spec, camera)
    speeds = vessel_speeds(spec, placements)
    assert speeds[0] == 0.0  # an explicit vessel is stopped unless the scene says otherwise
    assert speeds[1] == pytest.approx(9.5 * 1852.0 / 3600.0)
    for placement, speed in zip(placements[2:], speeds[2:], strict=True):
        lo, hi = VESSEL_CLASSES[placement.kind].service_speed_kn
        assert lo * KNOT_M_S <= speed <= hi * KNOT_M_S
    assert len(set(speeds[2:])) > 6  # drawn, not a constant
    # The speeds come from their own sub-stream of the layout seed: same seed, same speeds;
    # the layout is the one the sampler gives without them.
    assert vessel_speeds(spec, layout_vessels(spec, camera)) == speeds
    other = spec.model_copy(
        update={"vessels": spec.vessels.model_copy(update={"sample": replace_seed(spec, 9)})}
    )
    assert vessel_speeds(other, layout_vessels(other, camera))[2:] != speeds[2:]


def replace_seed(spec: SceneSpec, seed: int):
    assert spec.vessels.sample is not None
    return spec.vessels.sample.model_copy(update={"seed": seed})


def test_vessel_meta_records_the_speed() -> None:
    spec = _spec(vessels={"placed": [{**TUG, "speed_kn": 11.0}]})
    geometry = build_geometry(spec, Camera.from_spec(spec.camera))
    (entry,) = annotate.vessel_meta(geometry, [], np.zeros(1, np.int64), {})
    assert entry["speed_kn"] == pytest.approx(11.0)
    assert entry["speed_m_s"] == pytest.approx(11.0 * 1852.0 / 3600.0)


def test_sea_geometry_carries_foam_wakes_and_the_roughness_mix() -> None:
    """The sea mesh's attributes: the whitecaps' foam (in the far field, as a share of fresh
    foam, the albedo of the coverage law's W at Koepke's R_eff and of the residual foam around
    the whitecaps: W·(0.22 + 0.011)/0.55), the wake of a moving vessel, and the near-lobe
    weight; the switches remove them."""
    moving = _spec(vessels={"placed": [{**TUG, "speed_kn": 12.0}]})
    camera = Camera.from_spec(moving.camera)
    geometry = build_geometry(moving, camera)
    sea = geometry.sea
    assert set(sea.attributes) == {SEA_FOAM, SEA_FOAM_REFLECTANCE, SEA_NEAR_ROUGHNESS}
    law = ocean.whitecap_coverage(12.0)
    share = law * (ocean.FOAM_REFLECTANCE + 0.011) / ocean.FRESH_FOAM_REFLECTANCE
    assert geometry.sea_foam_coverage == pytest.approx(share, rel=0.01)
    assert geometry.sea_foam_reflectance == ocean.FRESH_FOAM_REFLECTANCE
    r = np.hypot(sea.vertices[:, 0], sea.vertices[:, 1])
    far = sea.attributes[SEA_FOAM][(r > 5_000.0) & (r < 20_000.0)]
    assert float(np.mean(far)) == pytest.approx(share, rel=0.3)  # distant whitecaps
    assert geometry.sea_roughness == pytest.approx(ocean.cox_munk_alpha(12.0))
    assert geometry.sea_roughness_near is not None
    assert geometry.sea_roughness_near < geometry.sea_roughness
    # The tug's white wake behind its stern (heading 120°: the wake trails toward -60°).
    tug = geometry.vessels[0]
    p = tug.placement
    back = np.radians(p.heading_deg + 180.0)
    stern = np.array([p.x, p.y]) + (0.5 * tug.length_m + 10.0) * np.array(
        [np.cos(back), np.sin(back)]
    )
    near_stern = np.hypot(sea.vertices[:, 0] - stern[0], sea.vertices[:, 1] - stern[1]) < 4.0
    assert sea.attributes[SEA_FOAM][near_stern].max() > 0.5
    assert tug.speed_kn == pytest.approx(12.0)

    still = build_geometry(moving.model_copy(update={"vessels": _spec().vessels}), camera)
    quiet = build_geometry(
        _spec(
            vessels={"placed": [{**TUG, "speed_kn": 12.0}], "wakes": False},
            sea={"whitecaps": False},
        ),
        camera,
    )
    assert SEA_FOAM not in quiet.sea.attributes and quiet.sea_foam_coverage == 0.0
    assert np.all(still.sea.vertices == quiet.sea.vertices)  # no wake waves either
    flat = build_geometry(_spec(sea={"model": "flat"}), camera)
    assert flat.sea.attributes == {} and flat.sea_roughness_near is None
    given = build_geometry(_spec(sea={"roughness": 0.1}), camera)
    assert given.sea_roughness == 0.1 and SEA_NEAR_ROUGHNESS not in given.sea.attributes


@pytest.mark.usefixtures("mitsuba_variant")
def test_the_loaded_scene_exposes_the_flat_sea_optics_for_the_physical_table() -> None:
    """``LoadedScene.sea_roughness`` / ``sea_foam_coverage`` / ``sea_foam_reflectance``, and the
    sea shape's BSDF sampled without a shape (as the physical mode's photon table does) is the
    foam-free far water, ``water_bsdf_dict(spec, sea_roughness)``, sample for sample."""
    import drjit as dr
    import mitsuba as mi

    from seahaze.render.scene import build_scene, water_bsdf_dict

    spec = _spec()
    camera = Camera.from_spec(spec.camera)
    geometry = build_geometry(spec, camera)
    loaded = build_scene(spec, camera, geometry, [1000.0], haze_box=False)
    assert loaded.sea_roughness == pytest.approx(ocean.cox_munk_alpha(12.0))
    # The plane model's foam is the whitecaps' and their residual foam's: a mean albedo of
    # Koepke's W·R_eff and the residual's few per cent, as a share of fresh foam.
    coverage, reflectance = loaded.sea_foam_coverage, loaded.sea_foam_reflectance
    assert reflectance == ocean.FRESH_FOAM_REFLECTANCE
    assert 1.0 < coverage * reflectance / ocean.whitecap_albedo(12.0) < 1.1
    (shape,) = [s for s in loaded.scene.shapes() if s.id() == "sea"]
    water = mi.load_dict(water_bsdf_dict(spec, loaded.sea_roughness))
    n = 4096
    rng = np.random.default_rng(0)
    cos_in = rng.uniform(0.05, 1.0, n)

    def sample(bsdf):
        si = dr.zeros(mi.SurfaceInteraction3f, n)
        si.n = mi.Normal3f(0.0, 0.0, 1.0)
        si.sh_frame = mi.Frame3f(mi.Vector3f(1, 0, 0), mi.Vector3f(0, 1, 0), mi.Vector3f(0, 0, 1))
        si.wi = mi.Vector3f(-np.sqrt(1.0 - cos_in**2), 0.0, cos_in)
        u = np.random.default_rng(1).random((n, 3))
        ctx = mi.BSDFContext(mi.TransportMode.Importance)
        bs, weight = bsdf.sample(ctx, si, mi.Float(u[:, 0]), mi.Point2f(u[:, 1], u[:, 2]))
        return np.array(bs.wo), np.array(weight)

    wo_sea, w_sea = sample(shape.bsdf())
    wo_water, w_water = sample(water)
    np.testing.assert_allclose(w_sea, w_water, rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose(wo_sea, wo_water, atol=1e-6)


@pytest.mark.usefixtures("mitsuba_variant")
def test_wake_foam_is_sea_boxes_and_instances_do_not_change() -> None:
    """A moving vessel's wake changes the sea's pixels, not the vessel's: its instance pixels
    and box are the same as at rest, up to the few pixels the bow wave covers."""
    from seahaze.labels import boxes_from_instances
    from seahaze.render import passes
    from seahaze.render.scene import build_scene

    def geometry_pass(speed: float):
        spec = _spec(
            camera={"resolution": [160, 90], "height_m": 15.0, "fov_deg": 30.0, "pitch_deg": -2.0},
            vessels={"placed": [{**TUG, "speed_kn": speed}]},
        )
        camera = Camera.from_spec(spec.camera)
        geometry = build_geometry(spec, camera)
        loaded = build_scene(spec, camera, geometry, [1000.0])
        return passes.render_geometry(loaded), geometry

    moving, geometry = geometry_pass(12.0)
    still, _ = geometry_pass(0.0)
    assert set(np.unique(moving.instance)) == {-1, 0}
    # The only pixels that change hands are at the waterline, where the wake's waves (the bow
    # wave, the trough along the hull) move the sea up or down the hull by a pixel or two.
    rows, cols = np.nonzero((moving.instance == 0) != (still.instance == 0))
    hull = (moving.instance == 0) | (still.instance == 0)
    waterline = np.array([np.nonzero(hull[:, c])[0].max() for c in cols])
    assert np.all(np.abs(rows - waterline) <= 2)
    assert len(rows) <= 0.1 * np.count_nonzero(still.instance == 0)
    (a,) = boxes_from_instances(moving.instance, [geometry.vessels[0].class_id], None)
    (b,) = boxes_from_instances(still.instance, [geometry.vessels[0].class_id], None)
    assert np.abs(np.array([a.x0, a.y0, a.x1, a.y1]) - [b.x0, b.y0, b.x1, b.y1]).max() <= 1.0
    sea = (moving.instance == -1) & np.isfinite(moving.distance_m)
    assert np.any(np.abs(moving.distance_m[sea] - still.distance_m[sea]) > 0.01)  # the waves


@pytest.mark.usefixtures("mitsuba_variant")
def test_same_seed_same_sea_and_image() -> None:
    """Sampled vessels under way, whitecaps and wakes: the same seed gives the same geometry
    (digest) and the same image bytes and metadata in the ``physical`` mode; another seed
    gives another sea."""
    from seahaze.render.engine import render_scene

    spec = _spec(
        camera={"resolution": [48, 27]},
        vessels={"sample": {"count": 3, "distance_m": [150.0, 1500.0]}},
        render={"mode": "physical", "spp": 2, "seed": 21},
    )
    camera = Camera.from_spec(spec.camera)
    first = build_geometry(spec, camera)
    assert any(v.speed_m_s > 0.0 for v in first.vessels)
    assert build_geometry(spec, camera).digest() == first.digest()
    a, b = render_scene(spec, "a"), render_scene(spec, "a")
    assert a.clean.tobytes() == b.clean.tobytes()
    assert a.levels[0].radiance.tobytes() == b.levels[0].radiance.tobytes()
    assert a.meta == b.meta
    assert [v["speed_kn"] for v in a.meta["vessels"]] == [v.speed_kn for v in first.vessels]
    other = spec.model_copy(update={"render": spec.render.model_copy(update={"seed": 22})})
    assert build_geometry(other, camera).digest() != first.digest()


# ---------------------------------------------------------------- measured on rendered images
def _fresnel(cos_i: np.ndarray, n: float = 1.333) -> np.ndarray:
    """Unpolarised Fresnel reflectance of water at incidence cosine ``cos_i``."""
    cos_t = np.sqrt(np.maximum(1.0 - (1.0 - cos_i**2) / n**2, 0.0))
    rs = ((cos_i - n * cos_t) / (cos_i + n * cos_t)) ** 2
    rp = ((n * cos_i - cos_t) / (n * cos_i + cos_t)) ** 2
    return 0.5 * (rs + rp)


def glitter_mean_square_slope(wind: float, model: str = "fft", roughness=None) -> float:
    """Mean square slope of the sea measured from its sun glitter (Cox & Munk 1954).

    Sun only (sky off, black water body, no foam), the sun at 60° elevation straight ahead, a
    120° camera 100 m up looking 60° down at the glitter. For each sea pixel the facet that
    mirrors the sun into it has the half-vector ``h`` of the view and sun directions, slope
    ``(-h_x/h_z, -h_y/h_z)``; Cox & Munk's glitter equation
    ``L = E·ρ(ω)·p(z_x, z_y) / (4 cos θ_v cos⁴β)`` gives the slope density ``p`` up to a
    constant. A Gaussian fitted to ``ln p`` (weighted least squares over the pixels above 5 %
    of the peak, so the image's finite slope range does not truncate the moments) has the
    covariance whose trace is the mean square slope.
    """
    from seahaze.render.engine import open_session

    sea = {
        "model": model,
        "wind_speed": wind,
        "fetch_km": 20.0,
        "whitecaps": False,
        "water_color": [0.0, 0.0, 0.0],
        "seed": 5,
        "quality": "medium",
    }
    if roughness is not None:
        sea["roughness"] = roughness
    spec = SceneSpec.model_validate(
        {
            "camera": {
                "height_m": 100.0,
                "fov_deg": 120.0,
                "pitch_deg": -60.0,
                "resolution": [64, 64],
            },
            "sun": {"elevation_deg": 60.0, "azimuth_deg": 0.0},
            "sky": {"scale": 0.0},
            "sea": sea,
            "haze": {"levels": [1000.0]},
            "render": {"mode": "reference", "spp": 16, "seed": 1},
        }
    )
    session = open_session(spec)
    y = session.render_clean().astype(float) @ LUMINANCE
    geo = session.pixels
    sea_px = np.isfinite(geo.distance_m) & (geo.instance == -1)
    d = geo.directions.astype(float)[sea_px]
    sun = sun_direction(60.0, 0.0)
    h = sun[None, :] - d
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    zx, zy = -h[:, 0] / h[:, 2], -h[:, 1] / h[:, 2]
    p = y[sea_px] * -d[:, 2] * h[:, 2] ** 4 / _fresnel(h @ sun)
    ok = p > 0.05 * p.max()
    design = np.c_[np.ones(ok.sum()), zx[ok], zy[ok], zx[ok] ** 2, zy[ok] ** 2, zx[ok] * zy[ok]]
    coef, *_ = np.linalg.lstsq(design * p[ok, None], np.log(p[ok]) * p[ok], rcond=None)
    inverse = -2.0 * np.array([[coef[3], 0.5 * coef[5]], [0.5 * coef[5], coef[4]]])
    return float(np.trace(np.linalg.inv(inverse)))


@pytest.mark.usefixtures("mitsuba_variant")
def test_glitter_measurement_recovers_a_known_roughness_on_a_flat_sea() -> None:
    """The measurement itself: on a flat sea the glitter is the BSDF's alone, alpha² known."""
    for wind in (3.0, 15.0):
        measured = glitter_mean_square_slope(wind, model="flat")
        assert measured == pytest.approx(ocean.mean_square_slope(wind), rel=0.03)


@pytest.mark.slow
@pytest.mark.usefixtures("mitsuba_variant")
def test_sun_glitter_widens_with_the_wind_as_cox_and_munk_measured() -> None:
    """The glitter of the rendered sea (resolved waves + sub-grid BSDF) widens monotonically
    with the wind and its mean square slope is Cox–Munk's total (measured 0.93–1.09×, test
    ±20 %). With the full Cox–Munk alpha on top of the resolved waves (the choice before issue
    16) it was 1.18–1.26× — the resolved slopes counted twice."""
    winds = (3.0, 7.0, 11.0, 15.0)
    measured = [glitter_mean_square_slope(w) for w in winds]
    assert all(b > a for a, b in itertools.pairwise(measured))
    for wind, mss in zip(winds, measured, strict=True):
        assert mss == pytest.approx(ocean.mean_square_slope(wind), rel=0.2), (wind, mss)
    double = glitter_mean_square_slope(15.0, roughness=ocean.cox_munk_alpha(15.0))
    assert double > 1.12 * measured[-1]


def whitecap_fraction(wind: float, heading_deg: float) -> tuple[float, float, float]:
    """Whitecap fraction of the rendered sea: ``(by threshold, by mean albedo, area m²)``.

    Camera 60 m up, pitch −60°, 120° field of view; fetch 20 km (peak wavelength 18–27 m, so
    the mesh resolves whitecap patches out to 100–150 m). Three renders of one geometry, clean
    and sky-lit: with the foam (``L``), without it (``L0``), and with a white Lambertian
    everywhere (``L1``, foam fraction and reflectance set to 1). Per pixel the foam albedo is
    ``a = (L - L0)/(L1 - L0)`` (exact for the Lambertian blend up to the water's own small
    radiance); a pixel is whitecap where ``a`` exceeds half of Koepke's effective reflectance,
    the photographic method's threshold halfway between water and an average whitecap.
    Pixels count by their area on the sea (``Ω d² / cos θ``), only where the mesh resolves
    whitecap patches (a quarter peak wavelength: vertex spacing below a sixteenth, displacement
    unfaded), where the threshold is meaningful.
    """
    from seahaze.render import passes
    from seahaze.render.scene import build_scene

    spec = SceneSpec.model_validate(
        {
            "camera": {
                "height_m": 60.0,
                "fov_deg": 120.0,
                "pitch_deg": -60.0,
                "heading_deg": heading_deg,
                "resolution": [96, 96],
            },
            "sun": {"elevation_deg": 50.0, "azimuth_deg": heading_deg + 150.0},
            "sea": {"model": "fft", "wind_speed": wind, "fetch_km": 20.0, "seed": 5},
            "haze": {"levels": [1000.0]},
            "render": {"mode": "reference", "spp": 16, "seed": 2},
        }
    )
    camera = Camera.from_spec(spec.camera)
    geometry = build_geometry(spec, camera)
    attributes = geometry.sea.attributes
    zero, one = np.zeros_like(attributes[SEA_FOAM]), np.ones_like(attributes[SEA_FOAM])
    variants = {
        "foam": {},
        "water": {SEA_FOAM: zero},
        "white": {SEA_FOAM: one, SEA_FOAM_REFLECTANCE: one},
    }
    images = []
    for changes in variants.values():
        sea_mesh = replace(geometry.sea, attributes={**attributes, **changes})
        loaded = build_scene(spec, camera, replace(geometry, sea=sea_mesh), [1000.0])
        images.append(passes.render_clean(loaded, 16, 2, 0.998, 0.75) @ LUMINANCE)
    geo = passes.render_geometry(loaded)  # the same geometry in all three
    lit, water, white = images
    albedo = (lit - water) / np.maximum(white - water, 1e-12)
    # Where the mesh resolves whitecap patches, at the pixel's sea point.
    mesh = ocean.build_sea_mesh_data(geometry.surface, camera_height_m=60.0, quality="medium")
    d = geo.directions.astype(float)
    with np.errstate(invalid="ignore"):
        ground = geo.origin[None, None, :2] + d[..., :2] * geo.distance_m[..., None]
    r = np.hypot(ground[..., 0], ground[..., 1])
    radii = mesh.ring_radii_m[1:]
    spacing = np.interp(r, radii, mesh.vertex_spacing_m[1 :: mesh.n_theta])
    patch = 0.25 * geometry.surface.peak_wavelength_m  # whitecap patches: a quarter wavelength
    weight = lowpass_weight(patch, spacing) * np.interp(
        r, radii, mesh.vertex_fade[1 :: mesh.n_theta]
    )
    sea = np.isfinite(geo.distance_m) & (geo.instance == -1) & (weight > 0.95)
    # Pixel area on the sea: solid angle × distance² / cos(incidence) (flat-sea normal).
    x = (np.arange(96) + 0.5) / 48.0 - 1.0
    tan_half = np.tan(np.radians(60.0))
    u, v = np.meshgrid(x * tan_half, x * tan_half)
    solid = (2.0 * tan_half / 96) ** 2 / (1.0 + u**2 + v**2) ** 1.5
    area = solid * geo.distance_m**2 / np.maximum(-d[..., 2], 1e-6)
    covered = albedo > 0.5 * ocean.FOAM_REFLECTANCE
    by_threshold = float(np.sum(area[sea & covered]) / np.sum(area[sea]))
    by_albedo = float(np.sum((area * albedo)[sea]) / np.sum(area[sea])) / ocean.FOAM_REFLECTANCE
    return by_threshold, by_albedo, float(np.sum(area[sea]))


@pytest.mark.usefixtures("mitsuba_variant")
@pytest.mark.slow
@pytest.mark.parametrize("wind", [8.0, 12.0, 15.0])
def test_rendered_whitecap_fraction_follows_the_coverage_law(wind: float) -> None:
    """The whitecap fraction measured on rendered images — two opposite headings, about two
    periods of the foam field — is within a factor of 2 of W = 3.84e-6 U^3.41 (Monahan &
    O'Muircheartaigh 1980) as the image's mean foam albedo over Koepke's effective 0.22 (the
    pair W·R_eff is what the law and the reflectance mean for an image; measured 0.89–0.96 W).
    The bright cores alone (foam albedo above half of 0.22, a photographic threshold) are a
    part of it (measured 0.38–0.45 W: the fresh foam is smaller than a mesh cell)."""
    law = ocean.whitecap_coverage(wind)
    results = [whitecap_fraction(wind, heading) for heading in (0.0, 180.0)]
    area = sum(a for _, _, a in results)
    by_threshold = sum(t * a for t, _, a in results) / area
    by_albedo = sum(m * a for _, m, a in results) / area
    assert law / 2.0 < by_albedo < 2.0 * law, (by_albedo, law)
    assert 0.2 * law < by_threshold < law, (by_threshold, law)


@pytest.mark.usefixtures("mitsuba_variant")
@pytest.mark.parametrize("heading_deg", [0.0, 120.0])
def test_faint_foam_never_darkens_the_water_it_lies_on(heading_deg: float) -> None:
    """Foam is drawn as a share of fresh foam with the water between (docs/ocean.md,
    *Whitecaps*), so even the faintest foam is at least as bright as the water around it. Drawn
    instead as a Lambertian of its own low reflectance over the whole patch (0.02-0.06 for the
    residual foam), it hid the water's Fresnel reflection of a bright sky at grazing incidence
    and put dark, brownish rims around the whitecaps (that code made 0.1-0.2 % of the sea's
    pixels here more than 20 % darker with the foam than without). A bridge-height camera
    looking 8° down across a force-8 sea, the sun behind it; clean renders with and without
    the foam, the same paths."""
    from seahaze.render import passes
    from seahaze.render.scene import build_scene

    spec = SceneSpec.model_validate(
        {
            "camera": {
                "height_m": 20.0,
                "fov_deg": 60.0,
                "pitch_deg": -8.0,
                "heading_deg": heading_deg,
                "resolution": [160, 90],
            },
            "sun": {"elevation_deg": 30.0, "azimuth_deg": (heading_deg + 140.0) % 360.0},
            "sea": {
                "model": "fft",
                "wind_speed": 17.0,
                "fetch_km": 300.0,
                "seed": 5,
                "direction_deg": heading_deg + 90.0,
            },
            "haze": {"levels": [1000.0]},
            "render": {"mode": "reference", "spp": 16, "seed": 2},
        }
    )
    camera = Camera.from_spec(spec.camera)
    geometry = build_geometry(spec, camera)
    attributes = geometry.sea.attributes
    images = []
    for changes in ({}, {SEA_FOAM: np.zeros_like(attributes[SEA_FOAM])}):
        sea_mesh = replace(geometry.sea, attributes={**attributes, **changes})
        loaded = build_scene(spec, camera, replace(geometry, sea=sea_mesh), [1000.0])
        images.append(passes.render_clean(loaded, 16, 2, 0.998, 0.75) @ LUMINANCE)
    geo = passes.render_geometry(loaded)
    sea = np.isfinite(geo.distance_m) & (geo.instance == -1)
    ratio = images[0][sea] / np.maximum(images[1][sea], 1e-12)
    assert np.mean(ratio > 1.1) > 0.05  # the foam is there, and it shows
    assert np.mean(ratio < 0.8) < 2e-4  # and nowhere does it darken the sea (2 pixels of 10240)
