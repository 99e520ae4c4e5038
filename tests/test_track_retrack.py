"""The frames before a correction tracked again backwards (issue 10): after a heading switch,
a limb swap or a recovery, how far the backward track goes, what it must beat, when it is
given up and how much of it is taken, on a short synthetic ToF sequence and closed forms."""
import numpy as np
import pytest
from renderer_kind import software_renderer

from depthtrack.body import BodyModel
from depthtrack.body.skeleton import POSE_INDEX
from depthtrack.evaluate.metrics import point_errors
from depthtrack.track import TrackerSettings
from depthtrack.track.twins import LEGS_SWAPPED, SIDES_SWAPPED, turned_pose
from depthtrack.track.state import TrackingState
from depthtrack.track.tracker import Tracker, fit_pose_to_joints


def test_the_frames_before_a_switch_are_tracked_again_backwards(squat):
    """With retro_frames, the frames the mirrored start spent back to front before the
    recheck's switch are re-tracked from the turned pose, and come out right."""
    body = BodyModel.default(height=1.75)
    truth = squat.joints
    x0 = turned_pose(fit_pose_to_joints(body, truth[0]))
    # the Gaussian motion prior: under Huber's loss the search turns the start by itself
    alone = TrackerSettings().updated({"search": {"untwist": []}, "energy": {"prior_huber": 0.0}})
    retro = alone.updated({"heading": {"retro_frames": 10}})
    pulled, poses = [], {}

    def source():
        for j in range(len(squat)):
            pulled.append(j)
            yield squat.depth(j)
    with Tracker(body, squat.camera, settings=retro) as tracker:
        for i, x in tracker.stream(source(), init_pose=x0):
            # each pose is held back ten frames (a switch may still re-track it), no more
            assert len(pulled) == min(i + 11, len(squat))
            poses[i] = x
        info = tracker.describe()
    assert sorted(poses) == list(range(len(squat)))
    joints = body.joint_positions(np.array([poses[i] for i in range(len(squat))]))
    err = point_errors(joints, truth).mean(axis=-1)
    if not info["heading_switches"] and err.max() < 0.1 and not software_renderer():
        # seen on an H200: the search turned the track before the recheck had to
        pytest.xfail("the recheck had to switch only on llvmpipe; another rasteriser's rounding "
                     "let the search turn the track first")
    # the default's revoke rule ("outscored_unless_met"; its backward track reaches the start
    # without meeting the forward heading, so judged as "outscored") takes the first switch
    # back (frame 4: its four backward frames 1 % worse, better on one of them), and the recheck turns the track
    # again four frames later; that switch's re-track goes back to the start
    switch = info["heading_switches"][-1]
    retracks = [r for r in info["heading_retracks"] if not r.get("revoked")]
    assert all(r["index"] < switch["index"] for r in info["heading_retracks"] if r.get("revoked"))
    retrack = retracks[-1]
    assert retrack["index"] == switch["index"] and retrack["taken"]
    assert retrack["first"] == 0 and retrack["last"] == switch["index"] - 1
    assert retrack["frames_taken"] == retrack["frames"] and retrack["first_taken"] == 0
    # before the first switch the two headings explain the frames alike (the mirrored even
    # a little better: continuity with the switch is what the re-track adds); the frames
    # the revoke left back to front score worse, so the backward track is no worse overall
    assert retrack["energy_backward"] <= 1.05 * retrack["energy_forward"]
    # no frame left back to front, frame 0 included (the previous test: without the
    # re-track the same start is mirrored, 25 cm and more, until the switch)
    assert err.max() < 0.1


def test_a_backward_track_gives_the_frames_up_to_where_it_stopped_doing_as_well():
    from depthtrack.track.retrack import best_prefix
    held = [[1.0, 1.0]] * 6
    assert best_prefix(held, 0.05) == 6                  # alike throughout: every frame
    assert best_prefix(held, 0.0) == 1                   # no margin: exact ties, the first
    lost = [[1.0, 1.0]] * 3 + [[3.0, 1.0]] * 3           # holds three frames, then lost
    assert best_prefix(lost, 0.05) == 3
    # the mean is within the margin (what "all" asks), the last frame is not
    tail = [[0.9, 1.0]] * 5 + [[1.2, 1.0]]
    assert np.mean(np.asarray(tail)[:, 0]) <= 1.05 * np.mean(np.asarray(tail)[:, 1])
    assert best_prefix(tail, 0.05) == 5
    assert best_prefix([[1.2, 1.0], [1.0, 1.0]], 0.05) == 0   # worse next to the correction
    assert best_prefix([[1.2, 1.0], [0.5, 1.0]], 0.05) == 2   # ... but made up for
    assert best_prefix(np.zeros((0, 2)), 0.05) == 0
    with pytest.raises(ValueError, match="retro_take"):
        TrackerSettings(heading={"retro_take": "some"})


