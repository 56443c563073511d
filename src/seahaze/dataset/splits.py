"""Scene-disjoint train/val/test splits that stay put when a batch grows.

Every scene goes to exactly one split, so no scene's images (clean or any level) are in two
splits. The split of a scene is decided by that scene alone: a SHA-256 of (master seed, scene
name) read as a number u in [0, 1), compared with the cumulative fractions (``u < train`` →
train, ``u < train + val`` → val, else test). Nothing is shuffled, so adding scenes to a batch
(``--scenes 100`` → ``--scenes 200``) or another scene file never moves a scene that was
already there. See docs/dataset-format.md#splits.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass
from typing import Any

SPLIT_NAMES: tuple[str, ...] = ("train", "val", "test")
"""The splits, in the order of ``--split TRAIN,VAL,TEST``."""

ALL_SCENES = "all"
"""The one split of a dataset made without ``--split``: every scene (exports name it so)."""

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

    def split_of(self, master_seed: int, scene: str) -> str:
        """The split of ``scene`` of a batch with master seed ``master_seed``."""
        u = scene_unit(master_seed, scene)
        edge = 0.0
        for name, fraction in self.as_dict().items():
            edge += fraction
            if fraction > 0 and u < edge:
                return name
        # u is below 1 and the fractions sum to 1 within rounding: the last non-empty split.
        return next(n for n, f in reversed(self.as_dict().items()) if f > 0)


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
