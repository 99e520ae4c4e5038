"""The tracker end to end on rendered frames: automatic start, tracking, EP recovery, the CLI."""
import json
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from depthtrack.body import BodyModel
from depthtrack.camera import Camera
from depthtrack.track.evidence import PartModel
from depthtrack.track.tracker import Tracker, TrackerSettings, fit_pose_to_joints

REPO = Path(__file__).resolve().parents[1]
CAMERA = Camera.preset("sr4000")


def _segment(depth, camera):
    """Foreground of a frame rendered without scenery: every pixel with a reading."""
    mask = depth > 0
    return SimpleNamespace(mask=mask, points=camera.backproject(depth)[mask], floor_plane=None)


def _motion(n, fps=25.0):
    """A slow wave: arms, elbows, a step and a turn of the pelvis."""
    t = np.arange(n) / fps
    poses = np.zeros((n, 48))
    poses[:, 0] = 0.1 * np.sin(t)
    poses[:, 2] = 3.2
    poses[:, 4] = 0.3 * np.sin(0.8 * t)                  # pelvis ry
    poses[:, 14] = -0.5 - 0.5 * np.sin(2.0 * t)          # l_shoulder rz: raise sideways
    poses[:, 23] = 0.4 + 0.3 * np.sin(1.5 * t)           # r_shoulder rz
    poses[:, 15] = -0.6 - 0.4 * np.sin(2.0 * t)          # l_elbow flexion
    poses[:, 30] = -0.3 * np.sin(2.0 * t)                # l_hip rx
    poses[:, 33] = 0.3 + 0.3 * np.sin(2.0 * t)           # l_knee rx
    return poses


@pytest.fixture(scope="module")
def scene():
    from depthtrack.render import FrameRenderer

    body = BodyModel.default(1.75)
    poses = _motion(10)
    renderer = FrameRenderer(CAMERA)
    rng = np.random.default_rng(0)
    frames = []
    for p in poses:
        d = renderer.render(body, p)
        frames.append((d + (d > 0) * rng.normal(scale=0.01, size=d.shape)).astype(np.float32))
    return body, poses, frames


def _errors(body, poses, truth):
    return np.linalg.norm(body.joint_positions(np.asarray(poses)) - body.joint_positions(truth), axis=-1)


def test_automatic_start_and_tracking_recover_the_joints(scene):
    body, truth, frames = scene
    tracker = Tracker(body, CAMERA, method="hc", segmenter=_segment)
    out = [tracker.init(frames[0])]
    out += [tracker.step(d) for d in frames[1:]]
    err = _errors(body, out, truth)
    assert tracker.init_info["mode"] == "automatic"
    assert err[0].mean() < 0.05
    assert err.mean() < 0.05
    assert (err < 0.10).mean() > 0.95
    assert tracker.counts["recoveries"] == 0


def test_evidence_propagation_recovers_a_lost_arm_that_hill_climbing_does_not(scene):
    body, truth, frames = scene
    parts = PartModel.from_body(body)
    # a detector that reports the true left hand (and nothing else) on every frame
    frame_index = {"i": 0}

    def detector(depth, camera, foreground):
        hand = parts.positions(body, truth[frame_index["i"]][None])[0, parts.index("l_hand")]
        return [SimpleNamespace(label="hand", position=hand, direction=np.zeros(3), score=1.0)]

    lost = truth[0].copy()
    lost[12:15] = [0.0, 0.0, 0.0]                          # left arm hanging instead of raised
    lost[15] = 0.0
    results = {}
    for method in ("hc", "hc+ep"):
        tracker = Tracker(body, CAMERA, method=method, segmenter=_segment, detector=detector,
                          # the Gaussian motion prior: hill climbing alone stays lost
                          settings=TrackerSettings(lost_ratio=1e9).updated(
                              {"energy": {"prior_huber": 0.0}}))
        frame_index["i"] = 0
        tracker.init(frames[0], pose=lost)
        out = []
        for i in range(1, 4):
            frame_index["i"] = i
            out.append(tracker.step(frames[i]))
        wrist = _errors(body, out, truth[1:4])[:, 5]
        results[method] = (wrist, tracker.counts["accepted"])
    # EP puts the hand back on the first frame; HC alone is still 10+ cm off there
    assert results["hc+ep"][1] >= 1
    assert results["hc+ep"][0][0] < 0.06
    assert results["hc"][0][0] > 0.10


