"""Re-seating a limb from the limb library (depthtrack/track/reseat.py)."""
import numpy as np
import pytest

from depthtrack.body import BodyModel
from depthtrack.body.skeleton import LOWER, POSE_INDEX, UPPER
from depthtrack.contract import JOINT_INDEX
from depthtrack.io import open_sequence
from depthtrack.synth.generate import synthesize_procedural
from depthtrack.track import TrackerSettings
from depthtrack.track.reseat import (LIMB_SLOTS, MIRROR, free_space_limbs, limb_library,
                                     recheck_reseat, reseat_candidates, reseat_limbs)
from depthtrack.track.state import TrackingState
from depthtrack.track.tracker import Tracker, fit_pose_to_joints

R_ARM = [JOINT_INDEX[n] for n in ("r_elbow", "r_wrist")]


@pytest.fixture(scope="module")
def squat(tmp_path_factory):
    """6 frames of a half squat, arms forward (SR4000, ToF noise)."""
    d = tmp_path_factory.mktemp("squat") / "seq"
    synthesize_procedural("squat", d, start=0.6, seconds=0.24, seed=3)
    return open_sequence(d)


def test_the_shipped_library_holds_arm_and_leg_poses_within_the_joint_limits():
    lib = limb_library()
    assert set(lib) == {"arm", "leg"}
    for kind in ("arm", "leg"):
        values = lib[kind]
        assert values.shape[1] == 6 and 16 <= len(values) <= 64
        slots = LIMB_SLOTS[f"l_{kind}"]
        assert (values >= LOWER[slots] - 1e-6).all() and (values <= UPPER[slots] + 1e-6).all()
        # spread, not all variations of one pose: the poses reach far apart
        assert np.ptp(values[:, 0]) > 1.5
    # the mirror maps the left limits onto the right ones
    for kind in ("arm", "leg"):
        left, right = LIMB_SLOTS[f"l_{kind}"], LIMB_SLOTS[f"r_{kind}"]
        lo, hi = LOWER[left] * MIRROR, UPPER[left] * MIRROR
        np.testing.assert_allclose(np.minimum(lo, hi), LOWER[right])
        np.testing.assert_allclose(np.maximum(lo, hi), UPPER[right])


def test_candidates_set_one_limb_each_and_mirror_the_right_side():
    lib = {"arm": np.array([[0.1, 0.2, 0.3, -0.5, 0.1, 0.2]]),
           "leg": np.array([[-0.4, 0.1, 0.2, 0.8, 0.0, 0.1]])}
    pose = np.linspace(-0.3, 0.3, 48)
    limbs, poses = reseat_candidates(pose, lib)
    assert limbs == ["l_arm", "r_arm", "l_leg", "r_leg"] and poses.shape == (4, 48)
    for name, p in zip(limbs, poses):
        slots = LIMB_SLOTS[name]
        side, kind = name.split("_")
        want = lib[kind][0] * (MIRROR if side == "r" else 1.0)
        np.testing.assert_array_equal(p[slots], want)
        rest = np.setdiff1d(np.arange(48), slots)
        np.testing.assert_array_equal(p[rest], pose[rest])
    assert LIMB_SLOTS["r_arm"][:3] == [POSE_INDEX[f"r_shoulder_{a}"] for a in ("rx", "ry", "rz")]


