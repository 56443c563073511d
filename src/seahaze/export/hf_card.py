"""The card of an ``hf`` export: ``README.md`` with the Hugging Face Hub's YAML front-matter
(licence, task categories, tags, size, and the configurations: ``all`` levels by default and
one per level, each with its splits' Parquet files), then the dataset's own description (the
sections of the dataset folder's card, :mod:`seahaze.dataset.card`), what a row holds, how to
load it, and the citation.

``datasets.load_dataset`` reads the ``configs`` block to find each configuration's files; the
Hub shows the rest. ``datasets`` caches a local folder under its name and a hash of that block
(not of the files: measured with datasets 2.19.2 and 5.2.0, a second export into the same
folder was loaded from the first one's cache), so each configuration's ``description`` carries
:func:`content_id`, which changes whenever the rows would.
"""

from __future__ import annotations

import hashlib
import json
import re
from typing import Any

import yaml

from ..dataset.card import citation_section, count_labels, description_sections
from .source import ExportError, SourceDataset

DEFAULT_CONFIG = "all"
"""The configuration of every level, loaded when none is named."""
NO_LICENSE = "other"
"""The licence field when ``--license`` is not given: the Hub's value for one not listed."""
LICENSE_PATTERN = re.compile(r"[a-z0-9][a-z0-9.+-]{0,63}")
"""A Hub licence identifier (``cc-by-4.0``, ``apache-2.0``, ``cc0-1.0`` …)."""
TASKS = ("image-to-image", "object-detection", "depth-estimation")
"""Hub task categories: dehazing (hazy → clean), vessel detection, the per-pixel distance."""
TAGS = ("dehazing", "haze", "fog", "visibility", "maritime", "synthetic", "seahaze")


def check_license(license_id: str) -> str:
    """``license_id`` if it can be a Hub licence identifier, else :class:`ExportError`."""
    if LICENSE_PATTERN.fullmatch(license_id) is None:
        shown = license_id[:40] + ("…" if len(license_id) > 40 else "")
        raise ExportError(
            f"--license {shown!r}: allowed: a Hub licence identifier such as cc-by-4.0, "
            "apache-2.0 or other (lowercase letters, digits, '.', '+', '-'; at most 64)"
        )
    return license_id


def card_text(
    source: SourceDataset, rows: dict[str, dict[str, int]], license_id: str = NO_LICENSE
) -> str:
    """The card of an ``hf`` export of ``source`` whose configuration of each level has
    ``rows[level][split]`` rows."""
    data = source.manifest
    try:
        described = description_sections(data, count_labels(source.layout, data))
    except (KeyError, TypeError, ValueError, AttributeError, IndexError) as err:
        # The card reads parts of dataset.json that an export does not otherwise check.
        raise ExportError(
            f"{source.layout.manifest}: cannot describe the dataset in the card "
            f"({type(err).__name__}: {str(err)[:80]}); the manifest is damaged: rerun the "
            "'seahaze render' command that made it"
        ) from None
    front = yaml.safe_dump(
        front_matter(rows, license_id, content_id(source)),
        sort_keys=False,
        allow_unicode=True,
        width=100,
    )
    sections = [*described, _export(source, rows), _license(license_id), citation_section()]
    return f"---\n{front}---\n\n" + "\n".join(sections)


def front_matter(rows: dict[str, dict[str, int]], license_id: str, content: str) -> dict[str, Any]:
    """The Hub's YAML metadata: a configuration ``all`` (the default) over every level's
    files and one per level, each with its splits and a description naming ``content`` (the
    export's :func:`content_id`)."""
    splits = list(dict.fromkeys(split for per_level in rows.values() for split in per_level))
    configs: list[dict[str, Any]] = [
        {
            "config_name": DEFAULT_CONFIG,
            "default": True,
            "description": f"every level; seahaze export {content}",
            "data_files": [{"split": s, "path": f"data/*/{s}-*.parquet"} for s in splits],
        }
    ]
    for level, per_split in rows.items():
        files = [{"split": s, "path": f"data/{level}/{s}-*.parquet"} for s in per_split]
        description = f"level {level}; seahaze export {content}"
        configs.append({"config_name": level, "description": description, "data_files": files})
    total = sum(sum(per_split.values()) for per_split in rows.values())
    return {
        "license": license_id,
        "pretty_name": "seahaze maritime haze dataset",
        "task_categories": list(TASKS),
        "tags": list(TAGS),
        "size_categories": [size_category(total)],
        "configs": configs,
    }


ROW_FORMAT = 1
"""Version of what a row holds and how (raised when either changes, so that an export made
after such a change is not loaded from the cache of an older one)."""


