"""``seahaze export``: a view of a finished dataset in another tool's folder layout.

The order makes a refusal safe: the dataset is checked and the whole plan made first; then the
output folder's record of seahaze's files is read and any file in the way that seahaze did not
write refuses the export with nothing written; only then are files placed, and files an earlier
export of this folder made but this one does not are deleted.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..dataset.owned import ForeignFileError, OwnedFiles
from ..fileio import write_text
from .layouts import LAYOUTS
from .links import Placer
from .source import ExportError, open_finished


@dataclass(frozen=True)
class ExportReport:
    """What an export wrote."""

    out: Path
    layout: str
    splits: tuple[str, ...]
    levels: tuple[str, ...]
    placed: int
    texts: int
    pairs: int
    methods: str
    """How the dataset files were placed, e.g. ``hard links: 104``."""
    removed: int
    """Files of an earlier export of this folder that this one no longer has."""
    warnings: tuple[str, ...] = ()
    """Record entries not trusted and files left alone, one line each."""


def export_dataset(
    dataset: Path,
    out: Path,
    layout: str,
    link: str = "auto",
    levels: list[str] | None = None,
) -> ExportReport:
    """Export the finished dataset at ``dataset`` into ``out`` in ``layout`` (see
    :data:`seahaze.export.layouts.LAYOUTS`), placing its files by ``link`` (see
    :class:`~seahaze.export.links.Placer`).

    Raises :class:`ExportError` (one line, nothing written) for an unfinished or foreign
    folder, an unknown layout or level, an output folder inside the dataset and a file in the
    way that seahaze did not write; ``OSError`` when the output cannot be written.
    """
    if layout not in LAYOUTS:
        raise ExportError(f"--layout {layout!r}: allowed {', '.join(LAYOUTS)}")
    source = open_finished(dataset, levels)
    out = Path(out).resolve()
    if out == source.root or out.is_relative_to(source.root):
        raise ExportError(f"--out {out}: inside the dataset {source.root}; choose a folder outside")
    plan = LAYOUTS[layout](source)
    placer = Placer(link)
    try:
        owned = OwnedFiles.open(out)
        owned.check(plan.targets())
    except ForeignFileError as err:
        raise ExportError(str(err)) from None
    info = {"tool": "seahaze export", "layout": layout, "dataset": str(source.root)}
    stale = owned.claim(plan.targets(), info)
    for target, path in plan.placed.items():
        placer.place(path, out / target)
    for target, text in plan.texts.items():
        write_text(out / target, text)
    owned.seal(plan.targets())
    kept = owned.release(stale)
    return ExportReport(
        out,
        layout,
        source.splits,
        tuple(source.level_names(with_clean=layout == "yolo")),
        len(plan.placed),
        len(plan.texts),
        plan.pairs,
        placer.summary(),
        len(stale) - len(kept),
        (*owned.ignored, *kept),
    )