def test_the_recheck_takes_a_reseated_limb_only_on_a_clear_lead_and_when_due():
    """A toy energy (no renderer): the distance of the right arm's slots to a target. The
    refit climbs nothing; the limb's climb returns the candidate as it is."""
    lib = {"arm": np.array([[0.0] * 6, [-1.4, 0.0, 0.0, -0.5, 0.0, 0.0]]),
           "leg": np.array([[0.0] * 6])}
    target = lib["arm"][1] * MIRROR
    slots = LIMB_SLOTS["r_arm"]

    def energy(poses):
        return 100.0 + np.abs(np.atleast_2d(poses)[:, slots] - target).sum(axis=1)

    refit = lambda pose: (pose, float(energy(pose)[0]))                  # noqa: E731
    climb_limb = lambda pose, limb: (pose, float(energy(pose)[0]))       # noqa: E731
    s = TrackerSettings(heading={"reseat_every": 2})
    state = TrackingState(log=({},) * 4)
    pose = np.zeros(48)
    y, changes, switched = recheck_reseat(state, pose, refit, energy, climb_limb, lib, s)
    assert switched and np.allclose(y[slots], target)
    event = changes["reseats"][0]
    assert event["limb"] == "r_arm" and event["frame"] == 4
    assert event["energy_reseated"] < event["energy_kept"]
    # not due on an odd frame; never with reseat_every 0
    odd = TrackingState(log=({},) * 5)
    assert recheck_reseat(odd, pose, refit, energy, climb_limb, lib, s)[2] is False
    off = TrackerSettings(heading={"reseat_free": 0.0})
    assert off.heading.reseat_every == 0
    assert recheck_reseat(state, pose, refit, energy, climb_limb, lib, off)[2] is False
    # a lead under the margin keeps the pose (the target 1.9 away: 1.9 % of ~101.9)
    strict = TrackerSettings(heading={"reseat_every": 2, "reseat_margin": 0.02})
    assert recheck_reseat(state, pose, refit, energy, climb_limb, lib, strict)[2] is False
    with pytest.raises(ValueError, match="reseat_climbs"):
        TrackerSettings(heading={"reseat_climbs": 0})


def test_a_limb_the_camera_sees_through_is_over_free_space():
    """free_space_limbs: a forearm drawn where the camera reads the wall 2 m behind it is
    listed with its share; one drawn on the trunk (readings 5 cm behind) is not; pixels
    without a reading count neither way; too few pixels are not enough."""
    from depthtrack.body.skeleton import JOINTS

    names = list(JOINTS)
    labels = np.full((20, 30), -1)
    model = np.zeros((20, 30))
    depth = np.full((20, 30), 4.0)                  # the wall
    labels[2:6, 2:12] = names.index("l_elbow")      # 40 pixels of the left forearm
    model[2:6, 2:12] = 2.0
    depth[2:6, 2:5] = 2.05                          # 12 of them over the trunk
    depth[5, 5:12] = 0.0                            # 7 without a reading
    labels[10:14, 2:12] = names.index("r_wrist")    # the right hand, on the trunk
    model[10:14, 2:12] = 2.0
    depth[10:14, 2:12] = 2.05
    out = dict(free_space_limbs(model, labels, depth, names, share=0.5, min_pixels=5))
    assert set(out) == {"l_arm"}
    assert out["l_arm"] == pytest.approx(21 / 33)   # 21 through, 33 with a reading
    assert free_space_limbs(model, labels, depth, names, share=0.7, min_pixels=5) == []
    assert free_space_limbs(model, labels, depth, names, share=0.5, min_pixels=22) == []
    # a gap larger than the wall's distance behind: nothing seen through
    assert free_space_limbs(model, labels, depth, names, share=0.5, gap=2.5) == []


def two_limb_energy(first, first_target, second, second_target):
    """A toy recheck energy: 100 plus the L1 distance of limb ``first``'s angles to
    ``first_target (6,)`` and five times limb ``second``'s to ``second_target``; with the refit
    and the limb climb that leave a pose as it is. Returns ``(energy, refit, climb_limb)``."""
    def energy(poses):
        p = np.atleast_2d(poses)
        return (100.0 + np.abs(p[:, LIMB_SLOTS[first]] - first_target).sum(axis=1)
                + 5.0 * np.abs(p[:, LIMB_SLOTS[second]] - second_target).sum(axis=1))

    def refit(pose):
        return pose, float(energy(pose)[0])

    def climb_limb(pose, limb):
        return pose, float(energy(pose)[0])
    return energy, refit, climb_limb


