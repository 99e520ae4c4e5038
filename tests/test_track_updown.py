"""The start's up/down check (issue 10): the upside-down twin of a start pose, against closed
forms (half a turn in the image plane about the middle of the joints' extent)."""
import numpy as np
import pytest

from depthtrack.body import BodyModel
from depthtrack.body.skeleton import JOINT_ID
from depthtrack.track import TrackerSettings
from depthtrack.track.heading import facing_direction, inverted_pose


@pytest.fixture(scope="module")
def body():
    return BodyModel.default(mesh="decimated")


def test_the_inverted_twin_turns_the_body_half_a_turn_in_the_image(body):
    rng = np.random.default_rng(3)
    x = np.zeros(48)
    x[:3] = [0.3, 0.1, 3.2]
    x[6:] = rng.normal(0.0, 0.15, 42)
    j = body.joint_positions(x[None])[0]
    y = inverted_pose(body, x)
    k = body.joint_positions(y[None])[0]
    centre = np.array([*(0.5 * (j[:, :2].min(axis=0) + j[:, :2].max(axis=0))), x[2]])
    # every joint mirrored through the line of sight: x and y about the centre, depth kept
    assert np.allclose(k[:, :2] - centre[:2], -(j[:, :2] - centre[:2]), atol=1e-9)
    assert np.allclose(k[:, 2], j[:, 2], atol=1e-9)
    # the same joint angles; the extent in the image is the same box
    assert np.allclose(y[6:], x[6:])
    assert np.allclose(k[:, :2].min(axis=0), j[:, :2].min(axis=0), atol=1e-9)
    # the neck goes below the body's middle (image y grows downwards), the front stays toward the camera
    head = JOINT_ID["neck"]
    assert k[head, 1] > k[:, 1].mean() > j[head, 1]
    assert np.sign(facing_direction(y)[2]) == np.sign(facing_direction(x)[2])
    # twice is the identity
    assert np.allclose(inverted_pose(body, y), x, atol=1e-9)


def test_the_up_down_check_is_an_option_off_by_default():
    assert TrackerSettings().heading.start_inverted is False
    assert TrackerSettings(heading={"start_inverted": True}).heading.start_inverted is True
    with pytest.raises(ValueError, match="start_inverted"):
        TrackerSettings(heading={"start_inverted": "yes"})
