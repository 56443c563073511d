"""Procedural ocean surfaces controlled by sea state (numpy/scipy only).

* :mod:`~seahaze.ocean.spectra` — Pierson–Moskowitz, JONSWAP and Phillips spectra, directional
  spreading, deep-water dispersion.
* :mod:`~seahaze.ocean.beaufort` — Beaufort 0–12 presets (wind speed, probable wave height).
* :mod:`~seahaze.ocean.gerstner`, :mod:`~seahaze.ocean.fft` — the two wave generators behind
  :class:`OceanSurface`; :func:`make_surface` picks one from :class:`OceanParams`.
* :mod:`~seahaze.ocean.mesh` — camera-centred polar mesh out to 100 km.
* :mod:`~seahaze.ocean.cox_munk` — Cox–Munk slope statistics → microfacet roughness, and the
  budget between resolved and sub-grid slopes.
* :mod:`~seahaze.ocean.whitecaps` — whitecap coverage (Monahan & O'Muircheartaigh 1980), foam
  reflectance (Koepke 1984), and a foam field on the breaking crests.
* :mod:`~seahaze.ocean.spindrift` — a gale's spray veil blown downwind of its breaking crests.
* :mod:`~seahaze.ocean.wake` — Kelvin ship waves, bow waves and turbulent foam wakes of moving
  vessels.

See ``docs/ocean.md``.
"""

from .base import (
    ChoppinessClampedWarning,
    FlatSurface,
    OceanParams,
    OceanSurface,
    height_at,
    invert_horizontal_displacement,
)
from .beaufort import (
    BEAUFORT_SCALE,
    BeaufortForce,
    beaufort,
    beaufort_force_for_wind,
    beaufort_wave_height,
    beaufort_wind_speed,
    ocean_params_for_beaufort,
)
from .cox_munk import (
    MeshRoughness,
    SlopeBudget,
    beckmann_alpha,
    cox_munk_alpha,
    cox_munk_anisotropic_alpha,
    mean_square_slope,
    mesh_roughness,
    slope_budget,
    sub_grid_roughness,
)
from .fft import FFTCascade, FFTOcean, fft_choppiness_limit
from .gerstner import GerstnerOcean
from .kelvin import transverse_wavelength
from .mesh import SeaMesh, build_sea_mesh, build_sea_mesh_data, horizon_gap_angle
from .spectra import SeaSpectrum
from .spindrift import SPRAY_REFLECTANCE, Spindrift, spindrift_opacity
from .surface import make_surface
from .wake import MovingVessel, ShipWaves, WakeField, wake_foam, wake_height
from .whitecaps import (
    FOAM_REFLECTANCE,
    FRESH_FOAM_REFLECTANCE,
    FoamField,
    as_fresh_foam,
    foam_fraction,
    layer_over,
    whitecap_albedo,
    whitecap_coverage,
)

__all__ = [
    "BEAUFORT_SCALE",
    "FOAM_REFLECTANCE",
    "FRESH_FOAM_REFLECTANCE",
    "SPRAY_REFLECTANCE",
    "BeaufortForce",
    "ChoppinessClampedWarning",
    "FFTCascade",
    "FFTOcean",
    "FlatSurface",
    "FoamField",
    "GerstnerOcean",
    "MeshRoughness",
    "MovingVessel",
    "OceanParams",
    "OceanSurface",
    "SeaMesh",
    "SeaSpectrum",
    "ShipWaves",
    "SlopeBudget",
    "Spindrift",
    "WakeField",
    "as_fresh_foam",
    "beaufort",
    "beaufort_force_for_wind",
    "beaufort_wave_height",
    "beaufort_wind_speed",
    "beckmann_alpha",
    "build_sea_mesh",
    "build_sea_mesh_data",
    "cox_munk_alpha",
    "cox_munk_anisotropic_alpha",
    "fft_choppiness_limit",
    "foam_fraction",
    "height_at",
    "horizon_gap_angle",
    "invert_horizontal_displacement",
    "layer_over",
    "make_surface",
    "mean_square_slope",
    "mesh_roughness",
    "ocean_params_for_beaufort",
    "slope_budget",
    "spindrift_opacity",
    "sub_grid_roughness",
    "transverse_wavelength",
    "wake_foam",
    "wake_height",
    "whitecap_albedo",
    "whitecap_coverage",
]
