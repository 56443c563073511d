"""A fog layer under thinner haze (`haze.fog_layer`): its profile, its reduced height and inverse
in numpy and drjit, what a level means there, the scene YAML, and `physical` against Mitsuba's
`volpath` through the same layer."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import box_vessel, flat_sea_mesh, small_spec
from seahaze.fog_layer import FogLayer, fog_layer_medium
from seahaze.medium import NUMPY, drjit_ops
from seahaze.scene_medium import haze_medium
from seahaze.sceneio import SceneFileError, parse_scene_text

FOG = fog_layer_medium(80.0, 8.0, 0.1, 300.0, 12.0)


def _midpoint_length(medium, oz: float, dz: float, t_end: float) -> float:
    """The reduced length by the midpoint rule on the density (independent of the closed form)."""
    t_end = min(t_end, 5.0e4)  # every ray used here has left the medium by then
    s = (np.arange(400_000) + 0.5) / 400_000 * t_end
    return float(np.sum(medium.density(oz + s * dz, NUMPY)) * t_end / len(s))


def test_the_profile_is_fog_below_thin_haze_above_and_one_at_the_camera() -> None:
    z = np.array([0.0, 12.0, 80.0, 200.0, 299.0, 301.0, -61.0])
    rho = FOG.density(z, NUMPY)
    assert rho[1] == pytest.approx(1.0, abs=1e-12)  # the level's σ holds at the camera
    assert rho[2] == pytest.approx(0.55 * FOG.scale)  # half-way at the fog top
    assert rho[3] == pytest.approx(FOG.scale * (0.1 + 0.9 / (1.0 + np.exp(15.0))), rel=1e-12)
    assert rho[5] == 0.0 and rho[6] == 0.0
    above = fog_layer_medium(80.0, 8.0, 0.1, 300.0, 150.0)  # a camera on a mast above the fog
    assert above.density(np.float64(150.0), NUMPY) == pytest.approx(1.0)
    logistic = lambda x: 1.0 / (1.0 + np.exp(-x))  # noqa: E731
    ratio = (0.1 + 0.9 * logistic(70.0 / 8.0)) / (0.1 + 0.9 * logistic(-70.0 / 8.0))
    assert above.density(np.float64(10.0), NUMPY) == pytest.approx(ratio, rel=1e-12)
    assert 9.9 < ratio < 10.0  # the fog below the mast: ten times the haze the camera is in


@pytest.mark.parametrize(
    ("oz", "dz", "t_end"),
    [
        (12.0, 0.8, np.inf),
        (12.0, 0.05, np.inf),
        (12.0, -0.3, 25.0),
        (12.0, 0.0, 1000.0),
        (12.0, 1e-5, 5000.0),
        (150.0, -0.02, np.inf),
        (150.0, 0.3, 200.0),
        (400.0, -0.5, np.inf),
        (80.0, 0.001, 3000.0),
    ],
)
def test_reduced_length_is_the_integral_of_the_density(oz, dz, t_end) -> None:
    _, got = FOG.reduced_length(np.float64(oz), np.float64(dz), np.float64(t_end), NUMPY)
    assert got == pytest.approx(_midpoint_length(FOG, oz, dz, t_end), rel=1e-6, abs=1e-6)


def test_a_horizontal_line_of_sight_at_the_camera_sees_the_level_extinction() -> None:
    # τ = σ d along the horizon at the camera's height: V keeps its meaning there.
    _, length = FOG.reduced_length(np.float64(12.0), np.float64(0.0), np.float64(1000.0), NUMPY)
    assert length == pytest.approx(1000.0, rel=1e-12)


def test_reduced_height_inverse_and_distance_agree_in_numpy_and_drjit(mitsuba_variant) -> None:
    import mitsuba as mi

    z = np.linspace(-60.0, 300.0, 3001)
    h = FOG.reduced_height(z, NUMPY)
    assert np.all(np.diff(h) > 0) and h[-1] == pytest.approx(FOG.reduced_top_m)
    np.testing.assert_allclose(FOG.height_of(h, NUMPY), z, atol=1e-9)
    ops = drjit_ops()
    np.testing.assert_allclose(np.array(FOG.reduced_height(mi.Float(z), ops)), h, atol=2e-4)
    np.testing.assert_allclose(np.array(FOG.height_of(mi.Float(h), ops)), z, atol=2e-3)
    # The point at a reduced distance has that reduced length up to it.
    rng = np.random.default_rng(4)
    oz, dz = rng.uniform(0.5, 290.0, 2000), rng.uniform(-1.0, 1.0, 2000)
    dz[:50] = 0.0
    enter, total = FOG.reduced_length(oz, dz, np.full(2000, 4000.0), NUMPY)
    reduced = rng.random(2000) * total
    t = FOG.distance_at(oz, dz, enter, reduced, NUMPY)
    _, up_to = FOG.reduced_length(oz, dz, t, NUMPY)
    np.testing.assert_allclose(up_to, reduced, rtol=1e-7, atol=1e-6)
    t32 = FOG.distance_at(*(mi.Float(a) for a in (oz, dz, enter, reduced)), ops)
    np.testing.assert_allclose(np.array(t32), t, rtol=2e-3, atol=0.05)


def test_the_scene_yaml_takes_a_fog_layer_and_refuses_one_past_the_haze_top() -> None:
    spec = parse_scene_text("haze:\n  top_m: 300\n  fog_layer:\n    top_m: 80\n    edge_m: 8\n")
    medium = haze_medium(spec.haze, spec.camera.height_m)
    assert isinstance(medium, FogLayer) and medium.above == 0.1
    assert medium.density(np.float64(spec.camera.height_m), NUMPY) == pytest.approx(1.0)
    text = "haze:\n  top_m: 100\n  fog_layer:\n    top_m: 90\n    edge_m: 10\n    above_ratio: 2\n"
    with pytest.raises(SceneFileError) as err:
        parse_scene_text(text, file="f.yaml")
    lines = str(err.value).splitlines()
    assert any(line.startswith("f.yaml:6: haze.fog_layer.above_ratio") for line in lines)
    with pytest.raises(SceneFileError, match=r"must not pass top_m \(100 m\)"):
        parse_scene_text(text.replace("above_ratio: 2", "above_ratio: 0.5"), file="f.yaml")


@pytest.mark.parametrize(
    ("camera_m", "visibility"), [(12.0, 1000.0), (120.0, 3000.0)], ids=["in-fog", "above-fog"]
)
@pytest.mark.slow
def test_physical_renders_the_fog_layer_as_volpath_does(mitsuba_variant, camera_m, visibility):
    """Sky and sea through a fog up to 60 m with a tenth of its density above, the camera in
    the fog or on a mast above it: `physical` (the layer as a slab in reduced height) against
    `volpath` through the layer's grid volume, within 3 % and their noise."""
    from conftest import SkyAndSea
    from seahaze.world import SceneGeometry

    spec = small_spec(
        camera={"resolution": [48, 27], "fov_deg": 40.0, "pitch_deg": -4.0, "height_m": camera_m},
        haze={"levels": [visibility], "fog_layer": {"top_m": 60.0, "edge_m": 5.0}},
    )
    vessel = box_vessel(0, (500.0, 30.0, 10.0), (40.0, 8.0, 20.0))
    geometry = SceneGeometry(flat_sea_mesh(), 0.05, None, [vessel])
    scene = SkyAndSea(spec, geometry, visibility)
    assert isinstance(scene.scenes["physical"].medium, FogLayer)
    assert scene.sky.sum() > 150 and scene.sea.sum() > 150
    region_means = scene.means
    ref, ref_se = region_means("reference", 256)
    phys, phys_se = region_means("physical", 32)
    allowed = 0.03 * ref + 3.0 * np.hypot(ref_se, phys_se)
    assert np.all(np.abs(phys - ref) <= allowed), (phys / ref - 1.0, allowed / ref)


def test_the_shipped_fog_scene_renders_and_records_its_medium(tmp_path) -> None:
    import json
    from pathlib import Path

    from seahaze.cli import main

    scene = Path(__file__).resolve().parents[1] / "scenes" / "fog_layer.yaml"
    args = ["render", str(scene), "--vis", "1000", "--res", "64x36", "--spp", "2"]
    assert main([*args, "--out", str(tmp_path), "--quiet"]) == 0
    meta = json.loads((tmp_path / "meta" / "fog_layer.json").read_text())
    medium = meta["haze"]["medium"]
    assert medium["kind"] == "FogLayer" and medium["fog_top_m"] == 25.0
    # The camera (40 m, five edge scales above the fog top) is in the thin haze: the density
    # is 1 there, so the fog below is close to 1/above_ratio times denser.
    above = medium["above_ratio"] + (1.0 - medium["above_ratio"]) / (1.0 + np.exp(15.0 / 3.0))
    assert medium["density_scale"] == pytest.approx(1.0 / above, rel=1e-12)
    assert 3.9 < medium["density_scale"] < 4.0
    assert (tmp_path / "images" / "v1000" / "fog_layer.png").stat().st_size > 0
