"""User meshes: formats, axes, scale, draft rule, materials and error messages."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh
from trimesh.visual.material import PBRMaterial, SimpleMaterial

from seahaze.vessels import Material, SubmergedMeshError, load_user_mesh
from seahaze.vessels.user_mesh import DEFAULT_DRAFT_FRACTION, axes_rotation

ASSET = Path(__file__).resolve().parents[1] / "assets" / "test" / "box_boat.obj"
BOAT_LENGTH, BOAT_BEAM, BOAT_HEIGHT = 10.0, 3.0, 2.7

# Vessel frame (x fwd, y port, z up) → file frame with +y up and -z forward (Blender's OBJ /
# glTF default): file = (-y_v, z_v, -x_v).
VESSEL_TO_FILE = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, 0.0, 0.0]])


def box_boat_parts() -> dict[str, trimesh.Trimesh]:
    """A 10 m box boat in the vessel frame: hull with a pointed bow at +x, cabin aft."""
    hull = trimesh.convex.convex_hull(
        np.array(
            [(x, y, z) for x in (-5.0, 3.0) for y in (-1.5, 1.5) for z in (-0.5, 1.0)]
            + [(5.0, 0.0, 1.0), (5.0, 0.0, 0.2)]
        )
    )
    cabin = trimesh.creation.box(bounds=[[-3.0, -1.0, 1.0], [0.0, 1.0, 2.2]])
    return {"hull": hull, "cabin": cabin}


def to_file_frame(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    moved = mesh.copy()
    moved.vertices = np.asarray(mesh.vertices) @ VESSEL_TO_FILE.T
    return moved


def write_box_boat(path: Path, *, coloured: bool = True) -> Path:
    """Write the box boat in the +y-up / -z-forward file frame (any trimesh format)."""
    colours = {"hull": (200, 30, 30), "cabin": (230, 230, 230)}
    meshes = {}
    for name, mesh in box_boat_parts().items():
        mesh = to_file_frame(mesh)
        if coloured and path.suffix == ".glb":
            mesh.visual = trimesh.visual.TextureVisuals(
                material=PBRMaterial(
                    name=f"{name}_paint", baseColorFactor=[*colours[name], 255], roughnessFactor=0.3
                )
            )
        elif coloured and path.suffix == ".obj":
            mesh.visual = trimesh.visual.TextureVisuals(
                material=SimpleMaterial(name=f"{name}_paint", diffuse=[*colours[name], 255])
            )
        elif coloured and path.suffix == ".ply":
            mesh.visual = trimesh.visual.ColorVisuals(
                mesh, face_colors=np.tile([*colours[name], 255], (len(mesh.faces), 1))
            )
        meshes[name] = mesh
    if path.suffix in (".ply", ".stl"):
        trimesh.util.concatenate(list(meshes.values())).export(path)
    elif path.suffix == ".obj":
        text, files = trimesh.exchange.obj.export_obj(
            trimesh.Scene(meshes), return_texture=True, mtl_name=path.with_suffix(".mtl").name
        )
        path.write_text(text)
        for name, data in files.items():
            (path.parent / name).write_bytes(data)
    else:
        trimesh.Scene(meshes).export(path)
    return path


@pytest.mark.parametrize("suffix", [".obj", ".stl", ".ply", ".glb"])
def test_round_trip_puts_the_boat_in_the_vessel_frame(tmp_path: Path, suffix: str) -> None:
    path = write_box_boat(tmp_path / f"boat{suffix}")
    model = load_user_mesh(path, "fishing_boat", 25.0, up_axis="+y", forward_axis="-z")
    scale = 25.0 / BOAT_LENGTH
    height = BOAT_HEIGHT * scale
    draft = DEFAULT_DRAFT_FRACTION * height
    half_beam = 0.5 * BOAT_BEAM * scale
    np.testing.assert_allclose(
        model.bounds(), [[-12.5, -half_beam, -draft], [12.5, half_beam, height - draft]], atol=1e-4
    )
    assert model.kind == "fishing_boat"
    assert model.length_m == 25.0
    assert model.beam_m == pytest.approx(BOAT_BEAM * scale)
    assert model.draft_m == pytest.approx(draft)
    assert model.air_draft_m == pytest.approx(height - draft)
    vertices = np.vstack([p.mesh.vertices for p in model.parts])
    # Bow (the pointed end) at +x: only the stem line reaches x > 0.45 L, on the centreline.
    bow = vertices[vertices[:, 0] > 0.45 * 25.0]
    assert len(bow) and np.abs(bow[:, 1]).max() < 1e-6
    # Cabin (highest points) aft of midships, as built.
    top = vertices[vertices[:, 2] > height - draft - 1e-6]
    assert top[:, 0].max() <= 1e-6


def test_materials_of_the_file_become_parts(tmp_path: Path) -> None:
    for suffix in (".glb", ".obj", ".ply"):
        model = load_user_mesh(
            write_box_boat(tmp_path / f"boat{suffix}"), "tug", 20.0, up_axis="+y", forward_axis="-z"
        )
        assert len(model.parts) == 2, suffix
        rgbs = sorted(p.material.rgb for p in model.parts)
        red, white = rgbs[0], rgbs[1]
        # sRGB (200, 30, 30) → linear ≈ (0.58, 0.013, 0.013); white (230) → ≈ 0.79.
        assert red[0] == pytest.approx(0.578, abs=0.01) and red[1] < 0.02, suffix
        assert white == pytest.approx((0.791,) * 3, abs=0.01), suffix
    glb = load_user_mesh(tmp_path / "boat.glb", "tug", 20.0, up_axis="+y", forward_axis="-z")
    assert {p.material.roughness for p in glb.parts} == {0.3}


def test_override_material_and_explicit_draft(tmp_path: Path) -> None:
    paint = Material("grey", (0.2, 0.2, 0.2), 0.4)
    model = load_user_mesh(
        write_box_boat(tmp_path / "boat.glb"), "tug", 30.0, "+y", "-z", material=paint, draft_m=1.5
    )
    assert [p.name for p in model.parts] == ["hull"]
    assert model.parts[0].material == paint
    assert model.bounds()[0, 2] == pytest.approx(-1.5)
    assert model.draft_m == 1.5


def test_a_draft_that_sinks_the_whole_mesh_is_refused(tmp_path: Path) -> None:
    boat = write_box_boat(tmp_path / "boat.stl")
    height = BOAT_HEIGHT * 20.0 / BOAT_LENGTH  # the box boat scaled to 20 m: 5.4 m high
    with pytest.raises(SubmergedMeshError, match=r"allowed: 0 <= draft_m < 5\.4") as info:
        load_user_mesh(boat, "tug", 20.0, "+y", "-z", draft_m=height + 0.05)
    assert info.value.height_m == pytest.approx(height)
    almost = load_user_mesh(boat, "tug", 20.0, "+y", "-z", draft_m=height - 0.1)
    assert almost.air_draft_m == pytest.approx(0.1)


def test_uncoloured_stl_gets_a_default_paint(tmp_path: Path) -> None:
    model = load_user_mesh(
        write_box_boat(tmp_path / "boat.stl", coloured=False), "tug", 20.0, "+y", "-z"
    )
    assert len(model.parts) == 1
    assert model.parts[0].material.rgb[0] == pytest.approx(model.parts[0].material.rgb[2])


def test_axes_rotation_is_a_proper_rotation() -> None:
    for up in ("+x", "-x", "+y", "-y", "+z", "-z"):
        for fwd in ("+x", "-x", "+y", "-y", "+z", "-z"):
            if up[1] == fwd[1]:
                continue
            rot = axes_rotation(up, fwd)
            np.testing.assert_allclose(rot @ rot.T, np.eye(3), atol=1e-12)
            assert np.linalg.det(rot) == pytest.approx(1.0)
    np.testing.assert_allclose(axes_rotation("+y", "-z") @ VESSEL_TO_FILE, np.eye(3), atol=1e-12)


def test_committed_test_asset_loads_as_documented() -> None:
    # assets/test/box_boat.obj(+.mtl) is write_box_boat() output, documented in assets/README.
    model = load_user_mesh(ASSET, "fishing_boat", 12.0, up_axis="+y", forward_axis="-z")
    (x0, _, _), (x1, _, _) = model.bounds()
    assert x1 - x0 == pytest.approx(12.0)
    assert len(model.parts) == 2
    assert ASSET.stat().st_size < 50_000


def test_errors_are_clear(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError, match="not found"):
        load_user_mesh(tmp_path / "missing.obj", "tug", 20.0)
    unsupported = tmp_path / "boat.fbx"
    unsupported.write_bytes(b"not a mesh")
    with pytest.raises(ValueError, match=r"unsupported mesh format '\.fbx'.*\.obj"):
        load_user_mesh(unsupported, "tug", 20.0)
    empty = tmp_path / "empty.obj"
    empty.write_text("# no geometry\n")
    with pytest.raises(ValueError, match="no triangles"):
        load_user_mesh(empty, "tug", 20.0)
    boat = write_box_boat(tmp_path / "boat.stl")
    with pytest.raises(ValueError, match="perpendicular"):
        load_user_mesh(boat, "tug", 20.0, up_axis="+y", forward_axis="-y")
    with pytest.raises(ValueError, match="one of"):
        load_user_mesh(boat, "tug", 20.0, up_axis="up")
    with pytest.raises(ValueError, match="allowed kinds"):
        load_user_mesh(boat, "hovercraft", 20.0)
    with pytest.raises(ValueError, match="scale_m"):
        load_user_mesh(boat, "tug", 0.0)
