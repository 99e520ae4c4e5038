"""Holding on: a mirrored start is corrected while tracking, a lost track is recovered and
reported (issue 10), on short synthetic ToF sequences."""
import numpy as np
import pytest
from renderer_kind import software_renderer

from depthtrack.body import BodyModel
from depthtrack.body.skeleton import POSE_INDEX
from depthtrack.contract import JOINT_NAMES
from depthtrack.track import TrackerSettings
from depthtrack.track.heading import (flip_search, recheck_heading, recheck_limb_sides,
                                      search_switch, settle_heading, sort_by_heading)
from depthtrack.track.twins import (LEGS_SWAPPED, SIDES_SWAPPED, facing_direction, fit_joints,
                                    limb_swapped_twins, swapped_twin, swapped_twins, turned_pose)
from depthtrack.track.judge import judge_frame
from depthtrack.track.retrack import revoke_rule
from depthtrack.track.state import TrackingState
from depthtrack.track.tracker import Tracker, fit_pose_to_joints


def _errors(joints, truth):
    return np.linalg.norm(np.asarray(joints) - truth, axis=-1).mean(axis=-1)


def test_swapped_twin_keeps_the_joints_and_faces_the_other_way():
    body = BodyModel.default(height=1.75)
    x = np.zeros(48)
    x[2] = 3.0
    x[POSE_INDEX["l_hip_rx"]] = -0.8                 # a thigh forward: not symmetric
    y = swapped_twin(body, x)
    a, b = np.asarray(body.joint_positions(x)), np.asarray(body.joint_positions(y))
    assert np.abs(b - a[SIDES_SWAPPED]).max() < 0.03
    from depthtrack.body.rotations import rotvec_to_matrix
    from depthtrack.body.skeleton import MODEL_FORWARD
    fa = rotvec_to_matrix(x[3:6]) @ MODEL_FORWARD
    fb = rotvec_to_matrix(y[3:6]) @ MODEL_FORWARD
    assert fa @ fb < -0.9
    # the fit from the rest pose lands on the same joints, facing the other way too
    both = swapped_twins(body, x, ("turned", "rest"))
    assert both.shape == (2, 48) and np.allclose(both[0], y)
    c = np.asarray(body.joint_positions(both[1]))
    assert np.abs(c - a[SIDES_SWAPPED]).max() < 0.03
    assert facing_direction(both[1]) @ fa < -0.9


def test_a_twin_turned_with_its_legs_kept_exchanges_every_side_but_the_legs():
    """``twin_swaps`` ``"all_but_legs"``: the twin faces the other way, its shoulders, arms
    and hips on the other sides, its knees and ankles where the pose had them (the
    thighs uncrossed from a wrong-facing track's crossed ones)."""
    body = BodyModel.default(height=1.75)
    legs = [JOINT_NAMES.index(f"{s}_{j}") for s in "lr" for j in ("knee", "ankle")]
    rest = [JOINT_NAMES.index(f"{s}_{j}") for s in "lr" for j in ("shoulder", "elbow", "wrist", "hip")]
    x = np.zeros(48)
    x[2] = 3.0
    x[POSE_INDEX["l_hip_rx"]] = -0.6                 # the left thigh forward
    a = np.asarray(body.joint_positions(x))
    knee = JOINT_NAMES.index("l_knee")
    assert np.linalg.norm(a[knee] - a[SIDES_SWAPPED][knee]) > 0.1
    twins = swapped_twins(body, x, ("turned", "rest"), ("all_but_legs",))
    assert twins.shape == (2, 48)
    for twin in twins:                               # from the turned pose and from rest
        b = np.asarray(body.joint_positions(twin))
        assert np.abs(b[legs] - a[legs]).max() < 0.04
        assert np.abs(b[rest] - a[SIDES_SWAPPED][rest]).max() < 0.04
        assert facing_direction(twin) @ facing_direction(x) < -0.9
    assert len(swapped_twins(body, x, ("rest",), ("all", "all_but_legs"))) == 2
    assert TrackerSettings().heading.twin_swaps == ("all",)
    with pytest.raises(ValueError, match="twin_swaps"):
        TrackerSettings(heading={"twin_swaps": ["legs"]})