def content_id(source: SourceDataset) -> str:
    """16 hex digits that change whenever the rows of an export of ``source`` would: a SHA-256
    of the row format, the classes, the exported levels' entries in ``dataset.json`` and every
    scene's name, split, sequence, frame and ``files_sha256`` (the digest of its meta, depth,
    images and labels that ``seahaze render`` records; a dataset without one is told apart by
    the rest only)."""
    scenes = source.manifest.get("scenes", {})
    exported = {level.name for level in source.levels}
    identity = {
        "row_format": ROW_FORMAT,
        "classes": list(source.classes),
        "levels": [
            entry
            for entry in source.manifest.get("levels", [])
            if isinstance(entry, dict) and entry.get("name") in exported
        ],
        "scenes": [
            [name, split, *(scenes[name].get(k) for k in ("sequence", "frame", "files_sha256"))]
            for name, split in source.scenes.items()
        ],
    }
    text = json.dumps(identity, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def size_category(rows: int) -> str:
    """The Hub's size category of ``rows`` rows (``n<1K``, ``1K<n<10K`` …)."""
    bounds = ["1K", "10K", "100K", "1M", "10M", "100M", "1B"]
    if rows < 1000:
        return "n<1K"
    for i, upper in enumerate(bounds[1:]):
        if rows < 10 ** (i + 4):
            return f"{bounds[i]}<n<{upper}"
    return "n>1T" if rows >= 10**12 else "1B<n<10B"


def _export(source: SourceDataset, rows: dict[str, dict[str, int]]) -> str:
    levels = list(rows)
    per_level = next(iter(rows.values()), {})
    split_rows = ", ".join(f"`{split}` {n}" for split, n in per_level.items())
    level = levels[len(levels) // 2] if levels else "v1000"
    lone = (
        "\nThe dataset has no split (`--split none`): its one split is `train` here (`all` "
        "means every split to `datasets`).\n"
        if list(source.splits) == ["all"]
        else ""
    )
    return f"""## This export: Hugging Face `datasets`

Made by `seahaze export --layout hf`: one row per scene and hazy level, in Parquet files under
`data/<level>/`. The configuration `{DEFAULT_CONFIG}` (the default) holds every level
({len(levels)}); each level is also a configuration of its own (`{"`, `".join(levels)}`), with
rows per split {split_rows}.
{lone}
{_field_table()}

```python
import numpy as np
from datasets import load_dataset

ds = load_dataset("path/to/this/folder")              # every level, split by split
level = load_dataset("path/to/this/folder", "{level}", split="train")
row = level[0]                                         # hazy and clean: PIL images
depth = np.asarray(row["depth"])                       # float32, metres, inf for sky
stream = load_dataset("path/to/this/folder", "{level}", split="train", streaming=True)
```

The folder is a dataset repository as it stands (this card and `data/`): upload it whole to
the Hub. Every field is described in seahaze's `docs/dataset-format.md`.
"""


FIELDS = (
    (
        "`scene`, `sequence`, `frame`",
        "string, string, int32",
        "scene name; a sequence's name and 0-based frame (else null)",
    ),
    (
        "`split`",
        "string",
        "`train`, `val` or `test`: scene-disjoint, every level of a scene in one split",
    ),
    (
        "`level`, `visibility_m`",
        "string, float64",
        "level folder name (`v0300`), visibility V in m",
    ),
    (
        "`sigma_per_m`, `sigma_rgb_per_m`",
        "float64, 3 × float64",
        "extinction at 550 nm and per channel R, G, B, 1/m",
    ),
    ("`regulation`", "string", "navigation regulation class of the level (MSVD Table 1)"),
    ("`hazy`, `clean`", "Image", "the 8-bit sRGB PNGs of the level and of the haze-free scene"),
    (
        "`depth`",
        "Image (float32 TIFF, mode `F`)",
        "distance along each pixel's ray in m, `inf` for sky",
    ),
    (
        "`objects`",
        "sequence",
        "the labelled vessels: `vessel` (index in the scene), `track_id` (sequences), `category` "
        "(class), `bbox` (`[x, y, w, h]` px), `distance_m`, `visible_fraction` (unoccluded share), "
        "and at this level `apparent_contrast`, `local_contrast`, `visible` (discernible against "
        "its local background) and `beyond_visibility`",
    ),
)
"""The card's table of a row's fields: name, type, meaning."""


def _field_table() -> str:
    rows = [f"| {name} | {kind} | {meaning} |" for name, kind, meaning in FIELDS]
    return "| field | type | meaning |\n|---|---|---|\n" + "\n".join(rows)


def _license(license_id: str) -> str:
    if license_id == NO_LICENSE:
        how = (
            "No licence was chosen when this folder was exported (`license: other`): whoever "
            "rendered the set chooses one, e.g. `seahaze export … --layout hf --license "
            "cc-by-4.0`."
        )
    else:
        how = f"`{license_id}`, as chosen when this folder was exported (`--license`)."
    return f"## Licence\n\n{how}\n"
