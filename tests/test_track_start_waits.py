"""Holding on, continued: a start that waits for the whole person and tracks the frames before
it backwards, and the rechecks' climbs (issue 10), on short synthetic ToF sequences. Split from
test_track_recovery.py so that the two CI workers (``--dist loadfile``) share the long tracks."""
import numpy as np
import pytest
from conftest import FirstFrames

from depthtrack.body import BodyModel
from depthtrack.track import TrackerSettings
from depthtrack.track.twins import SIDES_SWAPPED
from depthtrack.track.rechecks import heading_twins, recheck_twins
from depthtrack.track.state import TrackingState
from depthtrack.track.tracker import Tracker, fit_pose_to_joints


def _errors(joints, truth):
    return np.linalg.norm(np.asarray(joints) - truth, axis=-1).mean(axis=-1)


def test_a_start_waits_for_the_whole_person_and_tracks_the_frames_before_backwards(squat):
    """The first three frames show only the upper body (the rest out of view): with
    ``complete_fraction`` the start waits for the whole person and the frames before it are
    tracked backwards from there (ten frames: the start on frame 3, seven tracked on)."""
    squat = FirstFrames(squat, 10)
    body = BodyModel.default(height=1.75)
    truth = squat.joints
    depths = [squat.depth(i).copy() for i in range(len(squat))]
    c = squat.camera
    knee_rows = c.fy * truth[:3, 10, 1] / truth[:3, 10, 2] + c.cy      # l_knee's image row
    for k in range(3):
        depths[k][int(knee_rows[k]) - 25:] = 0.0                          # hips and legs gone
    settings = TrackerSettings(start={"complete_fraction": 0.7})
    with Tracker(body, c, fps=squat.fps, settings=settings) as tracker:
        poses = dict(tracker.stream(depths))
        info = tracker.state.init_info
        log = tracker.frame_log
        described = tracker.describe()
    assert info["deferred_frames"] == 3
    # the forward track's log starts at the start's sequence frame; every event says where
    assert [f["index"] for f in log] == list(range(3, len(squat)))
    for key in ("recoveries", "heading_switches", "limb_swaps", "reaches"):
        for event in described[key]:
            assert event["index"] == (log[event["frame"]]["index"] if event["frame"] is not None
                                      else event["index"]) and 0 <= event["index"] < len(squat)
    assert sorted(poses) == list(range(len(squat))) and all(p is not None for p in poses.values())
    joints = np.array([body.joint_positions(poses[i]) for i in range(len(squat))])
    err = _errors(joints, truth)
    assert err[3:].max() < 0.1                    # the start on the whole person holds
    # the backward track reached frame 0 (its frames are the last three tracked, in reverse)
    assert _errors(joints[2:3], truth[2:3])[0] < 1.0 and np.isfinite(joints[:3]).all()
    # off: the start is on frame 0, the upper body alone (three frames show it)
    with Tracker(body, c, fps=squat.fps,
                 settings=TrackerSettings(start={"complete_fraction": 0.0})) as tracker:
        poses_off = dict(tracker.stream(depths[:3]))
        assert "deferred_frames" not in tracker.state.init_info
    assert sorted(poses_off) == list(range(3))
    with pytest.raises(ValueError, match="complete_fraction"):
        TrackerSettings(start={"complete_fraction": 1.5})


def test_a_backward_tracks_events_get_their_sequence_frames():
    """The backward track counts its frames on from the start (log index ``start + k`` for
    the k-th frame back); its events are reported at the sequence frame ``start - k``."""
    from depthtrack.track.loop import _track_back

    start = TrackingState(log=({"cost": 0.1},) * 5, recoveries=({"frame": 1, "reason": "old"},))
    back = start.replace(log=start.log + ({"cost": 0.1},) * 3,
                         recoveries=start.recoveries + ({"frame": 6, "reason": "unexplained",
                                                         "frames_to_recover": 0},),
                         reaches=({"frame": 5, "limb": "l_arm"},))

    class Through:                      # the tracker's track_through, with the result above
        def track_through(self, state, depths):
            assert state is start and depths == ["d9", "d8", "d7"]
            return back, np.arange(3)[:, None] * np.ones(48), {}

    frames, events = _track_back(Through(), start, ["d7", "d8", "d9"], 7)
    assert [i for i, _ in frames] == [7, 8, 9] and frames[0][1][0] == 2   # reversed back
    assert events["recoveries"] == ({"frame": None, "reason": "unexplained", "frames_to_recover": 0,
                                     "index": 8, "backward": True},)
    assert events["reaches"] == ({"frame": None, "limb": "l_arm", "index": 9, "backward": True},)
    assert events["heading_switches"] == () and events["limb_swaps"] == ()


