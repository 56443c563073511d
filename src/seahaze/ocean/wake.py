"""Ship waves and wakes: the Kelvin wave pattern, the bow wave and the turbulent foam wake of
moving vessels, as height and foam fields to add to the sea surface.

Waves
    The steady Kelvin wave field of each hull comes from :mod:`seahaze.ocean.kelvin` (Havelock's
    pressure ship, solved on a grid in the vessel's frame); here it is placed at the vessel's
    position and heading and sampled at world points. A turning vessel's pattern is bent along
    the arc it sailed: the grid is sampled at the points' track coordinates (below) instead of
    its straight frame. That is an approximation — it is the steady pattern of a straight
    course, bent; the waves of a ship on a turn differ (their sources sit on a curve, so the
    divergent waves spread on the outside of the turn and crowd on the inside). It is good where
    the turning radius ``R`` is large compared to the width of the wake: the Kelvin wedge is
    ``2·tan(19.47°)·s ≈ 0.7·s`` wide at ``s`` behind, so to about ``s ≈ R`` behind the vessel;
    near the turn's centre (``|eta| -> R`` on the inside) the bent field is squeezed.

Breaking (bow wave foam)
    Where the linear wave slope ``|grad zeta|`` exceeds :data:`BREAKING_SLOPE` (0.44, the slope
    amplitude ``a·k`` of the steepest Stokes wave, Michell 1893: ``H/lambda = 0.142``) the
    crest is taken to break and carries foam (a smooth ramp from 70 % of it).

Turbulent foam wake
    The propeller and hull leave a band of white, bubbly water behind the stern. It is centred
    on the track with a half-width ``b(s) = (B/2)·(1 + s/B)^(1/5)`` at distance ``s`` behind the
    stern: self-propelled (momentumless) turbulent wakes widen as the 1/5 power of distance
    (Tennekes & Lumley 1972, *A First Course in Turbulence*, §4.2; Naudascher 1965, *J. Fluid
    Mech.* 22, 625–656) — an approximation for a ship's wake, which is not axisymmetric. Its
    foam fraction is 1 at the stern and decays as ``exp(-s/(U·tau))`` with the water's age
    ``s/U``. The surface stays white while the bubbles the hull and propeller mixed in are still
    rising, so ``tau`` scales with the depth they were mixed to — taken as the hull's draft
    ``T`` (an assumption) — over the rise speed of millimetre air bubbles, about 0.2 m/s (Clift,
    Grace & Weber 1978, *Bubbles, Drops and Particles*, ch. 7): ``tau = T / 0.2 m/s``, at least
    2 s (:func:`wake_foam_decay_s`). A tanker of 12 m draft keeps a white wake for about a
    minute (half a kilometre at 14 kn, two ship lengths), a speedboat of 0.6 m for 3 s (50 m at
    30 kn). Cross profile: ``(1 - (eta/b)²)²``. The band follows the track the vessel sailed: on
    a turn it curves along the arc (``s`` and ``eta`` are track coordinates), centred on the
    circle the stern swept, ``sqrt(R² + (L/2)²)`` from the turn's centre — outside the midships
    circle by about ``L²/8R`` (1.7 m for a 30 m tug on a 66 m circle), where the propeller was.

Turning vessels (track coordinates)
    A vessel turning at a constant rate ``r`` (deg/s, counter-clockwise positive) at speed ``U``
    sails on a circle of radius ``R = U/|r|`` (:meth:`seahaze.motion.Course.pose`), its centre
    to port for ``r > 0`` and to starboard for ``r < 0``. A world point ahead of midships (along
    the current heading) keeps its straight-frame coordinates; a point behind gets
    ``xi = -R·phi``, the arc length back along the sailed circle to the angle ``phi`` it sits at
    about the centre (swept back from midships), and ``eta = ±(R - rho)``, its signed distance
    from the circle (``rho`` from the centre; positive to port). The two agree where they meet
    (on the line through midships and the centre, whose near side is tangent to the arc), so the
    fields stay continuous there. The past track is one circle: beyond half of it (``phi = π``)
    points would be ambiguous, and near ``π`` the far side of the circle meets the region ahead
    of the vessel. So the swept angle is limited to :data:`MAX_SWEPT_ANGLE_RAD` (0.9·π): points
    beyond get ``xi = -inf`` (outside every wake field), and the turning vessel's waves and foam
    fade out (smoothstep) over the last :data:`SWEPT_FADE_RAD` before it, so the limit draws no
    edge. (The sequence's vessel is taken to have been turning for as long as its wake is.) A
    straight course (``r = 0``) uses the straight frame unchanged.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .base import cell_samples, lowpass_weight, smoothstep
from .kelvin import BREAKING_SLOPE, wave_grid
from .spectra import GRAVITY

KNOT_M_S = 1852.0 / 3600.0
"""One knot (international nautical mile per hour) in m/s."""

BUBBLE_RISE_M_S = 0.2
"""Rise speed of millimetre air bubbles in sea water (m/s; Clift, Grace & Weber 1978)."""

MIN_WAKE_FOAM_DECAY_S = 2.0
"""Shortest e-folding age of wake foam (s), for hulls of almost no draft."""

FOAM_CUTOFF = 1.0e-3
"""Turbulent wake foam below this fraction is ignored when finding where a wake has foam."""

MAX_FOAM_SAMPLES = 16
"""Most samples per axis when a mesh vertex's footprint is averaged over the wake foam."""

