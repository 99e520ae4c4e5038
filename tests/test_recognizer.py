"""The per-pixel body-part recogniser: part labels, features, the shipped forest on fresh renders."""
import numpy as np
import pytest

from depthtrack.body import BodyModel
from depthtrack.body.rotations import matrix_to_rotvec, rotation_about
from depthtrack.camera import Camera
from depthtrack.contract import JOINT_INDEX
from depthtrack.detect.features import BACKGROUND, depth_features, pair_features, probe_image
from depthtrack.detect.recognizer import (JointProposals, PartForest, joint_proposals,
                                          load_forest, mean_shift, recognize)
from depthtrack.detect.recognizer_parts import BODY_PARTS, PART_ID, mirror_parts
from depthtrack.errors import InputError
from depthtrack.synth.noise import ToFNoise
from depthtrack.synth.part_scenes import render_part_frame

#: Pixel accuracy the shipped forest reaches on the frontal standing frame (measured 0.39),
#: and counting a part's left/right twin as right (0.89); labels at random score 0.06 and 0.11.
FRONTAL_ACCURACY = 0.35
SIDE_FREE_ACCURACY = 0.80


@pytest.fixture(scope="module")
def scene():
    from depthtrack.render import FrameRenderer

    camera = Camera.preset("sr4000")
    renderer = FrameRenderer(camera)
    body = BodyModel.default(1.75)
    yield body, camera, renderer
    renderer.release()


def _frame(scene, rotation=None, noise=True, z=3.3, seed=3):
    body, camera, renderer = scene
    pose = body.default_pose((0.0, 0.0, z))
    pose[body.pose_names.index("l_elbow_rx")] = -0.5      # a little off the rest pose
    pose[body.pose_names.index("r_hip_rx")] = -0.3
    if rotation is not None:
        pose[3:6] = matrix_to_rotvec(rotation)
    noise = ToFNoise.for_camera("sr4000") if noise else None
    return render_part_frame(body, pose, camera, renderer, noise=noise, rng=np.random.default_rng(seed),
                             wall_gap=1.0)


def _centroid_uv(labels, part):
    v, u = np.nonzero(labels == PART_ID[part])
    return np.array([u.mean(), v.mean()]) if len(u) else np.full(2, np.nan)


def test_part_labels_cover_every_part_next_to_its_joint(scene):
    """The renderer's part image: all 18 parts show on a frontal body, each joint part's pixels
    centre near its joint in the image, and the subject's left is on the image's right."""
    body, camera, _ = scene
    f = _frame(scene, noise=False)
    assert set(np.unique(f.labels[f.labels >= 0])) == set(range(len(BODY_PARTS)))
    uv = camera.project(f.joints)
    for part, joint in (("head", "head"), ("l_elbow", "l_elbow"), ("r_knee", "r_knee"), ("l_hand", "l_wrist")):
        assert np.linalg.norm(_centroid_uv(f.labels, part) - uv[JOINT_INDEX[joint]]) < 8.0, part
    assert _centroid_uv(f.labels, "l_hand")[0] > camera.cx > _centroid_uv(f.labels, "r_hand")[0]
    twin = mirror_parts()
    assert twin[PART_ID["l_knee"]] == PART_ID["r_knee"] and twin[PART_ID["head"]] == PART_ID["head"]


