"""The dataset card: ``README.md`` of a finished dataset folder, written from its manifest.

It says what the set is, how it was made (seahaze version, an equivalent command, the config
hash), the levels with their extinction, the counts per split and class, the files, how to load
it (Ultralytics, COCO tools, the dehazing layouts of ``seahaze export``) and what to cite. The
text depends only on ``dataset.json`` and the label files, so the same dataset always gets the
same bytes (no date, no absolute path).
"""

from __future__ import annotations

import json
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..fileio import write_text
from ..visibility import CLEAN_LEVEL, CONTRAST_THRESHOLD, Threshold
from .layout import Layout
from .manifest import config_hash
from .splits import SPLIT_NAMES, scene_splits, split_order

CARD_MARKER = "<!-- seahaze dataset card: rewritten when the batch finishes; edit a copy -->"
"""First line of every card: a README.md without it is the user's and is never overwritten."""

MSVD_CITATION = """\
@unpublished{feng_msvd_visibility,
  title  = {Bridging the Gap Between Image Restoration and Navigational Safety in Hazy
            Conditions: A New Visibility Estimation Metric for Maritime Surveillance},
  author = {Feng, Wentao and Peng, Guobei and Mao, Wengang and Liu, Ryan Wen},
  note   = {Manuscript; introduces the MSVD dataset and the detector-based visibility metric}
}"""


@dataclass
class SplitCounts:
    """Scenes and labelled vessels per class of one split."""

    scenes: int = 0
    instances: Counter[int] = field(default_factory=Counter)


def count_labels(layout: Layout, data: dict[str, Any]) -> dict[str, SplitCounts]:
    """Scenes and vessels per class of every split, from ``labels/clean`` (the same boxes are
    written at every level)."""
    counts = {name: SplitCounts() for name in split_order(data)}
    for scene, split in scene_splits(data).items():
        entry = counts.setdefault(split, SplitCounts())
        entry.scenes += 1
        text = layout.label(CLEAN_LEVEL, scene).read_text(encoding="utf-8")
        entry.instances.update(int(line.split()[0]) for line in text.splitlines() if line.strip())
    return counts


def equivalent_command(data: dict[str, Any]) -> str:
    """A ``seahaze render`` command that makes this dataset from its scene files.

    Scene files are named ``<template>.yaml`` after their ``name:``; resolution, spp and mode
    are those of the first scene (every scene's full config is in ``dataset.json``).
    """
    config = data.get("config") or {}
    templates = list(dict.fromkeys(e["template"] for e in data["scenes"].values()))
    parts = ["seahaze render", *(f"{t}.yaml" for t in templates)]
    batch = config.get("batch")
    if batch:
        parts.append(f"--scenes {batch['scenes_per_template']}")
        seeds = set(batch["master_seeds"].values())
        if len(seeds) == 1:
            parts.append(f"--seed {seeds.pop()}")
    levels = ",".join(f"{level['visibility_m']:g}" for level in data["levels"])
    width, height = config.get("resolution", [0, 0])
    parts += [f"--vis {levels}", f"--res {width}x{height}", f"--spp {config.get('spp')}"]
    parts.append(f"--mode {config.get('mode')}")
    # Render switches a command line may have changed from the scene files' (first scene's).
    first = next(iter(data["scenes"].values()), {}).get("config") or {}
    render = first.get("render") or {}
    if render.get("dither", "on") == "off":
        parts.append("--dither off")
    if render.get("denoise", "off") == "on":
        parts.append("--denoise on")
    split = config.get("split")
    if split:
        parts.append("--split " + ",".join(f"{split[name]:g}" for name in SPLIT_NAMES))
    else:  # a new folder gets the default split: say that this one had none
        parts.append("--split none")
    return " ".join(parts)


def card_text(data: dict[str, Any], counts: dict[str, SplitCounts]) -> str:
    """The Markdown of the card for manifest ``data`` and its label ``counts``."""
    sections = [
        CARD_MARKER + "\n" + _summary(data, counts),
        *description_sections(data, counts)[1:],
        _files(data),
        _loading(data),
        citation_section(),
    ]
    return "\n".join(sections)


def description_sections(data: dict[str, Any], counts: dict[str, SplitCounts]) -> list[str]:
    """The sections that describe the set itself (what it is, how it was made, its levels and
    counts), without the marker line: shared by this card and the Hugging Face card of
    ``seahaze export --layout hf``, which adds its own files, loading and front-matter."""
    return [_summary(data, counts), _provenance(data), _levels(data), _counts(data, counts)]