MAX_SWEPT_ANGLE_RAD = 0.9 * math.pi
"""Largest angle (rad) a turning vessel's wake reaches back along its circle (module docstring):
below the half-circle, where points behind would become ambiguous."""

SWEPT_FADE_RAD = 0.25 * math.pi
"""Swept angle (rad) over which a turning vessel's waves and foam fade out before
:data:`MAX_SWEPT_ANGLE_RAD`."""


@dataclass(frozen=True)
class MovingVessel:
    """A vessel under way, as seen by the sea.

    Attributes:
        x, y: world position of midships (m).
        heading_deg: world azimuth the bow points to (deg, counter-clockwise from +x).
        speed_m_s: speed through the water (m/s); 0 makes no waves and no wake.
        length_m: waterline length (m).
        beam_m: beam (m).
        draft_m: draft (m).
        turn_rate_deg_s: rate of turn (deg/s, counter-clockwise positive); 0 sails straight.
            Its waves and wake follow the circle it sailed (module docstring).
    """

    x: float
    y: float
    heading_deg: float
    speed_m_s: float
    length_m: float
    beam_m: float
    draft_m: float
    turn_rate_deg_s: float = 0.0

    def __post_init__(self) -> None:
        if self.speed_m_s < 0.0 or min(self.length_m, self.beam_m, self.draft_m) <= 0.0:
            raise ValueError("speed must be >= 0 and length, beam, draft > 0")
        if not math.isfinite(self.turn_rate_deg_s):
            raise ValueError(f"turn rate must be finite, got {self.turn_rate_deg_s}")

    @property
    def froude_number(self) -> float:
        """Length Froude number ``U/sqrt(g·L)``."""
        return self.speed_m_s / math.sqrt(GRAVITY * self.length_m)

    def to_vessel_frame(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World (x, y) (m) → ``(xi, eta)``: metres ahead of midships and to port."""
        h = math.radians(self.heading_deg)
        dx = np.asarray(x, dtype=float) - self.x
        dy = np.asarray(y, dtype=float) - self.y
        return dx * math.cos(h) + dy * math.sin(h), -dx * math.sin(h) + dy * math.cos(h)

    @property
    def curvature_per_m(self) -> float:
        """Signed curvature of the track, ``r/U`` (1/m; positive turning to port, 1/R in
        magnitude); 0 on a straight course or at rest (no track to follow)."""
        if self.turn_rate_deg_s == 0.0 or self.speed_m_s == 0.0:
            return 0.0
        return math.radians(self.turn_rate_deg_s) / self.speed_m_s

    @property
    def stern_track_eta_m(self) -> float:
        """Track coordinate ``eta`` (m) of the circle the stern sweeps on a turn: about
        ``L²/8R`` outside the midships circle (to starboard on a turn to port),
        ``-κ(L/2)² / (1 + sqrt(1 + (κL/2)²))`` for the signed curvature ``κ``
        (:attr:`curvature_per_m`), the stable form of ``∓(sqrt(R² + (L/2)²) - R)``; 0 on a
        straight course."""
        half = 0.5 * self.length_m
        curvature = self.curvature_per_m
        return -curvature * half * half / (1.0 + math.hypot(1.0, curvature * half))

    def to_track_frame(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World (x, y) (m) → track coordinates ``(xi, eta)`` (m): signed distance along the
        sailed track from midships (negative behind) and signed distance to port of the track.

        Straight course: exactly :meth:`to_vessel_frame`. Turning: ahead of midships the
        straight frame, behind it the circle sailed (module docstring, "Turning vessels");
        points more than :data:`MAX_SWEPT_ANGLE_RAD` back around the circle get ``xi = -inf``.
        """
        xi, eta = self.to_vessel_frame(x, y)
        curvature = self.curvature_per_m
        if curvature == 0.0:
            return xi, eta
        return _bend_to_track(xi, eta, curvature)


def _bend_to_track(
    xi: np.ndarray, eta: np.ndarray, curvature: float
) -> tuple[np.ndarray, np.ndarray]:
    """Straight-frame ``(xi, eta)`` (m) → track coordinates on a circle of signed curvature
    ``curvature`` (1/m) through midships, tangent to the heading (module docstring)."""
    k = abs(curvature)
    # Position about the circle's centre (0, R·sign) in units of R: ``toward`` along the
    # centre-to-midships direction, ``back`` along the direction the vessel came from.
    back, toward = -k * xi, 1.0 - curvature * eta
    swept = np.arctan2(back, toward)  # angle swept back from midships (rad), (0, π) behind
    rho = np.hypot(back, toward)  # distance from the centre / R
    # eta = (1 - rho)/curvature, written without the cancellation of 1 - rho on gentle turns.
    eta_arc = (2.0 * eta - curvature * (xi * xi + eta * eta)) / (1.0 + rho)
    xi_arc = np.where(swept <= MAX_SWEPT_ANGLE_RAD, -swept / k, -np.inf)
    behind = xi < 0.0
    return np.where(behind, xi_arc, xi), np.where(behind, eta_arc, eta)


def wake_foam_decay_s(vessel: MovingVessel) -> float:
    """e-folding age (s) of the turbulent wake's foam: the hull draft over the bubbles' rise
    speed, ``T / 0.2 m/s``, at least :data:`MIN_WAKE_FOAM_DECAY_S` (module docstring)."""
    return max(vessel.draft_m / BUBBLE_RISE_M_S, MIN_WAKE_FOAM_DECAY_S)


class ShipWaves:
    """The steady wave field of one :class:`MovingVessel` on a grid in its own frame.

    ``height`` and ``slope`` sample it (bilinearly) at world points' track coordinates
    (:meth:`MovingVessel.to_track_frame`: the straight frame, or bent along a turn); zero
    outside the grid, ahead of the bow beyond one transverse wavelength, and beyond
    :func:`~seahaze.ocean.kelvin.wake_length_m`.
    """

    def __init__(self, vessel: MovingVessel, gravity: float = GRAVITY) -> None:
        self.vessel = vessel
        self.gravity = gravity
        self.moving = vessel.speed_m_s > 0.0
        if not self.moving:
            return
        grid = wave_grid(vessel.speed_m_s, vessel.length_m, vessel.beam_m, vessel.draft_m, gravity)
        self.wavelength_m = grid.wavelength_m
        self.length_behind_m = grid.length_behind_m
        self.ahead_m = grid.ahead_m
        self.spacing_m = grid.spacing_m
        self.origin = grid.origin
        self.shape = grid.height.shape
        self.grid = grid
        """The solved wave grid, shared by every vessel of this hull and speed."""
        self._height, self._slope = grid.height, grid.slope
        self._breaking_box = grid.breaking_box

    def _track(
        self, x: np.ndarray, y: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """Track coordinates ``(xi, eta)`` (m) of world points and, for a turning vessel, the
        weight (0–1) fading its fields out before :data:`MAX_SWEPT_ANGLE_RAD`; None when
        straight (no weight, so a straight course's values stay exactly as they were)."""
        xi, eta = self.vessel.to_track_frame(x, y)
        k = abs(self.vessel.curvature_per_m)
        if k == 0.0:
            return xi, eta, None
        # k·xi is minus the swept angle behind midships (and -inf beyond the limit).
        return xi, eta, smoothstep((MAX_SWEPT_ANGLE_RAD + k * xi) / SWEPT_FADE_RAD)

    def _sample(self, grid: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        xi, eta, fade = self._track(x, y)
        u = (xi - self.origin[0]) / self.spacing_m
        v = (eta - self.origin[1]) / self.spacing_m
        ny, nx = self.shape
        inside = (u >= 0.0) & (u <= nx - 1) & (v >= 0.0) & (v <= ny - 1)
        out = np.zeros(np.shape(u))
        if not np.any(inside):
            return out
        ui, vi = u[inside], v[inside]
        i0 = np.minimum(np.floor(ui).astype(np.int64), nx - 2)
        j0 = np.minimum(np.floor(vi).astype(np.int64), ny - 2)
        tu, tv = ui - i0, vi - j0
        top = grid[j0, i0] * (1.0 - tu) + grid[j0, i0 + 1] * tu
        bottom = grid[j0 + 1, i0] * (1.0 - tu) + grid[j0 + 1, i0 + 1] * tu
        out[inside] = top * (1.0 - tv) + bottom * tv
        return out if fade is None else out * fade

    def height(
        self, x: np.ndarray, y: np.ndarray, spacing_m: np.ndarray | float | None = None
    ) -> np.ndarray:
        """Wave elevation (m) of this vessel's waves at world points (x, y) (m).

        With a mesh vertex spacing ``spacing_m`` (m) the field is weighted by
        :func:`~seahaze.ocean.base.lowpass_weight` of the transverse wavelength, so a mesh too
        coarse to carry the waves gets none instead of aliases.
        """
        if not self.moving:
            return np.zeros(np.broadcast(np.asarray(x), np.asarray(y)).shape)
        out = self._sample(self._height, *np.broadcast_arrays(x, y))
        if spacing_m is not None:
            out = out * lowpass_weight(self.wavelength_m, spacing_m)
        return out

    def slope(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Wave slope magnitude ``|grad zeta|`` at world points (x, y) (m)."""
        if not self.moving:
            return np.zeros(np.broadcast(np.asarray(x), np.asarray(y)).shape)
        return self._sample(self._slope, *np.broadcast_arrays(x, y))

    def breaking_foam(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Foam fraction (0–1) of breaking ship waves: a smoothstep of the slope from
        ``0.7·BREAKING_SLOPE`` to :data:`BREAKING_SLOPE`."""
        s = self.slope(x, y)
        return smoothstep((s - 0.7 * BREAKING_SLOPE) / (0.3 * BREAKING_SLOPE))

    def turbulent_foam(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Foam fraction (0–1) of the turbulent wake behind the stern (module docstring)."""
        x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
        v = self.vessel
        if not self.moving:
            return np.zeros(x.shape)
        xi, eta, fade = self._track(x, y)
        if fade is not None:
            eta = eta - v.stern_track_eta_m  # on a turn, the band lies on the stern's circle
        s = -xi - 0.5 * v.length_m  # distance behind the stern along the track
        half_width = 0.5 * v.beam_m * (1.0 + np.maximum(s, 0.0) / v.beam_m) ** 0.2
        across = np.clip(1.0 - (eta / half_width) ** 2, 0.0, 1.0) ** 2
        age = np.maximum(s, 0.0) / v.speed_m_s
        # Ramp in over a tenth of the beam at the stern so the band starts softly.
        start = smoothstep(s / (0.1 * v.beam_m))
        foam = start * across * np.exp(-age / wake_foam_decay_s(v))
        return foam if fade is None else foam * fade

    def foam(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Foam fraction (0–1): turbulent wake and breaking waves, overlapping as independent
        coverages (``1 - (1 - a)(1 - b)``)."""
        a = self.turbulent_foam(x, y)
        if not self.moving:
            return a
        return 1.0 - (1.0 - a) * (1.0 - self.breaking_foam(x, y))

    def foam_region(self, x: np.ndarray, y: np.ndarray, margin_m: np.ndarray | float) -> np.ndarray:
        """True where a point (x, y) (m) lies within ``margin_m`` (m, world distance) of a region
        that can hold this vessel's foam: the turbulent wake until its foam is below
        :data:`FOAM_CUTOFF`, and the box of the grid cells steep enough to break — rectangles in
        track coordinates, which a turn bends into annular sectors (:func:`_near_track_box`)."""
        if not self.moving:
            return np.zeros(np.broadcast(np.asarray(x), np.asarray(y)).shape, dtype=bool)
        v = self.vessel
        xi, eta = v.to_vessel_frame(x, y)
        stern = -0.5 * v.length_m
        behind = v.speed_m_s * wake_foam_decay_s(v) * math.log(1.0 / FOAM_CUTOFF)
        half_width = 0.5 * v.beam_m * (1.0 + behind / v.beam_m) ** 0.2
        curvature = v.curvature_per_m
        if curvature != 0.0:
            centre = v.stern_track_eta_m
            wake = (stern - behind, stern, centre - half_width, centre + half_width)
            inside = _near_track_box(xi, eta, wake, margin_m, curvature)
            if self._breaking_box is not None:
                inside |= _near_track_box(xi, eta, self._breaking_box, margin_m, curvature)
            return inside
        inside = (
            (xi <= stern + margin_m)
            & (xi >= stern - behind - margin_m)
            & (np.abs(eta) <= half_width + margin_m)
        )
        box = self._breaking_box
        if box is not None:
            inside |= _near_box(xi, eta, box, margin_m)
        return inside

    @property
    def foam_feature_m(self) -> float:
        """Smallest foam feature (m): a quarter of the smaller of the beam (turbulent wake) and
        the transverse wavelength (breaking crests); inf at rest."""
        if not self.moving:
            return math.inf
        return 0.25 * min(self.vessel.beam_m, self.wavelength_m)

    def foam_averaged(
        self,
        x: np.ndarray,
        y: np.ndarray,
        azimuth_rad: np.ndarray,
        radial_m: np.ndarray,
        tangential_m: np.ndarray,
    ) -> np.ndarray:
        """Mean foam fraction over cells centred on world points (x, y) (m), 1-D arrays:
        ``radial_m`` long along the azimuth ``azimuth_rad`` and ``tangential_m`` across it (a
        polar mesh vertex's footprint). Cells larger than :attr:`foam_feature_m` are averaged
        over a grid of up to :data:`MAX_FOAM_SAMPLES`² points, so a wake narrower than the cell
        is neither missed between vertices nor spread over the whole cell at full strength."""
        out = np.zeros(np.shape(x))
        if not self.moving:
            return out
        cell = np.maximum(radial_m, tangential_m)
        index = np.nonzero(self.foam_region(x, y, cell))[0]
        n = np.clip(np.ceil(cell[index] / self.foam_feature_m), 1, MAX_FOAM_SAMPLES).astype(int)
        for count in np.unique(n):
            pick = index[n == count]
            sx, sy = cell_samples(
                x[pick], y[pick], azimuth_rad[pick], radial_m[pick], tangential_m[pick], int(count)
            )
            out[pick] = self.foam(sx, sy).mean(axis=1)
        return out


def _near_box(
    xi: np.ndarray,
    eta: np.ndarray,
    box: tuple[float, float, float, float],
    margin_m: np.ndarray | float,
) -> np.ndarray:
    """True where straight-frame points ``(xi, eta)`` (m) lie within ``margin_m`` of the box
    ``(xi_min, xi_max, eta_min, eta_max)`` grown per side (a square margin)."""
    return (
        (xi >= box[0] - margin_m)
        & (xi <= box[1] + margin_m)
        & (eta >= box[2] - margin_m)
        & (eta <= box[3] + margin_m)
    )


def _near_track_box(
    xi: np.ndarray,
    eta: np.ndarray,
    box: tuple[float, float, float, float],
    margin_m: np.ndarray | float,
    curvature: float,
) -> np.ndarray:
    """True where points, given in the straight frame ``(xi, eta)`` (m), lie within
    ``margin_m`` (m, world distance) of the world region whose track coordinates
    (:func:`_bend_to_track`, signed ``curvature`` in 1/m) fall in ``box``: its part ahead of
    midships is the straight box; its part behind is an annular sector about the turn's
    centre, cut at :data:`MAX_SWEPT_ANGLE_RAD`. Conservative: every point the margin reaches
    into the region passes (the test is the exact distance to the sector)."""
    xi_min, xi_max, eta_min, eta_max = box
    inside = np.zeros(np.broadcast(xi, eta, margin_m).shape, dtype=bool)
    if xi_max >= 0.0:
        inside |= _near_box(xi, eta, (max(xi_min, 0.0), xi_max, eta_min, eta_max), margin_m)
    k, sign = abs(curvature), math.copysign(1.0, curvature)
    radius = 1.0 / k
    phi_lo, phi_hi = -min(xi_max, 0.0) * k, min(-xi_min * k, MAX_SWEPT_ANGLE_RAD)
    # eta = sign·(R - rho): the sector's radii from the centre.
    r_lo, r_hi = sorted((radius - sign * eta_min, radius - sign * eta_max))
    if xi_min >= 0.0 or phi_lo > phi_hi or r_hi < 0.0:
        return inside
    r_lo = max(r_lo, 0.0)
    # Coordinates (m) about the centre: along the centre-to-midships direction and along the
    # direction the vessel came from; the swept angle is measured from the first to the second.
    toward, back = radius - sign * eta, -xi
    rho, phi = np.hypot(toward, back), np.arctan2(back, toward)
    # Within the sector's angles the nearest sector point lies on the same ray ...
    inside |= (
        (phi >= phi_lo) & (phi <= phi_hi) & (rho >= r_lo - margin_m) & (rho <= r_hi + margin_m)
    )
    # ... else on one of its two straight edges (the arcs' ends lie on them).
    for edge in (phi_lo, phi_hi):
        along = toward * math.cos(edge) + back * math.sin(edge)
        across = -toward * math.sin(edge) + back * math.cos(edge)
        gap = np.clip(along, r_lo, r_hi) - along
        inside |= gap * gap + across * across <= margin_m * margin_m
    return inside


class WakeField:
    """The waves and foam of several moving vessels, to be added to the sea surface.

    Heights add (linear waves superpose); foam fractions combine as independent coverages.
    ``height``/``foam`` take world positions (m); a mesh builder evaluates them at its
    vertices (:func:`seahaze.ocean.mesh.build_sea_mesh_data`, argument ``wakes``).
    """

    def __init__(self, vessels: Sequence[MovingVessel], gravity: float = GRAVITY) -> None:
        self.vessels = list(vessels)
        self.waves = [ShipWaves(v, gravity) for v in self.vessels]

    def height(
        self, x: np.ndarray, y: np.ndarray, spacing_m: np.ndarray | float | None = None
    ) -> np.ndarray:
        """Sum of the vessels' wave elevations (m) at world points (x, y), band-limited for a
        mesh vertex spacing ``spacing_m`` (m) if given (:meth:`ShipWaves.height`)."""
        total = np.zeros(np.broadcast(np.asarray(x), np.asarray(y)).shape)
        for waves in self.waves:
            total += waves.height(x, y, spacing_m)
        return total

    def foam(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Foam fraction (0–1) of all wakes at world points (x, y)."""
        clear = np.ones(np.broadcast(np.asarray(x), np.asarray(y)).shape)
        for waves in self.waves:
            clear *= 1.0 - waves.foam(x, y)
        return 1.0 - clear

    def reach_m(self, center_xy: tuple[float, float]) -> float:
        """Distance (m) from ``center_xy`` within which a mesh should resolve the wakes: per
        moving vessel, its distance plus half its length and the longer of one foam e-folding
        length and two transverse wavelengths behind the stern; 0 if none moves."""
        reach = 0.0
        for waves in self.waves:
            if not waves.moving:
                continue
            v = waves.vessel
            behind = max(v.speed_m_s * wake_foam_decay_s(v), 2.0 * waves.wavelength_m)
            distance = math.hypot(v.x - center_xy[0], v.y - center_xy[1])
            reach = max(reach, distance + 0.5 * v.length_m + behind)
        return reach

    def foam_averaged(
        self,
        x: np.ndarray,
        y: np.ndarray,
        azimuth_rad: np.ndarray,
        radial_m: np.ndarray,
        tangential_m: np.ndarray,
    ) -> np.ndarray:
        """Foam fraction (0–1) of all wakes averaged over polar mesh cells (1-D arrays; see
        :meth:`ShipWaves.foam_averaged`); vessels combine as independent coverages."""
        clear = np.ones(np.shape(x))
        for waves in self.waves:
            clear *= 1.0 - waves.foam_averaged(x, y, azimuth_rad, radial_m, tangential_m)
        return 1.0 - clear


def wake_height(vessels: Sequence[MovingVessel], x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Elevation (m) of the ship waves of ``vessels`` at world points (x, y) (m)."""
    return WakeField(vessels).height(x, y)


def wake_foam(vessels: Sequence[MovingVessel], x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Foam fraction (0–1) of the wakes of ``vessels`` at world points (x, y) (m)."""
    return WakeField(vessels).foam(x, y)
