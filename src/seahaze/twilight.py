"""The twilight sky: sunlight scattered in a spherical atmosphere, the sun below the horizon.

When the sun has set, no direct light reaches the sea: the sky is lit by sunlight that grazes
the Earth and scatters in the air still above the Earth's shadow. That shadow rises from the
horizon opposite the sun (the dark band under the "Belt of Venus") and climbs over the zenith as
the sun sinks: above an observer at sea level its edge lies at ``R (1/cos h − 1)``, about 1 km
at a depression ``h`` of 1°, 9 km at 3° and 35 km at 6° (the end of civil twilight). The
Hosek–Wilkie model of the clear day does not extend below the horizon; this module computes the
sky from the atmosphere itself.

Model (single scattering in a spherical shell; Nishita, T., Sirai, T., Tadamura, K. & Nakamae,
E. (1993). Display of the Earth taking into account atmospheric scattering. *SIGGRAPH '93*,
175–182)
    Along a view ray from sea level, each point ``p`` scatters the sunlight that reaches it
    toward the observer:

        L(λ) = E₀(λ) ∫ T_view(λ, s) · T_sun(λ, p) · Σ_k β_k(λ) n_k(z) P_k(Θ) ds

    where ``T_sun`` is zero where the straight line from ``p`` to the sun meets the sea (the
    Earth's shadow; refraction, which lifts the sun's rays by about half a degree at grazing,
    is left out), the transmittances are ``exp(−Σ_k β_k(λ) ∫ n_k ds)`` along each path, and
    ``Θ`` is the scattering angle.

Second order
    Single scattering leaves the Earth's shadow black. Each point also scatters the skylight
    around it, taken as the single-scattered sky of a sea-level observer whose sun stands
    where the point's does, uniform over the upper hemisphere and reflected by the sea below:
    a mean radiance ``J = E (1 + A) / 2π`` from that sky's horizontal irradiance ``E`` and the
    sea's albedo ``A`` (:func:`_skylight_source`). Higher orders are left out; they brighten
    the zenith late in civil twilight, so the model's deepest twilight is on the dark side
    (the test against measured illuminance below bounds it).

The atmosphere (three species, densities ``n_k`` relative to a reference)
    - Air (Rayleigh): ``n = exp(−z/8 km)``; vertical optical depth at sea level
      ``τ_R(λ) = 0.008569 λ⁻⁴ (1 + 0.0113 λ⁻² + 0.00013 λ⁻⁴)`` (λ in µm; Hansen, J. E. &
      Travis, L. D. (1974). Light scattering in planetary atmospheres. *Space Sci. Rev.* 16,
      527–610, eq. 2.29), phase ``3 (1 + cos²Θ) / 16π``.
    - Aerosol: ``n = exp(−z/1.2 km)``; vertical optical depth ``τ_a(550 nm)`` from the sky's
      Linke turbidity ``T_L`` by Ineichen's conversion at sea level with 1.5 cm of precipitable
      water, ``T_L = 3.91 e^0.689 τ_a + 0.376 ln 1.5 + 2.2`` (Ineichen, P. (2008). Conversion
      function between the Linke turbidity and the atmospheric water vapor and aerosol content.
      *Solar Energy* 82, 1095–1097), so ``T_L = 3`` gives ``τ_a ≈ 0.08`` and ``T_L = 6``
      ``τ_a ≈ 0.47``; Ångström exponent 1, single-scattering albedo 0.95, Henyey–Greenstein
      phase with ``g = 0.7`` (a maritime boundary-layer aerosol).
    - Ozone: absorbs only, in the Chappuis band, which is what keeps the twilight zenith blue
      when the sunlight reaching it has crossed hundreds of kilometres of air (Hulburt, E. O.
      (1953). Explanation of the brightness and color of the sky, particularly the twilight
      sky. *J. Opt. Soc. Am.* 43(2), 113–118). 300 Dobson units in a layer rising linearly
      from 10 km to its peak at 25 km and falling to zero at 40 km; cross-sections measured at
      233 K (Serdyuchenko, A., Gorshelev, V., Weber, M., Chehade, W. & Burrows, J. P. (2014).
      High spectral resolution ozone absorption cross-sections – Part 2: Temperature
      dependence. *Atmos. Meas. Tech.* 7, 625–636), means of their 10 nm bins.

    The sun above the atmosphere is a 5778 K black body (its spectral shape is all that
    matters: the renderer scales the sky to its own units). Spectra are sampled every 20 nm
    from 400 to 700 nm and turned into linear sRGB (the renderer's colour space) with the CIE
    1931 2° observer.

Checked against (tests/test_twilight.py): during a clear evening's civil twilight the
horizontal illuminance falls from about 410–585 lux at sunset to about 2–3.5 lux at a
depression of 6° (American Meteorological Society, *Glossary of Meteorology*, "civil
twilight").

Units: lengths in metres, angles in radians unless a name says degrees; radiance per unit of
the sun's spectral irradiance above the atmosphere (1/sr), before the renderer's scaling.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache

import numpy as np

EARTH_RADIUS_M = 6_371_000.0
"""Mean radius of the Earth (m)."""

ATMOSPHERE_TOP_M = 100_000.0
"""Height above which the model has no air (m): the air's density there is ``e^-12.5`` of
the sea level's."""

