"""The filters with estimated noise on a short synthetic stroke: they beat the measurements, the noise
estimates are right, and the gap baselines behave as their closed forms on a sinusoid."""
import numpy as np
import pytest

from depthtrack.motion.cyclic import CyclicMotionModel
from depthtrack.swim.experiment import TestWindow as Window
from depthtrack.swim.gaps import gap_baselines, gap_errors, gap_mask, gap_runs, withhold
from depthtrack.swim.stickfigure import angle_error_sq
from depthtrack.swim.tracking import run_rbpf, run_ukf_tuned
from depthtrack.swim.tuning import estimate_measurement_noise

A, L = 26, 100


def _pose(c, k):
    """Smooth periodic angles; thetas (even) stay in (0.6, 2.4), away from the poles."""
    c = np.asarray(c, float)[..., None]
    base = np.where(np.arange(A) % 2 == 0, 1.5, 0.3)
    amp = 0.25 + 0.02 * np.arange(A) % 0.3
    return base + amp * np.sin(2 * np.pi * c + 0.3 * np.arange(A) + 0.05 * k)


def _model_and_window(frames=120, speed=1 / 90, seed=0):
    s = np.arange(L) / L
    cycles = np.stack([_pose(s, k) for k in range(3)])
    vel = np.gradient(cycles, axis=1)
    acc = np.gradient(vel, axis=1)
    model = CyclicMotionModel(cycles.mean(0), vel.mean(0), acc, temporal_sigma=0.005 / L)
    phase = (0.1 + speed * np.arange(frames + 1)) % 1.0
    angles = _pose(phase, 1)
    window = Window(angles, np.zeros((frames + 1, 14, 3)), phase, np.full(frames + 1, speed),
                        np.full(13, 0.3), 0, 1, 60.0)
    # process noise: the one-step residuals of the truth (here: the model is nearly exact)
    Q = np.diag(np.concatenate([np.full(A, 1e-6), np.full(A, 1e-6)]))
    return model, window, Q


def _error(est, window):
    return float(angle_error_sq(est, window.angles[1:]).sum(-1).mean())


@pytest.mark.parametrize("noise", [0.05, 0.1])
def test_new_filters_beat_the_measurements_on_a_synthetic_stroke(noise):
    model, window, Q = _model_and_window()
    z = window.angles + noise * np.random.default_rng(1).standard_normal(window.angles.shape)
    sigma = estimate_measurement_noise(z)
    assert sigma == pytest.approx(noise, rel=0.15)
    meas = _error(z[1:], window)
    rb = run_rbpf(model, window, z, 2000, Q, sigma, seed=2)
    ukf = run_ukf_tuned(model, window, z, Q, sigma, seed=2)
    assert _error(rb["estimates"]["mean"], window) < 0.5 * meas
    assert _error(ukf["estimates"]["mean"], window) < 0.5 * meas
    assert _error(ukf["smoothed"]["estimates"]["mean"], window) < _error(ukf["estimates"]["mean"], window)


def test_filters_predict_through_a_gap_better_than_constant_velocity():
    model, window, Q = _model_and_window()
    z = window.angles + 0.05 * np.random.default_rng(4).standard_normal(window.angles.shape)
    mask = gap_mask(window.frames, 30, first=20, spacing=40)
    zg = withhold(z, mask)
    rb = run_rbpf(model, window, zg, 2000, Q, 0.05, seed=3)
    inside = mask[1:]
    err_rb = angle_error_sq(rb["estimates"]["mean"], window.angles[1:]).sum(-1)[inside].mean()
    cv = gap_baselines(z, mask)["constant_velocity"]
    err_cv = angle_error_sq(cv[1:], window.angles[1:]).sum(-1)[inside].mean()
    assert err_rb < 0.5 * err_cv


def test_gap_schedule_and_baselines_on_a_sinusoid():
    mask = gap_mask(100, 10, first=20, spacing=40)
    assert gap_runs(mask) == [(20, 30), (70, 80)] and not mask[0]
    t = np.arange(101.0)
    truth = np.stack([np.sin(0.05 * t), 0.02 * t], axis=1)     # a sinusoid and a straight line
    base = gap_baselines(truth, mask, window=5)
    # hold: the value at frame 19; interpolation between frames 19 and 30 is exact for the line
    np.testing.assert_allclose(base["hold"][20:30], np.tile(truth[19], (10, 1)))
    np.testing.assert_allclose(base["interpolation"][20:30, 1], truth[20:30, 1], atol=1e-12)
    np.testing.assert_allclose(base["constant_velocity"][20:30, 1], truth[20:30, 1], atol=1e-12)
    # the line through frames 15..19 of the sinusoid, extrapolated: slope ~ 0.05 cos(0.05 * 17)
    slope = (base["constant_velocity"][21, 0] - base["constant_velocity"][20, 0])
    assert slope == pytest.approx(0.05 * np.cos(0.05 * 17), rel=0.01)
    assert np.array_equal(base["hold"][~mask], truth[~mask])
    sq = np.ones(100)
    sq[19:29] = 4.0                                              # frames 20..29 are sq[19:29]
    e = gap_errors(sq, mask, phase=np.linspace(0, 0.99, 100), after=5)
    assert e["frames_inside"] == 20 and e["frames_after"] == 10
    assert e["inside"] == pytest.approx(2.5) and e["after"] == pytest.approx(1.0)
    assert len(e["inside_per_phase"]) == 4