def test_search_results_count_for_the_heading_they_have():
    x = np.zeros(48)
    turned = turned_pose(x)
    # a search asked for the other heading that came back facing the same way counts there
    flipped, e_flipped, e_same = sort_by_heading(x, 500.0, [(x + 0.01, 450.0), (turned, 470.0)])
    assert np.array_equal(flipped, turned) and e_flipped == 470.0 and e_same == 450.0
    assert sort_by_heading(x, 500.0, [(x, 520.0)]) == (None, None, 500.0)


def test_the_start_check_keeps_the_heading_its_score_prefers():
    start = TrackingState(pose=np.zeros(48), log=({},))
    depths = [None] * 3
    # the turned twin (pose all ones) leaves more unexplained but fits with lower energy
    scores = {0.0: {"unexplained": 0.10, "energy": 1.20}, 1.0: {"unexplained": 0.11, "energy": 1.15}}

    def track(state, frames):
        return state, np.tile(state.pose, (len(frames), 1)), scores[float(state.pose[0])]

    turn = lambda pose: pose + 1.0                       # noqa: E731
    by_share = TrackerSettings()
    assert by_share.heading.start_by == "unexplained"
    state, poses = settle_heading(start, depths, track, turn, by_share)
    check = state.init_info["heading_check"]
    assert check["kept"] == "initial" and check["by"] == "unexplained" and not poses.any()
    assert poses.shape == (4, 48) and check["energy_turned"] == 1.15
    assert check["ambiguous"]                           # 0.10 against 0.11: within 10 %
    by_energy = TrackerSettings(heading={"start_by": "energy"})
    state, poses = settle_heading(start, depths, track, turn, by_energy)
    assert state.init_info["heading_check"]["kept"] == "turned" and (poses == 1.0).all()
    assert state.init_info["heading_check"]["ambiguous"] is False   # margin 0: never close
    clear = {0.0: {"unexplained": 0.10, "energy": 1.2}, 1.0: {"unexplained": 0.2, "energy": 1.3}}
    state, _ = settle_heading(start, depths, lambda st, f: (st, np.tile(st.pose, (len(f), 1)),
                                                             clear[float(st.pose[0])]),
                              turn, by_share)
    assert state.init_info["heading_check"]["ambiguous"] is False
    # a lead within the margin keeps the start's heading
    close = TrackerSettings(heading={"start_by": "energy", "energy_margin": 0.05})
    state, _ = settle_heading(start, depths, track, turn, close)
    assert state.init_info["heading_check"]["kept"] == "initial"
    # the start's own track dropped: no decision
    assert settle_heading(start, depths, lambda s, f: None, turn, by_share) is None
    with pytest.raises(ValueError, match="start_by"):
        TrackerSettings(heading={"start_by": "votes"})


def test_a_close_start_check_is_decided_on_the_finer_tiles_when_asked():
    """``judge_start``: an ambiguous check (unexplained shares within 10 %) keeps the track
    whose energy on the judge's tiles is lower; a clear one stays with its own score."""
    start = TrackingState(pose=np.zeros(48), log=({},))
    scores = {0.0: {"unexplained": 0.110, "energy": 1.20, "judged": 1.50},
              1.0: {"unexplained": 0.107, "energy": 1.24, "judged": 1.40}}

    def track(state, frames, table=scores):
        return state, np.tile(state.pose, (len(frames), 1)), table[float(state.pose[0])]

    turn = lambda pose: pose + 1.0                       # noqa: E731
    judged = TrackerSettings(heading={"judge_tile": 256, "judge_start": True})
    state, poses = settle_heading(start, [None] * 3, track, turn, judged)
    check = state.init_info["heading_check"]
    assert check["kept"] == "turned" and (poses == 1.0).all() and check["decided_by"] == "judge"
    assert (check["judged_initial"], check["judged_turned"]) == (1.5, 1.4)
    # without judge_start (no "judged" score) the close call keeps the initial heading
    plain = {k: {n: v for n, v in sc.items() if n != "judged"} for k, sc in scores.items()}
    state, _ = settle_heading(start, [None] * 3, lambda st, f: track(st, f, plain), turn, judged)
    assert state.init_info["heading_check"]["kept"] == "initial"
    assert "decided_by" not in state.init_info["heading_check"]
    # a clear call is not re-decided: the turned twin 20 % better, the judge the other way
    clear = {0.0: {"unexplained": 0.20, "energy": 1.2, "judged": 1.0},
             1.0: {"unexplained": 0.10, "energy": 1.3, "judged": 2.0}}
    state, _ = settle_heading(start, [None] * 3, lambda st, f: track(st, f, clear), turn, judged)
    assert state.init_info["heading_check"]["kept"] == "turned"
    with pytest.raises(ValueError, match="judge_start"):
        TrackerSettings(heading={"judge_start": "yes"})


