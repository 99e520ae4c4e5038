"""The MAP energy's trunk-twist prior: the twist against closed forms, the term against the renderer."""
import numpy as np

from depthtrack.body.rotations import matrix_to_rotvec, rotation_about
from depthtrack.track.energy import spine_twist


def _spine(R):
    x = np.zeros(48)
    x[6:9] = matrix_to_rotvec(np.asarray(R)[None])[0]
    return x


def test_spine_twist_is_the_twist_about_the_vertical_whatever_the_bend():
    y, x, z = np.eye(3)[1], np.eye(3)[0], np.eye(3)[2]
    for twist in (-0.9, -0.3, 0.0, 0.4, 1.2):
        assert abs(spine_twist(_spine(rotation_about(y, twist)))[0] - twist) < 1e-9
        for bend_axis in (x, z):
            for bend in (-0.6, 0.5):
                # a swing about a horizontal axis after the twist: the twist is unchanged
                R = rotation_about(bend_axis, bend) @ rotation_about(y, twist)
                assert abs(spine_twist(_spine(R))[0] - twist) < 1e-9
    # a bend alone is no twist, and the rotation vector's ry component would say otherwise
    R = rotation_about(x, 0.8) @ rotation_about(y, 0.5)
    assert abs(_spine(R)[7] - 0.5) > 0.01
    assert spine_twist(np.zeros((3, 48))).shape == (3,)


def test_twist_prior_adds_its_gaussian_term_to_the_energy():
    from depthtrack.body.model import BodyModel
    from depthtrack.camera import Camera
    from depthtrack.render.tiles import TileRenderer
    from depthtrack.track.energy import Energy
    from depthtrack.track.record import Recorder

    body = BodyModel.default()
    camera = Camera.preset("sr4000")
    renderer = TileRenderer(body, camera, tile=32)
    try:
        pose = np.zeros(48)
        pose[2] = 2.5
        # the person's own render as the observation: the likelihood terms cancel anyway
        observed = np.zeros(camera.shape, np.float32)
        observed[20:120, 60:120] = 2.5
        renderer.set_observation(observed)
        poses = np.repeat(pose[None], 3, axis=0)
        poses[:, 6:9] = [_spine(rotation_about(np.eye(3)[1], t))[6:9] for t in (0.0, 0.3, -0.6)]
        plain = Energy(renderer, 100.0, True, Recorder(), pose_prior_std=1.0)
        twisted = Energy(renderer, 100.0, True, Recorder(), pose_prior_std=1.0, twist_std=0.2)
        np.testing.assert_allclose(twisted(poses) - plain(poses),
                                   0.5 * (np.array([0.0, 0.3, -0.6]) / 0.2) ** 2, rtol=1e-6)
    finally:
        renderer.release()
