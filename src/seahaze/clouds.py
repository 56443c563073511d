"""Broken cloud: a layer of cumulus over the sea that covers a given share of the sky.

Most days with haze at sea are cloudy; between a clear sky (Hosek–Wilkie) and a full deck (the
CIE overcast sky, :mod:`seahaze.overcast`) lie the skies of scattered and broken cloud, where
the sun is out or behind a cloud and blue sky shows between the clouds.

Cloud amount (WMO)
    In eighths of the sky covered (oktas ``N``): 1–2 "few", 3–4 "scattered", 5–7 "broken", 8
    "overcast" (WMO Manual on Codes, No. 306, code table 2700; the METAR groups FEW, SCT, BKN,
    OVC). Here ``N/8`` is the expected share of the cloud layer's area that is cloud.

Where the clouds are
    A flat layer at the cloud base height ``H`` (m; fair-weather cumulus and stratocumulus
    over the sea have bases of a few hundred metres to about 2 km). A direction of zenith angle
    ``θ`` and azimuth ``φ`` meets it at the horizontal offset ``H·tan θ·(sin φ, cos φ)``, so
    clouds of one size look smaller and crowd together toward the horizon, as in a
    photograph. The cover there is fractal value noise (:func:`seahaze.haze_field.value_noise`,
    :data:`OCTAVES` octaves, the largest of lattice spacing ``size_m``), cut at the level that
    leaves ``N/8`` of the layer covered, with a soft edge (:data:`EDGE_HALF_WIDTH`). Toward
    the horizon a texel of the sky's image spans more of the layer than an octave's lattice
    spacing; such octaves are left out (the rest rescaled to the same spread, so the cut keeps
    its meaning), and where even the largest spans less than a texel the cover fades to its
    mean, ``N/8`` (nothing a camera could resolve there would be left but aliasing).

How bright (Kasten & Czeplak 1980)
    A cumulus is optically thick (optical depth 10–100): the sun's beam does not pass it,
    diffuse light does. Seen from below, a cloud has the CIE overcast gradation
    ``(1 + 2 cos θ)/3`` and a brightness ``b(N)`` times that of the full deck of the overcast
    sky; the sky between the clouds is the clear sky of the same sun, and the sun is scaled by
    ``1 − c`` (``c`` the cover in its direction). Averaged over cloud fields (the sun is out
    with probability ``1 − N/8``, a direction is cloud with probability ``N/8``), the global
    horizontal irradiance is then

        G = (1 − N/8)·G_clear + (N/8)·b·T(8)·G_clear,

    and Kasten & Czeplak's ``G(N)/G_clear = T(N) = 1 − 0.75 (N/8)^3.4``
    (:func:`seahaze.overcast.cloud_transmission`) sets

        b(N) = (T(N) − (1 − N/8)) / ((N/8)·T(8)),

    which falls from 4 (a few sunlit fair-weather clouds, far brighter than a deck) to 1 at
    ``N = 8`` (the overcast sky itself). Clouds are grey: droplets scatter all visible
    wavelengths alike (:mod:`seahaze.overcast`, "Colour").

    Within a cloud the brightness follows its thickness, as a cumulus seen from below is
    bright at its thin edges and dark grey under its core: the optical depth rises from
    :data:`EDGE_OPTICAL_DEPTH` at the edge to :data:`CORE_OPTICAL_DEPTH` with the noise's
    height above the cut, and the radiance goes as the diffuse transmission of a thick
    non-absorbing layer, ``t = 1/(1.07 + 0.75(1 − g)τ)`` (the asymptotic theory of thick
    clouds; Kokhanovsky, A. A. (2004). Optical properties of terrestrial clouds. *Earth-Sci.
    Rev.* 64, 189–241), divided by its mean over the layer's cloud, so that the mean stays
    ``b(N)`` and the irradiance above holds.

Aerial perspective (Preetham, Shirley & Smits 1999)
    Between the sea and a cloud lies clear air: a distant cloud near the horizon fades into the
    horizon's sky, as it does in a photograph. Its optical depth along a slant path of zenith
    cosine ``μ`` up to the base ``H`` is ``τ(H)/μ``, with the vertical

        τ(H) = τ_m·(1 − e^(−H/H_m)) + (T − 1)·τ_m·(1 − e^(−H/H_h)),

    the molecules' share (``τ_m = 0.097`` at 550 nm from sea level, Bucholtz, A. (1995).
    Rayleigh-scattering calculations for the terrestrial atmosphere. *Appl. Opt.* 34(15),
    2765–2773; scale height ``H_m = 8.4`` km) and the aerosol's, which the sky's turbidity
    ``T = (τ_m + τ_h)/τ_m`` sets (Preetham, A. J., Shirley, P. & Smits, B. (1999). A practical
    analytic model for daylight. *SIGGRAPH '99*, 91–100; haze scale height ``H_h = 1.2`` km).
    A cloud is seen as ``t·L_cloud + (1 − t)·L_clear`` with ``t = exp(−τ(H)/μ)``: the clear
    sky's radiance in that direction stands in for the light the air between scatters toward
    the camera (near the horizon it is that path's own light; overhead, where ``t`` is near 1,
    the stand-in hardly matters).

Drift (Hsu, Meindl & Gilhousen 1994)
    In a sequence the layer moves with the wind at its height, ``m(x − v t)``: the wind the sea
    was built for (``U10`` toward ``sea.direction_deg``) raised to the cloud base by the
    power law of the marine surface layer, ``U(z) = U10·(z/10 m)^0.11`` (exponent 0.11 ± 0.03
    over the open sea in near-neutral air: Hsu, S. A., Meindl, E. A. & Gilhousen, D. B. (1994).
    Determining the power-law wind-profile exponent under near-neutral stability conditions at
    sea. *J. Appl. Meteor.* 33, 757–765), 1.66 × ``U10`` at 1000 m. A cloud crossing the sun
    dims it as its edge passes.

Limits: the clouds are flat (no sides or tops; near the horizon a real layer closes up more
than its cover), cast no shadows (the sun is out or in for the whole scene), have no bright
sunlit rims, and keep their shapes as they drift (no growth or decay).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np

from .haze_field import value_noise
from .overcast import FULL_DECK_OKTAS, cloud_transmission

OCTAVES = 5
"""Octaves of the cloud layer's fractal noise: lattice spacings from ``size_m`` to 1/16 of it."""

