"""The MSVD paper's detector-based visibility metric.

Stage 1 (:func:`calibrate`): a detector's mAP50 on every hazy level of a dataset gives the
visibility → mAP50 calibration table. Stage 2 (:func:`new_visibility`): the mAP50 of the same
detector on restored (dehazed) images maps back to a visibility by piecewise-linear
interpolation (paper, Eq. 5), whose navigation regulation class (paper, Table 1) follows.
mAP is computed by ``faster_coco_eval`` (:func:`coco_scores`). See docs/metric.md.
"""

from seahaze.metric.errors import MetricInputError
from seahaze.metric.evaluate import (
    CocoScores,
    LevelResult,
    build_coco,
    calibrate,
    coco_scores,
    evaluate_dataset,
    evaluate_level,
)
from seahaze.metric.reader import (
    Dataset,
    ImageTruth,
    YoloBox,
    load_dataset,
    load_level_truth,
    parse_level,
    read_yolo_file,
)
from seahaze.metric.table import (
    Bound,
    CalibrationPoint,
    CalibrationTable,
    NewVisibility,
    load_table,
    make_table,
    new_visibility,
    save_table,
)

__all__ = [
    "Bound",
    "CalibrationPoint",
    "CalibrationTable",
    "CocoScores",
    "Dataset",
    "ImageTruth",
    "LevelResult",
    "MetricInputError",
    "NewVisibility",
    "YoloBox",
    "build_coco",
    "calibrate",
    "coco_scores",
    "evaluate_dataset",
    "evaluate_level",
    "load_dataset",
    "load_level_truth",
    "load_table",
    "make_table",
    "new_visibility",
    "parse_level",
    "read_yolo_file",
    "save_table",
]
