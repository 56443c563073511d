"""``seahaze render``: scene files (or a batch of their variants) into a dataset folder."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from ..cpus import usable_cpus
from ..dataset.splits import DEFAULT_SPLIT_SOURCE
from ..spec import RENDER_MODES
from . import limits
from .common import DEFAULT_SCENE, UsageError, load_scenes, parse_res, parse_vis

DEFAULT_OUT = Path("out/dataset")


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


def parse_threads_flag(text: str | None) -> int | None:
    """``--threads`` as a thread count (None when not given); a bad value is bad input."""
    from ..cpus import parse_threads

    if text is None:
        return None
    try:
        return parse_threads(text)
    except ValueError as err:
        raise UsageError(f"--threads {text!r}: {err}") from None


def _check_batch_args(args: argparse.Namespace) -> None:
    """Reject batch flags that do not fit together, before any scene file is read."""
    from ..render.variant import SUPPORTED_VARIANTS

    if args.count is not None and not 1 <= args.count <= limits.MAX_SCENES:
        raise UsageError(
            f"--scenes {args.count}: must be within 1..{limits.MAX_SCENES:,} (a batch folder "
            "holds at most that many scenes; split larger datasets over several --out folders)"
        )
    most = limits.max_workers()
    if args.workers is not None and not 1 <= args.workers <= most:
        raise UsageError(
            f"--workers {args.workers}: must be within 1..{most} (this machine has "
            f"{usable_cpus()} core(s); each worker renders with cores/workers threads)"
        )
    if args.variant is not None and args.variant not in ("auto", *SUPPORTED_VARIANTS):
        raise UsageError(
            f"--variant {args.variant!r}: choose one of auto, {', '.join(SUPPORTED_VARIANTS)} "
            "(seahaze traces images as vectorised JIT arrays in RGB: scalar_*, *_mono and "
            "*_spectral* variants cannot render it)"
        )
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
        if args.threads is not None:
            raise UsageError(
                "--threads is for --executor local; a Dask worker renders with its own threads"
            )
        if args.dask_wait is not None and not 0.0 < args.dask_wait <= 86400.0:
            raise UsageError(
                f"--dask-wait {args.dask_wait:g}: must be within 0 (excluded)..86400 s"
            )
    elif args.scheduler:
        raise UsageError("--scheduler needs --executor dask")
    elif args.dask_wait is not None:
        raise UsageError("--dask-wait needs --executor dask")


def _check_out(out: Path) -> Any:
    """The --out folder's state; a file, or a folder seahaze did not make, is bad input."""
    from ..batch.errors import BatchRefusedError
    from ..batch.folder import inspect_folder

    try:
        return inspect_folder(out.resolve())
    except BatchRefusedError as err:
        raise UsageError(str(err)) from None
    except OSError as err:
        raise UsageError(f"--out {out}: cannot read it ({err.strerror or err})") from None


def _check_layouts(plan: Any, files: dict[str, str]) -> None:
    """Every scene's vessel layout can be built (its own seed and variation): a vessel over the
    camera or an impossible ``vessels.sample`` is bad input, not a failed scene hours later.
    ``files``: each template's scene file, where the line of its ``vessels:`` block is shown
    (a varied scene has no line of its own)."""
    from ..sceneio import layout_problems

    problems = []
    for job in plan.jobs:
        if job.frame:  # a sequence's frames share its spec: its first frame checks them all
            continue
        where = _block_location(files.get(job.template), "vessels")
        problems += [
            f"{where}{'.'.join(str(p) for p in loc)}: scene {job.name}: {message}"
            for loc, message in layout_problems(job.spec)[:1]
        ]
        if len(problems) == 5:
            problems.append("… (more scenes not checked)")
            break
    if len(problems) == 1:
        raise UsageError(problems[0])
    if problems:
        raise UsageError("\n".join(f"seahaze: error: {line}" for line in problems))


