"""``seahaze export``: a view of a finished dataset in another tool's folder layout.

The order makes a refusal safe: the dataset is checked and the whole plan made first; then the
output folder's record of seahaze's files is read and any file in the way that seahaze did not
write refuses the export with nothing written; then the files built from the dataset's contents
(the ``hf`` layout's Parquet shards) are written under temporary names, so that a dataset file
that cannot be read still refuses the export with nothing left behind; only then are files
placed and the built ones renamed into place, and files an earlier export of this folder made
but this one does not are deleted.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from ..dataset.owned import ForeignFileError, OwnedFiles
from ..fileio import write_text
from .hf_card import check_license
from .layouts import LAYOUTS, REQUIREMENTS
from .links import Placer
from .source import ExportError, open_finished

WITH_CLEAN = ("yolo", "yolo-hazy")
"""Layouts whose levels include ``clean`` as a level of its own."""


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
    built: int = 0
    """Files built from the dataset's contents (the ``hf`` layout's Parquet shards)."""
    built_bytes: int = 0
    kind: str = ""
    """What the built files are (``Parquet``)."""


def export_dataset(
    dataset: Path,
    out: Path,
    layout: str,
    link: str = "auto",
    levels: list[str] | None = None,
    license_id: str | None = None,
) -> ExportReport:
    """Export the finished dataset at ``dataset`` into ``out`` in ``layout`` (see
    :data:`seahaze.export.layouts.LAYOUTS`), placing its files by ``link`` (see
    :class:`~seahaze.export.links.Placer`); ``license_id`` is the licence of the ``hf``
    layout's card (no other layout takes one).

    Raises :class:`ExportError` (one line, nothing written) for an unfinished or foreign
    folder, an unknown layout or level, an output folder inside the dataset, a file in the
    way that seahaze did not write and a dataset file that cannot be read; ``OSError`` when
    the output cannot be written.
    """
    if layout not in LAYOUTS:
        raise ExportError(f"--layout {layout!r}: allowed {', '.join(LAYOUTS)}")
    options = {}
    if license_id is not None:
        if layout != "hf":
            raise ExportError(
                f"--license: only --layout hf writes a licence (in its card), not {layout}; "
                "leave --license out"
            )
        options["license_id"] = check_license(license_id)
    source = open_finished(dataset, levels)
    out = Path(out).resolve()
    if out == source.root or out.is_relative_to(source.root):
        raise ExportError(f"--out {out}: inside the dataset {source.root}; choose a folder outside")
    _check_out_folder(out)
    if layout in REQUIREMENTS:
        REQUIREMENTS[layout]()
    plan = LAYOUTS[layout](source, **options)
    _check_outside_dataset(out, plan.targets(), source.root)
    placer = Placer(link)
    try:
        owned = OwnedFiles.open(out)
        owned.check(plan.targets())
    except ForeignFileError as err:
        raise ExportError(str(err)) from None
    staged = _build(out, plan.built)
    try:
        info = {"tool": "seahaze export", "layout": layout, "dataset": str(source.root)}
        stale = owned.claim(plan.targets(), info)
        for target, path in plan.placed.items():
            placer.place(path, out / target)
        for target, tmp in staged.items():
            os.replace(tmp, out / target)
        for target, text in plan.texts.items():
            write_text(out / target, text)
    finally:
        for tmp in staged.values():
            tmp.unlink(missing_ok=True)
    owned.seal(plan.targets())
    kept = owned.release(stale)
    return ExportReport(
        out,
        layout,
        source.splits,
        tuple(source.level_names(with_clean=layout in WITH_CLEAN)),
        len(plan.placed),
        len(plan.texts),
        plan.pairs,
        placer.summary(),
        len(stale) - len(kept),
        (*owned.ignored, *kept),
        len(staged),
        sum((out / target).stat().st_size for target in staged),
        plan.kind,
    )


def _build(out: Path, builders: dict[str, Callable[[Path], None]]) -> dict[str, Path]:
    """Write each built file under a temporary name beside its target; returns target →
    temporary path. On any failure (a dataset file that cannot be read, a full disk, Ctrl-C)
    the temporary files and the folders made for them are removed before it propagates."""
    made = _missing_folders(out, builders)
    staged: dict[str, Path] = {}
    try:
        for target, build in builders.items():
            final = out / target
            final.parent.mkdir(parents=True, exist_ok=True)
            staged[target] = final.with_name(f".{final.name}.tmp{os.getpid()}")
            build(staged[target])
    except BaseException:
        for tmp in staged.values():
            tmp.unlink(missing_ok=True)
        for folder in made:  # deepest first; only the ones this export made, and only empty
            with contextlib.suppress(OSError):
                folder.rmdir()
        raise
    return staged


def _missing_folders(out: Path, targets: dict[str, Callable[[Path], None]]) -> list[Path]:
    """The folders that writing ``targets`` into ``out`` creates (``out`` and those above it
    included), deepest first."""
    missing: set[Path] = set()
    for target in targets:
        folder = (out / target).parent
        while not folder.exists() and folder != folder.parent:
            missing.add(folder)
            folder = folder.parent
    return sorted(missing, key=lambda path: len(path.parts), reverse=True)


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
