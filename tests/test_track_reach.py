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
    # candidates that say where they came from: the record says too
    sourced = lambda pose: (*candidates(pose), ["unexplained", "proposal"])  # noqa: E731
    _, changes, switched = recheck_reach(state, np.zeros(48), refit, raw, sourced, s)
    assert switched and changes["reaches"][0]["from"] == "unexplained"


def test_an_arm_in_plain_view_that_the_pose_leaves_unexplained_is_reached_for():
    """The truth raises its right arm forward; the tracked pose has it down. Rendered on
    SR4000 pixels, the person's raised forearm is a blob no part of the pose covers, and
    the right arm's candidate reaches into it."""
    from depthtrack.camera import Camera
    from depthtrack.render import FrameRenderer
    from depthtrack.track.reach import blob_reach_candidates, unexplained_blobs

    body = BodyModel.default(height=1.75, mesh="decimated")
    camera = Camera.preset("sr4000")
    truth_pose = _raised_right_arm()
    tracked = np.zeros(48)
    tracked[2] = 3.0
    with FrameRenderer(camera) as r:
        person = r.render(body, truth_pose)
        model = r.render(body, tracked)
    pixels = np.count_nonzero(person)
    blobs = unexplained_blobs(model, person, camera, int(0.02 * pixels))
    assert 1 <= len(blobs) <= 3
    assert all(len(b) >= 0.02 * pixels for b in blobs)
    # the points are the person's surface: back on its pixels
    uv = camera.project(blobs[0])
    u, v = np.round(uv[:, 0]).astype(int), np.round(uv[:, 1]).astype(int)
    np.testing.assert_allclose(person[v, u], blobs[0][:, 2], atol=1e-5)
    truth = np.asarray(body.joint_positions(truth_pose))
    poses, limbs = blob_reach_candidates(body, tracked, blobs)
    assert "r_arm" in limbs
    wrist = [np.linalg.norm(np.asarray(body.joint_positions(p))[J["r_wrist"]] - truth[J["r_wrist"]])
             for p, limb in zip(poses, limbs) if limb == "r_arm"]
    before = np.linalg.norm(np.asarray(body.joint_positions(tracked))[J["r_wrist"]] - truth[J["r_wrist"]])
    assert before > 0.3 and min(wrist) < 0.15
    # the same pose as the person leaves nothing to reach for
    assert unexplained_blobs(person, person, camera, int(0.02 * pixels)) == []


def test_a_person_pixel_in_front_of_the_model_is_unexplained_beyond_the_gap():
    from depthtrack.camera import Camera

    camera = Camera(8, 8, 10.0, 10.0, 3.5, 3.5)
    person = np.zeros((8, 8))
    person[2:6, 2:6] = 2.0
    model = np.where(person > 0, 2.05, 0.0)              # 5 cm behind: explained
    assert unexplained_blobs_of(model, person, camera) == []
    model[2:4, 2:6] = 2.3                                 # 30 cm behind on two rows: not
    blobs = unexplained_blobs_of(model, person, camera)
    assert len(blobs) == 1 and len(blobs[0]) == 8
    np.testing.assert_allclose(blobs[0][:, 2], 2.0)
    np.testing.assert_allclose(blobs[0][0], [(2 - 3.5) * 2.0 / 10.0, (2 - 3.5) * 2.0 / 10.0, 2.0])


def unexplained_blobs_of(model, person, camera):
    from depthtrack.track.reach import unexplained_blobs

    return unexplained_blobs(model, person, camera, 2)


def test_a_limb_whose_lower_segment_hardly_shows_is_hidden():
    from depthtrack.track.reach import hidden_limbs

    names = BodyModel.default(mesh="decimated").joint_names
    labels = np.full((10, 10), -1, np.int16)
    labels[0:5, :] = names.index("l_elbow")              # 50 pixels of the left forearm
    labels[5, 0:3] = names.index("r_wrist")               # 3 of the right hand
    labels[6:8, :] = names.index("l_knee")                # 20 of the left shin
    labels[8:10, :] = names.index("r_knee")               # 20 of the right shin, off the person
    person = np.ones((10, 10), bool)
    person[8:10, :] = False
    assert hidden_limbs(labels, person, names, 10) == {"r_arm", "r_leg"}
    assert hidden_limbs(labels, person, names, 60) == {"l_arm", "r_arm", "l_leg", "r_leg"}
