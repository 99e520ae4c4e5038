"""Rao-Blackwellised particle filter against closed forms: the Kalman filter where the cycle state is known."""
import numpy as np

from depthtrack.filters.kalman import KalmanFilter
from depthtrack.filters.rbpf import CycleRBPF, periodic_table


def _system(A=3, seed=0):
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(2 * A, 2 * A)) * 0.01
    Q = a @ a.T + 1e-4 * np.eye(2 * A)
    x0 = rng.normal(size=2 * A) * 0.1
    P0 = np.eye(2 * A) * 0.01
    return rng, Q, x0, P0


def test_rbpf_without_a_mean_cycle_is_the_kalman_filter():
    A, rho = 3, 0.9
    rng, Q, x0, P0 = _system(A)
    zeros = np.zeros((10, A))
    n = 500
    f = CycleRBPF(zeros, zeros, Q, 0.05 ** 2, x0, P0, rng.random(n), np.full(n, 0.013), rho=rho,
                  temporal_sigma=1e-3, rng=rng)
    F = rho * np.block([[np.eye(A), np.eye(A)], [np.zeros((A, A)), np.eye(A)]])
    kf = KalmanFilter(x0, P0, F, np.eye(A, 2 * A), Q, 0.05 ** 2 * np.eye(A))
    x = x0.copy()
    for t in range(25):
        x = F @ x + rng.multivariate_normal(np.zeros(2 * A), Q)
        z = x[:A] + 0.05 * rng.normal(size=A) if t % 7 != 3 else None      # a withheld frame now and then
        kf.predict()
        if z is not None:
            kf.update(z)
        f.step(z)
        np.testing.assert_allclose(f.mean_x, kf.x, atol=1e-9)
        np.testing.assert_allclose(f.map_x, kf.x, atol=1e-9)
        np.testing.assert_allclose(f.P, kf.P, atol=1e-12)


def test_rbpf_with_a_known_cycle_state_is_the_kalman_filter_with_the_mean_cycle_as_input():
    """All particles share (c, v) and move deterministically: the RBPF is one Kalman filter whose
    prediction is g(s_t) + Phi (x - g(s_{t-1})), g = [m(cell), d(cell) v L]."""
    A, L, rho, v = 2, 8, 0.95, 0.02
    rng, Q, x0, P0 = _system(A, 1)
    t_ = np.arange(L) / L
    m = np.stack([np.sin(2 * np.pi * t_), 0.5 * np.cos(2 * np.pi * t_)], axis=1)
    d = np.stack([np.cos(2 * np.pi * t_), -0.5 * np.sin(2 * np.pi * t_)], axis=1) * 2 * np.pi / L
    n = 50
    f = CycleRBPF(m, d, Q, 0.05 ** 2, x0, P0, np.full(n, 0.1), np.full(n, v), rho=rho, temporal_sigma=0.0,
                  cells=4 * L, rng=rng)
    mc, dc = periodic_table(m, 4 * L), periodic_table(d, 4 * L) * L
    F = rho * np.block([[np.eye(A), np.eye(A)], [np.zeros((A, A)), np.eye(A)]])
    H = np.eye(A, 2 * A)
    x, P, c = x0.copy(), P0.copy(), 0.1
    for t in range(30):
        old = int(np.floor(np.float32(c) * 4 * L))
        c = float(np.float32(c) + np.float32(v)) % 1.0
        new = int(np.floor(np.float32(c) * 4 * L))
        g_old = np.concatenate([mc[old], dc[old] * v])
        g_new = np.concatenate([mc[new], dc[new] * v])
        x = g_new + F @ (x - g_old)
        P = F @ P @ F.T + Q
        z = mc[new] + 0.1 * rng.normal(size=A)
        S = H @ P @ H.T + 0.05 ** 2 * np.eye(A)
        K = P @ H.T @ np.linalg.inv(S)
        x = x + K @ (z - H @ x)
        P = (np.eye(2 * A) - K @ H) @ P
        f.step(z)
        np.testing.assert_allclose(f.mean_x, x, atol=1e-6)
        np.testing.assert_allclose(f.map_x, x, atol=1e-6)