def test_recheck_switches_after_enough_votes_only():
    s = TrackerSettings()
    h = s.heading
    state = TrackingState(log=({},) * h.every)          # a frame the recheck runs on
    twin = lambda pose: pose + 1.0                      # noqa: E731
    # the pose (all zeros) refits to energy 200, its twin (all ones) to 100
    refit = lambda pose: (pose, 100.0 if pose[0] else 200.0)  # noqa: E731
    x, changes, switched = recheck_heading(state, np.zeros(48), refit, twin, 1000.0, s)
    assert not switched and changes["heading_votes"] == 1 and not x.any()
    state = state.replace(heading_votes=h.votes - 1)
    x, changes, switched = recheck_heading(state, np.zeros(48), refit, twin, 1000.0, s)
    assert switched and (x == 1.0).all() and changes["heading_switches"][0]["frame"] == h.every
    # within the margin: no vote, and the votes start over
    half = 0.5 * h.recheck_margin * 1000.0
    close = lambda pose: (pose, 200.0 - (half if pose[0] else 0.0))  # noqa: E731
    _, changes, switched = recheck_heading(state, np.zeros(48), close, twin, 1000.0, s)
    assert not switched and changes["heading_votes"] == 0
    # not on the frames between rechecks
    _, changes, switched = recheck_heading(state.replace(log=({},)), np.zeros(48), refit, twin,
                                           1000.0, s)
    assert not switched and changes == {}


def test_the_judge_compares_the_climbed_poses_and_the_setting_reaches_it():
    """With a judge (``HeadingSettings.judge_tile``) the two climbed hypotheses are compared
    by its energies, not by the climbs': a tie at the climbs' tiles that the finer tiles
    decide votes, and the judge sees the climbed poses."""
    s = TrackerSettings()
    h = s.heading
    state = TrackingState(log=({},) * h.every, heading_votes=h.votes - 1)
    twin = lambda pose: pose + 1.0                      # noqa: E731
    tie = lambda pose: (pose + 0.5, 200.0)              # noqa: E731 (climbing moves the poses)
    _, changes, switched = recheck_heading(state, np.zeros(48), tie, twin, 1000.0, s)
    assert not switched and changes["heading_votes"] == 0
    seen = []

    def judge(poses):                                   # the twin (climbed: 1.5) far lower
        seen.append(np.asarray(poses)[:, 0].tolist())
        return np.where(np.asarray(poses)[:, 0] > 1.0, 100.0, 200.0)

    x, changes, switched = recheck_heading(state, np.zeros(48), tie, twin, 1000.0, s, judge=judge)
    assert seen == [[0.5, 1.5]] and switched and (x == 1.5).all()
    assert changes["heading_switches"][0]["energy_turned"] == 100.0
    assert TrackerSettings(heading={"judge_tile": 256}).heading.judge_tile == 256
    with pytest.raises(ValueError, match="judge_tile"):
        TrackerSettings(heading={"judge_tile": 100})


