"""Temporal smoothing of tracked trajectories (optional, off by default).

A spec string chooses the filter (``--smooth`` on ``depthtrack track`` and ``export``):

* ``none``                  -- no smoothing (the default);
* ``savgol:W``              -- Savitzky-Golay, window ``W`` frames (odd, >= 3), quadratic fit;
  zero lag, keeps peaks better than a moving average;
* ``gaussian:SIGMA``        -- Gaussian kernel, ``SIGMA`` frames; zero lag;
* ``oneeuro:MINCUTOFF,BETA`` -- the One Euro filter (Casiez et al., CHI 2012): a causal
  low-pass whose cut-off rises with speed (``MINCUTOFF`` Hz at rest, ``+ BETA * |speed|``;
  derivative cut-off 1 Hz), so it suits live use; it lags a little.

Gaps are respected: frames without a value (NaN) stay NaN, and each run of known frames
between gaps is filtered on its own, so nothing leaks across a gap. A run shorter than a
Savitzky-Golay window uses the largest odd window that fits (runs of 1 or 2 frames stay
as they are).

Poses are smoothed as translations plus per-joint unit quaternions (made sign-continuous
before filtering, renormalised after), never as Euler angles or raw rotation vectors.
The raw track is never modified: callers smooth copies.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError

SMOOTHING_KINDS = ("none", "savgol", "gaussian", "oneeuro")

SMOOTH_HELP = ("temporal smoothing of the exported motion: none (default), savgol:W (window W frames, "
               "odd), gaussian:SIGMA (frames), oneeuro:MINCUTOFF,BETA (Hz, e.g. 1.0,0.3); gaps stay gaps")


@dataclass(frozen=True)
class Smoothing:
    """A parsed ``--smooth`` spec.

    Attributes
    ----------
    kind : str
        One of :data:`SMOOTHING_KINDS`.
    params : tuple of float
        ``(W,)`` for savgol, ``(sigma,)`` for gaussian, ``(min_cutoff, beta)`` for oneeuro.
    """

    kind: str = "none"
    params: tuple = ()

    @property
    def active(self) -> bool:
        return self.kind != "none"

    def __str__(self) -> str:
        if not self.params:
            return self.kind
        return f"{self.kind}:" + ",".join(f"{p:g}" for p in self.params)


def parse_smoothing(spec) -> Smoothing:
    """Parse a spec such as ``"savgol:9"``, ``"gaussian:1.5"``, ``"oneeuro:1.0,0.3"``, ``"none"``.

    Raises
    ------
    InputError
        An unknown filter or bad parameters (one line saying what is expected).
    """
    if spec is None or isinstance(spec, Smoothing):
        return spec or Smoothing()
    text = str(spec).strip().lower()
    kind, _, rest = text.partition(":")
    expected = {"none": "none", "savgol": "savgol:W (odd window, >= 3 frames)",
                "gaussian": "gaussian:SIGMA (frames, > 0)",
                "oneeuro": "oneeuro:MINCUTOFF,BETA (min cut-off in Hz > 0, beta >= 0)"}
    if kind not in expected:
        raise InputError(None, f"unknown smoothing {spec!r}; use one of: {', '.join(expected.values())}")
    try:
        params = tuple(float(p) for p in rest.split(",")) if rest else ()
    except ValueError:
        raise InputError(None, f"smoothing {spec!r}: parameters must be numbers; expected {expected[kind]}") from None
    ok = {
        "none": params == (),
        "savgol": len(params) == 1 and params[0] >= 3 and params[0] % 2 == 1,
        "gaussian": len(params) == 1 and math.isfinite(params[0]) and params[0] > 0,
        "oneeuro": (len(params) == 2 and all(math.isfinite(p) for p in params)
                    and params[0] > 0 and params[1] >= 0),
    }[kind]
    if not ok:
        raise InputError(None, f"smoothing {spec!r}: expected {expected[kind]}")
    return Smoothing(kind, params)


def finite_runs(valid) -> list:
    """``[(start, stop), ...]`` of the runs of True in ``valid (F,) bool``."""
    valid = np.asarray(valid, bool)
    edges = np.diff(np.concatenate([[0], valid.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))


def smooth_series(x, smoothing, fps: float) -> np.ndarray:
    """Smooth a trajectory along its first axis, gaps respected.

    Parameters
    ----------
    x : (F, ...) float
        NaN where unknown; a frame counts as known where all of its values are finite.
    smoothing : Smoothing or str
    fps : float
        Frames per second (the One Euro filter's cut-offs are in Hz).

    Returns
    -------
    (F, ...) float64, NaN exactly where ``x`` had an unknown frame.
    """
    smoothing = parse_smoothing(smoothing)
    x = np.asarray(x, dtype=np.float64)
    out = np.full_like(x, np.nan)
    flat = x.reshape(len(x), -1)
    valid = np.all(np.isfinite(flat), axis=1)
    out_flat = out.reshape(len(x), -1)
    for start, stop in finite_runs(valid):
        out_flat[start:stop] = _smooth_run(flat[start:stop], smoothing, fps)
    return out


def _smooth_run(run, smoothing, fps):
    """Filter one gap-free run ``(n, C)``."""
    n = len(run)
    if smoothing.kind == "none" or n < 2:
        return run.copy()
    if smoothing.kind == "savgol":
        from scipy.signal import savgol_filter
        window = min(int(smoothing.params[0]), n if n % 2 else n - 1)
        if window < 3:
            return run.copy()
        # a quadratic through 3 points is no filter: short runs fit a line instead
        return savgol_filter(run, window, polyorder=min(2, window - 2), axis=0, mode="interp")
    if smoothing.kind == "gaussian":
        from scipy.ndimage import gaussian_filter1d
        return gaussian_filter1d(run, smoothing.params[0], axis=0, mode="nearest")
    return one_euro(run, fps, *smoothing.params)


def _alpha(cutoff, fps):
    tau = 1.0 / (2.0 * np.pi * cutoff)
    return 1.0 / (1.0 + tau * fps)


def one_euro(x, fps: float, min_cutoff: float, beta: float, d_cutoff: float = 1.0) -> np.ndarray:
    """The One Euro filter along axis 0 of ``x (n, C)``, each column on its own; returns ``(n, C)``."""
    x = np.asarray(x, dtype=np.float64)
    out = np.empty_like(x)
    out[0] = x[0]
    dx = np.zeros(x.shape[1:])
    a_d = _alpha(d_cutoff, fps)
    for i in range(1, len(x)):
        raw_d = (x[i] - out[i - 1]) * fps
        dx = a_d * raw_d + (1.0 - a_d) * dx
        a = _alpha(min_cutoff + beta * np.abs(dx), fps)
        out[i] = a * x[i] + (1.0 - a) * out[i - 1]
    return out


def smooth_poses(poses, smoothing, fps: float) -> np.ndarray:
    """Smooth pose vectors of the body model (layout in :mod:`depthtrack.body.skeleton`).

    Parameters
    ----------
    poses : (F, D) float
        ``[0:3]`` root translation, then one rotation vector per joint; NaN rows = no pose.
    smoothing : Smoothing or str
    fps : float

    Returns
    -------
    (F, D) float64: translations filtered as they are; rotations filtered as unit
    quaternions (signs made continuous, renormalised) and turned back into rotation
    vectors. NaN rows stay NaN.
    """
    from ..body.rotations import quat_to_rotvec, rotvec_to_quat

    smoothing = parse_smoothing(smoothing)
    poses = np.asarray(poses, dtype=np.float64)
    if not smoothing.active:
        return poses.copy()
    F, D = poses.shape
    J = (D - 3) // 3
    valid = np.all(np.isfinite(poses), axis=1)
    quats = np.full((F, J, 4), np.nan)
    quats[valid] = rotvec_to_quat(poses[valid, 3:].reshape(-1, J, 3))
    for start, stop in finite_runs(valid):
        q = quats[start:stop]
        # q and -q are one rotation: flip each frame to the hemisphere of the one before
        for i in range(1, len(q)):
            flip = np.sum(q[i] * q[i - 1], axis=-1) < 0
            q[i, flip] *= -1.0
    out = np.full_like(poses, np.nan)
    out[:, :3] = smooth_series(poses[:, :3], smoothing, fps)
    q = smooth_series(quats, smoothing, fps)
    out[valid, 3:] = quat_to_rotvec(q[valid]).reshape(-1, 3 * J)
    return out
