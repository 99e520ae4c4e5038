"""The user's facing (``--facing``, :attr:`StartSettings.facing`): the start faces the side
the user names and skips the front/back check, on a synthetic sequence of a person with
their back to the camera."""
import json
import subprocess
import sys

import numpy as np
import pytest

from depthtrack.body import BodyModel
from depthtrack.io import open_sequence
from depthtrack.synth.generate import synthesize_procedural
from depthtrack.track import TrackerSettings
from depthtrack.track.twins import facing_direction
from depthtrack.track.start import clearly_facing, wrong_side
from depthtrack.track.tracker import Tracker
from tool_module import load_tool


@pytest.fixture(scope="module")
def from_behind(tmp_path_factory):
    """10 frames of a half squat filmed from behind (SR4000, ToF noise)."""
    d = tmp_path_factory.mktemp("behind") / "seq"
    synthesize_procedural("squat", d, start=0.6, seconds=0.4, seed=3, azimuth=180)
    return d


def _towards_camera(pose):
    """Cosine between the pose's forward direction and the way to the camera, flattened."""
    f = facing_direction(pose)
    t = -np.asarray(pose[:3], dtype=np.float64)
    f[1] = t[1] = 0.0                                  # camera y is (nearly) vertical here
    return float(f @ t / np.linalg.norm(f) / np.linalg.norm(t))


def test_wrong_side_is_the_half_plane_the_user_did_not_name():
    up = np.array([0.0, -1.0, 0.0])
    facing_camera = np.zeros(48)
    facing_camera[2] = 3.0
    assert _towards_camera(facing_camera) > 0.9        # the rest pose faces the camera
    away = facing_camera.copy()
    away[3:6] = [0.0, np.pi, 0.0]
    side = facing_camera.copy()
    side[3:6] = [0.0, 1.4, 0.0]                         # 80 degrees: still the camera's side
    poses = np.stack([facing_camera, away, side])
    assert wrong_side(poses, "camera", up).tolist() == [False, True, False]
    assert wrong_side(poses, "away", up).tolist() == [True, False, True]
    assert not wrong_side(poses, "auto", up).any()
    # within the margin of profile a pose counts as either side (the pelvis's heading is
    # uncertain there): 80, 110 and 150 degrees from the camera with a 45-degree margin
    past = facing_camera.copy()
    past[3:6] = [0.0, np.radians(110), 0.0]
    far = facing_camera.copy()
    far[3:6] = [0.0, np.radians(150), 0.0]
    poses = np.stack([facing_camera, side, past, far, away])
    assert wrong_side(poses, "camera", up, 45.0).tolist() == [False, False, False, True, True]
    assert wrong_side(poses, "away", up, 45.0).tolist() == [True, False, False, False, False]
    assert [clearly_facing(p, "camera", up, 45.0) for p in poses] == [True, False, False, False, False]
    assert [clearly_facing(p, "away", up, 45.0) for p in poses] == [False, False, False, True, True]


def test_facing_away_starts_from_behind_and_skips_the_check(from_behind):
    seq = open_sequence(from_behind)
    body = BodyModel.default(height=seq.subject_height or 1.75)
    truth = seq.joints
    starts = {}
    for facing in ("away", "camera"):
        settings = TrackerSettings(start={"facing": facing})
        with Tracker(body, seq.camera, fps=seq.fps, settings=settings) as tracker:
            if facing == "away":                    # the whole clip
                away = tracker.track_sequence(seq)
                start = away.poses[0]
            else:                                   # the start alone
                start = dict(tracker.stream([seq.depth(0)]))[0]
            info = tracker.state.init_info
        assert info["facing"] == facing and "heading_check" not in info
        starts[facing] = start
    assert _towards_camera(starts["away"]) < -0.5      # the back to the camera, as told
    assert np.linalg.norm(away.joints - truth, axis=-1).mean(axis=-1).max() < 0.1
    assert _towards_camera(starts["camera"]) > 0.0     # told so, the start faces the camera
    camera0 = np.asarray(body.joint_positions(starts["camera"]))
    assert np.linalg.norm(camera0 - truth[0], axis=-1).mean() > 0.15   # ... which is wrong here


