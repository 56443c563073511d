"""Translucent sails: single sheets of sailcloth that pass a share of their light to the other
side, so that a sail with the sun behind it glows as in photographs instead of standing dark
against the sea (docs/vessels.md, *Sailboat*)."""

from __future__ import annotations

import numpy as np
import pytest

from seahaze import vessels
from seahaze.render.fleet import CLOTH_CLASS, MATERIAL_CLASSES, ROUGHNESS_CLASSES, fleet_meshes
from seahaze.sceneio import parse_scene_text
from seahaze.vessels.geometry import SAIL_DIVISIONS, cambered_sail
from seahaze.vessels.materials import (
    SAIL_CLOTH,
    SAILCLOTH_TRANSMITTANCE,
    Material,
    pick_material,
)
from seahaze.world import build_geometry, frame_camera

LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


def _sails(seed: int, wind_from_deg: float) -> list:
    """The sail parts of a 12 m sloop with the wind ``wind_from_deg`` off its bow."""
    model = vessels.build_vessel("sailboat", 12.0, np.random.default_rng(seed), wind_from_deg)
    return [part for part in model.parts if part.name.startswith("sail_")]


def test_a_material_refuses_a_transmittance_outside_0_to_1() -> None:
    for bad in (-0.1, 1.5):
        with pytest.raises(ValueError, match="transmittance must be in"):
            Material("cloth", (0.5, 0.5, 0.5), 0.5, bad)


def test_sailcloth_is_translucent_and_keeps_it_through_the_palette_jitter() -> None:
    assert all(m.transmittance == SAILCLOTH_TRANSMITTANCE for m in SAIL_CLOTH)
    picked = pick_material(SAIL_CLOTH, np.random.default_rng(3))
    assert picked.transmittance == SAILCLOTH_TRANSMITTANCE
    assert picked.rgb != next(m.rgb for m in SAIL_CLOTH if m.name == picked.name)


def _is_one_open_sheet(mesh) -> bool:
    """One sheet with a single rim: a topological disk (Euler number 1), every interior edge
    shared by two faces, consistently wound."""
    import trimesh

    rim = trimesh.grouping.group_rows(mesh.edges_sorted, require_count=1)
    return (
        mesh.euler_number == 1
        and mesh.is_winding_consistent
        and not mesh.is_watertight
        and len(rim) == 3 * SAIL_DIVISIONS
    )


def test_set_sails_are_single_translucent_sheets() -> None:
    """A set sail is one open sheet (a closed plate would need the sun's light to cross two
    faces, which light sampling cannot connect); a stowed sail's cover is an opaque body."""
    seen = {"set": 0, "stowed": 0}
    for seed in range(4):  # seeds 2 and 3 cover the furled sails in grey sailcloth
        for wind in (60.0, 0.0):  # a beam reach sets the sails; head to wind furls them
            for part in _sails(seed, wind):
                if part.name == "sail_cover":
                    seen["stowed"] += 1
                    assert part.material.transmittance == 0.0 and part.mesh.is_watertight
                    continue
                seen["set"] += 1
                assert part.material.transmittance == SAILCLOTH_TRANSMITTANCE
                assert _is_one_open_sheet(part.mesh) and part.mesh.area > 1.0
    assert seen == {"set": 8, "stowed": 4}


@pytest.mark.parametrize("leeward", [1.0, -1.0])
def test_a_sail_bellies_to_leeward_by_its_camber_with_its_edges_on_the_flat_triangle(
    leeward: float,
) -> None:
    """Luff and leech stay on the plane of tack, head and clew; the foot's chord bows to the
    leeward side by ``4·depth·u(1 - u)`` of its length (``depth·c`` at mid-chord), and each
    chord higher up by the same share of its own, shorter length."""
    tack, head, clew = np.array([0.0, 0, 1]), np.array([0.5, 0, 13]), np.array([-4.5, 0.8, 1.2])
    depth = 0.12
    sail = cambered_sail(tack, head, clew, depth, (0.0, leeward, 0.0))
    assert _is_one_open_sheet(sail)
    normal = np.cross(clew - tack, head - tack)
    normal *= np.sign(normal[1] * leeward) / np.linalg.norm(normal)
    off_plane = (np.asarray(sail.vertices) - tack) @ normal
    assert off_plane.min() > -1e-9  # all of the belly to leeward
    foot = float(np.linalg.norm(clew - tack))
    assert off_plane.max() == pytest.approx(depth * foot, rel=1e-9)  # at mid-foot
    for share in (0.25, 0.5, 0.75):  # along the foot: the parabola
        point = tack + share * (clew - tack)
        flattened = np.asarray(sail.vertices) - off_plane[:, None] * normal
        nearest = np.argmin(np.linalg.norm(flattened - point, axis=1))
        expected = 4.0 * depth * foot * share * (1.0 - share)
        assert off_plane[nearest] == pytest.approx(expected, rel=1e-9)
    for edge_end in (tack, head, clew):
        gap = np.min(np.linalg.norm(np.asarray(sail.vertices) - edge_end, axis=1))
        assert gap < 1e-9


