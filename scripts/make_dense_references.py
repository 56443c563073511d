"""Converged ``reference`` images of the dense-haze scene at 50, 100 and 200 m (issue #19).

The scene (``scenes/dense.yaml``: the default sea, sun, sky and haze without vessels, camera
15 m inside the 300 m layer, 48×27) is rendered by Mitsuba ``volpath`` — the ``reference``
mode, with its unbounded default depth (``render.max_depth: -1``, Russian roulette only) and a
haze box at least three layer thicknesses wide — in independent batches of ``--batch-spp``
samples per pixel, each with its own seed. After every batch the running sums and the batch
means of every region are saved (``--work``), so an interrupted run resumes where it stopped.

A level is finished when, in every region (top, middle and bottom thirds of the frame; sky and
sea), the standard error of the region's mean radiance — from the spread of the batch means —
is below ``--target`` (0.5 %) of that mean, after at least ``--min-batches`` batches; or when
``--max-minutes`` of its own rendering have passed (the achieved error is recorded, never
hidden).

Outputs in ``assets/references/dense/``: ``<level>.exr`` (R, G, B mean linear radiance; Y_SE the
per-pixel standard error of the luminance), ``references.json`` (scene and geometry digests,
variant, Mitsuba version, depth, box width, and per level the spp, batches, seconds and every
region's mean and relative standard error) and ``SHA256SUMS``.
``scripts/compare_dense.py`` checks the digests before it uses them.

Usage: nice -n 19 python scripts/make_dense_references.py [--levels 50,100,200]
"""

from __future__ import annotations

import argparse
import hashlib
import json
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "dense.yaml"
OUT = ROOT / "assets" / "references" / "dense"
LEVELS = (50.0, 100.0, 200.0)


def scene_digest() -> str:
    """SHA-256 of the scene file: the references are valid only for this text."""
    return hashlib.sha256(SCENE.read_bytes()).hexdigest()


