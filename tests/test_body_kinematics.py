"""Forward kinematics, pose layout, limits and body dimensions against hand-computed chains."""
import numpy as np
import pytest

from depthtrack.body import BodyModel
from depthtrack.body.rotations import rotvec_to_matrix
from depthtrack.contract import JOINT_INDEX, JOINT_NAMES


@pytest.fixture(scope="module")
def body():
    return BodyModel.default(mesh="decimated")


def test_layout(body):
    assert body.dof == 48 and len(body.pose_names) == 48
    assert body.pose_names[:6] == ("pelvis_tx", "pelvis_ty", "pelvis_tz", "pelvis_rx", "pelvis_ry", "pelvis_rz")
    assert body.pose_names[3 + 3 * 4: 6 + 3 * 4] == ("l_elbow_rx", "l_elbow_ry", "l_elbow_rz")
    assert list(body.parents) == [-1, 0, 1, 1, 3, 4, 1, 6, 7, 0, 9, 10, 0, 12, 13]
    assert body.joint_names[4] == "l_elbow"
    np.testing.assert_array_equal(body.default_pose(position=(0, 0, 2.5)), np.r_[0, 0, 2.5, np.zeros(45)])


def test_zero_pose_faces_camera(body):
    j = body.joint_positions(body.default_pose())
    assert j[JOINT_INDEX["l_shoulder"], 0] > j[JOINT_INDEX["r_shoulder"], 0] + 0.2
    assert j[JOINT_INDEX["l_hip"], 0] > j[JOINT_INDEX["r_hip"], 0]
    assert j[JOINT_INDEX["head"], 1] < j[JOINT_INDEX["neck"], 1] < j[JOINT_INDEX["pelvis"], 1]
    assert j[JOINT_INDEX["pelvis"], 1] < j[JOINT_INDEX["l_knee"], 1] < j[JOINT_INDEX["l_ankle"], 1]
    np.testing.assert_allclose(j[JOINT_INDEX["pelvis"]], 0, atol=1e-12)


def test_world_transforms_follow_the_chain_formula(body):
    rng = np.random.default_rng(0)
    poses = rng.normal(scale=0.5, size=(7, 48))
    world = body.world_transforms(poses)
    assert world.shape == (7, 15, 4, 4) and world.dtype == np.float64
    for n in range(7):
        T = []
        for j in range(15):
            local = np.eye(4)
            local[:3, :3] = rotvec_to_matrix(poses[n, 3 + 3 * j: 6 + 3 * j])
            if j == 0:
                local[:3, 3] = poses[n, :3]
                T.append(local)
            else:
                trans = np.eye(4)
                trans[:3, 3] = body.offsets[j]
                T.append(T[body.parents[j]] @ trans @ local)
        np.testing.assert_allclose(world[n], np.stack(T), atol=1e-12)


def test_elbow_right_angle_moves_wrist_forward_by_forearm_length(body):
    j0 = body.joint_positions(body.default_pose())
    elbow, wrist = j0[JOINT_INDEX["l_elbow"]], j0[JOINT_INDEX["l_wrist"]]
    forearm = wrist - elbow
    length = np.linalg.norm(forearm)
    axis = np.cross(forearm / length, [0, 0, -1.0])
    axis /= np.linalg.norm(axis)
    pose = body.default_pose()
    pose[body.pose_names.index("l_elbow_rx"):][:3] = np.pi / 2 * axis
    j1 = body.joint_positions(pose)
    np.testing.assert_allclose(j1[JOINT_INDEX["l_wrist"]], elbow + [0, 0, -length], atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(j1[JOINT_INDEX["l_wrist"]] - wrist), length * np.sqrt(2), rtol=1e-12)
    moved = [n for n in JOINT_NAMES if not np.allclose(j1[JOINT_INDEX[n]], j0[JOINT_INDEX[n]])]
    assert moved == ["l_wrist"]
    # anatomical flexion is negative rx (see the skeleton docstring) and is inside the limits
    assert pose[body.pose_names.index("l_elbow_rx")] < 0
    np.testing.assert_array_equal(body.clip(pose), pose)


def test_knee_flexion_moves_ankle_backward(body):
    pose = body.default_pose()
    pose[body.pose_names.index("r_knee_rx")] = np.pi / 2
    j0, j1 = body.joint_positions(body.default_pose()), body.joint_positions(pose)
    knee, ankle = j0[JOINT_INDEX["r_knee"]], j0[JOINT_INDEX["r_ankle"]]
    shank = ankle - knee
    expected = knee + [shank[0], -shank[2], shank[1]]  # R_x(90 deg): (x, y, z) -> (x, -z, y)
    np.testing.assert_allclose(j1[JOINT_INDEX["r_ankle"]], expected, atol=1e-12)
    assert j1[JOINT_INDEX["r_ankle"], 2] > knee[2] + 0.3  # behind the knee


def test_root_rotation_and_translation_move_every_joint(body):
    r = np.array([0.3, -1.1, 0.4])
    t = np.array([0.2, -0.1, 3.0])
    pose = body.default_pose(position=t)
    pose[3:6] = r
    expected = body.joint_positions(body.default_pose()) @ rotvec_to_matrix(r).T + t
    np.testing.assert_allclose(body.joint_positions(pose), expected, atol=1e-12)


