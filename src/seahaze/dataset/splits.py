"""Scene-disjoint train/val/test splits that stay put when a batch grows.

Every scene goes to exactly one split, so no scene's images (clean or any level) are in two
splits. The split of a scene is decided by that scene alone: a SHA-256 of (master seed, scene
name) read as a number u in [0, 1), compared with the cumulative fractions (``u < train`` →
train, ``u < train + val`` → val, else test). Nothing is shuffled, so adding scenes to a batch
(``--scenes 100`` → ``--scenes 200``) or another scene file never moves a scene that was
already there. See docs/dataset-format.md#splits.

One exception, for batches too small for the hash alone (:func:`assign_splits`): ``train`` is
never empty, and with two or more scenes neither is ``val`` (when its fraction is above 0); the
scene whose hash lies nearest to an empty one moves into it, and ``seahaze render`` says so. A
batch of one scene cannot have a scene-disjoint ``val``: its scene is ``train`` and
``data.yaml``'s ``val`` is ``train.txt`` too.

``seahaze render`` uses :data:`DEFAULT_SPLIT` in a new folder without ``--split``; a folder
that holds a dataset keeps the split its ``dataset.json`` records (none, for a folder made
before the default or with ``--split none``) unless ``--split`` is given
(:func:`resolve_split`), so resuming never meets a changed configuration.
"""

from __future__ import annotations

import hashlib
import math
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

SPLIT_NAMES: tuple[str, ...] = ("train", "val", "test")
"""The splits, in the order of ``--split TRAIN,VAL,TEST``."""

ALL_SCENES = "all"
"""The one split of a dataset made without ``--split``: every scene (exports name it so)."""

DEFAULT_SPLIT = "0.8,0.1,0.1"
"""The split of ``seahaze render`` in a new folder without ``--split`` (train, val, test)."""
DEFAULT_SPLIT_SOURCE = "the default"
"""How :func:`resolve_split` names a split nobody asked for (neither ``--split`` nor a
folder's record)."""

NO_SPLIT = "none"
"""``--split none``: no split; ``train`` and ``val`` of ``data.yaml`` are every clean image."""

_SUM_TOLERANCE = 1e-6


class SplitError(ValueError):
    """A split specification that cannot be used; the message says what is allowed."""


@dataclass(frozen=True)
class SplitFractions:
    """The share of scenes in each split; each in [0, 1], together 1, ``train`` > 0."""

    train: float
    val: float
    test: float

    def __post_init__(self) -> None:
        values = self.as_dict()
        bad = [f"{k}={v!r}" for k, v in values.items() if not (math.isfinite(v) and 0 <= v <= 1)]
        if bad:
            raise SplitError(f"each fraction must be a number in [0, 1], got {', '.join(bad)}")
        if abs(sum(values.values()) - 1.0) > _SUM_TOLERANCE:
            raise SplitError(
                f"the fractions must sum to 1, got {self.train:g}+{self.val:g}+{self.test:g}"
                f" = {sum(values.values()):g}"
            )
        if self.train <= 0:
            raise SplitError("the train fraction must be > 0")

    @classmethod
    def parse(cls, text: str) -> SplitFractions:
        """``TRAIN,VAL,TEST`` fractions (``0.8,0.1,0.1``); raises :class:`SplitError`."""
        parts = [p.strip() for p in text.split(",")]
        if len(parts) != len(SPLIT_NAMES):
            raise SplitError(
                f"expected {len(SPLIT_NAMES)} comma-separated fractions train,val,test that "
                f"sum to 1, e.g. 0.8,0.1,0.1; got {len(parts)} value(s)"
            )
        try:
            values = [float(p) for p in parts]
        except ValueError:
            raise SplitError(
                "the fractions train,val,test must be numbers, e.g. 0.8,0.1,0.1"
            ) from None
        return cls(*values)

    @classmethod
    def from_config(cls, config: dict[str, float]) -> SplitFractions:
        """The fractions recorded in ``dataset.json`` (``config.split``)."""
        return cls(*(float(config[name]) for name in SPLIT_NAMES))

    def as_dict(self) -> dict[str, float]:
        """``{"train": …, "val": …, "test": …}``, as ``dataset.json`` records it."""
        return {"train": self.train, "val": self.val, "test": self.test}

    def text(self) -> str:
        """``0.8,0.1,0.1``: the fractions as ``--split`` takes them."""
        return ",".join(f"{value:g}" for value in self.as_dict().values())

    def edges(self, split: str) -> tuple[float, float]:
        """The interval ``[low, high)`` of scene units that fall into ``split``."""
        low = 0.0
        for name, fraction in self.as_dict().items():
            if name == split:
                return low, low + fraction
            low += fraction
        raise KeyError(split)

    def split_of(self, master_seed: int, scene: str) -> str:
        """The split of ``scene`` of a batch with master seed ``master_seed`` by its hash alone
        (:func:`assign_splits` may move a scene of a very small batch)."""
        return self.split_of_unit(scene_unit(master_seed, scene))

    def split_of_unit(self, u: float) -> str:
        """The split of a scene whose :func:`scene_unit` is ``u``."""
        edge = 0.0
        for name, fraction in self.as_dict().items():
            edge += fraction
            if fraction > 0 and u < edge:
                return name
        # u is below 1 and the fractions sum to 1 within rounding: the last non-empty split.
        return next(n for n, f in reversed(self.as_dict().items()) if f > 0)