RAYLEIGH_SCALE_HEIGHT_M = 8_000.0
AEROSOL_SCALE_HEIGHT_M = 1_200.0
"""Scale heights of the air's and the aerosol's exponential profiles (m)."""

OZONE_LAYER_M = (10_000.0, 25_000.0, 40_000.0)
"""Bottom, peak and top of the ozone layer's triangular profile (m)."""

OZONE_COLUMN_DU = 300.0
"""The ozone column (Dobson units; the global mean is close to 300)."""

DOBSON_UNIT_PER_M2 = 2.687e20
"""Molecules per square metre of one Dobson unit."""

WAVELENGTHS_NM = np.arange(400.0, 701.0, 20.0)
"""The spectrum's samples (nm)."""

OZONE_CROSS_SECTION_M2 = np.array(
    [
        1.5e-27, 5.5e-27, 1.6e-26, 3.7e-26, 7.8e-26, 1.48e-25, 2.14e-25, 3.09e-25,
        4.27e-25, 4.40e-25, 5.02e-25, 3.74e-25, 2.66e-25, 1.85e-25, 1.21e-25, 7.5e-26,
    ]
)  # fmt: skip
"""Ozone's absorption cross-section at :data:`WAVELENGTHS_NM` (m², 233 K; Serdyuchenko et al.
2014, the mean over the 10 nm from each wavelength, two or three digits)."""

SUN_TEMPERATURE_K = 5778.0
"""Effective temperature of the black body standing for the sun's spectrum (K)."""

AEROSOL_ANGSTROM_EXPONENT = 1.0
AEROSOL_ALBEDO = 0.95
AEROSOL_ASYMMETRY = 0.7
"""The aerosol's Ångström exponent, single-scattering albedo and Henyey–Greenstein ``g``."""

SUN_PATH_ALTITUDES = 96
SUN_PATH_COSINES = 256
SUN_PATH_STEPS = 500
"""The table of column amounts toward the sun: altitudes (squared spacing from the sea to the
top), cosines of the sun's zenith angle (squared spacing above the grazing one) and the
midpoint steps of each line's integral (4.5 km on the longest, the 2260 km grazing chord from
the top); these and the view's steps and grid below were chosen by their convergence
(docs/physics.md, "The sky", twilight)."""

VIEW_STEPS = 256
"""Midpoint steps along a view ray (4.4 km on the horizontal one, 1130 km to the top)."""

GRID_ELEVATIONS = 96
GRID_AZIMUTHS = 37
"""The sky is computed on view elevations ``90° · u²`` (fine at the horizon, where twilight
changes fastest) and relative azimuths 0–180° every 5° (it is mirror-symmetric about the
sun's vertical plane), then interpolated."""


@dataclass(frozen=True)
class Atmosphere:
    """Per-wavelength coefficients (1/m at reference density) of the model's three species."""

    rayleigh: np.ndarray
    aerosol: np.ndarray
    ozone: np.ndarray

    @property
    def extinction(self) -> np.ndarray:
        """(3, L): extinction per unit relative density of air, aerosol and ozone."""
        return np.stack([self.rayleigh, self.aerosol, self.ozone])


def rayleigh_optical_depth(wavelength_nm: np.ndarray) -> np.ndarray:
    """Vertical Rayleigh optical depth of a standard atmosphere at sea level (Hansen & Travis
    1974): 0.097 at 550 nm."""
    lam = np.asarray(wavelength_nm, np.float64) / 1000.0
    return 0.008569 * lam**-4 * (1.0 + 0.0113 * lam**-2 + 0.00013 * lam**-4)


