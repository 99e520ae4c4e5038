"""Evidence propagation: unscented statistical linearisation, iterated to the MAP."""
import numpy as np
import pytest
from scipy.optimize import minimize

from depthtrack.body import BodyModel
from depthtrack.motion.prior import ConstantVelocityPrior
from depthtrack.track.evidence import (PartModel, iterated_unscented_update, propagate_evidence,
                                       sigma_points, statistical_linearisation)


def test_sigma_points_reproduce_mean_and_covariance():
    rng = np.random.default_rng(0)
    L = rng.normal(size=(4, 4))
    cov = L @ L.T + np.eye(4)
    mean = rng.normal(size=4)
    for kwargs in ({}, {"alpha": 0.5, "beta": 2.0, "kappa": 1.0}):
        X, wm, wc = sigma_points(mean, cov, **kwargs)
        assert X.shape == (9, 4)
        np.testing.assert_allclose(wm @ X, mean, atol=1e-12)
        d = X - mean
        np.testing.assert_allclose((wc[:, None] * d).T @ d, cov, atol=1e-10)


def test_linear_gaussian_case_equals_the_kalman_closed_form():
    rng = np.random.default_rng(3)
    n, m = 6, 3
    H, c = rng.normal(size=(m, n)), rng.normal(size=m)
    P = np.diag(rng.uniform(0.5, 2.0, n))
    m0, z = rng.normal(size=n), rng.normal(size=m)
    R = 0.1 * np.eye(m)
    A, b, omega = statistical_linearisation(lambda X: X @ H.T + c, m0, P)
    np.testing.assert_allclose(A, H, atol=1e-10)
    np.testing.assert_allclose(b, c, atol=1e-10)
    np.testing.assert_allclose(omega, 0.0, atol=1e-10)
    res = iterated_unscented_update(lambda X: X @ H.T + c, m0, P, z, R, start=m0 + 1.0)
    S = H @ P @ H.T + R
    K = P @ H.T @ np.linalg.inv(S)
    np.testing.assert_allclose(res.mean, m0 + K @ (z - H @ m0 - c), atol=1e-10)
    np.testing.assert_allclose(res.cov, P - K @ S @ K.T, atol=1e-10)
    assert res.converged


def test_nonlinear_map_matches_direct_optimisation():
    # a two-link planar arm: the iterated update converges to the MAP of the exact posterior
    def f(X):
        a, b = X[:, 0], X[:, 1]
        return np.stack([np.cos(a) + 0.8 * np.cos(a + b), np.sin(a) + 0.8 * np.sin(a + b)], axis=1)

    m0 = np.array([0.3, 0.5])
    P = np.diag([0.4, 0.6]) ** 2
    R = np.eye(2) * 0.01 ** 2
    z = f(np.array([[0.9, 1.1]]))[0]
    res = iterated_unscented_update(f, m0, P, z, R, max_iterations=50, tol=1e-8)

    def neg_log_post(x):
        d = x - m0
        r = z - f(x[None])[0]
        return 0.5 * d @ np.linalg.solve(P, d) + 0.5 * r @ np.linalg.solve(R, r)

    direct = minimize(neg_log_post, np.array([0.9, 1.1]), method="BFGS", options={"gtol": 1e-10})
    assert res.converged
    np.testing.assert_allclose(res.mean, direct.x, atol=2e-3)


@pytest.fixture(scope="module")
def body():
    return BodyModel.default(1.75, mesh="decimated")


def test_detection_at_true_hand_pulls_the_arm_there(body):
    parts = PartModel.from_body(body)
    prior = ConstantVelocityPrior.load(fps=25.0)
    start = body.default_pose((0.1, 0.0, 3.0))
    truth = start.copy()
    truth[12:15] = [-1.1, 0.0, 0.4]     # l_shoulder: arm forward and up
    truth[15] = -0.9                   # l_elbow flexed
    k = parts.index("l_hand")
    target = parts.positions(body, truth[None])[0, k]
    before = np.linalg.norm(parts.positions(body, start[None])[0, k] - target)
    assert before > 0.5
    res = propagate_evidence(body, parts, "l_hand", target, start, np.zeros(48),
                             4.0 * prior.velocity_std, obs_std=0.02)
    assert res.part_error < 0.03
    moved = np.abs(res.pose - start) > 1e-9
    # only the chain root -> spine -> left arm may move; the rest of the body stays put
    chain = np.zeros(48, bool)
    chain[parts.chains["l_hand"]] = True
    assert not np.any(moved & ~chain)
    # the arm, not the root, did the work: the pelvis moved less than 3 cm
    assert np.linalg.norm(res.pose[:3] - start[:3]) < 0.03
    elbow = body.joint_positions(res.pose)[4]
    true_elbow = body.joint_positions(truth)[4]
    assert np.linalg.norm(elbow - true_elbow) < 0.25


def test_part_positions_match_the_skeleton(body):
    parts = PartModel.from_body(body)
    pose = body.default_pose((0.0, 0.0, 2.5))
    centres = parts.positions(body, pose[None], surface=False)[0]
    joints = body.joint_positions(pose)
    np.testing.assert_allclose(centres[parts.index("head")], joints[0], atol=1e-9)
    # hands beyond the wrists (downward in the A-pose), feet forward of the ankles
    assert centres[parts.index("l_hand"), 1] > joints[5, 1]
    assert centres[parts.index("l_foot"), 2] < joints[11, 2]
    surface = parts.positions(body, pose[None])[0]
    assert np.all(surface[:, 2] < centres[:, 2])
