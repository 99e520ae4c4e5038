"""Temporal smoothing of exports: less noise on a noisy line, gaps kept, specs checked."""
import numpy as np
import pytest

from depthtrack.body.rotations import rotvec_to_quat
from depthtrack.errors import InputError
from depthtrack.motion.smoothing import parse_smoothing, smooth_poses, smooth_series

FPS = 30.0


def _noisy_line(n=120, gap=(50, 60), seed=1, speed=0.5):
    t = np.arange(n) / FPS
    truth = np.stack([speed * t, -0.4 * speed * t + 1.0, np.full(n, 3.0)], axis=1)   # a straight walk
    noisy = truth + np.random.default_rng(seed).normal(0.0, 0.01, truth.shape)
    noisy[gap[0]:gap[1]] = np.nan
    return truth, noisy


@pytest.mark.parametrize("spec, speed", [("savgol:9", 0.5), ("gaussian:2", 0.5), ("oneeuro:1.0,0.0", 0.01)])
def test_smoothing_reduces_noise_and_keeps_gaps(spec, speed):
    # the One Euro filter is causal: it lags on a moving point (by speed / (2 pi cut-off)
    # with beta 0), so it is checked on a slow one; beta is what cuts the lag (below)
    truth, noisy = _noisy_line(speed=speed)
    out = smooth_series(noisy, spec, FPS)
    gap = np.isnan(noisy).any(axis=1)
    assert np.array_equal(np.isnan(out).any(axis=1), gap)          # gaps stay gaps, nothing else is lost
    before = np.sqrt(np.mean((noisy[~gap] - truth[~gap]) ** 2))
    after = np.sqrt(np.mean((out[~gap] - truth[~gap]) ** 2))
    assert after < 0.6 * before, (spec, before, after)


def test_one_euro_beta_cuts_the_lag_on_fast_motion():
    truth, noisy = _noisy_line(speed=1.0, gap=(0, 0))
    lag = [np.abs(smooth_series(noisy, f"oneeuro:1.0,{beta}", FPS) - truth)[10:].mean() for beta in (0, 20)]
    assert lag[1] < 0.3 * lag[0]


def test_runs_are_filtered_separately():
    """A jump across a gap does not leak into the frames either side of it."""
    x = np.zeros((40, 1))
    x[20:] = 1.0
    x[18:22] = np.nan
    out = smooth_series(x, "gaussian:3", FPS)
    assert np.allclose(out[:18], 0.0) and np.allclose(out[22:], 1.0)


def test_none_is_the_identity_and_specs_are_checked():
    _, noisy = _noisy_line()
    assert np.array_equal(smooth_series(noisy, "none", FPS), noisy, equal_nan=True)
    assert str(parse_smoothing("oneeuro:1,0.3")) == "oneeuro:1,0.3"
    for bad in ("savgol:4", "savgol", "gaussian:-1", "oneeuro:1", "median:3", "savgol:x"):
        with pytest.raises(InputError):
            parse_smoothing(bad)


def test_pose_rotations_are_smoothed_as_quaternions():
    """A steady turn through +-pi (where rotation vectors jump) stays a steady turn."""
    n = 60
    angle = np.linspace(2.8, 3.5, n)                                 # crosses pi
    poses = np.zeros((n, 48))
    poses[:, 4] = np.where(angle <= np.pi, angle, angle - 2 * np.pi)  # rotvec about y, wrapped
    poses[:, 4] += np.random.default_rng(0).normal(0, 0.01, n) * (angle <= np.pi)
    poses[30] = np.nan
    out = smooth_poses(poses, "savgol:7", FPS)
    assert np.isnan(out[30]).all() and np.isfinite(np.delete(out, 30, axis=0)).all()
    q_out = rotvec_to_quat(out[:, 3:6])
    q_true = rotvec_to_quat(np.stack([np.zeros(n), angle, np.zeros(n)], 1))
    err = 2 * np.arccos(np.clip(np.abs(np.sum(q_out * q_true, axis=1)), 0, 1))
    assert np.nanmax(err) < 0.03                                    # no spike at the wrap