def test_fit_pose_to_joints_reproduces_a_pose(scene):
    body, truth, _ = scene
    fitted = fit_pose_to_joints(body, body.joint_positions(truth[5]))
    assert _errors(body, fitted[None], truth[5][None]).max() < 0.01


def test_bad_input_is_one_line_and_exit_2(tmp_path):
    out = tmp_path / "out"
    res = subprocess.run([sys.executable, "-m", "depthtrack", "track", str(tmp_path / "missing"),
                          "-o", str(out)], capture_output=True, text=True, cwd=REPO)
    assert res.returncode == 2
    assert res.stderr.count("\n") == 1 and res.stderr.startswith("depthtrack track: ")
    assert not out.exists()
    # a non-track directory is never overwritten
    keep = tmp_path / "keep"
    keep.mkdir()
    (keep / "precious.txt").write_text("x")
    res = subprocess.run([sys.executable, "-m", "depthtrack", "track", str(tmp_path / "missing"),
                          "-o", str(keep)], capture_output=True, text=True, cwd=REPO)
    assert res.returncode == 2 and (keep / "precious.txt").exists()
    res = subprocess.run([sys.executable, "-m", "depthtrack", "track", str(tmp_path / "missing"),
                          "-o", str(out), "--overlay", str(tmp_path / "x.avi")],
                         capture_output=True, text=True, cwd=REPO)
    assert res.returncode == 2 and "mp4 or .gif" in res.stderr


def test_out_of_range_marks_open_space_but_not_dropouts():
    from depthtrack.track.observation import observation_image, out_of_range

    depth = np.full((144, 176), 3.0, np.float32)
    depth[:, 120:] = 0.0                       # the room beyond the sensor's range on the right
    mask = np.zeros(depth.shape, bool)
    mask[40:110, 60:90] = True                 # the person
    depth[mask] = 2.0
    depth[70, 75] = 0.0                        # a dropout on the person
    depth[20, 20] = 0.0                        # a dropout on the wall
    depth[50:60, 90:92] = 0.0                  # no reading right beside the person (e.g. dark sleeve)
    open_space = out_of_range(depth, mask)
    assert open_space[:, 125:].all()
    assert not open_space[70, 75] and not open_space[20, 20]
    assert not open_space[50:60, 90:92].any()
    assert not open_space[:, :120].any()
    from depthtrack.camera import Camera
    obs = observation_image(depth, mask, Camera.preset("sr4000"))
    assert np.isinf(obs[:, 125:]).all()        # background: a limb drawn there pays the silhouette cost
    assert obs[70, 75] == 0 and obs[20, 20] == 0


def test_body_height_is_fitted_when_the_sequence_does_not_give_it(tmp_path):
    from depthtrack.io import open_sequence
    from depthtrack.synth.generate import synthesize_procedural
    from depthtrack.track.tracker import body_for_sequence

    seq_dir = tmp_path / "short"
    synthesize_procedural("wave", seq_dir, seconds=0.2, height=1.6)
    meta = json.loads((seq_dir / "sequence.json").read_text())
    del meta["subject"]
    (seq_dir / "sequence.json").write_text(json.dumps(meta))
    body, height = body_for_sequence(open_sequence(seq_dir))
    assert "fitted" in height["source"]
    assert abs(height["height_m"] - 1.6) < 0.08 * 1.6
    assert body.height == pytest.approx(height["height_m"], abs=1e-3)
    assert len(height["candidates"]) >= 5


class _Frames:
    def __init__(self, frames):
        self.frames = frames

    def __len__(self):
        return len(self.frames)

    def depth(self, i):
        return self.frames[i]


def test_frames_without_a_person_get_no_pose_and_tracking_restarts(scene):
    body, truth, frames = scene
    empty = np.zeros_like(frames[0])
    # an empty room, the person, one frame the segmentation misses (bridged), the person,
    # the person gone for three frames (track dropped), the person back
    seq = _Frames([empty, empty] + frames[:3] + [empty] + frames[3:5] + [empty] * 3 + frames[5:8])
    tracker = Tracker(body, CAMERA, method="hc", segmenter=_segment)
    result = tracker.track_sequence(seq)
    missing = ~np.isfinite(result.poses).all(axis=1)
    np.testing.assert_array_equal(np.flatnonzero(missing), [0, 1, 8, 9, 10])
    assert np.isnan(result.joints[missing]).all()
    assert tracker.counts["reinitialisations"] == 1 and tracker.counts["frames_without_person"] == 5
    err = _errors(body, result.poses[[2, 3, 4, 6, 7, 11, 12, 13]], truth[:8])
    assert err.mean() < 0.05