def test_measurement_noise_estimate_ignores_withheld_rows():
    rng = np.random.default_rng(5)
    t = np.arange(400.0)
    z = np.sin(0.02 * t)[:, None] + 0.03 * rng.standard_normal((400, 6))
    z[100:130] = np.nan
    assert estimate_measurement_noise(z) == pytest.approx(0.03, rel=0.1)


def test_velocity_decay_fit_recovers_the_decay_of_a_synthetic_deviation():
    from depthtrack.swim.tuning import fit_velocity_decay, predict_ahead

    rng = np.random.default_rng(6)
    M, rho = 300, 0.8
    vel = 0.05 * np.sin(np.arange(M) / 20.0)[:, None] * np.ones((1, 3))      # the mean stroke's velocity
    acc = np.zeros((M, 3))
    th, om = np.zeros((M, 3)), np.zeros((M, 3))
    for t in range(M - 1):                      # the model, with a kick to the velocity now and then
        drift = rho * om[t] + (1 - rho) * vel[t]
        th[t + 1] = th[t] + drift
        om[t + 1] = drift + (0.05 * rng.standard_normal(3) if t % 15 == 0 else 0.0)
    assert fit_velocity_decay([(th, om, acc, vel)], horizon=10) == pytest.approx(rho, abs=0.03)
    pred = predict_ahead(th, om, acc, vel, 1.0, 5)
    assert pred.shape == (5, M - 5, 3)


def _flip(x, segments):
    """State ``[angles, velocities, ...]`` with the given segments in the ``(-theta, phi + pi)`` branch."""
    x = np.array(x, dtype=float)
    for j in segments:
        x[..., 2 * j] *= -1
        x[..., 2 * j + 1] += np.pi
        if x.shape[-1] > A:
            x[..., A + 2 * j] *= -1                  # the zenith velocity changes sign, the azimuth's not
    return x


def test_zenith_sign_marks_the_other_branch():
    from depthtrack.swim.stickfigure import zenith_sign
    ref = _pose(np.array([0.3]), 0)[0]
    sign = zenith_sign(_flip(ref, [2, 7])[:A], ref)
    expected = np.ones(A)
    expected[[4, 14]] = -1
    np.testing.assert_array_equal(sign, expected)


def test_ukf_prediction_does_not_depend_on_the_pose_representation():
    """A pose in the other branch of the mean stroke's moves as the same pose: the learned velocity and
    acceleration act on it with their zenith part negated (without that the limb would move backwards)."""
    from depthtrack.swim.stickfigure import nearest_equivalent
    from depthtrack.swim.tracking import decaying_transition
    model, window, _ = _model_and_window()
    c, v = 0.3, 1 / 90
    x = np.concatenate([_pose(np.array([c]), 1)[0], 0.01 * np.ones(A), [c, v]])
    fx = decaying_transition(model, 0.8)
    y, yf = x.copy(), _flip(x, [1, 5, 9])
    for _ in range(20):
        y, yf = fx(y)[0], fx(yf)[0]
    np.testing.assert_allclose(nearest_equivalent(yf[:A], y[:A]), y[:A], atol=1e-9)
    np.testing.assert_allclose(_flip(yf, [1, 5, 9])[A:2 * A], y[A:2 * A], atol=1e-9)
    # the motion is real: 20 frames move the angles far more than the tolerance
    assert np.abs(y[:A] - x[:A]).max() > 0.1


def test_rbpf_prediction_does_not_depend_on_the_pose_representation():
    from depthtrack.filters.rbpf import CycleRBPF
    from depthtrack.swim.stickfigure import nearest_equivalent, zenith_sign
    model, window, Q = _model_and_window()
    c, v = 0.3, 1 / 90
    x0 = np.concatenate([_pose(np.array([c]), 1)[0], 0.01 * np.ones(A)])

    def predict(x):
        f = CycleRBPF(model.mean_acceleration, Q, 0.05 ** 2, x, 1e-4 * np.eye(2 * A), np.full(50, c),
                      np.full(50, v), velocity_table=model.mean_velocities, rho=0.8,
                      input_sign=lambda ang: zenith_sign(ang, model.mean_angles), rng=np.random.default_rng(0))
        for _ in range(20):
            f.step(None)
        return f.mean_x

    y, yf = predict(x0), predict(_flip(x0, [0, 4, 12]))
    np.testing.assert_allclose(nearest_equivalent(yf[:A], y[:A]), y[:A], atol=1e-6)
    assert np.abs(y[:A] - x0[:A]).max() > 0.1


