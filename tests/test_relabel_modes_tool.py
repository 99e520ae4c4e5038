"""tools/relabel_modes.py: a track's failure mode named by the relabelling nearest the truth."""

import numpy as np
import pytest

from depthtrack.body import BodyModel
from depthtrack.body.skeleton import POSE_INDEX
from tool_module import load_tool


def _tool():
    return load_tool("relabel_modes")


def test_a_track_turned_with_its_legs_kept_is_named_so_and_a_right_one_is_not():
    tool = _tool()
    body = BodyModel.default(height=1.75)
    poses = np.zeros((4, 48))
    poses[:, 2] = 3.0
    poses[:, POSE_INDEX["l_hip_rx"]] = np.linspace(-0.9, -0.6, 4)     # a stride, not symmetric
    poses[:, POSE_INDEX["r_shoulder_rx"]] = -0.8
    truth = np.asarray(body.joint_positions(poses))
    order = tool.RELABELLINGS["turned_legs_kept"]
    wrong = truth[:, order]                  # the joints a track turned with its legs kept holds
    errors = tool.relabel_errors(wrong, truth)
    assert errors["turned_legs_kept"] == pytest.approx(np.zeros(4), abs=1e-9)
    assert (errors["as_tracked"] > 0.08).all() and (errors["turned"] > 0.08).all()
    found = tool.modes(errors, off=0.08, nearer=0.4)
    assert found["turned_legs_kept"] == [0, 1, 2, 3] and not found["turned"] and not found["legs"]
    # a track within a few centimetres: no mode
    close = tool.modes(tool.relabel_errors(truth + 0.02, truth), off=0.08, nearer=0.4)
    assert not any(close.values())


def test_a_missing_sequence_is_one_line_and_exit_status_2(tmp_path, capsys):
    assert _tool().main([str(tmp_path / "nope"), str(tmp_path / "track")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "nope" in err


def test_a_track_a_quarter_turn_off_is_named_so():
    """A trunk turned 90 degrees about the body's long axis (seen in profile where the
    person faces the camera): no exchange of sides mends it; ``quarter_turned`` names it, and
    half a turn is not a quarter turn."""
    from depthtrack.body.facing import facing_error_deg
    from depthtrack.rotations import rotation_about

    tool = _tool()
    body = BodyModel.default(height=1.75)
    poses = np.zeros((3, 48))
    poses[:, 2] = 3.0
    poses[:, POSE_INDEX["l_shoulder_rx"]] = -1.4          # both arms forward, as 105_05 walks
    poses[:, POSE_INDEX["r_shoulder_rx"]] = -1.4
    truth = np.asarray(body.joint_positions(poses))

    def turned(angle):
        out = []
        for j in truth:
            axis = (j[0] - j[2]) / np.linalg.norm(j[0] - j[2])       # pelvis to head
            out.append((j - j[2]) @ rotation_about(axis, angle).T + j[2])
        return np.array(out)

    quarter = turned(np.pi / 2)
    assert facing_error_deg(quarter, truth) == pytest.approx([90.0] * 3, abs=1.0)
    found = tool.modes(tool.relabel_errors(quarter, truth), 0.08, 0.4,
                       facing_error_deg(quarter, truth))
    assert found["quarter_turned"] == [0, 1, 2] and not found["turned"]
    half = turned(np.pi)
    found = tool.modes(tool.relabel_errors(half, truth), 0.08, 0.4, facing_error_deg(half, truth))
    assert not found["quarter_turned"]
    assert facing_error_deg(truth, truth) == pytest.approx([0.0] * 3, abs=1e-6)