def test_a_close_call_is_judged_again_polished_and_a_clear_one_is_not():
    """``HeadingSettings.polish_within``: where the judged lead is above minus the band,
    both poses are polished and judged again, and the polished twin is what takes over;
    where the twin trails by more than the band, nothing is polished."""
    s = TrackerSettings(heading={"polish_within": 0.05, "polish_evidence": "replace"})
    h = s.heading
    state = TrackingState(log=({},) * h.every, heading_votes=h.votes - 1)
    twin = lambda pose: pose + 1.0                      # noqa: E731
    tie = lambda pose: (pose + 0.5, 200.0)              # noqa: E731
    polished = []

    def polish(poses):                                  # the polished twin 0.2 / px lower
        polished.append(np.asarray(poses)[:, 0].tolist())
        return np.asarray(poses) + 0.25, np.array([300.0, 100.0])

    def judge_by(lead):                                 # the twin's judged lead per pixel
        return lambda poses: np.array([200.0, 200.0 - 1000.0 * lead])

    x, changes, switched = recheck_heading(state, np.zeros(48), tie, twin, 1000.0, s,
                                           judge=judge_by(-0.01), polish=polish)
    assert polished == [[0.5, 1.5]] and switched and (x == 1.75).all()
    assert changes["heading_switches"][0]["energy_turned"] == 100.0
    x, changes, switched = recheck_heading(state, np.zeros(48), tie, twin, 1000.0, s,
                                           judge=judge_by(-0.08), polish=polish)
    assert len(polished) == 1 and not switched and changes["heading_votes"] == 0
    # "both": a clear lead for the twin is left as judged, a close one either way polished
    both = TrackerSettings(heading={"polish_within": 0.05, "polish_side": "both",
                                    "polish_evidence": "replace"})
    x, changes, switched = recheck_heading(state, np.zeros(48), tie, twin, 1000.0, both,
                                           judge=judge_by(0.08), polish=polish)
    assert len(polished) == 1 and switched and (x == 1.5).all()
    x, changes, switched = recheck_heading(state, np.zeros(48), tie, twin, 1000.0, both,
                                           judge=judge_by(0.03), polish=polish)
    assert len(polished) == 2 and switched and (x == 1.75).all()
    assert TrackerSettings().heading.polish_within == 0.05
    with pytest.raises(ValueError, match="polish_within"):
        TrackerSettings(heading={"polish_within": -0.1})


def test_separate_polished_evidence_adds_switches_and_keeps_the_judged_ones():
    """``polish_evidence = "separate"``: the judged leads feed the default's votes and sum
    unchanged (a judged switch takes the unpolished twin, though the polish shrank its
    lead), the polished leads a second set whose switch takes the polished twin, marked
    ``polished``; a switch clears both sets. ``polish_revoke`` judges only polished switches."""
    s = TrackerSettings(heading={"polish_within": 0.05, "polish_evidence": "separate"})
    h = s.heading
    twin = lambda pose: pose + 1.0                      # noqa: E731
    tie = lambda pose: (pose + 0.5, 200.0)              # noqa: E731

    def polish_to(lead):                                # both moved by 0.25, the twin's lead
        return lambda poses: (np.asarray(poses) + 0.25, np.array([200.0, 200.0 - 1000.0 * lead]))

    def judge_by(lead):
        return lambda poses: np.array([200.0, 200.0 - 1000.0 * lead])

    # a judged vote away from a switch; polished, the lead is gone: the judged set still switches
    state = TrackingState(log=({},) * h.every, heading_votes=h.votes - 1)
    x, changes, switched = recheck_heading(state, np.zeros(48), tie, twin, 1000.0, s,
                                           judge=judge_by(0.08), polish=polish_to(-0.02))
    assert switched and (x == 1.5).all() and "polished" not in changes["heading_switches"][0]
    assert changes["polished_votes"] == 0 and changes["polished_evidence"] == 0.0
    # the judged lead small, the polished one a vote: only the polished set counts it
    state = TrackingState(log=({},) * h.every, polished_votes=h.votes - 1)
    x, changes, switched = recheck_heading(state, np.zeros(48), tie, twin, 1000.0, s,
                                           judge=judge_by(0.0), polish=polish_to(0.08))
    event = changes["heading_switches"][0]
    assert switched and (x == 1.75).all() and event["polished"] and event["by"] == "votes"
    assert event["energy_turned"] == 120.0
    # no switch: each set keeps its own sum
    state = TrackingState(log=({},) * h.every, heading_evidence=0.02, polished_evidence=0.02)
    x, changes, switched = recheck_heading(state, np.zeros(48), tie, twin, 1000.0, s,
                                           judge=judge_by(-0.03), polish=polish_to(0.04))
    assert not switched and (x == 0.0).all()
    assert changes["heading_evidence"] == 0.0
    assert changes["polished_evidence"] == pytest.approx(0.02 + 0.04 - h.evidence_drift)
    # "replace" (the default's shape): the polished lead stands for the judged one, one set
    one = TrackerSettings(heading={"polish_within": 0.05, "polish_evidence": "replace"})
    x, changes, switched = recheck_heading(state, np.zeros(48), tie, twin, 1000.0, one,
                                           judge=judge_by(-0.03), polish=polish_to(0.04))
    assert changes["heading_evidence"] == pytest.approx(0.02 + 0.04 - h.evidence_drift)
    assert "polished_evidence" not in changes
    with pytest.raises(ValueError, match="polish_evidence"):
        TrackerSettings(heading={"polish_evidence": "both"})
    # which rule judges a switch's re-track
    r = TrackerSettings(heading={"polish_revoke": "unsupported"}).heading
    assert revoke_rule(r, {"by": "votes", "polished": True}) == "unsupported"
    assert revoke_rule(r, {"by": "votes"}) == r.retro_revoke == "outscored_unless_met"
    same = TrackerSettings(heading={"polish_revoke": "same"}).heading
    assert revoke_rule(same, {"polished": True}) == "outscored_unless_met"
    d = TrackerSettings().heading                      # the default since 2026-11-29
    assert (d.polish_within, d.polish_evidence, d.polish_revoke) == (0.05, "separate", "unsupported")


