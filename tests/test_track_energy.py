"""The MAP energy's trunk-twist prior: the twist against closed forms, the term against the renderer."""
import numpy as np
import pytest

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


def test_pose_prior_takes_the_hidden_std_on_the_hidden_joints_only():
    """Closed forms: ``0.5 * sum((x_j / std)^2)`` over the joint rotations, the root free;
    the listed joints at their own std; a std of 0 drops its terms."""
    from depthtrack.body.skeleton import JOINT_ID
    from depthtrack.track.energy import pose_prior

    rng = np.random.default_rng(3)
    poses = rng.normal(size=(4, 48))
    joints = poses[:, 6:].reshape(4, 14, 3)
    per_joint = np.sum(joints ** 2, axis=2)                         # (4, 14), joints 1..14
    np.testing.assert_allclose(pose_prior(poses, 2.0), 0.5 * per_joint.sum(1) / 4.0)
    poses_moved = poses.copy()
    poses_moved[:, :6] += 5.0                                       # the root costs nothing
    np.testing.assert_allclose(pose_prior(poses_moved, 2.0), pose_prior(poses, 2.0))
    arm = [JOINT_ID[n] for n in ("l_shoulder", "l_elbow", "l_wrist")]
    expected = 0.5 * per_joint.sum(1) / 4.0 + 0.5 * per_joint[:, np.array(arm) - 1].sum(1) * (
        1.0 / 0.25 - 1.0 / 4.0)
    np.testing.assert_allclose(pose_prior(poses, 2.0, arm, 0.5), expected)
    np.testing.assert_allclose(pose_prior(poses, 0.0, arm, 0.5),
                               0.5 * per_joint[:, np.array(arm) - 1].sum(1) / 0.25)
    np.testing.assert_allclose(pose_prior(poses, 2.0, arm, 0.0),
                               0.5 * np.delete(per_joint, np.array(arm) - 1, axis=1).sum(1) / 4.0)
    assert pose_prior(poses[0], 1.0).shape == (1,)


def _turned(ry):
    """``(48,)`` the zero pose 3 m in front of the camera, its pelvis turned ``ry`` (rad)
    about the vertical (pi / 2: side on)."""
    x = np.zeros(48)
    x[2] = 3.0
    x[4] = ry
    return x


def _far_arm_raised(pose, far):
    """``pose`` with the ``far`` ("l" or "r") arm raised overhead at the shoulder."""
    from depthtrack.body.skeleton import JOINT_ID

    raised = np.array(pose, dtype=np.float64)
    raised[3 + 3 * JOINT_ID[f"{far}_shoulder"] + 2] = 2.8 if far == "l" else -2.8
    return raised


def _side_view_frame(tracker, pose):
    """The depth of ``pose`` rendered by the tracker's own full-image renderer, observed."""
    from types import SimpleNamespace

    from depthtrack.track.state import TrackingState

    depth = tracker.renderers.depth(pose).astype(np.float32)
    mask = depth > 0
    foreground = SimpleNamespace(mask=mask, points=tracker.camera.backproject(depth)[mask],
                                 floor_plane=None)
    frame, _ = tracker._observe(TrackingState(), depth, foreground=foreground)
    return frame


