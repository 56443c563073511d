"""The folder layouts ``seahaze export`` writes, as plans: which dataset file goes where, and
which small text files (pair lists, dataset YAMLs) are written beside them.

* ``paired`` — per split ``hazy/<scene>_<level>.png`` ↔ ``GT/<scene>.png``: the GT name is
  the hazy name without its last ``_<level>``; ``pairs.csv`` gives visibility and σ.
* ``same-name`` — per split ``hazy/<scene>_<level>.png`` ↔ ``GT/<scene>_<level>.png`` (the
  clean image linked once per level): loaders that read ``GT/<name>`` beside ``hazy/<name>``,
  such as DehazeFormer's ``PairLoader`` (``<split>`` is its ``sub_dir``).
* ``reside`` — per split ``hazy/<id>_<level>.png`` ↔ ``clear/<id>.png``, the RESIDE ITS/OTS
  naming that FFA-Net's loader and its many descendants read (the clean image's name is the
  hazy name up to the first ``_``); ``<id>`` is the scene name with ``_`` replaced by ``-``.
* ``yolo`` — one Ultralytics dataset per level: ``<level>/images/<split>/<scene>.png``,
  ``<level>/labels/<split>/<scene>.txt`` and ``<level>/data.yaml`` with the standard keys
  ``train``/``val``/``test`` and no ``path`` (Ultralytics then resolves against the YAML's own
  folder), so it works from any folder, in any YOLO tool, and after the view is moved.
* ``yolo-hazy`` — one Ultralytics dataset for training a detector on haze: the clean image
  and every exported level of each scene pooled in its scene's split,
  ``images/<split>/<scene>_<level>.png`` with ``labels/<split>/<scene>_<level>.txt`` (the
  visible-object labels of that level where the dataset has them, ``labels.write_visible``,
  else the level's labels), and one ``data.yaml`` (scene-disjoint: every image of a scene is
  in one split).
"""

from __future__ import annotations

import csv
import io
from collections.abc import Callable

import yaml

from ..visibility import CLEAN_LEVEL
from .hf import plan_hf, require_pyarrow
from .plan import ExportPlan
from .source import ExportError, SourceDataset

PAIRS_CSV = "pairs.csv"
PAIR_COLUMNS = ("hazy", "gt", "scene", "level", "visibility_m", "sigma_per_m", "split")
"""Columns of ``<split>/pairs.csv``: paths relative to the split folder, then the labels."""


def plan_paired(source: SourceDataset) -> ExportPlan:
    """The ``paired`` layout: ``hazy/<scene>_<level>.png`` ↔ ``GT/<scene>.png``."""
    return _plan_pairs(source, "GT", lambda scene, _level: f"{scene}.png", lambda s: s)


def plan_same_name(source: SourceDataset) -> ExportPlan:
    """The ``same-name`` layout: ``hazy/<scene>_<level>.png`` ↔ ``GT/<scene>_<level>.png``."""
    return _plan_pairs(source, "GT", lambda scene, level: f"{scene}_{level}.png", lambda s: s)


def plan_reside(source: SourceDataset) -> ExportPlan:
    """The ``reside`` layout: ``hazy/<id>_<level>.png`` ↔ ``clear/<id>.png``."""
    ids = reside_ids(list(source.scenes))
    return _plan_pairs(source, "clear", lambda scene, _level: f"{ids[scene]}.png", ids.get)


def reside_ids(scenes: list[str]) -> dict[str, str]:
    """Scene → RESIDE id: the name with ``_`` replaced by ``-`` (RESIDE loaders take the clean
    image's name from the hazy name up to its first ``_``). Raises :class:`ExportError` when two
    scenes get one id."""
    ids: dict[str, str] = {}
    seen: dict[str, str] = {}
    for scene in scenes:
        ident = scene.replace("_", "-")
        if ident in seen:
            raise ExportError(
                f"scenes {seen[ident]!r} and {scene!r} both become RESIDE id {ident!r}; "
                "use --layout paired"
            )
        ids[scene] = seen[ident] = ident
    return ids


