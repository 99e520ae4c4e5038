"""The cyclic motion model (thesis chapter 4): kinematics, 1/k^2 scaling, learned noise, phase."""
import numpy as np
import pytest

from depthtrack.motion.cyclic import CyclicMotionModel


def make_model(n_cycles=4, length=10, angles=3, seed=0, temporal_sigma=0.0):
    rng = np.random.default_rng(seed)
    acc = rng.normal(0, 0.01, (n_cycles, length, angles))
    return CyclicMotionModel(np.zeros((length, angles)), np.zeros((length, angles)), acc,
                             temporal_sigma=temporal_sigma, threads=1, chunk=4096)


def test_noise_free_transition_is_the_kinematic_update_with_1_over_k2():
    model = make_model(n_cycles=1, length=10)
    mu = model.mean_acceleration
    speed = 0.05                               # half the reference speed: k = 2
    p = model.particles_at(3, [0.1, 0.2, 0.3], [0.01, 0.0, -0.02], 0.34, speed)
    a0, v0 = p["angles"].copy(), p["velocities"].copy()
    model.propagate(p, np.random.default_rng(0))
    acc = mu[3] / 4.0                          # index floor(0.34 * 10) = 3, scaled by 1/k^2
    np.testing.assert_allclose(p["angles"], a0 + v0 + 0.5 * acc, atol=1e-6)
    np.testing.assert_allclose(p["velocities"], v0 + acc, atol=1e-6)
    np.testing.assert_allclose(p["phase"], 0.34 + speed, atol=1e-6)
    assert model.acceleration_scale(speed) == pytest.approx(0.25)


def test_sampled_accelerations_have_the_training_mean_and_covariance():
    model = make_model(n_cycles=5, length=4, angles=3, seed=1)
    n = 200000
    p = model.particles_at(n, np.zeros(3), np.zeros(3), 0.6, model.v_ref)   # k = 1, index 2
    model.propagate(p, np.random.default_rng(2))
    acc = p["velocities"].astype(float)        # velocities started at 0: they are the accelerations
    np.testing.assert_allclose(acc.mean(0), model.mean_acceleration[2], atol=4 * 0.01 / np.sqrt(n) * 3)
    cov = np.cov(acc.T)
    expected = np.cov(model.accelerations[:, 2].T)                         # unbiased, n - 1
    np.testing.assert_allclose(cov, expected, atol=3e-6)
    np.testing.assert_allclose(model.acceleration_covariance(2), expected, atol=1e-15)


def test_phase_wraps_and_temporal_noise_has_the_given_spread():
    model = make_model(temporal_sigma=1e-3)
    n = 100000
    p = model.particles_at(n, np.zeros(3), np.zeros(3), 0.99, 0.02)
    model.propagate(p, np.random.default_rng(3))
    assert np.all((p["phase"] >= 0) & (p["phase"] < 1))
    # v = v + a_t, c = c + v + a_t / 2
    assert p["speed"].std() == pytest.approx(1e-3, rel=0.03)
    assert np.median(p["phase"]) == pytest.approx(0.01, abs=1e-3)


def test_vector_transition_and_process_noise_match_the_particles():
    model = make_model(n_cycles=3, length=8, angles=2, seed=4)
    x = np.array([0.1, -0.2, 0.01, 0.02, 0.25, 0.0625])     # c = 0.25 -> index 2 exactly, v = v_ref/2
    y = model.transition(x)
    acc = model.mean_acceleration[2] * model.acceleration_scale(0.0625)
    np.testing.assert_allclose(y[:2], x[:2] + x[2:4] + 0.5 * acc)
    np.testing.assert_allclose(y[2:4], x[2:4] + acc)
    Q = model.process_noise(x)
    sigma = np.cov(model.accelerations[:, 2].T) * model.acceleration_scale(0.0625) ** 2
    np.testing.assert_allclose(Q[:2, :2], 0.25 * sigma, atol=1e-15)     # (dt^2/2)^2
    np.testing.assert_allclose(Q[2:4, 2:4], sigma, atol=1e-15)
    np.testing.assert_allclose(Q[:2, 2:4], 0.5 * sigma, atol=1e-15)


def test_results_do_not_depend_on_the_thread_count():
    model = make_model(n_cycles=4, length=20, angles=5, seed=5)
    model.chunk = 1000
    outs = []
    for threads in (1, 2):
        p = model.particles_at(5000, np.zeros(5), np.zeros(5), 0.3, 0.01)
        model.propagate(p, np.random.default_rng(7), threads=threads)
        outs.append(p["angles"].copy())
    np.testing.assert_array_equal(outs[0], outs[1])
