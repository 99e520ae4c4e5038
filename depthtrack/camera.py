"""Pinhole depth camera in the OpenCV convention.

Camera frame: x right, y down, z forward (away from the camera), metres.
A depth image holds camera-frame z per pixel, 0 where there is no reading.
Pixel ``(u, v)`` = (column, row); the centre of the top-left pixel is (0, 0).
"""
from __future__ import annotations

from dataclasses import dataclass, asdict

import numpy as np

from .errors import InputError

#: Real intrinsics of common depth cameras at their native depth resolution.
#: SR4000: MESA Imaging data sheet (176 x 144, 43.6 x 34.6 deg field of view).
#: Kinect v2 depth: typical factory calibration (512 x 424, 70.6 x 60 deg).
#: Azure Kinect NFOV unbinned: typical factory calibration (640 x 576, 75 x 65 deg).
CAMERA_PRESETS = {
    "sr4000": dict(width=176, height=144, fx=220.0, fy=220.0, cx=88.0, cy=72.0),
    "kinect-v2": dict(width=512, height=424, fx=365.5, fy=365.5, cx=257.0, cy=210.0),
    "azure-nfov": dict(width=640, height=576, fx=504.0, fy=504.0, cx=320.0, cy=288.0),
}


@dataclass(frozen=True)
class Camera:
    """Pinhole intrinsics of a depth camera.

    Parameters
    ----------
    width, height : int
        Image size in pixels.
    fx, fy : float
        Focal lengths in pixels.
    cx, cy : float
        Principal point in pixels.
    """

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float

    def __post_init__(self):
        values = np.array([self.width, self.height, self.fx, self.fy, self.cx, self.cy], float)
        if not np.all(np.isfinite(values)) or self.width <= 0 or self.height <= 0 \
                or self.fx <= 0 or self.fy <= 0:
            raise InputError(None, f"invalid camera intrinsics {asdict(self)}")
        object.__setattr__(self, "width", int(self.width))
        object.__setattr__(self, "height", int(self.height))

    @classmethod
    def preset(cls, name: str) -> "Camera":
        """Camera from a preset name in :data:`CAMERA_PRESETS`."""
        try:
            return cls(**CAMERA_PRESETS[name])
        except KeyError:
            raise InputError(None, f"unknown camera preset {name!r}; known: "
                                   f"{', '.join(CAMERA_PRESETS)}") from None

    @classmethod
    def from_dict(cls, d: dict, path=None) -> "Camera":
        """Camera from the ``camera`` object of ``sequence.json``."""
        keys = ("width", "height", "fx", "fy", "cx", "cy")
        missing = [k for k in keys if k not in d]
        if missing:
            raise InputError(path, f"camera is missing {', '.join(missing)}")
        try:
            return cls(**{k: float(d[k]) if k not in ("width", "height") else int(d[k]) for k in keys})
        except (TypeError, ValueError) as exc:
            raise InputError(path, f"camera has a non-numeric value ({exc})") from None

    def to_dict(self) -> dict:
        return asdict(self)

    @property
    def matrix(self) -> np.ndarray:
        """(3, 3) float intrinsic matrix K."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    @property
    def shape(self) -> tuple[int, int]:
        """Image shape ``(height, width)`` as numpy orders it."""
        return (self.height, self.width)

    def project(self, points) -> np.ndarray:
        """Project camera-frame points to pixels.

        Parameters
        ----------
        points : (..., 3) float
            Camera-frame points, metres.

        Returns
        -------
        uv : (..., 2) float
            Pixel coordinates (column, row); NaN for points at or behind the camera.
        """
        p = np.asarray(points, dtype=float)
        z = p[..., 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            u = self.fx * p[..., 0] / z + self.cx
            v = self.fy * p[..., 1] / z + self.cy
        uv = np.stack([u, v], axis=-1)
        uv[z <= 0] = np.nan
        return uv

    def pixel_area(self, z) -> np.ndarray:
        """Surface area (m^2) one pixel covers on a surface facing the camera at depth ``z``:
        ``z^2 / (fx fy)``; any shape."""
        z = np.asarray(z, dtype=float)
        return z * z / (self.fx * self.fy)

    def rays(self) -> np.ndarray:
        """(H, W, 3) float: per-pixel ray directions with z = 1."""
        v, u = np.mgrid[0:self.height, 0:self.width].astype(float)
        return np.stack([(u - self.cx) / self.fx, (v - self.cy) / self.fy, np.ones_like(u)], axis=-1)

    def backproject(self, depth, uv=None) -> np.ndarray:
        """Back-project depth to camera-frame points.

        Parameters
        ----------
        depth : (H, W) float, or (M,) float with ``uv``
            Camera-frame z in metres; 0 = no reading (gives a zero point).
        uv : (M, 2) float, optional
            Pixel coordinates of the depths, when ``depth`` is not an image.

        Returns
        -------
        points : (H, W, 3) or (M, 3) float
        """
        depth = np.asarray(depth, dtype=float)
        if uv is None:
            if depth.shape != self.shape:
                raise InputError(None, f"depth image is {depth.shape[::-1]} (w x h), camera is "
                                       f"{self.width} x {self.height}")
            return self.rays() * depth[..., None]
        uv = np.asarray(uv, dtype=float)
        x = (uv[..., 0] - self.cx) / self.fx * depth
        y = (uv[..., 1] - self.cy) / self.fy * depth
        return np.stack([x, y, depth], axis=-1)

    def point_cloud(self, depth) -> np.ndarray:
        """(M, 3) float: the points of the pixels with a reading (depth > 0)."""
        pts = self.backproject(depth)
        return pts[np.asarray(depth) > 0]