def test_a_limb_over_free_space_is_reseated_alone_on_any_frame():
    """The recheck with ``reseat_free``: on a frame the periodic re-seat is not due, a limb
    the frame lists as over free space is re-seated (only it: the left arm, which would gain
    more, is not tried) and its entry says why; without the setting, or with nothing
    listed, nothing happens."""
    lib = {"arm": np.array([[0.0] * 6, [-1.4, 0.0, 0.0, -0.5, 0.0, 0.0]]),
           "leg": np.array([[0.0] * 6])}
    target = lib["arm"][1] * MIRROR
    energy, refit, climb_limb = two_limb_energy("r_arm", target, "l_arm", lib["arm"][1])
    state = TrackingState(log=({},) * 6)                # frame 6: looked for every 2nd frame
    pose = np.zeros(48)
    s = TrackerSettings(heading={"reseat_free": 0.5, "reseat_free_every": 2})
    assert s.heading.reseat_every == 0
    free = lambda x: [("r_arm", 0.8)]                                     # noqa: E731
    y, changes, switched = recheck_reseat(state, pose, refit, energy, climb_limb, lib, s,
                                          free_limbs=free)
    assert switched and np.allclose(y[LIMB_SLOTS["r_arm"]], target)
    assert np.array_equal(y[LIMB_SLOTS["l_arm"]], pose[LIMB_SLOTS["l_arm"]])
    event = changes["reseats"][0]
    assert event["limb"] == "r_arm" and event["frame"] == 6
    assert event["trigger"] == "free" and event["free_share"] == {"r_arm": 0.8}
    assert not recheck_reseat(state, pose, refit, energy, climb_limb, lib, s,
                              free_limbs=lambda x: [])[2]
    assert not recheck_reseat(state, pose, refit, energy, climb_limb, lib,
                              TrackerSettings(heading={"reseat_free": 0.0}), free_limbs=free)[2]
    odd = TrackingState(log=({},) * 7)                                    # not looked for
    assert not recheck_reseat(odd, pose, refit, energy, climb_limb, lib, s, free_limbs=free)[2]


def test_a_limb_tracked_hidden_is_reseated_on_the_free_space_looks_frames():
    """The recheck with ``reseat_hidden``: a limb the frame lists as hidden is re-seated
    (only it) on the frames the free-space look runs, its entry says ``"trigger":
    "hidden"``; a limb over free space and a hidden one are tried together (the entry's
    trigger "free", both listed); off, or on other frames, nothing happens."""
    lib = {"arm": np.array([[0.0] * 6, [-1.4, 0.0, 0.0, -0.5, 0.0, 0.0]]),
           "leg": np.array([[0.0] * 6, [0.9, 0.0, 0.0, 0.8, 0.0, 0.0]])}
    arm = lib["arm"][1] * MIRROR
    energy, refit, climb_limb = two_limb_energy("r_arm", arm, "l_leg", lib["leg"][1])
    state = TrackingState(log=({},) * 8)
    pose = np.zeros(48)
    on = TrackerSettings(heading={"reseat_hidden": 0.01, "reseat_free_every": 4})
    hidden = lambda x: {"r_arm"}                                         # noqa: E731
    none_free = lambda x: []                                             # noqa: E731
    y, changes, switched = recheck_reseat(state, pose, refit, energy, climb_limb, lib, on,
                                          free_limbs=none_free, hidden_limbs=hidden)
    assert switched and np.allclose(y[LIMB_SLOTS["r_arm"]], arm)
    assert np.array_equal(y[LIMB_SLOTS["l_leg"]], pose[LIMB_SLOTS["l_leg"]])  # not tried
    event = changes["reseats"][0]
    assert event["trigger"] == "hidden" and event["hidden"] == ["r_arm"]
    assert event["limb"] == "r_arm" and "free_share" not in event
    # the leg over free space and the arm hidden: both tried, the leg gains more
    y, changes, _ = recheck_reseat(state, pose, refit, energy, climb_limb, lib, on,
                                   free_limbs=lambda x: [("l_leg", 0.7)], hidden_limbs=hidden)
    event = changes["reseats"][0]
    assert event["limb"] == "l_leg" and event["trigger"] == "free" and event["hidden"] == ["r_arm"]
    # off; and not on a frame the look does not run
    off = TrackerSettings(heading={"reseat_free_every": 4, "reseat_hidden": 0.0})
    assert not recheck_reseat(state, pose, refit, energy, climb_limb, lib, off,
                              free_limbs=none_free, hidden_limbs=hidden)[2]
    odd = TrackingState(log=({},) * 9)
    assert not recheck_reseat(odd, pose, refit, energy, climb_limb, lib, on,
                              free_limbs=none_free, hidden_limbs=hidden)[2]
    with pytest.raises(ValueError, match="reseat_hidden"):
        TrackerSettings(heading={"reseat_hidden": -0.1})


