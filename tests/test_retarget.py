"""Retargeting BVH motion onto the body model, and slerp resampling."""
from pathlib import Path

import numpy as np
import pytest

from depthtrack.body import BodyModel
from depthtrack.body.rotations import matrix_to_rotvec, rotvec_to_matrix
from depthtrack.contract import JOINT_INDEX as C
from depthtrack.io.bvh import read_bvh
from depthtrack.motion.retarget import (canonical_axes, resample_poses, retarget, rotation_between,
                                        subject_height)

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
WALK = DATA / "motions" / "walk.bvh"
CMU = DATA / "cmu" / "126_01.bvh"

LIMBS = [("l_shoulder", "l_elbow"), ("l_elbow", "l_wrist"), ("r_shoulder", "r_elbow"),
         ("r_elbow", "r_wrist"), ("l_hip", "l_knee"), ("l_knee", "l_ankle"), ("r_hip", "r_knee"),
         ("r_knee", "r_ankle"), ("neck", "head")]


@pytest.fixture(scope="module")
def body():
    return BodyModel.default(mesh="decimated")


def _placed(motion, offset=(0.3, -0.2, 3.0)):
    T = np.eye(4)
    T[:3, :3] = canonical_axes(motion)
    T[:3, 3] = offset
    return T


@pytest.mark.skipif(not WALK.exists(), reason="shared motion data absent")
def test_walk_retarget_matches_bvh_joints(body):
    motion = read_bvh(WALK)
    same = body.scaled(height=subject_height(motion, body))
    T = _placed(motion)
    poses = retarget(motion, same, T)
    assert poses.shape == (motion.n_frames, 48) and np.all(np.isfinite(poses))
    ours = same.joint_positions(poses)
    theirs = motion.contract_joint_positions() @ T[:3, :3].T + T[:3, 3]
    # Hip centres coincide (the root trajectory, scale 1 at equal height) ...
    hips = lambda j: j[:, [C["l_hip"], C["r_hip"]]].mean(axis=1)
    np.testing.assert_allclose(hips(ours), hips(theirs), atol=1e-6)
    # ... every joint is within a few cm of the BVH's, relative to it (what remains are the
    # two skeletons' different proportions: DeepMimic's shoulders sit 7 cm higher) ...
    error = np.linalg.norm((ours - hips(ours)[:, None]) - (theirs - hips(theirs)[:, None]), axis=-1)
    assert error.max() < 0.06, error.max(axis=0)
    # ... and limb bones point exactly the same way.
    for a, b in LIMBS:
        u = ours[:, C[b]] - ours[:, C[a]]
        v = theirs[:, C[b]] - theirs[:, C[a]]
        cos = np.sum(u * v, -1) / np.linalg.norm(u, axis=-1) / np.linalg.norm(v, axis=-1)
        assert np.degrees(np.arccos(np.clip(cos, -1, 1))).max() < 0.1, (a, b)


@pytest.mark.skipif(not WALK.exists(), reason="shared motion data absent")
def test_root_scaled_by_height_ratio_and_faces_camera(body):
    motion = read_bvh(WALK)
    poses = retarget(motion, body)            # default placement: facing the camera, 2.5 m away
    scale = body.height / subject_height(motion, body)
    hips = body.joint_positions(poses)[:, [C["l_hip"], C["r_hip"]]].mean(axis=1)
    bvh_hips = motion.contract_joint_positions()[:, [C["l_hip"], C["r_hip"]]].mean(axis=1)
    travelled = np.linalg.norm(hips[-1] - hips[0])
    assert travelled == pytest.approx(scale * np.linalg.norm(bvh_hips[-1] - bvh_hips[0]), rel=1e-6)
    np.testing.assert_allclose(hips[0], [0, 0, 2.5], atol=1e-9)
    # DeepMimic walks forward (+x, its facing): toward the camera, i.e. -z in the camera frame.
    assert hips[-1, 2] < hips[0, 2] - 0.5
    forward = rotvec_to_matrix(poses[0, 3:6]) @ [0, 0, -1.0]
    assert forward[2] < -0.9