def test_a_backward_track_is_taken_whole_within_the_margin_else_where_it_did_better():
    from depthtrack.track.retrack import frames_to_take
    # better next to the correction, worse further back, 3.5 % above the forward poses
    # over all twelve frames
    judged = [[0.9, 1.0]] * 6 + [[1.17, 1.0]] * 6
    assert np.sum(np.asarray(judged)[:, 0]) == pytest.approx(12.42)
    assert frames_to_take(judged, "limbs", 0.05, "prefix") == 12     # within the margin
    assert frames_to_take(judged, "limbs", 0.0, "prefix") == 6       # no margin: the prefix
    assert frames_to_take(judged, "limbs", 0.0, "all") == 0
    assert frames_to_take([[0.9, 1.0]] * 12, "limbs", 0.0, "prefix") == 12
    # after a start the oldest frames where the backward track did better, margin or not
    settle = [[1.0, 1.0]] * 4 + [[0.5, 1.0]] * 2
    assert frames_to_take(settle, "settle", 0.05, "prefix") == 2


def test_a_backward_track_is_given_up_once_it_scores_worse_frame_after_frame():
    from depthtrack.track.retrack import gave_up
    held, lost = [[1.0, 1.0]] * 3, [[2.0, 1.0]]
    # summed excess over 1.05 x forward: -0.05, -0.1, -0.15, then +0.95 a frame
    assert not gave_up(held + lost * 4, 0.05, 5)         # four frames past its best
    assert gave_up(held + lost * 5, 0.05, 5)             # five
    assert not gave_up(held + lost * 5, 0.05, 0)         # 0: never
    # worse frame after frame, but the sum still below zero: the mean rule may yet take it
    assert not gave_up([[0.5, 1.0]] * 3 + [[1.1, 1.0]] * 6, 0.05, 5)
    # a new minimum restarts the count
    back = lost * 2 + [[0.0, 1.0]] * 3                   # sums 0.95, 1.9, 0.85, -0.2, -1.25
    assert not gave_up(back + lost * 4, 0.05, 5)         # four past the new minimum
    assert gave_up(back + lost * 5, 0.05, 5)


def test_a_correction_is_told_by_its_kind_and_the_forward_track_by_what_it_has():
    from depthtrack.track.retrack import _forward_agrees, new_correction
    before = TrackingState(recoveries=({"frame": 1, "frames_to_recover": 0},))
    limbs = before.replace(limb_swaps=({"frame": 3, "limbs": "legs"},))
    assert new_correction(before, limbs, ("heading", "limbs")) == "limbs"
    assert new_correction(before, limbs, ("heading", "recovery")) is None
    # a loss still open is no correction; one closed with the track found is
    opened = before.replace(lost={"frame": 4})
    assert new_correction(before, opened, ("recovery",)) is None
    found = before.replace(recoveries=before.recoveries + ({"frame": 4, "frames_to_recover": 2},))
    given_up = before.replace(recoveries=before.recoveries + ({"frame": 4,
                                                               "frames_to_recover": None},))
    assert new_correction(before, found.replace(limb_swaps=limbs.limb_swaps),
                          ("limbs", "recovery")) == "recovery"
    assert new_correction(before, given_up, ("recovery",)) is None
    body = BodyModel.default(height=1.75)
    x = np.zeros(48)
    x[2] = 3.0
    x[POSE_INDEX["l_hip_rx"]] = -0.8                 # the left thigh forward
    joints = np.asarray(body.joint_positions(x))
    crossed = joints[LEGS_SWAPPED]
    assert _forward_agrees("limbs", "legs", joints, joints + 0.01)
    assert not _forward_agrees("limbs", "legs", joints, crossed)
    assert _forward_agrees("heading", None, joints, crossed)       # the trunk is the same
    assert not _forward_agrees("heading", None, joints, joints[SIDES_SWAPPED])
    assert _forward_agrees("recovery", None, joints, joints + 0.02)
    assert not _forward_agrees("recovery", None, joints, crossed)


