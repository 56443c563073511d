"""The ``physical`` estimator's tuning, as one frozen settings object passed to the renderer.

Every choice that trades noise against time in the ``physical`` mode — how many surfaces a
path meets, how the samples are shared between strategies, how many photons the diffuse tables
get, how the vessel-light pass is sampled and smoothed — is a field of
:class:`EstimatorSettings`. The renderer reads it while it traces its kernels, so nothing can
change it behind a compiled kernel's back, and a dataset records it (``meta``'s
``render.estimator``). A scene may override fields under ``render.estimator`` (docs/scenes.md);
benchmarks and tests construct settings instead of changing module state. What each default
was measured to do is in docs/benchmarks.md; what each estimator is, in docs/physics.md.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields, replace
from typing import Any


@dataclass(frozen=True)
class EstimatorSettings:
    """The ``physical`` mode's tuning (see the module docstring)."""

    bounces: int = 3
    """Surface interactions per camera path: sea → sky, vessel → sea → sky."""
    camera_points: int = 2
    """Stratified in-scattering points on the camera segment (one on later segments)."""
    glint_share: float = 0.7
    """Share (0–1) of a hull's next directions drawn toward the sea's sun glint
    (:mod:`seahaze.render.glint_lobe`); 0: BSDF sampling alone."""
    vessel_light_share: float = 1 / 14
    """The vessel-light pass's samples per pixel as a share (0–1) of the main pass's, rounded
    up (:func:`vessel_light_spp`); 0 leaves the pass out."""
    vessel_light_radius_px: int = 6
    """Radius (pixels) of the box filter the vessel-light pass is smoothed with, within each
    segment of the image (:mod:`seahaze.render.segment_smooth`); 0: unsmoothed."""
    near_share: float = 0.5
    """Share (0–1) of the vessel-light pass's probe points drawn near a vessel, the rest from
    the levels' mixture."""
    aim_share: float = 0.5
    """Share (0–1) of the vessel-light pass's probes aimed at a vessel's bounding sphere, the
    rest following the phase function."""
    table_photons: int | None = None
    """Photons per level table; None: :meth:`photons_for` the pass's camera samples."""
    samples_per_photon: int = 32
    """Camera samples (pixels × spp) per table photon, before rounding and the bounds."""
    min_table_photons: int = 1 << 17
    """Fewest photons per level table (half from the sun, half from the sky)."""
    max_table_photons: int = 1 << 20
    """Most photons per level table."""
    bank_photons: int | None = None
    """Photons per level of a fog bank's or patches' own diffuse field
    (:mod:`seahaze.render.bank_diffuse`, :mod:`seahaze.render.patch_diffuse`); None:
    :meth:`bank_photons_for` the tables' photons."""
    max_levels_per_pass: int = 12
    """Most levels one pass renders (its kernel grows with the count; more levels are rendered
    in several passes of the same camera paths, :func:`seahaze.render.physical.levels_per_pass`)."""

    def __post_init__(self) -> None:
        for name in ("glint_share", "vessel_light_share", "near_share", "aim_share"):
            value = getattr(self, name)
            if not 0.0 <= value <= 1.0:
                raise ValueError(f"estimator.{name} must lie in [0, 1], got {value}")
        positive = (
            "camera_points",
            "samples_per_photon",
            "min_table_photons",
            "max_levels_per_pass",
        )
        for name in ("bounces", "vessel_light_radius_px", *positive):
            value = getattr(self, name)
            if int(value) != value or value < (1 if name in positive else 0):
                floor = "1" if name in positive else "0"
                raise ValueError(f"estimator.{name} must be an integer >= {floor}, got {value}")
        if self.max_table_photons < self.min_table_photons:
            raise ValueError("estimator.max_table_photons must be >= min_table_photons")
        for name in ("table_photons", "bank_photons"):
            if getattr(self, name) is not None and getattr(self, name) < 1:
                raise ValueError(f"estimator.{name} must be >= 1 (or null: by the pass)")

    def photons_for(self, samples: int) -> int:
        """Photons per level table for a pass of ``samples`` camera samples (pixels × spp):
        :attr:`table_photons` if set, else one per :attr:`samples_per_photon` samples, rounded
        to a power of two and held within [:attr:`min_table_photons`,
        :attr:`max_table_photons`]. A table's noise moves a level's whole brightness rather
        than averaging out over pixels, so it grows with the pass (docs/benchmarks.md, "The
        diffuse tables' noise")."""
        if self.table_photons is not None:
            return self.table_photons
        wanted = max(samples, 1) / self.samples_per_photon
        rounded = 1 << max(round(math.log2(wanted)), 0)
        return min(max(rounded, self.min_table_photons), self.max_table_photons)

    def bank_photons_for(self, table_photons: int) -> int:
        """Photons per level of a fog bank's or patches' diffuse field for a pass whose tables
        get ``table_photons`` each: :attr:`bank_photons` if set, else the same number (at
        least :attr:`min_table_photons`). The bank's tally has forty-odd cells across the edge
        for each of the table's heights, the patches' box thousands of columns, but their
        ratios are summed along rays through them (docs/benchmarks.md, "How close is physical
        in a fog bank?", "… in drifting patches?")."""
        if self.bank_photons is not None:
            return self.bank_photons
        return max(table_photons, self.min_table_photons)

    def vessel_light_spp(self, spp: int) -> int:
        """Samples per pixel asked of the vessel-light pass for ``spp`` of the main pass: the
        :attr:`vessel_light_share` of them, rounded up (0 when the pass is off)."""
        if self.vessel_light_share <= 0.0:
            return 0
        return max(1, math.ceil(spp * self.vessel_light_share - 1e-9))

    def record(self) -> dict[str, Any]:
        """The settings as plain data (``meta``'s ``render.estimator``)."""
        return asdict(self)

    @classmethod
    def field_names(cls) -> tuple[str, ...]:
        """The names a scene's ``render.estimator`` may set."""
        return tuple(f.name for f in fields(cls))


DEFAULT_SETTINGS = EstimatorSettings()
"""The defaults every dataset is rendered with unless its scene says otherwise."""


def settings_from(overrides: Any) -> EstimatorSettings:
    """The defaults with a scene's ``render.estimator`` overrides (a
    :class:`seahaze.spec.EstimatorSpec` or a mapping; a None field keeps the default)."""
    if overrides is None:
        return DEFAULT_SETTINGS
    items = overrides.model_dump() if hasattr(overrides, "model_dump") else dict(overrides)
    unknown = set(items) - set(EstimatorSettings.field_names())
    if unknown:
        raise ValueError(f"unknown estimator settings: {', '.join(sorted(unknown))}")
    return replace(DEFAULT_SETTINGS, **{k: v for k, v in items.items() if v is not None})
