"""Rao-Blackwellised particle filter against closed forms: the Kalman filter where the cycle state does not
matter or is known, and the RTS smoother against the batch posterior of a small linear system."""
import numpy as np

from depthtrack.filters.kalman import KalmanFilter
from depthtrack.filters.rbpf import CycleRBPF
from depthtrack.filters.smoother import rts_smooth


def _system(A=3, seed=0):
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(2 * A, 2 * A)) * 0.01
    Q = a @ a.T + 1e-4 * np.eye(2 * A)
    return rng, Q, rng.normal(size=2 * A) * 0.1, np.eye(2 * A) * 0.01


def _F(A, rho=1.0):
    R = np.diag(np.broadcast_to(rho, (A,)))
    return np.block([[np.eye(A), R], [np.zeros((A, A)), R]])


def test_rbpf_without_a_mean_acceleration_is_the_kalman_filter():
    A = 3
    rng, Q, x0, P0 = _system(A)
    n = 500
    f = CycleRBPF(np.zeros((10, A)), Q, 0.05 ** 2, x0, P0, rng.random(n), np.full(n, 0.013),
                  temporal_sigma=1e-3, rng=rng, velocity_table=np.zeros((10, A)), rho=[0.8, 0.9, 1.0])
    kf = KalmanFilter(x0, P0, _F(A, [0.8, 0.9, 1.0]), np.eye(A, 2 * A), Q, 0.05 ** 2 * np.eye(A))
    x = x0.copy()
    for t in range(25):
        x = _F(A, [0.8, 0.9, 1.0]) @ x + rng.multivariate_normal(np.zeros(2 * A), Q)
        z = x[:A] + 0.05 * rng.normal(size=A) if t % 7 != 3 else None      # a withheld frame now and then
        kf.predict()
        if z is not None:
            kf.update(z)
        f.step(z)
        np.testing.assert_allclose(f.mean_x, kf.x, atol=1e-9)
        np.testing.assert_allclose(f.map_x, kf.x, atol=1e-9)
        np.testing.assert_allclose(f.P, kf.P, atol=1e-12)


def test_rbpf_with_a_known_cycle_state_is_the_kalman_filter_with_the_acceleration_as_input():
    """All particles share (c, v) and move deterministically: one Kalman filter with the control
    input r^2 [mu / 2, mu] + (1 - rho) r [d, d] at floor(c L), r = v L."""
    A, L, v, rho = 2, 8, np.float32(0.02), 0.9
    rng, Q, x0, P0 = _system(A, 1)
    mu, d = rng.normal(size=(L, A)) * 0.01, rng.normal(size=(L, A)) * 0.1
    n = 50
    f = CycleRBPF(mu, Q, 0.05 ** 2, x0, P0, np.full(n, 0.1), np.full(n, v), temporal_sigma=0.0, rng=rng,
                  velocity_table=d, rho=rho)
    H = np.eye(A, 2 * A)
    F = _F(A, rho)
    x, P, c = x0.copy(), P0.copy(), np.float32(0.1)
    for t in range(30):
        cell = int(np.floor(c * np.float32(L)))
        r = float(v * np.float32(L))
        x = F @ x + r ** 2 * np.concatenate([0.5 * mu[cell], mu[cell]]) + (1 - rho) * r * np.tile(d[cell], 2)
        P = F @ P @ F.T + Q
        z = x[:A] + 0.1 * rng.normal(size=A)
        S = H @ P @ H.T + 0.05 ** 2 * np.eye(A)
        K = P @ H.T @ np.linalg.inv(S)
        x, P = x + K @ (z - H @ x), (np.eye(2 * A) - K @ H) @ P
        f.step(z)
        c = (c + v) % np.float32(1)
        np.testing.assert_allclose(f.mean_x, x, atol=1e-6)
        np.testing.assert_allclose(f.map_x, x, atol=1e-6)


def test_rts_smoother_is_the_batch_gaussian_posterior():
    """x_t = F x_{t-1} + w, z_t = H x_t + n, t = 0..T-1, x_0 ~ N(m0, P0): the smoothed means are the
    mean of the joint Gaussian posterior of all states (one linear solve)."""
    rng = np.random.default_rng(3)
    F = np.array([[1.0, 1.0], [0.0, 0.9]])
    H = np.array([[1.0, 0.0]])
    Q = np.array([[0.02, 0.01], [0.01, 0.05]])
    R = np.array([[0.3]])
    m0, P0 = np.array([0.5, -0.2]), np.diag([0.4, 0.2])
    T = 6
    zs = rng.normal(size=(T, 1))
    # forward Kalman filter, keeping what the smoother needs
    kf = KalmanFilter(m0, P0, F, H, Q, R)
    xs, Ps, xp, Pp, Cs = [], [], [np.zeros(2)], [np.eye(2)], [np.eye(2)]
    kf.update(zs[0])
    xs.append(kf.x.copy()), Ps.append(kf.P.copy())
    for t in range(1, T):
        C = Ps[-1] @ F.T
        kf.predict()
        xp.append(kf.x.copy()), Pp.append(kf.P.copy()), Cs.append(C)
        kf.update(zs[t])
        xs.append(kf.x.copy()), Ps.append(kf.P.copy())
    sm, _ = rts_smooth(np.array(xs), np.array(Ps), np.array(xp), np.array(Pp), np.array(Cs))
    # batch: minimise |x0 - m0|^2_P0^-1 + sum |x_t - F x_{t-1}|^2_Q^-1 + sum |z_t - H x_t|^2_R^-1
    n = 2 * T
    J = np.zeros((n, n))
    h = np.zeros(n)
    Pi, Qi, Ri = np.linalg.inv(P0), np.linalg.inv(Q), np.linalg.inv(R)
    J[:2, :2] += Pi
    h[:2] += Pi @ m0
    for t in range(T):
        s = slice(2 * t, 2 * t + 2)
        J[s, s] += H.T @ Ri @ H
        h[s] += (H.T @ Ri @ zs[t]).ravel()
        if t:
            p = slice(2 * t - 2, 2 * t)
            J[s, s] += Qi
            J[p, p] += F.T @ Qi @ F
            J[s, p] -= Qi @ F
            J[p, s] -= F.T @ Qi
    batch = np.linalg.solve(J, h).reshape(T, 2)
    np.testing.assert_allclose(sm, batch, atol=1e-9)
