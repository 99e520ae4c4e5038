"""The final polish of each finished pose (``PolishSettings.final_tile``, issue 11): the tile
rule in closed form; on a short synthetic ToF sequence the track is the same with and
without it -- a heading switch, its re-track and the revoke of an earlier one included --
and the poses it reports fit the person better."""
import numpy as np
import pytest

from depthtrack.body import BodyModel
from depthtrack.evaluate.fit import summarize_fit, track_fit
from depthtrack.evaluate.metrics import mean_error, point_errors
from depthtrack.track import TrackerSettings
from depthtrack.track.final_polish import final_tile
from depthtrack.track.heading import turned_pose
from depthtrack.track.tracker import Tracker, fit_pose_to_joints

pytestmark = pytest.mark.final_polish


def test_the_tile_is_the_power_of_two_nearest_the_roi():
    rois = (130, 180, 182, 330, 700, 40, 0, float("nan"))
    assert [final_tile(r, 256) for r in rois] == [128, 128, 256, 256, 256, 64, 64, 64]
    assert final_tile(330, 128) == 128 and final_tile(330, 64) == 64


def test_settings_check_the_final_polish():
    from depthtrack.errors import InputError

    with pytest.raises(InputError, match="final_tile"):
        TrackerSettings().updated({"polish": {"final_tile": 100}})
    with pytest.raises(InputError, match="final_levels"):
        TrackerSettings().updated({"polish": {"final_levels": -1}})
    assert TrackerSettings().polish.final_tile == 256
    assert TrackerSettings().updated({"polish": {"final_tile": 0}}).polish.final_levels == 2


def test_the_final_polish_fits_finer_and_changes_no_decision(squat12):
    """Started mirrored (the turned twin of the true first pose), the track is switched and
    its frames re-tracked (test_track_retrack.py): with the final polish the switches,
    re-tracks and every frame's energy are those without it (its frames' segmentations
    kept and reused by the re-track), and the poses reported cover the person better."""
    seq = squat12
    frames = len(seq)
    body = BodyModel.default(height=1.75)
    x0 = turned_pose(fit_pose_to_joints(body, seq.joints[0]))
    # (the Gaussian motion prior: under Huber's loss the search turns the start by itself)
    base = TrackerSettings().updated({"search": {"untwist": []}, "energy": {"prior_huber": 0.0},
                                      "heading": {"retro_frames": 10}})
    runs = {}
    for tile in (0, 256):
        settings = base.updated({"polish": {"final_tile": tile}})
        with Tracker(body, seq.camera, settings=settings) as tracker:
            got = dict(tracker.stream((seq.depth(j) for j in range(frames)), init_pose=x0))
            info = tracker.describe()
            runs[tile] = (np.array([got[i] for i in range(frames)]),
                          [e.get("energy") for e in tracker.state.log],
                          info["heading_switches"], info["retracks"],
                          tracker.timings["final"],
                          tracker.recorder.candidates_by_stage.get("final", 0))
    plain, polished = runs[0], runs[256]
    assert plain[2] and plain[3]                     # a switch and its re-track happened
    assert plain[1:4] == polished[1:4]               # the track itself: every decision alike
    assert plain[4] == 0 and plain[5] == 0 and polished[4] > 0 and polished[5] > 0
    assert np.abs(polished[0] - plain[0]).max() > 1e-4   # the poses reported did move
    fit_plain = summarize_fit(track_fit(seq, plain[0], body))
    fit_polished = summarize_fit(track_fit(seq, polished[0], body))
    assert fit_polished["silhouette_iou"] > fit_plain["silhouette_iou"] + 0.01
    assert fit_polished["unexplained_fraction"] < fit_plain["unexplained_fraction"]
    truth = seq.joints
    err_plain = mean_error(point_errors(np.asarray(body.joint_positions(plain[0])), truth))
    err_polished = mean_error(point_errors(np.asarray(body.joint_positions(polished[0])), truth))
    assert err_polished < err_plain + 0.005


def test_tests_run_without_the_final_polish_unless_marked():
    """conftest's fixture (this file is marked, so the default stands here)."""
    from depthtrack.track.settings import PolishSettings

    assert PolishSettings().final_tile == 256