def test_small_steady_leads_add_up_and_mixed_ones_cancel():
    """The CUSUM: leads below the vote margin switch once their sum passes the threshold;
    leads of either sign (a frontal view) never do."""
    s = TrackerSettings()
    h = s.heading
    pixels = 1000.0
    lead = 0.5 * h.recheck_margin                        # below the margin: never a vote
    twin = lambda pose: pose + 1.0                      # noqa: E731
    steady = lambda pose: (pose, 200.0 - (lead * pixels if pose[0] else 0.0))  # noqa: E731
    state = TrackingState(log=({},) * h.every)
    needed = int(np.ceil(h.evidence_threshold / (lead - h.evidence_drift) + 1e-9))
    for k in range(1, needed + 1):
        _, changes, switched = recheck_heading(state, np.zeros(48), steady, twin, pixels, s)
        assert switched == (k == needed), k
        if not switched:
            assert changes["heading_votes"] == 0
            assert changes["heading_evidence"] == pytest.approx(k * (lead - h.evidence_drift))
            state = state.replace(**changes)
    assert changes["heading_switches"][-1]["by"] == "evidence"
    state = TrackingState(log=({},) * h.every)
    for k in range(40):
        sign = 1.0 if k % 2 else -1.0
        mixed = lambda pose, sg=sign: (pose, 200.0 - (sg * lead * pixels if pose[0] else 0.0))  # noqa: E731
        _, changes, switched = recheck_heading(state, np.zeros(48), mixed, twin, pixels, s)
        assert not switched
        state = state.replace(**changes)


