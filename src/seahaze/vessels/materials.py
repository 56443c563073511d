"""Paint and surface materials for procedural vessels.

Colours are stored as **linear-sRGB diffuse albedo** in [0, 1] because that is what a
physically based renderer multiplies with irradiance; the palettes below are written in
familiar 8-bit sRGB (what paint charts and photographs give) and converted once with the
IEC 61966-2-1 transfer function.

Albedo caveat: real white marine paint reflects roughly 80 % of visible light and black
hull paint 3-5 %, so the palettes never reach 0 or 1 in linear space. Roughness is the
microfacet roughness of a plastic / painted-steel BSDF (0 = mirror, 1 = chalky).

Sailcloth is the one translucent material: a sail is a single sheet, and a sail with the sun
behind it glows with the light it lets through (a photograph's backlit sail is bright, not a
dark shape). Its :attr:`Material.transmittance` is :data:`SAILCLOTH_TRANSMITTANCE`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

__all__ = [
    "ANTIFOULING_REDS",
    "BUOY_COLOURS",
    "CONTAINER_COLOURS",
    "DECK_PAINTS",
    "FUNNEL_PAINTS",
    "HULL_PAINTS_CARGO",
    "HULL_PAINTS_SMALL",
    "MACHINERY_PAINTS",
    "SAILCLOTH_TRANSMITTANCE",
    "SAIL_CLOTH",
    "SUPERSTRUCTURE_WHITES",
    "WINDOW_GLASS",
    "Material",
    "material_from_srgb8",
    "pick_material",
    "srgb_to_linear",
]


@dataclass(frozen=True)
class Material:
    """Diffuse albedo (linear sRGB, each channel in [0, 1]) and roughness of one surface, and
    the share of its diffuse light a thin sheet of it passes to its other side
    (``transmittance``, 0-1; 0: opaque paint, the surface of a closed body; above 0: a single
    sheet, lit from either side)."""

    name: str
    rgb: tuple[float, float, float]
    roughness: float = 0.5
    transmittance: float = 0.0

    def __post_init__(self) -> None:
        if len(self.rgb) != 3 or not all(0.0 <= c <= 1.0 for c in self.rgb):
            raise ValueError(
                f"material {self.name!r}: rgb must be 3 values in [0, 1], got {self.rgb}"
            )
        if not 0.0 <= self.roughness <= 1.0:
            raise ValueError(f"material {self.name!r}: roughness must be in [0, 1]")
        if not 0.0 <= self.transmittance <= 1.0:
            raise ValueError(f"material {self.name!r}: transmittance must be in [0, 1]")


def srgb_to_linear(srgb: Sequence[float] | np.ndarray) -> np.ndarray:
    """Convert non-linear sRGB in [0, 1] to linear sRGB (IEC 61966-2-1 piecewise curve)."""
    c = np.clip(np.asarray(srgb, dtype=np.float64), 0.0, 1.0)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def material_from_srgb8(
    name: str, srgb8: Sequence[int], roughness: float = 0.5, transmittance: float = 0.0
) -> Material:
    """Build a :class:`Material` from an 8-bit sRGB triple such as ``(200, 30, 30)``."""
    lin = srgb_to_linear(np.asarray(srgb8[:3], dtype=np.float64) / 255.0)
    rgb = (float(lin[0]), float(lin[1]), float(lin[2]))
    return Material(name, rgb, float(roughness), float(transmittance))


def pick_material(
    palette: Sequence[Material], rng: np.random.Generator, jitter: float = 0.06
) -> Material:
    """Choose one palette entry and vary its albedo by up to ±``jitter`` (relative).

    The jitter stands in for fading, dirt and different paint batches, so two ships of the
    same owner colour are not pixel-identical.
    """
    base = palette[int(rng.integers(len(palette)))]
    scale = 1.0 + rng.uniform(-jitter, jitter, size=3)
    rgb = np.clip(np.asarray(base.rgb) * scale, 0.0, 1.0)
    return replace(base, rgb=(float(rgb[0]), float(rgb[1]), float(rgb[2])))


def _palette(
    prefix: str,
    entries: dict[str, tuple[int, int, int]],
    roughness: float,
    transmittance: float = 0.0,
) -> tuple[Material, ...]:
    return tuple(
        material_from_srgb8(f"{prefix}_{key}", rgb, roughness, transmittance)
        for key, rgb in entries.items()
    )


# Hull topside paints of merchant ships (common owner colours: black, dark blue, red-brown,
# dark green, grey, orange). Semi-gloss paint, moderately weathered.
HULL_PAINTS_CARGO = _palette(
    "hull",
    {
        "black": (28, 28, 30),
        "navy": (25, 42, 82),
        "blue": (30, 70, 130),
        "red_brown": (120, 35, 30),
        "dark_green": (30, 75, 50),
        "grey": (110, 115, 120),
        "orange": (190, 80, 30),
        "light_blue": (70, 120, 170),
    },
    roughness=0.45,
)

# Small craft: mostly white gel-coat, some coloured hulls.
HULL_PAINTS_SMALL = _palette(
    "hull",
    {
        "white": (225, 225, 222),
        "off_white": (210, 205, 195),
        "navy": (25, 42, 82),
        "red": (170, 30, 30),
        "blue": (40, 90, 160),
        "green": (30, 100, 60),
        "grey": (130, 135, 140),
        "black": (28, 28, 30),
    },
    roughness=0.35,
)

# Antifouling / boot-top below the load line: the "red bottom" visible on ships in ballast.
ANTIFOULING_REDS = _palette(
    "antifouling",
    {"red": (150, 40, 35), "dark_red": (110, 30, 30), "black": (35, 35, 35)},
    roughness=0.6,
)

SUPERSTRUCTURE_WHITES = _palette(
    "superstructure",
    {"white": (230, 230, 228), "cream": (225, 218, 200), "light_grey": (200, 202, 205)},
    roughness=0.4,
)

DECK_PAINTS = _palette(
    "deck",
    {"green": (60, 95, 70), "red_brown": (120, 50, 40), "grey": (100, 100, 100)},
    roughness=0.7,
)

FUNNEL_PAINTS = _palette(
    "funnel",
    {
        "black": (30, 30, 30),
        "blue": (40, 80, 150),
        "red": (170, 40, 35),
        "yellow": (210, 170, 40),
        "white": (225, 225, 222),
        "orange": (200, 100, 30),
    },
    roughness=0.45,
)

MACHINERY_PAINTS = _palette(
    "machinery",
    {
        "yellow": (215, 175, 45),
        "white": (220, 220, 215),
        "grey": (140, 140, 140),
        "orange": (200, 100, 30),
    },
    roughness=0.5,
)

# ISO 668 boxes in typical line liveries (Maersk light blue, MSC yellow, Evergreen green,
# Hapag-Lloyd orange, CMA CGM navy, ONE magenta, COSCO blue, Triton/Textainer grey, rust
# red, white reefers).
CONTAINER_COLOURS = _palette(
    "container",
    {
        "light_blue": (110, 150, 180),
        "yellow": (205, 170, 50),
        "green": (40, 110, 70),
        "orange": (210, 100, 35),
        "navy": (30, 50, 100),
        "magenta": (170, 40, 110),
        "blue": (40, 90, 160),
        "grey": (140, 140, 140),
        "rust": (140, 55, 35),
        "white": (220, 220, 215),
    },
    roughness=0.65,
)

# Bridge and saloon glazing: dark, fairly smooth (a real glass BSDF is not worth it at a few
# pixels; a dark low-roughness plastic gives the typical dark window band).
WINDOW_GLASS = (material_from_srgb8("window", (22, 28, 36), 0.15),)

SAILCLOTH_TRANSMITTANCE = 0.3
"""Share of the diffuse light falling on one side of a sail that leaves the other side. Woven
polyester (Dacron) cruising sailcloth is visibly translucent: the sun behind a sail shows as
a glow through it. No measured transmittance of sailcloth was found to cite; 0.3 is a visual
choice that makes a backlit white sail read as a bright shape against the sea, as in
photographs (docs/vessels.md)."""

# The sailcloth colours are the cloth's whole diffuse albedo, what it reflects and what it
# lets through together: polyester absorbs little, so a white sail scatters some 95 % of the
# light, (1 - SAILCLOTH_TRANSMITTANCE) of it back to the lit side.
SAIL_CLOTH = _palette(
    "sail",
    {"white": (250, 250, 246), "cream": (245, 237, 214), "grey": (205, 205, 200)},
    roughness=0.85,
    transmittance=SAILCLOTH_TRANSMITTANCE,
)

# IALA signal colours (IALA Recommendation E-108 surface colours, approximated in sRGB).
BUOY_COLOURS: dict[str, Material] = {
    name: material_from_srgb8(f"buoy_{name}", rgb, 0.5)
    for name, rgb in {
        "red": (190, 30, 35),
        "green": (20, 120, 60),
        "yellow": (235, 190, 20),
        "black": (25, 25, 25),
        "white": (230, 230, 228),
    }.items()
}