def test_gap_diagnosis_splits_the_error_into_model_and_filter_state():
    from depthtrack.swim.experiment import SwimSetup
    from depthtrack.swim.gap_diagnosis import diagnose
    model, window, Q = _model_and_window()
    setup = SwimSetup(model, window, [], "", "", "", Q, 0, 1.0)
    z = window.angles + 0.05 * np.random.default_rng(5).standard_normal(window.angles.shape)
    out = diagnose(setup, z, 10, first=20, spacing=40)
    m = out["model_from"]
    # the synthetic stroke follows the model: from the true state the prediction is near exact,
    # from the filter's state it carries the state's error
    assert m["true state"] < 0.2 * m["filter state"]
    assert m["filter state"] < out["by_position"]["constant_velocity"][-1]
    assert len(out["by_position"]["ukf-tuned"]) == 10 and out["gaps"][0] == [20, 30]


def test_leave_one_cycle_out_residuals_are_n_over_n_minus_1_of_the_in_sample_ones():
    """Closed form: three cycles that differ only in the amplitude e_k of one sinusoid. Under the model of all
    three a cycle's residual is proportional to e_k - mean(e); under the model of the other two to
    e_k - mean of the others = 3/2 (e_k - mean(e)). So the leave-one-out residuals are 1.5 times the
    in-sample ones, angles and velocities alike."""
    from depthtrack.swim.cycles import TrainingCycles
    from depthtrack.swim.training import train_motion_model
    from depthtrack.swim.tuning import loo_residuals, one_step_residuals

    m, eps = 12, np.array([0.1, -0.05, 0.2])

    def pose(s, e):
        s = np.asarray(s, float)[..., None]
        return 1.5 + 0.3 * np.sin(2 * np.pi * s + 0.3 * np.arange(A)) + e * np.sin(2 * np.pi * s)

    frames = np.arange(3 * L + 1)
    take = pose(frames / L, eps[np.minimum(frames // L, 2)][:, None])     # one frame per reference sample
    cycles = TrainingCycles(np.stack([pose((np.arange(L + 2 * m) - m) / L, e) for e in eps]), m,
                            [(j * L, (j + 1) * L, "right") for j in range(3)])
    model = train_motion_model(cycles)
    inside = np.concatenate([one_step_residuals(model, take, [j * L, (j + 1) * L], 1) for j in range(3)])
    loo = loo_residuals(cycles, take, "right", 1)
    assert loo.shape == inside.shape
    for part in (slice(0, A), slice(A, 2 * A)):
        ratio = np.sqrt(np.mean(loo[:, part] ** 2) / np.mean(inside[:, part] ** 2))
        assert abs(ratio - 1.5) < 0.02


def test_rbpf_cycle_mean_is_the_weighted_mean_across_the_cycle_wrap():
    """Particles either side of the cycle's end (one at 0.98, three at 0.02): the mean phase is 0.01, not 0.26
    (the linear mean of the wrapped numbers), read after the particles have moved on by a frame."""
    from depthtrack.filters.rbpf import CycleRBPF
    model, _, Q = _model_and_window()
    phase = np.array([0.98, 0.02, 0.02, 0.02])
    speed = np.array([0.010, 0.012, 0.012, 0.012])
    f = CycleRBPF(model.mean_acceleration, Q, 0.05 ** 2, np.zeros(2 * A), 1e-4 * np.eye(2 * A), phase, speed,
                  rng=np.random.default_rng(0))
    f.step(None)                                   # equal weights: predicts, moves every particle by its speed
    f.log_w = np.log(np.array([0.25, 0.25, 0.25, 0.25], np.float32))
    c, v = f.cycle_mean()
    assert v == pytest.approx(0.0115, abs=1e-6)
    assert c == pytest.approx((-0.02 + 3 * 0.02) / 4, abs=1e-5)          # 0.98 is -0.02 across the wrap
    f.log_w = np.log(np.array([0.7, 0.1, 0.1, 0.1], np.float32))
    c, v = f.cycle_mean()
    assert v == pytest.approx(0.7 * 0.010 + 0.3 * 0.012, abs=1e-6)
    assert c == pytest.approx((0.7 * -0.02 + 0.3 * 0.02) % 1.0, abs=1e-5)     # 0.992