def test_a_mirrored_start_is_corrected_while_tracking(squat12):
    squat = squat12                 # the corrections land by frame 10
    body = BodyModel.default(height=1.75)
    truth = squat.joints
    x0 = turned_pose(fit_pose_to_joints(body, truth[0]))
    # the default corrects it by frame 7 in the search, with no heading switch: the untwist
    # moves do it (with them off the track stays mirrored until the recheck's switch)
    every = TrackerSettings().heading.every
    # (without the re-track of the frames before a switch: the next test measures that)
    forward = TrackerSettings(heading={"retro_frames": 0})
    with Tracker(body, squat.camera, settings=forward) as tracker:
        err = _errors(tracker.track_sequence(squat, init_pose=x0).joints, truth)
    assert err[0] > 0.25 and err[2 * every:].max() < 0.1
    # the heading recheck alone (untwist moves off) corrects it too, by a switch (and without
    # the re-track of the frames before it, which the next test measures)
    # the motion prior Gaussian (prior_huber 0): under Huber's loss the search alone turns
    # this start, and the control below is corrected too
    alone = TrackerSettings().updated({"search": {"untwist": []}, "heading": {"retro_frames": 0},
                                       "energy": {"prior_huber": 0.0}})
    with Tracker(body, squat.camera, settings=alone) as tracker:
        result = tracker.track_sequence(squat, init_pose=x0)
        switches = tracker.describe()["heading_switches"]
    err = _errors(result.joints, truth)
    assert err[0] > 0.25                          # the start is the mirrored twin
    if not switches and err[2 * every:].max() < 0.1 and not software_renderer():
        # seen on an H200: the search turned the track before the recheck had to
        pytest.xfail("the recheck had to switch only on llvmpipe; another rasteriser's rounding "
                     "let the search turn the track first")
    assert len(switches) == 1 and switches[0]["frame"] <= 2 * every
    assert err[switches[0]["frame"]:].max() < 0.1  # corrected from the switch on
    # the same start with the recheck off stays mirrored
    with Tracker(body, squat.camera, settings=alone.updated({"heading": {"every": 0}})) as tracker:
        stuck = _errors(tracker.track_sequence(squat, init_pose=x0).joints, truth)
    if stuck[-5:].min() <= 0.25 and not software_renderer():
        # on an H200 another stage (not the heading recheck) turned this track too
        pytest.xfail("the control stayed mirrored only on llvmpipe; another rasteriser's rounding "
                     "let another stage turn it")
    assert stuck[-5:].min() > 0.25


def test_limb_swapped_twins_exchange_one_pair_of_limbs_and_keep_the_trunk():
    body = BodyModel.default(height=1.75)
    pose = np.zeros(48)
    pose[30], pose[33] = -0.7, 0.9                     # left hip forward, left knee bent
    pose[12] = pose[21] = 1.2                          # both arms forward, hands in front,
    pose[14], pose[23] = 0.5, -0.5                     # a forearm's length apart
    pose[15] = -1.0                                    # left elbow bent
    joints = np.asarray(body.joint_positions(pose))
    twins = dict(limb_swapped_twins(body, pose))
    assert set(twins) == {"legs", "arms"}
    legs = np.asarray(body.joint_positions(twins["legs"]))
    from depthtrack.contract import JOINT_INDEX as J
    assert np.linalg.norm(legs[J["r_knee"]] - joints[J["l_knee"]]) < 0.03
    assert np.linalg.norm(legs[J["l_ankle"]] - joints[J["r_ankle"]]) < 0.03
    trunk = [J[n] for n in ("head", "neck", "pelvis", "l_shoulder", "r_shoulder", "l_elbow")]
    assert np.abs(legs[trunk] - joints[trunk]).max() < 0.02
    arms = np.asarray(body.joint_positions(twins["arms"]))
    for side, other in (("r_wrist", "l_wrist"), ("l_wrist", "r_wrist")):
        assert np.linalg.norm(arms[J[side]] - joints[J[other]]) < 0.1
    assert np.abs(arms[[J["l_knee"], J["r_ankle"]]] - joints[[J["l_knee"], J["r_ankle"]]]).max() < 0.02


def test_the_sides_recheck_takes_a_twin_only_on_a_clear_lead():
    s = TrackerSettings()
    h = s.heading
    state = TrackingState(log=({},) * h.limb_every)
    twins = lambda pose: [("legs", pose + 1.0), ("arms", pose + 2.0)]  # noqa: E731
    energies = {0.0: 100.0, 1.0: 80.0, 2.0: 90.0}
    refit = lambda pose: (pose, energies[float(pose[0])])             # noqa: E731
    x, changes, switched = recheck_limb_sides(state, np.zeros(48), refit, twins, s)
    assert switched and (x == 1.0).all()
    assert changes["limb_swaps"] == ({"frame": h.limb_every, "limbs": "legs",
                                      "energy_kept": 100.0, "energy_swapped": 80.0},)
    close = {0.0: 100.0, 1.0: 100.0 * (1 - 0.5 * h.limb_margin), 2.0: 120.0}
    x, changes, switched = recheck_limb_sides(
        state, np.zeros(48), lambda pose: (pose, close[float(pose[0])]), twins, s)
    assert not switched and changes == {} and not x.any()
    _, changes, switched = recheck_limb_sides(state.replace(log=({},)), np.zeros(48), refit,
                                              twins, s)
    assert not switched and changes == {}


