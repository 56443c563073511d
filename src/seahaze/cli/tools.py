"""The small subcommands: ``levels``, ``validate``, ``classes`` and ``preview``."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..visibility import (
    GRADED_LEVELS_M,
    Threshold,
    extinction_coefficient,
    level_name,
    regulation_class,
)
from .common import UsageError, load_scenes, parse_vis


def cmd_levels(args: argparse.Namespace) -> int:
    """Print the selected visibility levels with extinction and regulation class."""
    levels = parse_vis(args.vis) or [float(v) for v in GRADED_LEVELS_M]
    print(f"{'level':<7} {'V (m)':>8} {'sigma (1/m)':>12}  regulation class")
    for v in levels:
        cls = regulation_class(v)
        print(
            f"{level_name(v):<7} {v:>8g} {extinction_coefficient(v, args.threshold):>12.6f}  "
            f"{cls.key:<16} {cls.label}"
        )
    return 0


def cmd_validate(args: argparse.Namespace) -> int:
    """Check scene files and report every problem."""
    scenes = load_scenes(args.scenes)
    for _spec, name in scenes:
        print(f"ok: {name}")
    return 0


def cmd_classes(args: argparse.Namespace) -> int:
    """List the vessel classes with their YOLO ids and length ranges."""
    from ..vessels import CLASS_NAMES, VESSEL_CLASSES

    for i, name in enumerate(CLASS_NAMES):
        lo, hi = VESSEL_CLASSES[name].length_range_m
        print(f"{i:>2}  {name:<18} {lo:g}-{hi:g} m")
    return 0


def cmd_preview(args: argparse.Namespace) -> int:
    """Write a contact sheet of one scene: clean and levels side by side, boxes drawn; with
    ``--sequence``, an animated GIF or MP4 of a sequence's frames."""
    from ..preview import PreviewError, check_overwrite, contact_sheet, save_sheet

    root = Path(args.dataset)
    levels = [lv.strip() for lv in args.levels.split(",")] if args.levels else None
    if not (1 <= args.columns <= 64 and 32 <= args.tile_width <= 4096):
        raise UsageError("--columns must be within 1..64 and --tile-width within 32..4096")
    if args.sequence:
        return _preview_sequence(args, root, levels)
    try:
        sheet = contact_sheet(
            root, args.scene, levels, args.columns, args.tile_width, not args.no_boxes
        )
    except PreviewError as err:
        raise UsageError(str(err)) from None
    out = Path(args.out) if args.out else beside(root, "preview.png")
    try:
        check_overwrite(out)
        out.parent.mkdir(parents=True, exist_ok=True)
        save_sheet(sheet, out)
    except PreviewError as err:
        raise UsageError(str(err)) from None
    except (OSError, ValueError) as err:
        raise UsageError(f"--out {out}: cannot write the contact sheet ({err})") from None
    print(f"wrote {out}")
    return 0


def beside(root: Path, name: str) -> Path:
    """``<root>-<name>`` next to the dataset folder ``root``: a preview's default place, out
    of the dataset (whose files are seahaze's and an export's sources)."""
    folder = root.resolve()
    return folder.with_name(f"{folder.name}-{name}")


def _preview_sequence(args: argparse.Namespace, root: Path, levels: list[str] | None) -> int:
    """``seahaze preview --sequence NAME``: every frame's contact sheet as an animated GIF or
    an MP4, by the extension of ``--out``."""
    from ..preview import (
        ANIMATION_FORMATS,
        PreviewError,
        animation,
        check_overwrite,
        save_gif,
        save_mp4,
    )

    out = Path(args.out) if args.out else beside(root, f"{args.sequence}.gif")
    suffix = out.suffix.lower()
    if suffix not in ANIMATION_FORMATS:
        allowed = " or ".join(ANIMATION_FORMATS)
        raise UsageError(f"--out {out}: an animated preview is a {allowed} file")
    try:
        check_overwrite(out)
        sheets, fps = animation(
            root, args.sequence, levels, args.columns, args.tile_width, not args.no_boxes
        )
    except PreviewError as err:
        raise UsageError(str(err)) from None
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        (save_mp4 if suffix == ".mp4" else save_gif)(sheets, out, fps)
    except PreviewError as err:
        raise UsageError(str(err)) from None
    except OSError as err:
        raise UsageError(f"--out {out}: cannot write the animation ({err})") from None
    print(f"wrote {out} ({len(sheets)} frames at {fps:g} frames/s)")
    return 0


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """The ``levels``, ``validate``, ``preview`` and ``classes`` subcommands."""
    levels = sub.add_parser(
        "levels", help="print visibility levels with sigma and regulation class"
    )
    levels.add_argument(
        "--vis", metavar="SEL", help="levels as for 'render --vis' (default: the 11 graded levels)"
    )
    levels.add_argument(
        "--threshold",
        choices=[t.value for t in Threshold],
        default=Threshold.KOSCHMIEDER.value,
        help="contrast threshold convention (default: koschmieder, 2 %%)",
    )
    levels.set_defaults(func=cmd_levels)

    validate = sub.add_parser("validate", help="check scene files and report every problem")
    validate.add_argument("scenes", nargs="+", metavar="SCENE.yaml")
    validate.set_defaults(func=cmd_validate)

    preview = sub.add_parser(
        "preview", help="contact sheet of a scene: clean and levels side by side, boxes drawn"
    )
    preview.add_argument(
        "dataset", metavar="DIR", help="dataset folder written by 'seahaze render'"
    )
    preview.add_argument("--scene", help="scene name (default: the first in dataset.json)")
    preview.add_argument(
        "--sequence",
        metavar="NAME",
        help="animate every frame of sequence NAME into a GIF, or an MP4 with --out NAME.mp4 "
        "(needs pip install 'seahaze[video]'; default --out DIR/NAME.gif)",
    )
    preview.add_argument(
        "--levels", metavar="L1,L2", help="levels to show, e.g. clean,v0300,v1000 (default: all)"
    )
    preview.add_argument("--columns", type=int, default=3, help="tiles per row (default 3)")
    preview.add_argument(
        "--tile-width", type=int, default=640, help="width of one tile in pixels (default 640)"
    )
    preview.add_argument("--no-boxes", action="store_true", help="do not draw the label boxes")
    preview.add_argument(
        "--out",
        metavar="FILE",
        help="output file (default beside the dataset, never in it: DIR-preview.png, "
        "DIR-NAME.gif); an existing file is "
        "replaced only when it is a preview seahaze wrote, else choose another name",
    )
    preview.set_defaults(func=cmd_preview)

    classes = sub.add_parser("classes", help="list the vessel classes and their YOLO ids")
    classes.set_defaults(func=cmd_classes)
