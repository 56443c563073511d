"""The ``seahaze`` command line. It only parses arguments and calls the library.

Exit codes: 0 success, 1 a render failed, 2 bad input (arguments or scene files).
"""

from __future__ import annotations

import argparse
import re
import sys
import time
from pathlib import Path

from . import __version__
from .metric import cli as metric_cli
from .visibility import (
    GRADED_LEVELS_M,
    Threshold,
    VisSelectionError,
    extinction_coefficient,
    level_name,
    parse_vis_selection,
    regulation_class,
)

DEFAULT_SCENE = Path("scenes/default.yaml")
DEFAULT_OUT = Path("out/dataset")


class UsageError(Exception):
    """Bad command-line input; printed as one line, exit code 2."""


def _parse_res(text: str) -> tuple[int, int]:
    match = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text)
    if not match:
        raise UsageError(f"--res {text!r}: expected WIDTHxHEIGHT in pixels, e.g. 640x360")
    width, height = int(match[1]), int(match[2])
    if not (8 <= width <= 8192 and 8 <= height <= 8192):
        raise UsageError(f"--res {text!r}: width and height must be within 8..8192 pixels")
    return width, height


def _parse_vis(text: str | None) -> list[float] | None:
    if text is None:
        return None
    try:
        return parse_vis_selection(text)
    except VisSelectionError as err:
        raise UsageError(str(err)) from None


def _load_scenes(paths: list[str]):
    from .sceneio import SceneFileError, load_scene

    scenes, problems = [], []
    for path in paths:
        try:
            scenes.append(load_scene(path))
        except SceneFileError as err:
            problems += err.problems
    if problems:
        raise UsageError("\n".join(str(p) for p in problems))
    return scenes


def cmd_render(args: argparse.Namespace) -> int:
    """Render scenes into a dataset folder."""
    from .pipeline import DatasetError, render_dataset
    from .render.variant import VariantError
    from .spec import OverrideError, with_overrides

    paths = args.scenes or [str(DEFAULT_SCENE)]
    levels = _parse_vis(args.vis)
    resolution = _parse_res(args.res) if args.res else None
    if args.spp is not None and args.spp < 1:
        raise UsageError(f"--spp {args.spp}: must be >= 1")
    scenes = []
    for spec, name in _load_scenes(paths):
        try:
            spec = with_overrides(
                spec,
                spp=args.spp,
                resolution=resolution,
                seed=args.seed,
                mode=args.mode,
                variant=args.variant,
                levels=levels,
            )
        except OverrideError as err:
            raise UsageError(f"{name}: {err}") from None
        scenes.append((spec, name))
    out = Path(args.out)
    say = (
        (lambda _msg: None)
        if args.quiet
        else (lambda msg: print(f"[seahaze] {msg}", file=sys.stderr, flush=True))
    )
    start = time.perf_counter()
    try:
        results = render_dataset(scenes, out, say)
    except (DatasetError, VariantError) as err:
        raise UsageError(str(err)) from None
    images = sum(1 + len(spec.haze.levels) for spec, _ in scenes)
    print(
        f"wrote {len(results)} scene(s), {images} images to {out.resolve()} in "
        f"{time.perf_counter() - start:.1f} s"
    )
    return 0


def cmd_levels(args: argparse.Namespace) -> int:
    """Print the selected visibility levels with extinction and regulation class."""
    levels = _parse_vis(args.vis) or [float(v) for v in GRADED_LEVELS_M]
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
    scenes = _load_scenes(args.scenes)
    for _spec, name in scenes:
        print(f"ok: {name}")
    return 0


def cmd_classes(args: argparse.Namespace) -> int:
    """List the vessel classes with their YOLO ids and length ranges."""
    from .vessels import CLASS_NAMES, VESSEL_CLASSES

    for i, name in enumerate(CLASS_NAMES):
        lo, hi = VESSEL_CLASSES[name].length_range_m
        print(f"{i:>2}  {name:<18} {lo:g}-{hi:g} m")
    return 0


def cmd_preview(args: argparse.Namespace) -> int:
    """Write a contact sheet of one scene: clean and levels side by side, boxes drawn."""
    from .preview import PreviewError, contact_sheet

    root = Path(args.dataset)
    levels = [lv.strip() for lv in args.levels.split(",")] if args.levels else None
    if args.columns < 1 or args.tile_width < 32:
        raise UsageError("--columns must be >= 1 and --tile-width >= 32")
    try:
        sheet = contact_sheet(
            root, args.scene, levels, args.columns, args.tile_width, not args.no_boxes
        )
    except PreviewError as err:
        raise UsageError(str(err)) from None
    out = Path(args.out) if args.out else root / "preview.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    sheet.save(out)
    print(f"wrote {out}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``seahaze`` command."""
    parser = argparse.ArgumentParser(
        prog="seahaze",
        description="Physically based maritime haze datasets with exact visibility labels.",
    )
    parser.add_argument("--version", action="version", version=f"seahaze {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    render = sub.add_parser(
        "render",
        help="render scenes into a dataset folder",
        description="Render scene YAML files: clean image, hazy levels, distance, labels.",
    )
    render.add_argument(
        "scenes", nargs="*", metavar="SCENE.yaml", help=f"scene files (default: {DEFAULT_SCENE})"
    )
    render.add_argument(
        "--vis",
        metavar="SEL",
        help="levels: A..B (graded levels in [A,B]), A..B:N (N log-spaced), or 300,1000,2500; "
        "default the scene's haze.levels",
    )
    render.add_argument(
        "--out",
        default=str(DEFAULT_OUT),
        metavar="DIR",
        help=f"dataset folder (default: {DEFAULT_OUT})",
    )
    render.add_argument(
        "--spp", type=int, metavar="N", help="samples per pixel (default: the scene's render.spp)"
    )
    render.add_argument(
        "--res",
        metavar="WxH",
        help="image size in pixels, e.g. 160x90 (default: the scene's camera.resolution)",
    )
    render.add_argument(
        "--seed", type=int, metavar="S", help="master seed (default: the scene's render.seed)"
    )
    render.add_argument(
        "--mode",
        choices=["reference", "asm"],
        help="hazy-level renderer (default: the scene's render.mode)",
    )
    render.add_argument(
        "--variant",
        metavar="NAME",
        help="Mitsuba variant: auto, llvm_ad_rgb, cuda_ad_rgb, scalar_rgb, ...",
    )
    render.add_argument("--quiet", action="store_true", help="print only the final summary")
    render.set_defaults(func=cmd_render)

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
        "--levels", metavar="L1,L2", help="levels to show, e.g. clean,v0300,v1000 (default: all)"
    )
    preview.add_argument("--columns", type=int, default=3, help="tiles per row (default 3)")
    preview.add_argument(
        "--tile-width", type=int, default=640, help="width of one tile in pixels (default 640)"
    )
    preview.add_argument("--no-boxes", action="store_true", help="do not draw the label boxes")
    preview.add_argument("--out", metavar="PNG", help="output file (default: DIR/preview.png)")
    preview.set_defaults(func=cmd_preview)

    classes = sub.add_parser("classes", help="list the vessel classes and their YOLO ids")
    classes.set_defaults(func=cmd_classes)

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


if __name__ == "__main__":
    sys.exit(main())