def aerosol_optical_depth_550(turbidity: float) -> float:
    """Vertical aerosol optical depth at 550 nm of a sky of Linke ``turbidity`` (Ineichen 2008
    at sea level, 1.5 cm of water vapour); 0 for turbidities the water vapour alone explains."""
    water_and_air = 0.376 * math.log(1.5) + 2.0 + 0.54 - 0.5 + 0.16
    return max(turbidity - water_and_air, 0.0) / (3.91 * math.exp(0.689))


def atmosphere(turbidity: float, ozone_du: float = OZONE_COLUMN_DU) -> Atmosphere:
    """The model's atmosphere for a sky of Linke ``turbidity`` with ``ozone_du`` Dobson units
    of ozone."""
    ozone_peak = ozone_du * DOBSON_UNIT_PER_M2 / (OZONE_LAYER_M[2] - OZONE_LAYER_M[0]) * 2
    tau_a = aerosol_optical_depth_550(turbidity) * (WAVELENGTHS_NM / 550.0) ** (
        -AEROSOL_ANGSTROM_EXPONENT
    )
    return Atmosphere(
        rayleigh=rayleigh_optical_depth(WAVELENGTHS_NM) / RAYLEIGH_SCALE_HEIGHT_M,
        aerosol=tau_a / AEROSOL_SCALE_HEIGHT_M,
        ozone=OZONE_CROSS_SECTION_M2 * ozone_peak,
    )


def densities(altitude_m: np.ndarray) -> np.ndarray:
    """(3, …): relative densities of air, aerosol and ozone at ``altitude_m``."""
    z = np.asarray(altitude_m, np.float64)
    bottom, peak, top = OZONE_LAYER_M
    ozone = np.clip(np.minimum((z - bottom) / (peak - bottom), (top - z) / (top - peak)), 0, 1)
    inside = z <= ATMOSPHERE_TOP_M
    return np.stack(
        [
            np.exp(-z / RAYLEIGH_SCALE_HEIGHT_M) * inside,
            np.exp(-z / AEROSOL_SCALE_HEIGHT_M) * inside,
            ozone,
        ]
    )


def _grazing_cosine(radius: np.ndarray) -> np.ndarray:
    """Cosine of the zenith angle of the line from ``radius`` that grazes the sea."""
    return -np.sqrt(np.clip(1.0 - (EARTH_RADIUS_M / radius) ** 2, 0.0, 1.0))


def _distance_to_top(radius: np.ndarray, cos_zenith: np.ndarray) -> np.ndarray:
    """Length of the line from ``radius`` at ``cos_zenith`` to the top of the atmosphere."""
    top = EARTH_RADIUS_M + ATMOSPHERE_TOP_M
    return -radius * cos_zenith + np.sqrt(
        np.maximum(radius**2 * (cos_zenith**2 - 1.0) + top**2, 0.0)
    )


def _line_columns(radius: np.ndarray, cos_zenith: np.ndarray, steps: int) -> np.ndarray:
    """(3, …): ``∫ n_k ds`` of each species along the lines from ``radius`` at ``cos_zenith``
    to the top of the atmosphere (midpoint rule, ``steps`` steps)."""
    length = _distance_to_top(radius, cos_zenith)
    t = (np.arange(steps) + 0.5) / steps
    s = length[..., None] * t
    r = np.sqrt(radius[..., None] ** 2 + s**2 + 2.0 * radius[..., None] * s * cos_zenith[..., None])
    return densities(r - EARTH_RADIUS_M).sum(axis=-1) * (length / steps)


