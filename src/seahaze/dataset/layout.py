"""Paths of the files of one dataset folder (docs/dataset-format.md)::

OUT/data.yaml  OUT/dataset.json
OUT/images/clean/<scene>.png       OUT/images/v0300/<scene>.png ...
OUT/labels/<level>/<scene>.txt     OUT/depth/<scene>.exr
OUT/exr/<level>/<scene>.exr        OUT/meta/<scene>.json
OUT/coco/<level>.json              OUT/README.md (the dataset card)
OUT/labels_visible/<level>/<scene>.txt  OUT/coco_visible/<level>.json  (labels.write_visible)
OUT/transmission/<level>/<scene>.exr  (hazy levels, with the EXRs: T, tau per channel, V_eff)
OUT/train.txt OUT/val.txt OUT/test.txt (Ultralytics lists of the clean images; not with
                                      --split none)
OUT/mot/<level>/<sequence>/gt/gt.txt  OUT/mot/<level>/<sequence>/seqinfo.ini  (sequences: a
OUT/mot/<level>/<sequence>/img1/000001.png ...  OUT/mot/<level>/seqmap.txt  MOTChallenge folder)
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..visibility import CLEAN_LEVEL

TRANSMISSION_CHANNELS = ("T.R", "T.G", "T.B", "tau.R", "tau.G", "tau.B", "V_eff")
"""Channels of a ``transmission/<level>/<scene>.exr`` (:mod:`seahaze.render.transmission`):
transmittance and optical depth per channel and the effective visibility (m)."""


@dataclass(frozen=True)
class Layout:
    """Paths of the files of one dataset folder."""

    root: Path

    def image(self, level: str, scene: str) -> Path:
        return self.root / "images" / level / f"{scene}.png"

    def label(self, level: str, scene: str) -> Path:
        return self.root / "labels" / level / f"{scene}.txt"

    def visible_label(self, level: str, scene: str) -> Path:
        """The YOLO labels of the vessels seen in one level's image (``labels.write_visible``,
        :mod:`seahaze.visible`)."""
        return self.visible_label_dir(level) / f"{scene}.txt"

    def visible_label_dir(self, level: str) -> Path:
        return self.root / "labels_visible" / level

    def exr(self, level: str, scene: str) -> Path:
        return self.root / "exr" / level / f"{scene}.exr"

    def transmission(self, level: str, scene: str) -> Path:
        """A hazy level's per-pixel transmittance, optical depth and effective visibility."""
        return self.root / "transmission" / level / f"{scene}.exr"

    def depth(self, scene: str) -> Path:
        return self.root / "depth" / f"{scene}.exr"

    def coco(self, level: str) -> Path:
        return self.root / "coco" / f"{level}.json"

    def coco_visible(self, level: str) -> Path:
        """The COCO ground truth of ``labels_visible/<level>`` (``labels.write_visible``)."""
        return self.root / "coco_visible" / f"{level}.json"

    def mot_gt(self, level: str, sequence: str) -> Path:
        """A sequence's MOTChallenge ground truth at one level (dataset/tracks.py)."""
        return self.mot_sequence(level, sequence) / "gt" / "gt.txt"

    def mot_sequence(self, level: str, sequence: str) -> Path:
        """A sequence's MOTChallenge folder at one level: ``seqinfo.ini``, ``img1/``, ``gt/``."""
        return self.root / "mot" / level / sequence

    def mot_seqinfo(self, level: str, sequence: str) -> Path:
        return self.mot_sequence(level, sequence) / "seqinfo.ini"

    def mot_frame(self, level: str, sequence: str, frame: int) -> Path:
        """Frame ``frame`` (1-based, as MOTChallenge counts) of a sequence in its ``img1/``
        folder: ``000001.png`` …, a link to the level's image (dataset/tracks.py)."""
        return self.mot_sequence(level, sequence) / "img1" / f"{frame:06d}.png"

    def mot_seqmap(self, level: str) -> Path:
        """The list of a level's sequences in TrackEval's seqmap format (``name``, then one
        sequence a line)."""
        return self.root / "mot" / level / "seqmap.txt"

    def meta(self, scene: str) -> Path:
        return self.root / "meta" / f"{scene}.json"

    @property
    def data_yaml(self) -> Path:
        return self.root / "data.yaml"

    @property
    def manifest(self) -> Path:
        return self.root / "dataset.json"

    @property
    def card(self) -> Path:
        return self.root / "README.md"

    def split_list(self, split: str) -> Path:
        """The Ultralytics list of the clean images of one split (``train.txt`` …)."""
        return self.root / f"{split}.txt"

    def scene_files(
        self, scene: str, hazy_levels: list[str], exr: bool, visible: bool = False
    ) -> list[Path]:
        """Every file one scene writes: meta, depth, and per level (clean first) its image,
        label, (with ``exr``) linear EXR and, for a hazy level, its transmission EXR, and (with
        ``visible``, ``labels.write_visible``) its
        visible-object label. Without ``visible`` the list is that of a dataset made before the
        option existed, so such a dataset's recorded digests still match."""
        files = [self.meta(scene), self.depth(scene)]
        for level in [CLEAN_LEVEL, *hazy_levels]:
            files += [self.image(level, scene), self.label(level, scene)]
            if exr:
                files.append(self.exr(level, scene))
                if level != CLEAN_LEVEL:
                    files.append(self.transmission(level, scene))
            if visible:
                files.append(self.visible_label(level, scene))
        return files