OCTAVE_GAIN = 0.5
"""Amplitude of each octave relative to the one before (a fractal of dimension 2.5 in the
plane, the look of cumulus edges)."""

EDGE_HALF_WIDTH = 0.04
"""Half-width of the cloud edge in the noise's units (its standard deviation is about 0.3):
a cloud's edge is sharp but not a step at the texel."""

EDGE_OPTICAL_DEPTH = 2.0
"""Optical depth of a cloud at its edge, where it is thinnest."""

CORE_OPTICAL_DEPTH = 40.0
"""Optical depth of a cloud's thickest part (the noise's 99th percentile); cumulus have 10–100
(Stephens 1978, *J. Atmos. Sci.* 35, 2123–2132)."""

CLOUD_ASYMMETRY = 0.85
"""Henyey–Greenstein ``g`` of cloud droplets in the visible."""

EDGE_WIDTHS = np.geomspace(EDGE_HALF_WIDTH, 1.0, 16)
"""Half-widths of the widened (anti-aliased) edge at which the cut is tabulated."""

CUT_SAMPLES = 512
"""Samples per side of the square (:data:`CUT_SPAN` lattice spacings) over which the noise's
distribution is tabulated: its 99th percentile (a cloud's core) and the clouds' mean
transmission from all of them, the cut that leaves ``N/8`` covered from every other one a side
(the cut's error is the layer's own sampling, not the samples')."""

CUT_SPAN = 64.0
"""Side of that square in largest-octave lattice spacings."""


