"""Track labels of a dataset's sequences: MOTChallenge folders per level, video fields in COCO.

A sequence's frames are scenes of the dataset named ``<sequence>_f0000`` …, each listed in
``dataset.json`` with its ``sequence`` and ``frame``; every frame's ``meta/<frame>.json`` holds
each vessel's ``track_id`` (the same in every frame), box and per-level apparent contrast. From
them, when every scene of the batch is done, each level ``mot/<level>/`` is a MOTChallenge
benchmark folder that TrackEval and py-motmetrics read as it is (docs/dataset-format.md):

- ``mot/<level>/<sequence>/gt/gt.txt``: one line per labelled vessel and frame,
  ``frame,id,bb_left,bb_top,bb_width,bb_height,consider,class,visibility`` in MOTChallenge's
  convention (frame and pixel coordinates 1-based; ``class`` the YOLO class id + 1;
  ``visibility`` the vessel's unoccluded share, 0–1). ``consider`` is 1 where the vessel's
  apparent contrast at that level reaches the threshold contrast (0.02 Koschmieder, 0.05 MOR:
  an observer could see it), else 0, so the levels' files differ only there;
- ``mot/<level>/<sequence>/seqinfo.ini``: ``name``, ``imDir`` (``img1``), ``frameRate``,
  ``seqLength``, ``imWidth``, ``imHeight``, ``imExt`` (``.png``), in MOT17's order;
- ``mot/<level>/<sequence>/img1/000001.png`` …: frame ``k`` (1-based) of the level, a relative
  symbolic link to ``images/<level>/<sequence>_f<k-1>.png``. Links, not copies: no pixel is
  stored twice, a link follows its frame when the frame is rendered again (a hard link would
  keep the old file), and relative links stay valid when the dataset folder is moved or
  copied whole. Where the file system has no symbolic links the frame is hard-linked, else
  copied (rewritten at the end of every batch, so it cannot go stale);
- ``mot/<level>/seqmap.txt``: the level's sequences in TrackEval's seqmap format;
- in ``coco/<level>.json``: ``videos`` (id, name, fps, frames), each frame's ``video_id`` and
  ``frame_id`` (0-based) and each annotation's ``track_id`` (and ``instance_id``, its name in
  the COCO-video format of mmtracking).
"""

from __future__ import annotations

import json
import os
import re
import shutil
from collections import defaultdict
from pathlib import Path
from typing import Any

from .. import fileio
from ..visibility import CLEAN_LEVEL, Threshold
from .layout import Layout

THRESHOLD_CONTRAST = {Threshold.KOSCHMIEDER.value: 0.02, Threshold.MOR.value: 0.05}
"""The contrast threshold of each visibility definition (docs/physics.md)."""


def _manifest(root: Path) -> dict[str, Any]:
    return json.loads((root / "dataset.json").read_text(encoding="utf-8"))


def sequences(manifest: dict[str, Any]) -> dict[str, list[tuple[int, str, dict[str, Any]]]]:
    """Sequence name → its ``(frame, scene name, config)`` in frame order."""
    out: dict[str, list[tuple[int, str, dict[str, Any]]]] = defaultdict(list)
    for name, entry in (manifest.get("scenes") or {}).items():
        if isinstance(entry, dict) and entry.get("sequence") is not None:
            out[str(entry["sequence"])].append((int(entry["frame"]), name, entry["config"]))
    return {seq: sorted(frames) for seq, frames in sorted(out.items())}


def mot_lines(metas: list[dict[str, Any]], level: str, threshold: str) -> list[str]:
    """The ``gt.txt`` lines of one sequence at ``level`` from its frames' meta, in frame order."""
    contrast_min = THRESHOLD_CONTRAST[threshold]
    lines = []
    for meta in metas:
        frame = int(meta["sequence"]["frame"]) + 1
        for vessel in sorted(meta["vessels"], key=lambda v: v["track_id"]):
            box = vessel["box_px"]
            if box is None:
                continue
            x0, y0, x1, y1 = box
            contrast = vessel["levels"][level]["apparent_contrast"]
            consider = int(
                level == CLEAN_LEVEL or (contrast is not None and abs(contrast) >= contrast_min)
            )
            lines.append(
                f"{frame},{vessel['track_id']},{x0 + 1:.2f},{y0 + 1:.2f},{x1 - x0:.2f},"
                f"{y1 - y0:.2f},{consider},{vessel['class_id'] + 1},"
                f"{vessel['visible_fraction']:.4f}"
            )
    return lines


IMAGE_DIR = "img1"
"""The frames' folder of a MOTChallenge sequence (``imDir`` of ``seqinfo.ini``)."""

_FRAME_FILE = re.compile(r"^\d{6}\.png$")


