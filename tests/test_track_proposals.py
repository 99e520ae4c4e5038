"""The part recogniser in the tracker (issue 10): side-free disagreement, poses fitted to
proposals, and an upside-down track put right by the proposals' judgement."""
import numpy as np
import pytest

from depthtrack.body import BodyModel
from depthtrack.body.rotations import matrix_to_rotvec, rotation_about, rotvec_to_matrix
from depthtrack.body.skeleton import POSE_INDEX
from depthtrack.contract import JOINT_INDEX
from depthtrack.detect.recognizer import JointProposals
from depthtrack.track import TrackerSettings
from depthtrack.track.twins import ARMS_SWAPPED, LEGS_SWAPPED, SIDES_SWAPPED
from depthtrack.track.proposals import (TRUNK, disagreement, hip_angle, proposal_candidates,
                                        proposal_hip_angle)
from depthtrack.track.tracker import Tracker, fit_pose_to_joints


def _proposals(joints, confidence=0.01):
    """Perfect proposals: each joint's own position first, its twin's second (merge_sides)."""
    joints = np.asarray(joints, dtype=np.float64)
    pos = np.stack([joints, joints[SIDES_SWAPPED]], axis=1)          # (15, 2, 3)
    return JointProposals(pos, np.full((15, 2), confidence))


def _pose():
    x = np.zeros(48)
    x[2] = 3.0
    x[POSE_INDEX["l_hip_rx"]] = -0.6
    x[POSE_INDEX["r_shoulder_rz"]] = 1.0
    return x


def test_disagreement_is_side_free_and_counts_far_trunk_joints():
    body = BodyModel.default(height=1.75)
    joints = np.asarray(body.joint_positions(_pose()))
    props = _proposals(joints)
    off, checked = disagreement(joints, props, 0.002, 0.3)
    assert checked == len(TRUNK) and off == 0.0
    # the sides exchanged: still no disagreement (the recogniser's sides are not trusted)
    off, _ = disagreement(joints[SIDES_SWAPPED], props, 0.002, 0.3)
    assert off == 0.0
    # the head and neck 0.5 m away: 2 of the 5 trunk joints disagree
    moved = joints.copy()
    moved[[JOINT_INDEX["head"], JOINT_INDEX["neck"]]] += [0.0, 0.5, 0.0]
    off, _ = disagreement(np.stack([joints, moved]), props, 0.002, 0.3)
    assert off.tolist() == [0.0, pytest.approx(0.4)]
    # proposals below the confidence floor are not evidence at all
    off, checked = disagreement(moved, _proposals(joints, 0.001), 0.002, 0.3)
    assert checked == 0 and off == 0.0


def test_hip_angle_of_the_proposals_reads_a_fold_at_the_hips():
    # closed form: neck straight up, knees straight down -> 180; knees forward -> 90
    up, o = np.array([0.0, 0.5, 0.0]), np.zeros(3)
    assert hip_angle(up, o, -up, -up) == pytest.approx(180.0)
    assert hip_angle(up, o, [0.0, 0.0, 0.4], [0.1, 0.0, 0.4]) == pytest.approx(90.0)
    # batched: (2, 3) each -> (2,)
    knees = np.array([-up, [0.0, 0.0, 1.0]])
    assert hip_angle(np.stack([up, up]), np.zeros((2, 3)), knees, knees).tolist() == \
        pytest.approx([180.0, 90.0])
    body = BodyModel.default(height=1.75)
    rest = np.zeros(48)
    rest[2] = 3.0
    straight = np.asarray(body.joint_positions(rest))
    assert proposal_hip_angle(_proposals(straight)) > 170
    folded = rest.copy()
    folded[POSE_INDEX["l_hip_rx"]] = folded[POSE_INDEX["r_hip_rx"]] = -1.6
    joints = np.asarray(body.joint_positions(folded))
    assert 80 < proposal_hip_angle(_proposals(joints)) < 100
    # the most confident proposal counts, not the first: a confident straight knee outvotes
    props = _proposals(joints)
    knees = [JOINT_INDEX["l_knee"], JOINT_INDEX["r_knee"]]
    props.positions[knees, 1] = straight[knees]
    props.confidence[knees, 1] = 0.05
    assert proposal_hip_angle(props) > 170
    # no neck proposal: no angle (the gate then reads the share alone)
    props.positions[JOINT_INDEX["neck"]] = np.nan
    props.confidence[JOINT_INDEX["neck"]] = 0.0
    assert proposal_hip_angle(props) is None


