"""The filters that beat the measurements: the Rao-Blackwellised particle filter, the tuned UKF and its smoother.

Both use noise levels estimated from data (:mod:`depthtrack.swim.tuning`): the
process noise of ``[angles, velocities]`` from the model's one-step residuals
on the training frames, the measurement noise from the measurements' third
differences. Measurements may be withheld (rows of NaN in ``z``: occlusion
gaps); the filters then only predict with the motion model.

* ``rbpf``: :class:`depthtrack.filters.rbpf.CycleRBPF`, particles on the cycle
  state (progress, speed), a shared Kalman filter for the 52 angles and
  velocities (Doucet et al. 2000); estimates ``mean`` (posterior mean) and
  ``map`` (the best particle's Kalman mean).
* ``ukf-tuned``: the thesis's UKF (same motion model and sigma points, plus the
  RBPF's fitted velocity decay) with the estimated ``Q`` and ``R`` instead of
  the per-phase training covariance and a guessed sigma.
* ``smoother``: the unscented RTS smoother (Särkkä 2008) over the tuned UKF,
  for offline use (it sees the whole window, including frames after a gap).

Inside a withheld stretch the RBPF's and the UKF's estimates are, by default
(``gap_prediction="sphere"``), the roll-out of their posterior mean at the last
measured frame with the same model integrated on the sphere of segment
directions (:mod:`depthtrack.swim.sphere`: a pass near the pole is a straight
line there, not a spin of the azimuth); ``gap_prediction="filter"`` keeps the
filter's own prediction in angles. Either way the filter itself predicts in
angles and picks up after the gap as before.
"""
from __future__ import annotations

import time

import numpy as np

from ..errors import InputError
from ..filters.angles import wrap
from ..filters.rbpf import CycleRBPF
from ..filters.smoother import rts_smooth
from ..filters.ukf import MerweScaledSigmaPoints, UnscentedKalmanFilter
from ..motion.cyclic import CyclicMotionModel
from .experiment import TestWindow, initial_state
from .sphere import gap_predictions, sphere_transition
from .stickfigure import nearest_equivalent, zenith_sign

GAP_PREDICTIONS = ("sphere", "filter")


def _initial(model: CyclicMotionModel, window: TestWindow, z, init: str, r_sigma: float, rng):
    """Kalman mean and covariance of ``[angles, velocities]`` and the initial cycle state."""
    A = model.n_angles
    if init == "truth":
        a0, v0, c0, s0 = initial_state(model, window)
        x0 = np.concatenate([a0, v0])
        p0 = np.concatenate([np.full(A, 0.01 ** 2), np.full(A, 1e-4)])
        return x0, np.diag(p0), c0, s0
    if init == "random":
        c0, s0 = float(rng.random()), model.v_ref
        x0 = np.concatenate([z[0], np.zeros(A)])
        p0 = np.concatenate([np.full(A, max(r_sigma, 1e-3) ** 2), np.full(A, 0.05 ** 2)])
        return x0, np.diag(p0), c0, s0
    raise InputError(None, f"unknown initialisation {init!r} (truth, random)")


