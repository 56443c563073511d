"""Render scenes into a dataset folder: spec → geometry → Mitsuba passes → writers.

One Mitsuba scene is loaded per scene; the clean pass, the geometry pass and every hazy level
reuse it, only the medium changes (DESIGN.md §4).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import imaging, labels
from .camera import Camera
from .dataset import (
    CLEAN,
    Layout,
    write_json,
    write_text,
)
from .geometry import SceneGeometry, build_geometry
from .render import passes
from .render.mitsuba_scene import build_scene
from .render.variant import select_variant
from .spec import SceneSpec
from .visibility import channel_extinction, extinction_coefficient, level_name

Progress = Callable[[str], None]


@dataclass
class SceneResult:
    """What rendering one scene produced, with wall-clock seconds per pass."""

    name: str
    variant: str
    exposure: float
    boxes: list[labels.Box]
    timings: dict[str, float] = field(default_factory=dict)
    meta: dict[str, Any] = field(default_factory=dict)


def _quiet(_: str) -> None:
    pass


class _Timer:
    def __init__(self, timings: dict[str, float], key: str):
        self.timings, self.key = timings, key

    def __enter__(self) -> None:
        self.start = time.perf_counter()

    def __exit__(self, *exc: object) -> None:
        self.timings[self.key] = time.perf_counter() - self.start


HORIZON_SKY_BAND_DEG = 2.0
"""Sky pixels this close above the horizon define the horizon luminance for contrasts."""


def horizon_luminance(
    radiance: np.ndarray, distance: np.ndarray, elevation: np.ndarray
) -> float | None:
    """Mean luminance of the sky just above the horizon, or None where none is in view.

    The mean, not the median: Monte Carlo noise is skewed (rare bright samples), so the median
    of a noisy band reads low and would bias every apparent contrast.
    """
    band = np.isinf(distance) & (elevation >= 0.0) & (elevation < HORIZON_SKY_BAND_DEG)
    return float(np.mean(imaging.luminance(radiance[band]))) if band.sum() >= 4 else None


def apparent_contrasts(
    radiance: np.ndarray, instance: np.ndarray, n_vessels: int, horizon: float | None
) -> list[float | None]:
    """Per vessel ``(L_vessel - L_horizon) / L_horizon`` over its visible pixels (Koschmieder C)."""
    y = imaging.luminance(radiance)
    out: list[float | None] = []
    for vessel in range(n_vessels):
        mask = instance == vessel
        ok = horizon is not None and horizon > 0 and mask.any()
        out.append(float((y[mask].mean() - horizon) / horizon) if ok else None)
    return out


def _vessel_meta(
    geometry: SceneGeometry,
    boxes: list[labels.Box],
    footprint_px: np.ndarray,
    level_contrasts: dict[str, tuple[float, list[float | None]]],
) -> list[dict[str, Any]]:
    by_vessel = {b.vessel: b for b in boxes}
    out = []
    for v in geometry.vessels:
        p = v.placement
        box = by_vessel.get(v.index)
        distance = float(np.hypot(p.x, p.y))
        out.append(
            {
                "index": v.index,
                "class": v.kind,
                "class_id": v.class_id,
                "position_m": [p.x, p.y, v.waterline_z],
                "heading_deg": p.heading_deg,
                "length_m": v.length_m,
                "beam_m": v.beam_m,
                "air_draft_m": v.air_draft_m,
                "distance_m": distance,
                "bearing_deg": p.bearing_deg,
                "box_px": None if box is None else [box.x0, box.y0, box.x1, box.y1],
                "visible_pixels": 0 if box is None else box.pixels,
                "unoccluded_pixels": int(footprint_px[v.index])
                if v.index < len(footprint_px)
                else 0,
                "visible_fraction": None if box is None else box.visible_fraction,
                "levels": {
                    level: {
                        "apparent_contrast": contrasts[v.index],
                        "beyond_visibility": distance > visibility,
                    }
                    for level, (visibility, contrasts) in level_contrasts.items()
                },
            }
        )
    return out


def render_scene(
    spec: SceneSpec, name: str, root: Path, progress: Progress = _quiet
) -> SceneResult:
    """Render one scene (clean, distance, every level of ``spec.haze.levels``) into ``root``."""
    layout = Layout(root)
    timings: dict[str, float] = {}
    variant = select_variant(spec.render.variant)
    camera = Camera.from_spec(spec.camera)
    levels = list(spec.haze.levels)
    haze = spec.haze
    with _Timer(timings, "geometry_build"):
        geometry = build_geometry(spec, camera)
    with _Timer(timings, "scene_load"):
        # The physical mode computes the haze itself: no Mitsuba medium in its scene.
        loaded = build_scene(
            spec, camera, geometry, levels, haze_box=spec.render.mode != "physical"
        )
    progress(f"{name}: scene loaded ({variant}, {len(geometry.vessels)} vessels)")

    with _Timer(timings, "aov"):
        geo = passes.render_geometry(loaded)
    with _Timer(timings, "clean"):
        clean = passes.render_clean(loaded, spec.render.spp, spec.render.seed, haze.albedo, haze.g)
    progress(f"{name}: clean pass {timings['clean']:.1f} s")

    elevation = np.degrees(np.arcsin(np.clip(geo.directions[..., 2], -1.0, 1.0)))
    exposure = (
        imaging.auto_exposure(clean, geo.distance_m, elevation)
        if spec.render.exposure == "auto"
        else float(spec.render.exposure)
    )
    boxes = labels.boxes_from_instances(
        geo.instance,
        [v.class_id for v in geometry.vessels],
        geo.footprint_px,
        spec.labels.min_box_px,
        spec.labels.min_visible_fraction,
    )
    n_vessels = len(geometry.vessels)
    level_contrasts: dict[str, tuple[float, list[float | None]]] = {
        CLEAN: (
            np.inf,
            apparent_contrasts(
                clean, geo.instance, n_vessels, horizon_luminance(clean, geo.distance_m, elevation)
            ),
        )
    }
    label_text = labels.yolo_text(boxes, camera.width, camera.height)

    _write_image(layout, CLEAN, name, clean, exposure, spec.render.write_exr)
    write_text(layout.label(CLEAN, name), label_text)
    imaging.write_exr(layout.depth(name), {"Z": geo.distance_m})

    level_meta = []
    for i, v in enumerate(levels):
        sigma = channel_extinction(v, haze.threshold, haze.extinction_spectrum)
        key = level_name(v)
        with _Timer(timings, f"level_{key}"):
            level = passes.render_level(
                spec.render.mode, loaded, geo, clean, sigma, haze, spec.render, i
            )
        radiance, airlight = level.radiance, level.airlight
        _write_image(layout, key, name, radiance, exposure, spec.render.write_exr)
        write_text(layout.label(key, name), label_text)
        horizon = horizon_luminance(radiance, geo.distance_m, elevation)
        if horizon is None and airlight is not None:
            horizon = float(imaging.luminance(airlight.rgb))
        level_contrasts[key] = (v, apparent_contrasts(radiance, geo.instance, n_vessels, horizon))
        entry: dict[str, Any] = {
            "name": key,
            "visibility_m": v,
            "sigma_per_m": extinction_coefficient(v, haze.threshold),
            "sigma_rgb_per_m": sigma.tolist(),
            "horizon_luminance": horizon,
        }
        if airlight is not None:
            entry["airlight_rgb"] = airlight.rgb.tolist()
            entry["airlight_stderr_rgb"] = airlight.stderr.tolist()
        level_meta.append(entry)
        progress(f"{name}: {key} ({spec.render.mode}) {timings[f'level_{key}']:.1f} s")

    meta = {
        "scene": name,
        "variant": variant,
        "mode": spec.render.mode,
        "exposure": exposure,
        "camera": {**spec.camera.model_dump(mode="json"), "position_m": camera.origin.tolist()},
        "sun": spec.sun.model_dump(mode="json"),
        "sky": spec.sky.model_dump(mode="json"),
        "sea": {
            **spec.sea.model_dump(mode="json"),
            "roughness_used": geometry.sea_roughness,
            "triangles": len(geometry.sea.faces),
        },
        "haze": {
            **haze.model_dump(mode="json", exclude={"levels"}),
            "box_half_width_m": loaded.box_half_width_m,
        },
        "levels": level_meta,
        "vessels": _vessel_meta(geometry, boxes, geo.footprint_px, level_contrasts),
    }
    write_json(layout.meta(name), meta)
    return SceneResult(name, variant, exposure, boxes, timings, meta)


def _write_image(
    layout: Layout, level: str, scene: str, radiance: np.ndarray, exposure: float, exr: bool
) -> None:
    imaging.write_png(layout.image(level, scene), imaging.to_srgb8(radiance, exposure))
    if exr:
        imaging.write_rgb_exr(layout.exr(level, scene), radiance)


class DatasetError(ValueError):
    """Scenes that cannot form one dataset (e.g. different levels); the message is for the user."""


def render_dataset(
    scenes: Sequence[tuple[SceneSpec, str]], root: Path, progress: Progress = _quiet
) -> list[SceneResult]:
    """Render scenes into one dataset folder with ``data.yaml``, ``dataset.json`` and COCO files.

    One scene per ``(spec, name)``, rendered in this process by :mod:`seahaze.batch` (locked,
    resumable: scenes the folder already holds with the same config are skipped). Returns the
    results of the scenes rendered by this call. Raises :class:`DatasetError` for scenes that
    cannot form one dataset, :class:`seahaze.batch.BatchRefusedError` for a locked folder or
    one made with another config, and :class:`seahaze.batch.BatchFailedError` when a scene
    failed or a write error stopped the batch.
    """
    from .batch import BatchFailedError, Reporter, plan_scenes, run_batch

    reporter = Reporter(quiet=True, notes=progress)
    report = run_batch(plan_scenes(scenes), root, reporter=reporter)
    if report.outcome == "interrupted":
        raise KeyboardInterrupt
    if report.outcome != "complete":
        raise BatchFailedError(report)
    return report.results
