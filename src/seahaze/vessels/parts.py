"""Shared building blocks for the vessel families: hull + paint bands, deckhouses, funnels,
masts and cranes. All dimensions in metres, in the vessel frame (x forward, y port, z up,
waterline z = 0).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

from seahaze.vessels.geometry import (
    HullForm,
    box,
    concatenate,
    cylinder_between,
    loft_hull,
    prism_from_outline,
    tapered_block,
    vertical_cylinder,
)
from seahaze.vessels.materials import Material
from seahaze.vessels.model import VesselPart

__all__ = [
    "EMBED_M",
    "PartSet",
    "PrincipalDims",
    "deck_at",
    "deck_range",
    "detail_rng",
    "min_half_beam",
    "u",
]

# Sinking superstructure bodies slightly into the body below hides the seam at any view angle.
EMBED_M = 0.15


@dataclass(frozen=True)
class PrincipalDims:
    """Principal dimensions sampled by the library: overall length, beam, hull depth (keel to
    main deck at midships) and draft (waterline to keel), all in metres."""

    kind: str
    length: float
    beam: float
    depth: float
    draft: float
    wind_from_deg: float | None = None
    """Where the wind comes from, degrees off the bow (positive to port, −180..180); None:
    unknown (a sailboat then sets its sails at random)."""

    @property
    def freeboard(self) -> float:
        """Height of the main deck above the waterline at midships (m)."""
        return self.depth - self.draft


def u(rng: np.random.Generator, lo: float, hi: float) -> float:
    """One uniform draw as a plain float (keeps the builders terse and deterministic)."""
    return float(rng.uniform(lo, hi))


def detail_rng(d: PrincipalDims) -> np.random.Generator:
    """A generator for a builder's added details, seeded by the vessel's principal dimensions
    (themselves drawn from the caller's ``rng``): deterministic for a seed, and drawing nothing
    from the caller's ``rng``, so the vessels built after this one in a scene draw what they
    drew before the details existed (seeded as the tug's and fishing boat's details are in
    :mod:`seahaze.vessels.smallcraft`)."""
    dims = np.array([d.length, d.beam, d.depth, d.draft], np.float64)
    return np.random.default_rng(np.frombuffer(dims.tobytes(), np.uint32))


def deck_range(form: HullForm, x0: float, x1: float) -> tuple[float, float]:
    """Lowest and highest deck height (m) over ``[x0, x1]``: where to seat a deckhouse."""
    z = form.deck_z(np.linspace(min(x0, x1), max(x0, x1), 16))
    return float(z.min()), float(z.max())


def deck_at(form: HullForm, x: float) -> float:
    """Deck height (m) at station ``x`` (m): where a part stands on the deck there."""
    return float(form.deck_z(np.array([x]))[0])


def min_half_beam(form: HullForm, x0: float, x1: float) -> float:
    """Narrowest deck half-breadth over ``[x0, x1]`` so a block never overhangs the side."""
    return float(form.deck_half_beam(np.linspace(min(x0, x1), max(x0, x1), 16)).min())


class PartSet:
    """Collects bodies per part name; each part gets exactly one material."""

    def __init__(self) -> None:
        self._bodies: dict[str, list[trimesh.Trimesh]] = {}
        self._materials: dict[str, Material] = {}

    def add(self, name: str, mesh: trimesh.Trimesh, material: Material) -> None:
        """Add one watertight body to part ``name`` (which must keep a single material), or a
        single sheet of a translucent material (a sail)."""
        known = self._materials.setdefault(name, material)
        if known != material:
            raise ValueError(f"part {name!r} already uses material {known.name!r}")
        self._bodies.setdefault(name, []).append(mesh)

    def material_of(self, name: str) -> Material:
        """The material of part ``name`` (which must have been added)."""
        return self._materials[name]

    def to_parts(self) -> list[VesselPart]:
        """One :class:`VesselPart` per name, its bodies concatenated without merging."""
        return [
            VesselPart(name, concatenate(bodies), self._materials[name])
            for name, bodies in self._bodies.items()
        ]

    # ------------------------------------------------------------------ hull
    def add_hull(
        self,
        form: HullForm,
        hull: Material,
        *,
        bottom: Material | None = None,
        boot_top_z: float = 0.3,
        deck: Material | None = None,
    ) -> None:
        """Hull loft, optional antifouling band up to ``boot_top_z`` and optional deck plate.

        The paint band and deck plate are separate closed bodies 1-2 cm proud of the hull
        (painting faces of one watertight body per material is not possible with one material
        per part).
        """
        self.add("hull", loft_hull(form), hull)
        if bottom is not None:
            margin = 0.02 * form.draft
            interval = form.x_interval_below(boot_top_z, margin)
            if interval is not None:
                band = loft_hull(
                    form,
                    z_high=lambda x: np.full_like(x, boot_top_z),
                    inflate=min(0.02, 0.001 * form.beam),
                    x_range=interval,
                    n_stations=40,
                    n_vertical=8,
                )
                self.add("hull_bottom", band, bottom)
        if deck is not None:
            inset = -min(0.5, 0.02 * form.beam)
            plate = loft_hull(
                form,
                z_low=lambda x: form.deck_z(x) - 0.3,
                z_high=lambda x: form.deck_z(x) + 0.02,
                inflate=inset,
                x_range=(-0.49 * form.length, 0.49 * form.length),
                n_stations=40,
                n_vertical=3,
            )
            self.add("deck", plate, deck)

    # ------------------------------------------------------------ superstructure
    def add_accommodation(
        self,
        form: HullForm,
        x_aft: float,
        x_fwd: float,
        half_width: float,
        n_decks: int,
        deck_height: float,
        *,
        wing_half_width: float,
        wheelhouse_length: float,
        paint: Material,
        glass: Material,
    ) -> tuple[float, float, tuple[float, float]]:
        """Accommodation block with a full-width wheelhouse (bridge wings) on top.

        Returns the z of the house roof and of the wheelhouse roof, and the wheelhouse's aft and
        forward ends (x), in metres.
        """
        z_deck, _ = deck_range(form, x_aft, x_fwd)
        z_roof = z_deck + n_decks * deck_height
        self.add(
            "superstructure",
            tapered_block(x_aft, x_fwd, half_width, z_deck - EMBED_M, z_roof),
            paint,
        )
        # One window row per deck on the front face: reads as a lit/dark grid at short range.
        for k in range(1, n_decks):
            z0 = z_deck + k * deck_height + 0.9
            self.add(
                "windows",
                box(x_fwd - 0.3, x_fwd + 0.05, -0.8 * half_width, 0.8 * half_width, z0, z0 + 0.9),
                glass,
            )
        wh_height = deck_height * 1.05
        wh_x0 = x_fwd - wheelhouse_length
        wh_x1 = x_fwd + min(0.8, 0.2 * wheelhouse_length)
        self.add(
            "superstructure",
            tapered_block(wh_x0, wh_x1, wing_half_width, z_roof - EMBED_M, z_roof + wh_height),
            paint,
        )
        self.add(
            "windows",
            box(
                wh_x1 - 0.3,
                wh_x1 + 0.06,
                -(wing_half_width - 0.3),
                wing_half_width - 0.3,
                z_roof + 0.9,
                z_roof + wh_height - 0.4,
            ),
            glass,
        )
        return z_roof, z_roof + wh_height, (wh_x0, wh_x1)

    def add_window_band(
        self,
        x0: float,
        x1: float,
        half_width: float,
        z0: float,
        z1: float,
        glass: Material,
        *,
        proud: float = 0.05,
    ) -> None:
        """Dark glazing band wrapping a block: a box slightly larger than the block."""
        self.add(
            "windows",
            box(x0 - proud, x1 + proud, -half_width - proud, half_width + proud, z0, z1),
            glass,
        )

    def add_funnel(
        self,
        x_centre: float,
        y_centre: float,
        half_length: float,
        half_width: float,
        z0: float,
        z1: float,
        rake: float,
        paint: Material,
        top: Material | None = None,
    ) -> None:
        """Raked elliptic funnel casing with an optional dark soot band at the top (~12 %)."""
        self.add(
            "funnel",
            prism_from_outline(
                x_centre,
                y_centre,
                half_length,
                half_width,
                z0 - EMBED_M,
                z1,
                rake=rake,
                top_scale=0.92,
            ),
            paint,
        )
        if top is not None:
            frac = 0.88
            zb = z0 + frac * (z1 - z0)
            scale = 1.0 + frac * (0.92 - 1.0)
            grow = 1.03
            self.add(
                "funnel_top",
                prism_from_outline(
                    x_centre - rake * frac,
                    y_centre,
                    half_length * scale * grow,
                    half_width * scale * grow,
                    zb,
                    z1 + 0.05,
                    rake=rake * (1 - frac),
                    top_scale=0.92 / scale,
                ),
                top,
            )

    def add_mast(
        self,
        x: float,
        y: float,
        z0: float,
        height: float,
        radius: float,
        paint: Material,
        *,
        yard_half_width: float = 0.0,
        name: str = "mast",
    ) -> None:
        """Pole mast with an optional yard (cross-tree) at 80 % of its height."""
        self.add(name, vertical_cylinder(x, y, radius, z0 - EMBED_M, z0 + height), paint)
        if yard_half_width > 0.0:
            zy = z0 + 0.8 * height
            self.add(
                name,
                cylinder_between(
                    (x, y - yard_half_width, zy),
                    (x, y + yard_half_width, zy),
                    0.6 * radius,
                    sections=8,
                ),
                paint,
            )

    def add_crane(
        self,
        x: float,
        y: float,
        z_deck: float,
        pedestal_height: float,
        pedestal_radius: float,
        jib_length: float,
        jib_elevation_deg: float,
        direction: float,
        paint: Material,
    ) -> None:
        """Deck crane: pedestal, cab, and a jib lying fore-aft (``direction`` +1 fwd, -1 aft)."""
        z_top = z_deck + pedestal_height
        self.add(
            "cranes",
            vertical_cylinder(x, y, pedestal_radius, z_deck - EMBED_M, z_top, sections=12),
            paint,
        )
        cab = 1.2 * pedestal_radius
        self.add("cranes", box(x - cab, x + cab, y - cab, y + cab, z_top - 0.1, z_top + 2.2), paint)
        a = np.radians(jib_elevation_deg)
        start = (x + direction * cab, y, z_top + 1.0)
        end = (start[0] + direction * jib_length * np.cos(a), y, start[2] + jib_length * np.sin(a))
        self.add("cranes", cylinder_between(start, end, 0.35 * pedestal_radius), paint)

    def add_block(
        self,
        name: str,
        material: Material,
        x0: float,
        x1: float,
        half_width: float,
        z0: float,
        z1: float,
        **rakes: float,
    ) -> None:
        """Add a :func:`tapered_block` body (rakes/inset as keyword arguments) to ``name``."""
        self.add(name, tapered_block(x0, x1, half_width, z0, z1, **rakes), material)
