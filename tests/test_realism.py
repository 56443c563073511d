"""The realism benchmark's arithmetic (seahaze.metric.realism) and its detector's box mapping
(seahaze.metric.centernet); the detector itself runs when it is installed (make realism-deps)."""

from __future__ import annotations

import numpy as np
import pytest

from seahaze.metric import centernet, realism
from seahaze.metric.centernet import Detection
from seahaze.metric.realism import Vessel


def boat(x0, y0, x1, y1, score, label="boat"):
    return Detection(x0, y0, x1, y1, score, label)


def test_iou_of_two_boxes_by_hand():
    a = Vessel("i", "tug", 0, 0, 10, 10)
    # Half of a overlaps b: intersection 50, union 100 + 100 - 50.
    assert realism.iou(a, boat(5, 0, 15, 10, 1.0)) == pytest.approx(1 / 3)
    assert realism.iou(a, boat(0, 0, 10, 10, 1.0)) == pytest.approx(1.0)
    assert realism.iou(a, boat(10, 0, 20, 10, 1.0)) == 0.0  # touching edges


@pytest.mark.parametrize(
    ("height", "band"),
    [(0.0, "< 8 px"), (7.99, "< 8 px"), (8.0, "8–16 px"), (31.9, "16–32 px"), (32.0, "≥ 32 px")],
)
def test_height_bands_hold_their_lower_bound(height, band):
    assert realism.height_band(height) == band


def test_negative_height_has_no_band():
    with pytest.raises(ValueError, match="height"):
        realism.height_band(-1.0)


def two_images():
    """Two tugs (one found, one missed) and a ferry found, with a false positive."""
    vessels = [
        Vessel("a", "tug", 100, 100, 140, 120),
        Vessel("a", "passenger_ferry", 300, 100, 400, 130),
        Vessel("b", "tug", 10, 10, 16, 14),
    ]
    detections = {
        "a": [
            boat(101, 100, 141, 121, 0.90),  # the first tug
            boat(300, 101, 400, 131, 0.92),  # the ferry
            boat(500, 300, 540, 330, 0.95),  # open sea
        ],
        "b": [],
    }
    return vessels, detections


def test_group_recall_and_ap50_against_the_101_point_rule():
    vessels, detections = two_images()
    tugs = realism.score_group(vessels, detections, lambda v: v.cls == "tug")
    assert tugs.vessels == 2
    assert tugs.recall == pytest.approx(0.5)
    # By score: the open-sea box (false), the ferry's (a crowd region for the tugs: ignored),
    # the tug's (true): precision 1/2 at recall 1/2. COCO's interpolated precision is 1/2 at
    # the 51 recall points 0, 0.01 … 0.50 and 0 beyond: AP = 51 · 0.5 / 101.
    assert tugs.ap50 == pytest.approx(51 * 0.5 / 101)


def test_a_group_counts_other_vessels_found_as_neither_hit_nor_miss():
    vessels, detections = two_images()
    # Were the ferry's box a false positive, the tug's would come third: precision 1/3.
    everything = realism.score_group(vessels, detections, lambda v: True)
    assert everything.vessels == 3
    assert everything.recall == pytest.approx(2 / 3)
    # By score: false (0/1), ferry (1/2), tug (2/3): interpolated 2/3 up to recall 2/3.
    assert everything.ap50 == pytest.approx(67 * (2 / 3) / 101)


def test_an_empty_group_has_no_score_and_no_detection_scores_zero():
    vessels, detections = two_images()
    assert realism.score_group(vessels, detections, lambda v: v.cls == "buoy").ap50 is None
    empty = realism.score_group(vessels, {"a": [], "b": []}, lambda v: True)
    assert (empty.recall, empty.ap50) == (0.0, 0.0)


def test_detections_of_other_classes_neither_find_nor_spoil():
    vessels = [Vessel("a", "container_ship", 0, 100, 200, 130)]
    train = boat(0, 100, 200, 130, 0.8, label="train")
    assert realism.score_group(vessels, {"a": [train]}, lambda v: True).recall == 0.0