def test_a_start_with_the_legs_crossed_is_uncrossed_while_tracking(squat12):
    squat = squat12                 # the corrections land by frame 10
    body = BodyModel.default(height=1.75)
    truth = squat.joints
    x_true = fit_pose_to_joints(body, truth[0])
    x0 = fit_joints(body, np.asarray(body.joint_positions(x_true))[LEGS_SWAPPED], x_true)
    legs = [i for i, n in enumerate(JOINT_NAMES) if n[2:] in ("knee", "ankle")]

    def leg_errors(joints):
        return np.linalg.norm(np.asarray(joints)[:, legs] - truth[:, legs], axis=-1).mean(axis=-1)

    assert leg_errors(body.joint_positions(x0)[None])[0] > 0.15   # the start's legs crossed
    # with the frames before the swap re-tracked backwards from it (retro_after)
    retro = TrackerSettings(heading={"retro_after": ["heading", "limbs"]})
    with Tracker(body, squat.camera, settings=retro) as tracker:
        result = tracker.track_sequence(squat, init_pose=x0)
        info = tracker.describe()
    swaps = info["limb_swaps"]
    err = leg_errors(result.joints)
    assert swaps and swaps[0]["limbs"] == "legs"
    assert swaps[0]["frame"] <= 2 * TrackerSettings().heading.limb_every
    # the forward track is right from the swap on, and the re-track puts the frames before
    # it right too, the start's frame included
    retrack = info["retracks"][0]
    assert retrack["kind"] == "limbs" and retrack["index"] == swaps[0]["index"]
    assert retrack["taken"] and retrack["first"] == 0
    assert info["heading_retracks"] == [r for r in info["retracks"] if r["kind"] == "heading"]
    assert err.max() < 0.1
    off = TrackerSettings(heading={"limb_every": 0})
    with Tracker(body, squat.camera, settings=off) as tracker:
        stuck = leg_errors(tracker.track_sequence(squat, init_pose=x0).joints)
    if stuck[-5:].min() <= 0.15 and not software_renderer():
        # seen on an H200: another stage (not the sides recheck) uncrossed this track too
        pytest.xfail("the control stayed crossed only on llvmpipe; another rasteriser's rounding "
                     "let another stage uncross it")
    assert stuck[-5:].min() > 0.15


def test_flip_search_asks_for_the_other_heading_and_switches_on_a_clear_lead_only():
    pose = np.zeros(48)
    pose[3:6] = [0.0, 0.7, 0.0]
    asked = []
    flip_search(lambda heading, axis: asked.append((heading, axis)) or (pose, 0.0), pose)
    heading, axis = asked[0]
    assert heading @ facing_direction(pose) == pytest.approx(-1.0)
    assert np.linalg.norm(axis) == pytest.approx(1.0) and abs(axis @ heading) < 1e-9
    s = TrackerSettings()
    pixels = 1000.0
    state = TrackingState(log=({},) * 7)
    margin = s.heading.search_margin * pixels
    taken, changes = search_switch(state, 500.0, pose + 1, 500.0 - 0.9 * margin, pixels, s)
    assert taken is None and changes == {}
    taken, changes = search_switch(state, 500.0, pose + 1, 500.0 - 1.1 * margin, pixels, s)
    assert np.array_equal(taken, pose + 1)
    assert changes["heading_switches"][-1]["by"] == "search"
    assert changes["heading_switches"][-1]["frame"] == 7


def test_a_mirrored_start_is_corrected_by_the_flip_search(squat12):
    """With the twin recheck off, the periodic flip search alone turns a mirrored track."""
    squat = squat12                 # the corrections land by frame 10
    body = BodyModel.default(height=1.75)
    truth = squat.joints
    x0 = turned_pose(fit_pose_to_joints(body, truth[0]))
    heading = TrackerSettings().heading.__class__(every=0, search_every=5, retro_frames=0)
    with Tracker(body, squat.camera, settings=TrackerSettings(heading=heading)) as tracker:
        result = tracker.track_sequence(squat, init_pose=x0)
        switches = tracker.describe()["heading_switches"]
    err = _errors(result.joints, truth)
    assert err[0] > 0.25
    assert switches and switches[0]["by"] == "search" and switches[0]["frame"] <= 10
    assert err[switches[0]["frame"]:].max() < 0.1