@pytest.mark.skipif(not CMU.exists(), reason="shared CMU data absent")
def test_resample_120_to_25_hits_source_frames(body):
    motion = read_bvh(CMU)
    poses = retarget(motion, body)
    out = resample_poses(poses, motion.fps, 25.0, start=1.0, duration=2.0)
    assert out.shape == (50, 48)
    # Output frame k is at source time 1 + k/25 s = source frame 120 + 4.8 k (120.0005 Hz file).
    for k in (0, 5, 10):
        t = (1.0 + k / 25.0) * motion.fps
        i = int(np.floor(t))
        if t - i < 1e-3:
            np.testing.assert_allclose(out[k], poses[i], atol=1e-3)
    joints = body.joint_positions(out)
    assert np.all(np.isfinite(joints))


def test_resample_slerps_rotations():
    a = np.zeros((2, 48))
    a[1, 0] = 1.0
    a[0, 6:9] = [0.0, 0.0, 3.0]                  # near a half turn about z
    a[1, 6:9] = [0.0, 0.0, -3.0]                 # the other way round: the short arc crosses pi
    out = resample_poses(a, 1.0, 4.0)
    assert out.shape == (5, 48)
    np.testing.assert_allclose(out[:, 0], [0, 0.25, 0.5, 0.75, 1.0])
    angles = [np.linalg.norm(r) for r in out[:, 6:9]]
    # Slerp goes the short way through pi (angle 3 -> pi -> 3); Euler/lerp would pass 0.
    assert min(angles) > 3.0 - 1e-9 and max(angles) == pytest.approx(np.pi, abs=1e-6)
    np.testing.assert_allclose(out[2, 6:9] @ [0, 0, 1], np.pi, atol=1e-6)  # the half turn
    np.testing.assert_allclose(out[:, 3:6], 0.0)


def test_rotation_between():
    rng = np.random.default_rng(0)
    a = rng.normal(size=(100, 3))
    b = rng.normal(size=(100, 3))
    b[0] = -a[0]
    R = rotation_between(a, b)
    moved = np.einsum("nij,nj->ni", R, a)
    np.testing.assert_allclose(moved / np.linalg.norm(moved, axis=1, keepdims=True),
                               b / np.linalg.norm(b, axis=1, keepdims=True), atol=1e-9)
    # minimal: the rotation axis is perpendicular to both
    axis = matrix_to_rotvec(R[1:])
    assert np.abs(np.sum(axis * a[1:], -1)).max() < 1e-8


@pytest.mark.skipif(not CMU.exists(), reason="shared CMU data absent")
def test_cmu_t_pose_rest_limb_directions(body):
    # CMU's rest pose is a T-pose (ours an A-pose) and its spine has four joints.
    motion = read_bvh(CMU)
    T = _placed(motion, offset=(0, 0, 3))
    poses = retarget(motion, body, T)
    ours = body.joint_positions(poses)
    theirs = motion.contract_joint_positions() @ T[:3, :3].T + T[:3, 3]
    for a, b in LIMBS:
        u = ours[:, C[b]] - ours[:, C[a]]
        v = theirs[:, C[b]] - theirs[:, C[a]]
        cos = np.sum(u * v, -1) / np.linalg.norm(u, axis=-1) / np.linalg.norm(v, axis=-1)
        assert np.degrees(np.arccos(np.clip(cos, -1, 1))).max() < 0.1, (a, b)
    # The pelvis turns with the BVH hips: the hip axis (left minus right) agrees within 10 deg.
    u = ours[:, C["l_hip"]] - ours[:, C["r_hip"]]
    v = theirs[:, C["l_hip"]] - theirs[:, C["r_hip"]]
    cos = np.sum(u * v, -1) / np.linalg.norm(u, axis=-1) / np.linalg.norm(v, axis=-1)
    assert np.degrees(np.arccos(np.clip(cos, -1, 1))).max() < 10
