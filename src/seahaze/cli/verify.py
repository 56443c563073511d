"""``seahaze verify``: measure the visibility a rendering mode produces."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..spec import RENDER_MODES
from .common import DEFAULT_SCENE, UsageError, load_scenes, parse_res, parse_vis
from .limits import MAX_SAMPLES_PER_IMAGE
from .render import parse_threads_flag

DEFAULT_VERIFY_OUT = Path("out/verify")


def cmd_verify(args: argparse.Namespace) -> int:
    """Measure the visibility of a rendering mode on black calibration targets.

    Exit code 0 when every level is within the tolerance, 1 when one is not, 2 on bad input.
    """
    from .. import verify
    from ..cpus import render_threads
    from ..interrupts import stoppable
    from ..render.variant import VariantError
    from ..spec import SceneSpec

    out = Path(args.out)
    blocking = next((p for p in (out, *out.parents) if p.exists()), None)
    if blocking is not None and not blocking.is_dir():
        raise UsageError(f"--out {out}: {blocking} is a file, not a folder")
    threads = parse_threads_flag(args.threads)
    levels = parse_vis(args.vis) or [verify.DEFAULT_VISIBILITY_M]
    resolution = verify.DEFAULT_RESOLUTION
    if args.resolution is not None:
        resolution = parse_res(args.resolution)
    per_batch = args.spp // max(args.batches, 1)
    if resolution[0] * resolution[1] * per_batch > MAX_SAMPLES_PER_IMAGE:
        raise UsageError(
            f"--resolution {resolution[0]}x{resolution[1]} at {per_batch} spp per batch is more "
            "than 2^32 samples per image, Mitsuba's limit: lower --spp or raise --batches"
        )
    say = (
        (lambda _msg: None)
        if args.quiet
        else (lambda msg: print(f"[seahaze verify] {msg}", file=sys.stderr, flush=True))
    )
    if args.scene:
        base, _name = load_scenes([args.scene])[0]
    elif DEFAULT_SCENE.exists():
        base, _name = load_scenes([str(DEFAULT_SCENE)])[0]
    else:
        say(f"{DEFAULT_SCENE} not found: using the built-in default sun, sky and haze")
        base = SceneSpec()
    if args.denoise == "on":
        from ..render import denoise

        if not denoise.available():  # as `render` says it, before any work (not exit 1 after)
            raise UsageError(
                "--denoise on needs the optional package pyoidn: pip install 'seahaze[denoise]'"
            )
    measurements: dict[str, verify.LevelMeasurement] = {}
    try:
        settings = verify.VerifySettings(
            mode=args.mode,
            spp=args.spp,
            resolution=resolution,
            batches=args.batches,
            tolerance=args.tolerance,
            seed=args.seed,
            variant=args.variant,
            target_width_deg=args.target_width,
            denoise=args.denoise == "on",
        )
        with stoppable(), render_threads(threads):
            report = verify.run_verify(base, levels, settings, progress=say, keep=measurements)
    except (verify.VerifyInputError, VariantError, ValueError) as err:
        raise UsageError(str(err)) from None
    print(verify.format_report(report))
    try:
        written = verify.write_outputs(report, out, measurements)
    except OSError as err:
        print(f"seahaze: error: cannot write to {out}: {err}", file=sys.stderr)
        return 3
    for path in written:
        print(f"wrote {path}")
    return 0 if report.passed else 1


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The ``verify`` subcommand and its flags."""
    from .. import verify

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
        choices=list(RENDER_MODES),
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
        help="Mitsuba variant: auto (cuda_ad_rgb where a GPU works, else llvm_ad_rgb), "
        "cuda_ad_rgb or llvm_ad_rgb",
    )
    parser.add_argument(
        "--denoise",
        choices=["off", "on"],
        default="off",
        help="measure denoised images, as render.denoise on writes them (needs pyoidn)",
    )
    parser.add_argument(
        "--threads",
        metavar="N",
        help="render threads (1..4 per CPU of the machine; default: the CPUs this process may "
        "use, its affinity and cgroup CPU quota)",
    )
    parser.add_argument("--quiet", action="store_true", help="no progress messages on stderr")
    parser.set_defaults(func=cmd_verify)