def is_foreign(path: Path) -> bool:
    """Whether ``path`` is a file seahaze did not write as a card (it never touches those)."""
    if not (path.exists() or path.is_symlink()):
        return False
    if not path.is_file():
        return True  # a folder or a broken link named README.md: not ours either
    with path.open(encoding="utf-8", errors="replace") as fh:
        return fh.readline().rstrip("\n") != CARD_MARKER


def write_card(root: Path) -> bool:
    """Write ``root/README.md`` for the finished dataset at ``root``; False (nothing written)
    when a README.md that seahaze did not write is there."""
    layout = Layout(root)
    if is_foreign(layout.card):
        return False
    data = json.loads(layout.manifest.read_text(encoding="utf-8"))
    write_text(layout.card, card_text(data, count_labels(layout, data)))
    return True


def remove_card(root: Path) -> None:
    """Delete the card of ``root`` while scenes are pending (its counts would be stale); a
    README.md seahaze did not write stays."""
    card = Layout(root).card
    if not is_foreign(card):
        card.unlink(missing_ok=True)


# --------------------------------------------------------------------------------------------
# Sections


def _summary(data: dict[str, Any], counts: dict[str, SplitCounts]) -> str:
    scenes = len(data["scenes"])
    visibilities = [level["visibility_m"] for level in data["levels"]]
    images = scenes * (1 + len(visibilities))
    vessels = sum(sum(c.instances.values()) for c in counts.values())
    levels = ", ".join(f"{v:g}" for v in visibilities) + " m"
    return f"""# seahaze maritime haze dataset

Rendered maritime scenes, each as a haze-free image and as hazy images of a homogeneous haze
with an exact visibility label V (σ = −ln ε / V, {_threshold(data)}).

- visibility levels: {levels}
- {scenes} scenes, {images} images, {vessels} labelled vessels per level
- YOLO and COCO vessel boxes, per-pixel distance, per-scene metadata

Made with seahaze for the protocol of the MSVD paper (see *Citation*).
"""


def _threshold(data: dict[str, Any]) -> str:
    threshold = (data.get("config") or {}).get("threshold") or Threshold.KOSCHMIEDER.value
    eps = CONTRAST_THRESHOLD[Threshold(threshold)]
    return f"contrast threshold ε = {eps:g}, `{threshold}`"


def _provenance(data: dict[str, Any]) -> str:
    config = data.get("config") or {}
    split = config.get("split")
    how = (
        ", ".join(f"{name} {split[name]:g}" for name in SPLIT_NAMES)
        + "; scene-disjoint, each scene's from a SHA-256 of (master seed, scene name), so a"
        " scene keeps its split when the batch grows"
        if split
        else "none (made with `--split none`, or before splits were the default): `train` and"
        " `val` of `data.yaml` are every"
        " clean image; exports call the one split `all`"
    )
    return f"""## How it was made

- seahaze {data.get("seahaze_version")}, dataset format {data.get("format_version")}
- config hash `{config_hash(data)}` (SHA-256 of `dataset.json` without scene states; the same
  hash means the same configuration)
- render mode `{config.get("mode")}`, spp {config.get("spp")}, resolution
  {"×".join(str(v) for v in config.get("resolution", []))} pixels
{_camera_model(data)}- splits: {how}
- an equivalent command (each scene file named after its `name:`; every scene's full
  configuration is in `dataset.json`):

```bash
{equivalent_command(data)}
```
"""


def _camera_model(data: dict[str, Any]) -> str:
    """The card's line on the scenes' ``render.camera_model``, or nothing where no scene has
    one (the card of a dataset without it reads as before it existed)."""
    configs = [(e.get("config") or {}).get("render") or {} for e in data["scenes"].values()]
    used = [c["camera_model"] for c in configs if c.get("camera_model") is not None]
    if not used:
        return ""
    scope = "every scene" if len(used) == len(configs) else f"{len(used)} of {len(configs)} scenes"
    if len({json.dumps(c, sort_keys=True) for c in used}) > 1:
        settings = "settings per scene in `dataset.json`"
    else:
        settings = ", ".join(f"{key} {value}" for key, value in used[0].items())
    return f"- camera model ({scope}; clean and every level alike, EXRs without it): {settings}\n"


def _levels(data: dict[str, Any]) -> str:
    rows = [
        f"| `{lv['name']}` | {lv['visibility_m']:g} | {lv['sigma_per_m']:.6f} | "
        f"{lv['regulation_label']} |"
        for lv in data["levels"]
    ]
    return (
        "## Levels\n\n"
        "| folder | visibility V (m) | σ at 550 nm (1/m) | regulation class (MSVD Table 1) |\n"
        "|---|---|---|---|\n"
        f"| `{CLEAN_LEVEL}` | – | 0 | haze-free |\n" + "\n".join(rows) + "\n"
    )