def test_poses_fitted_to_proposals_put_the_joints_there():
    body = BodyModel.default(height=1.75)
    x = _pose()
    R = rotation_about(np.array([1.0, 0.0, 0.0]), 2.2)         # lying, head away from the camera
    x[3:6] = matrix_to_rotvec(R[None])[0]
    joints = np.asarray(body.joint_positions(x))
    fits = proposal_candidates(body, _proposals(joints), 0.002)
    assert fits.shape == (4, 48)                 # as labelled, all, legs, arms exchanged
    got = np.asarray(body.joint_positions(fits))
    assert np.linalg.norm(got[0] - joints, axis=1).max() < 0.03
    assert np.linalg.norm(got[1] - joints[SIDES_SWAPPED], axis=1).max() < 0.05
    assert np.linalg.norm(got[2] - joints[LEGS_SWAPPED], axis=1).max() < 0.05
    # the legs exchanged, the trunk stays where the proposals put it (arms exchanged
    # across the body cannot reach: that fit is only nearer than the unexchanged one)
    trunk = [JOINT_INDEX[n] for n in ("head", "neck", "pelvis")]
    assert np.linalg.norm(got[:3, trunk] - joints[trunk], axis=2).max() < 0.02
    assert np.linalg.norm(got[3] - joints[ARMS_SWAPPED], axis=1).mean() < \
        np.linalg.norm(got[0] - joints[ARMS_SWAPPED], axis=1).mean()
    # the root follows: the fitted body lies as the true one does
    up = rotvec_to_matrix(fits[0, 3:6]) @ np.array([0.0, 1.0, 0.0])
    assert up @ (R @ np.array([0.0, 1.0, 0.0])) > 0.95


def test_an_upside_down_track_is_put_right_by_the_proposals(squat12):
    squat = squat12                 # put right by frame 9
    body = BodyModel.default(height=1.75)
    truth = squat.joints
    x0 = fit_pose_to_joints(body, truth[0])
    R = rotvec_to_matrix(x0[3:6])
    flipped = x0.copy()                              # head down, turned about the pelvis
    flipped[3:6] = matrix_to_rotvec((rotation_about(np.array([0.0, 0.0, 1.0]), np.pi) @ R)[None])[0]
    with Tracker(body, squat.camera, settings=TrackerSettings()) as tracker:
        tracker.init(squat.depth(0), pose=flipped)
        joints = [body.joint_positions(tracker.pose)]
        for i in range(1, len(squat)):
            joints.append(body.joint_positions(tracker.step(squat.depth(i))))
        info = tracker.describe()
    err = np.linalg.norm(np.asarray(joints) - truth, axis=-1).mean(axis=-1)
    assert err[0] > 0.5
    reasons = [r["reason"] for r in info["recoveries"]]
    assert "proposals" in reasons, info["recoveries"]
    first = next(r for r in info["recoveries"] if r["reason"] == "proposals")
    # judged after ProposalSettings.lost_frames frames in a row, then back within 5 frames
    assert first["frame"] <= TrackerSettings().propose.lost_frames + 1
    back = first["frame"] + first["frames_to_recover"]
    assert err[back:].max() < 0.1 and back <= first["frame"] + 5


def test_settings_validate_and_turn_the_recogniser_off():
    from depthtrack.errors import InputError
    from depthtrack.track.settings import ProposalSettings

    with pytest.raises(InputError):
        ProposalSettings(enabled="yes")
    with pytest.raises(InputError):
        ProposalSettings(lost_frames=0)
    from depthtrack.track.settings import HeadingSettings
    with pytest.raises(InputError):
        HeadingSettings(start_twin="mirrored")
    body = BodyModel.default(height=1.75)
    from depthtrack.camera import Camera

    cam = Camera.preset("sr4000")
    off = TrackerSettings(propose=ProposalSettings(enabled=False))
    with Tracker(body, cam, settings=off) as a, Tracker(body, cam) as b, \
            Tracker(body, cam, method="hc") as c:
        assert a.forest is None and b.forest is not None and c.forest is None
    assert TrackerSettings().to_dict()["propose"]["lost_frames"] == 3


def test_track_settings_option_reaches_the_tracker_and_bad_ones_are_refused(squat, tmp_path, capsys):
    import json

    from depthtrack.cli import main

    short = tmp_path / "short"
    out = tmp_path / "track"
    # five frames are enough to see the settings written; no check after the start, and
    # neither the height fit nor the shape fit (the height given, the fit off)
    from depthtrack.io.sequence import write_sequence
    write_sequence(short, [squat.depth(i) for i in range(5)], squat.camera, squat.fps,
                   subject={"height_m": 1.75})
    given = {"heading": {"frames": 0, "every": 8}, "propose": {"lost_frames": 5},
             "shape": {"enabled": False}}
    assert main(["track", str(short), "-o", str(out), "--quiet", "--settings", json.dumps(given)]) == 0
    written = json.loads((out / "summary.json").read_text())["settings"]
    assert written["heading"]["every"] == 8 and written["propose"]["lost_frames"] == 5
    assert written["heading"]["start_twin"] == "swapped"           # the rest stays default
    assert written["shape"]["enabled"] is False and written["shape"]["frames"] == 16
    # a track's summary.json gives the same settings back
    assert main(["track", str(short), "-o", str(tmp_path / "again"), "--quiet",
                 "--settings", str(out / "summary.json")]) == 0
    assert json.loads((tmp_path / "again" / "summary.json").read_text())["settings"] == written
    bad = tmp_path / "bad.json"
    bad.write_text('{"heading": {"start_twin": "mirrored"}}')
    capsys.readouterr()
    assert main(["track", str(short), "-o", str(tmp_path / "no"), "--quiet", "--settings", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "start_twin" in err[0] and not (tmp_path / "no").exists()
