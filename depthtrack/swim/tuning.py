"""Noise levels estimated from data, not guessed: process noise from training frames, measurement noise
from the measurements.

* Velocity decay ``rho`` (:class:`depthtrack.filters.rbpf.CycleRBPF`): the value
  on a grid in [0.5, 1] whose deterministic predictions 1 to 30 frames ahead
  (the gap lengths of interest) fit the training frames best.
* Process noise ``Q`` (2A x 2A) of ``[angles, velocities]`` per frame: the
  residuals of the motion model's one-step prediction on the training take's
  own frames (at the evaluation's frame step, phase and speed from the
  training cycle starts). Velocities are central differences of the angles;
  the residual of frame t is ``x_{t+1} - F x_t - u(c_t, v_t)`` and ``Q`` its
  second moment (bias included: the model's mean error is noise to the
  filter too). In-sample residuals are too small for a frame the model was
  not trained on (the mean stroke was fitted to the very cycles it is
  scored on: with n cycles, a cycle's deviation from a mean that includes it
  is (n - 1) / n of its deviation from the true mean), so
  ``process_noise="loo"`` (:func:`loo_residuals`) scores each training
  cycle with a model trained on the cycles that do not overlap it (leave one
  cycle out, the cross-validation estimate of prediction error; Hastie,
  Tibshirani & Friedman, *Elements of Statistical Learning*, 7.10).
* Measurement noise ``sigma^2`` per angle: from the measurements alone, by
  the third difference. For white noise, ``Var(Delta^3 z) = 20 sigma^2``
  (binomial coefficients 1, 3, 3, 1 squared and summed); the swimmer's own
  motion at 60 Hz contributes little to it (126_01, truth only: mean
  ``(Delta^3 theta)^2 = 4.3e-5`` rad^2, i.e. a bias of 2e-6 rad^2 on
  ``sigma^2``, 0.1 % at sigma = 0.05). The median of the squared differences
  divided by its chi-square(1) median (0.455) makes it robust to outliers.
"""
from __future__ import annotations

import numpy as np

from ..filters.angles import wrap
from ..motion.cyclic import CyclicMotionModel
from .cycles import cycle_phase
from .stickfigure import continue_angles, zenith_sign


def _training_frames(model: CyclicMotionModel, angles, starts, step: int):
    """Angles, velocities (central differences), mean acceleration and mean velocity per filter frame
    between the first and last cycle start: four (M, A) arrays (M may be 0)."""
    angles = np.asarray(angles, dtype=float)
    starts = np.asarray(starts, dtype=int)
    idx = np.arange(starts[0], starts[-1], step)
    A = model.n_angles
    if len(idx) < 5:
        return (np.zeros((0, A)),) * 4
    phase, speed = cycle_phase(len(angles), starts)
    c, v = phase[idx], speed[idx] * step
    th = continue_angles(angles[idx], reference=model.interpolated(model.mean_angles, c[0]))
    om = 0.5 * (th[2:] - th[:-2])
    cell = model.index(c)[1:-1]
    r = (v * model.length)[1:-1, None]
    # the learned tables in each frame's own branch (a continuous trajectory can be in the other one)
    sign = zenith_sign(th[1:-1], model.mean_angles[cell])
    return th[1:-1], om, sign * model.mean_acceleration[cell] * r ** 2, sign * model.mean_velocities[cell] * r


def predict_ahead(theta, omega, acc, vel, rho: float, horizon: int):
    """Deterministic k-step predictions of the angles, k = 1 .. horizon, from every frame t, with the
    mean acceleration and velocity of the true later frames (the cycle state known):
    ``(horizon, M - horizon, A)`` predictions of ``theta[t + k]``."""
    M = len(theta)
    n = M - horizon
    th, om = theta[:n].copy(), omega[:n].copy()
    out = np.empty((horizon, n, theta.shape[1]))
    for k in range(horizon):
        a, d = acc[k:k + n], vel[k:k + n]
        th = th + rho * om + (1 - rho) * d + 0.5 * a
        om = rho * om + (1 - rho) * d + a
        out[k] = th
    return out


def fit_velocity_decay(frames, horizon: int = 30, grid=np.linspace(0.5, 1.0, 51)) -> float:
    """The ``rho`` of :class:`depthtrack.filters.rbpf.CycleRBPF` that predicts the training frames best
    over 1 .. ``horizon`` frames ahead (mean squared wrapped angle error; ``frames`` a list of
    :func:`_training_frames` tuples)."""
    best, best_err = 1.0, np.inf
    for rho in grid:
        err = n = 0.0
        for th, om, acc, vel in frames:
            if len(th) <= horizon:
                continue
            pred = predict_ahead(th, om, acc, vel, rho, horizon)
            truth = np.stack([th[k + 1:k + 1 + len(th) - horizon] for k in range(horizon)])
            err += float((wrap(pred - truth) ** 2).sum())
            n += pred.size
        if n and err / n < best_err:
            best, best_err = float(rho), err / n
    return best


