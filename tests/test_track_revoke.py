"""A heading switch taken back when the frames before it do not bear it out
(``HeadingSettings.retro_revoke``, issue 10): the rules in closed form, and a wrong switch
injected into a track that faces the right way, on a short synthetic ToF sequence; and a
track a quarter turn off replaced by a fresh look (``JudgeSettings.look_every``)."""
import numpy as np
import pytest

from depthtrack.body import BodyModel
from depthtrack.evaluate.metrics import point_errors
from depthtrack.track import TrackerSettings
from depthtrack.track.tracker import Tracker, fit_pose_to_joints


def test_a_switch_is_taken_back_by_the_rule_asked_for():
    """retro_revoke's rules over (frames taken, frames next to the switch done better)."""
    from depthtrack.track.retrack import revokes

    cases = [(0, 0), (5, 0), (3, 3), (0, 2)]   # refused; taken whole but worse next to it; ...
    assert [revokes("never", *c) for c in cases] == [False] * 4
    assert [revokes("refused", *c) for c in cases] == [True, False, False, True]
    assert [revokes("unsupported", *c) for c in cases] == [True, True, False, False]
    # "outscored" reads the whole stretch too: (taken, better, frames re-tracked, worse over them)
    stretch = [(44, 13, 44, True), (44, 13, 44, False), (44, 22, 44, True), (9, 0, 9, False),
               (16, 5, 16, False)]
    assert [revokes("outscored", t, b, n, outscored=w) for t, b, n, w in stretch] == \
        [True, False, False, True, False]
    assert [revokes("unsupported", t, b, n, outscored=w) for t, b, n, w in stretch] == \
        [False, False, False, True, False]
    # "outscored_unless_met": "outscored", but "unsupported" where the backward track met the
    # forward heading (the turn found inside the window: a fast spin's frames fit either badly)
    assert [revokes("outscored_unless_met", t, b, n, outscored=w) for t, b, n, w in stretch] == \
        [True, False, False, True, False]
    assert [revokes("outscored_unless_met", t, b, n, outscored=w, met=True)
            for t, b, n, w in stretch] == [False, False, False, True, False]
    assert revokes("outscored_unless_met", 0, 3, 9, outscored=True, met=True) is False
    assert revokes("outscored", 0, 3, 9, outscored=True, met=True) is True



def _switch_to_the_twin_on(frame: int, monkeypatch) -> None:
    """Make the heading recheck switch to the swapped twin, climbed, on ``frame`` (when it
    runs there: ``heading.every``), ``by`` ``"injected"``; on other frames it is itself."""
    import depthtrack.track.rechecks as rechecks

    real = rechecks.recheck_heading

    def switching_on_one_frame(state, pose, refit, twins, pixels, settings, judge=None,
                               polish=None):
        if state.frame != frame or not settings.heading.every:
            return real(state, pose, refit, twins, pixels, settings, judge, polish)
        twin, _ = refit(np.asarray(twins(pose)).reshape(-1, len(pose))[0])
        switch = {"frame": state.frame, "energy_kept": 0.0, "energy_turned": 0.0,
                  "by": "injected", "evidence": 0.0}
        return twin, {"heading_votes": 0, "heading_evidence": 0.0,
                      "heading_switches": state.heading_switches + (switch,)}, True
    monkeypatch.setattr(rechecks, "recheck_heading", switching_on_one_frame)


