"""Render converged ``reference`` images of the benchmark scene (issue #5), resumably.

The benchmark scene (``scenes/benchmark.yaml``, 80×45) is rendered clean and at 300, 1000 and
4000 m with Mitsuba ``volpath`` in independent batches of ``--batch-spp`` samples per pixel, each
with its own seed. After every batch the running mean and the spread of the batch means are
saved (``--work`` folder), so an interrupted run resumes where it stopped. A level is finished
when the standard error of the mean, averaged over pixels, is below ``--target`` (1 %) of the
mean luminance (with at least ``--min-batches`` batches, so the estimate of the error is itself
sound), or when ``--max-minutes`` of its own rendering have passed (the achieved error is then
recorded, never hidden).

Outputs in ``assets/references/benchmark/``: ``<level>.exr`` with channels R, G, B (mean linear
radiance) and ``Y_SE`` (per-pixel standard error of the luminance), ``references.json`` (scene,
levels, spp, batches, achieved error, wall time, Mitsuba version, variant) and ``SHA256SUMS``.
The benchmark (``scripts/bench_modes.py``) checks the checksums, the scene file's hash and the
hash of its geometry (``SceneGeometry.digest``: a change in the ocean or vessel generators makes
the references stale even when the scene file is unchanged) before use.

Usage: nice -n 19 python scripts/make_references.py [--levels clean,300,1000,4000]
"""

from __future__ import annotations

import argparse
import hashlib
import json
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "benchmark.yaml"
OUT = ROOT / "assets" / "references" / "benchmark"
LEVELS = ("clean", "300", "1000", "4000")


def scene_digest() -> str:
    """SHA-256 of the benchmark scene file: the references are valid only for this text."""
    return hashlib.sha256(SCENE.read_bytes()).hexdigest()


def level_key(level: str) -> str:
    """File stem of a level: ``clean`` or the zero-padded visibility (``v0300``)."""
    from seahaze.visibility import level_name

    return "clean" if level == "clean" else level_name(float(level))


