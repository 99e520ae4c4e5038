"""The paper's association loop: prune, expand by class, greedy EP + refine, keep what lowers the energy."""
from types import SimpleNamespace

import numpy as np

from depthtrack.track.association import associate, expand_correspondences, prune_explained


def det(label, pos, score=1.0):
    return SimpleNamespace(label=label, position=np.asarray(pos, float), score=score)


PARTS = np.array([[0, -0.7, 3.0], [0.3, 0.0, 3.0], [-0.3, 0.0, 3.0], [0.1, 0.9, 3.0], [-0.1, 0.9, 3.0]])


def test_prune_keeps_only_unexplained_detections():
    dets = [det("hand", [0.31, 0.02, 3.0]), det("hand", [0.6, -0.6, 2.8]),
            det("head", [0.29, 0.0, 3.05])]          # a head detection on a hand: explained too
    kept = prune_explained(dets, PARTS, 0.15)
    assert kept == [dets[1]]


def test_expand_by_class_best_score_first():
    dets = [det("foot", [0, 0, 0], 0.2), det("hand", [0, 0, 0], 0.9), det("head", [0, 0, 0], 0.5)]
    corr = expand_correspondences(dets)
    assert [(c.part, c.detection.label) for c in corr] == [
        ("l_hand", "hand"), ("r_hand", "hand"), ("head", "head"), ("l_foot", "foot"), ("r_foot", "foot")]


def test_greedy_loop_accepts_only_improvements_and_propagates_from_the_current_best():
    # energy = distance of pose[0] from 5; each proposal sets pose[0] to a value per part
    proposals = {"l_hand": 9.0, "r_hand": 4.0, "head": 6.0}
    seen_starts = []

    def propagate(pose, part, detection):
        seen_starts.append(pose[0])
        out = pose.copy()
        out[0] = proposals[part]
        return out

    def evaluate(pose, part):
        return pose, abs(pose[0] - 5.0)

    start = np.zeros(48)
    dets = [det("hand", [1, 1, 3], 0.9), det("head", [2, 2, 3], 0.5)]
    res = associate(start, 5.0, dets, PARTS, propagate, evaluate, prune_distance=0.15)
    assert [c.part for c in res.tried] == ["l_hand", "r_hand", "head"]
    assert [c.accepted for c in res.tried] == [True, True, False]   # 4 (e=1) beats 9 (e=4); 6 ties
    assert res.pose[0] == 4.0 and res.energy == 1.0
    # each correspondence is propagated alone from the best pose so far
    assert seen_starts == [0.0, 9.0, 4.0]


def test_no_detections_leaves_the_pose():
    start = np.arange(48.0)
    res = associate(start, 1.0, [], PARTS, None, None)
    assert np.array_equal(res.pose, start) and res.energy == 1.0 and res.tried == []
