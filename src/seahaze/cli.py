"""The ``seahaze`` command line. It only parses arguments and calls the library.

Exit codes: 0 success, 1 a scene failed, 2 bad input or refused (arguments, scene files, a
locked folder, a changed config), 3 a write error stopped the batch (disk full, I/O error),
130 interrupted. After 1, 3 or 130, rerunning the same command renders only what is missing.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

from . import __version__
from .metric import cli as metric_cli
from .spec import RENDER_MODES
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


def _scene_paths(items: list[str]) -> list[str]:
    """Scene files from the command line: files as given, folders expanded to their *.yaml."""
    paths: list[str] = []
    for item in items:
        folder = Path(item)
        if folder.is_dir():
            found = sorted(
                (p for p in folder.iterdir() if p.suffix in (".yaml", ".yml") and p.is_file()),
                key=lambda p: p.name,
            )
            if not found:
                raise UsageError(f"{item}: the folder holds no scene files (*.yaml, *.yml)")
            paths += [str(p) for p in found]
        else:
            paths.append(item)
    return paths


def _check_batch_args(args: argparse.Namespace) -> None:
    """Reject batch flags that do not fit together, before any scene file is read."""
    if args.count is not None and args.count < 1:
        raise UsageError(f"--scenes {args.count}: must be >= 1")
    if args.workers is not None and args.workers < 1:
        raise UsageError(f"--workers {args.workers}: must be >= 1")
    if args.executor == "dask":
        if not args.scheduler:
            raise UsageError(
                "--executor dask needs --scheduler ADDRESS, e.g. tcp://10.0.0.5:8786 "
                "(see docs/batches.md)"
            )
        if args.workers is not None:
            raise UsageError(
                "--workers is for --executor local; a Dask cluster's size is its workers"
            )
    elif args.scheduler:
        raise UsageError("--scheduler needs --executor dask")


def cmd_render(args: argparse.Namespace) -> int:
    """Render scenes (or a batch of scene variants) into a dataset folder."""
    from .batch import BatchOptions, BatchRefusedError, Reporter, plan_scenes, run_batch
    from .pipeline import DatasetError
    from .render.variant import VariantError, select_variant
    from .spec import OverrideError, with_overrides

    _check_batch_args(args)
    paths = _scene_paths(args.scenes or [str(DEFAULT_SCENE)])
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
    try:
        plan = plan_scenes(scenes, args.count)
    except DatasetError as err:
        raise UsageError(str(err)) from None
    if args.executor == "local":
        # A variant that cannot run here is bad input, not a failure of every scene. (Dask
        # workers choose theirs: the coordinator may be a login node without Mitsuba's LLVM.)
        try:
            for variant in sorted({s.render.variant for s, _ in scenes}):
                select_variant(variant)
        except VariantError as err:
            raise UsageError(str(err)) from None
    out = Path(args.out)
    try:
        reporter = Reporter(quiet=args.quiet, log=Path(args.log) if args.log else None)
    except OSError as err:
        raise UsageError(f"--log {args.log}: cannot open it ({err.strerror})") from None
    options = BatchOptions(
        workers=args.workers or 1,
        executor=args.executor,
        scheduler=args.scheduler,
        force=args.force,
    )
    try:
        report = run_batch(plan, out, options, reporter)
    except BatchRefusedError as err:
        # main() prints a one-line message after "seahaze: error:", a multi-line one as is.
        text = str(err)
        raise UsageError(text if "\n" not in text else f"seahaze: error: {text}") from None
    except OSError as err:
        print(f"seahaze: error: cannot write to {out}: {err}", file=sys.stderr)
        return 3
    finally:
        reporter.close()
    if report.outcome == "complete" and report.rendered == 0:
        print(
            f"nothing to render: all {report.planned} scene(s) in {out.resolve()} are done "
            "(delete the folder to render them again)"
        )
        return 0
    before = f", {report.done_before} already done" if report.done_before else ""
    failed = f", {len(report.failed)} failed" if report.failed else ""
    rate = report.images / report.seconds if report.seconds > 0 else 0.0
    print(
        f"wrote {report.rendered} scene(s), {report.images} images to {out.resolve()} in "
        f"{report.seconds:.1f} s ({rate:.2f} images/s){before}{failed}; "
        f"{report.done} of {report.planned} scenes done"
    )
    if report.message:
        print(f"seahaze: error: {report.message}", file=sys.stderr)
    return report.exit_code


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


DEFAULT_VERIFY_OUT = Path("out/verify")


def cmd_verify(args: argparse.Namespace) -> int:
    """Measure the visibility of a rendering mode on black calibration targets.

    Exit code 0 when every level is within the tolerance, 1 when one is not, 2 on bad input.
    """
    from . import verify
    from .render.variant import VariantError
    from .spec import SceneSpec

    levels = _parse_vis(args.vis) or [verify.DEFAULT_VISIBILITY_M]
    resolution = _parse_res(args.resolution) if args.resolution else verify.DEFAULT_RESOLUTION
    say = (
        (lambda _msg: None)
        if args.quiet
        else (lambda msg: print(f"[seahaze verify] {msg}", file=sys.stderr, flush=True))
    )
    if args.scene:
        base, _name = _load_scenes([args.scene])[0]
    elif DEFAULT_SCENE.exists():
        base, _name = _load_scenes([str(DEFAULT_SCENE)])[0]
    else:
        say(f"{DEFAULT_SCENE} not found: using the built-in default sun, sky and haze")
        base = SceneSpec()
    measurements: dict[str, verify.LevelMeasurement] = {}
    try:
        report = verify.run_verify(
            base,
            levels,
            mode=args.mode,
            spp=args.spp,
            resolution=resolution,
            batches=args.batches,
            tolerance=args.tolerance,
            seed=args.seed,
            variant=args.variant,
            target_width_deg=args.target_width,
            progress=say,
            keep=measurements,
        )
    except (verify.VerifyInputError, VariantError, ValueError) as err:
        raise UsageError(str(err)) from None
    print(verify.format_report(report))
    for path in verify.write_outputs(report, Path(args.out), measurements):
        print(f"wrote {path}")
    return 0 if report.passed else 1


def _add_verify_parser(sub: argparse._SubParsersAction) -> None:
    from typing import get_args

    from . import verify
    from .spec import RenderSpec

    modes = list(get_args(RenderSpec.model_fields["mode"].annotation))
    parser = sub.add_parser(
        "verify",
        help="measure the visibility a rendering mode produces on black calibration targets",
        description="Render a calibration scene (the scene's sun, sky and haze; a flat sea; "
        "thin black targets from 0.05 V to 1.5 V against the horizon), measure each target's "
        "contrast, fit the visibility and compare it with the label. Writes a table to stdout "
        "and report.json, contrast.png and strips.png to --out. Exit code 0: every level "
        "within --tolerance; 1: a level outside it; 2: bad input.",
    )
    parser.add_argument(
        "scene",
        nargs="?",
        metavar="SCENE.yaml",
        help=f"scene whose sun, sky, haze and camera height are used (default: {DEFAULT_SCENE} "
        "if present, else the built-in defaults)",
    )
    parser.add_argument(
        "--vis",
        metavar="SEL",
        help="levels as for 'render --vis': A..B, A..B:N or 300,1000,2500 (default: "
        f"{verify.DEFAULT_VISIBILITY_M:g})",
    )
    parser.add_argument(
        "--mode",
        choices=modes,
        default="reference",
        help="hazy-level renderer to verify (default: reference)",
    )
    parser.add_argument(
        "--spp",
        type=int,
        default=verify.DEFAULT_SPP,
        metavar="N",
        help=f"samples per pixel in all, split evenly over the batches (default: "
        f"{verify.DEFAULT_SPP})",
    )
    parser.add_argument(
        "--resolution",
        "--res",
        metavar="WxH",
        help="size of the calibration view in pixels; it spans 24° x (24° H/W) around the "
        "horizon (default: {}x{})".format(*verify.DEFAULT_RESOLUTION),
    )
    parser.add_argument(
        "--batches",
        type=int,
        default=verify.DEFAULT_BATCHES,
        metavar="B",
        help="independent render batches (seeds) that measure the noise, >= 2 (default: "
        f"{verify.DEFAULT_BATCHES})",
    )
    parser.add_argument(
        "--tolerance",
        type=float,
        default=verify.DEFAULT_TOLERANCE,
        metavar="F",
        help="largest accepted relative error of the measured visibility, e.g. 0.05 for 5 %% "
        f"(default: {verify.DEFAULT_TOLERANCE:g})",
    )
    parser.add_argument(
        "--target-width",
        type=float,
        default=verify.TARGET_WIDTH_DEG,
        metavar="DEG",
        help="angular width of the targets; wider ones read darker (the target-size effect, "
        f"docs/physics.md) (default: {verify.TARGET_WIDTH_DEG:g})",
    )
    parser.add_argument(
        "--out",
        default=str(DEFAULT_VERIFY_OUT),
        metavar="DIR",
        help=f"folder for report.json and the plots (default: {DEFAULT_VERIFY_OUT})",
    )
    parser.add_argument(
        "--seed", type=int, metavar="S", help="master seed (default: the scene's render.seed)"
    )
    parser.add_argument(
        "--variant",
        metavar="NAME",
        help="Mitsuba variant: auto, llvm_ad_rgb, cuda_ad_rgb, scalar_rgb, ...",
    )
    parser.add_argument("--quiet", action="store_true", help="no progress messages on stderr")
    parser.set_defaults(func=cmd_verify)


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
        "scenes",
        nargs="*",
        metavar="SCENE.yaml",
        help=f"scene files or folders of them (*.yaml) (default: {DEFAULT_SCENE})",
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
        "--seed",
        type=int,
        metavar="S",
        help="master seed; with --scenes, the seed every scene's seed derives from "
        "(default: the scene's render.seed)",
    )
    render.add_argument(
        "--mode",
        choices=list(RENDER_MODES),
        help="hazy-level renderer (default: the scene's render.mode)",
    )
    render.add_argument(
        "--variant",
        metavar="NAME",
        help="Mitsuba variant: auto, llvm_ad_rgb, cuda_ad_rgb, scalar_rgb, ...",
    )
    render.add_argument(
        "--scenes",
        dest="count",
        type=int,
        metavar="N",
        help="render N scenes per scene file, named <scene>_00000 ...; scene i draws camera "
        "heading, sun, sea and vessel layout from the file's 'variation:' ranges with a seed "
        "derived from (--seed, scene name, i) (default: one scene per file, as written)",
    )
    render.add_argument(
        "--workers",
        type=int,
        metavar="K",
        help="render K scenes at once in local worker processes (default 1: in this process)",
    )
    render.add_argument(
        "--executor",
        choices=["local", "dask"],
        default="local",
        help="where scenes render: 'local' (this machine, --workers) or 'dask' (tasks on the "
        "Dask cluster at --scheduler; the output folder must be shared with its workers)",
    )
    render.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="address of a running Dask scheduler, e.g. tcp://10.0.0.5:8786 (--executor dask)",
    )
    render.add_argument(
        "--force",
        action="store_true",
        help="accept a config that differs from the one the --out folder was made with: "
        "re-render what changed, delete scenes and levels no longer configured",
    )
    render.add_argument(
        "--log",
        metavar="FILE.jsonl",
        help="append one JSON line per event (start, scene done with timings, scene failed, "
        "end) to FILE, for batch systems",
    )
    render.add_argument(
        "--quiet",
        action="store_true",
        help="no progress bar or messages, only warnings and the final summary",
    )
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

    _add_verify_parser(sub)
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