def plan_yolo(source: SourceDataset) -> ExportPlan:
    """The ``yolo`` layout: a standard Ultralytics dataset per level (clean included)."""
    plan = ExportPlan()
    layout = source.layout
    for level in source.level_names(with_clean=True):
        for split in source.splits:
            for scene in source.scenes_of(split):
                plan.placed[f"{level}/images/{split}/{scene}.png"] = layout.image(level, scene)
                plan.placed[f"{level}/labels/{split}/{scene}.txt"] = layout.label(level, scene)
        plan.texts[f"{level}/data.yaml"] = _view_yaml(source, level)
    return plan


def plan_yolo_hazy(source: SourceDataset) -> ExportPlan:
    """The ``yolo-hazy`` layout: the clean image and the levels of each scene pooled in one
    Ultralytics dataset, each image with its own level's labels (see the module docstring)."""
    plan = ExportPlan()
    layout = source.layout
    levels = source.level_names(with_clean=True)
    scenes = [scene for split in source.splits for scene in source.scenes_of(split)]
    visible = all(layout.visible_label(lv, sc).is_file() for lv in levels for sc in scenes)
    label = layout.visible_label if visible else layout.label
    for split in source.splits:
        for scene in source.scenes_of(split):
            for level in levels:
                name = f"{scene}_{level}"
                plan.placed[f"images/{split}/{name}.png"] = layout.image(level, scene)
                plan.placed[f"labels/{split}/{name}.txt"] = label(level, scene)
    which = "labels_visible/ (the vessels seen at each level)" if visible else "labels/"
    plan.texts["data.yaml"] = _view_yaml(source, f"clean and {', '.join(levels[1:])}; {which}")
    return plan


def _view_yaml(source: SourceDataset, level: str) -> str:
    present = [split for split in source.splits if source.scenes_of(split)]
    keys = {"train": present[0], "val": present[0]} if present == ["all"] else {}
    data: dict[str, object] = {
        **{key: f"images/{split}" for key, split in keys.items()},
        **{split: f"images/{split}" for split in present if split != "all"},
        "names": dict(enumerate(source.classes)),
    }
    return (
        f"# seahaze export of {source.root} at level {level}: an Ultralytics dataset with no\n"
        "# 'path', so Ultralytics resolves the folders against this file's own folder\n"
        + yaml.safe_dump(data, sort_keys=False)
    )


LAYOUTS: dict[str, Callable[..., ExportPlan]] = {
    "paired": plan_paired,
    "same-name": plan_same_name,
    "reside": plan_reside,
    "yolo": plan_yolo,
    "yolo-hazy": plan_yolo_hazy,
    "hf": plan_hf,
}
"""``--layout`` name → its planner (each takes the :class:`SourceDataset`; ``hf`` also its
card's ``license_id``)."""

REQUIREMENTS: dict[str, Callable[[], None]] = {"hf": require_pyarrow}
"""``--layout`` name → a check that what it writes with is installed (raises
:class:`ExportError` naming the extra), made once the dataset is known to be finished."""


def _plan_pairs(
    source: SourceDataset,
    gt_dir: str,
    gt_name: Callable[[str, str], str],
    hazy_stem: Callable[[str], str | None],
) -> ExportPlan:
    """Per split: ``hazy/<stem>_<level>.png`` and ``<gt_dir>/<gt_name>``, plus ``pairs.csv``."""
    plan = ExportPlan()
    layout = source.layout
    for split in source.splits:
        rows = []
        for scene in source.scenes_of(split):
            for level in source.levels:
                hazy = f"hazy/{hazy_stem(scene)}_{level.name}.png"
                gt = f"{gt_dir}/{gt_name(scene, level.name)}"
                plan.placed[f"{split}/{hazy}"] = layout.image(level.name, scene)
                plan.placed[f"{split}/{gt}"] = layout.image(CLEAN_LEVEL, scene)
                rows.append((hazy, gt, scene, level.name, level.visibility_m, level.sigma_per_m))
        if rows:
            plan.texts[f"{split}/{PAIRS_CSV}"] = _pairs_csv(rows, split)
            plan.pairs += len(rows)
    return plan


def _pairs_csv(rows: list[tuple[str, str, str, str, float, float]], split: str) -> str:
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(PAIR_COLUMNS)
    for hazy, gt, scene, level, vis, sigma in rows:
        writer.writerow([hazy, gt, scene, level, f"{vis:g}", repr(sigma), split])
    return out.getvalue()
