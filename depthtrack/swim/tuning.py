"""Noise levels estimated from data, not guessed: process noise from training frames, measurement noise from the measurements.

* The deviation model's decay ``rho`` and process noise ``Q`` (2A x 2A) of
  ``[angles, velocities]`` per frame: on the training take's own frames (at the
  evaluation's frame step, phase and speed from the training cycle starts),
  the deviations from the mean cycle ``e = theta - m(c)``, ``e_dot = omega - d(c) v L``
  (velocities by central differences); ``rho`` by least squares of
  ``e' = rho (e + e_dot)``, ``e_dot' = rho e_dot``, and ``Q`` the second moment of
  the residuals of that one-step prediction (bias included: the model's
  mean error is noise to the filter too).
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
from ..filters.rbpf import periodic_interp
from .stickfigure import continue_angles, equivalent_branch


def deviation_sequence(model: CyclicMotionModel, angles, starts, step: int = 1):
    """Deviations from the mean cycle on real frames, for the deviation model of
    :class:`depthtrack.filters.rbpf.CycleRBPF`.

    Parameters
    ----------
    angles : (F, A) float
        Angles of every frame of the take (continuous).
    starts : (K,) int
        Consecutive cycle-start frames (the phase is known between the first and the last).
    step : int
        Frame step of the filter (2: 60 Hz from 120 Hz mocap).

    Returns
    -------
    e, e_dot : (M, A) float
        Angle deviation ``theta - m(c)`` and velocity deviation ``omega - d(c) v L`` per filter
        frame (velocities are central differences; the first and last frame are dropped).
    """
    angles = np.asarray(angles, dtype=float)
    starts = np.asarray(starts, dtype=int)
    idx = np.arange(starts[0], starts[-1], step)
    if len(idx) < 5:
        return np.zeros((0, model.n_angles)), np.zeros((0, model.n_angles))
    phase, speed = cycle_phase(len(angles), starts)
    c, v = phase[idx], speed[idx] * step
    ref = model.interpolated(model.mean_angles, c[0])
    th = continue_angles(angles[idx], reference=ref)
    om = 0.5 * (th[2:] - th[:-2])
    th, c, v = th[1:-1], c[1:-1], v[1:-1]
    mean, flipped = equivalent_branch(periodic_interp(model.mean_angles, c), th)
    sign = np.ones(th.shape)
    sign[:, 0::2] = np.where(flipped, -1.0, 1.0)
    e = th - mean
    e_dot = om - sign * periodic_interp(model.mean_velocities, c) * (v * model.length)[:, None]
    return e, e_dot


def fit_reversion(pairs) -> float:
    """Least-squares decay ``rho`` of ``e' = rho (e + e_dot)``, ``e_dot' = rho e_dot`` over the
    ``[(e, e_dot), ...]`` sequences, clipped to [0, 1]."""
    num = den = 0.0
    for e, ed in pairs:
        if len(e) < 2:
            continue
        a, b = e[:-1] + ed[:-1], ed[:-1]
        num += float((e[1:] * a).sum() + (ed[1:] * b).sum())
        den += float((a * a).sum() + (b * b).sum())
    return float(np.clip(num / den, 0.0, 1.0)) if den > 0 else 1.0


def deviation_residuals(pairs, rho: float):
    """(M, 2A) one-step residuals ``[e' - rho (e + e_dot), e_dot' - rho e_dot]`` of the deviation model."""
    out = [np.concatenate([e[1:] - rho * (e[:-1] + ed[:-1]), ed[1:] - rho * ed[:-1]], axis=1)
           for e, ed in pairs if len(e) >= 2]
    return np.concatenate(out) if out else np.zeros((0, 0))


def training_noise(model: CyclicMotionModel, angles, cycles, step: int = 1):
    """Decay ``rho`` and the one-step residuals of the deviation model over the training cycles
    ``[(first, end), ...]`` (taken run by contiguous run).

    Returns ``rho`` and the (M, 2A) residuals.
    """
    cycles = sorted((int(a), int(b)) for a, b in cycles)
    runs = []
    for a, b in cycles:
        if runs and runs[-1][-1] == a:
            runs[-1].append(b)
        else:
            runs.append([a, b])
    pairs = [deviation_sequence(model, angles, starts, step) for starts in runs]
    rho = fit_reversion(pairs)
    return rho, deviation_residuals(pairs, rho)


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
