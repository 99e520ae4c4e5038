"""``depthtrack eval`` on track outputs made from the ground truth: JSON shape, report, bad input."""
import json

import numpy as np
import pytest

from depthtrack.body import BodyModel
from depthtrack.camera import Camera
from depthtrack.cli import main
from depthtrack.contract import JOINT_INDEX
from depthtrack.evaluate import report
from depthtrack.evaluate.runs import evaluate
from depthtrack.io.sequence import write_sequence
from depthtrack.io.track_output import write_track
from depthtrack.body.markers import MARKER_NAMES, marker_positions

FRAMES = 5
METRIC_KEYS = {"frames", "fps", "wall_fps", "mean_error_m", "max_error_m", "within_10cm",
               "marker_mean_error_m", "marker_max_error_m", "silhouette_iou", "unexplained_fraction",
               "median_depth_residual_m", "segment_length_error_m", "back_to_front_fraction",
               "trunk_twist_error_deg"}


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    """A 5-frame sequence with joints (one row missing) and markers, and tracks of it:
    the ground-truth poses (hc) and the same shifted 5 cm along x (hc+ep)."""
    root = tmp_path_factory.mktemp("eval")
    body = BodyModel.default(height=1.7)
    rng = np.random.default_rng(3)
    poses = np.tile(body.default_pose((0.0, 0.0, 3.0)), (FRAMES, 1))
    poses[:, 3:] += rng.normal(0.0, 0.1, (FRAMES, 45))
    joints = body.joint_positions(poses)
    truth = joints.copy()
    truth[2, JOINT_INDEX["l_wrist"]] = np.nan          # unknown ground truth row
    markers = marker_positions(body, poses)
    camera = Camera.preset("sr4000")
    depth = np.zeros((FRAMES, camera.height, camera.width), np.float32)
    seq = write_sequence(root / "walkseq", depth, camera, 25.0, joints=truth, markers=markers,
                         marker_names=MARKER_NAMES, subject=1.7)
    exact = write_track(root / "track_hc", joints, poses, body.pose_names, body, 25.0,
                        {"method": "hc", "seconds": 2.0, "wall_seconds": 4.0})
    shifted_poses = poses.copy()
    shifted_poses[:, 0] += 0.05
    shifted = write_track(root / "track_hcep", body.joint_positions(shifted_poses), shifted_poses,
                          body.pose_names, body, 25.0, {"method": "hc+ep", "seconds": 0.5})
    bare = write_sequence(root / "nogt", depth, camera, 25.0)
    return {"root": root, "seq": seq, "exact": exact, "shifted": shifted, "bare": bare,
            "poses": poses, "body": body}


def _run(capsys, *argv):
    code = main(["eval", *map(str, argv)])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_json_shape_and_zero_error_for_ground_truth_track(data, capsys):
    code, out, err = _run(capsys, data["seq"], "--track", data["exact"], "--json", "--quiet")
    assert code == 0 and err == ""
    result = json.loads(out)                       # stdout is nothing but the JSON
    assert set(result) == {"sequences", "overall"}
    assert set(result["sequences"]) == {"walkseq"}
    m = result["sequences"]["walkseq"]["hc"]
    assert set(m) == METRIC_KEYS
    assert m["frames"] == FRAMES
    assert m["fps"] == pytest.approx(FRAMES / 2.0)
    assert m["wall_fps"] == pytest.approx(FRAMES / 4.0)      # the body fits' time too
    assert m["mean_error_m"] < 1e-5 and m["max_error_m"] < 1e-5   # CSV keeps 1 um
    assert m["within_10cm"] == 1.0
    assert m["marker_mean_error_m"] < 1e-5 and m["marker_max_error_m"] < 1e-5
    assert set(result["overall"]) == {"hc"} and set(result["overall"]["hc"]) == METRIC_KEYS


def test_two_tracks_of_one_sequence_and_a_known_offset(data, capsys):
    code, out, _ = _run(capsys, data["seq"], data["seq"], "--track", data["exact"], data["shifted"],
                        "--json", "--quiet")
    assert code == 0
    result = json.loads(out)
    assert set(result["sequences"]["walkseq"]) == {"hc", "hc+ep"}
    m = result["sequences"]["walkseq"]["hc+ep"]
    # a rigid 5 cm shift moves every joint and marker by exactly 5 cm
    for key in ("mean_error_m", "max_error_m", "marker_mean_error_m", "marker_max_error_m"):
        assert m[key] == pytest.approx(0.05, abs=2e-6), key
    assert m["fps"] == pytest.approx(FRAMES / 0.5)


def test_sequence_without_markers_gives_null_marker_fields(data, tmp_path, capsys):
    body = BodyModel.default(height=1.7)
    poses = np.tile(body.default_pose((0.0, 0.0, 3.0)), (3, 1))
    camera = Camera.preset("sr4000")
    seq = write_sequence(tmp_path / "nomarkers", np.zeros((3, 144, 176)), camera, 25.0,
                         joints=body.joint_positions(poses))
    track = write_track(tmp_path / "t", body.joint_positions(poses), poses, body.pose_names, body, 25.0,
                        {"method": "ep"})
    code, out, _ = _run(capsys, seq, "--track", track, "--json", "--quiet")
    m = json.loads(out)["sequences"]["nomarkers"]["ep"]
    assert code == 0
    assert m["marker_mean_error_m"] is None and m["marker_max_error_m"] is None
    assert m["fps"] is None                         # no "seconds" in the summary