@cache
def _sun_path_table() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The grid (``v`` = sqrt of the altitude's share of the atmosphere, ``x`` = sqrt of the
    cosine's share above the grazing one) and the (3, altitudes, cosines) columns toward the
    sun from each of its points."""
    v = np.linspace(0.0, 1.0, SUN_PATH_ALTITUDES)
    x = np.linspace(0.0, 1.0, SUN_PATH_COSINES)
    radius = EARTH_RADIUS_M + ATMOSPHERE_TOP_M * v**2
    grazing = _grazing_cosine(radius)[:, None]
    cos_zenith = grazing + (1.0 - grazing) * x[None, :] ** 2
    rows = [
        _line_columns(np.full(x.shape, r), c, SUN_PATH_STEPS)
        for r, c in zip(radius, cos_zenith, strict=True)
    ]
    return v, x, np.stack(rows, axis=1)


def sun_columns(
    altitude_m: np.ndarray, cos_sun_zenith: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(3, …) columns of each species from points at ``altitude_m`` toward a sun at
    ``cos_sun_zenith`` (their local zenith), bilinear in the table, and a mask of the points
    the sun lights (its line does not meet the sea)."""
    v_grid, x_grid, table = _sun_path_table()
    z = np.clip(altitude_m, 0.0, ATMOSPHERE_TOP_M)
    radius = EARTH_RADIUS_M + z
    grazing = _grazing_cosine(radius)
    lit = cos_sun_zenith >= grazing
    share = np.clip((cos_sun_zenith - grazing) / (1.0 - grazing), 0.0, 1.0)
    fv = np.sqrt(z / ATMOSPHERE_TOP_M) * (len(v_grid) - 1)
    fx = np.sqrt(share) * (len(x_grid) - 1)
    i = np.minimum(fv.astype(int), len(v_grid) - 2)
    j = np.minimum(fx.astype(int), len(x_grid) - 2)
    a, b = fv - i, fx - j
    columns = (
        table[:, i, j] * (1 - a) * (1 - b)
        + table[:, i + 1, j] * a * (1 - b)
        + table[:, i, j + 1] * (1 - a) * b
        + table[:, i + 1, j + 1] * a * b
    )
    return columns, lit


def phase_functions(cos_scatter: np.ndarray) -> np.ndarray:
    """(2, …): the Rayleigh and the aerosol's Henyey–Greenstein phase functions (1/sr)."""
    g = AEROSOL_ASYMMETRY
    rayleigh = 3.0 * (1.0 + cos_scatter**2) / (16.0 * math.pi)
    hg = (1.0 - g * g) / (4.0 * math.pi * (1.0 + g * g - 2.0 * g * cos_scatter) ** 1.5)
    return np.stack([rayleigh, hg])


def spectral_radiance(
    view_elevation: np.ndarray,
    relative_azimuth: np.ndarray,
    sun_elevation: float,
    turbidity: float,
    multiple: bool = True,
    ozone_du: float = OZONE_COLUMN_DU,
) -> np.ndarray:
    """(…, L) sky radiance at :data:`WAVELENGTHS_NM` seen from sea level in
    the directions of ``view_elevation`` (≥ 0) and ``relative_azimuth`` from the sun, per unit
    of the sun's spectral irradiance above the atmosphere (1/sr): sunlight scattered once,
    and, with ``multiple``, the skylight scattered once more (:func:`_skylight_source`)."""
    air = atmosphere(turbidity, ozone_du)
    e = np.asarray(view_elevation, np.float64)[..., None]
    phi = np.asarray(relative_azimuth, np.float64)[..., None]
    view = np.stack(
        np.broadcast_arrays(np.cos(e) * np.cos(phi), np.cos(e) * np.sin(phi), np.sin(e))
    )
    sun = np.array([math.cos(sun_elevation), 0.0, math.sin(sun_elevation)])
    cos_scatter = np.tensordot(sun, view, axes=1)
    length = _distance_to_top(np.full(e.shape, EARTH_RADIUS_M), np.sin(e))
    ds = length / VIEW_STEPS
    s = ds * (np.arange(VIEW_STEPS) + 0.5)
    radius = np.sqrt(EARTH_RADIUS_M**2 + s**2 + 2.0 * EARTH_RADIUS_M * s * np.sin(e))
    altitude = radius - EARTH_RADIUS_M
    n = densities(altitude)
    to_here = (np.cumsum(n, axis=-1) - 0.5 * n) * ds
    # cos of the sun's zenith angle at each point: (p · sun) / |p| with p = R ẑ + s·view.
    cos_sun = (EARTH_RADIUS_M * sun[2] + s * cos_scatter) / radius
    to_sun, lit = sun_columns(altitude, cos_sun)
    rayleigh_phase, aerosol_phase = phase_functions(cos_scatter)
    skylight = _skylight_source(cos_sun, turbidity, ozone_du) if multiple else None
    extinction = air.extinction
    out = np.empty((*e.shape[:-1], len(WAVELENGTHS_NM)))
    for k in range(len(WAVELENGTHS_NM)):
        beta = extinction[:, k]
        sunlit = np.exp(-np.tensordot(beta, to_sun, axes=1)) * lit
        scattering = (beta[0] * n[0], AEROSOL_ALBEDO * beta[1] * n[1])
        source = sunlit * (scattering[0] * rayleigh_phase + scattering[1] * aerosol_phase)
        if skylight is not None:
            source = source + (scattering[0] + scattering[1]) * skylight[..., k]
        out[..., k] = (np.exp(-np.tensordot(beta, to_here, axes=1)) * source).sum(-1) * ds[..., 0]
    return out


SKYLIGHT_SUN_ELEVATIONS_DEG = np.arange(-24.0, 12.1, 1.0)
"""Sun elevations of the table of single-scattered horizontal irradiance that lights the
second order (deg): a view ray's far end, a thousand kilometres away, sees the sun up to 10°
higher or lower than the observer does."""

SKYLIGHT_FLOOR = 1e-30
"""The table's floor before its logarithm is taken (a sun so deep that no air it lights is
seen gives an exact 0)."""

SEA_ALBEDO = 0.06
"""Albedo of the sea under a diffuse sky, which returns part of the skylight upward."""


def view_grid(elevations: int, azimuths: int) -> tuple[np.ndarray, np.ndarray]:
    """View elevations ``90° · u²`` (rad, fine at the horizon, where twilight changes fastest)
    and relative azimuths spread evenly over 0–180° (rad; the sky is mirror-symmetric about
    the sun's vertical plane)."""
    elevation = 0.5 * math.pi * np.linspace(0.0, 1.0, elevations) ** 2
    return elevation, np.radians(np.linspace(0.0, 180.0, azimuths))


COARSE_GRID = (24, 13)
"""Elevations × azimuths of the coarse grid on which the sky's horizontal irradiance alone is
integrated (the second order's table, the renderer's scale): within 0.2 % of the fine grid's."""


def hemisphere_integral(
    radiance: np.ndarray, elevation: np.ndarray, azimuth: np.ndarray
) -> np.ndarray:
    """``∫ L cos θ dω`` over the upper hemisphere of ``radiance`` (elevations × azimuths × …)
    on a grid of ``elevation`` and relative ``azimuth`` (rad, 0–π): the trapezoidal rule in
    both, the sky mirrored about the sun's vertical plane."""
    weight = (np.sin(elevation) * np.cos(elevation)).reshape(-1, *[1] * (radiance.ndim - 1))
    over_elevation = np.trapezoid(radiance * weight, elevation, axis=0)
    return 2.0 * np.trapezoid(over_elevation, azimuth, axis=0)


def spectral_irradiance(
    sun_elevation_deg: float,
    turbidity: float,
    multiple: bool = True,
    ozone_du: float = OZONE_COLUMN_DU,
) -> np.ndarray:
    """(L,) horizontal irradiance of the sky at sea level for a sun at ``sun_elevation_deg``,
    per unit of the sun's spectral irradiance above the atmosphere, on :data:`COARSE_GRID`."""
    elevation, azimuth = view_grid(*COARSE_GRID)
    e, phi = np.meshgrid(elevation, azimuth, indexing="ij")
    sun = math.radians(sun_elevation_deg)
    radiance = spectral_radiance(e, phi, sun, turbidity, multiple, ozone_du)
    return hemisphere_integral(radiance, elevation, azimuth)


def irradiance_rgb(sun_elevation_deg: float, turbidity: float) -> np.ndarray:
    """(3,) linear sRGB horizontal irradiance of the sky for a sun at ``sun_elevation_deg``
    (:func:`spectral_irradiance`)."""
    return spectral_irradiance(sun_elevation_deg, turbidity) @ spectrum_to_rgb()


@cache
def _skylight_table(turbidity: float, ozone_du: float) -> np.ndarray:
    """(elevations, L): horizontal irradiance of the single-scattered sky at sea level for a
    sun at each of :data:`SKYLIGHT_SUN_ELEVATIONS_DEG` (:func:`spectral_irradiance`)."""
    rows = [
        spectral_irradiance(float(h), turbidity, False, ozone_du)
        for h in SKYLIGHT_SUN_ELEVATIONS_DEG
    ]
    return np.stack(rows)


def _skylight_source(cos_sun_zenith: np.ndarray, turbidity: float, ozone_du: float) -> np.ndarray:
    """(…, L): the mean radiance ``J = (1/4π) ∫ L dω`` of the single-scattered skylight at
    points whose sun is at ``cos_sun_zenith``: the sky of a sea-level observer with that sun,
    taken as uniform over the upper hemisphere (``E/π``) and reflected by the sea below, so
    ``J = E (1 + A) / 2π``."""
    table = _skylight_table(turbidity, ozone_du)
    elevation = np.degrees(np.arcsin(np.clip(cos_sun_zenith, -1.0, 1.0)))
    # The skylight falls about tenfold every 2° of depression: interpolated in its logarithm.
    log_table = np.log(np.maximum(table, SKYLIGHT_FLOOR))
    columns = [
        np.exp(np.interp(elevation, SKYLIGHT_SUN_ELEVATIONS_DEG, log_table[:, k], left=-np.inf))
        for k in range(table.shape[1])
    ]
    return np.stack(columns, axis=-1) * (1.0 + SEA_ALBEDO) / (2.0 * math.pi)


def planck_radiance(wavelength_nm: np.ndarray, temperature_k: float) -> np.ndarray:
    """Spectral radiance of a black body, ``2hc²/λ⁵ / (e^(hc/λkT) − 1)`` (W m⁻² sr⁻¹ m⁻¹;
    Planck's law with the CODATA 2018 constants)."""
    h, c, k = 6.62607015e-34, 2.99792458e8, 1.380649e-23
    lam = np.asarray(wavelength_nm, np.float64) * 1e-9
    return 2.0 * h * c**2 / lam**5 / np.expm1(h * c / (lam * k * temperature_k))


@cache
def spectrum_to_rgb() -> np.ndarray:
    """(L, 3): linear sRGB of each spectral sample weighted by the sun's black body (its CIE
    1931 2° colour-matching functions times the sun's relative spectrum, through the XYZ to
    linear sRGB matrix). The tables are Mitsuba's own, from its scalar variant: no import of
    colour-science, which pulls in matplotlib."""
    import mitsuba.scalar_rgb as ms

    xyz_bar = np.array([list(ms.cie1931_xyz(float(w))) for w in WAVELENGTHS_NM])
    to_rgb = np.array([list(ms.xyz_to_srgb(ms.Color3f(*axis))) for axis in np.eye(3)]).T
    sun = planck_radiance(WAVELENGTHS_NM, SUN_TEMPERATURE_K)
    return (xyz_bar * (sun / sun.max())[:, None]) @ to_rgb.T


@dataclass(frozen=True)
class SkyGrid:
    """The twilight sky on the model's grid: elevations (rad, ascending), relative azimuths
    (rad, 0–π) and linear sRGB radiance (elevations × azimuths × 3)."""

    elevation: np.ndarray
    azimuth: np.ndarray
    rgb: np.ndarray

    def horizontal_irradiance(self) -> np.ndarray:
        """``∫ L cos θ dω`` (RGB) over the upper hemisphere (:func:`hemisphere_integral`)."""
        return hemisphere_integral(self.rgb, self.elevation, self.azimuth)

    def radiance(self, elevation: np.ndarray, relative_azimuth: np.ndarray) -> np.ndarray:
        """(…, 3) RGB radiance in these directions (rad; 0 below the horizon), bilinear in the
        grid."""
        from scipy.interpolate import RegularGridInterpolator

        folded = np.abs(np.angle(np.exp(1j * np.asarray(relative_azimuth))))
        lookup = RegularGridInterpolator((self.elevation, self.azimuth), self.rgb)
        points = np.stack([np.clip(elevation, 0.0, math.pi / 2), folded], axis=-1)
        return lookup(points) * (np.asarray(elevation) >= 0.0)[..., None]


@cache
def sky_grid(sun_elevation_deg: float, turbidity: float) -> SkyGrid:
    """The sky (sunlight scattered once, skylight once more) of a sun at ``sun_elevation_deg``
    in a sky of Linke ``turbidity`` on the model's grid (:data:`GRID_ELEVATIONS` ×
    :data:`GRID_AZIMUTHS`)."""
    elevation, azimuth = view_grid(GRID_ELEVATIONS, GRID_AZIMUTHS)
    e, phi = np.meshgrid(elevation, azimuth, indexing="ij")
    spectral = spectral_radiance(e, phi, math.radians(sun_elevation_deg), turbidity)
    return SkyGrid(elevation, azimuth, spectral @ spectrum_to_rgb())