def test_a_heading_switch_tracks_back_past_a_limb_swap_or_a_recovery_by_rank():
    from depthtrack.track.retrack import CORRECTION_ORDER, reach_after
    start = dict.fromkeys(CORRECTION_ORDER, 3)                     # tracking started on 3
    # "any": every later re-track stops past the correction, whatever its kind
    assert reach_after(start, "limbs", 10, "any") == dict.fromkeys(CORRECTION_ORDER, 11)
    # "rank": a limb swap bars only limb re-tracks, a recovery recoveries and limbs
    after_limbs = reach_after(start, "limbs", 10, "rank")
    assert after_limbs == {"heading": 3, "recovery": 3, "limbs": 11}
    after_found = reach_after(after_limbs, "recovery", 20, "rank")
    assert after_found == {"heading": 3, "recovery": 21, "limbs": 21}
    # a heading switch bars every kind, and a later limb swap leaves it where it was
    after_turn = reach_after(after_found, "heading", 30, "rank")
    assert after_turn == dict.fromkeys(CORRECTION_ORDER, 31)
    assert reach_after(after_turn, "limbs", 40, "rank")["heading"] == 31
    # the default (since 2026-11-29): a recovery's re-track goes on past a limb swap the
    # lost track made (a cartwheel followed 180 degrees out of phase, then found again)
    default = TrackerSettings().heading.retro_stop
    assert reach_after(start, "limbs", 10, default)["recovery"] == 3
    with pytest.raises(ValueError, match="retro_stop"):
        TrackerSettings(heading={"retro_stop": "never"})


def test_a_settled_track_gives_the_frames_from_the_start_where_it_did_better():
    from depthtrack.track.retrack import settled_frames
    # nearest the settled frame first: alike there, better next to the start
    assert settled_frames([[1.0, 1.0]] * 4 + [[0.5, 1.0]] * 2) == 2
    # worse next to the start, alike after it: nothing
    assert settled_frames([[1.0, 1.0]] * 4 + [[1.5, 1.0]]) == 0
    # alike from the start, better next to the settled frame: the sum from the start is
    # lowest at the far end, so the whole backward track (the first of equal minima is
    # where a tie would stop)
    assert settled_frames([[0.5, 1.0]] * 2 + [[1.0, 1.0]] * 4) == 6
    # a frame worse next to the start, made up for by the one after it
    assert settled_frames([[1.0, 1.0], [0.4, 1.0], [1.2, 1.0]]) == 2
    assert settled_frames(np.zeros((0, 2))) == 0
    with pytest.raises(ValueError, match="retro_settle"):
        TrackerSettings(heading={"retro_settle": -1})


def test_a_start_wrong_in_one_arm_is_tracked_again_from_where_the_track_settled(squat12):
    """retro_settle: a start with the right arm raised 64 cm off, which the track puts right
    on the next frame by itself (no correction to re-track from), gets its first frames
    tracked again backwards from frame 6 and frame 0 comes out right."""
    body = BodyModel.default(height=1.75)
    truth = squat12.joints
    x0 = fit_pose_to_joints(body, truth[0])
    x0[POSE_INDEX["r_shoulder_rz"]] += 1.2                     # the right arm up and out
    wrist = 8                                                    # contract joint r_wrist
    start_error = np.linalg.norm(np.asarray(body.joint_positions(x0))[wrist] - truth[0][wrist])
    assert start_error > 0.4
    settings = TrackerSettings().updated({"heading": {"retro_settle": 6, "retro_frames": 12}})
    with Tracker(body, squat12.camera, settings=settings) as tracker:
        poses = dict(tracker.stream((squat12.depth(j) for j in range(len(squat12))),
                                    init_pose=x0))
        info = tracker.describe()
    settled = [r for r in info["retracks"] if r["kind"] == "settle"]
    assert len(settled) == 1
    entry = settled[0]
    # frames 5 back to 0, all of them: no agreement stops it, no giving up on the way
    assert entry["index"] == 6 and entry["frames"] == 6 and entry["first"] == 0
    assert entry["taken"] and entry["first_taken"] == 0
    joints = np.asarray(body.joint_positions(np.array([poses[i] for i in range(len(squat12))])))
    err = point_errors(joints, truth)
    assert err[0, wrist] < 0.1
    assert err.max() < 0.15
