"""Error metrics against hand-computed values (NaN = unknown ground truth or estimate)."""
import math

import numpy as np
import pytest

from depthtrack.evaluate import metrics

nan = np.nan


def _pair():
    """2 frames x 3 points; errors by construction (3-4-5 triangles and axis offsets):
    frame 0: 0.05, 0.30, unknown truth;  frame 1: 0.10, unknown estimate, 0.02."""
    truth = np.zeros((2, 3, 3))
    truth[0, 2] = nan                      # ground-truth row missing
    est = np.zeros((2, 3, 3))
    est[0, 0] = (0.03, 0.04, 0.0)          # 0.05
    est[0, 1] = (0.0, 0.18, 0.24)          # 0.30
    est[1, 0] = (0.0, 0.0, -0.10)          # 0.10
    est[1, 1] = nan                        # no estimate
    est[1, 2] = (0.02, 0.0, 0.0)           # 0.02
    return est, truth


def test_point_errors_are_distances_with_nan_for_unknown():
    est, truth = _pair()
    err = metrics.joint_errors(est, truth)
    # unknown truth: NaN (left out); known truth without an estimate: +inf (a miss)
    expected = np.array([[0.05, 0.30, nan], [0.10, np.inf, 0.02]])
    np.testing.assert_allclose(err, expected, atol=1e-12)


def test_summary_statistics_by_hand():
    err = metrics.joint_errors(*_pair())
    # known: 0.05, 0.30, 0.10, 0.02
    assert metrics.mean_error(err) == pytest.approx((0.05 + 0.30 + 0.10 + 0.02) / 4)
    # worst per frame 0.30 and 0.10
    assert metrics.mean_max_error(err) == pytest.approx(0.20)
    # within 10 cm (inclusive): 0.05, 0.10, 0.02 of 5 (the missing estimate is a miss)
    assert metrics.fraction_within(err, 0.10) == pytest.approx(0.6)
    assert metrics.fraction_within(err, 0.04) == pytest.approx(0.2)
    np.testing.assert_allclose(metrics.per_frame_mean(err), [0.175, 0.06])
    np.testing.assert_allclose(metrics.per_point_mean(err), [0.075, 0.30, 0.02])


def test_frames_without_anything_known_are_left_out():
    err = np.array([[0.2, nan], [nan, nan], [0.1, 0.3]])
    assert metrics.mean_max_error(err) == pytest.approx((0.2 + 0.3) / 2)
    assert np.isnan(metrics.per_frame_max(err)[1])
    assert np.isnan(metrics.per_frame_mean(err)[1])
    all_unknown = np.full((2, 3), nan)
    assert math.isnan(metrics.mean_error(all_unknown))
    assert math.isnan(metrics.mean_max_error(all_unknown))
    assert math.isnan(metrics.fraction_within(all_unknown))


def test_paper_marker_metrics_average_per_frame_first():
    # frame 0 has 4 visible markers, frame 1 only one: the per-frame mean comes first,
    # so frame 1's single marker weighs as much as frame 0's four.
    measured = np.zeros((2, 4, 3))
    measured[1, 1:] = nan
    model = np.zeros((2, 4, 3))
    model[0, :, 0] = (0.01, 0.02, 0.03, 0.06)
    model[1, 0, 2] = 0.10
    err = metrics.marker_errors(model, measured)
    assert metrics.average_marker_error(err) == pytest.approx(((0.01 + 0.02 + 0.03 + 0.06) / 4 + 0.10) / 2)
    assert metrics.max_marker_error(err) == pytest.approx((0.06 + 0.10) / 2)


def test_fps_and_summary():
    assert metrics.frames_per_second(50, 4.0) == 12.5
    assert math.isnan(metrics.frames_per_second(50, None))
    assert math.isnan(metrics.frames_per_second(50, 0.0))
    err = metrics.joint_errors(*_pair())
    s = metrics.summarize(err, frames=2, seconds=0.5)
    assert list(s) == list(metrics.METRIC_KEYS)
    assert s["fps"] == 4.0 and s["frames"] == 2
    assert s["mean_error_m"] == pytest.approx(0.1175)
    assert s["marker_mean_error_m"] is None and s["marker_max_error_m"] is None
    assert metrics.summarize(err, 2)["fps"] is None


