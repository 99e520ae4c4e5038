"""Reaching for a lost hand or foot (issue 10): limbs re-fitted to the recogniser's far
proposals, and the recheck that takes one only on a clear lead."""
import numpy as np

from depthtrack.body import BodyModel
from depthtrack.body.skeleton import POSE_INDEX
from depthtrack.contract import JOINT_INDEX as J
from depthtrack.detect.recognizer import JointProposals
from depthtrack.track import TrackerSettings
from depthtrack.track.reach import reach_candidates, recheck_reach
from depthtrack.track.state import TrackingState


def _raised_right_arm():
    x = np.zeros(48)
    x[2] = 3.0
    x[POSE_INDEX["r_shoulder_rx"]] = 1.2                 # the right arm forward
    x[POSE_INDEX["r_elbow_rx"]] = -1.0                   # its forearm bent
    return x


def _proposals(joints):
    """Every joint's own position as its proposal (one per joint)."""
    return JointProposals(np.asarray(joints, dtype=np.float64)[:, None].copy(), np.full((15, 1), 0.01))


def test_a_limb_reaches_a_far_proposal_and_nothing_else_moves():
    body = BodyModel.default(height=1.75)
    truth = np.asarray(body.joint_positions(_raised_right_arm()))
    tracked = np.zeros(48)
    tracked[2] = 3.0                                     # arms down: the right hand is lost
    joints = np.asarray(body.joint_positions(tracked))
    assert np.linalg.norm(joints[J["r_wrist"]] - truth[J["r_wrist"]]) > 0.3
    poses, limbs = reach_candidates(body, tracked, _proposals(truth), 0.002)
    # only the right arm is far from its proposals; each candidate once with the elbow free,
    # once at the elbow proposal
    assert limbs == ["r_arm", "r_arm"] and poses.shape == (2, 48)
    for pose, within in zip(poses, (0.05, 0.03)):         # the free elbow fits less closely
        got = np.asarray(body.joint_positions(pose))
        assert np.linalg.norm(got[J["r_wrist"]] - truth[J["r_wrist"]]) < within
        others = [j for j in range(15) if j not in (J["r_elbow"], J["r_wrist"])]
        assert np.abs(got[others] - joints[others]).max() < 0.02
    got = np.asarray(body.joint_positions(poses[1]))
    assert np.linalg.norm(got[J["r_elbow"]] - truth[J["r_elbow"]]) < 0.03


def test_proposals_out_of_reach_or_already_reached_give_no_candidate():
    body = BodyModel.default(height=1.75)
    tracked = np.zeros(48)
    tracked[2] = 3.0
    joints = np.asarray(body.joint_positions(tracked))
    assert len(reach_candidates(body, tracked, _proposals(joints), 0.002)[0]) == 0
    far = joints.copy()
    far[J["r_wrist"]] += [0.0, 0.0, 1.5]                 # 1.5 m behind: no arm reaches that
    far[J["l_wrist"]] += [0.0, 0.0, 1.5]
    assert len(reach_candidates(body, tracked, _proposals(far), 0.002)[0]) == 0
    weak = JointProposals(_proposals(far).positions, np.full((15, 1), 0.001))
    assert len(reach_candidates(body, tracked, weak, 0.002)[0]) == 0
    assert len(reach_candidates(body, tracked, None, 0.002)[0]) == 0


def test_the_reach_recheck_takes_a_candidate_only_on_a_clear_lead():
    s = TrackerSettings()
    p = s.propose
    state = TrackingState(log=({},) * p.reach_every)
    candidates = lambda pose: (np.stack([pose + 1.0, pose + 2.0]), ["r_arm", "l_leg"])  # noqa: E731
    raw = lambda poses: np.asarray(poses)[:, 0]          # noqa: E731  (the first is best)
    energies = {0.0: 100.0, 1.0: 90.0, 2.0: 50.0}
    refit = lambda pose: (pose, energies[float(pose[0])])  # noqa: E731
    x, changes, switched = recheck_reach(state, np.zeros(48), refit, raw, candidates, s)
    assert switched and (x == 1.0).all()
    assert changes["reaches"] == ({"frame": p.reach_every, "limb": "r_arm", "energy_kept": 100.0,
                                   "energy_reached": 90.0},)
    close = {0.0: 100.0, 1.0: 100.0 * (1 - 0.5 * p.reach_margin), 2.0: 50.0}
    x, changes, switched = recheck_reach(state, np.zeros(48), lambda q: (q, close[float(q[0])]),
                                         raw, candidates, s)
    assert not switched and changes == {} and not x.any()
    _, changes, switched = recheck_reach(state.replace(log=({},)), np.zeros(48), refit, raw,
                                         candidates, s)
    assert not switched and changes == {}
    off = TrackerSettings(propose={"reach_every": 0})
    assert not recheck_reach(state, np.zeros(48), refit, raw, candidates, off)[2]
