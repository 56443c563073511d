"""The foam streaks' coverage as a Mitsuba texture, read at every shading point of the sea.

:class:`seahaze.ocean.streaks.FoamStreaks` is the numpy definition; this is the same formula in
the render kernel (the lattice hash of :mod:`seahaze.render.field_medium`, float32 positions),
evaluated at the hit's world ``(x, y)``. The sea's BSDF blends a Lambertian streak foam over
its water and whitecaps by it (:func:`seahaze.render.scene.sea_surface_bsdf`). The wind's
direction, the streaks' drift, the share of lines present and the seed are kernel parameters:
every scene with streaks runs one kernel. An interaction with no shape (a BSDF sampled on its
own, as the photon tracer's sea samples are) reads 0, as the sea's other textures do; the
tables take the streaks' mean coverage instead (:func:`seahaze.ocean.streaks.with_streaks`).

``tests/test_streaks.py`` holds it to the numpy definition within 1e-4.

Import this module only once a Mitsuba variant is set.
"""

from __future__ import annotations

import math
from typing import Any

import drjit as dr
import mitsuba as mi

from ..ocean.streaks import (
    BRIGHTNESS,
    EDGE_WANDER_M,
    EDGE_WANDER_SCALE_M,
    END_WANDER_M,
    END_WANDER_SCALE_M,
    FIBRE_WANDER_M,
    FIBRE_WANDER_SCALE_M,
    FINE_LACE_M,
    FINE_LACE_SHARE,
    JITTER,
    LACE_CONTRAST,
    LACE_M,
    MEANDER_LENGTH_M,
    MEANDER_M,
    SEGMENT_FADE,
    SEGMENT_LENGTH_M,
    SPACING_M,
    WIDTH_M,
    FoamStreaks,
    line_share,
)
from .field_medium import lattice_value, planar_value_noise

PLUGIN = "seahaze_foam_streaks"
"""Mitsuba plugin name of the streak texture."""

_REGISTERED: set[str] = set()
"""Variants the plugin is registered with."""


def streak_texture(streaks: FoamStreaks) -> Any:
    """A loaded texture of ``streaks``' coverage (module docstring)."""
    variant = mi.variant()
    if variant not in _REGISTERED:
        cls = _streak_class()
        mi.register_texture(PLUGIN, lambda props: cls(props))
        _REGISTERED.add(variant)
    texture = mi.load_dict({"type": PLUGIN})
    texture.set_streaks(streaks)
    return texture


def streak_fraction(streaks: Any, x: Any, y: Any) -> Any:
    """:meth:`FoamStreaks.fraction` in the kernel at world ``(x, y)`` (``mi.Float``), with the
    texture's kernel parameters ``streaks`` (``cos``, ``sin`` of the direction, ``drift``,
    ``share``, ``seed``)."""
    u = x * streaks.cos + y * streaks.sin - streaks.drift
    across = y * streaks.cos - x * streaks.sin

    def wander(scale: tuple[float, float], salt: int) -> Any:
        return planar_value_noise(
            u * (1.0 / scale[0]), across * (1.0 / scale[1]), streaks.seed + salt
        )

    v = across + MEANDER_M * _noise_1d(u * (1.0 / MEANDER_LENGTH_M), mi.Float(0.0), streaks.seed)
    v = v + EDGE_WANDER_M * wander(EDGE_WANDER_SCALE_M, 4)
    u_ends = u + END_WANDER_M * wander(END_WANDER_SCALE_M, 6)
    cell = dr.floor(v * (1.0 / SPACING_M))
    total = mi.Float(0.0)
    for offset in (-1.0, 0.0, 1.0):
        k = cell + offset
        centre = (k + 0.5 + JITTER * (_hash_01(k, 1, streaks.seed) - 0.5)) * SPACING_M
        width = WIDTH_M * (0.5 + _hash_01(k, 2, streaks.seed))
        offset_v = (v - centre) / width
        profile = dr.exp(-(offset_v * offset_v))
        segment = _noise_1d(u_ends * (1.0 / SEGMENT_LENGTH_M), k, streaks.seed + 1)
        along = dr.clip(segment * (1.0 / SEGMENT_FADE) + 0.5, 0.0, 1.0)
        present = _hash_01(k, 3, streaks.seed) < streaks.share
        density = BRIGHTNESS[0] + BRIGHTNESS[1] * _hash_01(k, 4, streaks.seed)
        total = dr.maximum(total, dr.select(present, density * profile * along, 0.0))
    fibre_v = across + FIBRE_WANDER_M * wander(FIBRE_WANDER_SCALE_M, 3)
    coarse = planar_value_noise(
        u * (1.0 / LACE_M[0]), fibre_v * (1.0 / LACE_M[1]), streaks.seed + 2
    )
    fine = planar_value_noise(
        u * (1.0 / FINE_LACE_M[0]), fibre_v * (1.0 / FINE_LACE_M[1]), streaks.seed + 5
    )
    lace = (1.0 - FINE_LACE_SHARE) * coarse + FINE_LACE_SHARE * fine
    return total * 0.5 * (1.0 + dr.clip(LACE_CONTRAST * lace, -1.0, 1.0))


def _hash_01(k: Any, channel: int, seed: Any) -> Any:
    line = mi.Int64(k)
    value = lattice_value(line, mi.Int64(channel), mi.Int64(0), seed, mi.Float)
    return 0.5 * (value + 1.0)


def _noise_1d(t: Any, k: Any, seed: Any) -> Any:
    base = dr.floor(t)
    f = t - base
    fade = f * f * f * (f * (f * 6.0 - 15.0) + 10.0)
    i, line, zero = mi.Int64(base), mi.Int64(k), mi.Int64(0)
    a = lattice_value(i, line, zero, seed, mi.Float)
    b = lattice_value(i + 1, line, zero, seed, mi.Float)
    return a + fade * (b - a)


def _streak_class() -> type:
    class FoamStreakTexture(mi.Texture):
        """The streaks' coverage at the hit (module docstring)."""

        def set_streaks(self, streaks: FoamStreaks) -> None:
            az = math.radians(streaks.toward_deg)
            self.cos = dr.opaque(mi.Float, math.cos(az))
            self.sin = dr.opaque(mi.Float, math.sin(az))
            self.share = dr.opaque(mi.Float, line_share(streaks.wind_speed))
            self.seed = dr.opaque(mi.UInt64, streaks.noise_seed)
            self.drift = dr.opaque(mi.Float, streaks.drift_m)
            self.coverage = streaks.coverage

        def eval_1(self, si: Any, active: Any = True) -> Any:
            valid = active & (dr.reinterpret_array(mi.UInt32, si.shape) != 0)
            return dr.select(valid, streak_fraction(self, si.p.x, si.p.y), 0.0)

        def eval(self, si: Any, active: Any = True) -> Any:
            return mi.Color3f(self.eval_1(si, active))

        def mean(self) -> float:
            return self.coverage

        def to_string(self) -> str:
            return "FoamStreakTexture[]"

    return FoamStreakTexture