def test_the_cli_passes_facing_into_the_settings(from_behind, tmp_path):
    out = tmp_path / "track"
    run = subprocess.run([sys.executable, "-m", "depthtrack", "track", str(from_behind), "-o",
                          str(out), "--facing", "away", "--preset", "fast", "--quiet"],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["settings"]["start"]["facing"] == "away"
    assert summary["initialisation_details"]["facing"] == "away"
    bad = subprocess.run([sys.executable, "-m", "depthtrack", "track", str(from_behind), "-o",
                          str(tmp_path / "bad"), "--settings", '{"start": {"facing": "left"}}'],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "Traceback" not in bad.stderr
    assert "facing" in bad.stderr and len(bad.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "bad").exists()


def test_eval_tracks_with_the_facing_given(from_behind, tmp_path):
    tracks = tmp_path / "tracks"
    run = subprocess.run([sys.executable, "-m", "depthtrack", "eval", str(from_behind),
                          "--methods", "hc", "--facing", "away", "--tracks-out", str(tracks),
                          "--preset", "fast", "--json", "--quiet"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    summary = json.loads((tracks / "seq" / "hc" / "summary.json").read_text())
    assert summary["settings"]["start"]["facing"] == "away"
    assert summary["initialisation_details"]["facing"] == "away"
    scored = json.loads(run.stdout)["sequences"]["seq"]["hc"]
    assert scored["within_10cm"] > 0.6            # back to front it would be about 20 %
    # scoring existing tracks takes no tracker settings: refused in one line, exit 2
    bad = subprocess.run([sys.executable, "-m", "depthtrack", "eval", str(from_behind), "--track",
                          str(tracks / "seq" / "hc"), "--facing", "away"],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1
    assert "--facing" in bad.stderr


def test_the_benchmark_reads_the_facing_off_the_truth(from_behind, tmp_path):
    tool = load_tool("benchmark")
    assert tool.facing_from_truth(from_behind) == "away"
    front = tmp_path / "front"
    synthesize_procedural("squat", front, start=0.6, seconds=0.08, seed=3, azimuth=30)
    assert tool.facing_from_truth(front) == "camera"
    # bent over on frame 0 (the dev split's bend from 120 degrees faces the camera at 30
    # degrees): the rule reads the pelvis against the floor, not against the trunk's axis
    bent = tmp_path / "bent"
    synthesize_procedural("bend", bent, start=0.5, seconds=2.0, seed=1, azimuth=120,
                          camera="kinect-v2")         # its trunk rule read "away" (dot -0.002)
    assert tool.facing_from_truth(bent) == "camera"


def test_a_twin_the_facing_rules_out_leaves_the_start_as_it_is():
    """``settle_heading`` with a ``turn`` that returns None (the twin faces the side the
    user ruled out): the initial track is kept, and ``heading_check`` says why."""
    from depthtrack.track.heading import settle_heading
    from depthtrack.track.state import TrackingState

    start = TrackingState(pose=np.zeros(48), log=({},))

    def track(state, depths):         # the turned twin (pose[0] = 1) explains the frames better
        better = state.pose[0] == 1.0
        return state, np.zeros((len(depths), 48)), {"unexplained": 0.1 if better else 0.5,
                                                    "energy": 1.0}

    for turn, kept in ((lambda pose: None, "initial"), (lambda pose: pose + 1.0, "turned")):
        state, poses = settle_heading(start, [None] * 3, track, turn, TrackerSettings())
        check = state.init_info["heading_check"]
        assert check["kept"] == kept and len(poses) == 4
        assert check["turned_ruled_out"] == (kept == "initial")
        assert (check["unexplained_turned"] is None) == (kept == "initial")


def test_other_starts_are_settled_too_and_the_lowest_kept_track_stands():
    """``settle_heading`` with ``others`` (:attr:`StartSettings.displaced_checked`): each
    other start is settled against its own twin, and the kept track with the lowest score
    stands, whichever start it came from."""
    from depthtrack.track.heading import settle_heading
    from depthtrack.track.state import TrackingState

    start = TrackingState(pose=np.zeros(48), log=({},))
    scores = {0.0: 0.40, 1.0: 0.30, 5.0: 0.35, 6.0: 0.20}   # pose[0] -> unexplained share

    def track(state, depths):
        return state, np.full((len(depths), 48), state.pose[0]), {
            "unexplained": scores[state.pose[0]], "energy": 1.0}

    def turn(pose):
        return pose + 1.0

    alone, poses_alone = settle_heading(start, [None] * 3, track, turn, TrackerSettings())
    assert alone.init_info["heading_check"]["kept"] == "turned" and poses_alone[0, 0] == 1.0
    assert "others" not in alone.init_info["heading_check"]
    # the other start's twin (6) explains the frames best: its track stands
    state, poses = settle_heading(start, [None] * 3, track, turn, TrackerSettings(),
                                  others=[np.full(48, 5.0)])
    check = state.init_info["heading_check"]
    assert check["kept_start"] == 1 and check["others"][0]["kept"] == "turned"
    assert check["kept"] == "turned" and check["starts_by"] == "unexplained"
    assert poses.shape == (4, 48) and np.all(poses[:, 0] == 6.0)
    # where the other start's kept track is worse, the first start's stands as alone
    scores[6.0] = 0.32
    state, poses = settle_heading(start, [None] * 3, track, turn, TrackerSettings(),
                                  others=[np.full(48, 5.0)])
    assert state.init_info["heading_check"]["kept_start"] == 0
    np.testing.assert_array_equal(poses, poses_alone)
