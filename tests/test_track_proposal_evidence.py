"""The recogniser's joint proposals as side-free detections for evidence propagation."""
from types import SimpleNamespace

import numpy as np
import pytest

from depthtrack.body import BodyModel
from depthtrack.contract import JOINT_INDEX
from depthtrack.detect.recognizer import JointProposals
from depthtrack.motion.prior import ConstantVelocityPrior
from depthtrack.track.association import associate, prune_by_class
from depthtrack.track.evidence import PART_JOINT, PartModel, propagate_evidence
from depthtrack.track.propagate import PART_GROUPS, evidence_parts
from depthtrack.track.proposals import JOINT_CLASSES, proposal_detections
from depthtrack.track.settings import ProposalSettings, TrackerSettings

KNEES = {"knee": JOINT_CLASSES["knee"]}


@pytest.fixture(scope="module")
def body():
    return BodyModel.default(1.75, mesh="decimated")


def test_joint_centre_parts_sit_on_the_joints_and_their_chains_stop_above(body):
    parts = PartModel.from_body(body, centres=("l_knee", "r_elbow"))
    assert parts.names == tuple(PART_JOINT) + ("l_knee", "r_elbow")
    pose = body.default_pose((0.1, 0.0, 3.0))
    pose[30:33] = [-0.8, 0.2, -0.3]
    p = parts.positions(body, pose[None])[0]
    joints = body.joint_positions(pose)
    np.testing.assert_allclose(p[5], joints[JOINT_INDEX["l_knee"]], atol=1e-9)   # no surface push
    np.testing.assert_allclose(p[6], joints[JOINT_INDEX["r_elbow"]], atol=1e-9)
    # the knee moves with the root and the hip, not with its own rotation
    assert list(parts.chains["l_knee"]) == [0, 1, 2, 3, 4, 5, 30, 31, 32]
    assert set(PART_GROUPS["l_knee"]) >= {"l_hip", "l_knee", "l_ankle"}


def test_proposals_merge_both_sides_into_one_class_most_confident_first():
    pos = np.full((15, 3, 3), np.nan)
    conf = np.zeros((15, 3))
    a, b, c = [0.1, 0.4, 3.0], [-0.1, 0.45, 3.1], [0.0, 0.0, 3.0]
    l, r = JOINT_INDEX["l_knee"], JOINT_INDEX["r_knee"]
    pos[l, :2], conf[l, :2] = [a, b], [0.004, 0.003]
    pos[r, :3], conf[r, :3] = [b, a, c], [0.01, 0.001, 0.0005]     # c below min_confidence
    pos[JOINT_INDEX["l_elbow"], 0], conf[JOINT_INDEX["l_elbow"], 0] = c, 0.02
    dets = proposal_detections(JointProposals(pos, conf), ["knee"], 0.002)
    assert [d.label for d in dets] == ["knee", "knee"]
    np.testing.assert_allclose([d.position for d in dets], [b, a])
    np.testing.assert_allclose([d.score for d in dets], [0.013, 0.004])     # b: 0.003 + 0.01
    assert proposal_detections(None, ["knee"], 0.002) == []


def test_a_proposal_is_explained_only_by_a_model_joint_of_its_class():
    model = {"l_knee": np.array([0.1, 0.4, 3.0]), "r_knee": np.array([-0.1, 0.4, 3.0]),
             "l_hand": np.array([0.3, 0.0, 3.0])}
    near_right = SimpleNamespace(label="knee", position=np.array([-0.12, 0.45, 3.05]))
    on_hand = SimpleNamespace(label="knee", position=np.array([0.31, 0.0, 3.0]))
    assert prune_by_class([near_right, on_hand], model, KNEES, 0.15) == [on_hand]


def test_knee_proposal_pulls_a_wrongly_bent_leg_back(body):
    """A lost left leg (hanging straight while the subject kicks): a knee proposal at the true
    knee, side-free, is tried as either knee; evidence propagation from the left knee's
    correspondence moves the knee there and is accepted, the right knee's is not."""
    parts = PartModel.from_body(body, centres=JOINT_CLASSES["knee"])
    prior = ConstantVelocityPrior.load(fps=25.0)
    truth = body.default_pose((0.1, 0.0, 3.0))
    truth[30] = -0.8                     # l_hip flexed: thigh forward
    truth[33] = 1.0                      # l_knee flexed
    start = truth.copy()
    start[30:36] = 0.0                   # the track lost the leg: straight down
    true_joints = body.joint_positions(truth)
    l_knee = JOINT_INDEX["l_knee"]
    assert np.linalg.norm(body.joint_positions(start)[l_knee] - true_joints[l_knee]) > 0.25

    def energy(x):                       # a stand-in likelihood: joints' distance from the truth
        return float(np.linalg.norm(body.joint_positions(x) - true_joints, axis=1).sum())

    # the tracker's evidence-propagation prior, the root held tighter: here nothing climbs
    # the root back afterwards, as the tracker's hill climbing of the chain does
    std = 4.0 * prior.velocity_std
    std[:6] *= 0.1

    def propagate(x, part, detection):
        return propagate_evidence(body, parts, part, detection.position, x, np.zeros(48),
                                  std, obs_std=0.04).pose

    model = parts.positions(body, start[None])[0]
    proposal = SimpleNamespace(label="knee", position=true_joints[l_knee], score=0.01)
    explained = SimpleNamespace(label="knee", position=model[parts.index("r_knee")] + 0.05,
                                score=0.02)
    res = associate(start, energy(start), [], model[:5], propagate, lambda x, part: (x, energy(x)),
                    proposals=[explained, proposal], joint_positions=dict(zip(parts.names, model)),
                    proposal_classes=KNEES, proposal_distance=0.2, max_proposal_correspondences=4)
    assert res.pruned == 1                                   # the proposal at the right knee
    assert [(c.part, c.proposal) for c in res.tried] == [("l_knee", True), ("r_knee", True)]
    assert [c.accepted for c in res.tried] == [True, False]
    knee = body.joint_positions(res.pose)[l_knee]
    # from over 25 cm to within 7 cm (the MAP stops short of the proposal by the prior's pull)
    assert np.linalg.norm(knee - true_joints[l_knee]) < 0.07
    # the right leg stayed where it was
    np.testing.assert_allclose(res.pose[39:48], start[39:48])

    # no proposal correspondences when their budget is 0 (the setting off)
    off = associate(start, energy(start), [], model[:5], propagate, lambda x, part: (x, energy(x)),
                    proposals=[proposal], joint_positions=dict(zip(parts.names, model)),
                    proposal_classes=KNEES, max_proposal_correspondences=0)
    assert off.tried == [] and np.array_equal(off.pose, start)


def test_evidence_settings_validated_and_off_switch():
    assert evidence_parts(ProposalSettings()) == ("l_elbow", "r_elbow", "l_knee", "r_knee")
    assert evidence_parts(ProposalSettings(evidence=False)) == ()
    assert evidence_parts(ProposalSettings(enabled=False)) == ()
    s = TrackerSettings(propose={"evidence_joints": ["knee", "hip"]})
    assert s.propose.evidence_joints == ("knee", "hip")
    assert TrackerSettings(**s.to_dict()) == s
    from depthtrack.errors import InputError
    for bad in ({"evidence": "yes"}, {"evidence_joints": ("neck",)}, {"evidence_max": 1.5},
                {"evidence_distance": 0.0}):
        with pytest.raises(InputError):
            ProposalSettings(**bad)
