"""A body folded over with hands and feet on the floor: the straight grid of the global search
does not reach it, the bent bodies (``StartSettings.bends``) do."""
import numpy as np

from depthtrack.body import BodyModel
from depthtrack.body.rotations import rotvec_to_matrix
from depthtrack.body.skeleton import MODEL_UP, POSE_INDEX
from depthtrack.contract import JOINT_INDEX
from depthtrack.track import TrackerSettings
from depthtrack.track.start import BEND_POSES, candidate_poses, head_to_feet_turn
from depthtrack.track.tracker import Tracker


def _down_dog(body):
    """``(2, 48)``: the trunk tipped 135 degrees forward, hips flexed 90, arms overhead --
    hands and feet on the floor, hips up (yoga's "downward dog")."""
    from depthtrack.synth.procedural import ground_lock

    p = np.zeros((2, body.dof))
    p[:, POSE_INDEX["pelvis_rx"]] = np.radians(135)
    p[:, POSE_INDEX["l_hip_rx"]] = p[:, POSE_INDEX["r_hip_rx"]] = np.radians(-90)
    p[:, POSE_INDEX["l_shoulder_rx"]] = p[:, POSE_INDEX["r_shoulder_rx"]] = np.radians(-165)
    return ground_lock(body, p)


def test_bent_candidates_lie_feet_to_head_along_the_search_axes():
    body = BodyModel.default(height=1.75)
    rng = np.random.default_rng(0)
    points = rng.normal(size=(400, 3)) * [0.7, 0.25, 0.1] + [0.0, 0.0, 3.0]
    up = np.array([0.0, -1.0, 0.0])
    straight, k = candidate_poses(points, up, points.mean(axis=0), body, TrackerSettings())
    for bend in BEND_POSES:
        bent, k2 = candidate_poses(points, up, points.mean(axis=0), body, TrackerSettings(), bend)
        assert bent.shape == straight.shape and k2 == k
        # the same orientations: the straight body's trunk and the bent body's feet-to-head
        # chord point the same way
        J = body.joint_positions(bent)
        chord = J[:, JOINT_INDEX["head"]] - 0.5 * (J[:, JOINT_INDEX["l_ankle"]]
                                                   + J[:, JOINT_INDEX["r_ankle"]])
        chord /= np.linalg.norm(chord, axis=1, keepdims=True)
        trunk = rotvec_to_matrix(straight[:, 3:6]) @ MODEL_UP
        assert np.min(np.sum(chord * trunk, axis=1)) > 0.999
        # and the bend is really there: the trunk is far from the chord
        bent_trunk = rotvec_to_matrix(bent[:, 3:6]) @ MODEL_UP
        assert np.max(np.sum(bent_trunk * chord, axis=1)) < 0.95
    assert np.allclose(head_to_feet_turn(body, np.zeros(body.dof)), np.eye(3), atol=0.05)


def test_a_body_folded_over_is_found_from_the_bent_candidates(tmp_path):
    from depthtrack.io import open_sequence
    from depthtrack.synth.generate import synthesize

    body = BodyModel.default(height=1.75, mesh="full")
    synthesize(tmp_path / "seq", body, _down_dog(body), fps=25.0, camera="sr4000", azimuth=90.0,
               noise="tof", seed=1)
    seq = open_sequence(tmp_path / "seq")
    settings = TrackerSettings().updated({"start": {"bends": "start"}})
    with Tracker(BodyModel.default(height=1.75), seq.camera, settings=settings) as tracker:
        tracker.init(seq.depth(0))
        joints = tracker.body.joint_positions(tracker.pose)
        info = tracker.describe()["initialisation"]
    err = np.linalg.norm(joints - seq.joints[0], axis=1)
    assert err.mean() < 0.08, err
    assert info["chosen_from"] == "grid" and info["chosen_bend"] in BEND_POSES
