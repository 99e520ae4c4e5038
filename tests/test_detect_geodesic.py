"""Geodesic extrema: they find the ends of the limbs and point along them."""
import numpy as np
import pytest

from depthtrack.contract import JOINT_NAMES
from depthtrack.detect import detect_parts, geodesic_extrema, segment_foreground
from depthtrack.detect.geodesic import build_surface_graph
from depthtrack.errors import InputError

import detect_frames as F

ENDS = ("head", "l_wrist", "r_wrist", "l_ankle", "r_ankle")


@pytest.mark.parametrize("name", ["a_pose", "t_pose"])
def test_extrema_include_head_hands_and_feet(name):
    f = F.frame(name)
    fg = segment_foreground(f.depth, F.camera())
    ex = geodesic_extrema(fg, F.camera(), count=6)
    truth = f.joints[[JOINT_NAMES.index(n) for n in ENDS]]
    d = np.linalg.norm(ex.centres[:, None] - truth[None], axis=2)       # (K, 5)
    assert np.all(d.min(axis=0) < 0.10), dict(zip(ENDS, d.min(axis=0).round(3)))
    # five different extrema account for the five ends
    assert len(set(np.argmin(d, axis=0))) == 5
    # extrema lie on the foreground surface, directions are unit vectors
    assert np.all(np.linalg.norm(ex.directions, axis=1) == pytest.approx(1.0))
    u, v = ex.pixels.T
    assert fg.mask[v, u].all()


def test_extended_arm_direction_is_parallel_to_forearm():
    f = F.frame("t_pose")
    fg = segment_foreground(f.depth, F.camera())
    ex = geodesic_extrema(fg, F.camera(), count=6)
    for side in ("l", "r"):
        wrist = f.joints[JOINT_NAMES.index(f"{side}_wrist")]
        elbow = f.joints[JOINT_NAMES.index(f"{side}_elbow")]
        k = np.argmin(np.linalg.norm(ex.centres - wrist, axis=1))
        forearm = (wrist - elbow) / np.linalg.norm(wrist - elbow)
        assert np.degrees(np.arccos(ex.directions[k] @ forearm)) < 20.0


def test_geodesic_distance_of_a_straight_strip_is_its_length():
    """A flat 4 m x 0.2 m strip facing the camera: the extrema are its ends, 2 m from its centre."""
    from depthtrack.camera import Camera
    from depthtrack.detect.segment import Foreground

    cam = Camera(width=200, height=40, fx=100.0, fy=100.0, cx=99.5, cy=19.5)
    depth = np.zeros(cam.shape)
    depth[15:25, :] = 2.0                                   # 200 px at 2 m / 100 px = 4 m wide
    mask = depth > 0
    rows, cols = np.nonzero(mask)
    fg = Foreground(mask, cam.backproject(depth)[mask], np.stack([cols, rows], 1))
    ex = geodesic_extrema(fg, cam, count=2)
    # the strip spans u = 0..199 at 2 cm per pixel: centre to end is 2 m
    assert ex.distances[0] == pytest.approx(2.0, abs=0.05)
    # the other end, 2 m from the nearest source (the centre), on the opposite side
    assert ex.distances[1] == pytest.approx(2.0, abs=0.05)
    assert ex.positions[0][0] * ex.positions[1][0] < 0
    # each end's direction points outward along the strip
    np.testing.assert_allclose(ex.directions[:, 0], np.sign(ex.positions[:, 0]), atol=0.05)


def test_large_foreground_is_subsampled():
    f = F.frame("a_pose")
    fg = segment_foreground(f.depth, F.camera())
    g = build_surface_graph(fg, F.camera(), max_nodes=800)
    assert g.stride >= 2 and len(g.points) <= 800


def test_detect_parts_rejects_bad_depth():
    with pytest.raises(InputError):
        detect_parts(np.full((144, 176), np.nan), F.camera())
    with pytest.raises(InputError):
        detect_parts(np.zeros((10, 10)), F.camera())


def test_empty_or_tiny_foreground_gives_no_extrema():
    from depthtrack.detect.segment import Foreground

    cam = F.camera()
    empty = Foreground(np.zeros(cam.shape, bool), np.zeros((0, 3)), np.zeros((0, 2), int))
    assert len(geodesic_extrema(empty, cam)) == 0
    assert detect_parts(np.zeros(cam.shape), cam) == []
    mask = np.zeros(cam.shape, bool)
    mask[70:72, 80:82] = True                                     # a 2 x 2 px speck: 1.4 cm across
    depth = np.where(mask, 2.0, 0.0)
    speck = Foreground(mask, cam.backproject(depth)[mask], np.argwhere(mask)[:, ::-1])
    assert len(geodesic_extrema(speck, cam)) == 0                 # nothing 10 cm from the centre
