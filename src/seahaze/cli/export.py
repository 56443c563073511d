"""``seahaze export``: a finished dataset in the folder layout of a dehazing or detection tool."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .common import UsageError


def _levels(text: str | None) -> list[str] | None:
    """``--levels v0300,1000`` → level folder names (None: every hazy level)."""
    if text is None:
        return None
    from ..metric.errors import MetricInputError
    from ..metric.reader import parse_level

    try:
        levels = [parse_level(item) for item in text.split(",") if item.strip()]
    except MetricInputError as err:
        raise UsageError(str(err).replace("--level ", "--levels ")) from None
    if not levels:
        raise UsageError(
            f"--levels {text!r}: no level named; give levels such as v0300,1000 (comma-separated), "
            "or leave --levels out for every hazy level"
        )
    return levels


def cmd_export(args: argparse.Namespace) -> int:
    """Export a finished dataset into another tool's layout; links where possible."""
    from ..export import ExportError, export_dataset

    try:
        report = export_dataset(
            Path(args.dataset),
            Path(args.out),
            args.layout,
            args.link,
            _levels(args.levels),
            args.license,
        )
    except ExportError as err:
        raise UsageError(str(err)) from None
    except OSError as err:
        where = f" ({err.filename})" if err.filename else ""
        hint = "; try --link auto or copy" if args.link in ("hard", "symlink") else ""
        print(
            f"seahaze: error: cannot write the export: {err.strerror}{where}{hint}", file=sys.stderr
        )
        return 3
    for line in report.warnings:
        print(f"seahaze: warning: {line}", file=sys.stderr)
    pairs = f", {report.pairs} hazy/clean pairs" if report.pairs else ""
    removed = f"; removed {report.removed} file(s) of an earlier export" if report.removed else ""
    files = (
        f"{report.built} {report.kind} file(s) ({report.built_bytes / 1e6:.1f} MB)"
        if report.built
        else f"{report.placed} dataset files ({report.methods})"
    )
    print(
        f"exported {report.layout}: splits {', '.join(report.splits)}, levels "
        f"{', '.join(report.levels)}{pairs} to {report.out}: {files}, {report.texts} text "
        f"file(s){removed}"
    )
    return 0


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The ``export`` subcommand and its flags."""
    from ..export import LAYOUTS, LINK_MODES

    parser = sub.add_parser(
        "export",
        help="a finished dataset in a dehazing or detection tool's folder layout (links)",
        description="Write a view of a finished dataset in another tool's folder layout: "
        "paired hazy/clean images per split for dehazing code, one Ultralytics dataset per "
        "level, or a Hugging Face datasets folder of Parquet files. Dataset files are "
        "hard-linked (symbolic links or copies where that is impossible); files in --out that "
        "seahaze did not write are never overwritten. "
        "See docs/dataset-format.md#exports. Exit code 2: bad input or refused; 3: write error.",
    )
    parser.add_argument("dataset", metavar="DIR", help="a finished dataset of 'seahaze render'")
    parser.add_argument(
        "--layout",
        required=True,
        choices=list(LAYOUTS),
        help="paired: <split>/hazy/<scene>_<level>.png + <split>/GT/<scene>.png + pairs.csv; "
        "same-name: GT/<scene>_<level>.png beside the hazy image of that name (DehazeFormer); "
        "reside: <split>/hazy/<id>_<level>.png + <split>/clear/<id>.png (RESIDE, FFA-Net); "
        "yolo: <level>/data.yaml with images/<split>/ and labels/<split>/ (Ultralytics); "
        "yolo-hazy: one data.yaml over the clean image and every level of each scene, "
        "images/<split>/<scene>_<level>.png with that level's labels (training on haze); "
        "hf: data/<level>/<split>-*.parquet + README.md for Hugging Face datasets, one row per "
        "scene and level with hazy, clean, depth, visibility, σ and vessels (needs "
        "pip install 'seahaze[hf]')",
    )
    parser.add_argument("--out", required=True, metavar="DIR", help="folder of the export")
    parser.add_argument(
        "--link",
        choices=list(LINK_MODES),
        default="auto",
        help="how dataset files are placed: auto (hard link, else symbolic link, else copy; "
        "the summary says which), hard, symlink or copy (default: auto); the hf layout copies "
        "the pixels into its Parquet files and links nothing",
    )
    parser.add_argument(
        "--license",
        metavar="ID",
        help="--layout hf only: the licence in its card's front-matter, a Hub identifier such "
        "as cc-by-4.0 (default: other, and the card says none was chosen)",
    )
    parser.add_argument(
        "--levels",
        metavar="L1,L2",
        help="hazy levels to export, e.g. v0300,v1000 or 300,1000 (default: every level)",
    )
    parser.set_defaults(func=cmd_export)