def test_the_far_arm_of_a_side_view_takes_the_hidden_prior():
    """From the side the far arm hangs behind the body: :meth:`Tracker.hidden_joints` lists
    its three joints (and no joint of the near arm), from the front none of the arms; the
    energy of a frame then charges that arm's rotations at ``hidden_prior_std``, only with
    the setting on and a pose to look from."""
    from depthtrack.body.model import BodyModel
    from depthtrack.camera import Camera
    from depthtrack.body.skeleton import JOINT_ID
    from depthtrack.track.energy import pose_prior
    from depthtrack.track.tracker import Tracker, TrackerSettings

    body = BodyModel.default(1.75)
    camera = Camera.preset("sr4000")
    settings = TrackerSettings(energy={"hidden_prior_std": 0.4})
    with Tracker(body, camera, settings=settings) as tracker:
        side = _turned(np.pi / 2)                                   # pelvis ry: side on
        frame = _side_view_frame(tracker, side)
        hidden = tracker.hidden_joints(frame, side)
        z = body.joint_positions(side)[:, 2]
        far = "l" if z[JOINT_ID["l_shoulder"]] > z[JOINT_ID["r_shoulder"]] else "r"
        near = "r" if far == "l" else "l"
        far_arm = {JOINT_ID[f"{far}_{j}"] for j in ("shoulder", "elbow", "wrist")}
        assert far_arm <= set(hidden)
        assert not {JOINT_ID[f"{near}_{j}"] for j in ("shoulder", "elbow", "wrist")} & set(hidden)
        assert tracker.counts["hidden_limbs"] >= 1
        energy = tracker._energy(frame, hidden_of=side)
        assert energy.hidden_joints == tuple(hidden) and energy.hidden_prior_std == 0.4
        bent = side.copy()
        bent[3 + 3 * JOINT_ID[f"{far}_elbow"]] = -1.0                # the far elbow flexed
        np.testing.assert_allclose(energy(np.stack([bent]))[0] - energy.one(side),
                                   pose_prior(bent, 1.0, hidden, 0.4)[0]
                                   - pose_prior(side, 1.0, hidden, 0.4)[0]
                                   + (energy.likelihood(bent) - energy.likelihood(side)),
                                   rtol=1e-6)
        assert tracker._energy(frame).hidden_joints == ()            # no pose to look from
        front = side.copy()
        front[4] = 0.0
        frame = _side_view_frame(tracker, front)
        hidden = set(tracker.hidden_joints(frame, front))
        assert not hidden & {JOINT_ID[f"{s}_{j}"] for s in "lr" for j in ("elbow", "wrist")}
    # at a share of 5 % the far foot, of which a few pixels show, lists the far leg too;
    # with hidden_prior_limbs "arms" only the arm is charged
    for limbs, legs in (("all", True), ("arms", False)):
        looser = TrackerSettings(energy={"hidden_prior_std": 0.4, "hidden_prior_limbs": limbs},
                                 heading={"reseat_hidden": 0.05})
        with Tracker(body, camera, settings=looser) as tracker:
            hidden = set(tracker.hidden_joints(_side_view_frame(tracker, side), side))
            assert far_arm <= hidden
            far_leg = {JOINT_ID[f"{far}_{j}"] for j in ("hip", "knee", "ankle")}
            assert (far_leg <= hidden) == legs and (not far_leg & hidden) == (not legs)
    with Tracker(body, camera) as tracker:                           # off by default
        assert tracker._energy(_side_view_frame(tracker, side), hidden_of=side).hidden_joints == ()


def test_far_side_limbs_follow_the_trunk_not_the_limb():
    """:func:`far_side_limbs`: a body turned 90 degrees to the camera lists the arm and leg
    whose shoulder and hip lie farther away, the other side when turned the other way, none
    from the front or the back or beyond ``within_deg`` of a side view; raising the far arm
    over the head (out of the trunk's shadow) changes nothing, since the trunk decides."""
    from depthtrack.body.model import BodyModel
    from depthtrack.contract import JOINT_INDEX
    from depthtrack.track.reach import far_side_limbs

    body = BodyModel.default(1.75)
    for ry in (np.pi / 2, 3 * np.pi / 2):
        joints = body.joint_positions(_turned(ry))
        far = "l" if (np.linalg.norm(joints[JOINT_INDEX["l_shoulder"]])
                      > np.linalg.norm(joints[JOINT_INDEX["r_shoulder"]])) else "r"
        assert far_side_limbs(joints, 45.0) == {f"{far}_arm", f"{far}_leg"}
    assert far_side_limbs(body.joint_positions(_turned(np.pi / 2)), 45.0) != far_side_limbs(
        body.joint_positions(_turned(3 * np.pi / 2)), 45.0)
    for ry in (0.0, np.pi, np.pi / 2 - np.radians(50)):
        assert far_side_limbs(body.joint_positions(_turned(ry)), 45.0) == set()
    assert far_side_limbs(body.joint_positions(_turned(np.pi / 2 - np.radians(50))), 60.0)
    side = _turned(np.pi / 2)
    far = next(iter(far_side_limbs(body.joint_positions(side), 45.0) - {"l_leg", "r_leg"}))[0]
    raised = _far_arm_raised(side, far)                              # overhead
    assert far_side_limbs(body.joint_positions(raised), 45.0) == far_side_limbs(
        body.joint_positions(side), 45.0)