def run_rbpf(model: CyclicMotionModel, window: TestWindow, z, n_particles: int, Q, r_sigma: float,
             init: str = "truth", seed: int = 0, progress=None, rho: float = 1.0, gap_rho=None,
             gap_prediction: str = "sphere") -> dict:
    """Track the window with :class:`CycleRBPF`.

    Parameters
    ----------
    z : (T + 1, A) float
        Measurements of frames 0 .. T; rows of NaN are withheld.
    Q : (2A, 2A) float
        Process noise of angles and velocities per frame.
    r_sigma : float
        Measurement noise per angle (rad).
    rho, gap_rho : float
        Velocity decay on measured and on withheld frames (:mod:`depthtrack.swim.tuning`; 1 = the
        thesis's model; ``gap_rho`` defaults to ``rho``).
    gap_prediction : str
        ``sphere`` or ``filter``: the estimates inside withheld stretches (module docstring).

    Returns
    -------
    dict with ``estimates`` {"mean", "map"} (T, A), ``phase``, ``speed``, ``ess`` (T,), ``seconds``,
    ``states`` {"mean", "map"} (T + 1, 2A + 2) posterior mean / best particle's state of frames 0 .. T
    (the mean's phase and speed are the posterior mean's at the last frame before a gap, elsewhere the
    best particle's), and with withheld frames ``filter_estimates`` (the
    filter's own predictions in angles).
    """
    rng = np.random.default_rng(seed)
    A = model.n_angles
    x0, P0, c0, s0 = _initial(model, window, z, init, r_sigma, rng)
    if init == "truth":
        phase = c0 + 0.01 * rng.standard_normal(n_particles)
        speed = s0 * (1 + 0.05 * rng.standard_normal(n_particles))
    else:
        phase = rng.random(n_particles)
        speed = model.v_ref * rng.uniform(0.3, 2.0, n_particles)
    phase -= np.floor(phase)
    f = CycleRBPF(model.mean_acceleration, Q, r_sigma ** 2, x0, P0, phase, speed,
                  temporal_sigma=model.temporal_sigma, circular=model.circular, rng=rng,
                  min_speed=0.05 * model.v_ref, velocity_table=model.mean_velocities, rho=rho,
                  gap_rho=gap_rho, input_sign=lambda angles: zenith_sign(angles, model.mean_angles))
    T = window.frames
    est = {"mean": np.empty((T, A)), "map": np.empty((T, A))}
    out_phase, out_speed, ess = np.empty(T), np.empty(T), np.empty(T)
    states = {k: np.empty((T + 1, model.dim)) for k in est}
    states["mean"][0] = states["map"][0] = np.concatenate([x0, [c0, s0]])
    previous = x0[:A]
    start = time.perf_counter()
    for t in range(1, T + 1):
        zt = None if not np.all(np.isfinite(z[t])) else nearest_equivalent(z[t], previous)
        f.step(zt)
        est["mean"][t - 1] = f.mean_x[:A]
        est["map"][t - 1] = f.map_x[:A]
        out_phase[t - 1], out_speed[t - 1], ess[t - 1] = f.map_phase, f.map_speed, f.ess
        states["mean"][t, :2 * A], states["map"][t, :2 * A] = f.mean_x, f.map_x
        states["map"][t, 2 * A:] = f.map_phase, f.map_speed
        # the mean state's cycle part: the posterior mean, needed only where a gap starts next frame
        gap_next = t < T and not np.all(np.isfinite(z[t + 1])) and zt is not None
        states["mean"][t, 2 * A:] = f.cycle_mean() if gap_next else (f.map_phase, f.map_speed)
        previous = f.mean_x[:A]
        if progress is not None:
            progress.update(1)
    seconds = time.perf_counter() - start
    out = {"estimates": est, "phase": out_phase, "speed": out_speed, "ess": ess, "seconds": seconds,
           "states": states}
    return _predict_gaps(out, states, model, z, gap_prediction, rho if gap_rho is None else gap_rho)


def _predict_gaps(out: dict, states: dict, model: CyclicMotionModel, z, gap_prediction: str, rho) -> dict:
    """With withheld frames in ``z`` and ``gap_prediction="sphere"``, each of ``out["estimates"]`` inside the
    gaps becomes the roll-out on the sphere (:func:`depthtrack.swim.sphere.gap_predictions`) of its
    ``states (T + 1, 2A + 2)`` (frames 0 .. T). A per-angle decay ``rho`` is averaged: the sphere's step
    moves each segment's direction as a whole."""
    if gap_prediction not in GAP_PREDICTIONS:
        raise InputError(None, f"unknown gap prediction {gap_prediction!r} ({', '.join(GAP_PREDICTIONS)})")
    mask = ~np.all(np.isfinite(np.asarray(z, dtype=float)), axis=1)
    mask[0] = False
    if gap_prediction == "filter" or not mask.any():
        return out
    fx = sphere_transition(model, float(np.mean(rho)))
    out["filter_estimates"] = out["estimates"]
    out["estimates"] = {k: gap_predictions(fx, states[k], mask, e) for k, e in out["estimates"].items()}
    return out


def decaying_transition(model: CyclicMotionModel, rho: float):
    """The thesis's transition (:meth:`CyclicMotionModel.transition`, mean acceleration interpolated in c)
    with the RBPF's velocity decay, ``omega' = rho omega + (1 - rho) d(c) v L + a``, and the learned
    velocity and acceleration in each sigma point's own branch (:func:`zenith_sign`: a segment whose
    state is the ``(-theta, phi + pi)`` representation of the mean stroke's gets their zenith part
    negated), for sigma points ``(K, 2A + 2)``."""
    A, L = model.n_angles, model.length
    rho = np.asarray(rho, dtype=float)

    def fx(x):
        x = np.array(np.atleast_2d(x), dtype=float)
        c, v = x[:, 2 * A], x[:, 2 * A + 1]
        sign = zenith_sign(x[:, :A], model.interpolated_rows(model.mean_angles, c))
        acc = sign * model.interpolated_rows(model.mean_acceleration, c) * ((v * L) ** 2)[:, None]
        vel = sign * model.interpolated_rows(model.mean_velocities, c) * (v * L)[:, None]
        drift = rho * x[:, A:2 * A] + (1 - rho) * vel
        x[:, :A] += drift + 0.5 * acc
        x[:, A:2 * A] = drift + acc
        x[:, 2 * A] = c + v
        return x

    return fx


