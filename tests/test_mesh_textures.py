"""Textures that read a mesh's own values (src/seahaze/render/mesh_textures.py) against
Mitsuba's ``mesh_attribute`` texture, which asks the shape."""

from __future__ import annotations

import numpy as np
import pytest

pytestmark = pytest.mark.usefixtures("mitsuba_variant")


def _grid_mesh(values: np.ndarray):
    """A 2 × 2-quad mesh in the plane z = 0 over [0, 2]², with ``values`` per vertex as the
    Mitsuba attribute ``vertex_v``, in a scene; and its faces."""
    import mitsuba as mi

    xs, ys = np.meshgrid(np.arange(3.0), np.arange(3.0), indexing="xy")
    vertices = np.stack([xs.ravel(), ys.ravel(), np.zeros(9)], axis=1).astype(np.float32)
    faces = []
    for j in range(2):
        for i in range(2):
            a, b, c, d = 3 * j + i, 3 * j + i + 1, 3 * (j + 1) + i, 3 * (j + 1) + i + 1
            faces += [[a, b, d], [a, d, c]]
    faces = np.array(faces, np.uint32)
    mesh = mi.Mesh("m", vertex_count=9, face_count=len(faces), props=mi.Properties())
    mesh.add_attribute("vertex_v", 1, values.astype(np.float32))
    params = mi.traverse(mesh)
    params["vertex_positions"] = vertices.ravel()
    params["faces"] = faces.ravel()
    params.update()
    return mi.load_dict({"type": "scene", "m": mesh}), mesh, faces


def test_vertex_values_equal_mitsubas_interpolated_attribute() -> None:
    import drjit as dr
    import mitsuba as mi

    from seahaze.render.mesh_textures import vertex_textures

    rng = np.random.default_rng(4)
    values = rng.random(9).astype(np.float32)
    scene, mesh, faces = _grid_mesh(values)
    texture = vertex_textures(faces, {"v": values})["v"]
    xy = rng.random((500, 2)) * 1.98 + 0.01
    ray = mi.Ray3f(mi.Point3f(xy[:, 0], xy[:, 1], 1.0), mi.Vector3f(0.0, 0.0, -1.0))
    si = scene.ray_intersect(ray)
    assert bool(dr.all(si.is_valid()))
    ours = np.array(texture.eval_1(si))
    theirs = np.array(mesh.eval_attribute_1("vertex_v", si))
    np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-6)
    assert np.ptp(ours) > 0.3  # the points span the values, not one vertex's
    rgb = texture.eval(si)
    np.testing.assert_array_equal(np.array(rgb.y), ours)


def test_textures_read_zero_where_no_shape_is_attached() -> None:
    import drjit as dr
    import mitsuba as mi

    from seahaze.render.mesh_textures import face_paint, vertex_textures

    values = np.full(9, 0.7, np.float32)
    _, _, faces = _grid_mesh(values)
    bare = dr.zeros(mi.SurfaceInteraction3f, 4)
    texture = vertex_textures(faces, {"v": values})["v"]
    assert np.all(np.array(texture.eval_1(bare)) == 0.0)
    paint = face_paint()
    paint.set_faces(np.full((len(faces), 3), 0.4, np.float32), owner=1)
    assert np.all(np.array(paint.eval(bare).x) == 0.0)
