"""The vessels as a fixed set of Mitsuba meshes (src/seahaze/render/fleet.py): every part kept
with its paint, its vessel and its roughness, and one compiled kernel for scenes with
different vessels."""

from __future__ import annotations

import hashlib
import re

import numpy as np
import pytest

from seahaze import vessels
from seahaze.render.fleet import (
    HIDDEN_DEPTH_M,
    MATERIAL_CLASSES,
    ROUGHNESS_CLASSES,
    fleet_meshes,
    roughness_class,
    vessel_spheres,
)
from seahaze.sceneio import parse_scene_text
from seahaze.vessels.materials import Material
from seahaze.world import build_geometry, frame_camera


def _materials_of(module: object) -> set[float]:
    found: set[float] = set()

    def walk(value: object) -> None:
        if isinstance(value, Material):
            found.add(value.roughness)
        elif isinstance(value, tuple | list):
            for item in value:
                walk(item)
        elif isinstance(value, dict):
            for item in value.values():
                walk(item)

    for value in vars(module).values():
        walk(value)
    return found


def test_every_built_in_roughness_is_a_class_of_its_own() -> None:
    """Built-in vessels keep their exact roughness: every roughness their materials use is a
    class (a user mesh's goes to the nearest one)."""
    from seahaze.vessels import buoy, materials, merchant, smallcraft, user_mesh

    used = set().union(
        *(_materials_of(m) for m in (materials, buoy, merchant, smallcraft, user_mesh))
    )
    assert used <= set(ROUGHNESS_CLASSES)
    for kind in vessels.CLASS_NAMES:
        for seed in range(3):
            model = vessels.build_vessel(kind, None, np.random.default_rng(seed))
            assert {part.material.roughness for part in model.parts} <= set(ROUGHNESS_CLASSES)
    assert ROUGHNESS_CLASSES[roughness_class(0.02)] == 0.15
    assert ROUGHNESS_CLASSES[roughness_class(0.52)] == 0.5


SCENE = """
name: fleet
camera: {height_m: 12, pitch_deg: -2, resolution: [64, 36]}
sea: {quality: low}
vessels:
  placed:
    - {class: tug, distance_m: 300, bearing_deg: 5, heading_deg: 200, length_m: 30}
    - {class: sailboat, distance_m: 500, bearing_deg: -8, heading_deg: 90}
    - {class: container_ship, distance_m: 1500, bearing_deg: 12, heading_deg: 10}
haze: {levels: [1000]}
render: {spp: 1, seed: 3}
"""


def test_every_part_keeps_its_faces_paint_and_vessel() -> None:
    spec = parse_scene_text(SCENE, "fleet.yaml")
    camera = frame_camera(spec, None)
    geometry = build_geometry(spec, camera, None)
    fleet = fleet_meshes(geometry.vessels, (camera.x_m, camera.y_m))
    assert [(m.roughness, m.transmittance) for m in fleet] == list(MATERIAL_CLASSES)
    parts = [(v.index, p) for v in geometry.vessels for p in v.parts]
    cloth = len(ROUGHNESS_CLASSES)
    for k, mesh in enumerate(fleet):
        mine = [
            (i, p)
            for i, p in parts
            if (cloth if p.transmittance > 0.0 else roughness_class(p.roughness)) == k
        ]
        if not mine:  # a placeholder: one small triangle far under the sea, nobody's
            assert mesh.face_vessel.tolist() == [-1]
            assert np.all(mesh.vertices[:, 2] == -HIDDEN_DEPTH_M)
            continue
        assert len(mesh.faces) == sum(len(p.faces) for _, p in mine)
        start = 0
        for index, part in mine:  # faces in order, each on its part's own vertices
            faces = mesh.faces[start : start + len(part.faces)]
            np.testing.assert_array_equal(mesh.vertices[faces], part.vertices[part.faces])
            np.testing.assert_allclose(
                mesh.paint[start : start + len(part.faces)],
                np.broadcast_to(part.rgb, (len(part.faces), 3)),
            )
            assert np.all(mesh.face_vessel[start : start + len(part.faces)] == index)
            start += len(part.faces)