def test_confusion_names_the_class_that_took_the_vessel():
    vessels = [
        Vessel("a", "container_ship", 0, 100, 200, 130),
        Vessel("a", "container_ship", 300, 100, 500, 130),
        Vessel("a", "tug", 600, 100, 640, 120),
    ]
    detections = {
        "a": [
            boat(0, 100, 200, 130, 0.3),
            boat(0, 100, 200, 131, 0.6, label="train"),  # outscores the boat box: confused
            boat(300, 100, 500, 130, 0.5),
            boat(300, 100, 500, 130, 0.4, label="airplane"),  # below the boat box: not
            boat(0, 0, 10, 10, 0.9, label="bird"),  # covers nothing
        ]
    }
    taken = realism.confusion(vessels, detections)
    assert taken["container_ship"] == {"train": 1}
    assert sum(taken["tug"].values()) == 0


def test_model_rows_map_back_to_the_image_pixels():
    # The image is stretched to 512×512: x scales by 640/512, y by 360/512.
    d = centernet.to_image([256.0, 128.0, 384.0, 256.0, 0.7, 8.0], 640, 360)
    assert (d.x0, d.y0, d.x1, d.y1) == pytest.approx((320.0, 90.0, 480.0, 180.0))
    assert (d.score, d.label) == (pytest.approx(0.7), "boat")
    outside = centernet.to_image([-20.0, 500.0, 600.0, 530.0, 0.1, 6.0], 640, 360)
    assert (outside.x0, outside.y1, outside.x1) == (0.0, 360.0, 640.0)
    assert outside.label == "train"


def test_model_input_is_the_stretched_image():
    image = np.zeros((90, 160, 3), np.uint8)
    image[:, 80:] = 255  # right half white
    square = centernet.model_input(image)
    assert square.shape == (512, 512, 3)
    assert square[:, :250].max() == 0 and square[:, 262:].min() == 255
    with pytest.raises(ValueError, match="uint8"):
        centernet.model_input(image.astype(np.float32))


def test_coco_names_are_the_80_detection_classes():
    assert len(centernet.COCO_NAMES) == 80 == len(set(centernet.COCO_NAMES))
    assert centernet.COCO_NAMES.index("boat") == 8 and centernet.COCO_NAMES[-1] == "toothbrush"


def test_a_missing_detector_says_how_to_install_it(tmp_path):
    with pytest.raises(centernet.DetectorUnavailableError, match="make realism-deps"):
        centernet.detect([np.zeros((9, 16, 3), np.uint8)], project=tmp_path)


INSTALLED = not centernet.missing_parts(centernet.default_project())


@pytest.mark.skipif(not INSTALLED, reason="detector not installed (make realism-deps)")
def test_the_detector_boxes_painted_shapes_where_they_are():
    """Run the real model on a synthetic picture (a dark hull with a white house, on a sea
    under a sky) and on its mirror image. Whatever COCO class it calls them, some of its ten
    best boxes must cover each painted rectangle (IoU ≥ 0.7) in both: a wrong mapping back
    from the stretched 512×512 input (x by the height, a missed scale, no mirror) would not."""
    image = np.empty((360, 640, 3), np.uint8)
    image[:180] = (170, 200, 225)  # sky
    image[180:] = (50, 75, 95)  # sea
    shapes = {"hull": (120, 160, 420, 195), "house": (330, 130, 400, 160)}
    image[160:195, 120:420] = (60, 40, 35)
    image[130:160, 330:400] = (235, 235, 230)
    found = centernet.detect([image, image[:, ::-1].copy()])
    for mirrored, detections in zip((False, True), found, strict=True):
        best = sorted(detections, key=lambda d: -d.score)[:10]
        assert all(0.0 <= d.x0 <= d.x1 <= 640.0 and 0.0 <= d.y0 <= d.y1 <= 360.0 for d in best)
        for x0, y0, x1, y1 in shapes.values():
            if mirrored:
                x0, x1 = 640 - x1, 640 - x0
            painted = Vessel("i", "tug", x0, y0, x1, y1)
            assert max(realism.iou(painted, d) for d in best) >= 0.7


@pytest.mark.skipif(not INSTALLED, reason="detector not installed (make realism-deps)")
def test_a_detector_past_its_time_says_so():
    with pytest.raises(centernet.DetectorUnavailableError, match="ran past"):
        centernet.detect([np.zeros((9, 16, 3), np.uint8)], timeout_s=0.01)
