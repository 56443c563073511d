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
    _check_out_folder(out)
    plan = LAYOUTS[layout](source)
    _check_outside_dataset(out, plan.targets(), source.root)
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
        tuple(source.level_names(with_clean=layout in ("yolo", "yolo-hazy"))),
        len(plan.placed),
        len(plan.texts),
        plan.pairs,
        placer.summary(),
        len(stale) - len(kept),
        (*owned.ignored, *kept),
    )


def _check_out_folder(out: Path) -> None:
    """``out`` is a folder or can become one: a file there, or on the way to it, is bad input
    (it was a write error, exit 3, after the plan was made)."""
    for path in (out, *out.parents):
        if path.exists():
            if not path.is_dir():
                what = "is a file" if path == out else f"lies under the file {path}"
                raise ExportError(
                    f"--out {out}: {what}, not a folder; give a new folder or one of an "
                    "earlier export"
                )
            return


def _check_outside_dataset(out: Path, targets: list[str], dataset: Path) -> None:
    """No file of the export lands inside the dataset: an ``--out`` above the dataset (its
    parent, with the dataset named like a split or level folder) or a folder of ``--out`` that
    is a link into the dataset would place files among the dataset's own."""
    folders = {str(Path(target).parent) for target in targets}
    for folder in sorted(folders):
        where = (out / folder).resolve()
        if where == dataset or where.is_relative_to(dataset):
            raise ExportError(
                f"--out {out}: its {folder}/ would be inside the dataset {dataset} (the export "
                "would write among the dataset's files); choose a folder outside the dataset"
            )
