"""The ``hf`` layout: the dataset as the Hugging Face ``datasets`` library loads it, one row per
(scene, hazy level), in Parquet shards with typed features, and a dataset card whose YAML
front-matter names a configuration per level (and ``all``, the default) with its splits::

    VIEW/README.md                                    # the card: front-matter + description
    VIEW/data/<level>/<split>-00000-of-00001.parquet  # the rows of one level and split

``datasets.load_dataset("VIEW")`` gives every level, ``load_dataset("VIEW", "v1000")`` one;
``streaming=True`` reads the shards as they are. Each row holds the hazy image, the clean image
and the depth map (each as the bytes of its file: the dataset's own PNGs, the depth as a
float32 TIFF in metres), the level's visibility, σ and regulation class, the scene's split and
its labelled vessels with class, box, distance and, at that level, contrast and whether the
vessel can be seen (:mod:`seahaze.export.hf_rows`, docs/dataset-format.md#the-hf-layout).

Why Parquet rather than ``imagefolder`` with a metadata file, measured in docs/benchmarks.md
("Which format for the Hugging Face export?"): an imagefolder of linked images is cheaper to
write, keep and load the first time, but the shards are a few self-contained files that load
again from the cache at once, keep loading after the folder is moved (an imagefolder's cache
holds absolute paths), carry their features typed, load with datasets 2.19 and upload to the
Hub as they are. The price is disk space: the clean image and the depth are in every level's
rows (the other layouts link the dataset's files instead).

A dataset without a split (``--split none``) is exported as one ``train`` split: ``all``, the
name the other layouts give it, means every split to ``datasets`` and cannot name one.
"""

from __future__ import annotations

from functools import partial

from ..dataset.splits import ALL_SCENES
from ..fileio import check_exr, check_png
from ..visibility import CLEAN_LEVEL
from .hf_card import NO_LICENSE, card_text
from .hf_rows import DepthTiffs, SceneRecord, read_scene, write_shard
from .plan import ExportPlan
from .source import ExportError, SourceDataset

HF_INSTALL = "pip install 'seahaze[hf]'"
"""The extra that brings pyarrow (and ``datasets``, to load the export)."""

MAX_SHARD_BYTES = 500 << 20
"""Largest Parquet shard, estimated from its files' sizes (the size ``datasets`` pushes)."""


def hub_split(split: str) -> str:
    """The ``datasets`` split name of a dataset split (``all`` → ``train``, see above)."""
    return "train" if split == ALL_SCENES else split


def require_pyarrow() -> None:
    """Raise :class:`ExportError` naming the extra when pyarrow, which writes Parquet, is
    missing (checked before the plan, which reads every scene's files, and before writing)."""
    try:
        import pyarrow.parquet  # noqa: F401
    except ImportError:
        raise ExportError(
            f"--layout hf writes Parquet with pyarrow, which is not installed; {HF_INSTALL} "
            "(pyarrow and Hugging Face datasets)"
        ) from None


def plan_hf(source: SourceDataset, license_id: str = NO_LICENSE) -> ExportPlan:
    """The ``hf`` layout: Parquet shards per level and split, and the card (its front-matter's
    ``license`` is ``license_id``). Making the plan needs no pyarrow; its builders do
    (:func:`require_pyarrow`).

    Every file a row reads is checked here, before anything is written: each scene's meta
    (its vessels' boxes against the label files), its depth EXR and its images (complete, the
    size of the camera). Raises :class:`ExportError` (one line naming the file) otherwise.
    """
    levels = [level.name for level in source.levels]
    records = {
        scene: read_scene(
            source.layout,
            scene,
            hub_split(split),
            levels,
            source.classes,
            source.manifest["scenes"][scene],
        )
        for scene, split in source.scenes.items()
    }
    for scene, record in records.items():
        _check_files(source, scene, record)
    plan = ExportPlan(kind="Parquet")
    depth = DepthTiffs()
    shards: dict[str, dict[str, int]] = {}
    for split in source.splits:
        scenes = source.scenes_of(split)
        if not scenes:
            continue
        groups = _shard_groups(source, scenes)
        name = hub_split(split)
        # Every level of a group of scenes in a row: the group's depth maps are encoded once.
        for index, group in enumerate(groups):
            for level in source.levels:
                target = f"data/{level.name}/{name}-{index:05d}-of-{len(groups):05d}.parquet"
                rows = [records[scene] for scene in group]
                plan.built[target] = partial(
                    write_shard, rows=rows, level=level, source=source, depth=depth
                )
                shards.setdefault(level.name, {})
                shards[level.name][name] = shards[level.name].get(name, 0) + len(group)
        plan.pairs += len(scenes) * len(source.levels)
    plan.texts["README.md"] = card_text(source, shards, license_id)
    return plan


def _check_files(source: SourceDataset, scene: str, record: SceneRecord) -> None:
    """The images and the depth of ``scene`` are complete files of its camera's size."""
    layout = source.layout
    images = [layout.image(level, scene) for level in source.level_names(with_clean=True)]
    checks = [(path, check_png(path, record.size)) for path in images]
    depth = layout.depth(scene)
    checks.append((depth, check_exr(depth, record.size, {"Z"}) if depth.is_file() else "missing"))
    for path, problem in checks:
        if problem is not None:
            raise ExportError(
                f"{path}: {problem} (the camera is {record.size[0]}x{record.size[1]}); the "
                "dataset is damaged: rerun the 'seahaze render' command that made it"
            )


def _shard_groups(source: SourceDataset, scenes: list[str]) -> list[list[str]]:
    """``scenes`` in order, cut into groups whose rows fit :data:`MAX_SHARD_BYTES` at every
    level (estimated from the sizes of the files a row holds; the depth TIFF is about the size
    of its EXR), so that the shards of all levels hold the same scenes."""
    layout = source.layout
    groups: list[list[str]] = [[]]
    total = 0
    for scene in scenes:
        common = layout.image(CLEAN_LEVEL, scene).stat().st_size
        common += layout.depth(scene).stat().st_size
        hazy = max(layout.image(level, scene).stat().st_size for level in source.level_names())
        size = common + hazy + 4096  # the labels and the row's other fields
        if groups[-1] and total + size > MAX_SHARD_BYTES:
            groups.append([])
            total = 0
        groups[-1].append(scene)
        total += size
    return groups
