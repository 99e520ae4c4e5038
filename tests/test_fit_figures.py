"""Fit figures (silhouette IoU, unexplained share, depth residual) and eval without ground truth."""
import json

import numpy as np
import pytest

from depthtrack.body.shape import BodyShape
from depthtrack.cli import main
from depthtrack.evaluate.fit import frame_fit, person_masks, summarize_fit, track_fit

render = pytest.importorskip("depthtrack.render")


def test_frame_fit_by_hand():
    person = np.zeros((4, 5), bool)
    person[1:3, 1:4] = True                       # 6 person pixels
    depth = np.where(person, 2.0, 0.0)
    depth[1, 1] = 0.0                             # one without a reading
    rendered = np.zeros((4, 5))
    rendered[1:3, 2:5] = 2.03                     # covers 4 person pixels and 2 others
    rendered[2, 3] = 2.5                          # ... one of them at the wrong depth
    iou, unexplained, residual = frame_fit(person, depth, rendered)
    assert iou == pytest.approx(4 / 8)
    # 5 person pixels with a reading; explained: (1,2), (1,3), (2,2) -> 2 of 5 unexplained
    assert unexplained == pytest.approx(2 / 5)
    assert residual == pytest.approx(0.03)        # median of 0.03, 0.03, 0.03, 0.5
    assert frame_fit(person, depth, None)[:2] == (0.0, 1.0)        # a person but no pose
    assert all(np.isnan(frame_fit(np.zeros((4, 5), bool), depth, rendered)))
    s = summarize_fit([[0.5, 0.4, 0.03], [1.0, 0.0, 0.01], [np.nan] * 3])
    assert s == {"silhouette_iou": 0.75, "unexplained_fraction": 0.2,
                 "median_depth_residual_m": pytest.approx(0.02)}
    assert summarize_fit(np.full((2, 3), np.nan))["silhouette_iou"] is None


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory):
    """Two noise-free Kinect v2 frames of a shaped person in a room, the true camera-frame
    poses, and a copy of the sequence without ground truth."""
    try:
        render.gl_context()
    except render.GLUnavailableError as exc:
        pytest.skip(f"no OpenGL: {exc}")
    from depthtrack.io.sequence import open_sequence, write_sequence
    from depthtrack.synth.generate import synthesize
    from depthtrack.synth.scene import transform_poses
    from depthtrack.synth.subject import make_subject

    root = tmp_path_factory.mktemp("fit")
    body, subject = make_subject(1.7, BodyShape(thigh=1.08, torso_girth=1.2, shoulder_width=1.08))
    world = np.tile(body.default_pose(), (2, 1))
    world[1, 3 + 3 * 3 + 2] = -1.0                # left arm raised in frame 1
    synth = synthesize(root / "seq", body, world, 10.0, camera="kinect-v2", noise="none",
                       subject=subject)
    poses = transform_poses(world, np.array(synth["placement"]["world_to_camera"]))
    seq = open_sequence(root / "seq")
    bare = write_sequence(root / "bare", [seq.depth(i) for i in range(len(seq))], seq.camera,
                          seq.fps)
    return {"root": root, "body": body, "poses": poses, "seq": seq, "bare": bare}


def test_true_pose_explains_the_frame_and_a_shifted_one_less(synthetic):
    seq, body, poses = synthetic["seq"], synthetic["body"], synthetic["poses"]
    masks = person_masks(seq)
    true_fit = track_fit(seq, poses, body, masks)
    assert true_fit.shape == (2, 3)
    assert np.all(true_fit[:, 0] > 0.95)            # IoU: segmentation edges cost a little
    assert np.all(true_fit[:, 1] < 0.03)
    assert np.all(true_fit[:, 2] < 0.005)           # noise-free: the depths agree
    shifted = poses.copy()
    shifted[:, 0] += 0.10                           # 10 cm sideways
    off = track_fit(seq, shifted, body, masks)
    assert np.all(off[:, 0] < true_fit[:, 0] - 0.1)
    assert np.all(off[:, 1] > true_fit[:, 1] + 0.1)
    missing = poses.copy()
    missing[1] = np.nan
    part = track_fit(seq, missing, body, masks)
    assert part[1, 0] == 0.0 and part[1, 1] == 1.0


def test_eval_without_ground_truth_and_shape_errors(synthetic, tmp_path, capsys):
    from depthtrack.body import BodyModel
    from depthtrack.io.track_output import write_track
    from depthtrack.track.shape_fit import write_body_json

    body, poses = synthetic["body"], synthetic["poses"]
    joints = body.joint_positions(poses)
    track = write_track(tmp_path / "track", joints, poses, body.pose_names, body, 10.0, {"method": "hc"})
    # the template body of the same height: what a track without body.json is read with
    template = write_track(tmp_path / "template", joints, poses, body.pose_names,
                           BodyModel.default(height=body.height), 10.0, {"method": "hc+ep"})
    write_body_json(track / "body.json", body)
    code = main(["eval", str(synthetic["bare"]), "--track", str(track), "--json", "--quiet"])
    out = capsys.readouterr().out
    assert code == 0
    m = json.loads(out)["sequences"]["bare"]["hc"]
    assert m["mean_error_m"] is None and m["within_10cm"] is None
    assert m["silhouette_iou"] > 0.95 and m["unexplained_fraction"] < 0.03
    assert m["segment_length_error_m"] is None       # the bare copy has no synth.shape
    seq = str(synthetic["root"] / "seq")
    report = tmp_path / "rep"
    code = main(["eval", seq, seq, "--track", str(track), str(template), "--json", "--quiet",
                 "--report", str(report)])
    result = json.loads(capsys.readouterr().out)["sequences"]["seq"]
    assert code == 0
    assert result["hc"]["segment_length_error_m"] == pytest.approx(0.0, abs=1e-4)
    assert result["hc+ep"]["segment_length_error_m"] > 0.005
    assert result["hc+ep"]["segment_length_errors_m"]["shoulder_width"] < -0.02
    # the template is too narrow: it explains less of the person
    assert result["hc+ep"]["silhouette_iou"] < result["hc"]["silhouette_iou"]
    rows = (report / "errors.csv").read_text().splitlines()
    assert rows[0].endswith("silhouette_iou,unexplained_fraction,median_depth_residual_m")
    assert len(rows) == 1 + 2 * 2 and float(rows[1].split(",")[7]) > 0.95
    assert "silhouette IoU" in (report / "report.md").read_text()
    assert (report / "fit_over_time.png").read_bytes()[:4] == b"\x89PNG"