def test_overall_is_sequence_weighted():
    a = {"frames": 10, "fps": 2.0, "mean_error_m": 0.1, "max_error_m": 0.2, "within_10cm": 0.5,
         "marker_mean_error_m": None, "marker_max_error_m": None}
    b = {"frames": 30, "fps": 4.0, "mean_error_m": 0.3, "max_error_m": 0.4, "within_10cm": 1.0,
         "marker_mean_error_m": 0.05, "marker_max_error_m": 0.09}
    o = metrics.average_summaries([a, b])
    assert o["frames"] == 40
    assert o["mean_error_m"] == pytest.approx(0.2)      # not frame-weighted (0.25)
    assert o["fps"] == pytest.approx(3.0)
    assert o["within_10cm"] == pytest.approx(0.75)
    assert o["marker_mean_error_m"] == pytest.approx(0.05)   # only b has markers


def test_shape_mismatch_is_rejected():
    with pytest.raises(ValueError):
        metrics.point_errors(np.zeros((2, 3, 3)), np.zeros((2, 4, 3)))


def test_back_to_front_marks_a_trunk_facing_away_and_leaves_unknown_frames_out():
    from depthtrack.body import BodyModel
    from depthtrack.body.skeleton import MODEL_UP
    from depthtrack.track.twins import SIDES_SWAPPED, turned_pose

    body = BodyModel.default(height=1.75)
    pose = np.zeros(body.dof)
    pose[0:3] = (0.1, 0.0, 3.0)
    truth = np.repeat(np.asarray(body.joint_positions(pose))[None], 4, axis=0)   # (4, 15, 3)
    est = truth.copy()
    est[1] = np.asarray(body.joint_positions(turned_pose(pose)))   # half a turn: away
    est[2] = truth[2][SIDES_SWAPPED]                              # sides exchanged: away too
    est[3] = nan                                                   # no estimate
    turned = pose.copy()
    turned[3:6] = np.radians(60) * MODEL_UP                         # a turn short of profile
    flags = metrics.back_to_front(np.concatenate([est, np.asarray(body.joint_positions(turned))[None]]),
                                  np.concatenate([truth, truth[:1]]))
    assert flags[:3].tolist() == [0.0, 1.0, 1.0] and math.isnan(flags[3]) and flags[4] == 0.0
    s = metrics.summarize(metrics.joint_errors(est, truth), 4, reversed_frames=flags[:4])
    assert s["back_to_front_fraction"] == pytest.approx(2 / 3)      # of the three known frames
    assert metrics.summarize(metrics.joint_errors(est, truth), 4)["back_to_front_fraction"] is None


def test_trunk_twist_is_the_chest_turned_against_the_hips_whatever_the_lean():
    from depthtrack.body import BodyModel
    from depthtrack.body.rotations import matrix_to_rotvec, rotation_about

    body = BodyModel.default(height=1.75)
    up = np.array([0.0, 1.0, 0.0])
    poses = []
    for twist, lean in ((0.0, 0.0), (30.0, 0.0), (-45.0, 0.0), (30.0, 50.0)):
        x = np.zeros(body.dof)
        x[0:3] = (0.0, 0.0, 3.0)
        # the whole body leaned (root), the chest twisted about its own vertical (spine)
        x[3:6] = matrix_to_rotvec(rotation_about(np.array([1.0, 0.0, 0.0]), np.radians(lean))[None])[0]
        x[6:9] = matrix_to_rotvec(rotation_about(up, np.radians(twist))[None])[0]
        poses.append(np.asarray(body.joint_positions(x)))
    joints = np.array(poses)
    tw = metrics.trunk_twist(joints)
    # the rest pose's chest joints sit over the pelvis, so the twist is the spine's own;
    # right-handed about the pelvis-to-neck axis, which points along the model's -y
    np.testing.assert_allclose(tw - tw[0], [0.0, -30.0, 45.0, -30.0], atol=0.5)
    err = metrics.twist_errors(joints, joints[[0, 0, 0, 0]])
    np.testing.assert_allclose(err, [0.0, 30.0, 45.0, 30.0], atol=0.5)
    joints[2] = nan
    s = metrics.summarize(metrics.joint_errors(joints, joints), 4,
                          twist_err=metrics.twist_errors(joints, joints[[0, 0, 0, 0]]))
    assert s["trunk_twist_error_deg"] == pytest.approx(20.0, abs=0.5)   # of the three known