def test_the_rechecks_climbs_begin_on_the_configured_rung(squat):
    """``heading.refit_level``: the rechecks' climbs skip the coarsest rungs and score fewer
    candidates; the frames' own search is the same, and a track right from the start stays
    right."""
    body = BodyModel.default(height=1.75)
    truth = squat.joints
    x0 = fit_pose_to_joints(body, truth[0])
    depths = [squat.depth(i) for i in range(4)]
    heading = {}
    for level in (0, 3):
        settings = TrackerSettings(heading={"every": 1, "limb_every": 0, "refit_level": level},
                                   propose={"reach_every": 0}, polish={"fine_tile": 0},
                                   search={"passes": 1})
        with Tracker(body, squat.camera, settings=settings) as tracker:
            state, _, _ = tracker.start(TrackingState(), depths[0], pose=x0)
            poses = []
            for depth in depths[1:]:
                state, x = tracker.advance(state, depth)
                poses.append(x)
            heading[level] = tracker.recorder.candidates_by_stage["heading"]
            assert not state.heading_switches
        assert _errors(body.joint_positions(np.array(poses)), truth[1:4]).max() < 0.1
    assert heading[3] < 0.8 * heading[0]


def test_the_recheck_climbs_only_the_twin_fits_lowest_before_climbing(squat):
    body = BodyModel.default(height=1.75)
    x = fit_pose_to_joints(body, squat.joints[0])
    target = np.asarray(body.joint_positions(x))[SIDES_SWAPPED]

    def energy(poses):              # any energy: here the twin's distance to its target joints
        joints = np.asarray(body.joint_positions(np.asarray(poses)))
        return np.linalg.norm(joints - target, axis=-1).mean(axis=-1)

    for k, want in ((0, 2), (1, 1), (2, 2)):
        settings = TrackerSettings(heading={"twin_climbs": k})
        twins = heading_twins(body, settings, x)
        picked = recheck_twins(body, settings, energy, x)
        assert len(twins) == 2 and picked.shape == (want, 48)
        if want == 1:
            np.testing.assert_array_equal(picked[0], twins[int(np.argmin(energy(twins)))])


def test_a_start_waits_for_the_person_clear_of_the_image_edge(squat):
    """``complete_uncut``: of the frames with enough of the person, the start takes the first
    whose person does not run off the image (dev 02_03: a runner entering the view had a leg
    and an arm outside it on the frame the area alone chose)."""
    import collections

    from depthtrack.track.loop import _complete_view, first_complete
    from depthtrack.track.observation import cut_by_border

    mask = np.zeros((40, 50), dtype=bool)
    mask[10:30, 20:30] = True
    assert not cut_by_border(mask)
    mask[15:20, 0:20] = True                        # an arm out of the left edge
    assert cut_by_border(mask)
    mask[15:20, 0] = False
    mask[16:18, 0] = True                           # two stray pixels are not a cut
    assert not cut_by_border(mask)
    assert first_complete([0.5, 0.8, 1.0, 1.0], 0.7) == 1
    assert first_complete([0.5, 0.8, 1.0, 1.0], 0.7, [False, True, True, False]) == 3
    # nobody clear of the edges in the frames read ahead: the area alone decides
    assert first_complete([0.5, 0.8, 1.0, 1.0], 0.7, [True] * 4) == 1

    # the squat's first two frames moved left until the person's leftmost columns leave the
    # image (most of the person still in view, so the area alone would start on frame 0)
    c = squat.camera
    depths = [squat.depth(i).copy() for i in range(8)]
    with Tracker(BodyModel.default(height=1.75), c, fps=squat.fps) as tracker:
        for k in range(2):
            cols = np.flatnonzero(tracker.segmenter(depths[k], c).mask.any(axis=0))
            s = int(cols[0]) + 3
            shifted = np.empty_like(depths[k])
            shifted[:, :-s], shifted[:, -s:] = depths[k][:, s:], depths[k][:, -1:]
            depths[k] = shifted
        fg0 = tracker.segmenter(depths[0], c)
        assert cut_by_border(fg0.mask)

        def view(uncut):
            tracker.settings = TrackerSettings(start={"complete_uncut": uncut})
            rest, pending = collections.deque(depths[1:]), collections.deque()
            take = lambda n: [rest.popleft() for _ in range(min(n, len(rest)))]  # noqa: E731
            return _complete_view(tracker, depths[0], fg0, take, pending)

        start, _, early = view(True)
        assert len(early) == 2 and start is depths[2]
        start, _, early = view(False)
        assert early == [] and start is depths[0]