def test_missing_estimates_count_as_misses():
    from depthtrack.evaluate.metrics import fraction_within, mean_error, point_errors

    truth = np.zeros((2, 2, 3))
    truth[1, 1] = np.nan                                   # unknown truth: left out
    estimated = np.zeros((2, 2, 3))
    estimated[0, 0] = [0.02, 0.0, 0.0]
    estimated[0, 1] = np.nan                               # the tracker reported nothing
    errors = point_errors(estimated, truth)
    assert np.isinf(errors[0, 1]) and np.isnan(errors[1, 1])
    assert fraction_within(errors, 0.1) == pytest.approx(2 / 3)
    assert mean_error(errors) == pytest.approx(0.02 / 2)


def test_a_person_facing_away_is_found_by_tracking_both_headings():
    from depthtrack.render import FrameRenderer

    body = BodyModel.default(1.75)
    n = 12                                                # the check's ten frames and two more
    t = np.arange(n) / 25.0
    truth = np.zeros((n, 48))
    truth[:, 2] = 3.2
    truth[:, 4] = np.pi                                   # back to the camera
    truth[:, 30] = -0.6 * np.sin(6.0 * t)                 # hips swing like walking
    truth[:, 39] = 0.6 * np.sin(6.0 * t)
    truth[:, 33] = 0.5 + 0.4 * np.sin(6.0 * t)            # knees bend (one way only)
    truth[:, 42] = 0.5 - 0.4 * np.sin(6.0 * t)
    truth[:, 15] = -0.8 - 0.3 * np.sin(6.0 * t)           # elbows bend
    truth[:, 24] = -0.8 + 0.3 * np.sin(6.0 * t)
    renderer = FrameRenderer(CAMERA)
    seq = _Frames([renderer.render(body, p).astype(np.float32) for p in truth])
    tracker = Tracker(body, CAMERA, method="hc", segmenter=_segment)
    result = tracker.track_sequence(seq)
    check = tracker.init_info["heading_check"]
    assert check["kept"] == "turned" and check["by"] == "unexplained"
    assert check["unexplained_turned"] < check["unexplained_initial"]
    assert check["energy_turned"] < check["energy_initial"]
    err = _errors(body, result.poses, truth)
    assert np.median(err) < 0.06                           # facing the camera would swap left and right


def test_the_search_with_leg_poses_finds_a_kick_the_grid_alone_misses():
    """StartSettings.legs: the global search's grid hangs the legs down; a person caught
    with a leg raised forward (a kick, seen from the side) is found with the leg where it is
    only when the grid's candidates are also tried with a leg raised (start.LEG_POSES)."""
    from depthtrack.body.skeleton import POSE_INDEX
    from depthtrack.contract import JOINT_INDEX
    from depthtrack.render import FrameRenderer
    from depthtrack.track.start import LEG_POSES, with_leg_poses

    grid = np.zeros((3, 48))
    legs = with_leg_poses(grid)
    assert legs.shape == (3 * (1 + len(LEG_POSES)), 48) and np.all(legs[:3] == 0)
    for k, (slot, angle) in enumerate(LEG_POSES.values(), start=1):
        block = legs[3 * k: 3 * (k + 1)]
        assert np.all(block[:, POSE_INDEX[slot]] == angle)
        assert np.count_nonzero(block) == 3

    body = BodyModel.default(1.75)
    truth = np.zeros(48)
    truth[2] = 3.4
    truth[4] = np.pi / 2                                   # seen from the side
    truth[POSE_INDEX["r_hip_rx"]] = -1.35                  # the right leg kicked forward
    truth[POSE_INDEX["l_knee_rx"]] = 0.15
    with FrameRenderer(CAMERA) as renderer:
        depth = renderer.render(body, truth).astype(np.float32)
    foot = JOINT_INDEX["r_ankle"]
    errors = {}
    for legs_setting in ("never", "always"):
        # without the bent bodies (StartSettings.bends), which reach a raised leg too
        settings = TrackerSettings(start={"legs": legs_setting, "bends": "never"},
                                   heading={"frames": 0})
        with Tracker(body, CAMERA, method="hc", segmenter=_segment, settings=settings) as tracker:
            x = tracker.init(depth)
            info = tracker.init_info
        errors[legs_setting] = float(_errors(body, [x], truth)[0][foot])
        if legs_setting == "always":
            assert info["chosen_legs"] in ("down", *LEG_POSES)
    assert errors["always"] < 0.10, errors
    assert errors["never"] > 0.2, errors


