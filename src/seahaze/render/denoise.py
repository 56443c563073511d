"""The optional denoiser: Intel Open Image Denoise (OIDN) through the ``pyoidn`` package.

OIDN's ``RT`` filter (Áfra, Intel Open Image Denoise, https://www.openimagedenoise.org) takes
the noisy HDR colour with two feature images that guide it and carry no Monte Carlo noise of
the lighting: the first surface's albedo and its shading normal, written here by Mitsuba's
``aov`` integrator at :data:`AUX_SPP` samples per pixel (antialiased, so ``cleanAux`` is off
and OIDN prefilters them). The sky has albedo and normal 0, the vessels and the sea theirs, so
an edge between a faint vessel and the haze behind it is an edge in the features too.

The same buffers and filter settings are applied to the clean image and to every hazy level
(the haze changes the colour, not the surfaces). Radiance is scaled by the scene's exposure
before the filter (display white = 1, where OIDN's HDR training data puts it) and back after,
so the denoised image is linear radiance again. ``pyoidn`` is optional (``pip install
seahaze[denoise]``): :func:`available` tells whether it imports.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .scene import LoadedScene

DENOISE_MODES = ("off", "on")
"""Values of ``render.denoise`` (and ``--denoise``)."""
AUX_SPP = 16
"""Samples per pixel of the albedo and normal pass (the edges of vessels are antialiased)."""
QUALITY = "high"
"""OIDN's filter quality (``high``: its largest network; the slowest, the least blur)."""


class DenoiserUnavailableError(RuntimeError):
    """Denoising was asked for but ``pyoidn`` does not import."""


def available() -> bool:
    """Whether the ``pyoidn`` package (and the OIDN library it ships) can be imported."""
    try:
        import pyoidn  # noqa: F401
    except (ImportError, OSError):
        return False
    return True


def library_version() -> str:
    """``pyoidn``'s version string (it is OIDN's version plus a binding number), e.g.
    ``2.5.1.0``; raises :class:`DenoiserUnavailableError` without it."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("pyoidn")
    except PackageNotFoundError as err:
        raise DenoiserUnavailableError(_MISSING) from err


_MISSING = (
    "denoising needs the optional package pyoidn (Intel Open Image Denoise): "
    "pip install 'seahaze[denoise]'"
)


@dataclass(frozen=True)
class FeatureBuffers:
    """OIDN's guide images of one camera view."""

    albedo: np.ndarray
    """(H, W, 3) float32 albedo of the first surface, 0..1 (0 for the sky)."""
    normal: np.ndarray
    """(H, W, 3) float32 world-frame shading normal of the first surface, -1..1 (0 for sky)."""


def feature_buffers(loaded: LoadedScene, seed: int, spp: int = AUX_SPP) -> FeatureBuffers:
    """Albedo and normal of ``loaded``'s camera by Mitsuba's ``aov`` integrator."""
    import mitsuba as mi

    integrator = mi.load_dict({"type": "aov", "aovs": "albedo:albedo,nn:sh_normal"})
    # The scene without the haze box where there is one: the box's null surface is no feature.
    scene = loaded.clean_scene if loaded.clean_scene is not None else loaded.scene
    loaded.bind_paint()
    image = np.array(mi.render(scene, spp=spp, seed=seed, integrator=integrator), np.float32)
    albedo = np.clip(np.nan_to_num(image[..., 0:3]), 0.0, 1.0)
    normal = np.clip(np.nan_to_num(image[..., 3:6]), -1.0, 1.0)
    return FeatureBuffers(np.ascontiguousarray(albedo), np.ascontiguousarray(normal))


def denoise(radiance: np.ndarray, features: FeatureBuffers, exposure: float) -> np.ndarray:
    """OIDN's ``RT`` filter on linear ``radiance`` (H, W, 3), guided by ``features``;
    ``exposure`` (the scene's, linear) only sets the filter's working range. Returns linear
    radiance (H, W, 3) float32, non-negative."""
    try:
        import pyoidn
    except (ImportError, OSError) as err:
        raise DenoiserUnavailableError(_MISSING) from err
    scale = float(exposure) if np.isfinite(exposure) and exposure > 0 else 1.0
    color = np.ascontiguousarray(np.nan_to_num(radiance, nan=0.0) * scale, dtype=np.float32)
    out: Any = pyoidn.denoise(
        color, features.albedo, features.normal, hdr=True, clean_aux=False, quality=QUALITY
    )
    return np.maximum(np.asarray(out, dtype=np.float32) / np.float32(scale), 0.0)