def cloud_brightness(oktas: float, deck_seen: float = 1.0, clear_lost: float = 0.0) -> float:
    """``b(N)``: a cloud's radiance over the full deck's (module docstring), for ``0 < oktas
    ≤ 8``; without air between (the defaults) 4 as ``N → 0``, 1 at ``N = 8``.

    Through the air below the layer ("Aerial perspective"), the clouds' light reaching the sea
    is ``deck_seen`` (``∫ t D cos θ dω / ∫ D cos θ dω``, ``D`` the deck's gradation) of theirs,
    and a cloud direction brings ``(1 − t)`` of the clear sky's light instead, in all
    ``clear_lost`` of ``G_clear`` over the sky (``∫ (1 − t) L_clear cos θ dω / G_clear``): so
    that the mean global irradiance still is Kasten & Czeplak's,
    ``b = (T(N) − (1 − N/8) − (N/8)·clear_lost) / ((N/8)·T(8)·deck_seen)``."""
    share = _share(oktas)
    if share == 0.0:
        raise ValueError("a sky without cloud has no cloud brightness")
    full_deck = cloud_transmission(FULL_DECK_OKTAS)
    gained = cloud_transmission(oktas) - (1.0 - share) - share * clear_lost
    return gained / (share * full_deck * deck_seen)


WIND_PROFILE_EXPONENT = 0.11
"""Power-law exponent of the wind's rise with height over the open sea (Hsu et al. 1994)."""

WIND_REFERENCE_HEIGHT_M = 10.0
"""Height of the wind speed ``U10`` the sea is built for (m)."""


def wind_at_height(u10: float, height_m: float) -> float:
    """Wind speed (m/s) at ``height_m`` (m) over the open sea for ``u10`` (m/s at 10 m): the
    power law ``U10·(z/10)^0.11`` (module docstring, "Drift")."""
    return float(u10) * (float(height_m) / WIND_REFERENCE_HEIGHT_M) ** WIND_PROFILE_EXPONENT


def _share(oktas: float) -> float:
    if not 0.0 <= oktas <= FULL_DECK_OKTAS:
        raise ValueError(f"cloud amount {oktas} oktas is outside 0..{FULL_DECK_OKTAS}")
    return oktas / FULL_DECK_OKTAS