def _block_location(file: str | None, key: str) -> str:
    """``FILE:LINE: `` of the top-level ``key`` of a scene file already validated (line 1
    where the file has no such key), or nothing for a scene without a file."""
    if file is None:
        return ""
    from ..yamlguard import YamlLimitError, compose_limited, read_limited_text

    line = 1
    try:
        _, root = compose_limited(read_limited_text(Path(file), 1 << 20, "a scene file", ""))
    except YamlLimitError:
        root = None
    for name, _value in getattr(root, "value", None) or []:
        if getattr(name, "value", None) == key:
            line = name.start_mark.line + 1
    return f"{file}:{line}: "


def _warn_below_validated_range(plan: Any) -> None:
    """A warning for levels thinner than the mode's validated range (docs/physics.md): its
    own where a job's haze varies across the sea (patches, a bank: ranges of their own)."""
    for mode in sorted({job.spec.render.mode for job in plan.jobs}):
        specs = [job.spec for job in plan.jobs if job.spec.render.mode == mode]
        patches = any(s.haze.patches is not None for s in specs)
        bank = any(s.haze.bank is not None for s in specs)
        # Patches with a bank are the least validated (the tables' diffuse field), then patches.
        if patches and bank:
            ranges = limits.PATCHES_WITH_BANK_VALIDATED_FROM_M
        elif patches:
            ranges = limits.PATCHES_VALIDATED_FROM_M
        elif bank:
            ranges = limits.BANK_VALIDATED_FROM_M
        else:
            ranges = limits.VALIDATED_FROM_M
        floor = ranges.get(mode)
        below = sorted(v for v in plan.levels if floor is not None and v < floor)
        if below:
            where = "in patchy haze " if patches else "in a fog bank " if bank else ""
            # Patches with a bank keep the tables' diffuse field (neither tracer covers both).
            why = ", where dense patches may render too bright" if patches and bank else ""
            within = "3.5 %" if patches and bank else "3 %"
            print(
                f"seahaze: warning: {where}the {mode} mode is validated (within {within} of "
                f"converged references) down to V = {floor:g} m; "
                f"{', '.join(f'{v:g}' for v in below)} m lie below it{why} (docs/physics.md); "
                "--mode reference is unbiased there but slow",
                file=sys.stderr,
            )


def _say_split(plan: Any, source: str, quiet: bool) -> None:
    """The split the batch uses, in one line: a warning (shown with --quiet too) when the batch
    is too small for a split the user asked for, else a note. A batch too small for the
    default split (one scene: the quickstart's render) gets the note only: nobody asked."""
    if plan.assignment is None:
        if not quiet:
            print(
                f"[seahaze] split: none ({source}): train and val of data.yaml are every clean "
                "image",
                file=sys.stderr,
            )
        return
    warning = plan.assignment.warning()
    if warning is not None and (source != DEFAULT_SPLIT_SOURCE or len(plan.jobs) > 1):
        print(f"seahaze: warning: split ({source}): {warning}", file=sys.stderr)
    elif warning is not None and not quiet:
        print(f"[seahaze] split ({source}): {warning}", file=sys.stderr)
    elif not quiet:
        print(f"[seahaze] split ({source}): {plan.assignment.describe()}", file=sys.stderr)


def _estimate(
    scenes: list[tuple[Any, str]], args: argparse.Namespace, folder: Any, make_plan: Any
) -> tuple[Any, limits.Estimate, str | None]:
    """The job's estimate and why it needs ``--yes`` (None: it does not), and the plan when
    it had to be made.

    The estimate of all ``--scenes`` of every template comes first (variation does not change
    a scene's cost), so a huge job is refused before it is planned; only a resumed folder's
    job is planned to leave out the scenes already done."""
    plan, count = None, args.count or 1
    at_once = (args.workers or 1) if args.executor == "local" else 1
    jobs = [(spec, count * limits.frames_of(spec)) for spec, _ in scenes]
    job = limits.estimate(jobs, at_once=at_once)
    reason = limits.confirmation_needed(job)
    resumed = bool((folder.manifest or {}).get("scenes"))
    if resumed and (args.estimate or (reason and not args.yes)):
        plan = make_plan()
        job = limits.estimate([(spec, 1) for spec in _todo(plan, folder)], at_once=at_once)
        reason = limits.confirmation_needed(job)
    return plan, job, reason