def test_a_switch_whose_backward_track_gives_nothing_is_taken_back(squat, monkeypatch):
    """With retro_revoke "refused", a heading switch to the wrong heading -- the swapped
    twin, climbed, injected on frame 4 of a track that faces the right way, the judge's
    recovery off so that only the re-track can answer it -- is re-tracked, the backward
    track scores worse from its first frame, and the switch is taken back: no frame back to
    front. Without it frame 4 is back to front (the recheck would turn the track again four
    frames later; six frames are tracked)."""
    from depthtrack.body.facing import back_to_front

    body = BodyModel.default(height=1.75)
    x0 = fit_pose_to_joints(body, squat.joints[0])
    wrong_on = 4                         # the recheck's first turn (every 4)
    _switch_to_the_twin_on(wrong_on, monkeypatch)
    base = TrackerSettings().updated({"search": {"untwist": []},
                                      "heading": {"retro_frames": 10, "every": 4},
                                      "judge": {"lost_ratio": 100.0},
                                      "propose": {"lost_frames": 1000}})
    runs = {}
    frames = 6                           # the switch on 4, the recheck's next turn on 8
    for revoke in ("never", "refused"):
        settings = base.updated({"heading": {"retro_revoke": revoke}})
        with Tracker(body, squat.camera, settings=settings) as tracker:
            poses = [x for _, x in tracker.stream((squat.depth(j) for j in range(frames)),
                                                  init_pose=x0)]
            runs[revoke] = (tracker.describe(), body.joint_positions(np.array(poses)))
    info, joints = runs["never"]
    assert info["heading_switches"][0]["index"] == wrong_on
    truth = squat.joints[:frames]
    assert back_to_front(joints, truth)[wrong_on] == 1.0      # the injected switch
    first = info["retracks"][0]
    assert first["index"] == wrong_on and not first["taken"] and "revoked" not in first
    info, joints = runs["refused"]
    entry = info["retracks"][0]
    assert entry["revoked"] and entry["index"] == wrong_on and entry["switch"]["by"] == "injected"
    assert entry["frames"] > 0 and entry["frames_taken"] == 0 and entry["frames_better"] == 0
    assert entry["energy_backward"] > entry["energy_forward"]
    assert all(s["index"] != wrong_on for s in info["heading_switches"])
    assert not np.any(back_to_front(joints, truth) == 1.0)
    assert point_errors(joints, truth).mean(axis=-1).max() < 0.1


def _a_start_a_quarter_turn_off(squat):
    """``(body, x0 (48,), settings)``: the truth's frame-0 pose turned 90 degrees about the
    body's long axis, and settings that look every other frame with the loss judge, the
    proposals' loss and the front/back and limb rechecks off."""
    from depthtrack.rotations import matrix_to_rotvec, rotation_about, rotvec_to_matrix
    from depthtrack.body.skeleton import MODEL_UP

    body = BodyModel.default(height=1.75)
    x0 = fit_pose_to_joints(body, squat.joints[0])
    R = rotvec_to_matrix(x0[3:6])
    x0[3:6] = matrix_to_rotvec((rotation_about(R @ MODEL_UP, np.pi / 2) @ R)[None])[0]
    settings = TrackerSettings().updated({"heading": {"every": 0, "limb_every": 0},
                                          "judge": {"lost_ratio": 100.0, "look_every": 2},
                                          "propose": {"lost_frames": 1000}})
    return body, x0, settings


def test_a_fresh_look_replaces_a_track_a_quarter_turn_off(squat):
    """JudgeSettings.look_every: a track started a quarter turn off (the truth's frame-0
    pose turned 90 degrees about the body's long axis; the loss judge and the front/back
    recheck off) is replaced by the global search on the first frame due ("look" in the
    recoveries, 0 frames to recover), and the frames before it are tracked again from there:
    every frame on the person (up to front and back, the heading recheck's question, off
    here), frame 0 included. With look_margin 1 (no search is 100 % lower) the search runs
    on the same frames and is never taken, and frame 0 stays a quarter turn off; so with
    look_turn 30 degrees (the search's pose faces about 90 degrees from the track's): every
    look refused and counted in looks_turned_away."""
    from depthtrack.track.twins import SIDES_SWAPPED

    body, x0, base = _a_start_a_quarter_turn_off(squat)
    frames = 5
    runs = {}
    for margin, turn in ((0.1, 120.0), (1.0, 120.0), (0.1, 30.0)):
        settings = base.updated({"judge": {"look_margin": margin, "look_turn": turn}})
        with Tracker(body, squat.camera, settings=settings) as tracker:
            poses = [x for _, x in tracker.stream((squat.depth(j) for j in range(frames)),
                                                  init_pose=x0)]
            joints = np.asarray(body.joint_positions(np.array(poses)))
        truth = squat.joints[:frames]
        runs[margin, turn] = (tracker.describe(), np.minimum(    # nearer as is or turned
            point_errors(joints, truth).mean(axis=-1),
            point_errors(joints[:, SIDES_SWAPPED], truth).mean(axis=-1)))
    info, err = runs[0.1, 120.0]
    looks = [r for r in info["recoveries"] if r["reason"] == "look"]
    assert looks and looks[0]["index"] == 2 and looks[0]["frames_to_recover"] == 0
    assert err.max() < 0.08 and err[0] < 0.05
    never, err_never = runs[1.0, 120.0]
    assert never["counts"]["recoveries_tried"] == 2 and never["counts"]["recoveries"] == 0
    assert not [r for r in never["recoveries"] if r["reason"] == "look"]
    assert err_never[0] > 0.2
    away, err_away = runs[0.1, 30.0]
    assert away["counts"]["looks_turned_away"] == 2 and away["counts"]["recoveries"] == 0
    assert not [r for r in away["recoveries"] if r["reason"] == "look"]
    assert err_away[0] > 0.2