@dataclass(frozen=True)
class CloudLayer:
    """A broken cloud layer: ``oktas`` eighths of cover at base height ``base_m`` (m), largest
    cloud scale ``size_m`` (m, the largest octave's lattice spacing), drawn by ``seed``."""

    oktas: float
    base_m: float
    size_m: float
    seed: int
    offset_m: tuple[float, float] = (0.0, 0.0)
    """How far the layer has drifted (m, world x and y): the cover at ``p`` is the undrifted
    layer's at ``p − offset``."""

    @property
    def share(self) -> float:
        """Expected covered share of the layer, ``N/8``."""
        return _share(self.oktas)

    def cover(self, directions: np.ndarray, texel_rad: float = 0.0) -> np.ndarray:
        """Cloud cover (0–1) of unit world directions (…, 3), z up; 0 below the horizon.
        ``texel_rad``: the angular size of what one value stands for (an image's texel), which
        leaves out the octaves it cannot resolve (module docstring); 0 keeps every octave."""
        d = np.asarray(directions, np.float64)
        up = d[..., 2] > 1e-6
        out = np.zeros(up.shape)
        noise, resolved = self._noise_toward(d[up], texel_rad)
        out[up] = self._blend(_soft_cut(noise, self._cut, EDGE_HALF_WIDTH), resolved)
        return out

    def latlong_cover(self, rows: int, columns: int) -> tuple[np.ndarray, np.ndarray]:
        """Cloud cover (0–1) and the clouds' relative brightness (mean 1 over the layer's
        cloud; module docstring), rows × columns each, at the texel centres of a
        latitude–longitude image laid out as :func:`latlong_directions`. Anti-aliased: a
        cloud's edge is widened to the noise's change from one texel to the next, so that an
        edge the texels cannot resolve (near the horizon a row spans hundreds of metres of the
        layer) is a ramp over about two texels, not a staircase of one-texel steps."""
        directions = latlong_directions(rows, columns)
        up_rows = int(np.count_nonzero(directions[:, 0, 2] > 1e-6))
        cover, shade = np.zeros((rows, columns)), np.ones((rows, columns))
        upper = directions[:up_rows]
        noise, resolved = self._noise_toward(upper.reshape(-1, 3), math.pi / (rows - 1))
        noise, resolved = noise.reshape(up_rows, columns), resolved.reshape(up_rows, columns)
        across = 0.5 * np.abs(np.roll(noise, -1, axis=1) - np.roll(noise, 1, axis=1))
        along = np.abs(np.gradient(noise, axis=0)) if up_rows > 1 else 0.0
        half_width = np.maximum(EDGE_HALF_WIDTH, across + along)
        cut = self._cut_at(half_width)
        cover[:up_rows] = self._blend(_soft_cut(noise, cut, half_width), resolved)
        shade[:up_rows] = resolved * self._shade(noise) + (1.0 - resolved)
        return cover, shade

    def _shade(self, noise: np.ndarray) -> np.ndarray:
        """A cloud's radiance relative to the layer's mean cloud: its diffuse transmission at
        the optical depth its noise gives (module docstring)."""
        return _transmission(self._optical_depth(noise)) / self._mean_transmission

    def _optical_depth(self, noise: np.ndarray) -> np.ndarray:
        cut, core = self._cut, self._tabulated[1]
        depth = np.clip((noise - cut) / max(core - cut, 1e-9), 0.0, 1.0)
        return EDGE_OPTICAL_DEPTH + (CORE_OPTICAL_DEPTH - EDGE_OPTICAL_DEPTH) * depth

    @cached_property
    def _mean_transmission(self) -> float:
        """The clouds' diffuse transmission averaged over the layer's cloud (cover-weighted)."""
        noise = self._tabulated[0]
        cover = _soft_cut(noise, self._cut, EDGE_HALF_WIDTH)
        t = _transmission(self._optical_depth(noise))
        return float(np.sum(cover * t) / max(np.sum(cover), 1e-300))

    def sun_transmission(self, sun_direction: np.ndarray) -> float:
        """Share of the sun's beam that reaches the sea: ``1 − c`` of the sun's direction
        (a cloud passes no direct beam)."""
        return float(1.0 - self.cover(np.asarray(sun_direction, np.float64)))

    def _noise_toward(
        self, directions: np.ndarray, texel_rad: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """The layer's noise where upward ``directions`` (n, 3) meet it, band-limited to what
        a texel of ``texel_rad`` resolves there, and how much its largest octave is."""
        mu = directions[:, 2]
        x = self.base_m * directions[:, 0] / mu - self.offset_m[0]
        y = self.base_m * directions[:, 1] / mu - self.offset_m[1]
        footprint = self.base_m * texel_rad / (mu * mu)  # along the range: H dθ / cos² θ
        return self._noise(x, y, footprint)

    def _blend(self, cover: np.ndarray, resolved: np.ndarray) -> np.ndarray:
        """Where even the largest clouds are unresolved, their mean cover, ``N/8``."""
        return resolved * cover + (1.0 - resolved) * self.share

    def _noise(
        self, x: np.ndarray, y: np.ndarray, footprint: np.ndarray | float
    ) -> tuple[np.ndarray, np.ndarray]:
        """Fractal noise at layer points (m) with the octaves a ``footprint`` (m) resolves,
        rescaled to the full noise's spread, and how much the largest octave is resolved."""
        return _fractal_noise(x, y, footprint, self.size_m, self.seed)

    @property
    def _tabulated(self) -> tuple[np.ndarray, float]:
        """The full noise over a large square of the layer and its 99th percentile (a cloud's
        core): :func:`_tabulated_noise`."""
        return _tabulated_noise(self.size_m, self.seed)

    @property
    def _cut(self) -> float:
        """The noise level above which the layer is cloud, with the sharp edge: the mean soft
        cover of a large square of the layer is ``N/8``."""
        return float(self._cuts[0])

    def _cut_at(self, half_width: np.ndarray) -> np.ndarray:
        """The cut for an edge widened to ``half_width`` (anti-aliasing): set for every width
        so that the mean cover stays ``N/8`` (a wider ramp over a cut in the noise's tail would
        otherwise add cover to a few-okta sky and take it from an almost overcast one)."""
        return np.interp(np.log(half_width), np.log(EDGE_WIDTHS), self._cuts)

    @property
    def _cuts(self) -> np.ndarray:
        """The cut of each of :data:`EDGE_WIDTHS`: :func:`_tabulated_cuts`."""
        return _tabulated_cuts(self.share, self.size_m, self.seed)


def _fractal_noise(
    x: np.ndarray, y: np.ndarray, footprint: np.ndarray | float, size_m: float, seed: int
) -> tuple[np.ndarray, np.ndarray]:
    """:meth:`CloudLayer._noise` of a layer of largest spacing ``size_m`` drawn by ``seed``."""
    shape = np.broadcast_shapes(np.shape(x), np.shape(y), np.shape(footprint))
    total = np.zeros(shape)
    power = np.zeros(shape)
    resolved = np.ones(shape)
    for octave in range(OCTAVES):
        spacing = size_m / 2.0**octave
        weight = OCTAVE_GAIN**octave * _resolved(footprint, spacing)
        if octave == 0:
            resolved = np.broadcast_to(weight, shape)
        if not np.any(weight > 0.0):
            break
        total += weight * value_noise(x / spacing, y / spacing, 0.0, seed + 7919 * octave)
        power += weight * weight
    full_power = sum(OCTAVE_GAIN ** (2 * o) for o in range(OCTAVES))
    scale = np.sqrt(full_power / np.maximum(power, 1e-300))
    return np.where(power > 0.0, total * scale, 0.0), resolved


# The tables below depend on the layer's size and seed (and the cut on its cover), not on its
# drift: a sequence's frames, and a scene's sun and sky built apart, share them.
@lru_cache(maxsize=8)
def _tabulated_noise(size_m: float, seed: int) -> tuple[np.ndarray, float]:
    """The full noise over a large square of a layer (:data:`CUT_SAMPLES`² points,
    :data:`CUT_SPAN` largest spacings a side; read-only), and its 99th percentile."""
    grid = (np.arange(CUT_SAMPLES) + 0.5) * (CUT_SPAN * size_m / CUT_SAMPLES)
    x, y = np.meshgrid(grid, grid)
    noise, _ = _fractal_noise(x, y, 0.0, size_m, seed)
    noise.setflags(write=False)
    return noise, float(np.quantile(noise, 0.99))


@lru_cache(maxsize=32)
def _tabulated_cuts(share: float, size_m: float, seed: int) -> np.ndarray:
    """The cut of each of :data:`EDGE_WIDTHS` that leaves ``share`` of the tabulated noise
    covered, by bisection (read-only)."""
    noise = _tabulated_noise(size_m, seed)[0][::2, ::2]  # 256² points: the error is the layer's
    ordered = np.sort(noise, axis=None)
    cuts = []
    for width in EDGE_WIDTHS:
        low, high = float(ordered[0]) - width, float(ordered[-1]) + width
        for _ in range(40):  # the mean cover falls as the cut rises
            middle = 0.5 * (low + high)
            if _mean_soft_cover(ordered, middle, width) > share:
                low = middle
            else:
                high = middle
        cuts.append(0.5 * (low + high))
    table = np.array(cuts)
    table.setflags(write=False)
    return table


def _mean_soft_cover(ordered: np.ndarray, cut: float, half_width: float) -> float:
    """The mean of :func:`_soft_cut` over sorted noise values: 1 above the edge, 0 below it,
    so that only the values on the edge are evaluated."""
    start, end = np.searchsorted(ordered, (cut - half_width, cut + half_width))
    edge = _soft_cut(ordered[start:end], cut, half_width)
    return float((ordered.size - end + np.sum(edge)) / ordered.size)


def _transmission(optical_depth: np.ndarray) -> np.ndarray:
    """Diffuse transmission of a thick non-absorbing cloud layer (Kokhanovsky 2004)."""
    return 1.0 / (1.07 + 0.75 * (1.0 - CLOUD_ASYMMETRY) * optical_depth)


def _soft_cut(noise: np.ndarray, cut: float, half_width: np.ndarray | float) -> np.ndarray:
    """Cover 1 above ``cut + half_width``, 0 below ``cut − half_width``, a smoothstep
    between."""
    t = np.clip((noise - cut + half_width) / (2.0 * half_width), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def _resolved(footprint: np.ndarray | float, spacing: float) -> np.ndarray:
    """How much an octave of lattice ``spacing`` (m) is resolved by samples ``footprint`` (m)
    apart: 1 up to half a spacing, 0 from a whole one, a smoothstep between."""
    t = np.clip(2.0 - 2.0 * np.asarray(footprint, np.float64) / spacing, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def latlong_directions(rows: int, columns: int) -> np.ndarray:
    """World directions (rows × columns × 3, z up) of the pixels of a latitude–longitude sky
    image where the renderer's ``envmap`` reads them: row ``i`` at zenith angle
    ``π i/(rows − 1)`` (the top row at the zenith, the bottom at the nadir: Mitsuba spans the
    rows' centres from pole to pole), column ``j`` at azimuth ``2π(j + ½)/columns`` from +y
    toward +x (found by lighting one pixel and scanning the emitter; tests/test_clouds.py)."""
    theta = math.pi * np.arange(rows) / (rows - 1)
    phi = 2.0 * math.pi * (np.arange(columns) + 0.5) / columns
    sin_t, cos_t = np.sin(theta)[:, None], np.cos(theta)[:, None]
    return np.stack(np.broadcast_arrays(sin_t * np.sin(phi), sin_t * np.cos(phi), cos_t), axis=-1)


def broken_sky_radiance(
    clear: np.ndarray, deck_zenith: float, layer: CloudLayer, turbidity: float
) -> np.ndarray:
    """The broken sky as a latitude–longitude image: the clear sky's radiance ``clear`` (rows
    × columns × 3, laid out as :func:`latlong_directions`) where there is no cloud, and where
    there is, ``b(N)`` times the full deck's ``deck_zenith·(1 + 2 cos θ)/3`` (grey), seen
    through the air below the layer of the sky's ``turbidity`` (:func:`air_transmittance`),
    mixed by the cover (:meth:`CloudLayer.latlong_cover`)."""
    from .overcast import HORIZONTAL_IRRADIANCE_PER_ZENITH_RADIANCE, REC709_LUMINANCE, gradation

    rows, columns = clear.shape[:2]
    mu = np.cos(math.pi * np.arange(rows) / (rows - 1))
    t = air_transmittance(mu, layer.base_m, turbidity)
    # Irradiance weights of the rows (midpoint rule in θ over the upper hemisphere), and the
    # clear day's global luminance the deck was scaled from (overcast.zenith_radiance).
    weight = np.where(mu > 0.0, mu * np.sqrt(1.0 - mu * mu), 0.0) * (math.pi / (rows - 1))
    deck = gradation(mu)
    clear_row = (np.asarray(clear, np.float64) @ REC709_LUMINANCE).mean(axis=1) * 2.0 * math.pi
    g_clear = (
        deck_zenith
        * HORIZONTAL_IRRADIANCE_PER_ZENITH_RADIANCE
        / cloud_transmission(FULL_DECK_OKTAS)
    )
    brightness = cloud_brightness(
        layer.oktas,
        deck_seen=float(np.sum(weight * t * deck) / np.sum(weight * deck)),
        clear_lost=float(np.sum(weight * (1.0 - t) * clear_row)) / g_clear if g_clear else 0.0,
    )
    cover, shade = (a[..., None] for a in layer.latlong_cover(rows, columns))
    cloud = brightness * deck_zenith * deck[:, None, None] * shade
    seen = t[:, None, None]
    return (clear + cover * seen * (cloud - clear)).astype(np.float32)


MOLECULAR_OPTICAL_DEPTH = 0.097
"""Rayleigh optical depth of the whole atmosphere above sea level at 550 nm (Bucholtz 1995)."""

MOLECULAR_SCALE_HEIGHT_M = 8400.0
"""Scale height of the air's molecules (m)."""

AEROSOL_SCALE_HEIGHT_M = 1200.0
"""Scale height of the aerosol haze (m; Preetham et al. 1999)."""


def air_transmittance(cos_zenith: np.ndarray, height_m: float, turbidity: float) -> np.ndarray:
    """Transmittance ``exp(−τ(H)/μ)`` of the clear air from the sea up to ``height_m`` (m)
    along directions of zenith cosine ``cos_zenith`` (module docstring, "Aerial
    perspective"); 0 at and below the horizon."""
    tau = MOLECULAR_OPTICAL_DEPTH * (
        -np.expm1(-height_m / MOLECULAR_SCALE_HEIGHT_M)
        + (turbidity - 1.0) * -np.expm1(-height_m / AEROSOL_SCALE_HEIGHT_M)
    )
    mu = np.asarray(cos_zenith, np.float64)
    with np.errstate(divide="ignore", over="ignore"):
        return np.where(mu > 0.0, np.exp(-tau / np.where(mu > 0.0, mu, 1.0)), 0.0)