def test_report_files_and_plot_contents(data, tmp_path, capsys):
    out_dir = tmp_path / "rep"
    code, out, _ = _run(capsys, data["seq"], data["seq"], "--track", data["exact"], data["shifted"],
                        "--report", out_dir, "--quiet")
    assert code == 0 and "walkseq" in out
    for name in ("metrics.json", "report.md", "errors.csv", *report.PLOT_FILES):
        assert (out_dir / name).is_file() and (out_dir / name).stat().st_size > 0, name
    for name in report.PLOT_FILES:
        assert (out_dir / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    saved = json.loads((out_dir / "metrics.json").read_text())
    assert saved["sequences"]["walkseq"]["hc+ep"]["mean_error_m"] == pytest.approx(0.05, abs=2e-6)
    assert "| walkseq | hc+ep | 5 | 5.0 |" in (out_dir / "report.md").read_text()
    assert len((out_dir / "errors.csv").read_text().splitlines()) == 1 + 2 * FRAMES
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]   # no temporaries left

    evaluation = evaluate([data["seq"], data["seq"]], track_dirs=[data["exact"], data["shifted"]])
    methods = evaluation.methods
    fig = report.plot_methods(evaluation)
    top, bottom = fig.axes[:2]
    assert len(top.patches) == 1 * len(methods)            # sequences x methods bars
    assert len(bottom.patches) == 1                        # hc+ep - hc per sequence
    assert bottom.patches[0].get_height() == pytest.approx(5.0, abs=1e-3)   # cm
    fig = report.plot_error_over_time(evaluation)
    assert len(fig.axes) == 1 and len(fig.axes[0].get_lines()) == 2 * len(methods)
    shifted_mean = fig.axes[0].get_lines()[2].get_ydata()
    np.testing.assert_allclose(shifted_mean, 5.0, atol=1e-3)
    fig = report.plot_joint_errors(evaluation)
    assert len(fig.axes[0].patches) == 15 * len(methods)


def test_tracking_path_runs_each_method_once_per_sequence(data, monkeypatch, capsys):
    """Without --track every (sequence, method) is tracked through the library; a stand-in
    tracker that returns the truth (shifted per method) checks the wiring, not the tracker."""
    from depthtrack.evaluate import runs

    calls = []
    offsets = {"hc": 0.0, "ep": 0.2}

    def fake_track(seq, method, likelihood, quiet, settings=None):
        calls.append((seq.path.name, method, likelihood))
        poses = data["poses"].copy()
        poses[:, 1] += offsets[method]
        return data["body"].joint_positions(poses), poses, data["body"], 4.0, {"method": method}

    monkeypatch.setattr(runs, "track_sequence", fake_track)
    code, out, _ = _run(capsys, data["seq"], "--methods", "hc,ep", "--likelihood", "pixel", "--json", "--quiet")
    assert code == 0
    assert calls == [("walkseq", "hc", "pixel"), ("walkseq", "ep", "pixel")]
    result = json.loads(out)
    assert list(result["sequences"]["walkseq"]) == ["hc", "ep"]
    assert result["overall"]["ep"]["mean_error_m"] == pytest.approx(0.2, abs=2e-6)
    assert result["overall"]["ep"]["within_10cm"] == 0.0
    assert result["overall"]["hc"]["fps"] == pytest.approx(FRAMES / 4.0)


def test_bad_input_exits_2_with_one_line_and_writes_nothing(data, tmp_path, capsys):
    rep = tmp_path / "rep"
    cases = [
        (tmp_path / "missing", "--track", data["exact"]),
        (data["seq"], "--methods", "hc,zz"),                                      # unknown method
        (data["seq"], "--methods", "hc", "--track", data["exact"]),
        (data["seq"], "--track", data["exact"], data["shifted"]),                 # 2 tracks, 1 seq
        (data["seq"], "--track", tmp_path / "nowhere"),
    ]
    for case in cases:
        code, out, err = _run(capsys, *case, "--report", rep, "--json")
        assert code == 2, case
        assert out == ""
        lines = err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("depthtrack eval: "), err
        assert not rep.exists()
    short = write_sequence(tmp_path / "short", np.zeros((2, 144, 176)), Camera.preset("sr4000"), 25.0,
                           joints=np.zeros((2, 15, 3)))
    code, _, err = _run(capsys, short, "--track", data["exact"])          # 5-frame track, 2 frames
    assert code == 2 and "frames" in err


def test_tracker_options_with_an_existing_track_are_refused_in_one_line(data, capsys):
    for option in (["--preset", "fast"], ["--settings", '{"heading": {"every": 8}}']):
        code, out, err = _run(capsys, data["seq"], "--track", data["exact"], *option)
        assert code == 2 and out == ""
        assert len(err.strip().splitlines()) == 1 and "not to --track" in err
