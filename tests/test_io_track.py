"""Track output directory: write, read back, atomicity, BVH inside it."""
import json

import numpy as np
import pytest

from depthtrack.errors import InputError
from depthtrack.io.bvh import BVH_FROM_CAMERA, read_bvh
from depthtrack.io.track_output import read_track, write_track

body_mod = pytest.importorskip("depthtrack.body")


def test_write_read_track(tmp_path):
    body = body_mod.BodyModel.default(mesh="decimated").scaled(height=1.62)
    rng = np.random.default_rng(0)
    poses = rng.normal(0, 0.3, (12, body.dof))
    poses[:, :3] += [0, 0, 2.5]
    poses[5] = np.nan                      # a frame the tracker lost
    joints = body.joint_positions(np.nan_to_num(poses))
    joints[5] = np.nan
    out = tmp_path / "out"
    write_track(out, joints, poses, body.pose_names, body, 25.0,
                {"method": "hill-climb", "settings": {"particles": 64}, "seconds": 1.5})
    assert sorted(p.name for p in out.iterdir()) == ["body.json", "joints.csv", "poses.npz", "summary.json",
                                                       "track.bvh"]
    track = read_track(out)
    np.testing.assert_allclose(track.joints, joints, atol=1e-6)
    np.testing.assert_array_equal(track.poses, poses)
    assert track.pose_names == list(body.pose_names) and track.fps == 25.0
    assert track.body_height == pytest.approx(1.62)
    assert track.summary == {"method": "hill-climb", "settings": {"particles": 64}, "seconds": 1.5,
                             "frames": 12, "fps": 25.0}
    motion = read_bvh(out / "track.bvh")
    bvh_joints = motion.contract_joint_positions() @ BVH_FROM_CAMERA   # back to the camera frame
    keep = np.arange(12) != 5
    assert np.abs(bvh_joints[keep] - joints[keep]).max() < 1e-3
    np.testing.assert_allclose(bvh_joints[5], bvh_joints[4], atol=1e-6)   # lost frame holds the last pose


def test_failed_track_write_keeps_old_output(tmp_path):
    body = body_mod.BodyModel.default(mesh="decimated")
    out = tmp_path / "out"
    poses = np.zeros((2, body.dof))
    write_track(out, body.joint_positions(poses), poses, body.pose_names, body, 25.0, {"method": "a"})
    with pytest.raises(TypeError):
        write_track(out, body.joint_positions(poses), poses, body.pose_names, body, 25.0,
                    {"method": object()})
    assert json.loads((out / "summary.json").read_text())["method"] == "a"
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_read_track_errors(tmp_path):
    with pytest.raises(InputError, match="no such track"):
        read_track(tmp_path / "absent")
    (tmp_path / "t").mkdir()
    with pytest.raises(InputError, match="missing poses.npz"):
        read_track(tmp_path / "t")