def test_features_are_depth_invariant():
    """A probe offset in metres reaches the same body point at 2 m and at 4 m."""
    cam = Camera(width=200, height=200, fx=200.0, fy=200.0, cx=100.0, cy=100.0)
    feats = []
    for z in (2.0, 4.0):
        depth = np.zeros(cam.shape, np.float32)
        half = int(round(0.3 * cam.fx / z))           # a 0.6 m wide square, 0.2 m nearer in its right half
        depth[100 - half:100 + half, 100 - half:100 + half] = z
        depth[100 - half:100 + half, 100:100 + half] = z - 0.2
        mask = depth > 0
        image = probe_image(depth, mask)
        offsets = np.array([[0.15, 0.0, 0.0, 0.0], [0.5, 0.0, 0.0, 0.0], [0.15, 0.0, -0.15, 0.0]], np.float32)
        feats.append(depth_features(image, np.array([[100, 99]]), offsets, cam.fx, cam.fy)[0])
        one = pair_features(image, np.array([100]), np.array([99]), image[100, 99:100], offsets[2:3], cam.fx, cam.fy)
        assert one[0] == pytest.approx(feats[-1][2])
    for f, z in zip(feats, (2.0, 4.0)):
        assert f[0] == pytest.approx(-0.2, abs=1e-5)            # the probe lands on the nearer half
        assert f[1] == pytest.approx(BACKGROUND - z, abs=1e-5)  # off the person
        assert f[2] == pytest.approx(-0.2, abs=1e-5)


def test_mean_shift_finds_two_clusters():
    rng = np.random.default_rng(0)
    a = rng.normal([0, 0, 2], 0.02, (60, 3))
    b = rng.normal([0.5, 0, 2], 0.02, (30, 3))
    modes, support, owner = mean_shift(np.vstack([a, b]), np.ones(90), 0.065)
    assert np.all(owner[:60] == 0) and np.all(owner[60:] == 1)
    assert len(modes) == 2
    assert np.linalg.norm(modes[0] - [0, 0, 2]) < 0.02 and np.linalg.norm(modes[1] - [0.5, 0, 2]) < 0.02
    assert support[0] == pytest.approx(60, abs=1) and support[1] == pytest.approx(30, abs=1)


def test_model_file_round_trip_and_bad_file(tmp_path):
    forest = load_forest()
    path = tmp_path / "r.npz"
    forest.save(path)
    again = PartForest.load(path)
    assert np.array_equal(again.parts.left, forest.parts.left)
    assert np.allclose(again.parts.leaf_values, forest.parts.leaf_values, atol=0.01)
    assert (again.orient is None) == (forest.orient is None)
    assert again.extras == forest.extras and (again.side is None) == (forest.side is None)
    (tmp_path / "bad.npz").write_bytes(b"not a model")
    with pytest.raises(InputError, match="bad.npz"):
        PartForest.load(tmp_path / "bad.npz")


def test_labels_match_the_renderer_on_a_frontal_frame(scene):
    f = _frame(scene)
    labels, probs = recognize(f.depth, f.mask, scene[1])
    assert labels.dtype == np.int8 and probs.shape == f.depth.shape + (len(BODY_PARTS),)
    assert np.all(labels[~f.mask] == -1)
    assert np.allclose(probs[f.mask].sum(1), 1.0, atol=0.02)
    accuracy = np.mean(labels[f.mask] == f.labels[f.mask])
    twin = mirror_parts()
    side_free = np.mean((labels[f.mask] == f.labels[f.mask]) | (twin[labels[f.mask]] == f.labels[f.mask]))
    assert accuracy >= FRONTAL_ACCURACY and side_free >= SIDE_FREE_ACCURACY


def test_proposals_near_the_joints_on_a_clean_render(scene):
    f = _frame(scene, noise=False)
    _, probs = recognize(f.depth, f.mask, scene[1])
    prop = joint_proposals(f.depth, probs, scene[1], k=3)
    assert isinstance(prop, JointProposals) and prop.positions.shape == (15, 3, 3)
    assert np.all(np.diff(prop.confidence, axis=1) <= 0)
    dist = np.nanmin(np.linalg.norm(prop.positions - f.joints[:, None], axis=2), axis=1)
    assert np.sum(dist < 0.10) >= 12, np.round(dist, 3)


def _side_agreement(labels, truth, mask):
    """Of the pixels labelled as a left or right part whose truth is sided: the share on the true side."""
    names = np.array([n[:2] for n in BODY_PARTS])
    sided = mask & (labels >= 0) & (truth >= 0)
    got, want = names[labels[sided]], names[truth[sided]]
    both = np.isin(got, ["l_", "r_"]) & np.isin(want, ["l_", "r_"])
    return np.mean(got[both] == want[both])