def _counts(data: dict[str, Any], counts: dict[str, SplitCounts]) -> str:
    splits = list(counts)
    per_scene = 1 + len(data["levels"])
    header = "| | " + " | ".join(f"`{s}`" for s in splits) + " | total |\n"
    header += "|---" * (len(splits) + 2) + "|\n"
    scenes = [counts[s].scenes for s in splits]
    lines = [
        _row("scenes", scenes),
        _row("images (clean + levels)", [n * per_scene for n in scenes]),
    ]
    for class_id, name in enumerate(data["classes"]):
        values = [counts[s].instances[class_id] for s in splits]
        if any(values):
            lines.append(_row(f"`{name}` (id {class_id})", values))
    lines.append(_row("vessels (all classes)", [sum(counts[s].instances.values()) for s in splits]))
    return (
        "## Counts per split and class\n\n"
        "Vessels are counted once per image; every level holds the same boxes as `clean`.\n\n"
        + header
        + "\n".join(lines)
        + "\n"
    )


def _row(label: str, values: list[int]) -> str:
    return f"| {label} | " + " | ".join(str(v) for v in values) + f" | {sum(values)} |"


def _files(data: dict[str, Any]) -> str:
    split = bool((data.get("config") or {}).get("split"))
    splits = "train, val, test" if split else "train, val"
    rows = [("data.yaml", f"Ultralytics: {splits}, and one split per level")]
    if split:
        rows.append(
            ("train.txt val.txt test.txt", "Ultralytics lists of each split's clean images")
        )
    rows += [
        ("dataset.json", "manifest: config, levels, classes, every scene's config and split"),
        ("images/<level>/<scene>.png", "8-bit sRGB; <level> = clean, v0300, …"),
        ("labels/<level>/<scene>.txt", "YOLO 'class cx cy w h', normalised, the same per level"),
        ("coco/<level>.json", "COCO ground truth of the level (category_id = class + 1)"),
        ("depth/<scene>.exr", "float32 distance along each pixel's ray (m), inf for sky"),
        ("exr/<level>/<scene>.exr", "linear RGB radiance, float32 (when rendered with EXR)"),
        (
            "transmission/<level>/<scene>.exr",
            "per-pixel transmittance, optical depth and effective visibility of a hazy level, "
            "float32 (with the EXRs)",
        ),
        ("meta/<scene>.json", "camera, sun, sea, haze, per-vessel distance and contrast"),
    ]
    table = "\n".join(f"{name:<28}  # {what}" for name, what in rows)
    return (
        f"## Files\n\n```text\n{table}\n```\n\n"
        "Every field is described in seahaze's `docs/dataset-format.md`.\n"
    )


def _loading(data: dict[str, Any]) -> str:
    level = data["levels"][len(data["levels"]) // 2]["name"] if data["levels"] else CLEAN_LEVEL
    split = bool((data.get("config") or {}).get("split"))
    train = (
        "yolo train model=yolo11n.yaml data=data.yaml       # train.txt, validated on val.txt\n"
        if split
        else "yolo train model=yolo11n.yaml data=data.yaml       # every clean image\n"
    )
    return f"""## Loading

Ultralytics, from any folder (each level is a split of `data.yaml`; `path` is absolute, so
after moving the folder rerun its `seahaze render` command there, which renders nothing and
rewrites `data.yaml`, or use `seahaze export --layout yolo`):

```bash
{train}yolo val model=WEIGHTS.pt data=data.yaml split={level}  # every scene of one level
```

COCO tools: `pycocotools.coco.COCO("coco/{level}.json")`; `file_name` is relative to this folder.

Dehazing: paired hazy and clean images per split, as links (no pixels copied):

```bash
seahaze export . --layout paired --out ../paired  # hazy/<scene>_<level>.png, GT/<scene>.png
seahaze export . --layout reside --out ../reside  # hazy/<id>_<level>.png, clear/<id>.png
```

The MSVD visibility metric with a detector (one command per stage):

```bash
seahaze metric calibrate --dataset . --model WEIGHTS.pt --pred preds --out table
seahaze metric newvis --table table.json --model WEIGHTS.pt --images DEHAZED/ --pred dehazed \\
    --dataset . --level {level}
```
"""


def citation_section() -> str:
    """The card's *Citation* section: the MSVD paper, whose levels and metric the set follows."""
    return f"""## Citation

The graded visibility levels, the regulation classes and the visibility metric follow the MSVD
paper; cite it when you use them:

```bibtex
{MSVD_CITATION}
```
"""