def _confirm(job: limits.Estimate, reason: str | None, args: argparse.Namespace) -> None:
    """Refuse a job of an hour or more, or one that needs more memory than the machine has,
    without --yes (before anything is planned)."""
    if reason and not args.yes:
        raise UsageError(
            f"{reason}: {job.describe()}. Pass --yes to start it, or lower --res, --spp, "
            "--scenes, --workers or the levels"
        )


def _announce(job: limits.Estimate, reason: str | None, args: argparse.Namespace) -> None:
    """Print the estimate of a long job, or say that kernels compile first, once every check
    passed (a refusal after it would read as if the work had started)."""
    if args.quiet or not job.scenes:
        return
    if reason or job.seconds >= limits.ANNOUNCE_SECONDS:
        print(f"seahaze: estimated {job.describe()}", file=sys.stderr)
    elif job.compile_seconds >= limits.ANNOUNCE_COMPILE_SECONDS:
        # A first render of a new size or sample count spends most of its time compiling.
        print(
            f"seahaze: compiling kernels for a new render first (about "
            f"{limits.format_duration(job.compile_seconds)}, once per size and sample count); "
            f"estimated {job.describe()}",
            file=sys.stderr,
        )


def _todo(plan: Any, folder: Any) -> list[Any]:
    """The specs of the planned scenes the folder does not hold done with the same config."""
    from ..batch.folder import comparable

    old = (folder.manifest or {}).get("scenes") or {}
    return [
        job.spec
        for job in plan.jobs
        if not (
            isinstance(old.get(job.name), dict)
            and old[job.name].get("status") == "done"
            and comparable(old[job.name]) == comparable(job.entry("done"))
        )
    ]


