"""The built-in motions of the held-out benchmark, and their train / dev / test split."""
import numpy as np
import pytest

from depthtrack.body import BodyModel
from depthtrack.contract import JOINT_INDEX as C
from depthtrack.synth.procedural import PROCEDURAL_MOTIONS, PROCEDURAL_SPLIT, procedural_motion
from depthtrack.track.twins import facing_direction


@pytest.fixture(scope="module")
def body():
    return BodyModel.default(mesh="decimated")


def test_every_motion_in_exactly_one_split():
    names = [n for split in ("train", "dev", "test") for n in PROCEDURAL_SPLIT[split]]
    assert sorted(names) == sorted(PROCEDURAL_MOTIONS) and len(names) == len(set(names))


def test_spins_turn_in_place_at_their_speeds(body):
    for name, turns in (("spin-slow", 1), ("spin", 2), ("spin-fast", 3)):
        poses = procedural_motion(name, body, 25.0)
        assert poses[-1, 4] == pytest.approx(2 * np.pi * turns)          # pelvis_ry: turns about the vertical
        assert np.abs(poses[:, [0, 2]]).max() < 1e-9                       # in place


def test_benchmark_motions_rest_on_the_floor(body):
    rest = np.asarray(body.posed_vertices(np.zeros((1, body.dof))))[0, :, 1].max()
    for name in ("bend", "squat-deep", "lie-down", "lie-front", "overhead", "sidestep", "walk-back"):
        poses = procedural_motion(name, body, 10.0)
        assert np.all(np.isfinite(poses))
        assert np.abs(np.diff(poses, axis=0)[:, 3:]).max() < 0.5            # smooth at 10 fps
        lowest = np.asarray(body.posed_vertices(poses))[..., 1].max(axis=1)
        np.testing.assert_allclose(lowest, rest, atol=1e-9)
        joints = body.joint_positions(poses)
        if name == "lie-down":          # lying flat: the head near the floor (y down), halfway through
            mid = joints[len(joints) // 2]
            assert rest - mid[C["head"], 1] < 0.3 and rest - joints[0, C["head"], 1] > 1.4
        if name == "lie-front":         # lying flat on the front, the wrists past the head
            mid = joints[len(joints) // 2]
            assert rest - mid[C["head"], 1] < 0.3 and rest - mid[C["pelvis"], 1] < 0.3
            assert facing_direction(poses[len(poses) // 2])[1] > 0.95          # face down (y down)
            axis = mid[C["head"]] - mid[C["pelvis"]]
            assert (mid[C["l_wrist"]] - mid[C["pelvis"]]) @ axis > axis @ axis   # beyond the head
        if name == "sidestep":          # to the subject's left (+x) and back
            assert joints[:, C["pelvis"], 0].max() > 1.0 and abs(joints[-1, C["pelvis"], 0]) < 0.1
        if name == "walk-back":         # away from where it faces (it faces -z)
            assert joints[:, C["pelvis"], 2].max() > 0.8


def test_camera_pitch_and_height_are_honoured(body):
    from depthtrack.camera import Camera
    from depthtrack.synth.scene import place_camera

    poses = procedural_motion("spin", body, 5.0)
    default = place_camera(Camera.preset("sr4000"), body, poses)
    high = place_camera(Camera.preset("sr4000"), body, poses, height=2.2, pitch_deg=20.0, azimuth_deg=135.0)
    assert high.pitch_deg == pytest.approx(20.0) and high.height == pytest.approx(2.2)
    assert 0 < default.pitch_deg < 15                 # aimed at the middle of the body from chest height
    assert high.in_view == 1.0                        # backed off until the whole body is in view


def test_a_motion_that_travels_too_far_stays_within_the_sensors_range(body):
    """3.5 m straight at the camera, swaying side to side (whole-body roll up to 0.5 rad,
    as a cartwheel's run-up does), cannot stay wholly in view at any distance;
    the placement then keeps the most of the body seen -- not a distance where the person
    starts beyond the sensor's range (where a few more frames happen to be whole)."""
    from depthtrack.camera import Camera
    from depthtrack.synth.scene import place_camera

    camera = Camera.preset("sr4000")
    poses = np.zeros((50, body.dof))
    poses[:, 2] = -np.linspace(0.0, 3.5, 50)           # it faces -z: goes 3.5 m towards the camera
    poses[:, 5] = 0.5 * np.sin(np.linspace(0.0, 2 * np.pi, 50))
    place = place_camera(camera, body, poses, max_depth=5.0)
    assert place.in_view < 1.0
    assert place.visible > 0.9
    pelvis = body.joint_positions(poses)[:, C["pelvis"]]
    T = place.world_to_camera
    depth = pelvis @ T[2, :3] + T[2, 3]
    assert depth.max() < 5.0         # in range from the first frame (counting whole frames: 5.25 m)
    fixed = place_camera(camera, body, poses, max_depth=5.0, distance=place.distance)
    assert fixed.visible == pytest.approx(place.visible) and fixed.in_view == place.in_view
