"""What the subcommands share: the usage error, argument parsers and scene loading."""

from __future__ import annotations

import re
from pathlib import Path

from ..spec import SceneSpec
from ..visibility import VisSelectionError, parse_vis_selection

DEFAULT_SCENE = Path("scenes/default.yaml")


class UsageError(Exception):
    """Bad command-line input; printed as one line, exit code 2."""


def parse_res(text: str) -> tuple[int, int]:
    """``WIDTHxHEIGHT`` in pixels, each within 8..8192."""
    match = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text)
    if not match:
        raise UsageError(f"--res {text!r}: expected WIDTHxHEIGHT in pixels, e.g. 640x360")
    width, height = int(match[1]), int(match[2])
    if not (8 <= width <= 8192 and 8 <= height <= 8192):
        raise UsageError(f"--res {text!r}: width and height must be within 8..8192 pixels")
    return width, height


def parse_vis(text: str | None) -> list[float] | None:
    """The levels of a ``--vis`` selection (None when the flag is absent)."""
    if text is None:
        return None
    try:
        return parse_vis_selection(text)
    except VisSelectionError as err:
        raise UsageError(str(err)) from None


def load_scenes(paths: list[str]) -> list[tuple[SceneSpec, str]]:
    """Every scene file, validated; all problems of all files in one :class:`UsageError`.

    Every problem is one line ``seahaze: error: FILE:LINE: FIELD: MESSAGE``, whether a file
    has one or many, for ``validate``, ``render`` and ``verify`` alike.
    """
    from ..sceneio import SceneFileError, load_scene

    scenes, problems = [], []
    for path in paths:
        try:
            scenes.append(load_scene(path))
        except SceneFileError as err:
            problems += err.problems
    if len(problems) == 1:
        raise UsageError(str(problems[0]))  # main() puts "seahaze: error: " before one line
    if problems:
        # main() prints a message of several lines as it is: each gets the prefix here.
        raise UsageError("\n".join(f"seahaze: error: {p}" for p in problems))
    return scenes
