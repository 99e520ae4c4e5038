"""The final polish of each finished pose (``PolishSettings.final_tile``, issue 11): the tile
rule in closed form; on a short synthetic ToF sequence the track is the same with and
without it (every frame's energy alike), and the poses it reports fit the person better."""
import numpy as np
import pytest
from conftest import FirstFrames

from depthtrack.body import BodyModel
from depthtrack.evaluate.fit import summarize_fit, track_fit
from depthtrack.evaluate.metrics import mean_error, point_errors
from depthtrack.track import TrackerSettings
from depthtrack.track.final_polish import final_tile
from depthtrack.track.tracker import Tracker, fit_pose_to_joints


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


def test_the_final_polish_fits_finer_and_changes_no_decision(squat):
    frames = 6
    seq = FirstFrames(squat, frames)
    body = BodyModel.default(height=1.75)
    x0 = fit_pose_to_joints(body, squat.joints[0])
    runs = {}
    for tile in (0, 256):
        settings = TrackerSettings().updated({"polish": {"final_tile": tile}})
        with Tracker(body, squat.camera, settings=settings) as tracker:
            poses = np.array([x for _, x in tracker.stream(
                (seq.depth(j) for j in range(frames)), init_pose=x0)])
            energies = [e.get("energy") for e in tracker.state.log]
            runs[tile] = (poses, energies, tracker.timings["final"],
                          tracker.recorder.candidates_by_stage.get("final", 0))
    (plain, e_plain, t_plain, n_plain), (polished, e_polished, t_polished, n_polished) = \
        runs[0], runs[256]
    assert e_plain == e_polished                 # the track itself: every decision alike
    assert t_plain == 0 and n_plain == 0 and t_polished > 0 and n_polished > 0
    assert np.abs(polished - plain).max() > 1e-4  # the poses reported did move
    fit_plain = summarize_fit(track_fit(seq, plain, body))
    fit_polished = summarize_fit(track_fit(seq, polished, body))
    assert fit_polished["silhouette_iou"] > fit_plain["silhouette_iou"] + 0.01
    assert fit_polished["unexplained_fraction"] < fit_plain["unexplained_fraction"]
    truth = seq.joints
    err_plain = mean_error(point_errors(np.asarray(body.joint_positions(plain)), truth))
    err_polished = mean_error(point_errors(np.asarray(body.joint_positions(polished)), truth))
    assert err_polished < err_plain + 0.005
