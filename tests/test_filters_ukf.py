"""Unscented Kalman filter against the linear Kalman filter, and with wrapped angles."""
import numpy as np
import pytest

from depthtrack.filters.angles import wrap
from depthtrack.filters.kalman import KalmanFilter
from depthtrack.filters.ukf import MerweScaledSigmaPoints, UnscentedKalmanFilter, unscented_transform


def test_unscented_transform_is_exact_for_linear_maps():
    rng = np.random.default_rng(0)
    n = 4
    x = rng.normal(size=n)
    a = rng.normal(size=(n, n))
    P = a @ a.T + np.eye(n)
    pts = MerweScaledSigmaPoints(n, alpha=0.3)
    sig = pts.sigma_points(x, P)
    M = rng.normal(size=(3, n))
    mean, cov = unscented_transform(sig @ M.T, pts.Wm, pts.Wc)
    np.testing.assert_allclose(mean, M @ x, atol=1e-9)
    np.testing.assert_allclose(cov, M @ P @ M.T, atol=1e-9)


def test_ukf_equals_kalman_filter_on_a_linear_model():
    rng = np.random.default_rng(1)
    dt = 1.0
    F = np.array([[1, dt], [0, 1]])
    H = np.array([[1.0, 0.0]])
    Q = np.array([[dt ** 4 / 4, dt ** 3 / 2], [dt ** 3 / 2, dt ** 2]]) * 0.01
    R = np.array([[0.25]])
    kf = KalmanFilter([0.0, 1.0], np.eye(2), F, H, Q, R)
    ukf = UnscentedKalmanFilter([0.0, 1.0], np.eye(2), lambda s: s @ F.T, lambda s: s @ H.T, Q, R,
                                points=MerweScaledSigmaPoints(2, alpha=0.5))
    x = np.array([0.0, 1.0])
    for _ in range(30):
        x = F @ x + rng.multivariate_normal([0, 0], Q)
        z = H @ x + rng.normal(0, 0.5, 1)
        kf.predict()
        kf.update(z)
        ukf.predict()
        ukf.update(z)
        np.testing.assert_allclose(ukf.x_prior, kf.x_prior, atol=1e-9)
        np.testing.assert_allclose(ukf.x, kf.x, atol=1e-9)
        np.testing.assert_allclose(ukf.P, kf.P, atol=1e-9)


def test_ukf_tracks_an_angle_across_the_wrap():
    F = np.array([[1.0, 1.0], [0.0, 1.0]])
    Q = np.diag([1e-6, 1e-6])
    R = np.array([[0.01]])

    def res(a, b):
        d = np.asarray(a) - np.asarray(b)
        d[..., 0] = wrap(d[..., 0])
        return d

    def mean(sig, wm):
        return sig[0] + wm @ res(sig, sig[0])

    ukf = UnscentedKalmanFilter([3.0, 0.1], np.diag([0.01, 0.01]), lambda s: s @ F.T, lambda s: s[:, :1], Q, R,
                                points=MerweScaledSigmaPoints(2, alpha=0.5), residual_x=res,
                                residual_z=lambda a, b: wrap(a - b), mean_x=mean,
                                mean_z=lambda s, wm: s[0] + wm @ wrap(s - s[0]))
    angle = 3.0
    for _ in range(20):
        angle = wrap(angle + 0.1)
        ukf.predict()
        ukf.update([angle])
    assert abs(wrap(ukf.x[0] - angle)) < 0.05
    assert ukf.x[1] == pytest.approx(0.1, abs=0.02)
