"""A time-of-flight depth noise model (pure numpy, driven by a ``numpy.random.Generator``).

What a continuous-wave ToF camera (SR4000, Kinect v2, Azure Kinect) does to an ideal
depth image, in the order applied by :func:`apply_tof_noise`:

1. **Flying (mixed) pixels.** A pixel whose footprint straddles a depth
   discontinuity (a 4-neighbour differs by more than ``flying_threshold``) mixes
   the returns of the near and the far surface and reports a depth in between:
   with probability ``flying_probability`` it becomes ``a z_near + (1 - a) z_far``
   with ``a ~ U(0, 1)``; edges against "no reading" (0) are left alone.
2. **Depth-dependent Gaussian noise.** Phase noise grows with distance because the
   returned light falls off with z^2: ``sigma(z) = sigma_base + sigma_quadratic z^2``
   (metres), added independently per pixel.
3. **Dropouts.** Each valid pixel is lost (0) with probability ``dropout``
   (saturation, low amplitude, multipath rejected by the sensor).
4. **Range limits.** Readings beyond ``max_range`` (past the modulation's
   unambiguous range or too dark) or nearer than ``min_range`` are invalid (0).
5. **Quantisation** to the sequence's ``depth_scale`` (what the 16-bit PNG holds).

Default magnitudes follow the SR4000 data sheet (about 1 cm repeatability at 2-3 m,
5 m unambiguous range at 30 MHz); :data:`CAMERA_RANGES` gives the other presets'
operating ranges. The parameters are stored in ``sequence.json`` under
``synth.noise`` (:meth:`ToFNoise.to_dict`).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, replace

import numpy as np

#: (min_range, max_range) in metres of the camera presets' depth modes.
CAMERA_RANGES = {
    "sr4000": (0.1, 5.0),         # 30 MHz modulation: 5 m unambiguous range
    "kinect-v2": (0.5, 4.5),
    "azure-nfov": (0.5, 3.86),    # NFOV unbinned operating range
}


@dataclass(frozen=True)
class ToFNoise:
    """Parameters of the ToF noise model (see the module docstring).

    Attributes
    ----------
    sigma_base : float
        Metres of Gaussian noise at zero range.
    sigma_quadratic : float
        Metres of Gaussian noise per square metre of range.
    flying_threshold : float
        Depth jump (m) between 4-neighbours that makes an edge.
    flying_probability : float
        Chance that an edge pixel becomes a mixed pixel.
    dropout : float
        Chance that a valid pixel reads 0.
    min_range, max_range : float
        Valid reading interval, metres.
    depth_scale : float
        Quantisation step, metres (0 = none).
    """

    sigma_base: float = 0.003
    sigma_quadratic: float = 0.001
    flying_threshold: float = 0.10
    flying_probability: float = 0.5
    dropout: float = 0.002
    min_range: float = 0.1
    max_range: float = 5.0
    depth_scale: float = 0.001

    @classmethod
    def for_camera(cls, name: str, **changes) -> "ToFNoise":
        """Default parameters with the range of a camera preset."""
        lo, hi = CAMERA_RANGES.get(name, (cls.min_range, cls.max_range))
        return replace(cls(min_range=lo, max_range=hi), **changes)

    def sigma(self, z) -> np.ndarray:
        """Gaussian noise standard deviation (m) at range ``z (...)``."""
        z = np.asarray(z)
        z = z if z.dtype == np.float32 else z.astype(np.float64)
        return z.dtype.type(self.sigma_base) + z.dtype.type(self.sigma_quadratic) * z * z

    def to_dict(self) -> dict:
        return {"model": "tof", **asdict(self)}

    @classmethod
    def from_dict(cls, d: dict) -> "ToFNoise":
        return cls(**{k: v for k, v in d.items() if k != "model"})

    def apply(self, depth, rng: np.random.Generator) -> np.ndarray:
        """Noisy copy of ``depth``; see :func:`apply_tof_noise`."""
        return apply_tof_noise(depth, self, rng)


def edge_mask(depth, threshold: float):
    """Pixels on a depth discontinuity and the depth across it.

    Parameters
    ----------
    depth : (H, W) float
        0 = no reading (never makes an edge).
    threshold : float
        Metres.

    Returns
    -------
    edge : (H, W) bool
        Valid pixels with a valid 4-neighbour more than ``threshold`` farther or nearer.
    other : (H, W) float32
        For edge pixels, the neighbour depth with the largest jump.
    """
    z = np.asarray(depth, dtype=np.float32)
    best = np.zeros_like(z)
    other = np.zeros_like(z)
    # (this pixel's slice, its neighbour's slice) for the 4 neighbours
    pairs = (((slice(1, None), slice(None)), (slice(None, -1), slice(None))),
             ((slice(None, -1), slice(None)), (slice(1, None), slice(None))),
             ((slice(None), slice(1, None)), (slice(None), slice(None, -1))),
             ((slice(None), slice(None, -1)), (slice(None), slice(1, None))))
    for here, there in pairs:
        a, b = z[here], z[there]
        jump = np.abs(b - a)
        jump[(a <= 0) | (b <= 0)] = 0.0
        take = jump > best[here]
        best_view, other_view = best[here], other[here]
        best_view[take] = jump[take]
        other_view[take] = b[take]
    return best > threshold, other


def apply_tof_noise(depth, params: ToFNoise, rng: np.random.Generator) -> np.ndarray:
    """Apply the ToF noise model to an ideal depth image.

    Parameters
    ----------
    depth : (H, W) float
        Ideal camera-frame z, metres; 0 = nothing there.
    params : ToFNoise
    rng : numpy.random.Generator

    Returns
    -------
    noisy : (H, W) float32
        Metres; 0 = no reading.
    """
    z = np.asarray(depth, dtype=np.float32)
    valid = z > 0
    out = z.copy()
    edge, other = edge_mask(z, params.flying_threshold)
    fly = edge & (rng.random(z.shape, dtype=np.float32) < params.flying_probability)
    a = rng.random(int(fly.sum()), dtype=np.float32)
    out[fly] = a * z[fly] + (1 - a) * other[fly]
    out += rng.standard_normal(z.shape, dtype=np.float32) * params.sigma(out)
    out[rng.random(z.shape, dtype=np.float32) < params.dropout] = 0.0
    out[~valid | (out > params.max_range) | (out < params.min_range)] = 0.0
    if params.depth_scale > 0:
        out = np.rint(out / np.float32(params.depth_scale)) * np.float32(params.depth_scale)
    return out.astype(np.float32)


def noise_from_name(name: str, camera_name: str, depth_scale: float = 0.001):
    """``"tof"`` -> the camera's :class:`ToFNoise`; ``"none"`` -> None."""
    if name == "none":
        return None
    if name == "tof":
        return ToFNoise.for_camera(camera_name, depth_scale=depth_scale)
    raise ValueError(f"unknown noise model {name!r} (tof or none)")
