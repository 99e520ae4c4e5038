"""Stick figure angles (thesis eq. 2.1): round trips, poles, wrapping, equivalence, mirroring."""
import numpy as np
import pytest

from depthtrack.filters.angles import angle_diff, circular_mean, wrap
from depthtrack.swim.stickfigure import (
    ANGLE_NAMES, SWIM_INDEX, SWIM_PARENTS, angle_error_sq, angles_to_joints, canonical_angles, continue_angles,
    equivalent_branch, joints_to_angles, segment_lengths)


def random_figure(rng, n=50):
    lengths = rng.uniform(0.1, 0.5, 13)
    d = rng.normal(size=(n, 13, 3))
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    joints = np.zeros((n, 14, 3))
    joints[:, 0] = rng.normal(size=(n, 3))
    for j in range(1, 14):
        joints[:, j] = joints[:, SWIM_PARENTS[j]] + lengths[j - 1] * d[:, j - 1]
    return joints, lengths


def test_round_trip_joints_angles_joints():
    rng = np.random.default_rng(0)
    joints, lengths = random_figure(rng)
    angles = joints_to_angles(joints)
    assert angles.shape == (50, 26) and len(ANGLE_NAMES) == 26
    back = angles_to_joints(angles, lengths, joints[:, 0])
    np.testing.assert_allclose(back, joints, atol=1e-12)
    np.testing.assert_allclose(segment_lengths(joints), np.broadcast_to(lengths, (50, 13)), atol=1e-12)
    # and angles -> joints -> angles away from the poles
    np.testing.assert_allclose(joints_to_angles(back), angles, atol=1e-10)


def test_equation_2_1_conventions():
    joints = np.zeros((14, 3))
    for j in range(1, 14):
        joints[j] = joints[SWIM_PARENTS[j]]
    i = SWIM_INDEX["l_knee"]
    joints[i:] += [1.0, 0.0, 0.0]          # l_knee one unit along +x from l_hip
    a = joints_to_angles(joints)
    k = 2 * (i - 1)
    assert a[k] == pytest.approx(np.pi / 2)        # zenith from +y
    assert a[k + 1] == pytest.approx(np.pi / 2)    # azimuth from +z towards +x


def test_pole_gives_zero_azimuth_and_joints_still_exact():
    joints = np.zeros((14, 3))
    for j in range(1, 14):
        joints[j] = joints[SWIM_PARENTS[j]] + [0.0, 0.3, 0.0]   # every segment straight up
    a = joints_to_angles(joints)
    assert np.all(a[0::2] == 0) and np.all(a[1::2] == 0)
    odd = a.copy()
    odd[1::2] = 1.234                                          # any azimuth at the pole ...
    np.testing.assert_allclose(angles_to_joints(odd, np.full(13, 0.3)), joints, atol=1e-12)
    assert np.all(joints_to_angles(angles_to_joints(odd, np.full(13, 0.3)))[1::2] == 0)  # ... comes back as 0


def test_wrapping_and_circular_mean():
    assert wrap(np.float32(3 * np.pi / 2)) == pytest.approx(-np.pi / 2)
    assert wrap(np.array([np.pi - 0.1, -np.pi - 0.1])).tolist() == pytest.approx([np.pi - 0.1, np.pi - 0.1])
    assert angle_diff(np.pi - 0.05, -np.pi + 0.05) == pytest.approx(-0.1)
    assert circular_mean(np.array([np.pi - 0.1, -np.pi + 0.1])) == pytest.approx(np.pi, abs=1e-12) or \
        circular_mean(np.array([np.pi - 0.1, -np.pi + 0.1])) == pytest.approx(-np.pi, abs=1e-12)
    assert wrap(np.float32(10.0)).dtype == np.float32


def test_pole_equivalent_representations_have_zero_error():
    rng = np.random.default_rng(1)
    a = canonical_angles(rng.uniform(-np.pi, np.pi, (20, 26)))
    other = a.copy()
    other[:, 0::2] = -a[:, 0::2] + 2 * np.pi * rng.integers(-2, 3, (20, 13))
    other[:, 1::2] = a[:, 1::2] + np.pi + 2 * np.pi * rng.integers(-2, 3, (20, 13))
    np.testing.assert_allclose(angle_error_sq(other, a), 0, atol=1e-20)
    np.testing.assert_allclose(angles_to_joints(other, np.ones(13)), angles_to_joints(a, np.ones(13)), atol=1e-12)
    aligned, flipped = equivalent_branch(other, a)
    assert flipped.all()
    np.testing.assert_allclose(aligned, a, atol=1e-12)
    shifted = a + 0.1
    assert angle_error_sq(shifted, a).sum(-1) == pytest.approx(np.full(20, 26 * 0.01))


def test_continue_angles_passes_over_the_pole_continuously():
    # An arm swinging over the top in the y-z plane: canonical phi flips by pi at the pole.
    t = np.linspace(-0.5, 0.5, 41)
    joints = np.zeros((41, 14, 3))
    for j in range(1, 14):
        joints[:, j] = joints[:, SWIM_PARENTS[j]] + [0.0, -0.3, 0.0]
    e = SWIM_INDEX["r_elbow"]
    joints[:, e] = joints[:, SWIM_INDEX["r_shoulder"]] + 0.3 * np.stack([0 * t, np.cos(t), np.sin(t)], -1)
    for j in range(e + 1, 14):
        joints[:, j] = joints[:, SWIM_PARENTS[j]] + [0.0, -0.3, 0.0]
    raw = joints_to_angles(joints)
    k = 2 * (e - 1)
    assert np.abs(np.diff(raw[:, k + 1])).max() > 3.0          # the flip
    cont = continue_angles(raw)
    assert np.abs(np.diff(cont, axis=0)).max() < 0.03           # smooth: theta passes through 0
    np.testing.assert_allclose(angles_to_joints(cont, np.full(13, 0.3)), joints - joints[:, :1], atol=1e-12)