@pytest.mark.parametrize("turn", [0.0, np.pi])
def test_both_sides_proposed_front_and_back(scene, turn):
    """Facing the camera or turned away, every left and right joint that shows has a proposal
    of its own within 10 cm (the twins share their modes, see ``merge_sides``)."""
    body, camera, _ = scene
    f = _frame(scene, rotation=rotation_about(np.array([0.0, 1.0, 0.0]), turn), noise=False)
    _, probs = recognize(f.depth, f.mask, camera)
    prop = joint_proposals(f.depth, probs, camera, k=3)
    dist = np.nanmin(np.linalg.norm(prop.positions - f.joints[:, None], axis=2), axis=1)
    for name in ("l_shoulder", "r_shoulder", "l_elbow", "r_elbow", "l_wrist", "r_wrist", "l_knee", "r_knee"):
        assert dist[JOINT_INDEX[name]] < 0.10, (name, np.round(dist, 3))
    # the twins share their modes (all of them when k allows), each ranked by its own side's weight
    every = joint_proposals(f.depth, probs, camera, k=40)
    l, r = every.positions[JOINT_INDEX["l_knee"]], every.positions[JOINT_INDEX["r_knee"]]
    assert np.allclose(np.sort(l[:, 0]), np.sort(r[:, 0]), equal_nan=True)


@pytest.mark.xfail(strict=True, reason="known limitation: the shipped forest tells the subject's left "
                                       "from right no better than chance (README, Body-part recogniser)")
@pytest.mark.parametrize("turn", [0.0, np.pi])
def test_left_and_right_labels_not_swapped_front_and_back(scene, turn):
    f = _frame(scene, rotation=rotation_about(np.array([0.0, 1.0, 0.0]), turn))
    labels, _ = recognize(f.depth, f.mask, scene[1])
    assert _side_agreement(labels, f.labels, f.mask) > 0.8


def test_body_frame_features_side_and_height():
    from depthtrack.detect.features import body_frame_features

    # a body facing the camera (forward -z), head up (-y): its left is +x in the camera frame
    pts = np.array([[0.3, 0.0, 2.0], [-0.3, -0.5, 2.0]])
    out = body_frame_features(pts, np.array([0.0, 0.0, 2.0]), np.array([0, 0, -1.0]), np.array([0, -1.0, 0]))
    assert out.shape == (2, 8)
    assert np.allclose(out[:, 6], [0.3, -0.3]) and np.allclose(out[:, 7], [0.0, 0.5])


def test_centroid_and_side_features():
    """The silhouette-frame inputs: offsets from the person's centre in metres, and each
    pixel's place along the frame's estimated left axis."""
    from depthtrack.detect.features import centroid_features, side_features

    pts = np.array([[0.3, 0.1, 2.0], [-0.3, -0.5, 2.2]])
    off = centroid_features(pts, pts.mean(axis=0))
    assert off.shape == (2, 3) and np.allclose(off, [[0.3, 0.3, -0.1], [-0.3, -0.3, 0.1]])
    side = side_features(off, np.array([0.5, 0.0]))       # left half-confidently along +x
    assert side.shape == (2, 3)
    assert np.allclose(side[:, :2], [[0.5, 0.0], [0.5, 0.0]]) and np.allclose(side[:, 2], [0.15, -0.15])


def test_upside_down_head_found(scene):
    """A handstand-like view (the body rotated 180 degrees about the optical axis): the most
    confident head proposal is at the head (the feet draw some head labels too, measured
    about a third of the weight: the second and third proposals)."""
    body, camera, _ = scene
    f = _frame(scene, rotation=rotation_about(np.array([0.0, 0.0, 1.0]), np.pi))
    labels, probs = recognize(f.depth, f.mask, camera)
    assert (labels == PART_ID["head"]).sum() > 50
    prop = joint_proposals(f.depth, probs, camera)
    head = JOINT_INDEX["head"]
    assert np.linalg.norm(prop.positions[head, 0] - f.joints[head]) < 0.10
