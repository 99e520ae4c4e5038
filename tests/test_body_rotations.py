"""Rotation helpers against scipy and closed forms, including angles near 0 and pi."""
import numpy as np
import pytest
from scipy.spatial.transform import Rotation, Slerp

from depthtrack.body import rotations as rot


def _random_rotvecs(rng, n):
    axis = rng.normal(size=(n, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    return axis * rng.uniform(0, np.pi, size=(n, 1))


def test_rotvec_to_matrix_matches_scipy():
    r = _random_rotvecs(np.random.default_rng(0), 500)
    np.testing.assert_allclose(rot.rotvec_to_matrix(r), Rotation.from_rotvec(r).as_matrix(), atol=1e-12)


def test_rotvec_to_matrix_keeps_batch_shape():
    r = _random_rotvecs(np.random.default_rng(1), 24).reshape(2, 3, 4, 3)
    assert rot.rotvec_to_matrix(r).shape == (2, 3, 4, 3, 3)
    assert rot.matrix_to_rotvec(rot.rotvec_to_matrix(r)).shape == (2, 3, 4, 3)


def test_quarter_turn_about_z_closed_form():
    m = rot.rotvec_to_matrix([0, 0, np.pi / 2])
    np.testing.assert_allclose(m @ [1, 0, 0], [0, 1, 0], atol=1e-15)


@pytest.mark.parametrize("angle", [0.0, 1e-12, 1e-9, 1e-6, 1e-4, 0.3, np.pi - 1e-3, np.pi - 1e-7, np.pi])
def test_round_trip_near_zero_and_pi(angle):
    rng = np.random.default_rng(2)
    axis = rng.normal(size=(50, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    r = axis * angle
    back = rot.matrix_to_rotvec(rot.rotvec_to_matrix(r))
    # at exactly pi, r and -r are the same rotation
    same = np.minimum(np.linalg.norm(back - r, axis=1), np.linalg.norm(back + r, axis=1))
    tol = 1e-6 if angle >= np.pi - 1e-6 else 1e-10
    assert same.max() < tol
    np.testing.assert_allclose(rot.rotvec_to_matrix(back), rot.rotvec_to_matrix(r), atol=1e-10)


def test_small_angle_matrix_is_first_order_exact():
    r = np.array([1e-9, -2e-9, 3e-9])
    expected = np.eye(3) + rot.skew(r)
    np.testing.assert_allclose(rot.rotvec_to_matrix(r), expected, atol=1e-17)


def test_matrix_to_rotvec_matches_scipy():
    r = _random_rotvecs(np.random.default_rng(3), 500)
    m = Rotation.from_rotvec(r).as_matrix()
    np.testing.assert_allclose(rot.matrix_to_rotvec(m), Rotation.from_matrix(m).as_rotvec(), atol=1e-9)


def test_quaternion_conversions_match_scipy():
    r = _random_rotvecs(np.random.default_rng(4), 200)
    q = rot.rotvec_to_quat(r)
    ref = Rotation.from_rotvec(r).as_quat()
    ref = np.where(ref[:, 3:] < 0, -ref, ref)
    np.testing.assert_allclose(q, ref, atol=1e-12)
    np.testing.assert_allclose(rot.quat_to_matrix(q), Rotation.from_quat(q).as_matrix(), atol=1e-12)
    np.testing.assert_allclose(rot.matrix_to_quat(rot.quat_to_matrix(q)), q, atol=1e-10)


def test_compose_is_matrix_product():
    rng = np.random.default_rng(5)
    a, b = _random_rotvecs(rng, 100), _random_rotvecs(rng, 100)
    c = rot.compose_rotvec(a, b)
    np.testing.assert_allclose(rot.rotvec_to_matrix(c),
                               rot.rotvec_to_matrix(a) @ rot.rotvec_to_matrix(b), atol=1e-10)


def test_slerp_matches_scipy_and_endpoints():
    rng = np.random.default_rng(6)
    r0, r1 = _random_rotvecs(rng, 60), _random_rotvecs(rng, 60)
    t = rng.uniform(0, 1, 60)
    out = rot.slerp(r0, r1, t)
    for i in range(60):
        ref = Slerp([0, 1], Rotation.from_rotvec([r0[i], r1[i]]))([t[i]]).as_matrix()[0]
        np.testing.assert_allclose(rot.rotvec_to_matrix(out[i]), ref, atol=1e-9)
    np.testing.assert_allclose(rot.rotvec_to_matrix(rot.slerp(r0, r1, 0.0)), rot.rotvec_to_matrix(r0), atol=1e-10)
    np.testing.assert_allclose(rot.rotvec_to_matrix(rot.slerp(r0, r1, 1.0)), rot.rotvec_to_matrix(r1), atol=1e-10)


def test_slerp_halfway_about_one_axis_and_identical_inputs():
    mid = rot.slerp([0, 0, 0.2], [0, 0, 1.0], 0.5)
    np.testing.assert_allclose(mid, [0, 0, 0.6], atol=1e-12)
    same = rot.slerp([0.1, 0.2, 0.3], [0.1, 0.2, 0.3], 0.37)
    np.testing.assert_allclose(same, [0.1, 0.2, 0.3], atol=1e-12)
    # the short way round: 170 deg and -170 deg about z meet at 180 deg, not 0
    half = rot.slerp([0, 0, np.radians(170)], [0, 0, -np.radians(170)], 0.5)
    assert abs(np.linalg.norm(half) - np.pi) < 1e-9
