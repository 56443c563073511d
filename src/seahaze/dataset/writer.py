"""Write one rendered scene into a dataset folder: images, labels, distance and metadata.

Images are the linear radiance exposed with the scene's one exposure and sRGB-encoded
(:mod:`seahaze.imaging`); with ``write_exr`` the linear radiance is written too. Every level
gets the same label file: the boxes do not depend on the haze.
"""

from __future__ import annotations

import numpy as np

from .. import fileio, imaging
from ..render.engine import SceneRender
from ..visibility import CLEAN_LEVEL
from .layout import Layout


def write_scene(layout: Layout, scene: SceneRender) -> None:
    """Write every file of ``scene`` (see :meth:`Layout.scene_files`), each atomically."""
    name = scene.name
    _write_image(layout, CLEAN_LEVEL, scene, scene.clean_image, scene.clean)
    fileio.write_text(layout.label(CLEAN_LEVEL, name), scene.label_text)
    fileio.write_exr(layout.depth(name), {"Z": scene.geometry.distance_m})
    for level in scene.levels:
        _write_image(layout, level.name, scene, level.image, level.radiance)
        fileio.write_text(layout.label(level.name, name), scene.label_text)
    fileio.write_json(layout.meta(name), scene.meta)


def _write_image(
    layout: Layout, level: str, scene: SceneRender, shown: np.ndarray, radiance: np.ndarray
) -> None:
    """The PNG of ``shown`` (denoised when denoising is on) and the EXR of the rendered,
    undenoised ``radiance``."""
    fileio.write_png(layout.image(level, scene.name), imaging.to_srgb8(shown, scene.exposure))
    if scene.write_exr:
        fileio.write_rgb_exr(layout.exr(level, scene.name), radiance)