def test_with_reseat_free_climbed_the_climbed_pose_replaces_a_limb_over_free_space():
    """No library pose leads (the library holds only the tracked arm), but the climbed pose
    (the refit: the right elbow bent) clears the listed limb: with ``reseat_free_climbed``
    it replaces the tracked pose and its entry says so; where the climbed pose still holds
    the limb over free space, or without the setting, the tracked pose stays."""
    lib = {"arm": np.array([[0.0] * 6]), "leg": np.array([[0.0] * 6])}
    elbow = LIMB_SLOTS["r_arm"][3]

    def energy(poses):
        return 100.0 + np.abs(np.atleast_2d(poses)[:, elbow] + 0.8)

    bent = np.zeros(48)
    bent[elbow] = -0.8
    refit = lambda pose: (bent, float(energy(bent)[0]))                  # noqa: E731
    climb_limb = lambda pose, limb: (pose, float(energy(pose)[0]))       # noqa: E731
    free = lambda x: [("r_arm", 0.9)] if x[elbow] == 0 else []            # noqa: E731
    state = TrackingState(log=({},) * 4)
    pose = np.zeros(48)
    on = TrackerSettings(heading={"reseat_free_every": 2, "reseat_free_climbed": True,
                                  "reseat_margin": 0.05})
    y, changes, switched = recheck_reseat(state, pose, refit, energy, climb_limb, lib, on,
                                          free_limbs=free)
    assert switched and np.array_equal(y, bent)
    event = changes["reseats"][0]
    assert event["climbed"] is True and event["limb"] == "r_arm" and event["trigger"] == "free"
    assert event["energy_kept"] == pytest.approx(100.8) and event["energy_reseated"] == 100.0
    # the climbed pose still over free space: kept
    assert not recheck_reseat(state, pose, refit, energy, climb_limb, lib, on,
                              free_limbs=lambda x: [("r_arm", 0.9)])[2]
    # the setting off (the default): the tracked pose stays
    default = TrackerSettings(heading={"reseat_free_every": 2, "reseat_margin": 0.05})
    assert default.heading.reseat_free_climbed is False
    assert not recheck_reseat(state, pose, refit, energy, climb_limb, lib, default,
                              free_limbs=free)[2]
    with pytest.raises(ValueError, match="reseat_free_climbed"):
        TrackerSettings(heading={"reseat_free_climbed": 1})


def test_the_start_reseats_limbs_in_turn_while_each_gains_by_the_margin():
    """reseat_limbs (StartSettings.reseat_rounds) on a toy energy: both arms off their
    targets; each round re-seats the limb that gains most, and stops at the first round
    whose best re-seat is under the margin."""
    lib = {"arm": np.array([[0.0] * 6, [-1.4, 0.0, 0.0, -0.5, 0.0, 0.0], [0.6, 0.0, 0.0, 0.0, 0.0, 0.0]]),
           "leg": np.array([[0.0] * 6])}
    right, left = lib["arm"][1] * MIRROR, lib["arm"][2]

    def energy(poses):
        p = np.atleast_2d(poses)
        return (100.0 + 2.0 * np.abs(p[:, LIMB_SLOTS["r_arm"]] - right).sum(axis=1)
                + np.abs(p[:, LIMB_SLOTS["l_arm"]] - left).sum(axis=1))

    climb_limb = lambda pose, limb: (pose, float(energy(pose)[0]))       # noqa: E731
    pose = np.zeros(48)
    e0 = float(energy(pose)[0])                                          # 100 + 3.8 + 0.6
    x, e, events = reseat_limbs(pose, e0, energy, climb_limb, lib, rounds=3, margin=0.0)
    assert [ev["limb"] for ev in events] == ["r_arm", "l_arm"]           # the larger gain first
    np.testing.assert_allclose(x[LIMB_SLOTS["r_arm"]], right)
    np.testing.assert_allclose(x[LIMB_SLOTS["l_arm"]], left)
    assert e == pytest.approx(100.0) and events[0]["energy_kept"] == pytest.approx(e0, abs=0.05)
    # one round: one limb; a margin above the second limb's gain (0.6 of ~100.6) stops there
    assert len(reseat_limbs(pose, e0, energy, climb_limb, lib, rounds=1, margin=0.0)[2]) == 1
    assert len(reseat_limbs(pose, e0, energy, climb_limb, lib, rounds=3, margin=0.01)[2]) == 1
    # nothing gains: the pose comes back as it was
    y, e_y, none = reseat_limbs(x, e, energy, climb_limb, lib, rounds=3, margin=0.0)
    assert none == [] and e_y == e and np.array_equal(y, x)
    assert TrackerSettings().start.reseat_rounds == 0                    # off by default
    with pytest.raises(ValueError, match="reseat_rounds"):
        TrackerSettings(start={"reseat_rounds": -1})