def test_the_side_gate_charges_the_far_arm_wherever_it_is():
    """``hidden_prior_gate`` "side": :meth:`Tracker.hidden_joints` lists the far arm of a side
    view from the trunk alone -- also with that arm raised in plain view, where the "shown"
    gate does not list it -- and nothing from the front."""
    from depthtrack.body.model import BodyModel
    from depthtrack.body.skeleton import JOINT_ID
    from depthtrack.camera import Camera
    from depthtrack.errors import InputError
    from depthtrack.track.tracker import Tracker, TrackerSettings

    body = BodyModel.default(1.75)
    camera = Camera.preset("sr4000")
    side = _turned(np.pi / 2)
    z = body.joint_positions(side)[:, 2]
    far = "l" if z[JOINT_ID["l_shoulder"]] > z[JOINT_ID["r_shoulder"]] else "r"
    far_arm = {JOINT_ID[f"{far}_{j}"] for j in ("shoulder", "elbow", "wrist")}
    raised = _far_arm_raised(side, far)
    gated = TrackerSettings(energy={"hidden_prior_std": 0.5, "hidden_prior_gate": "side",
                                    "hidden_prior_limbs": "arms"})
    shown = TrackerSettings(energy={"hidden_prior_std": 0.5, "hidden_prior_limbs": "arms"})
    with Tracker(body, camera, settings=gated) as tracker:
        for pose in (side, raised):
            assert set(tracker.hidden_joints(_side_view_frame(tracker, pose), pose)) == far_arm
        front = side.copy()
        front[4] = 0.0
        assert tracker.hidden_joints(_side_view_frame(tracker, front), front) == []
        energy = tracker._energy(_side_view_frame(tracker, side), hidden_of=side)
        assert set(energy.hidden_joints) == far_arm and energy.hidden_prior_std == 0.5
    with Tracker(body, camera, settings=shown) as tracker:
        assert not far_arm & set(tracker.hidden_joints(_side_view_frame(tracker, raised), raised))
    with pytest.raises(InputError, match="hidden_prior_gate"):
        TrackerSettings(energy={"hidden_prior_gate": "behind"})
    with pytest.raises(InputError, match="hidden_side_deg"):
        TrackerSettings(energy={"hidden_side_deg": 120.0})


def test_tracking_a_side_view_searches_the_far_arm_under_the_hidden_prior():
    """Wired in: each tracked frame of a side view charges its far arm (``hidden_limbs``
    counts one limb a frame), and the tracked far elbow stays where it hangs; with the
    setting off nothing is counted."""
    from types import SimpleNamespace

    from depthtrack.body.model import BodyModel
    from depthtrack.camera import Camera
    from depthtrack.track.tracker import Tracker, TrackerSettings

    def segment(depth, camera):
        mask = depth > 0
        return SimpleNamespace(mask=mask, points=camera.backproject(depth)[mask], floor_plane=None)

    body = BodyModel.default(1.75)
    camera = Camera.preset("sr4000")
    side = _turned(np.pi / 2)
    for std, counted in ((0.5, 3), (0.0, 0)):
        settings = TrackerSettings(energy={"hidden_prior_std": std})
        with Tracker(body, camera, method="hc", settings=settings, segmenter=segment) as tracker:
            depth = tracker.renderers.depth(side).astype(np.float32)
            tracker.init(depth, pose=side)
            for _ in range(3):
                x = tracker.step(depth)
            assert tracker.counts["hidden_limbs"] == counted
            err = np.linalg.norm(body.joint_positions(x) - body.joint_positions(side), axis=1)
            assert err.max() < 0.1