def test_every_vessel_lies_in_its_bounding_sphere() -> None:
    """The sphere the vessel-light pass aims at holds every vertex of its vessel (and of no
    placeholder), centred on the vessel's bounding box, and is no larger than the box's
    half-diagonal nor smaller than its half-length."""
    spec = parse_scene_text(SCENE, "fleet.yaml")
    camera = frame_camera(spec, None)
    geometry = build_geometry(spec, camera, None)
    fleet = fleet_meshes(geometry.vessels, (camera.x_m, camera.y_m))
    spheres = vessel_spheres(fleet, len(geometry.vessels))
    assert spheres.shape == (3, 4)
    for vessel, (x, y, z, radius) in zip(geometry.vessels, spheres, strict=True):
        points = np.concatenate([part.vertices for part in vessel.parts]).astype(float)
        low, high = points.min(axis=0), points.max(axis=0)
        np.testing.assert_allclose([x, y, z], 0.5 * (low + high), atol=1e-3)
        assert np.all(np.linalg.norm(points - [x, y, z], axis=1) <= radius + 1e-6)
        assert 0.5 * np.max(high - low) - 1e-6 <= radius <= 0.5 * np.linalg.norm(high - low) + 1e-6
    assert vessel_spheres(fleet, 0).shape == (0, 4)


def _kernel_code(entry: dict) -> str:
    """A digest of a launched kernel's LLVM code (drjit's kernel history) without the layout
    of its virtual calls' instance data: that layout follows the registry ids of the live
    instances, which a scene's objects take from the lowest free ones, in an order that now
    and then depends on when the previous scene's objects were freed. Any value baked into
    the code (a sun direction, a ray count, a buffer's alignment) still shows."""
    code = entry["ir"].getvalue()
    code = re.sub(r"(func|drjit)_[0-9a-f]{32}", r"\1", code)
    code = re.sub(r"ptr %data, i64 \d+", "ptr %data, i64 N", code)
    return hashlib.sha256("\n".join(sorted(code.splitlines())).encode()).hexdigest()


def test_scenes_with_different_vessels_run_one_compiled_kernel() -> None:
    """Two physical renders of scenes with different vessel kinds and counts launch the same
    largest kernel (drjit's kernel hash): the second scene compiles nothing big."""
    dr = pytest.importorskip("drjit")
    from seahaze.render.engine import render_scene

    other = (
        SCENE.replace("name: fleet", "name: other")
        .replace(
            "    - {class: container_ship, distance_m: 1500, bearing_deg: 12, heading_deg: 10}\n",
            "",
        )
        .replace("class: tug", "class: fishing_boat")
    )
    hashes = []
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        for text, name in ((SCENE, "fleet"), (other, "other")):
            dr.kernel_history()  # clear
            render_scene(parse_scene_text(text, f"{name}.yaml"), name)
            biggest = max(dr.kernel_history(), key=lambda h: h.get("operation_count", 0))
            hashes.append(_kernel_code(biggest))
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
    assert hashes[0] == hashes[1]


def test_a_scene_with_another_sun_sea_and_fleet_compiles_no_kernel_of_its_own() -> None:
    """Every kernel of 100 operations or more that a second scene launches — its own sun,
    wind, sea roughness and vessels — is one the first scene launched (drjit's kernel hash):
    no scene value, numpy buffer address or count of rays through vessels is part of a
    kernel, so a batch compiles its kernels once, not a few per scene."""
    dr = pytest.importorskip("drjit")
    from seahaze.render.engine import render_scene

    other = (
        SCENE.replace("name: fleet", "name: other")
        .replace("sea: {quality: low}", "sea: {quality: low, wind_speed: 11, seed: 9}")
        .replace("haze:", "sun: {elevation_deg: 51, azimuth_deg: 250}\nhaze:")
        .replace("class: tug, distance_m: 300", "class: fishing_boat, distance_m: 260")
    )
    launched: list[set[str]] = []
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        for text, name in ((SCENE, "fleet"), (other, "other")):
            dr.kernel_history()  # clear
            render_scene(parse_scene_text(text, f"{name}.yaml"), name)
            history = dr.kernel_history()
            launched.append(
                {_kernel_code(h) for h in history if h.get("operation_count", 0) >= 100}
            )
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
    assert len(launched[1]) >= 5  # the geometry pass, sun, sea, photons and the render
    assert launched[1] <= launched[0]