def run_ukf_tuned(model: CyclicMotionModel, window: TestWindow, z, Q, r_sigma: float, init: str = "truth",
                  seed: int = 0, smooth: bool = True, rho: float = 1.0, gap_rho=None,
                  gap_prediction: str = "sphere") -> dict:
    """The UKF with the estimated noise, and (``smooth``) the unscented RTS smoother over it.

    ``gap_prediction``: ``sphere`` or ``filter``, the estimates inside withheld stretches (module
    docstring; the smoother is not affected).

    Returns
    -------
    dict with ``estimates`` {"mean"}, ``phase``, ``speed``, ``seconds``, ``states`` (T, 2A + 2) of frames
    1 .. T, with withheld frames ``filter_estimates`` (the filter's own predictions in angles) and, with
    ``smooth``, ``smoothed`` (a dict of the same form for the smoother).
    """
    A, D = model.n_angles, model.dim
    rng = np.random.default_rng(seed)
    x0, P0, c0, s0 = _initial(model, window, z, init, r_sigma, rng)
    if init == "truth":
        x0 = np.concatenate([x0, [c0, s0]])
        pc = [0.01 ** 2, (0.05 * s0) ** 2]
    else:
        x0 = np.concatenate([x0, [c0, s0]])
        pc = [1 / 12, (0.5 * s0) ** 2]
    P0 = np.block([[P0, np.zeros((2 * A, 2))], [np.zeros((2, 2 * A)), np.diag(pc)]])
    Qfull = model.process_noise(x0)              # the thesis's temporal block for (c, v)
    Qfull[:2 * A, :] = 0.0
    Qfull[:, :2 * A] = 0.0
    Qfull[:2 * A, :2 * A] = Q
    Qfull += 1e-10 * np.eye(D)

    def hx(sig):
        return sig[:, :A]

    def mean_x(sig, wm):
        return sig[0] + np.tensordot(wm, model.state_residual(sig, sig[0]), axes=(0, 0))

    def mean_z(sig, wm):
        return sig[0] + np.tensordot(wm, wrap(sig - sig[0]), axes=(0, 0))

    fx_measured = decaying_transition(model, rho)
    fx_gap = decaying_transition(model, rho if gap_rho is None else gap_rho)
    ukf = UnscentedKalmanFilter(x0, P0, fx_measured, hx, Qfull, np.eye(A) * r_sigma ** 2,
                                points=MerweScaledSigmaPoints(D, alpha=0.1, beta=2.0, kappa=0.0),
                                residual_x=model.state_residual, residual_z=lambda a, b: wrap(a - b),
                                mean_x=mean_x, mean_z=mean_z, align_z=nearest_equivalent)
    T = window.frames
    xs, Ps = np.empty((T + 1, D)), np.empty((T + 1, D, D))
    xp, Pp, Cs = np.empty((T + 1, D)), np.empty((T + 1, D, D)), np.empty((T + 1, D, D))
    xs[0], Ps[0] = ukf.x, ukf.P
    start = time.perf_counter()
    for t in range(1, T + 1):
        measured = bool(np.all(np.isfinite(z[t])))
        ukf.fx = fx_measured if measured else fx_gap
        ukf.predict()
        xp[t], Pp[t], Cs[t] = ukf.x_prior, ukf.P_prior, ukf.C
        if measured:
            ukf.update(z[t])
        ukf.x[2 * A] %= 1.0
        ukf.x[2 * A + 1] = max(ukf.x[2 * A + 1], 0.05 * model.v_ref)
        xs[t], Ps[t] = ukf.x, ukf.P
    seconds = time.perf_counter() - start
    out = {"estimates": {"mean": xs[1:, :A].copy()}, "phase": xs[1:, 2 * A].copy(), "speed": xs[1:, 2 * A + 1].copy(),
           "seconds": seconds, "states": xs[1:].copy()}
    if smooth:
        start = time.perf_counter()
        xs_s, _ = rts_smooth(xs, Ps, xp, Pp, Cs, residual=model.state_residual)
        out["smoothed"] = {"estimates": {"mean": xs_s[1:, :A]}, "phase": np.mod(xs_s[1:, 2 * A], 1.0),
                           "speed": xs_s[1:, 2 * A + 1], "seconds": seconds + time.perf_counter() - start}
    return _predict_gaps(out, {"mean": xs}, model, z, gap_prediction, rho if gap_rho is None else gap_rho)
