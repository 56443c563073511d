"""The hull the large cargo ships share (container ship, bulk carrier, tanker): its form, its
boot-topping and the foremast on its forecastle. Metres; vessel frame x forward, y port, z up,
waterline z = 0.

Every draw comes from the builder's ``rng`` in a fixed order (the builders in
:mod:`seahaze.vessels.merchant` and :mod:`seahaze.vessels.bulk_tanker` rely on it: the vessels
built after one in a scene draw what they always drew).
"""

from __future__ import annotations

import numpy as np

from seahaze.vessels.geometry import HullForm
from seahaze.vessels.materials import Material
from seahaze.vessels.parts import PartSet, PrincipalDims, u

__all__ = ["DECK_HEIGHT_M", "boot_top", "foremast", "merchant_hull"]

DECK_HEIGHT_M = 2.8
"""Height of one accommodation deck (m): about 2.8 m floor to floor on merchant ships."""


def merchant_hull(d: PrincipalDims, rng: np.random.Generator, *, fullness: float) -> HullForm:
    """Cargo-ship hull: parallel middle body, raked stem, forecastle, transom counter stern.

    ``fullness`` in [0, 1] goes from a fine container-ship entrance to a bluff bulker bow.
    """
    return HullForm(
        length=d.length,
        beam=d.beam,
        draft=d.draft,
        freeboard=d.freeboard,
        sheer_fwd=u(rng, 0.04, 0.1) * d.depth,
        sheer_aft=u(rng, 0.0, 0.03) * d.depth,
        forecastle_height=u(rng, 2.3, 3.0),
        forecastle_length=u(rng, 0.06, 0.09) * d.length,
        parallel_fwd=u(rng, 0.1, 0.25) + 0.2 * fullness,
        parallel_aft=u(rng, 0.15, 0.3) + 0.1 * fullness,
        # Deck planform: blunt, so a flared bow still carries containers / a forecastle;
        # the waterline stays fine through bow_flare.
        entrance_exponent=u(rng, 2.3, 2.9) + 0.8 * fullness,
        bow_roundness=1.0 + 0.4 * fullness,
        transom_width=u(rng, 0.7, 0.88),
        stem_rake=u(rng, 0.018, 0.035),
        stem_exponent=0.5,
        stern_cutup=u(rng, 0.08, 0.12),
        transom_immersion=u(rng, -0.15, 0.15),
        section_exponent=7.0,
        bow_flare=u(rng, 0.35, 0.5) - 0.15 * fullness,
    )


def boot_top(d: PrincipalDims) -> float:
    """Antifouling top (m above the current waterline): the design load line at ~72 % depth.

    A ship in ballast floats high and shows its red bottom; a laden one shows a thin band.
    """
    return max(0.3, 0.72 * d.depth - d.draft + 0.3)


def foremast(parts: PartSet, form: HullForm, paint: Material, rng: np.random.Generator) -> None:
    """Pole foremast with a cross-tree on the forecastle, 2.5-4 % L aft of the stem, 3-5 % L
    tall (two draws from ``rng``)."""
    x = form.half_length - u(rng, 0.025, 0.04) * form.length
    z0 = float(form.deck_z(np.array([x]))[0])
    parts.add_mast(
        x,
        0.0,
        z0,
        u(rng, 0.03, 0.05) * form.length,
        max(0.25, 0.0015 * form.length),
        paint,
        yard_half_width=0.6,
    )