def one_step_residuals(model: CyclicMotionModel, angles, starts, step: int = 1, first=None, last=None,
                       rho: float = 1.0):
    """Residuals of the model's one-step prediction on real frames.

    Parameters
    ----------
    model : CyclicMotionModel
    angles : (F, A) float
        Angles of every frame of the training take (continuous, :func:`continue_angles`).
    starts : (K,) int
        Cycle-start frames of the take (the phase is known between them).
    step : int
        Frame step of the filter (2: 60 Hz from 120 Hz mocap).
    first, last : int, optional
        Use only frames in ``[first, last]`` (the training range).

    rho : float
        Velocity decay of the model (1: the thesis's).

    Returns
    -------
    (M, 2A) float residuals of ``[angles, velocities]`` per filter frame.
    """
    angles = np.asarray(angles, dtype=float)
    starts = np.asarray(starts, dtype=int)
    lo = starts[0] if first is None else max(starts[0], first)
    hi = starts[-1] - 1 if last is None else min(starts[-1] - 1, last)
    idx = np.arange(lo, hi + 1, step)
    if len(idx) < 5:
        return np.zeros((0, 2 * model.n_angles))
    phase, speed = cycle_phase(len(angles), starts)
    c, v = phase[idx], speed[idx] * step
    ref = model.interpolated(model.mean_angles, c[0])
    th = continue_angles(angles[idx], reference=ref)
    om = np.full_like(th, np.nan)
    om[1:-1] = 0.5 * (th[2:] - th[:-2])
    cell = model.index(c)
    sign = zenith_sign(th, model.mean_angles[cell])         # the tables in each frame's own branch
    acc = sign * model.mean_acceleration[cell] * model.acceleration_scale(v)[:, None]
    vel = sign * model.mean_velocities[cell] * (v * model.length)[:, None]
    t = np.arange(1, len(idx) - 2)
    drift = (1 - rho) * vel[t] + 0.5 * acc[t]
    r_th = wrap(th[t + 1] - th[t] - rho * om[t] - drift)
    r_om = om[t + 1] - rho * om[t] - (1 - rho) * vel[t] - acc[t]
    return np.concatenate([r_th, r_om], axis=1)


def training_residuals(model: CyclicMotionModel, angles, cycles, step: int = 1, rho=None, horizon: int = 30):
    """Velocity decay and one-step residuals over the training cycles ``[(first, end), ...]``, taken run
    by contiguous run.

    ``rho`` None: fitted by :func:`fit_velocity_decay` (``horizon`` frames ahead).

    Returns ``rho`` and the (M, 2A) residuals.
    """
    cycles = sorted((int(a), int(b)) for a, b in cycles)
    runs = []
    for a, b in cycles:
        if runs and runs[-1][-1] == a:
            runs[-1].append(b)
        else:
            runs.append([a, b])
    if rho is None:
        rho = fit_velocity_decay([_training_frames(model, angles, st, step) for st in runs], horizon)
    out = [one_step_residuals(model, angles, st, step, rho=rho) for st in runs]
    return rho, (np.concatenate(out) if out else np.zeros((0, 2 * model.n_angles)))


def loo_residuals(training, angles, side: str, step: int = 1, derivative: str = "taylor3",
                  temporal_sigma=None, rho: float = 1.0):
    """One-step residuals of each ``side`` training cycle under a model trained without it.

    Parameters
    ----------
    training : depthtrack.swim.cycles.TrainingCycles
        All training cycles (both sides); for cycle ``(first, end, side)`` the model is trained on the
        cycles whose frames do not overlap ``[first, end)`` (the other arm's mirrored cycles of the same
        frames are left out too). Cycles with fewer than one such other cycle are skipped.
    angles : (F, A) float
        Continuous angles of every frame of the training take.
    side, step, derivative, temporal_sigma, rho
        As for :func:`one_step_residuals` and :func:`depthtrack.swim.training.train_motion_model`.

    Returns
    -------
    (M, 2A) float residuals (M may be 0).
    """
    from .cycles import TrainingCycles
    from .training import train_motion_model

    sources = training.sources
    out = [np.zeros((0, 2 * angles.shape[1]))]
    for first, end, sd in sources:
        if sd != side:
            continue
        keep = [i for i, (a, b, _) in enumerate(sources) if b <= first or a >= end]
        if not keep:
            continue
        rest = TrainingCycles(training.extended[keep], training.margin, [sources[i] for i in keep])
        model = train_motion_model(rest, derivative, temporal_sigma=temporal_sigma)
        out.append(one_step_residuals(model, angles, [first, end], step, rho=rho))
    return np.concatenate(out)


def process_noise_from_residuals(residuals, floor: float = 1e-8):
    """``(M, D)`` residuals -> ``(D, D)`` second-moment matrix, plus ``floor`` on the diagonal."""
    r = np.asarray(residuals, dtype=float)
    if len(r) == 0:
        raise ValueError("no residuals to estimate the process noise from")
    return r.T @ r / len(r) + floor * np.eye(r.shape[1])


def estimate_measurement_noise(z) -> float:
    """Per-angle measurement noise standard deviation (rad) from ``z (T, A)`` alone (module docstring).

    Rows with NaN (withheld frames) are skipped; differences only over consecutive present rows.
    """
    z = np.asarray(z, dtype=float)
    ok = np.all(np.isfinite(z), axis=1)
    d3 = wrap(z[3:] - 3 * z[2:-1] + 3 * z[1:-2] - z[:-3])
    valid = ok[3:] & ok[2:-1] & ok[1:-2] & ok[:-3]
    sq = d3[valid] ** 2
    if sq.size == 0:
        raise ValueError("need at least 4 consecutive measured frames to estimate the noise")
    return float(np.sqrt(np.median(sq) / 0.4549364 / 20.0))
