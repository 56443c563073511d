"""Planning a batch: scene templates → scenes with their own seeds and varied parameters.

Every scene file (a *template*) gives one scene, or with ``count`` (``seahaze render --scenes
N``) N scenes named ``<template>_00000`` …, scene ``i`` drawing its camera heading, sun, sea
state and vessel layout from the template's ``variation:`` ranges with a seed derived from
(master seed, template name, ``i``) (:func:`seahaze.seeds.scene_seed`). With ``split``
fractions every scene also gets its train/val/test split from (master seed, scene name) alone
(:func:`seahaze.dataset.splits.assign_splits`), so the scenes of a grown batch keep theirs (a
batch of a few scenes excepted, where an empty train or val takes the nearest scene).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

from ..dataset.splits import SplitAssignment, SplitFractions, assign_splits
from ..seeds import scene_seed, variation_rng
from ..spec import TWILIGHT_SUN_DEG, SceneSpec, VariationSpec
from .errors import DatasetError

VARIED: dict[str, tuple[str, str]] = {
    "camera_heading_deg": ("camera", "heading_deg"),
    "sun_elevation_deg": ("sun", "elevation_deg"),
    "sun_azimuth_deg": ("sun", "azimuth_deg"),
    "wind_speed": ("sea", "wind_speed"),
    "sea_direction_deg": ("sea", "direction_deg"),
    "camera_height_m": ("camera", "height_m"),
    "camera_pitch_deg": ("camera", "pitch_deg"),
    "camera_fov_deg": ("camera", "fov_deg"),
    "camera_roll_deg": ("camera", "roll_deg"),
}
"""Each ``variation`` range and the spec field it sets; the order fixes each one's stream."""


def _draw_twilight_sun(data: dict, variation: VariationSpec, seed: int) -> None:
    """A twilight scene's sun: drawn uniformly from ``twilight_sun_elevation_deg``, or from
    all of civil twilight where ``sky_models`` drew the twilight (its daylight sun, drawn or
    the template's, is no twilight sun); its own stream, after the sky model's."""
    if data["sky"].get("model") != "twilight":
        return
    bounds = variation.twilight_sun_elevation_deg
    if bounds is None and variation.sky_models is None:
        return  # a twilight template keeps its own sun
    low, high = bounds if bounds is not None else TWILIGHT_SUN_DEG
    value = round(float(variation_rng(seed, len(VARIED) + 2).uniform(low, high)), 3)
    data["sun"]["elevation_deg"] = min(max(value, low), high)


@dataclass(frozen=True)
class SceneJob:
    """One scene of a batch: its name, its fully resolved spec and where it came from."""

    name: str
    spec: SceneSpec
    template: str
    index: int | None = None
    split: str | None = None
    """``train``, ``val`` or ``test``; None in a dataset made without ``--split``."""
    sequence: str | None = None
    """Name of the sequence this job is a frame of (None: a still scene)."""
    frame: int | None = None
    """Frame of ``spec.sequence`` this job renders (0-based; None: a still scene)."""

    def images(self) -> int:
        """Images this scene writes: clean plus one per level."""
        return 1 + len(self.spec.haze.levels)

    def entry(self, status: str) -> dict[str, Any]:
        """This scene's record in ``dataset.json`` (``split`` only when the batch has one, so a
        dataset made without ``--split`` keeps the manifest it always had; a frame's also names
        its sequence)."""
        entry: dict[str, Any] = {
            "status": status,
            "seed": self.spec.render.seed,
            "template": self.template,
            "index": self.index,
        }
        if self.split is not None:
            entry["split"] = self.split
        if self.frame is not None:
            entry |= {"sequence": self.sequence, "frame": self.frame}
        return entry | {"config": self.spec.model_dump(mode="json", by_alias=True)}


def frame_name(sequence: str, frame: int, frames: int) -> str:
    """File name stem of ``frame`` of a sequence of ``frames``: ``<sequence>_f0007`` (4 digits
    or more, so names sort in frame order)."""
    width = max(4, len(str(frames - 1)))
    return f"{sequence}_f{frame:0{width}d}"


def expand_frames(jobs: Sequence[SceneJob]) -> list[SceneJob]:
    """Each job of a sequence scene replaced by one job per frame (a frame is the unit of
    work, resumed like a still scene); still scenes as they are."""
    out: list[SceneJob] = []
    for job in jobs:
        sequence = job.spec.sequence
        if sequence is None:
            out.append(job)
            continue
        out += [
            SceneJob(
                frame_name(job.name, i, sequence.frames),
                job.spec,
                job.template,
                job.index,
                split=job.split,  # a sequence's frames share its split: splits stay disjoint
                sequence=job.name,
                frame=i,
            )
            for i in range(sequence.frames)
        ]
    return out


@dataclass(frozen=True)
class BatchPlan:
    """Every scene of a batch in its canonical order, plus what the manifest's config records."""

    jobs: tuple[SceneJob, ...]
    levels: tuple[float, ...]
    threshold: str
    count: int | None = None
    master_seeds: dict[str, int] = field(default_factory=dict)
    assignment: SplitAssignment | None = None
    """Every scene's split and the fractions asked for; None for a batch without a split."""

    @property
    def split(self) -> SplitFractions | None:
        """The share of scenes each split got (None without a split): the splits with a share
        above 0 are the ones that get a list file and a ``data.yaml`` entry. The fractions
        asked for are ``assignment.fractions``; ``config`` records those."""
        return None if self.assignment is None else self.assignment.shares()

    def config(self) -> dict[str, Any]:
        """The manifest's ``config``: dataset-wide settings, for ``--scenes`` the batch, and for
        a split the fractions asked for (absent without: the config of older folders is
        unchanged)."""
        first = self.jobs[0].spec
        batch = (
            None
            if self.count is None
            else {"scenes_per_template": self.count, "master_seeds": dict(self.master_seeds)}
        )
        config: dict[str, Any] = {
            "threshold": self.threshold,
            "mode": first.render.mode,
            "spp": first.render.spp,
            "resolution": list(first.camera.resolution),
            "batch": batch,
        }
        if self.assignment is not None:
            config["split"] = self.assignment.fractions.as_dict()
        return config


