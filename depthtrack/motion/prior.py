"""The tracker's temporal model: relative velocities with Gaussian accelerations (the ToF paper).

State at frame t: the pose ``x_t (48,)`` and its first discrete-time derivative ``v_t (48,)``.

* ``p(v_t | v_{t-1}) = N(damping * v_{t-1}, Sigma)``, ``Sigma`` diagonal (random accelerations).
* ``p(x_t | x_{t-1}, v_t)`` is deterministic: ``x_t = apply_velocity(x_{t-1}, v_t)``.

Velocities are *relative* transformations, like the pose itself: the pelvis translation
velocity is a camera-frame displacement (metres per frame) added to the translation, and
each joint's rotational velocity is a rotation vector (radians per frame) applied in that
joint's current local frame, ``R(x_t^j) = R(x_{t-1}^j) R(v_t^j)``. So the knee's velocity is
the change of the angle between shin and thigh, whatever the thigh does.

Frame-rate scaling of Sigma (derivation)
----------------------------------------
Let ``alpha`` be an angular (or linear) acceleration in rad/s^2 (m/s^2), held constant over one
frame of length ``dt = 1/fps`` and drawn independently per frame (the "piecewise constant
white acceleration" model). A rotation that turns at ``omega`` rad/s moves ``v = omega dt``
radians per frame. Over one frame omega changes by ``alpha dt``, so the per-frame velocity
changes by ``dv = (alpha dt) dt = alpha dt^2``. Hence

    std(v_t - v_{t-1}) = sigma_alpha * dt^2 = sigma_alpha / fps^2,

which is what :meth:`ConstantVelocityPrior.velocity_std` returns. ``sigma_alpha`` per pose
parameter comes from motion capture: ``tools/make_motion_prior.py`` retargets every BVH clip
onto the body model, resamples it to an analysis rate, takes second differences of the
relative pose (``v_t - v_{t-1}`` with the same relative velocity as here) and divides by
``dt^2``; it writes the root mean square (and a high percentile) per parameter to
``depthtrack/data/motion_prior.json``. A finite difference at a coarse analysis rate
under-estimates brief acceleration peaks; the file states the rate it was measured at.

Units: translation parameters m/s^2 (per frame: m/frame), rotations rad/s^2 (rad/frame).
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np

from ..body.rotations import compose_rotvec
from ..errors import InputError

#: Number of pose parameters and joints of the body model (pelvis translation + 15 rotations).
DOF = 48
NUM_ROTATIONS = 15

#: Shipped prior, made by tools/make_motion_prior.py.
DEFAULT_PRIOR_FILE = "motion_prior.json"


def apply_velocity(poses, velocities):
    """Apply relative velocities to poses: the deterministic CPD ``x_t = x_{t-1} (+) v_t``.

    Parameters
    ----------
    poses : (..., 48) float
        Poses ``x_{t-1}``.
    velocities : (..., 48) float
        ``[0:3]`` camera-frame displacement of the pelvis (m); then per joint a rotation
        vector applied in the joint's local frame (right-multiplied), broadcast with ``poses``.

    Returns
    -------
    (..., 48) float
        Poses ``x_t``; rotation vectors have angles in [0, pi].
    """
    x = np.asarray(poses, dtype=np.float64)
    v = np.asarray(velocities, dtype=np.float64)
    batch = np.broadcast_shapes(x.shape, v.shape)[:-1]
    out = np.empty(batch + (DOF,))
    out[..., :3] = x[..., :3] + v[..., :3]
    # each side converted at its own shape (one pose against many moves: converted once)
    rotations = compose_rotvec(x[..., 3:].reshape(x.shape[:-1] + (NUM_ROTATIONS, 3)),
                               v[..., 3:].reshape(v.shape[:-1] + (NUM_ROTATIONS, 3)))
    out[..., 3:] = rotations.reshape(batch + (DOF - 3,))
    return out


def pose_velocity(previous, poses):
    """The relative velocity that takes ``previous`` to ``poses`` (inverse of :func:`apply_velocity`).

    Parameters
    ----------
    previous, poses : (..., 48) float

    Returns
    -------
    (..., 48) float
        ``v`` with ``apply_velocity(previous, v) == poses`` (rotations up to the rotation-vector
        representation); rotational parts are the shortest rotations, angle in [0, pi].
    """
    a = np.asarray(previous, dtype=np.float64)
    b = np.asarray(poses, dtype=np.float64)
    a, b = np.broadcast_arrays(a, b)
    out = np.empty(a.shape)
    out[..., :3] = b[..., :3] - a[..., :3]
    shape = a.shape[:-1] + (NUM_ROTATIONS, 3)
    out[..., 3:] = compose_rotvec(-a[..., 3:].reshape(shape), b[..., 3:].reshape(shape)).reshape(
        a.shape[:-1] + (DOF - 3,))
    return out


def velocities_of(poses):
    """Per-frame relative velocities of a pose sequence: ``(F, 48) -> (F-1, 48)``."""
    poses = np.asarray(poses, dtype=np.float64)
    return pose_velocity(poses[:-1], poses[1:])


def accelerations_of(poses, fps: float):
    """Accelerations of a pose sequence in physical units (m/s^2, rad/s^2): ``(F, 48) -> (F-2, 48)``.

    ``(v_t - v_{t-1}) * fps^2`` with ``v`` from :func:`velocities_of` (see the module docstring).
    """
    v = velocities_of(poses)
    return np.diff(v, axis=0) * float(fps) ** 2


def huber_penalty(z, k: float):
    """``(..., D) -> (...)``: Huber's loss of standardised residuals ``z`` summed over the
    last axis, ``z^2 / 2`` where ``|z| <= k`` and ``k |z| - k^2 / 2`` beyond (continuous, with
    a continuous slope, at ``|z| = k``)."""
    a = np.abs(np.asarray(z, dtype=np.float64))
    return np.sum(np.where(a <= k, 0.5 * a * a, k * a - 0.5 * k * k), axis=-1)


@dataclass
class ConstantVelocityPrior:
    """``v_t ~ N(damping * v_{t-1}, Sigma)``, ``x_t = x_{t-1} (+) v_t``, with Sigma from mocap.

    Parameters
    ----------
    accel_std : (48,) float
        Standard deviation of the acceleration per pose parameter (m/s^2 or rad/s^2).
    fps : float
        Frame rate of the sequence being tracked; Sigma scales with ``1 / fps^4``.
    damping : float
        Factor on the previous velocity in the prediction (1 = the paper's constant-velocity
        model; below 1 damps velocities estimated from noisy poses).
    huber : float
        0 (default): the Gaussian penalty. Above 0: each parameter's penalty grows
        quadratically up to ``huber`` standard deviations from the prediction and linearly
        beyond (Huber's loss), the tails of a distribution with rare large accelerations: a
        kick or a spin, where the Gaussian's charge for a fast change outweighs the image.
    min_velocity_std : (48,) float or float
        Floor on the per-frame velocity standard deviation, so parameters that barely move
        in the training motions keep a usable search range.
    source : dict
        Where ``accel_std`` came from (file, clips, analysis rate).

    Attributes
    ----------
    velocity_std : (48,) float
        Per-frame standard deviation of ``v_t - damping v_{t-1}``.
    """

    accel_std: np.ndarray
    fps: float
    damping: float = 1.0
    huber: float = 0.0
    min_velocity_std: object = 0.0
    source: dict = field(default_factory=dict)

    def __post_init__(self):
        self.accel_std = np.asarray(self.accel_std, dtype=np.float64).reshape(-1)
        if self.accel_std.shape != (DOF,) or not np.all(np.isfinite(self.accel_std)) \
                or np.any(self.accel_std <= 0):
            raise InputError(None, f"motion prior needs {DOF} positive acceleration deviations")
        if not (np.isfinite(self.fps) and self.fps > 0):
            raise InputError(None, f"frame rate must be positive, got {self.fps}")
        self.fps = float(self.fps)

    # ------------------------------------------------------------------ construction
    @classmethod
    def load(cls, path=None, fps: float = 25.0, **kwargs) -> "ConstantVelocityPrior":
        """Read a prior file written by ``tools/make_motion_prior.py`` (default: the shipped one).

        Parameters
        ----------
        path : path-like or None
        fps : float
            Frame rate to scale the accelerations to.
        **kwargs
            ``damping``, ``min_velocity_std`` overrides.
        """
        if path is None:
            path = Path(str(resources.files("depthtrack") / "data" / DEFAULT_PRIOR_FILE))
        path = Path(path)
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise InputError(path, "motion prior file is missing (run tools/make_motion_prior.py)") from None
        except (OSError, ValueError) as exc:
            raise InputError(path, f"cannot read motion prior ({exc})") from None
        try:
            names = data["pose_names"]
            std = np.array([data["accel_std"][n] for n in names], dtype=np.float64)
        except (KeyError, TypeError) as exc:
            raise InputError(path, f"motion prior lacks {exc}") from None
        source = {k: data[k] for k in ("clips", "analysis_fps", "statistic", "made_by") if k in data}
        source["file"] = str(path)
        return cls(std, fps, source=source, **kwargs)

    @property
    def dt(self) -> float:
        return 1.0 / self.fps

    @property
    def velocity_std(self) -> np.ndarray:
        """(48,) per-frame std of the velocity change: ``accel_std * dt^2`` (floored)."""
        return np.maximum(self.accel_std * self.dt ** 2, self.min_velocity_std)

    @property
    def covariance(self) -> np.ndarray:
        """(48, 48) diagonal Sigma of ``v_t`` given ``v_{t-1}`` (per frame)."""
        return np.diag(self.velocity_std ** 2)

    # ------------------------------------------------------------------ model
    def predict_velocity(self, velocity):
        """Mean of ``p(v_t | v_{t-1})``: ``(..., 48) -> (..., 48)``."""
        return self.damping * np.asarray(velocity, dtype=np.float64)

    def predict(self, pose, velocity):
        """Predicted ``(x_t, v_t)`` means from ``x_{t-1} (48,)`` and ``v_{t-1} (48,)``."""
        v = self.predict_velocity(velocity)
        return apply_velocity(pose, v), v

    def mahalanobis(self, velocities, predicted_velocity):
        """Squared Mahalanobis distance of velocities from the prediction.

        Parameters
        ----------
        velocities : (..., 48) float
        predicted_velocity : (48,) float

        Returns
        -------
        (...) float ``sum(((v - v_pred) / sigma)^2)``; ``-log p(v_t | v_{t-1})`` is half of it
        (plus a constant).
        """
        d = (np.asarray(velocities, dtype=np.float64) - predicted_velocity) / self.velocity_std
        return np.sum(d * d, axis=-1)

    def penalty(self, poses, previous_pose, predicted_velocity):
        """``-log p(x_t, v_t | x_{t-1}, v_{t-1})`` up to a constant for candidate poses.

        Parameters
        ----------
        poses : (N, 48) or (48,) float
            Candidates ``x_t``.
        previous_pose : (48,) float
        predicted_velocity : (48,) float

        Returns
        -------
        (N,) or () float
        """
        velocities = pose_velocity(previous_pose, poses)
        if not self.huber:
            return 0.5 * self.mahalanobis(velocities, predicted_velocity)
        return huber_penalty((velocities - predicted_velocity) / self.velocity_std, self.huber)

    def to_dict(self) -> dict:
        return {"model": "v_t ~ N(damping v_{t-1}, Sigma), Sigma = diag(accel_std^2) / fps^4",
                "fps": self.fps, "damping": self.damping,
                **({"huber": self.huber} if self.huber else {}), **self.source}
