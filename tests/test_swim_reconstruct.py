"""Reconstruction from 2D markings (thesis 2.4-2.6): noisy projections of mocap back to 3D."""
import json

import numpy as np
import pytest

from depthtrack.cli import main
from depthtrack.swim.cycles import detect_cycle_starts
from depthtrack.swim.markings import read_markings, reconstruct_markings, write_markings
from depthtrack.swim.mocap import load_swim_mocap
from depthtrack.swim.reconstruct import (
    complete_other_half, join_above_below, reconstruct_single_view, reconstruct_two_views, sync_offset,
    taylor_scale, view_scale)
from depthtrack.swim.stickfigure import SEGMENTS, SWIM_INDEX, SWIM_PARENTS, mirror_joints, segment_lengths

LEFT = [SWIM_INDEX[n] for n in ("l_hip", "l_knee", "l_foot", "l_shoulder", "l_elbow", "l_hand")]


@pytest.fixture(scope="module")
def pool_joints(shared_data):
    """A back-stroke stretch in a side-view pool frame: lane along x, lateral along z, root at 0."""
    mocap = load_swim_mocap(shared_data / "cmu" / "126_01.bvh")
    j = mocap.joints[700:1100]
    p = np.stack([j[..., 2], j[..., 1], -j[..., 0]], axis=-1)
    return p - p[:, :1]


def side_projection(points, scale, noise, rng):
    return scale * np.stack([points[..., 0], -points[..., 1]], -1) + rng.normal(0, noise, points.shape[:-1] + (2,))


def test_taylor_single_view_exact_without_noise():
    rng = np.random.default_rng(0)
    d = rng.normal(size=(30, 13, 3))
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    lengths = rng.uniform(0.2, 0.5, 13)
    pts = np.zeros((30, 14, 3))
    for j in range(1, 14):
        pts[:, j] = pts[:, SWIM_PARENTS[j]] + lengths[j - 1] * d[:, j - 1]
    uv = side_projection(pts, 250.0, 0.0, rng)
    nearer = (pts[:, 1:, 2] - pts[:, SWIM_PARENTS[1:], 2]) < 0
    rec, scale = reconstruct_single_view(uv, lengths, nearer)
    assert scale <= 250.0 + 1e-9                        # eq. 2.7: the bound never exceeds the true scale
    assert scale == pytest.approx(taylor_scale(uv, lengths))
    rec_true, _ = reconstruct_single_view(uv, lengths, nearer, scale=250.0)
    np.testing.assert_allclose(rec_true, pts, atol=1e-9)


def test_single_view_from_noisy_mocap_projection(pool_joints):
    rng = np.random.default_rng(1)
    lengths = np.median(segment_lengths(pool_joints), axis=0)
    uv = side_projection(pool_joints, 300.0, 1.0, rng)          # 1 px noise at 300 px/m
    nearer = (pool_joints[:, 1:, 2] - pool_joints[:, SWIM_PARENTS[1:], 2]) < 0
    rec, scale = reconstruct_single_view(uv, lengths, nearer)
    err = np.linalg.norm(rec - rec[:, :1] - pool_joints, axis=-1).mean()
    assert 300 < scale < 330                                     # noise inflates the lower bound
    assert err < 0.13                                            # measured 11.6 cm
    rec_q, scale_q = reconstruct_single_view(uv, lengths, nearer, quantile=0.9)
    assert np.linalg.norm(rec_q - rec_q[:, :1] - pool_joints, axis=-1).mean() < 0.06   # measured 5.0 cm
    rec_s, _ = reconstruct_single_view(uv, lengths, nearer, scale=300.0)
    assert np.linalg.norm(rec_s - rec_s[:, :1] - pool_joints, axis=-1).mean() < 0.03    # measured 2.5 cm


def test_two_views_from_noisy_mocap_projection(pool_joints):
    rng = np.random.default_rng(2)
    lengths = np.median(segment_lengths(pool_joints), axis=0)
    side = side_projection(pool_joints, 300.0, 1.0, rng)
    top = 210.0 * np.stack([pool_joints[..., 0], pool_joints[..., 2]], -1) + rng.normal(0, 1.0, side.shape)
    joints, info = reconstruct_two_views(side, top, lengths)
    assert info["view_scale"] == pytest.approx(0.7, rel=0.01)
    assert np.linalg.norm(joints - pool_joints, axis=-1).mean() < 0.015          # measured 0.8 cm
    assert view_scale([1.0, 2.0, 3.0], [2.0, 4.0, 6.0]) == pytest.approx(2.0)