def vary_scene(spec: SceneSpec, seed: int) -> SceneSpec:
    """The scene of a batch with seed ``seed``: ``spec`` with its ``variation`` ranges sampled.

    Every varied quantity has its own random stream, so adding a range to a template does not
    change the values drawn for the others. Values are rounded to 1e-3 (they stay inside their
    ranges, whose ends the schema holds to at most three decimals' worth of meaning).
    """
    variation = spec.variation
    data = spec.model_dump(mode="json", by_alias=True)
    data["render"]["seed"] = seed
    for k, key in enumerate(VARIED):
        bounds = getattr(variation, key)
        if bounds is None:
            continue
        low, high = bounds
        value = min(max(round(float(variation_rng(seed, k).uniform(low, high)), 3), low), high)
        section, name = VARIED[key]
        data[section][name] = value
        if key == "wind_speed":
            data["sea"]["beaufort"] = None  # a Beaufort force would override the drawn wind
    if variation.sky_models is not None:
        # One of the listed models, each entry equally likely; its own stream.
        draw = variation_rng(seed, len(VARIED) + 1).integers(len(variation.sky_models))
        data["sky"]["model"] = variation.sky_models[int(draw)]
    _draw_twilight_sun(data, variation, seed)
    if data["sky"].get("model", "clear") != "broken":
        data["sky"].pop("clouds", None)  # a clear or overcast sky has no cloud layer
    elif variation.cloud_oktas is not None:
        # Whole oktas, each equally likely; the stream after every VARIED range's.
        low, high = variation.cloud_oktas
        oktas = int(variation_rng(seed, len(VARIED)).integers(low, high + 1))
        data["sky"]["clouds"] = {**(data["sky"].get("clouds") or {}), "oktas": oktas}
    if variation.resample_clouds and data["sky"].get("clouds") is not None:
        data["sky"]["clouds"]["seed"] = None  # derived from render.seed (render.sky)
    if variation.resample_sea:
        data["sea"]["seed"] = None  # derived from the scene's render.seed (seahaze.world)
    if variation.resample_layout and data["vessels"].get("sample") is not None:
        data["vessels"]["sample"]["seed"] = None
    return SceneSpec.model_validate(data)


def plan_scenes(
    templates: Sequence[tuple[SceneSpec, str]],
    count: int | None = None,
    master_seed: int | None = None,
    split: SplitFractions | None = None,
) -> BatchPlan:
    """The scenes of a batch, in canonical order: templates in the given order, then index.

    ``count`` None: one scene per template, as written. ``count`` N: N scenes per template named
    ``<template>_<i>`` (5 digits or more), each with :func:`seahaze.seeds.scene_seed` of the
    master seed (``master_seed``, else the template's ``render.seed``) and :func:`vary_scene`
    applied. With ``split``, each scene's split comes from its master seed (the batch's, else
    its own ``render.seed``) and its name, as :func:`~seahaze.dataset.splits.assign_splits`
    gives it (a sequence's frames all take the sequence's). Raises :class:`DatasetError` for
    scenes that cannot share one dataset.
    """
    if not templates:
        raise DatasetError("no scene to render")
    if count is not None and count < 1:
        raise DatasetError(f"the number of scenes must be >= 1, got {count}")
    first, first_name = templates[0]
    for spec, name in templates[1:]:
        if (
            list(spec.haze.levels) != list(first.haze.levels)
            or spec.haze.threshold != first.haze.threshold
        ):
            raise DatasetError(
                f"scene '{name}' has other haze levels or threshold than '{first_name}'; "
                "pass --vis to use the same levels"
            )
    jobs: list[SceneJob] = []
    masters: list[int] = []  # each job's master seed, which (with its name) fixes its split
    seeds: dict[str, int] = {}
    if count is None:
        for spec, name in templates:
            jobs.append(SceneJob(name, spec, name, None))
            masters.append(spec.render.seed)
    else:
        width = max(5, len(str(count - 1)))
        for spec, name in templates:
            master = spec.render.seed if master_seed is None else master_seed
            seeds[name] = master
            for i in range(count):
                seed = scene_seed(master, name, i)
                jobs.append(SceneJob(f"{name}_{i:0{width}d}", vary_scene(spec, seed), name, i))
                masters.append(master)
    assignment = None
    if split is not None:
        # Before the frames are expanded: a sequence is one scene of the split.
        assignment = assign_splits(split, [(j.name, m) for j, m in zip(jobs, masters, strict=True)])
        jobs = [replace(job, split=assignment.splits[job.name]) for job in jobs]
    jobs = expand_frames(jobs)
    counts = Counter(job.name for job in jobs)
    duplicates = sorted(name for name, n in counts.items() if n > 1)
    if duplicates:
        raise DatasetError(
            f"two scenes share the name(s) {duplicates[:5]}; set 'name:' in the YAML"
        )
    return BatchPlan(
        tuple(jobs), tuple(first.haze.levels), str(first.haze.threshold), count, seeds, assignment
    )