@pytest.mark.usefixtures("mitsuba_variant")
def test_vessel_bsdfs_are_loaded_once_and_only_the_last_set_is_kept() -> None:
    pytest.importorskip("mitsuba")
    from seahaze.render import fleet

    first = fleet.vessel_materials(fleet.MATERIAL_CLASSES)
    again = fleet.vessel_materials(fleet.MATERIAL_CLASSES)
    assert all(a.bsdf is b.bsdf and a.paint is b.paint for a, b in zip(first, again, strict=True))
    black = fleet.vessel_materials(fleet.MATERIAL_CLASSES, black=True)
    assert not any(a.bsdf is b.bsdf for a, b in zip(first, black, strict=True))
    assert all(m.paint is None for m in black)  # black: nothing painted
    # The painted set was dropped: drjit would trace every live BSDF into the black scene's
    # kernel otherwise.
    assert len(fleet.kept_bsdf_keys()) == len(fleet.MATERIAL_CLASSES)
    assert {key[3] for key in fleet.kept_bsdf_keys()} == {True}


def _loaded(text: str, name: str):
    from seahaze.render.scene import build_scene

    spec = parse_scene_text(text, f"{name}.yaml")
    camera = frame_camera(spec, None)
    geometry = build_geometry(spec, camera, None)
    return build_scene(spec, camera, geometry, [1000.0], haze_box=False), geometry


@pytest.mark.usefixtures("mitsuba_variant")
def test_each_scene_renders_its_own_paint_though_the_textures_are_shared() -> None:
    """The vessels' paint textures are kept from scene to scene with their BSDFs and hold one
    scene's paint at a time: a scene built first and rendered after another was built still
    shows its own colours, and every vessel pixel's albedo is the paint of a part of the
    vessel the geometry pass sees there."""
    pytest.importorskip("mitsuba")
    from seahaze.render.denoise import feature_buffers
    from seahaze.render.passes import render_geometry

    # Large enough for the near vessels to have inner pixels.
    text = SCENE.replace("resolution: [64, 36]", "resolution: [256, 144]")
    first, geometry = _loaded(text, "fleet")
    alone = feature_buffers(first, seed=1, spp=1).albedo
    instance = render_geometry(first).instance
    other, _ = _loaded(text.replace("class: tug", "class: fishing_boat"), "other")
    mine = other.vessel_materials[0].paint
    assert mine is first.vessel_materials[0].paint  # shared
    theirs = feature_buffers(other, seed=1, spp=1).albedo
    again = feature_buffers(first, seed=1, spp=1).albedo
    np.testing.assert_array_equal(again, alone)
    # Pixels whose 3 × 3 neighbourhood is one vessel: its paint, whatever the sample position.
    inner = np.ones_like(instance, bool)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            inner &= np.roll(instance, (dy, dx), axis=(0, 1)) == instance
    inner &= instance >= 0
    inner[[0, -1], :] = inner[:, [0, -1]] = False
    assert inner.sum() >= 10
    for y, x in zip(*np.nonzero(inner), strict=True):
        paints = np.array([part.rgb for part in geometry.vessels[instance[y, x]].parts])
        assert np.min(np.abs(paints - alone[y, x]).max(axis=1)) < 1e-6
    assert not np.array_equal(theirs[inner], alone[inner])  # the other fleet is painted apart