@dataclass(frozen=True)
class SplitAssignment:
    """The split of every scene of a batch (a sequence counts as one scene: its frames share
    its split), and what :func:`assign_splits` had to change for a very small batch."""

    fractions: SplitFractions
    """The fractions asked for (``--split`` or the default), as ``dataset.json`` records them."""
    splits: dict[str, str]
    """Scene (or sequence) name → ``train``, ``val`` or ``test``, in plan order."""
    moved: tuple[tuple[str, str, str], ...] = ()
    """``(scene, from, to)`` for each scene moved out of its hash's split."""

    def counts(self) -> dict[str, int]:
        """Scenes per split, every split named."""
        counts = Counter(self.splits.values())
        return {name: counts[name] for name in SPLIT_NAMES}

    def shares(self) -> SplitFractions:
        """Each split's share of the scenes it got: a split with none has share 0, so it gets
        no list file and no ``data.yaml`` entry (an empty ``val.txt`` would stop Ultralytics)."""
        total = len(self.splits)
        counts = self.counts()
        return SplitFractions(*(counts[name] / total for name in SPLIT_NAMES))

    def empty(self) -> list[str]:
        """The splits asked for (fraction above 0) that got no scene."""
        counts = self.counts()
        return [n for n, f in self.fractions.as_dict().items() if f > 0 and counts[n] == 0]

    def describe(self) -> str:
        """One line: the scenes per split and the rule that put them there."""
        counts = self.counts()
        shown = ", ".join(f"{name} {counts[name]}" for name in SPLIT_NAMES)
        return f"{self.fractions.text()} by scene hash: {shown} scene(s), no scene in two splits"

    def warning(self) -> str | None:
        """One line for a batch too small for its split (None: the hash alone gave every split
        asked for at least one scene)."""
        empty = self.empty()
        if not (self.moved or empty):
            return None
        if len(self.splits) == 1:
            (scene,) = self.splits
            return (
                f"1 scene ({scene}) is too few for a scene-disjoint split: it goes to train, and "
                "data.yaml's val is train.txt too (train = val); render 2 or more scenes for a "
                "separate val"
            )
        what = [
            f"moved {scene} from {a} to {b} so that {b} is not empty" for scene, a, b in self.moved
        ]
        if empty:
            files = ", ".join(f"{name}.txt" for name in empty)
            what.append(f"{' and '.join(empty)} got no scene (no {files})")
        counts = self.counts()
        shown = ", ".join(f"{name} {counts[name]}" for name in SPLIT_NAMES)
        return (
            f"{len(self.splits)} scenes are too few for the split {self.fractions.text()} by "
            f"scene hash alone: {'; '.join(what)}; using {shown}, no scene in two splits"
        )