def test_loss_bookkeeping_opens_closes_and_gives_up():
    s = TrackerSettings()
    state = TrackingState(log=({"cost": 0.2},) * 4)
    changes, flags = judge_frame(state, 0.9, "unexplained", s)
    assert changes["lost"] == {"frame": 4, "reason": "unexplained"} and flags == {"lost": True}
    state = state.replace(log=state.log + ({"cost": 0.9, **flags},) * 2, **changes)
    changes, flags = judge_frame(state, 0.2, None, s)
    assert changes["recoveries"] == ({"frame": 4, "reason": "unexplained",
                                      "frames_to_recover": 2},) and changes["lost"] is None
    assert state.recent_costs(8) == [0.2] * 4     # lost frames are not the norm
    long = state.replace(log=state.log + ({"lost": True},) * s.judge.max_lost_frames)
    changes, flags = judge_frame(long, 0.9, "unexplained", s)
    assert changes["recoveries"][-1]["frames_to_recover"] is None and flags["reset"]


def test_a_recovery_must_beat_the_tracked_pose_on_what_recover_by_names(squat):
    """The search's pose replaces the tracked one only where it is better by the figure
    :attr:`JudgeSettings.recover_by` names. The tracked pose here is the previous frame's
    true pose, said to leave everything unexplained: the unexplained rule takes the
    search's pose; the energy rule sees the tracked pose explain the frame better (it is
    nearly right) and keeps it."""
    from depthtrack.track.judge import recover
    body = BodyModel.default(height=1.75)
    truth = squat.joints
    f = 8
    before = fit_pose_to_joints(body, truth[f - 1])

    def recovered(rule, x, cost):
        settings = TrackerSettings(judge={"recover_by": rule})
        with Tracker(body, squat.camera, settings=settings) as tracker:
            state, _, _ = tracker.start(tracker.state, squat.depth(f - 1), pose=before)
            frame, _ = tracker._observe(state, squat.depth(f), predicted=before)
            return recover(tracker, tracker._energy(frame), frame, before, x, cost)
    taken, y, y_cost = recovered("unexplained", before, 1.0)
    assert taken and y_cost < 1.0 and not np.allclose(y, before)
    kept, z, z_cost = recovered("energy", before, 1.0)
    assert not kept and z is before and z_cost == 1.0
    assert _errors(body.joint_positions(before[None]), truth[f:f + 1])[0] < 0.05


def test_a_lost_track_is_recovered_within_five_frames_and_reported(squat):
    body = BodyModel.default(height=1.75)
    truth = squat.joints
    lose = 6
    with Tracker(body, squat.camera, settings=TrackerSettings()) as tracker:
        tracker.init(squat.depth(0), pose=fit_pose_to_joints(body, truth[0]))
        joints = [body.joint_positions(tracker.pose)]
        for i in range(1, len(squat)):
            if i == lose:                           # the track jumps far off
                far = tracker.pose.copy()
                far[0] += 0.7
                far[3:6] = turned_pose(far)[3:6]
                tracker.state = tracker.state.replace(pose=far)
            joints.append(body.joint_positions(tracker.step(squat.depth(i))))
        info = tracker.describe()
    err = _errors(np.array(joints), truth)
    assert err[:lose].max() < 0.1
    rec = info["recoveries"]
    assert rec[0]["frame"] == lose and rec[0]["reason"] == "unexplained"
    assert rec[0]["index"] == lose                  # init/step: the frames stepped
    # every loss reported closed, the last within 5 frames of the jump (a global search
    # may land a few centimetres off and be judged lost once more)
    assert all(r["frames_to_recover"] is not None for r in rec)
    back = rec[-1]["frame"] + rec[-1]["frames_to_recover"]
    assert back - lose <= 5
    assert err[lose + 5:].max() < 0.1