def region_masks(distance_m: np.ndarray) -> dict[str, np.ndarray]:
    """Boolean (H, W) masks of the compared regions: thirds of the rows, sky and sea."""
    height = distance_m.shape[0]
    rows = np.arange(height)[:, None] * np.ones_like(distance_m, dtype=bool)
    cut = [0, height // 3, 2 * height // 3, height]
    masks = {
        name: (rows >= cut[i]) & (rows < cut[i + 1])
        for i, name in enumerate(("top", "middle", "bottom"))
    }
    masks["sky"] = ~np.isfinite(distance_m)
    masks["sea"] = np.isfinite(distance_m)
    return {k: v for k, v in masks.items() if v.any()}


def region_means(rgb: np.ndarray, masks: dict[str, np.ndarray]) -> dict[str, float]:
    """Mean luminance of ``rgb`` (H, W, 3) over every region."""
    from seahaze.imaging import luminance

    y = luminance(rgb)
    return {name: float(y[mask].mean()) for name, mask in masks.items()}


class Batches:
    """Running sums of independent batch images and every batch's region means."""

    def __init__(self, shape: tuple[int, int]):
        self.sum = np.zeros((*shape, 3))
        self.y_sum = np.zeros(shape)
        self.y_sq = np.zeros(shape)
        self.regions: list[dict[str, float]] = []
        self.seconds = 0.0

    @property
    def n(self) -> int:
        return len(self.regions)

    def add(self, rgb: np.ndarray, masks: dict[str, np.ndarray], seconds: float) -> None:
        from seahaze.imaging import luminance

        y = luminance(rgb)
        self.sum += rgb
        self.y_sum += y
        self.y_sq += y * y
        self.regions.append(region_means(rgb, masks))
        self.seconds += seconds

    def mean(self) -> np.ndarray:
        return self.sum / max(self.n, 1)

    def y_stderr(self) -> np.ndarray:
        n = max(self.n, 2)
        var = np.maximum(self.y_sq / n - (self.y_sum / n) ** 2, 0.0) * n / (n - 1)
        return np.sqrt(var / n)

    def region_stats(self) -> dict[str, dict[str, float]]:
        """Per region: mean and relative standard error of the mean (from the batch means)."""
        out = {}
        for name in self.regions[0] if self.regions else ():
            values = np.array([r[name] for r in self.regions])
            mean = float(values.mean())
            se = float(values.std(ddof=1) / np.sqrt(len(values))) if len(values) > 1 else np.inf
            out[name] = {"mean": mean, "relative_stderr": se / mean if mean > 0 else np.inf}
        return out

    def worst_error(self) -> float:
        stats = self.region_stats()
        return max((s["relative_stderr"] for s in stats.values()), default=np.inf)

    def save(self, path: Path) -> None:
        tmp = path.with_name(path.stem + ".tmp.npz")
        names = sorted(self.regions[0]) if self.regions else []
        np.savez(
            tmp,
            sum=self.sum,
            y_sum=self.y_sum,
            y_sq=self.y_sq,
            names=np.array(names),
            regions=np.array([[r[k] for k in names] for r in self.regions]),
            seconds=self.seconds,
        )
        tmp.replace(path)

    @classmethod
    def load(cls, path: Path, shape: tuple[int, int]) -> Batches:
        acc = cls(shape)
        if path.exists():
            data = np.load(path)
            acc.sum, acc.y_sum, acc.y_sq = data["sum"], data["y_sum"], data["y_sq"]
            names = [str(k) for k in data["names"]]
            rows = data["regions"]
            acc.regions = [dict(zip(names, map(float, row), strict=True)) for row in rows]
            acc.seconds = float(data["seconds"])
        return acc


def options() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add = parser.add_argument
    add("--levels", default=",".join(f"{v:g}" for v in LEVELS), help="visibilities (m)")
    add("--batch-spp", type=int, default=256, help="samples per pixel of one batch")
    add("--target", type=float, default=0.005, help="relative stderr of every region's mean")
    add("--min-batches", type=int, default=8, help="batches at least, per level")
    add("--max-minutes", type=float, default=90.0, help="rendering time at most, per level")
    add("--work", type=Path, default=ROOT / "out" / "dense-references-work")
    return parser.parse_args()


def record(meta: dict, session, spec, masks: dict[str, np.ndarray], args) -> dict:
    """``references.json`` for this scene and geometry (emptied when either changed)."""
    import mitsuba as mi

    digest, world = scene_digest(), session.geometry.digest()
    if meta.get("scene_sha256") != digest or meta.get("world_sha256") != world:
        meta = {}  # the scene or its geometry changed: earlier references are stale
    return {
        **meta,
        "scene": str(SCENE.relative_to(ROOT)),
        "scene_sha256": digest,
        "world_sha256": world,
        "variant": session.variant,
        "mitsuba": mi.__version__,
        "integrator": "volpath",
        "max_depth": spec.render.max_depth,
        "box_half_width_m": session.loaded.box_half_width_m,
        "batch_spp": args.batch_spp,
        "target_region_relative_stderr": args.target,
        "regions": {k: int(v.sum()) for k, v in masks.items()},
        "levels": meta.get("levels", {}),
    }


def converge(session, spec, level: float, masks, args, work: Path) -> Batches:
    """Render batches of one level until every region's mean is converged (or time is up)."""
    from seahaze.render import passes
    from seahaze.seeds import RenderPass, render_seed
    from seahaze.visibility import channel_extinction

    haze, camera = spec.haze, session.camera
    acc = Batches.load(work, (camera.height, camera.width))
    sigma = channel_extinction(level, haze.threshold, haze.extinction_spectrum)
    session.loaded.set_haze(sigma, haze.albedo, haze.g)
    index = LEVELS.index(level) if level in LEVELS else int(level)
    while not (acc.n >= args.min_batches and acc.worst_error() <= args.target):
        if acc.seconds > 60.0 * args.max_minutes:
            break
        seed = render_seed(spec.render.seed, RenderPass.CONVERGED_REFERENCE, index, acc.n)
        start = time.perf_counter()
        rgb = passes.render_radiance(session.loaded, args.batch_spp, seed).astype(np.float64)
        acc.add(rgb, masks, time.perf_counter() - start)
        acc.save(work)
        print(
            f"{work.stem[:5]}: batch {acc.n}, spp {acc.n * args.batch_spp}, worst region "
            f"stderr {acc.worst_error():.4f}, {acc.seconds:.0f} s",
            flush=True,
        )
    return acc


def main() -> None:
    args = options()
    from seahaze.fileio import write_exr
    from seahaze.render.engine import open_session
    from seahaze.sceneio import load_scene
    from seahaze.spec import with_overrides
    from seahaze.visibility import level_name

    spec, name = load_scene(SCENE)
    session = open_session(with_overrides(spec, mode="reference", levels=list(LEVELS)))
    spec = session.spec
    masks = region_masks(session.pixels.distance_m)
    args.work.mkdir(parents=True, exist_ok=True)
    OUT.mkdir(parents=True, exist_ok=True)
    meta_path = OUT / "references.json"
    meta = json.loads(meta_path.read_text()) if meta_path.exists() else {}
    meta = record(meta, session, spec, masks, args)
    tag = f"{meta['scene_sha256'][:12]}-{meta['world_sha256'][:12]}-{args.batch_spp}"
    for level in (float(v) for v in args.levels.split(",")):
        key = level_name(level)
        acc = converge(session, spec, level, masks, args, args.work / f"{key}-{tag}.npz")
        mean = acc.mean()
        channels = {"R": mean[..., 0], "G": mean[..., 1], "B": mean[..., 2]}
        write_exr(OUT / f"{key}.exr", {**channels, "Y_SE": acc.y_stderr()})
        meta["levels"][key] = {
            "visibility_m": level,
            "batches": acc.n,
            "spp": acc.n * args.batch_spp,
            "render_seconds": round(acc.seconds, 1),
            "converged": acc.worst_error() <= args.target,
            "regions": acc.region_stats(),
        }
        meta_path.write_text(json.dumps(meta, indent=2, sort_keys=True) + "\n")
        exrs = sorted(OUT.glob("*.exr"))
        lines = [f"{hashlib.sha256(p.read_bytes()).hexdigest()}  {p.name}" for p in exrs]
        (OUT / "SHA256SUMS").write_text("\n".join(lines) + "\n")
        print(f"{key}: wrote {OUT / (key + '.exr')}", flush=True)
    print(f"scene {name}: done", flush=True)


if __name__ == "__main__":
    main()