def cmd_render(args: argparse.Namespace) -> int:
    """Render scenes (or a batch of scene variants) into a dataset folder."""
    from ..batch import (
        BatchOptions,
        BatchRefusedError,
        DatasetError,
        Reporter,
        plan_scenes,
        run_batch,
    )
    from ..dataset.splits import SplitError, resolve_split
    from ..render.variant import VariantError, select_variant
    from ..spec import OverrideError, with_overrides

    _check_batch_args(args)
    threads = parse_threads_flag(args.threads)
    out = Path(args.out)
    folder = _check_out(out)
    paths = _scene_paths(args.scenes or [str(DEFAULT_SCENE)])
    levels = parse_vis(args.vis)
    resolution = parse_res(args.res) if args.res is not None else None
    if args.spp is not None and args.spp < 1:
        raise UsageError(f"--spp {args.spp}: must be >= 1")
    try:
        # Without --split: a folder's recorded split (resuming stays the same config), else
        # the default (docs/dataset-format.md#splits).
        split, split_from = resolve_split(args.split, folder.manifest)
    except SplitError as err:
        raise UsageError(f"--split {args.split!r}: {err}; or 'none' for no split") from None
    if args.frames is not None and not 1 <= args.frames <= limits.MAX_SCENES:
        raise UsageError(f"--frames {args.frames}: must be within 1..{limits.MAX_SCENES:,}")
    if args.fps is not None and not 0.0 < args.fps <= 120.0:
        raise UsageError(f"--fps {args.fps:g}: must be within 0 (excluded)..120 frames/s")
    scenes = []
    for spec, name in load_scenes(paths):
        try:
            spec = with_overrides(
                spec,
                spp=args.spp,
                resolution=resolution,
                seed=args.seed,
                mode=args.mode,
                variant=args.variant,
                levels=levels,
                frames=args.frames,
                fps=args.fps,
                denoise=args.denoise,
                dither=args.dither,
            )
        except OverrideError as err:
            raise UsageError(f"{name}: {err}") from None
        scenes.append((spec, name))
    if any(spec.render.denoise == "on" for spec, _ in scenes):
        from ..render import denoise

        if not denoise.available():
            raise UsageError(
                "render.denoise on (or --denoise on) needs the optional package pyoidn: "
                "pip install 'seahaze[denoise]'"
            )
    total = (args.count or 1) * sum(limits.frames_of(spec) for spec, _ in scenes)
    try:
        limits.check_hard_limits([(name, spec) for spec, name in scenes], total, args.workers)
    except limits.LimitError as err:
        raise UsageError(str(err)) from None

    def make_plan() -> Any:
        try:
            return plan_scenes(scenes, args.count, split=split)
        except DatasetError as err:
            raise UsageError(str(err)) from None

    plan, job, reason = _estimate(scenes, args, folder, make_plan)
    if args.estimate:
        print(json.dumps({**job.record(), "needs_yes": reason}))
        return 0
    _confirm(job, reason, args)
    plan = plan or make_plan()
    _check_layouts(plan, {name: path for path, (_, name) in zip(paths, scenes, strict=True)})
    _warn_below_validated_range(plan)
    _say_split(plan, split_from, args.quiet)
    if args.executor == "local":
        # A variant that cannot run here is bad input, not a failure of every scene. (Dask
        # workers choose theirs: the coordinator may be a login node without Mitsuba's LLVM.)
        try:
            for variant in sorted({s.render.variant for s, _ in scenes}):
                select_variant(variant)
        except VariantError as err:
            raise UsageError(str(err)) from None
    _announce(job, reason, args)
    try:
        reporter = Reporter(quiet=args.quiet, log=Path(args.log) if args.log else None)
    except OSError as err:
        raise UsageError(f"--log {args.log}: cannot open it ({err.strerror})") from None
    options = BatchOptions(
        workers=args.workers or 1,
        executor=args.executor,
        scheduler=args.scheduler,
        **({"dask_wait": args.dask_wait} if args.dask_wait is not None else {}),
        force=args.force,
        threads=threads,
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
    if report.rendered and args.executor == "local":
        # This machine compiled these renders' kernels: the next estimate counts no compiling.
        limits.KernelRecord.load().remember(spec for spec, _ in scenes)
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


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The ``render`` subcommand and its flags."""
    parser = sub.add_parser(
        "render",
        help="render scenes into a dataset folder",
        description="Render scene YAML files: clean image, hazy levels, distance, labels.",
    )
    parser.add_argument(
        "scenes",
        nargs="*",
        metavar="SCENE.yaml",
        help=f"scene files or folders of them (*.yaml) (default: {DEFAULT_SCENE})",
    )
    parser.add_argument(
        "--vis",
        metavar="SEL",
        help="levels: A..B (graded levels in [A,B]), A..B:N (N log-spaced), or 300,1000,2500; "
        "default the scene's haze.levels",
    )
    parser.add_argument(
        "--out",
        default=str(DEFAULT_OUT),
        metavar="DIR",
        help=f"dataset folder (default: {DEFAULT_OUT})",
    )
    parser.add_argument(
        "--spp", type=int, metavar="N", help="samples per pixel (default: the scene's render.spp)"
    )
    parser.add_argument(
        "--denoise",
        choices=["off", "on"],
        help="Intel Open Image Denoise on the PNGs of the clean image and every level (EXRs "
        "stay undenoised; needs pip install 'seahaze[denoise]'; default: the scene's "
        "render.denoise)",
    )
    parser.add_argument(
        "--dither",
        choices=["on", "off"],
        help="on: triangular noise of +-1 code before rounding the PNGs to 8 bits, so hazy "
        "skies show no bands (seeded: the same config gives the same bytes); off: the nearest "
        "code; default: the scene's render.dither (on)",
    )
    parser.add_argument(
        "--res",
        metavar="WxH",
        help="image size in pixels, e.g. 160x90 (default: the scene's camera.resolution)",
    )
    parser.add_argument(
        "--seed",
        type=int,
        metavar="S",
        help="master seed; with --scenes, the seed every scene's seed derives from "
        "(default: the scene's render.seed)",
    )
    parser.add_argument(
        "--mode",
        choices=list(RENDER_MODES),
        help="hazy-level renderer (default: the scene's render.mode)",
    )
    parser.add_argument(
        "--variant",
        metavar="NAME",
        help="Mitsuba variant: auto (cuda_ad_rgb where a GPU works, else llvm_ad_rgb), "
        "cuda_ad_rgb or llvm_ad_rgb",
    )
    parser.add_argument(
        "--frames",
        type=int,
        metavar="N",
        help="render each scene as a sequence of N frames (default: the scene's "
        "sequence.frames; a scene without 'sequence:' is one still frame)",
    )
    parser.add_argument(
        "--fps",
        type=float,
        metavar="F",
        help="frame rate of the sequences (default: the scene's sequence.fps, else 10); a "
        "still scene (no 'sequence:') needs --frames N with it",
    )
    parser.add_argument(
        "--scenes",
        dest="count",
        type=int,
        metavar="N",
        help="render N scenes per scene file, named <scene>_00000 ...; scene i draws camera "
        "heading, sun, sea and vessel layout from the file's 'variation:' ranges with a seed "
        "derived from (--seed, scene name, i) (default: one scene per file, as written)",
    )
    parser.add_argument(
        "--split",
        metavar="TRAIN,VAL,TEST",
        help="scene-disjoint train/val/test splits, e.g. 0.8,0.1,0.1: each scene's split comes "
        "from a hash of (master seed, scene name), so a scene keeps it when the batch grows; "
        "recorded in dataset.json, used by data.yaml (train.txt, val.txt, test.txt) and by "
        "'seahaze export'; 'none': no split, train and val are every clean image (default: "
        "0.8,0.1,0.1 in a new folder; an existing dataset keeps the split it was made with)",
    )
    parser.add_argument(
        "--workers",
        type=int,
        metavar="K",
        help="render K scenes at once in local worker processes (default 1: in this process)",
    )
    parser.add_argument(
        "--threads",
        metavar="N",
        help="render threads in all, shared by the --workers (1..4 per CPU of the machine; "
        "default: the CPUs this process may use, its affinity and cgroup CPU quota); fewer "
        "leave CPUs to other work, the same bytes (docs/benchmarks.md)",
    )
    parser.add_argument(
        "--executor",
        choices=["local", "dask"],
        default="local",
        help="where scenes render: 'local' (this machine, --workers) or 'dask' (tasks on the "
        "Dask cluster at --scheduler; the output folder must be shared with its workers)",
    )
    parser.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="address of a running Dask scheduler, e.g. tcp://10.0.0.5:8786 (--executor dask)",
    )
    parser.add_argument(
        "--dask-wait",
        type=float,
        metavar="S",
        help="when the Dask scheduler has no workers, wait S seconds (0 < S <= 86400) for one "
        "to join, then give up with exit 2 (default 60; reaching the scheduler itself has a "
        "15 s deadline; --executor dask)",
    )
    parser.add_argument(
        "--force",
        action="store_true",
        help="accept a config that differs from the one the --out folder was made with: "
        "re-render what changed, delete scenes and levels no longer configured",
    )
    parser.add_argument(
        "--log",
        metavar="FILE.jsonl",
        help="append one JSON line per event (start, scene done with timings, scene failed, "
        "end) to FILE, for batch systems",
    )
    parser.add_argument(
        "--quiet",
        action="store_true",
        help="no progress bar or messages, only warnings and the final summary",
    )
    parser.add_argument(
        "--yes",
        action="store_true",
        help="start a job estimated at an hour or more (or close to the machine's memory); "
        "without it such a job stops with its estimate (docs/limits.md)",
    )
    parser.add_argument(
        "--estimate",
        action="store_true",
        help="print the job's estimate as one JSON line (scenes, seconds, compile_seconds, "
        "scene_bytes, peak_bytes, needs_yes) and exit without rendering or touching --out",
    )
    parser.set_defaults(func=cmd_render)