def test_an_arm_held_behind_the_back_is_reseated_while_tracking(squat):
    """The right arm starts swung back behind the body while it is held forward. "hc" (no
    recogniser, no association) climbs it back only slowly; the re-seat puts it back on its
    first due frame. Without it the arm is still far off on that frame."""
    body = BodyModel.default(height=1.75)
    truth = squat.joints
    x0 = fit_pose_to_joints(body, truth[0])
    x0[LIMB_SLOTS["r_arm"]] = [0.9, 0.0, 0.0, -0.2, 0.0, 0.0]         # swung back
    depths = [squat.depth(i) for i in range(len(squat))]

    def arm_errors(settings):
        with Tracker(body, squat.camera, method="hc", settings=settings) as tracker:
            state, _, _ = tracker.start(TrackingState(), depths[0], pose=x0)
            joints = []
            for depth in depths[1:]:
                state, x = tracker.advance(state, depth)
                joints.append(body.joint_positions(x)[R_ARM])
        err = np.linalg.norm(np.array(joints) - truth[1:, R_ARM], axis=-1).mean(axis=-1)
        return err, state.reseats

    common = {"every": 0, "limb_every": 0}
    err, reseats = arm_errors(TrackerSettings(heading={**common, "reseat_every": 2}))
    assert err[0] > 0.5                                  # frame 1: not yet due
    assert reseats[0]["limb"] == "r_arm" and reseats[0]["frame"] == 2
    assert reseats[0]["energy_reseated"] < 0.97 * reseats[0]["energy_kept"]
    assert err[1:].max() < 0.08                          # frames 2-5
    stuck, none = arm_errors(TrackerSettings(heading=common))
    assert not none and stuck[1] > 0.5


def test_an_arm_out_past_the_body_is_reseated_on_the_next_frame(squat):
    """The right arm starts swung across the trunk and out past its far side, where the
    camera sees the room behind the forearm, while it hangs at the side. With
    ``reseat_free`` the re-seat puts it back on frame 1 (no periodic re-seat); without it
    the arm is still far off there."""
    body = BodyModel.default(height=1.75)
    truth = squat.joints
    x0 = fit_pose_to_joints(body, truth[0])
    x0[LIMB_SLOTS["r_arm"]] = [0.0, 0.0, -1.3, 0.0, 0.0, 0.0]         # across and out
    depths = [squat.depth(i) for i in range(3)]

    def first_frame(settings):
        with Tracker(body, squat.camera, method="hc", settings=settings) as tracker:
            state, _, _ = tracker.start(TrackingState(), depths[0], pose=x0)
            state, x = tracker.advance(state, depths[1])
        err = np.linalg.norm(body.joint_positions(x)[R_ARM] - truth[1, R_ARM], axis=-1).mean()
        return err, state.reseats

    common = {"every": 0, "limb_every": 0}
    err, reseats = first_frame(TrackerSettings(heading={**common, "reseat_free": 0.5,
                                                        "reseat_free_every": 1}))
    assert reseats and reseats[0]["limb"] == "r_arm" and reseats[0]["frame"] == 1
    assert reseats[0]["trigger"] == "free" and reseats[0]["free_share"]["r_arm"] >= 0.5
    assert err < 0.1
    stuck, none = first_frame(TrackerSettings(heading={**common, "reseat_free": 0.0}))
    assert not none and stuck > 0.3
