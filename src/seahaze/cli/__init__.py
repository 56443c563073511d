"""The ``seahaze`` command line. It only parses arguments and calls the library.

Exit codes: 0 success, 1 a scene failed, 2 bad input or refused (arguments, scene files, a
locked folder, a changed config), 3 a write error stopped the batch (disk full, I/O error),
130 interrupted. After 1, 3 or 130, rerunning the same command renders only what is missing.
"""

from __future__ import annotations

import argparse
import sys

from .. import __version__
from ..metric import cli as metric_cli
from . import export, render, tools, verify
from .common import UsageError

__all__ = ["UsageError", "build_parser", "entry", "main"]


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``seahaze`` command."""
    parser = argparse.ArgumentParser(
        prog="seahaze",
        description="Physically based maritime haze datasets with exact visibility labels.",
    )
    parser.add_argument("--version", action="version", version=f"seahaze {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    render.add_parser(sub)
    export.add_parser(sub)
    tools.add_parsers(sub)
    verify.add_parser(sub)
    metric_cli.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``seahaze`` command; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except UsageError as err:
        print(f"seahaze: error: {err}" if "\n" not in str(err) else str(err), file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("seahaze: interrupted", file=sys.stderr)
        return 130


def entry() -> None:
    """The ``seahaze`` console command: :func:`main`, then exit with its code."""
    sys.exit(main())
