"""Annotations: occlusion-aware boxes, frame edges, visibility thresholds, COCO export."""

from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import box_vessel, load_flat_scene, small_spec
from seahaze.labels import boxes_from_instances
from seahaze.metric.dataset import load_dataset
from seahaze.metric.evaluate import evaluate_level
from seahaze.render import passes

pytestmark = pytest.mark.usefixtures("mitsuba_variant")


def _box_corners(center, size):
    return np.array(
        [
            [
                center[0] + sx * size[0] / 2,
                center[1] + sy * size[1] / 2,
                center[2] + sz * size[2] / 2,
            ]
            for sx in (-1, 1)
            for sy in (-1, 1)
            for sz in (-1, 1)
        ]
    )


def _rays_hitting_box(camera, center, size) -> int:
    """Number of pixel-centre rays that intersect an axis-aligned box (ray–slab test)."""
    d = camera.pixel_center_directions().reshape(-1, 3)
    lo = np.asarray(center) - np.asarray(size) / 2 - camera.origin
    hi = np.asarray(center) + np.asarray(size) / 2 - camera.origin
    with np.errstate(divide="ignore", invalid="ignore"):
        t0, t1 = lo / d, hi / d
    near = np.nanmax(np.minimum(t0, t1), axis=1)
    far = np.nanmin(np.maximum(t0, t1), axis=1)
    return int(np.count_nonzero((near <= far) & (far > 0)))


def _projected_box(camera, center, size):
    u, v, _ = camera.project(_box_corners(center, size))
    return np.clip([u.min(), v.min(), u.max(), v.max()], 0, [camera.width, camera.height] * 2)


def test_occluded_vessel_gets_the_box_of_its_visible_part():
    # A near box hides the left half of a far box; the far box keeps only its right part.
    spec = small_spec(camera={"resolution": [160, 90], "pitch_deg": -1.0})
    near_c, near_s = (300.0, 10.0, 8.0), (20.0, 20.0, 16.0)
    far_c, far_s = (900.0, 0.0, 8.0), (30.0, 60.0, 16.0)  # lower than the near box: no top shows
    loaded, camera = load_flat_scene(
        spec, vessels=[box_vessel(0, near_c, near_s), box_vessel(1, far_c, far_s)]
    )
    geo = passes.render_geometry(loaded)
    near, far = boxes_from_instances(geo.instance, [0, 0], geo.footprint_px)
    full_far = _projected_box(camera, far_c, far_s)
    near_box = _projected_box(camera, near_c, near_s)
    assert np.all(np.abs(np.array([near.x0, near.y0, near.x1, near.y1]) - near_box) <= 1.0)
    # The visible part of the far vessel starts where the near one ends (bearing left = image left).
    assert far.x0 == pytest.approx(near_box[2], abs=1.0)
    assert far.x1 == pytest.approx(full_far[2], abs=1.0)
    assert 0.2 < far.visible_fraction < 0.8 and near.visible_fraction == 1.0
    # Its unoccluded footprint: pixel-centre rays that meet the box, by an independent slab test.
    assert abs(int(geo.footprint_px[1]) - _rays_hitting_box(camera, far_c, far_s)) <= 1


def test_mostly_hidden_vessel_is_dropped_below_the_visible_fraction():
    spec = small_spec(camera={"resolution": [160, 90], "pitch_deg": -1.0})
    vessels = [
        box_vessel(0, (300.0, 0.0, 8.0), (20.0, 40.0, 16.0)),
        box_vessel(1, (900.0, 2.0, 8.0), (20.0, 60.0, 16.0)),
    ]
    loaded, _ = load_flat_scene(spec, vessels=vessels)
    geo = passes.render_geometry(loaded)
    kept = boxes_from_instances(geo.instance, [0, 0], geo.footprint_px, min_visible_fraction=0.5)
    assert [b.vessel for b in kept] == [0]


def test_vessel_at_the_frame_edge_is_clipped_to_the_frame():
    spec = small_spec(camera={"resolution": [160, 90], "pitch_deg": -1.0, "fov_deg": 40.0})
    center, size = (
        (400.0, 150.0, 10.0),
        (20.0, 80.0, 20.0),
    )  # straddles the left edge (bearing ~20.6°)
    loaded, camera = load_flat_scene(spec, vessels=[box_vessel(0, center, size)])
    geo = passes.render_geometry(loaded)
    (box,) = boxes_from_instances(geo.instance, [0], geo.footprint_px)
    assert box.x0 == 0.0
    expected = _projected_box(camera, center, size)
    assert box.x1 == pytest.approx(expected[2], abs=1.0)
    assert 0.0 <= box.x0 < box.x1 <= camera.width and 0 <= box.y0 < box.y1 <= camera.height


def test_small_boxes_are_dropped():
    instance = np.full((10, 10), -1)
    instance[2, 2] = 0
    instance[4:8, 4:8] = 1
    assert [b.vessel for b in boxes_from_instances(instance, [0, 0], min_box_px=2)] == [1]


def test_coco_export_scores_a_perfect_prediction_as_ap50_one(dataset, tmp_path):
    coco = json.loads((dataset / "coco" / "v0300.json").read_text())
    assert coco["images"][0]["file_name"] == "images/v0300/default.png"
    assert len(coco["annotations"]) >= 1
    pred = tmp_path / "pred" / "v0300"
    pred.mkdir(parents=True)
    lines = (dataset / "labels" / "v0300" / "default.txt").read_text().splitlines()
    (pred / "default.txt").write_text("".join(f"{line} 1.0\n" for line in lines))
    result = evaluate_level(load_dataset(dataset), "v0300", tmp_path / "pred")
    assert result.scores.map50 == pytest.approx(1.0)


def test_meta_reports_contrast_falling_with_visibility(dataset):
    meta = json.loads((dataset / "meta" / "default.json").read_text())
    for vessel in meta["vessels"]:
        levels = vessel["levels"]
        assert levels["v0300"]["beyond_visibility"] == (vessel["distance_m"] > 300)
        # Koschmieder: |C| = t |J - A| / A shrinks as the haze thickens.
        contrasts = [levels[k]["apparent_contrast"] for k in ("v4000", "v0300")]
        if None not in contrasts:
            assert abs(contrasts[0]) > abs(contrasts[1])
