"""The pinhole camera model shared by the renderer, the label projection and the tests.

World frame: Z up, metres, sea level at z = 0, camera at ``(0, 0, height)`` (a ship platform's
camera moves: ``(x_m, y_m, height)``). Heading is measured
counter-clockwise from +x, pitch upward from the horizontal, roll about the optical axis
positive clockwise as seen from behind the camera (its right side down: the horizon rises to
the right of the image with slope ``tan(roll)``). Image coordinates ``(u, v)`` are in
pixels with the origin at the top-left corner of the top-left pixel, ``u`` to the right and
``v`` down; pixel ``(i, j)`` covers ``[i, i+1) x [j, j+1)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .spec import CameraSpec


@dataclass(frozen=True)
class Camera:
    """A pinhole camera with a horizontal field of view and square pixels."""

    height_m: float
    fov_deg: float
    pitch_deg: float
    heading_deg: float
    width: int
    height: int
    x_m: float = 0.0
    """Horizontal position (m) of the camera: 0 but on a moving platform (a sequence's ship)."""
    y_m: float = 0.0
    roll_deg: float = 0.0
    """Roll about the optical axis (deg), positive right side down (module docstring)."""

    @classmethod
    def from_spec(cls, spec: CameraSpec) -> Camera:
        """The camera a scene spec describes."""
        width, height = spec.resolution
        return cls(
            spec.height_m,
            spec.fov_deg,
            spec.pitch_deg,
            spec.heading_deg,
            width,
            height,
            roll_deg=spec.roll_deg,
        )

    @property
    def origin(self) -> np.ndarray:
        """Camera position in world coordinates (m)."""
        return np.array([self.x_m, self.y_m, self.height_m])

    def basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Unit vectors ``(forward, right, up)`` of the camera in world coordinates.

        Without roll ``right`` is horizontal; a roll turns ``right`` and ``up`` about
        ``forward``, right side down for a positive roll (a right-handed turn about
        ``forward`` in a frame whose ``y`` points left, as a ship's roll is port up).
        """
        h, p = math.radians(self.heading_deg), math.radians(self.pitch_deg)
        forward = np.array([math.cos(p) * math.cos(h), math.cos(p) * math.sin(h), math.sin(p)])
        right = np.array([math.sin(h), -math.cos(h), 0.0])
        up = np.cross(right, forward)
        if self.roll_deg == 0.0:
            return forward, right, up  # exactly the unrolled basis: a level camera's bytes
        r = math.radians(self.roll_deg)
        return (
            forward,
            right * math.cos(r) - up * math.sin(r),
            up * math.cos(r) + right * math.sin(r),
        )

    def pointing(self, forward: np.ndarray, up: np.ndarray) -> Camera:
        """This camera turned so that its :meth:`basis` has ``forward`` and ``up`` (unit,
        perpendicular world vectors): the heading, pitch and roll that give them.

        Heading is ``atan2`` of ``forward`` (-180..180), so it may differ from this camera's
        by a multiple of 360.
        """
        f = np.asarray(forward, float)
        heading = math.degrees(math.atan2(f[1], f[0]))
        pitch = math.degrees(math.asin(max(-1.0, min(1.0, float(f[2])))))
        level = replace(self, heading_deg=heading, pitch_deg=pitch, roll_deg=0.0)
        _, right0, up0 = level.basis()
        u = np.asarray(up, float)
        # up = up0 cos(roll) + right0 sin(roll) (see basis).
        return replace(level, roll_deg=math.degrees(math.atan2(u @ right0, u @ up0)))

    @property
    def tan_half_fov_x(self) -> float:
        return math.tan(math.radians(self.fov_deg) / 2.0)

    @property
    def tan_half_fov_y(self) -> float:
        return self.tan_half_fov_x * self.height / self.width

    def ray_directions(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Unit world directions (..., 3) of rays through image points ``(u, v)`` in pixels."""
        forward, right, up = self.basis()
        x = (2.0 * np.asarray(u, float) / self.width - 1.0) * self.tan_half_fov_x
        y = (1.0 - 2.0 * np.asarray(v, float) / self.height) * self.tan_half_fov_y
        d = forward + x[..., None] * right + y[..., None] * up
        return d / np.linalg.norm(d, axis=-1, keepdims=True)

    def pixel_center_directions(self) -> np.ndarray:
        """Unit directions (H, W, 3) through every pixel centre."""
        v, u = np.mgrid[0 : self.height, 0 : self.width] + 0.5
        return self.ray_directions(u, v)

    def project(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Project world points (N, 3) to ``(u, v, in_front)``; ``in_front`` is False behind
        the camera."""
        forward, right, up = self.basis()
        rel = np.asarray(points, float) - self.origin
        z = rel @ forward
        in_front = z > 1e-9
        safe_z = np.where(in_front, z, 1.0)
        x = (rel @ right) / safe_z / self.tan_half_fov_x
        y = (rel @ up) / safe_z / self.tan_half_fov_y
        return (x + 1.0) * 0.5 * self.width, (1.0 - y) * 0.5 * self.height, in_front

    def horizon_elevation_deg(self) -> np.ndarray:
        """Elevation angle (deg) of every pixel-centre ray; negative rays look down at the sea."""
        d = self.pixel_center_directions()
        return np.degrees(np.arcsin(np.clip(d[..., 2], -1.0, 1.0)))

    def view_azimuth_half_width(self, samples_per_edge: int = 32) -> float:
        """Largest horizontal angle (rad) between the camera heading and any ray of the image,
        from rays along the image border; ``pi`` when the view holds the nadir or the zenith
        (every azimuth is then seen). Meshes use it to spend detail only where it is seen."""
        t = np.linspace(0.0, 1.0, samples_per_edge)
        u = np.concatenate([t, t, np.zeros_like(t), np.ones_like(t)]) * self.width
        v = np.concatenate([np.zeros_like(t), np.ones_like(t), t, t]) * self.height
        d = self.ray_directions(u, v)
        forward, right, up = self.basis()
        for pole in (np.array([0.0, 0.0, -1.0]), np.array([0.0, 0.0, 1.0])):
            depth = pole @ forward
            if depth > 0.0:
                x = (pole @ right) / depth / self.tan_half_fov_x
                y = (pole @ up) / depth / self.tan_half_fov_y
                if abs(x) <= 1.0 and abs(y) <= 1.0:
                    return math.pi
        heading = math.radians(self.heading_deg)
        azimuth = np.arctan2(d[:, 1], d[:, 0]) - heading
        return float(np.max(np.abs(np.angle(np.exp(1j * azimuth)))))
