"""Write one rendered scene into a dataset folder: images, labels, distance and metadata.

Images are the linear radiance exposed with the scene's one exposure and sRGB-encoded
(:mod:`seahaze.imaging`), dithered as ``meta``'s ``render`` record says (``render.dither``:
each image with its own seed, from the scene's seed, its name and the level; a record without
it, the nearest code); when the record has a ``camera_model`` (``render.camera_model``) they
are first blurred, given sensor noise and compressed as a camera would
(:mod:`seahaze.camera_model`). With ``write_exr`` the linear radiance is written too (without
the camera model), and each hazy level's per-pixel transmittance, optical depth and effective
visibility (``transmission/<level>/``, :mod:`seahaze.render.transmission`). Every level gets
the same label file: the boxes do not depend on the haze (the MSVD paper's protocol). With
``labels.write_visible`` each level also gets the labels of the vessels seen in its image
(``labels_visible/<level>/``, :mod:`seahaze.visible`).
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np

from .. import camera_model, fileio
from ..cpus import usable_cpus
from ..render.engine import RenderedLevel, SceneRender
from ..visibility import CLEAN_LEVEL
from .layout import Layout


def write_scene(layout: Layout, scene: SceneRender) -> None:
    """Write every file of ``scene`` (see :meth:`Layout.scene_files`), each atomically.

    The images are encoded and written by a few threads (PNG and EXR compression release the
    GIL; what each file costs: docs/benchmarks.md, "What do a scene's files cost to write?").
    The bytes do not depend on the order; the first failure is raised once all writes ended.
    """
    name = scene.name
    images = [(CLEAN_LEVEL, scene.clean_image, scene.clean)]
    images += [(level.name, level.image, level.radiance) for level in scene.levels]
    with ThreadPoolExecutor(max_workers=min(4, usable_cpus())) as pool:
        writes = [pool.submit(_write_image, layout, *image, scene) for image in images]
    for write in writes:  # the pool has waited for every write
        write.result()
    for level, _, _ in images:
        fileio.write_text(layout.label(level, name), scene.label_text)
    for level, text in (scene.visible_labels or {}).items():
        fileio.write_text(layout.visible_label(level, name), text)
    fileio.write_exr(layout.depth(name), {"Z": scene.geometry.distance_m})
    if scene.write_exr:
        for level in scene.levels:
            if level.transmission is not None:
                fileio.write_exr(layout.transmission(level.name, name), _channels(level))
    fileio.write_json(layout.meta(name), scene.meta)


def _write_image(
    layout: Layout, level: str, shown: np.ndarray, radiance: np.ndarray, scene: SceneRender
) -> None:
    """The PNG of ``shown`` (denoised when denoising is on) and the EXR of the rendered,
    undenoised ``radiance``."""
    render = scene.meta.get("render", {})
    image8 = camera_model.png_pixels(
        shown, scene.exposure, render, scene.name, level, scene.motion_px
    )
    fileio.write_png(layout.image(level, scene.name), image8)
    if scene.write_exr:
        fileio.write_rgb_exr(layout.exr(level, scene.name), radiance)


def _channels(level: RenderedLevel) -> dict[str, np.ndarray]:
    """A level's transmission maps as the channels of its EXR (``TRANSMISSION_CHANNELS``)."""
    maps = level.transmission
    assert maps is not None
    channels = {f"T.{c}": maps.transmittance[..., i] for i, c in enumerate("RGB")}
    channels |= {f"tau.{c}": maps.optical_depth[..., i] for i, c in enumerate("RGB")}
    channels["V_eff"] = maps.visibility_eff_m
    return channels
