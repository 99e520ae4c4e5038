"""The thesis's evaluation (section 7.3) on motion capture: train, predict, compare.

Protocol (thesis 7.3.2, with real mocap instead of hand-marked video):

* training cycles come from the first part of a take, the test window from a
  later part (never overlapping when train and test are the same file);
* the test take is subsampled by ``step`` (default 2: 60 Hz from CMU's 120 Hz, so
  200 frames cover about 1.1 back-stroke cycles of this subject, whose cycles last
  ~2.9 s);
* the filter starts at test frame 0 — from the truth (angles, cycle progress and
  speed from the test take's cycle starts, angular velocities from the model's
  mean velocity at that progress) or at random — and then predicts and updates
  ``frames`` frames;
* the measurement of frame t is the true pose plus Gaussian noise of ``noise``
  rad per angle (a noisy observation of the truth), and the particle weights
  are an isotropic Gaussian of standard deviation ``sigma`` around it;
* the error of a frame is the squared angle error summed over the 26 angles
  (pole-equivalent representations count as equal), averaged over the frames;
  the report also gives the RMS angle (degrees) and the mean joint-position
  error of the stick figure (cm) built with the test take's segment lengths.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..filters.angles import wrap
from ..filters.particle import ParticleFilter, gaussian_angle_log_likelihood, kmeans_estimate
from ..filters.ukf import MerweScaledSigmaPoints, UnscentedKalmanFilter
from ..motion.cyclic import CyclicMotionModel
from .cycles import build_training_cycles, cycle_phase, detect_cycle_starts
from .mocap import SwimMocap, load_swim_mocap
from .stickfigure import (ANGLE_NAMES, angle_error_sq, angles_to_joints, continue_angles, joints_to_angles,
                          nearest_equivalent, segment_lengths)
from .training import train_motion_model


@dataclass
class TestWindow:
    """Ground truth of the test frames.

    Attributes
    ----------
    angles : (T + 1, 26) float
        True angles of test frames 0 .. T (frame 0 initialises).
    joints : (T + 1, 14, 3) float
    phase, speed : (T + 1,) float
        True cycle progress and speed (cycles per test frame).
    lengths : (13,) float
        Median segment lengths of the test take.
    first_frame : int
        Take frame of test frame 0.
    step : int
    fps : float
        Test frame rate.
    """

    angles: np.ndarray
    joints: np.ndarray
    phase: np.ndarray
    speed: np.ndarray
    lengths: np.ndarray
    first_frame: int
    step: int
    fps: float

    @property
    def frames(self) -> int:
        return len(self.angles) - 1


def _extrapolated_phase(n_frames, starts):
    phase, speed = cycle_phase(n_frames, starts)
    starts = np.asarray(starts)
    if len(starts) >= 2:
        last_len = starts[-1] - starts[-2]
        f = np.arange(starts[-1], n_frames)
        phase[f] = ((f - starts[-1]) / last_len) % 1.0
        speed[f] = 1.0 / last_len
        first_len = starts[1] - starts[0]
        f = np.arange(0, starts[0])
        phase[f] = ((f - starts[0]) / first_len) % 1.0
        speed[f] = 1.0 / first_len
    return phase, speed


def plan_split(train: SwimMocap, test: SwimMocap, frames: int, step: int, side: str = "right",
               stroke: str = "back"):
    """Choose the training range and the test window.

    Returns ``(last_train_frame, test_first_frame, test_starts)``. With the same take
    for both, the test window starts at the latest cycle start that leaves room
    for ``frames * step`` frames, and training uses only cycles ending at or before it.
    """
    span = frames * step
    test_starts = detect_cycle_starts(test.joints, test.fps, stroke, side)
    same = train.path is not None and test.path is not None and \
        Path(train.path).resolve() == Path(test.path).resolve()
    if same:
        candidates = [s for s in test_starts if s + span <= len(test) - 1]
        first = int(candidates[-1]) if candidates else len(test) - 1 - span
        if first < 0:
            raise InputError(test.path, f"take too short for {frames} test frames at step {step}")
        return first, first, test_starts
    candidates = [s for s in test_starts if s + span <= len(test) - 1]
    first = int(candidates[0]) if candidates else 0
    if first + span > len(test) - 1:
        raise InputError(test.path, f"take too short for {frames} test frames at step {step}")
    return None, first, test_starts


def make_test_window(test: SwimMocap, first: int, frames: int, step: int, starts) -> TestWindow:
    """Ground truth for test frames ``first, first + step, ...`` (``frames + 1`` of them)."""
    idx = first + step * np.arange(frames + 1)
    joints = test.joints[idx]
    angles = continue_angles(joints_to_angles(joints))
    phase, speed = _extrapolated_phase(len(test), starts)
    return TestWindow(angles, joints, phase[idx], speed[idx] * step,
                      np.median(segment_lengths(test.joints), axis=0), first, step, test.fps / step)


def measurements(window: TestWindow, noise: float, rng) -> np.ndarray:
    """Noisy observations of the true angles: ``(T + 1, 26)``."""
    return window.angles + noise * rng.standard_normal(window.angles.shape)


def initial_state(model: CyclicMotionModel, window: TestWindow):
    """Truth initialisation: angles (in the model's representation), velocities from the
    model's mean velocity at the true progress scaled to the true speed, progress, speed."""
    c0, v0 = float(window.phase[0]), float(window.speed[0])
    mean_pose = model.interpolated(model.mean_angles, c0)
    angles = nearest_equivalent(window.angles[0], mean_pose)
    velocities = model.interpolated(model.mean_velocities, c0) * v0 * model.length
    return angles, velocities, c0, v0


def frame_errors(estimates, window: TestWindow):
    """Per-frame squared angle error (T,), RMS angle (deg) and joint error (m) of ``estimates (T, 26)``
    against test frames 1 .. T."""
    truth = window.angles[1:]
    sq = angle_error_sq(estimates, truth).sum(axis=-1)
    j_est = angles_to_joints(estimates, window.lengths)
    j_true = angles_to_joints(truth, window.lengths)
    joint_err = np.linalg.norm(j_est - j_true, axis=-1).mean(axis=-1)
    return sq, joint_err


def summarise(sq, joint_err) -> dict:
    return {
        "error": float(np.mean(sq)),
        "rms_deg": float(np.degrees(np.sqrt(np.mean(sq) / len(ANGLE_NAMES)))),
        "joint_error_cm": float(100 * np.mean(joint_err)),
    }


def run_particle_filter(model: CyclicMotionModel, window: TestWindow, z, n_particles: int, sigma: float,
                        init: str = "truth", estimators=("map", "kmeans"), seed: int = 0, threads: int = 1,
                        kmeans_points: int = 5000, kmeans_iterations: int = 5, progress=None) -> dict:
    """Track the test window with the particle filter; errors of each estimator.

    Returns
    -------
    dict with ``estimates`` {name: (T, 26)}, ``phase`` (T,) of the MAP particle,
    ``speed`` (T,), ``seconds`` and ``ess`` (T,).
    """
    rng = np.random.default_rng(seed)
    if init == "truth":
        a0, v0, c0, s0 = initial_state(model, window)
        # The thesis starts from the correct angles; the spread is in progress and speed only.
        particles = model.particles_at(n_particles, a0, v0, c0, s0, rng, angle_spread=0.0,
                                       velocity_spread=0.0, phase_spread=0.01, speed_spread=0.05)
        previous = a0
    elif init == "random":
        particles = model.random_particles(n_particles, rng, speed_range=(0.3, 2.0))
        previous = z[0]
    else:
        raise InputError(None, f"unknown initialisation {init!r} (truth, random)")

    def transition(p, g, ancestors=None, out=None):
        return model.propagate(p, g, threads=threads, ancestors=ancestors, out=out)

    def loglik(p, zt):
        return gaussian_angle_log_likelihood(p["angles"], zt, sigma, threads=threads)

    def transition_and_score(p, g, zt, ancestors=None, out=None):
        return model.propagate(p, g, threads=threads, ancestors=ancestors, out=out, score=(zt, sigma))

    pf = ParticleFilter(particles, transition, loglik, rng, order_key=model.order_key, fused_resampling=True,
                        transition_and_score=transition_and_score)
    T = window.frames
    est = {name: np.empty((T, model.n_angles)) for name in estimators}
    phase = np.empty(T)
    speed = np.empty(T)
    ess = np.empty(T)
    kinfo = None
    start = time.perf_counter()
    for t in range(1, T + 1):
        zt = nearest_equivalent(z[t], previous)
        pf.step(zt.astype(np.float32))
        best = pf.map_particle
        if "map" in est:
            est["map"][t - 1] = best["angles"]
        if "kmeans" in est:
            distinct, counts = pf.distinct_posterior("angles")
            centre, kinfo = kmeans_estimate(distinct, 0.01, counts, max_points=kmeans_points,
                                            iterations=kmeans_iterations, rng=rng)
            est["kmeans"][t - 1] = centre
        phase[t - 1] = best["phase"]
        speed[t - 1] = best["speed"]
        ess[t - 1] = pf.ess
        previous = best["angles"].astype(float)
        if progress is not None:
            progress.update(1)
    seconds = time.perf_counter() - start
    return {"estimates": est, "phase": phase, "speed": speed, "ess": ess, "seconds": seconds,
            "kmeans": kinfo}


def run_ukf(model: CyclicMotionModel, window: TestWindow, z, sigma: float, init: str = "truth",
            seed: int = 0) -> dict:
    """Track the test window with the unscented Kalman filter and the same motion model."""
    A = model.n_angles
    rng = np.random.default_rng(seed)
    if init == "truth":
        a0, v0, c0, s0 = initial_state(model, window)
        x0 = np.concatenate([a0, v0, [c0, s0]])
        p0 = np.concatenate([np.full(A, 0.01 ** 2), np.full(A, 1e-4), [0.01 ** 2, (0.05 * s0) ** 2]])
    elif init == "random":
        c0 = rng.random()
        s0 = model.v_ref
        a0 = model.interpolated(model.mean_angles, c0)
        x0 = np.concatenate([a0, np.zeros(A), [c0, s0]])
        p0 = np.concatenate([np.full(A, np.pi ** 2 / 3), np.full(A, 1e-3), [1 / 12, (0.5 * s0) ** 2]])
    else:
        raise InputError(None, f"unknown initialisation {init!r} (truth, random)")

    def hx(sig):
        return sig[:, :A]

    def mean_x(sig, wm):
        ref = sig[0]
        return ref + np.tensordot(wm, model.state_residual(sig, ref), axes=(0, 0))

    def mean_z(sig, wm):
        ref = sig[0]
        return ref + np.tensordot(wm, wrap(sig - ref), axes=(0, 0))

    def process_noise(x):
        return model.process_noise(x) + 1e-10 * np.eye(model.dim)

    ukf = UnscentedKalmanFilter(x0, np.diag(p0), model.transition, hx, process_noise, np.eye(A) * sigma ** 2,
                                points=MerweScaledSigmaPoints(model.dim, alpha=0.1, beta=2.0, kappa=0.0),
                                residual_x=model.state_residual, residual_z=lambda a, b: wrap(a - b),
                                mean_x=mean_x, mean_z=mean_z, align_z=nearest_equivalent)
    T = window.frames
    est = np.empty((T, A))
    phase = np.empty(T)
    speed = np.empty(T)
    start = time.perf_counter()
    for t in range(1, T + 1):
        ukf.predict()
        if np.all(np.isfinite(z[t])):        # withheld frames (NaN): predict only
            ukf.update(z[t])
        ukf.x[2 * A] %= 1.0
        ukf.x[2 * A + 1] = max(ukf.x[2 * A + 1], 0.05 * model.v_ref)
        est[t - 1] = ukf.x[:A]
        phase[t - 1] = ukf.x[2 * A]
        speed[t - 1] = ukf.x[2 * A + 1]
    return {"estimates": {"mean": est}, "phase": phase, "speed": speed, "seconds": time.perf_counter() - start}


PROCESS_NOISE = ("training", "loo")


@dataclass
class SwimSetup:
    """Everything an evaluation needs: the trained model, the test window, the split."""

    model: CyclicMotionModel
    window: TestWindow
    train_sources: list
    train_path: str
    test_path: str
    units: str
    process_q: np.ndarray | None = None
    residual_count: int = 0
    velocity_decay: float = 1.0
    process_noise: str = "training"


def prepare(train_path, test_path, frames: int = 200, step: int = 2, length: int = 100,
            smooth_sigma: float = 2.0, derivative: str = "taylor3", temporal_sigma=None,
            train_starts=None, side: str = "right", units=None, test_start: int | None = None,
            stroke: str = "back", joint_map=None, process_noise: str = "training") -> SwimSetup:
    """Load the takes, split, train the model, estimate its process noise and cut the test window.

    ``test_start`` (a frame of the test take) places the test window there; with the
    same take for both, training then uses only the cycles that do not overlap it.
    ``process_noise``: ``training`` (the one-step residuals on the training cycles) or ``loo``
    (each cycle's residuals under a model trained without it, :func:`depthtrack.swim.tuning.loo_residuals`).
    """
    from .tuning import loo_residuals, process_noise_from_residuals, training_residuals

    if process_noise not in PROCESS_NOISE:
        raise InputError(None, f"unknown process noise estimate {process_noise!r} ({', '.join(PROCESS_NOISE)})")

    if frames < 1 or step < 1:
        raise InputError(None, "--frames and --step must be positive")
    train = load_swim_mocap(train_path, units, joint_map)
    same = Path(test_path).resolve() == Path(train_path).resolve()
    test = train if same else load_swim_mocap(test_path, units, joint_map)
    exclude = None
    if test_start is None:
        last_train, first, test_starts = plan_split(train, test, frames, step, side, stroke)
    else:
        if test_start < 0 or test_start + frames * step > len(test) - 1:
            raise InputError(test_path, f"--test-start {test_start}: the take has {len(test)} frames, "
                                        f"{frames} test frames at step {step} do not fit")
        last_train, first = None, int(test_start)
        test_starts = detect_cycle_starts(test.joints, test.fps, stroke, side)
        if same:
            exclude = (first, first + frames * step)
    training = build_training_cycles(train.joints, train.fps, starts=train_starts, length=length,
                                     smooth_sigma=smooth_sigma, side=side, last_frame=last_train,
                                     exclude=exclude, stroke=stroke)
    if len(training) < 2:
        raise InputError(train_path, f"only {len(training)} complete training cycle(s) outside the test window; "
                                     "need at least 2")
    model = train_motion_model(training, derivative, temporal_sigma=temporal_sigma)
    window = make_test_window(test, first, frames, step, test_starts)
    units_note = f"{train.units_m:.6g} m per BVH unit ({train.units_source})"
    own = [(s, e) for s, e, sd in training.sources if sd == side]
    train_angles = continue_angles(joints_to_angles(train.joints))
    # filtering: the thesis's model (rho = 1), its noise from one-step residuals; gaps: the decay
    # that predicts 1 to 30 frames ahead best on the training frames
    if process_noise == "loo":
        residuals = loo_residuals(training, train_angles, side, step, derivative, temporal_sigma)
    else:
        _, residuals = training_residuals(model, train_angles, own, step, rho=1.0)
    rho, _ = training_residuals(model, train_angles, own, step)
    q = process_noise_from_residuals(residuals) if len(residuals) else None
    return SwimSetup(model, window, training.sources, str(train_path), str(test_path), units_note, q,
                     len(residuals), rho, process_noise)