def test_look_turn_is_how_far_the_root_is_turned_front_for_back_or_head_for_feet():
    """judge.look_turn_deg: 0 for a pose itself, the turn for the pose turned about its long
    axis (front for back) or about its forward direction (head for feet, in the image plane
    of a body facing the camera), 90 and 180 degrees, whatever the pose's own orientation."""
    from depthtrack.rotations import matrix_to_rotvec, rotation_about, rotvec_to_matrix
    from depthtrack.body.skeleton import MODEL_FORWARD, MODEL_UP
    from depthtrack.track.judge import look_turn_deg

    rng = np.random.default_rng(3)
    for _ in range(5):
        x = np.zeros(48)
        x[3:6] = rng.normal(size=3)
        R = rotvec_to_matrix(x[3:6])
        assert look_turn_deg(x, x) == pytest.approx(0.0, abs=1e-4)
        for axis in (MODEL_UP, MODEL_FORWARD):    # front for back; head for feet
            for deg in (90.0, 180.0):
                y = x.copy()
                y[3:6] = matrix_to_rotvec((rotation_about(R @ axis, np.radians(deg)) @ R)[None])[0]
                assert look_turn_deg(x, y) == pytest.approx(deg, abs=1e-3)


def test_the_start_checks_tracks_take_no_fresh_look(squat):
    """judge.NO_LOOK: the start check's two tracks each test one heading and run without
    fresh looks. Looking on every frame (look_every 1) over six frames with a two-frame start
    check, only the two frames tracked after the check get the look's search (start on 0,
    check on 1 and 2 for each heading, forward 3 to 5: three searches, not seven)."""
    body = BodyModel.default(height=1.75)
    settings = TrackerSettings().updated({"heading": {"frames": 2, "min_frames": 2},
                                          "judge": {"look_every": 1, "lost_ratio": 100.0},
                                          "propose": {"lost_frames": 1000}})
    with Tracker(body, squat.camera, settings=settings) as tracker:
        poses = [x for _, x in tracker.stream(squat.depth(j) for j in range(6))]
        info, check = tracker.describe(), tracker.state.init_info["heading_check"]
    assert len(poses) == 6 and check["frames"] == 2
    assert info["counts"]["recoveries_tried"] == 3


def test_a_look_its_rule_takes_back_leaves_the_track_as_it_was(squat, monkeypatch):
    """JudgeSettings.look_revoke: a look whose re-track the rule takes back (here every one:
    the rule itself is tested in closed form above) is gone from the recoveries, its frame
    tracked again without it, and its entry kept in the re-track's ``recovery`` with
    ``revoked``; the start a quarter turn off then stays so, as with no look taken."""
    from depthtrack.track import retrack

    rules = []

    def every_look(rule, *args, **kwargs):
        rules.append(rule)
        return rule != "never"
    monkeypatch.setattr(retrack, "revokes", every_look)
    body, x0, settings = _a_start_a_quarter_turn_off(squat)
    with Tracker(body, squat.camera, settings=settings) as tracker:
        poses = [x for _, x in tracker.stream((squat.depth(j) for j in range(5)), init_pose=x0)]
        info = tracker.describe()
    assert "outscored" in rules                       # the default look_revoke judged a look
    assert not [r for r in info["recoveries"] if r["reason"] == "look"]
    revoked = [r for r in info["retracks"] if r.get("revoked")]
    assert revoked and all(r["recovery"]["reason"] == "look" and r["kind"] == "recovery"
                           for r in revoked)
    joints = np.asarray(body.joint_positions(np.array(poses)))
    assert point_errors(joints[:1], squat.joints[:1]).mean() > 0.2


