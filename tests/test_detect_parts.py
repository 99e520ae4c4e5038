"""The patch classifier: features, numpy forest evaluation, the shipped model on fresh frames."""
import numpy as np
import pytest

from depthtrack.camera import Camera
from depthtrack.detect import detect_parts, geodesic_extrema, segment_foreground
from depthtrack.detect.classifier import (DEFAULT_PATH, FEATURE_NAMES, PATCH_CELLS, PartClassifier,
                                          default_classifier, extremum_features)
from depthtrack.synth.part_scenes import extremum_truth
from depthtrack.detect.segment import Foreground
from depthtrack.errors import InputError

import detect_frames as F


def _strip_foreground(vertical: bool):
    """A 1.2 m x 0.12 m flat strip at 2 m, horizontal or vertical in a square image."""
    cam = Camera(width=121, height=121, fx=100.0, fy=100.0, cx=60.0, cy=60.0)
    depth = np.zeros(cam.shape)
    if vertical:
        depth[:, 57:64] = 2.0
    else:
        depth[57:64, :] = 2.0
    mask = depth > 0
    rows, cols = np.nonzero(mask)
    fg = Foreground(mask, cam.backproject(depth)[mask], np.stack([cols, rows], 1))
    return depth, cam, fg


def test_patches_are_rotation_normalised():
    """The same strip lying across or along the image gives the same features at its ends."""
    feats = []
    for vertical in (False, True):
        depth, cam, fg = _strip_foreground(vertical)
        ex = geodesic_extrema(fg, cam, count=2)
        X = extremum_features(depth, cam, ex, fg)
        patch = X[:, :PATCH_CELLS * PATCH_CELLS].reshape(2, PATCH_CELLS, PATCH_CELLS)
        feats.append(patch)
        # the strip runs down the middle of the patch: on-person cells are at depth 0
        # relative to the tip, cells beside the strip are background
        assert np.all(patch[:, -1, PATCH_CELLS // 2] == 0.0)
        assert np.all(patch[:, :, 0] == 0.6)
    # the strip is 7 px wide: an odd width, centred the same in both images
    np.testing.assert_array_equal(np.sort(feats[0].ravel()), np.sort(feats[1].ravel()))


def test_numpy_forest_matches_sklearn_and_survives_save_load(tmp_path):
    from sklearn.ensemble import RandomForestClassifier

    rng = np.random.default_rng(0)
    X = rng.normal(size=(400, len(FEATURE_NAMES))).astype(np.float32)
    y = (X[:, 0] > 0).astype(int) + 2 * (X[:, 5] > 0.5).astype(int)     # 4 classes
    forest = RandomForestClassifier(n_estimators=7, max_depth=6, random_state=0).fit(X, y)
    model = PartClassifier.from_sklearn(forest, position_offset=[0.01, 0.02, 0.03, 0.0])
    Xt = rng.normal(size=(200, len(FEATURE_NAMES))).astype(np.float32)
    np.testing.assert_allclose(model.predict_proba(Xt), forest.predict_proba(Xt), atol=1e-6)
    path = tmp_path / "pc.npz"
    model.save(path)
    loaded = PartClassifier.load(path)
    # leaf probabilities are stored as float16
    np.testing.assert_allclose(loaded.predict_proba(Xt), forest.predict_proba(Xt), atol=2e-3)
    np.testing.assert_allclose(loaded.position_offset, [0.01, 0.02, 0.03, 0.0])


def test_unreadable_classifier_file_is_input_error(tmp_path):
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"not a zip")
    with pytest.raises(InputError):
        PartClassifier.load(bad)
    np.savez(tmp_path / "other.npz", feature_names=np.array(["x"]))
    with pytest.raises(InputError, match="other features"):
        PartClassifier.load(tmp_path / "other.npz")


def test_shipped_classifier_labels_fresh_frames():
    """Frames rendered now (poses not in the training motions): head >= 0.8, all extrema >= 0.75."""
    model = default_classifier()
    if model is None:
        pytest.skip(f"{DEFAULT_PATH} not trained yet")
    from depthtrack.synth.part_scenes import render_scene_frames
    from depthtrack.synth.noise import ToFNoise

    body, cam = F.body(), F.camera()
    poses = np.stack([F.pose(**F.POSES[n]) for n in ("a_pose", "t_pose", "reach")])
    truth_all, pred_all = [], []
    for azimuth, noisy in ((0.0, False), (35.0, True), (-60.0, True)):
        frames = render_scene_frames(body, poses, cam, noise=ToFNoise.for_camera("sr4000") if noisy else None,
                                     rng=np.random.default_rng(7), azimuth=azimuth, labels=True)
        for f in frames:
            fg = segment_foreground(f.depth, cam)
            ex = geodesic_extrema(fg, cam, count=6)
            labels, scores, _ = model.classify(f.depth, cam, ex, fg)
            labels = np.where(scores >= 0.5, labels, "other")
            truth_all.append(extremum_truth(f.labels, ex.pixels, body.joint_names))
            pred_all.append(labels)
    truth, pred = np.concatenate(truth_all), np.concatenate(pred_all)
    head = truth == "head"
    assert head.sum() >= 7
    assert np.mean(pred[head] == "head") >= 0.8
    assert np.mean(pred == truth) >= 0.75


def test_detect_parts_reports_head_hands_feet_near_the_truth():
    f = F.frame("t_pose", noisy=True, seed=2)
    from depthtrack.contract import JOINT_NAMES

    for classifier in (None, "heuristic"):
        dets = detect_parts(f.depth, F.camera(), classifier=classifier)
        assert {d.label for d in dets} <= {"head", "hand", "foot"}
        for d in dets:
            assert d.position.shape == (3,) and d.direction.shape == (3,) and d.pixel.shape == (2,)
            assert np.linalg.norm(d.direction) == pytest.approx(1.0)
            assert 0.5 <= d.score <= 1.0
            joints = {"head": ["head"], "hand": ["l_wrist", "r_wrist"], "foot": ["l_ankle", "r_ankle"]}[d.label]
            err = min(np.linalg.norm(f.joints[JOINT_NAMES.index(j)] - d.position) for j in joints)
            assert err < 0.20, (classifier, d.label, err)
        labels = sorted(d.label for d in dets)
        assert labels.count("head") == 1 and labels.count("foot") == 2 and labels.count("hand") == 2


def test_unknown_classifier_name_is_input_error():
    f = F.frame("a_pose")
    with pytest.raises(InputError):
        detect_parts(f.depth, F.camera(), classifier="magic")