def test_translucent_parts_join_the_cloth_mesh_and_the_class_matches_the_cloth() -> None:
    """Every translucent built-in material is the cloth class's (one BSDF serves them all);
    a sailboat's sails, and only they, land in that mesh."""
    assert MATERIAL_CLASSES[-1] == CLOTH_CLASS == (SAIL_CLOTH[0].roughness, SAILCLOTH_TRANSMITTANCE)
    assert all((m.roughness, m.transmittance) == CLOTH_CLASS for m in SAIL_CLOTH)
    text = """\
name: sails
camera: {height_m: 6, fov_deg: 20, pitch_deg: -0.5, resolution: [64, 36]}
sea: {quality: low, seed: 3, wind_speed: 6, direction_deg: 30}
vessels:
  placed:
    - {class: sailboat, distance_m: 150, bearing_deg: 0, heading_deg: 100, length_m: 12}
    - {class: tug, distance_m: 300, bearing_deg: 5, heading_deg: 10}
"""
    spec = parse_scene_text(text, "sails.yaml")
    camera = frame_camera(spec, None)
    geometry = build_geometry(spec, camera, None)
    fleet = fleet_meshes(geometry.vessels, (camera.x_m, camera.y_m))
    assert len(fleet) == len(ROUGHNESS_CLASSES) + 1
    cloth = fleet[-1]
    assert cloth.transmittance == SAILCLOTH_TRANSMITTANCE
    sails = [p for p in geometry.vessels[0].parts if p.transmittance > 0.0]
    assert sails and all(p.name.split("_", 1)[1].startswith("sail_") for p in sails)
    assert len(cloth.faces) == sum(len(p.faces) for p in sails)
    assert set(cloth.face_vessel) == {0}
    assert all(m.transmittance == 0.0 for m in fleet[:-1])


@pytest.mark.usefixtures("mitsuba_variant")
def test_the_cloth_bsdf_passes_its_share_of_the_diffuse_light_through() -> None:
    """Integrated over the sphere (10^6 uniform directions, light arriving 35° off the
    normal), the cloth BSDF of albedo ``a`` sends ``t·a`` to the far side and about
    ``(1 - t)·a`` back (plus its faint sheen): the share asked of Mitsuba's thin principled
    BSDF is the one it gives. Seen from either face the same."""
    import drjit as dr
    import mitsuba as mi

    from seahaze.render.fleet import vessel_bsdf

    albedo, t = 0.9, SAILCLOTH_TRANSMITTANCE
    paint = {"type": "rgb", "value": [albedo] * 3}
    bsdf = mi.load_dict(vessel_bsdf(0.85, paint, t))
    rng = np.random.default_rng(4)
    d = rng.normal(size=(1_000_000, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    for side in (1.0, -1.0):
        si = dr.zeros(mi.SurfaceInteraction3f, len(d))
        theta = np.radians(35.0)
        si.wi = mi.Vector3f(float(np.sin(theta)), 0.0, float(side * np.cos(theta)))
        si.n = mi.Normal3f(0.0, 0.0, 1.0)
        si.sh_frame = mi.Frame3f(si.n)
        wo = mi.Vector3f(*(mi.Float(d[:, i].astype(np.float32)) for i in range(3)))
        value = np.asarray(bsdf.eval(mi.BSDFContext(), si, wo))
        value = value[:, 0] if value.shape[0] == len(d) else value[0]
        far = side * d[:, 2] < 0.0
        transmitted = 4.0 * np.pi * np.mean(value * far)
        reflected = 4.0 * np.pi * np.mean(value * ~far)
        assert transmitted == pytest.approx(t * albedo, rel=0.02)
        assert (1.0 - t) * albedo * 0.98 < reflected < (1.0 - t) * albedo * 1.15


SCENE = """\
name: backlit
camera: {{height_m: 6, fov_deg: 10, pitch_deg: 0.5, heading_deg: 0, resolution: [96, 54]}}
sun: {{elevation_deg: 20, azimuth_deg: {azimuth}}}
sea: {{quality: low, seed: 3, wind_speed: 6, direction_deg: 30}}
vessels:
  placed:
    - {{class: sailboat, distance_m: 150, bearing_deg: 0, heading_deg: 100, length_m: 12}}
haze: {{levels: [4000]}}
render: {{mode: physical, spp: 16, seed: 1}}
"""


def _sail_luminance(azimuth: float) -> float:
    """Mean clean luminance of the sailboat's pixels more than 2.5 m above the water: its
    sails (and the thin mast)."""
    from seahaze.render.engine import render_scene

    spec = parse_scene_text(SCENE.format(azimuth=azimuth), "backlit.yaml")
    scene = render_scene(spec, "backlit")
    geo = scene.geometry
    height = geo.origin[2] + geo.directions[..., 2] * geo.distance_m
    sail = (geo.instance == 0) & (height > 2.5)
    assert sail.sum() > 40
    return float(np.mean(scene.clean[sail] @ LUMINANCE))


@pytest.mark.usefixtures("mitsuba_variant")
def test_a_sail_with_the_sun_behind_it_glows() -> None:
    """The same sloop broadside to the camera with the sun 20° high in front of the camera
    (behind the sails) and behind it (on them). Lit from behind, the sails show the light
    they let through: measured 0.70 of their front-lit luminance (0.56 in a 480×270 view of
    the same boat), where the opaque closed sails they replace gave 0.10 in that view (their
    shaded face lit only by the sky and sea). The sun's share alone would be ``t/(1 - t)`` =
    0.43; the bright sky near the sun adds to the backlit sails."""
    ratio = _sail_luminance(0.0) / _sail_luminance(180.0)
    assert 0.3 < ratio < 1.0, ratio