def test_the_coarse_render_mesh_scores_with_half_the_triangles_and_tracks(scene):
    """``observe.render_mesh = "coarse"``: the candidates are drawn with the 500-triangle
    mesh (the start's and the height fit's renderers too) and a short track from the true
    first pose stays on the joints."""
    body, truth, frames = scene
    settings = TrackerSettings().updated({"observe": {"render_mesh": "coarse"}})
    with Tracker(body, CAMERA, method="hc", segmenter=_segment, settings=settings) as coarse, \
            Tracker(body, CAMERA, method="hc", segmenter=_segment) as decimated:
        assert coarse.render_body.mesh.num_faces < 0.6 * decimated.render_body.mesh.num_faces
        assert coarse.renderers.coarse.body is coarse.render_body
        out = [coarse.init(frames[0], pose=truth[0])] + [coarse.step(d) for d in frames[1:4]]
    assert (_errors(body, out, truth[:4]) < 0.10).mean() > 0.95


def test_the_far_band_makes_a_wall_close_behind_the_person_background():
    """``observe.far_band``: readings of a wall 0.35 m behind the person, beside it (inside
    the dilated mask), are part of the observation with the default band (0.4 m both ways)
    and background with a far band of 0.2 m; an arm 0.3 m in front of the person that the
    segmentation missed stays a reading either way (the near side keeps ``depth_band``)."""
    from depthtrack.camera import Camera
    from depthtrack.detect.segment import Foreground
    from depthtrack.track import TrackerSettings
    from depthtrack.track.observe import observe

    camera = Camera.preset("sr4000")
    depth = np.full(camera.shape, 4.85, np.float32)           # the wall
    mask = np.zeros(camera.shape, bool)
    mask[40:110, 60:90] = True
    depth[40:110, 60:90] = 4.4 + 0.1 * np.linspace(0, 1, 30)[None, :]   # the person, 4.4 - 4.5 m
    depth[70:73, 90:93] = 4.1                                 # a missed hand, in front
    fg = Foreground(mask, np.zeros((0, 3)), np.zeros((0, 2), int))
    wall = (slice(40, 110), slice(57, 60))     # beside the person, inside the dilated mask
    for far, wall_kept in ((None, True), (0.2, False)):
        s = TrackerSettings().updated({"observe": {"far_band": far}})
        frame, _ = observe(depth, fg, camera, s)
        assert np.isfinite(frame.observed[wall]).all() == wall_kept
        assert np.isinf(frame.observed[wall]).all() != wall_kept
        assert (frame.observed[70:73, 90:93] == np.float32(4.1)).all()
        assert (frame.observed[mask] == depth[mask]).all()
        assert np.isinf(frame.observed[:, :40]).all()          # far from the person


def test_wall_background_makes_the_segmented_walls_plane_background():
    """``observe.wall_background``: the segmentation gives the planes of the walls it dropped
    (``Foreground.wall_planes``); with the option on, readings on such a plane beside the
    person are background even inside the depth band, while the person and a hand in front
    stay readings. A synthetic frame: a fronto-parallel wall at 4.85 m, a person at 4.4 - 4.5 m
    (the default band reaches 4.9 m)."""
    from depthtrack.camera import Camera
    from depthtrack.detect import segment_foreground
    from depthtrack.track import TrackerSettings
    from depthtrack.track.observe import observe

    camera = Camera.preset("sr4000")
    depth = np.full(camera.shape, 4.85, np.float32)
    depth[30:120, 60:95] = 4.4 + 0.1 * np.linspace(0, 1, 35)[None, :]   # the person, 4.4 - 4.5 m
    fg = segment_foreground(depth, camera, floor=False)
    assert fg.mask[30:120, 60:95].all() and fg.mask.sum() == 90 * 35
    walls = fg.wall_planes
    assert walls is not None and walls.shape == (1, 4)
    normal, offset = walls[0, :3] * np.sign(walls[0, 2]), walls[0, 3] * np.sign(walls[0, 2])
    assert normal @ [0.0, 0.0, 1.0] > 0.999 and offset == pytest.approx(-4.85, abs=0.01)
    beside = (slice(30, 120), slice(57, 60))                      # inside the dilated mask
    for on in (False, True):
        s = TrackerSettings().updated({"observe": {"wall_background": on}})
        frame, _ = observe(depth, fg, camera, s)
        assert np.isinf(frame.observed[beside]).all() == on
        assert (frame.observed[fg.mask] == depth[fg.mask]).all()
