"""Hill climbing: the block schedule on a closed-form energy, and on rendered depth."""
import numpy as np
import pytest

from depthtrack.motion.prior import pose_velocity
from depthtrack.track.hill_climb import HillClimber, SearchGroup, default_blocks, restrict_blocks


def _quadratic(target, weights):
    def energy(poses):
        d = pose_velocity(target, poses)
        return np.sum(weights * d * d, axis=-1)
    return energy


def test_reaches_the_minimum_of_a_separable_energy_within_the_finest_step():
    rng = np.random.default_rng(5)
    target = np.zeros(48)
    target[2] = 3.0
    start = target.copy()
    start[:3] += [0.08, -0.05, 0.1]
    start[3:] += rng.uniform(-0.25, 0.25, 45)
    calls = []

    def energy(poses):
        calls.append(len(poses))
        return _quadratic(target, np.ones(48))(poses)

    climber = HillClimber(levels=5, max_iterations=20)
    res = climber.climb(start, energy)
    d = np.abs(pose_velocity(target, res.pose))
    finest = {g.name: g.step * 0.5 ** 4 for b in climber.blocks for g in b}
    for block in climber.blocks:
        for g in block:
            assert d[list(g.params)].max() <= finest[g.name] * 1.5, g.name
    assert res.evaluations == sum(calls) and res.calls == len(calls)
    assert res.energy < 1e-2 * energy(start[None])[0]


def test_limbs_of_one_block_move_together():
    # two independent groups in one block: each iteration's improving moves are combined
    target = np.zeros(48)
    start = target.copy()
    start[12] = 0.4
    start[21] = -0.4
    block = [[SearchGroup("l_shoulder", (12, 13, 14), 0.2), SearchGroup("r_shoulder", (21, 22, 23), 0.2)]]
    res = HillClimber(blocks=block, levels=1, max_iterations=2).climb(start, _quadratic(target, np.ones(48)))
    # one step for each shoulder per iteration: 2 iterations of 0.2 reach both targets
    np.testing.assert_allclose(res.pose[[12, 21]], [0.0, 0.0], atol=1e-9)


def test_restrict_blocks_keeps_order():
    blocks = restrict_blocks(default_blocks(), ["l_elbow", "pelvis_t", "l_shoulder"])
    assert [[g.name for g in b] for b in blocks] == [["pelvis_t"], ["l_shoulder"], ["l_elbow"]]


def test_clip_keeps_candidates_inside_joint_limits():
    lower = np.full(48, -np.inf)
    upper = np.full(48, np.inf)
    upper[15] = 0.1                         # the elbow may not pass 0.1
    target = np.zeros(48)
    target[15] = 1.0
    res = HillClimber(levels=3, clip=lambda p: np.clip(p, lower, upper)).climb(
        np.zeros(48), _quadratic(target, np.ones(48)))
    assert res.pose[15] <= 0.1 + 1e-12


@pytest.mark.slow
def test_recovers_a_perturbed_pose_from_rendered_depth():
    from depthtrack.body import BodyModel
    from depthtrack.camera import Camera
    from depthtrack.render import FrameRenderer, TileRenderer
    from depthtrack.track.observation import square_roi

    body = BodyModel.default(1.75)
    camera = Camera.preset("sr4000")
    truth = body.default_pose((0.1, 0.05, 3.2))
    truth[12:15] = [-0.5, 0.0, 0.5]
    truth[15] = -0.7
    truth[30] = -0.4
    truth[33] = 0.6
    depth = FrameRenderer(camera).render(body, truth)
    tiles = TileRenderer(body.with_mesh("decimated"), camera, tile=64)
    observed = np.where(depth > 0, depth, np.inf).astype(np.float32)
    tiles.set_observation(observed, roi=square_roi(depth > 0, 0.15))
    start = truth.copy()
    start[:3] += [0.05, -0.04, 0.06]
    start[3:] += np.random.default_rng(2).uniform(-0.2, 0.2, 45)
    res = HillClimber(clip=body.clip, levels=4).climb(start, lambda p: tiles.costs(p), passes=2)
    err = np.linalg.norm(body.joint_positions(res.pose) - body.joint_positions(truth), axis=1)
    err0 = np.linalg.norm(body.joint_positions(start) - body.joint_positions(truth), axis=1)
    assert err.mean() < 0.04 < err0.mean()
    assert err.max() < 0.10


def _bent_pose(body, seed, spread, root=(0.2, 0.5, -0.1), chest_twist=None):
    """A pose ``(48,)`` turned by ``root`` with every joint bent at random (``spread`` rad),
    the spine's ``ry`` set to ``chest_twist`` when given, within the joint limits."""
    x = np.zeros(48)
    x[3:6] = root
    x[6:] = np.random.default_rng(seed).normal(0.0, spread, 42)
    if chest_twist is not None:
        x[7] = chest_twist
    return body.clip(x[None])[0]