def test_batch_and_single_agree(body):
    poses = np.random.default_rng(1).normal(scale=0.4, size=(5, 48))
    batch = body.joint_positions(poses)
    assert batch.shape == (5, 15, 3)
    np.testing.assert_allclose(body.joint_positions(poses[3]), batch[3])
    assert body.skin_matrices(poses).shape == (5, 15, 4, 4) and body.skin_matrices(poses).dtype == np.float32
    assert body.skin_matrices(poses[0]).shape == (15, 4, 4)
    with pytest.raises(ValueError):
        body.joint_positions(np.zeros(47))


def test_head_is_fixed_in_neck_frame(body):
    pose = body.default_pose()
    pose[body.pose_names.index("neck_rx"):][:3] = [0.7, 0, 0]  # nod forward
    j0, j1 = body.joint_positions(body.default_pose()), body.joint_positions(pose)
    neck = j0[JOINT_INDEX["neck"]]
    np.testing.assert_allclose(np.linalg.norm(j1[0] - neck), np.linalg.norm(j0[0] - neck), rtol=1e-12)
    assert j1[0, 2] < j0[0, 2] - 0.05  # head moved toward the camera (-z)


def test_limits_and_clip(body):
    lo, hi = body.lower, body.upper
    assert lo.shape == hi.shape == (48,) and np.all(lo < hi)
    assert np.all(np.isinf(lo[:6])) and np.all(np.isinf(hi[:6]))
    knee = body.pose_names.index("l_knee_rx")
    assert lo[knee] > -0.2 and hi[knee] > 2.0  # bends backward only
    elbow = body.pose_names.index("r_elbow_rx")
    assert hi[elbow] < 0.2 and lo[elbow] < -2.0
    poses = np.random.default_rng(2).normal(scale=3.0, size=(10, 48))
    clipped = body.clip(poses)
    assert np.all(clipped >= lo) and np.all(clipped <= hi)
    np.testing.assert_array_equal(clipped[:, :6], poses[:, :6])


def test_height_scaling(body):
    for height in (1.50, 1.75, 1.95):
        b = BodyModel.default(height=height, mesh="decimated")
        v = b.posed_vertices(b.default_pose())
        # top of the head to the sole, measured on the posed surface
        assert abs((v[:, 1].max() - v[:, 1].min()) - height) < 0.02 * height
        assert abs(b.height - height) < 1e-12
    small, tall = BodyModel.default(1.5, "decimated"), BodyModel.default(1.95, "decimated")
    np.testing.assert_allclose(tall.offsets, (1.95 / 1.5) * small.offsets, rtol=1e-9, atol=1e-15)
    # levels of detail of one body share one skeleton
    np.testing.assert_allclose(BodyModel.default(1.95, "full").offsets, tall.offsets, rtol=1e-12)


def test_segment_stretch_changes_only_that_bone(body):
    b = body.scaled(segment_scale={"l_knee": 1.2})
    j0, j1 = body.joint_positions(body.default_pose()), b.joint_positions(b.default_pose())

    def length(j, a, c):
        return np.linalg.norm(j[JOINT_INDEX[a]] - j[JOINT_INDEX[c]])

    bones = [("l_shoulder", "l_elbow"), ("l_elbow", "l_wrist"), ("l_hip", "l_knee"), ("l_knee", "l_ankle"),
             ("r_hip", "r_knee"), ("r_knee", "r_ankle"), ("neck", "head"), ("pelvis", "neck"),
             ("pelvis", "l_hip")]
    for a, c in bones:
        ratio = length(j1, a, c) / length(j0, a, c)
        assert ratio == pytest.approx(1.2 if (a, c) == ("l_hip", "l_knee") else 1.0, rel=1e-12), (a, c)
    # the surface follows: the lowest vertex of the left leg drops by the extra thigh length
    v0, v1 = body.rest_vertices, b.rest_vertices
    extra = 0.2 * length(j0, "l_hip", "l_knee")
    left = body.mesh.vertices[:, 0] > 0.05
    assert v1[left, 1].max() - v0[left, 1].max() == pytest.approx(extra, rel=0.05)
    assert v1[~left, 1].max() == pytest.approx(v0[~left, 1].max(), abs=1e-6)
    # a stretched body keeps its joints on its (stretched) surface skeleton: bind pose skins to rest
    np.testing.assert_allclose(b.posed_vertices(b.default_pose()), b.rest_vertices)


def test_scaled_height_includes_stretch(body):
    b = body.scaled(height=1.80, segment_scale={"l_knee": 1.1, "r_knee": 1.1})
    assert b.height == pytest.approx(1.80, abs=1e-12)
    assert b.segment_scale == {"l_knee": 1.1, "r_knee": 1.1}
    with pytest.raises(ValueError):
        body.scaled(segment_scale={"elbow": 1.1})
    with pytest.raises(ValueError):
        body.scaled(height=-1)
