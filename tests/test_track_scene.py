"""The scene behind the person (ObserveSettings.scene_memory) and the rechecks' margins over
what a pose can still explain (HeadingSettings.margins_over)."""
import numpy as np
import pytest

from depthtrack.camera import Camera
from depthtrack.track.observation import observation_image, update_scene

CAMERA = Camera.preset("sr4000")


def _wall_and_person(person_x=slice(60, 90)):
    """(depth (144, 176), mask): a wall at 4.9 m, a person at 4.4 m in columns ``person_x``."""
    depth = np.full((144, 176), 4.9, np.float32)
    mask = np.zeros(depth.shape, bool)
    mask[30:120, person_x] = True
    depth[mask] = 4.4
    return depth, mask


def _near(mask, k=7):
    import cv2

    return cv2.dilate(mask.astype(np.uint8), np.ones((k, k), np.uint8)) > 0


def test_the_scene_is_learnt_away_from_the_person_and_kept_where_the_person_stands():
    depth, mask = _wall_and_person(slice(60, 90))
    scene = update_scene(None, depth, _near(mask))
    assert scene.dtype == np.float32 and scene.shape == depth.shape
    assert np.all(scene[_near(mask)] == 0)                  # where the person may be: unknown
    assert np.allclose(scene[~_near(mask)], 4.9)
    depth2, mask2 = _wall_and_person(slice(100, 130))       # the person has moved right
    depth2[0, 0] = 0.0                                       # a dropout keeps what was seen
    scene2 = update_scene(scene, depth2, _near(mask2))
    assert scene2[0, 0] == pytest.approx(4.9)
    assert np.allclose(scene2[50, 60:90], 4.9)               # uncovered wall: now known
    assert np.allclose(scene2[50, 100:130], 4.9)             # under the person: the earlier wall
    assert scene is not scene2 and np.all(scene[_near(mask)] == 0)   # no change in place
    # a frame whose mask missed the person: the body does not overwrite the wall seen before
    missed, _ = _wall_and_person(slice(100, 130))
    scene3 = update_scene(scene2, missed, np.zeros(missed.shape, bool))
    assert np.allclose(scene3[50, 100:130], 4.9)
    # where only the person had been seen, the wall seen later replaces it
    first = update_scene(None, missed, np.zeros(missed.shape, bool))
    assert np.allclose(first[50, 100:130], 4.4)
    assert np.allclose(update_scene(first, depth, _near(mask))[50, 100:130], 4.9)


def test_a_known_wall_beside_the_person_is_background_and_the_person_is_not():
    before, mask_before = _wall_and_person(slice(60, 90))   # the frame before, person to the left
    scene = update_scene(None, before, _near(mask_before))
    depth, mask = _wall_and_person(slice(100, 130))
    near = _near(mask, 15)
    without = observation_image(depth, mask, CAMERA, near=near)
    with_scene = observation_image(depth, mask, CAMERA, near=near, scene=scene, scene_tolerance=0.1)
    halo = near & ~mask
    assert np.all(without[halo] == pytest.approx(4.9))       # the wall is a reading to explain
    learnt = halo & (scene > 0)
    assert learnt.any() and np.all(np.isinf(with_scene[learnt]))
    assert np.all(with_scene[halo & (scene == 0)] == pytest.approx(4.9))  # not seen yet: as before
    assert np.all(with_scene[mask] == pytest.approx(4.4))    # the person is never background
    # something in front of the wall (a hand the mask missed) stays a reading
    depth[50, 95] = 4.5
    assert observation_image(depth, mask, CAMERA, near=near, scene=scene)[50, 95] == pytest.approx(4.5)


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