def test_half_body_by_half_cycle_shift_and_by_mirroring(pool_joints):
    rng = np.random.default_rng(3)
    lengths = np.median(segment_lengths(pool_joints), axis=0)
    uv = side_projection(pool_joints, 300.0, 0.0, rng)
    uv[:, LEFT] = np.nan
    nearer = (pool_joints[:, 1:, 2] - pool_joints[:, SWIM_PARENTS[1:], 2]) < 0
    half, _ = reconstruct_single_view(uv, lengths, nearer, scale=300.0)
    starts = detect_cycle_starts(pool_joints, 120.0)
    full = complete_other_half(half, "back", starts)
    full -= full[:, :1]
    err = np.linalg.norm(full[:, LEFT] - pool_joints[:, LEFT], axis=-1).mean()
    assert np.isfinite(full).all() and err < 0.30      # the real left arm is not exactly half a cycle late
    # mirroring reproduces a mirror-symmetric figure exactly
    sym = pool_joints[:5].copy()
    sym[:, SWIM_INDEX["neck"], 2] = 0.0        # hips and neck on the plane of symmetry
    mirrored = mirror_joints(sym, axis=2)
    sym[:, LEFT] = mirrored[:, LEFT]
    holes = sym.copy()
    holes[:, LEFT] = np.nan
    np.testing.assert_allclose(complete_other_half(holes, "breast"), sym, atol=1e-12)


def test_join_above_and_below_water_and_sync():
    below = np.full((2, 14, 2), np.nan)
    above = np.full((2, 14, 2), np.nan)
    s, e, h = SWIM_INDEX["r_shoulder"], SWIM_INDEX["r_elbow"], SWIM_INDEX["r_hand"]
    below[:, s] = [10.0, 20.0]
    above[:, s] = [110.0, 220.0]            # the above-water camera sees the shoulder elsewhere
    above[:, e] = [130.0, 200.0]
    above[:, h] = [150.0, 190.0]
    joined = join_above_below(below, above)
    np.testing.assert_allclose(joined[:, e], [[30.0, 0.0]] * 2)
    np.testing.assert_allclose(joined[:, h], [[50.0, -10.0]] * 2)
    assert sync_offset([12, 80], [5, 73]) == -7


def test_markings_csv_round_trip_and_cli(pool_joints, tmp_path):
    rng = np.random.default_rng(4)
    pts = pool_joints[:60]
    lengths = np.median(segment_lengths(pool_joints), axis=0)
    side = side_projection(pts, 300.0, 0.5, rng)
    top = 200.0 * np.stack([pts[..., 0], pts[..., 2]], -1)
    top_late = np.full((70, 14, 2), np.nan)
    top_late[10:] = top                                             # top recording starts 10 frames later
    nearer = (pts[:, 1:, 2] - pts[:, SWIM_PARENTS[1:], 2]) < 0
    csv_path = tmp_path / "m.csv"
    write_markings(csv_path, {"side": side, "top": top_late}, nearer, {"side": [5], "top": [15]})
    m = read_markings(csv_path)
    assert m.cycle_starts == {"side": [5], "top": [15]}
    np.testing.assert_array_equal(m.nearer[:60], nearer)
    joints, info = reconstruct_markings(m, lengths)
    assert "two views" in info
    assert np.linalg.norm(joints[:60] - pts, axis=-1).mean() < 0.01
    lengths_path = tmp_path / "lengths.json"
    lengths_path.write_text(json.dumps(dict(zip(SEGMENTS, lengths.tolist()))))
    out = tmp_path / "joints.csv"
    assert main(["swim", "reconstruct", str(csv_path), "--lengths", str(lengths_path), "-o", str(out)]) == 0
    lines = out.read_text().splitlines()
    assert lines[0] == "frame,joint,x,y,z" and len(lines) > 60 * 14


def test_bad_markings_fail_with_one_line(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("frame,joint,u,v,view\n0,nose,1,2,side\n")
    lengths = tmp_path / "l.json"
    lengths.write_text(json.dumps([0.3] * 13))
    assert main(["swim", "reconstruct", str(bad), "--lengths", str(lengths), "-o", str(tmp_path / "o.csv")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "unknown joint 'nose'" in err[0] and str(bad) in err[0]
    assert not (tmp_path / "o.csv").exists()
