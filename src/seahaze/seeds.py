"""Every random seed of seahaze, derived from one master seed through named streams.

A scene has one master seed (``render.seed``; a batch derives each scene's from ``--seed``).
Everything random — the wave phases, the vessel layout, the vessel models, the Monte Carlo
noise of each render pass, the scenes of a batch and their variations — draws from its own
stream of :class:`numpy.random.SeedSequence` ``[master, stream, ...]``, so adding a stream or
a draw in one never shifts the numbers of another. The stream numbers below are part of the
output contract: changing one changes the bytes of every dataset rendered with it.
"""

from __future__ import annotations

import hashlib
import zlib
from enum import IntEnum

import numpy as np

MAX_SEED = 2**31 - 1
"""Largest seed Mitsuba and the scene schema accept (``render.seed``, ``mi.render(seed=)``)."""


class Stream(IntEnum):
    """Streams of the master seed; each value is fixed forever (see the module docstring)."""

    # Geometry (seahaze.world)
    SEA = 1
    """Wave phases of the sea surface (unless ``sea.seed`` is given)."""
    LAYOUT = 2
    """Where the sampled vessels go (unless ``vessels.sample.seed`` is given)."""
    VESSELS = 3
    """Proportions, parts and paint of the procedural vessel models."""
    MOTION = 4
    """A sequence's encounter geometry and the courses of sampled vessels that must give way."""
    # Batches (seahaze.batch)
    BATCH = 11
    """Scene seeds of a batch, from (master seed, template name, scene index)."""
    VARIATION = 12
    """Per scene, one generator per varied quantity of the ``variation:`` ranges."""
    # Images (seahaze.imaging)
    DITHER = 13
    """The dither of each PNG, per scene and level (``render.dither``)."""
    # The haze (seahaze.haze_field)
    HAZE_PATCHES = 14
    """The lattice values of the haze's patches (``haze.patches``)."""
    # The camera model (seahaze.camera_model)
    CAMERA_NOISE = 15
    """The sensor noise of a scene's PNGs, one realisation for its clean image and every level
    (``render.camera_model``)."""
    # The sky (seahaze.clouds)
    CLOUDS = 16
    """The cloud layer of a broken sky (unless ``sky.clouds.seed`` is given)."""


class RenderPass(IntEnum):
    """Render passes of one scene: each draws its Monte Carlo noise from its own seed."""

    CLEAN = 0
    REFERENCE_LEVEL = 1
    AIRLIGHT = 2
    PHYSICAL_LEVEL = 3
    """Retired: the per-level physical renders before one pass served every level."""
    PHYSICAL_PASS = 4
    """The physical mode's one pass: the clean image and every level, common random numbers."""
    DENOISE_FEATURES = 5
    """The albedo and normal pass that guides the denoiser (``render.denoise: on``)."""
    VESSEL_LIGHT = 6
    """The physical mode's second pass: the light vessels send into the haze before them."""
    CONVERGED_REFERENCE = 99
    """Batches of the converged benchmark references (scripts/make_references.py)."""
    VERIFY = 0x7E51F
    """Batches of the ``seahaze verify`` calibration renders."""


def stream_seed(master: int, stream: int, explicit: int | None = None) -> int:
    """The 32-bit seed of one stream of ``master``; ``explicit`` (a seed the user gave) wins."""
    if explicit is not None:
        return explicit
    return int(np.random.SeedSequence([master, int(stream)]).generate_state(1)[0])


def stream_rng(master: int, stream: int, explicit: int | None = None) -> np.random.Generator:
    """A numpy generator for one stream of ``master`` (see :func:`stream_seed`)."""
    return np.random.default_rng(stream_seed(master, stream, explicit))


def render_seed(master: int, render_pass: int, *parts: int) -> int:
    """The 31-bit Mitsuba seed of a render pass (and its level, batch, ... ``parts``)."""
    entropy = [master, int(render_pass), *map(int, parts)]
    state = np.random.SeedSequence(entropy).generate_state(1, np.uint32)
    return int(state[0]) & MAX_SEED


def scene_seed(master: int, template: str, index: int) -> int:
    """Seed of scene ``index`` of batch template ``template``.

    The template name enters through CRC-32 (stable across runs, unlike ``hash``), so two
    templates of one batch draw independent scenes and adding a template leaves the others'
    scenes unchanged.
    """
    name_key = zlib.crc32(template.encode("utf-8"))
    state = np.random.SeedSequence([master, int(Stream.BATCH), name_key, index]).generate_state(1)
    return int(state[0]) & MAX_SEED


def variation_rng(scene: int, quantity: int) -> np.random.Generator:
    """The generator of varied quantity number ``quantity`` of the scene with seed ``scene``."""
    return np.random.default_rng(np.random.SeedSequence([scene, int(Stream.VARIATION), quantity]))


def dither_seed(master: int, scene: str, level: str) -> np.random.SeedSequence:
    """The seed of the dither of image ``level`` (``clean``, ``v0300``, ...) of scene ``scene``
    whose master seed is ``master``.

    Both names enter whole, through SHA-256 (stable across runs, unlike ``hash``; CRC-32 would
    give two of a batch's 10^5 scene names the same key), so every image of a dataset, and the
    same image under another seed, gets its own noise.
    """
    return np.random.SeedSequence([master, int(Stream.DITHER), _name_key(scene), _name_key(level)])


def camera_noise_seed(master: int, scene: str) -> np.random.SeedSequence:
    """The seed of the sensor noise of scene ``scene`` whose master seed is ``master``
    (``render.camera_model``).

    The level is not part of it: the clean image and every hazy level of a scene share one
    noise realisation per pixel (common random numbers), so the difference between two levels'
    PNGs is the haze's, not the noise's. The scene's name enters as in :func:`dither_seed`, so
    every scene (and every frame of a sequence) gets its own noise.
    """
    return np.random.SeedSequence([master, int(Stream.CAMERA_NOISE), _name_key(scene)])


def _name_key(name: str) -> int:
    """A 128-bit key of ``name``: the first 16 bytes of its SHA-256, little-endian."""
    return int.from_bytes(hashlib.sha256(name.encode("utf-8")).digest()[:16], "little")