def assign_splits(fractions: SplitFractions, scenes: Sequence[tuple[str, int]]) -> SplitAssignment:
    """The split of each ``(scene name, master seed)``: :meth:`SplitFractions.split_of`, except
    that ``train`` is never empty and, with two or more scenes, ``val`` neither (where its
    fraction is above 0).

    An empty one of those takes one scene from the split with the most scenes (``train``
    first on a tie) that can spare one without emptying train or val: the scene whose unit
    lies nearest to the empty split's interval (then the first name), so the move is the
    smallest the rule allows and needs no other input. Only batches of a few scenes are
    touched (a val share of 0.1 leaves ``val`` empty by chance in 0.9**n of batches of n
    scenes: 35 % at 10, 0.5 % at 50).
    """
    units = {name: scene_unit(seed, name) for name, seed in scenes}
    splits = {name: fractions.split_of_unit(u) for name, u in units.items()}
    needed = ["train"] + (["val"] if len(splits) >= 2 and fractions.val > 0 else [])
    moved: list[tuple[str, str, str]] = []
    for target in needed:
        counts = Counter(splits.values())
        if counts[target] == 0:
            # A donor keeps a scene of its own if it is one of the splits that must have one;
            # some split always can spare one (n >= 1 for train, n >= 2 for val).
            spare = [
                s for s in SPLIT_NAMES if s != target and counts[s] > (1 if s in needed else 0)
            ]
            donor = max(spare, key=lambda s: counts[s])  # the first of the largest
            low, high = fractions.edges(target)
            scene = min(
                (name for name, split in splits.items() if split == donor),
                key=lambda name: (max(low - units[name], units[name] - high, 0.0), name),
            )
            splits[scene] = target
            moved.append((scene, donor, target))
    return SplitAssignment(fractions, splits, tuple(moved))


def resolve_split(
    flag: str | None, folder_manifest: dict[str, Any] | None
) -> tuple[SplitFractions | None, str]:
    """The split ``seahaze render`` uses, and where it comes from (for its message).

    ``--split`` decides when given (``none``: no split). Without it, a folder that holds a
    dataset (``folder_manifest``: its ``dataset.json``) keeps the split that records — none for
    a folder made before the default or with ``--split none`` — so resuming an existing folder
    never turns into a configuration change; a new folder gets :data:`DEFAULT_SPLIT`. Raises
    :class:`SplitError` for a flag that is not ``none`` or three fractions.
    """
    if flag is not None:
        if flag.strip().lower() == NO_SPLIT:
            return None, "--split none"
        return SplitFractions.parse(flag), "--split"
    if folder_manifest is not None:
        config = folder_manifest.get("config")
        recorded = config.get("split") if isinstance(config, dict) else None
        if not recorded:
            return None, "kept from the folder's dataset.json, made without a split"
        try:
            return SplitFractions.from_config(recorded), "kept from the folder's dataset.json"
        except (SplitError, KeyError, TypeError, ValueError):
            pass  # a damaged record: the default, and the config check names the difference
    return SplitFractions.parse(DEFAULT_SPLIT), DEFAULT_SPLIT_SOURCE


def scene_unit(master_seed: int, scene: str) -> float:
    """A number in [0, 1) fixed by (master seed, scene name): the first 8 bytes of a SHA-256.

    A hash rather than a random stream: it needs no other scene, so a scene's split never
    depends on which or how many scenes the batch holds.
    """
    digest = hashlib.sha256(f"seahaze-split\0{master_seed}\0{scene}".encode()).digest()
    return int.from_bytes(digest[:8], "big") / 2.0**64


def scene_splits(data: dict[str, Any]) -> dict[str, str]:
    """Scene → split of a manifest; every scene is in ``all`` when it has no split."""
    return {
        name: entry.get("split") or ALL_SCENES for name, entry in (data.get("scenes") or {}).items()
    }


def split_order(data: dict[str, Any]) -> list[str]:
    """The splits a manifest uses, in ``train, val, test`` order (``all`` without a split)."""
    if not (data.get("config") or {}).get("split"):
        return [ALL_SCENES]
    return list(SPLIT_NAMES)
