"""Model markers on a fitted body: the synthesizer's marker vertices, NaN where unknown."""
import numpy as np

from depthtrack.body import BodyModel
from depthtrack.evaluate.markers import known_marker_names, marker_positions
from depthtrack.body.markers import MARKER_NAMES, marker_vertices


def test_marker_positions_are_the_posed_marker_vertices():
    body = BodyModel.default(height=1.62)
    rng = np.random.default_rng(11)
    poses = np.tile(body.default_pose((0.2, 0.0, 3.0)), (3, 1))
    poses[:, 3:] += rng.normal(0.0, 0.2, (3, 45))
    poses[1] = np.nan                                   # no estimate in frame 1
    names = ["NOT_A_MARKER", "RKNE", "LFHD", "C7"]
    got = marker_positions(body, poses, names)
    assert got.shape == (3, 4, 3)
    assert np.isnan(got[:, 0]).all() and np.isnan(got[1]).all()
    vertices = marker_vertices(body)[[MARKER_NAMES.index(n) for n in names[1:]]]
    expected = body.posed_vertices(poses[[0, 2]])[:, vertices]      # the full skinning reference
    np.testing.assert_allclose(got[[0, 2], 1:], expected, atol=1e-9)
    assert known_marker_names(names) == names[1:]