def test_pelvis_alone_turns_only_the_pelvis_and_carries_the_hip_sockets():
    # SearchGroup.isolate: the third set of pelvis moves keeps the chest's and the thighs'
    # world rotations; only the hip sockets (rigid with the pelvis) and what hangs from
    # them move, by a translation
    from depthtrack.body.model import BodyModel
    from depthtrack.body.skeleton import JOINT_ID
    from depthtrack.contract import JOINT_INDEX
    from depthtrack.motion.prior import apply_velocity
    from depthtrack.track.energy import spine_twist

    body = BodyModel.default()
    x = _bent_pose(body, 3, 0.25, root=(0.2, 0.6, -0.1))
    plain = default_blocks(1.0, False)[1][0]
    alone = default_blocks(1.0, False, pelvis_alone=True)[1][0]
    assert plain.isolate == () and alone.isolate == (JOINT_ID["spine"],)
    moves = alone.moves(0.12, x)
    assert len(moves) == len(plain.moves(0.12, x)) + 6
    turned = apply_velocity(x, moves[-6:])
    j0 = np.asarray(body.joint_positions(x))
    j = np.asarray(body.joint_positions(turned))
    # the twist moves (about the pelvis's own vertical, moves 1 and 4) leave the neck and
    # shoulders where they were and change the chest's twist by exactly the step
    for m in (1, 4):
        for name in ("neck", "head", "l_shoulder", "r_shoulder"):
            np.testing.assert_allclose(j[m, JOINT_INDEX[name]], j0[JOINT_INDEX[name]], atol=0.004)
        assert abs(abs(spine_twist(turned[m])[0] - spine_twist(x)[0]) - 0.12) < 0.02
    # a leg moves rigidly with its hip socket: knee minus hip unchanged
    for m in range(6):
        for side in ("l_", "r_"):
            np.testing.assert_allclose(j[m, JOINT_INDEX[side + "knee"]] - j[m, JOINT_INDEX[side + "hip"]],
                                       j0[JOINT_INDEX[side + "knee"]] - j0[JOINT_INDEX[side + "hip"]],
                                       atol=1e-6)


def test_untwist_moves_turn_the_pelvis_back_by_fractions_of_the_chest_twist():
    from depthtrack.body.model import BodyModel
    from depthtrack.contract import JOINT_INDEX
    from depthtrack.motion.prior import apply_velocity
    from depthtrack.track.energy import spine_twist

    body = BodyModel.default()
    x = _bent_pose(body, 0, 0.2, chest_twist=0.7)       # the chest twisted 40 degrees
    group = default_blocks(1.0, False, untwist=(0.5, 1.0))[1][0]
    moves = group.moves(0.12, x)
    assert len(moves) == len(default_blocks(1.0, False)[1][0].moves(0.12, x)) + 2
    turned = apply_velocity(x, moves[-2:])
    np.testing.assert_allclose(spine_twist(turned), [0.5 * spine_twist(x)[0], 0.0], atol=1e-9)
    j0, j = np.asarray(body.joint_positions(x)), np.asarray(body.joint_positions(turned))
    for name in ("head", "neck", "l_shoulder", "r_wrist"):       # the chest and arms stay
        np.testing.assert_allclose(j[:, JOINT_INDEX[name]], np.repeat(j0[None, JOINT_INDEX[name]], 2, 0),
                                   atol=1e-9)
    assert np.linalg.norm(j[1, JOINT_INDEX["l_hip"]] - j0[JOINT_INDEX["l_hip"]]) > 0.03


def test_untwist_moves_bring_back_a_pelvis_left_behind_the_chest():
    # the failure they are for: the person turned 50 degrees, the track's pelvis 46 degrees
    # behind with the chest and legs where they are (the hip sockets off). The plain
    # schedule leaves the twist (34 degrees when written, the hips 5 and 10 cm off); with
    # the untwist moves the hips come back
    from depthtrack.body import BodyModel
    from depthtrack.body.rotations import matrix_to_rotvec, rotation_about, rotvec_to_matrix
    from depthtrack.camera import Camera
    from depthtrack.contract import JOINT_INDEX
    from depthtrack.motion.prior import apply_velocity
    from depthtrack.render import FrameRenderer, TileRenderer
    from depthtrack.track.energy import spine_twist
    from depthtrack.track.hill_climb import SPINE
    from depthtrack.track.observation import square_roi

    body = BodyModel.default(1.75)
    camera = Camera.preset("sr4000")
    truth = body.default_pose((0.1, 0.05, 3.2))
    turned = rotation_about(np.array([0.0, 1.0, 0.0]), 0.9) @ rotvec_to_matrix(truth[3:6])
    truth[3:6] = matrix_to_rotvec(turned[None])[0]
    truth[12:15] = [-0.4, 0.0, 0.4]
    truth[30] = -0.4
    truth[33] = 0.3
    depth = FrameRenderer(camera).render(body, truth)
    tiles = TileRenderer(body.with_mesh("decimated"), camera, tile=64)
    try:
        tiles.set_observation(np.where(depth > 0, depth, np.inf).astype(np.float32),
                              roi=square_roi(depth > 0, 0.15))
        pelvis = default_blocks()[1][0]
        behind = np.zeros((1, 48))
        behind[0, 4] = -0.8                    # the pelvis alone turned back, chest kept
        start = apply_velocity(truth, pelvis.compensated(behind, pelvis.compensate + (SPINE,),
                                                          truth))[0]
        assert np.degrees(spine_twist(start)[0]) > 40
        hips = [JOINT_INDEX["l_hip"], JOINT_INDEX["r_hip"]]
        climber = HillClimber(blocks=default_blocks(1.0, False, untwist=(0.5, 1.0)),
                              clip=body.clip, levels=3)
        res = climber.climb(start, lambda p: tiles.costs(p), passes=2)
        err = np.linalg.norm(body.joint_positions(res.pose) - body.joint_positions(truth), axis=1)
        assert abs(np.degrees(spine_twist(res.pose)[0])) < 12
        assert err[hips].max() < 0.04 and err.mean() < 0.03
    finally:
        tiles.release()