def test_a_look_sets_no_floor_for_a_later_re_track(squat, monkeypatch):
    """retrack.was_look: the frames a fresh look's re-track went back over stay open to a
    later correction's re-track (a look is one frame's energy; dev wide cartwheel seed 2:
    the proposals' recovery on 21 stopped at the floor a look on 16 had set), while any
    other correction's re-track closes them. The look is real (the start a quarter turn
    off, taken on frame 2); the later correction is a recovery injected on frame 4 (a loss
    found again at once). Its re-track may reach frame 0 after the look; with the look read
    as a loss (``was_look`` patched to say no), only frame 3."""
    from depthtrack.track import loop

    floors = []
    real_retrack, real_advance = loop.retrack_before_correction, loop._advance_into

    def recording(tracker, held, recent, first, at, kind="heading"):
        floors.append((at, kind, first))
        return real_retrack(tracker, held, recent, first, at, kind)

    def found_again_on_4(tracker, held, i, depth):
        real_advance(tracker, held, i, depth)
        if i == 4:
            s = tracker.state
            tracker.state = s.replace(recoveries=s.recoveries + (
                {"frame": 4, "index": 4, "reason": "injected", "frames_to_recover": 0},))
    monkeypatch.setattr(loop, "retrack_before_correction", recording)
    monkeypatch.setattr(loop, "_advance_into", found_again_on_4)
    body, x0, settings = _a_start_a_quarter_turn_off(squat)
    settings = settings.updated({"judge": {"look_every": 2, "look_revoke": "never"}})
    seen = {}
    for look_is_look in (True, False):
        floors.clear()
        if not look_is_look:
            monkeypatch.setattr(loop, "was_look", lambda state, kind: False)
        with Tracker(body, squat.camera, settings=settings) as tracker:
            list(tracker.stream((squat.depth(j) for j in range(5)), init_pose=x0))
            looks = [r["index"] for r in tracker.describe()["recoveries"] if r["reason"] == "look"]
        assert looks[:1] == [2]                        # the look itself, taken on frame 2
        seen[look_is_look] = dict(((at, kind), first) for at, kind, first in floors)
    assert seen[True][2, "recovery"] == 0 and seen[True][4, "recovery"] == 0
    assert seen[False][2, "recovery"] == 0 and seen[False][4, "recovery"] == 3


def test_a_switch_taken_back_after_a_look_is_the_switch(squat, monkeypatch):
    """revoke_switch takes back the correction it was asked to: a heading switch injected on
    frame 4, after a fresh look on frame 2 (the start a quarter turn off), that its re-track
    takes back ("refused") is the switch -- gone from the heading switches, its entry's
    ``switch`` -- and the look stands. (Read from the newest recovery alone, the look was
    taken back instead and the switch left standing: dev 01_08 from 90 degrees seed 3.) The
    rules patched: "refused" takes back every correction, "never" none (the rules
    themselves are tested in closed form above)."""
    from depthtrack.track import retrack

    monkeypatch.setattr(retrack, "revokes", lambda rule, *args, **kwargs: rule == "refused")
    body, x0, settings = _a_start_a_quarter_turn_off(squat)
    settings = settings.updated({"heading": {"every": 4, "retro_revoke": "refused"},
                                 "judge": {"look_revoke": "never"}})
    _switch_to_the_twin_on(4, monkeypatch)
    with Tracker(body, squat.camera, settings=settings) as tracker:
        list(tracker.stream((squat.depth(j) for j in range(6)), init_pose=x0))
        info = tracker.describe()
    assert [r["index"] for r in info["recoveries"] if r["reason"] == "look"][:1] == [2]
    revoked = [r for r in info["retracks"] if r.get("revoked")]
    assert [(r["kind"], r["index"]) for r in revoked] == [("heading", 4)]
    assert revoked[0]["switch"]["by"] == "injected" and "recovery" not in revoked[0]
    assert all(sw["index"] != 4 for sw in info["heading_switches"])