class Accumulator:
    """Running mean and spread (Welford) of independent batch-mean images."""

    def __init__(self, shape: tuple[int, int]):
        self.n = 0
        self.mean = np.zeros((*shape, 3))
        self.m2 = np.zeros((*shape, 3))
        self.y_mean = np.zeros(shape)
        self.y_m2 = np.zeros(shape)
        self.seconds = 0.0

    def add(self, rgb: np.ndarray, seconds: float) -> None:
        """Fold in one batch-mean image (H, W, 3)."""
        from seahaze.imaging import luminance

        self.n += 1
        self.seconds += seconds
        for value, mean, m2 in (
            (rgb, self.mean, self.m2),
            (luminance(rgb), self.y_mean, self.y_m2),
        ):
            delta = value - mean
            mean += delta / self.n
            m2 += delta * (value - mean)

    def y_stderr(self) -> np.ndarray:
        """Per-pixel standard error of the mean luminance (from the spread of the batches)."""
        return np.sqrt(self.y_m2 / max(self.n - 1, 1) / max(self.n, 1))

    def relative_error(self) -> float:
        """Mean per-pixel standard error over the mean luminance of the image."""
        return float(self.y_stderr().mean() / self.y_mean.mean())

    def save(self, path: Path) -> None:
        tmp = path.with_suffix(".tmp.npz")
        np.savez(
            tmp,
            n=self.n,
            mean=self.mean,
            m2=self.m2,
            y_mean=self.y_mean,
            y_m2=self.y_m2,
            seconds=self.seconds,
        )
        tmp.replace(path)

    @classmethod
    def load(cls, path: Path, shape: tuple[int, int]) -> Accumulator:
        acc = cls(shape)
        if path.exists():
            data = np.load(path)
            acc.n, acc.seconds = int(data["n"]), float(data["seconds"])
            acc.mean, acc.m2 = data["mean"], data["m2"]
            acc.y_mean, acc.y_m2 = data["y_mean"], data["y_m2"]
        return acc


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--levels", default=",".join(LEVELS), help="clean and/or visibilities (m)")
    parser.add_argument("--batch-spp", type=int, default=1024, help="samples per pixel per batch")
    parser.add_argument("--target", type=float, default=0.01, help="relative standard error")
    parser.add_argument("--min-batches", type=int, default=8, help="batches before stopping")
    parser.add_argument("--max-minutes", type=float, default=120.0, help="per level")
    parser.add_argument("--work", type=Path, default=ROOT / "out" / "references-work")
    args = parser.parse_args()

    import mitsuba as mi

    from seahaze.render import passes
    from seahaze.render.engine import open_session
    from seahaze.sceneio import load_scene
    from seahaze.seeds import RenderPass, render_seed
    from seahaze.spec import with_overrides
    from seahaze.visibility import channel_extinction, extinction_coefficient

    spec, name = load_scene(SCENE)
    # volpath through the haze box, sized for all benchmark levels, whichever are rendered now.
    spec = with_overrides(spec, mode="reference", levels=[float(v) for v in LEVELS[1:]])
    session = open_session(spec)
    variant, camera, loaded = session.variant, session.camera, session.loaded
    world = session.geometry.digest()
    haze = spec.haze
    args.work.mkdir(parents=True, exist_ok=True)
    OUT.mkdir(parents=True, exist_ok=True)
    shape = (camera.height, camera.width)
    digest = scene_digest()
    meta_path = OUT / "references.json"
    meta = json.loads(meta_path.read_text()) if meta_path.exists() else {}
    if meta.get("scene_sha256") not in (None, digest) or meta.get("world_sha256") != world:
        meta = {}  # the scene or its geometry changed: earlier references are stale
    meta.update(
        {
            "scene": str(SCENE.relative_to(ROOT)),
            "scene_sha256": digest,
            "world_sha256": world,
            "variant": variant,
            "mitsuba": mi.__version__,
            "integrator": "volpath",
            "max_depth": spec.render.max_depth,
            "batch_spp": args.batch_spp,
            "target_relative_stderr": args.target,
        }
    )
    meta.setdefault("levels", {})

    for level in args.levels.split(","):
        key = level_key(level)
        work = args.work / f"{key}-{digest[:12]}-{world[:12]}.npz"
        acc = Accumulator.load(work, shape)
        clean = level == "clean"
        sigma = 0.0 if clean else extinction_coefficient(float(level), haze.threshold)
        rgb = (
            0.0
            if clean
            else channel_extinction(float(level), haze.threshold, haze.extinction_spectrum)
        )
        loaded.set_haze(rgb, haze.albedo, haze.g)
        level_index = LEVELS.index(level)
        while True:
            done = acc.n >= args.min_batches and acc.relative_error() <= args.target
            if done or acc.seconds > 60.0 * args.max_minutes:
                break
            seed = render_seed(spec.render.seed, RenderPass.CONVERGED_REFERENCE, level_index, acc.n)
            start = time.perf_counter()
            rgb = passes.render_radiance(loaded, args.batch_spp, seed)
            acc.add(rgb.astype(np.float64), time.perf_counter() - start)
            acc.save(work)
            print(
                f"{key}: batch {acc.n}, spp {acc.n * args.batch_spp}, "
                f"relative stderr {acc.relative_error():.4f}, {acc.seconds:.0f} s",
                flush=True,
            )
        from seahaze.fileio import write_exr

        write_exr(
            OUT / f"{key}.exr",
            {
                "R": acc.mean[..., 0],
                "G": acc.mean[..., 1],
                "B": acc.mean[..., 2],
                "Y_SE": acc.y_stderr(),
            },
        )
        meta["levels"][key] = {
            "visibility_m": None if level == "clean" else float(level),
            "sigma_per_m": sigma,
            "batches": acc.n,
            "spp": acc.n * args.batch_spp,
            "relative_stderr": acc.relative_error(),
            "converged": acc.relative_error() <= args.target,
            "render_seconds": round(acc.seconds, 1),
        }
        meta_path.write_text(json.dumps(meta, indent=2, sort_keys=True) + "\n")
        sums = [
            f"{hashlib.sha256(p.read_bytes()).hexdigest()}  {p.name}"
            for p in sorted(OUT.glob("*.exr"))
        ]
        (OUT / "SHA256SUMS").write_text("\n".join(sums) + "\n")
        print(f"{key}: wrote {OUT / (key + '.exr')}", flush=True)
    print(f"scene {name}: done", flush=True)


if __name__ == "__main__":
    main()
