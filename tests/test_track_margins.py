"""The rechecks' relative margins over what a pose can still explain
(HeadingSettings.margins_over: energy.fixed_energy, energy.relative_lead)."""
import numpy as np
import pytest

from depthtrack.camera import Camera

CAMERA = Camera.preset("sr4000")


def test_relative_lead_is_a_fraction_of_the_energy_above_the_floor():
    from depthtrack.track.energy import relative_lead

    assert relative_lead(100.0, 97.0) == pytest.approx(0.03)
    assert relative_lead(100.0, 97.0, floor=40.0) == pytest.approx(0.05)
    assert relative_lead(100.0, 103.0, floor=40.0) == pytest.approx(-0.05)


def test_fixed_energy_is_what_every_pose_pays_for_an_roi_reaching_out_of_the_image():
    from depthtrack.body import BodyModel
    from depthtrack.likelihood import LikelihoodParams
    from depthtrack.render import TileRenderer
    from depthtrack.track.energy import Energy, fixed_energy
    from depthtrack.track.record import Recorder

    body = BodyModel.default(mesh="decimated")
    params = LikelihoodParams()
    depth = np.full(CAMERA.shape, np.inf, np.float32)       # open space: background
    depth[20:130, 70:110] = 2.6
    roi = (88.0, 6.0, 112.0)                                  # its right 24 columns outside
    r = TileRenderer(body, CAMERA, tile=64, params=params)
    try:
        r.set_observation(depth, roi=roi)
        energy = Energy(r, 112.0 ** 2, True, Recorder())
        outside = np.mean((np.arange(64) + 0.5) * 112 / 64 + 88 >= CAMERA.width)
        assert fixed_energy(energy) == pytest.approx(112.0 ** 2 * params.no_reading_cost * outside,
                                                     rel=0.05)
        rng = np.random.default_rng(0)
        poses = np.repeat(body.default_pose(position=(0.0, 0.0, 2.6))[None], 6, axis=0)
        poses[:, 6:] += rng.normal(0, 0.2, poses[:, 6:].shape)
        poses[:, 0] += rng.uniform(-0.5, 0.5, 6)
        assert np.all(energy.weight * energy.likelihood_costs(poses) >= fixed_energy(energy) - 1e-6)
    finally:
        r.release()