def _seqinfo(name: str, config: dict[str, Any], frames: int) -> str:
    width, height = config["camera"]["resolution"]
    fps = config["sequence"]["fps"]
    return (
        f"[Sequence]\nname={name}\nimDir={IMAGE_DIR}\nframeRate={fps:g}\nseqLength={frames}\n"
        f"imWidth={width}\nimHeight={height}\nimExt=.png\n"
    )


def place_frame(source: Path, target: Path) -> str:
    """Put ``source`` (a level's frame) at ``target`` (in ``img1/``): a relative symbolic link,
    else a hard link, else a copy; returns which (``symlink``, ``hard``, ``copy``). A link that
    already points at ``source`` is left as it is."""
    relative = os.path.relpath(source, target.parent)
    if target.is_symlink() and os.readlink(target) == relative:
        return "symlink"
    target.parent.mkdir(parents=True, exist_ok=True)
    if target.is_symlink() or target.exists():
        target.unlink()
    try:
        os.symlink(relative, target)
        return "symlink"
    except OSError:
        pass  # a file system without symbolic links (some network and Windows shares)
    try:
        os.link(source, target)
        return "hard"
    except OSError:
        shutil.copyfile(source, target)
        return "copy"


def _place_frames(layout: Layout, level: str, seq: str, names: list[str]) -> list[Path]:
    """Each frame of ``seq`` at ``level`` in its ``img1/``; frame files of a longer past
    sequence removed (only ``NNNNNN.png``: nothing else there is seahaze's)."""
    placed = []
    for k, name in enumerate(names, start=1):
        target = layout.mot_frame(level, seq, k)
        place_frame(layout.image(level, name), target)
        placed.append(target)
    folder = layout.mot_sequence(level, seq) / IMAGE_DIR
    keep = {path.name for path in placed}
    for entry in sorted(folder.iterdir()):
        if _FRAME_FILE.match(entry.name) and entry.name not in keep and not entry.is_dir():
            entry.unlink()
    return placed


def write_tracks(root: Path) -> list[Path]:
    """Write every sequence's MOTChallenge folder (``seqinfo.ini``, ``img1/``, ``gt/gt.txt``)
    and each level's ``seqmap.txt``; the paths written (the frames' links included)."""
    layout = Layout(root)
    manifest = _manifest(root)
    levels = [CLEAN_LEVEL, *(entry["name"] for entry in manifest["levels"])]
    threshold = manifest["config"]["threshold"]
    written = []
    seqs = sequences(manifest)
    for seq, frames in seqs.items():
        metas = [json.loads(layout.meta(name).read_text(encoding="utf-8")) for _, name, _ in frames]
        for level in levels:
            lines = mot_lines(metas, level, threshold)
            gt, info = layout.mot_gt(level, seq), layout.mot_seqinfo(level, seq)
            fileio.write_text(gt, "".join(line + "\n" for line in lines))
            fileio.write_text(info, _seqinfo(seq, frames[0][2], len(frames)))
            written += [gt, info, *_place_frames(layout, level, seq, [n for _, n, _ in frames])]
    if seqs:
        for level in levels:
            seqmap = layout.mot_seqmap(level)
            fileio.write_text(seqmap, "name\n" + "".join(f"{seq}\n" for seq in seqs))
            written.append(seqmap)
    return written


def add_video_fields(truth: dict[str, Any], root: Path) -> None:
    """Add ``videos``, ``video_id``/``frame_id`` and ``track_id`` to a level's COCO ``truth``
    (from :func:`seahaze.metric.evaluate.build_coco`, whose annotations follow each label
    file's lines, that is the boxed vessels in index order). A dataset without sequences is
    left as it is."""
    manifest = _manifest(root)
    seqs = sequences(manifest)
    if not seqs:
        return
    layout = Layout(root)
    frame_of: dict[str, tuple[int, int]] = {}
    videos = []
    for video_id, (seq, frames) in enumerate(seqs.items(), start=1):
        fps = frames[0][2]["sequence"]["fps"]
        videos.append({"id": video_id, "name": seq, "fps": fps, "frames": len(frames)})
        frame_of.update({name: (video_id, frame) for frame, name, _ in frames})
    tracks: dict[int, list[int]] = {}
    for image in truth["images"]:
        stem = Path(image["file_name"]).stem
        if stem not in frame_of:
            continue
        image["video_id"], image["frame_id"] = frame_of[stem]
        meta = json.loads(layout.meta(stem).read_text(encoding="utf-8"))
        boxed = sorted(
            (v for v in meta["vessels"] if v["box_px"] is not None), key=lambda v: v["index"]
        )
        tracks[image["id"]] = [v["track_id"] for v in boxed]
    seen: dict[int, int] = defaultdict(int)
    for annotation in truth["annotations"]:
        ids = tracks.get(annotation["image_id"])
        if ids is None:
            continue
        k = seen[annotation["image_id"]]
        seen[annotation["image_id"]] += 1
        annotation["track_id"] = annotation["instance_id"] = ids[k]
    truth["videos"] = videos
