"""Where joints miss, as the camera saw them (``evaluate.joint_view``), in closed form, and
tools/joint_errors.py on a real sequence with a "track" at the true poses."""
import json

import numpy as np
import pytest

from depthtrack.body import BodyModel
from depthtrack.camera import Camera
from depthtrack.contract import JOINT_INDEX as J
from depthtrack.evaluate.joint_view import (TRUNK_HALF_AXES_M, TRUNK_LENGTH_M, elbow_offsets,
                                            hidden_joints, trunk_penetration)
from tool_module import load_tool


def _rest_joints(n: int = 1) -> np.ndarray:
    """``(n, 15, 3)`` the template's joints at its zero pose (arms hanging out to the sides)."""
    body = BodyModel.default(height=1.75)
    return np.repeat(np.asarray(body.joint_positions(np.zeros((1, 48)))), n, axis=0)


def _turned(joints, angle: float, shift) -> np.ndarray:
    """``joints (F, 15, 3)`` rotated by ``angle`` about the camera's y axis and moved by ``shift``."""
    c, s = np.cos(angle), np.sin(angle)
    rot = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    return joints @ rot.T + np.asarray(shift, dtype=np.float64)


def test_a_joint_behind_a_wall_is_hidden_one_just_behind_its_surface_is_not():
    camera = Camera.preset("sr4000")
    h, w = camera.shape
    depth = np.full((h, w), 2.0, np.float32)
    depth[:, : w // 4] = 0.0                                  # no reading on the left quarter
    pixel = camera.backproject(np.array([1.0]), np.array([[w / 2, h / 2]]))[0]   # the ray at z = 1
    left = camera.backproject(np.array([1.0]), np.array([[w / 8, h / 2]]))[0]
    joints = np.array([2.5 * pixel,       # 0.5 m behind the wall: hidden
                       1.5 * pixel,       # in front of it
                       2.05 * pixel,      # inside the gap, as a limb's joint behind its surface
                       3.0 * left,        # behind a pixel with no reading
                       [50.0, 0.0, 2.5]])  # outside the image
    assert hidden_joints(depth, camera, joints).tolist() == [True, False, False, False, False]
    assert hidden_joints(depth, camera, joints, gap=0.01).tolist() == [True, False, True, False, False]


def test_elbow_offsets_are_the_same_for_either_arm_and_any_placement():
    rest = _rest_joints(3)
    left, right = elbow_offsets(rest, "l"), elbow_offsets(rest, "r")
    assert left == pytest.approx(right, abs=1e-9)            # the template is symmetric
    forward, outward, up = left[0]
    assert abs(forward) < 0.02 and outward > 0.1 and up < -0.25
    moved = _turned(rest, 0.7, [0.3, -0.2, 3.0])
    assert elbow_offsets(moved, "l") == pytest.approx(left, abs=1e-9)
    for angle in (2.0, -2.5):
        assert elbow_offsets(_turned(rest, angle, [0.0, 0.0, 3.0]), "r") == pytest.approx(right, abs=1e-9)
    with pytest.raises(ValueError, match="side"):
        elbow_offsets(rest, "left")


def test_an_arm_through_the_trunk_reads_as_deep_as_the_trunk_and_a_hanging_arm_not_at_all():
    rest = _rest_joints(2)
    assert np.all(trunk_penetration(rest) == 0.0)
    through = rest.copy()
    middle = 0.5 * (rest[1, J["pelvis"]] + rest[1, J["neck"]])
    through[1, J["l_elbow"]] = middle                         # the elbow on the trunk's axis
    through[1, J["l_wrist"]] = middle + np.array([0.0, 0.0, 0.3])
    length = np.linalg.norm(rest[1, J["neck"]] - rest[1, J["pelvis"]])
    depth = trunk_penetration(through)
    assert depth[0] == pytest.approx([0.0, 0.0])
    assert depth[1, 0] == pytest.approx(TRUNK_HALF_AXES_M[1] * length / TRUNK_LENGTH_M)
    assert depth[1, 1] == 0.0
    # the same, the whole body turned and moved: the trunk's frame goes with it
    assert trunk_penetration(_turned(through, 1.1, [0.2, 0.1, 3.0])) == pytest.approx(depth)


@pytest.fixture(scope="module")
def short_squat(tmp_path_factory):
    """Six frames of the built-in squat, SR4000, ToF noise, seen from its side."""
    from depthtrack.synth.generate import synthesize_procedural

    d = tmp_path_factory.mktemp("side") / "seq"
    synthesize_procedural("squat", d, start=0.6, seconds=0.24, seed=1, azimuth=90.0)
    return d


def test_the_tool_on_a_track_at_the_true_poses(short_squat, tmp_path, capsys):
    from depthtrack.body.skeleton import POSE_NAMES
    from depthtrack.io import open_sequence, write_track
    from depthtrack.synth.generate import rendered_poses

    seq = open_sequence(short_squat)
    body, poses = rendered_poses(json.loads((short_squat / "sequence.json").read_text()))
    track = write_track(tmp_path / "track", np.asarray(body.joint_positions(poses)), poses,
                        POSE_NAMES, body, seq.fps)
    tool = load_tool("joint_errors")
    assert tool.main([str(short_squat), str(track), "--json", str(tmp_path / "j.json")]) == 0
    row = json.loads((tmp_path / "j.json").read_text())[0]
    assert row["within_10cm"] == 1.0 and row["frames"] == len(seq)
    assert row["arms_in_trunk"] == {"tracked": 0, "true": 0, "limb_frames": 2 * len(seq)}
    # seen from its right, the near arm and leg are seen, the far elbow is behind the body
    shares = {k: v["hidden_share"] for k, v in row["joints"].items()}
    assert shares["r_wrist"] == 0.0 and shares["r_ankle"] == 0.0
    assert shares["l_elbow"] > 0.5
    for e in row["elbows_when_hidden"].values():
        assert e["true_m"] == e["tracked_m"]
    capsys.readouterr()
    assert tool.main([str(short_squat), str(tmp_path / "nope")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "nope" in err
