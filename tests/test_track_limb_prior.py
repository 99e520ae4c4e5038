"""The learned limb prior: the mixture against closed forms, the floor's bounds, the mirror,
its place in the energy, and the shipped file against the tool that makes it."""
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import multivariate_normal

from depthtrack.track.energy import pose_prior
from depthtrack.track.limb_prior import (PRIOR_JOINTS, LimbPrior, Mixture, floored_cost,
                                         limb_prior_cost, load_mixtures, mixture_log_density,
                                         prior_path)
from depthtrack.track.reseat import LIMB_SLOTS, MIRROR
from tool_module import load_tool

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data"


def _mixture(dim=6, k=3, seed=0):
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(k, dim, dim))
    cov = a @ np.swapaxes(a, 1, 2) * 0.1 + 0.05 * np.eye(dim)
    w = rng.random(k)
    return Mixture(w / w.sum(), rng.normal(scale=0.5, size=(k, dim)), cov)


def test_mixture_log_density_is_the_weighted_sum_of_its_gaussians():
    m = _mixture()
    x = np.random.default_rng(1).normal(scale=0.7, size=(7, 6))
    expected = np.log(sum(w * multivariate_normal(mu, c).pdf(x)
                          for w, mu, c in zip(m.weights, m.means, m.covariances)))
    np.testing.assert_allclose(mixture_log_density(x, m.weights, m.means,
                                                   np.linalg.cholesky(m.covariances)),
                               expected, rtol=1e-10)
    np.testing.assert_allclose(m.log_density(x[0]), expected[:1], rtol=1e-10)


def test_the_floor_bounds_the_cost_by_the_gaussian_it_replaces():
    """floor 1: the Gaussian's ``0.5 |x|^2 / std^2``; any floor: at most that plus
    ``log(1 / floor)``, and at most the mixture's share alone; near the mixture's mean
    a smaller floor costs less, far from it more."""
    m = _mixture()
    rng = np.random.default_rng(2)
    x = rng.normal(scale=1.5, size=(200, 6))
    gauss = 0.5 * np.sum(x * x, axis=1) / 0.8 ** 2
    np.testing.assert_allclose(floored_cost(x, m, 0.8, 1.0), gauss)
    for floor in (0.5, 0.1, 0.01):
        c = floored_cost(x, m, 0.8, floor)
        assert np.all(c <= gauss + np.log(1 / floor) + 1e-9)
        # and at most the mixture's own share alone: -log((1 - floor) g(x)) + log n(0)
        assert np.all(c <= -np.log(1 - floor) - m.log_density(x)
                      - 0.5 * 6 * np.log(2 * np.pi * 0.8 ** 2) + 1e-9)
    at_mean = m.means[np.argmax(m.weights)][None]
    assert floored_cost(at_mean, m, 0.8, 0.1)[0] < floored_cost(at_mean, m, 0.8, 1.0)[0] - 1
    far = np.full((1, 6), 4.0)
    assert floored_cost(far, m, 0.8, 0.1)[0] == pytest.approx(
        0.5 * 96 / 0.64 + np.log(10), abs=1e-6)                  # the mixture is nil there


def test_a_limb_and_its_mirror_cost_the_same():
    mixtures = {"arm": _mixture(seed=3), "leg": _mixture(seed=4)}
    rng = np.random.default_rng(5)
    pose = rng.normal(scale=0.5, size=(4, 48))
    mirrored = pose.copy()
    for kind in ("arm", "leg"):
        left, right = LIMB_SLOTS[f"l_{kind}"], LIMB_SLOTS[f"r_{kind}"]
        mirrored[:, left] = pose[:, right] * MIRROR
        mirrored[:, right] = pose[:, left] * MIRROR
    np.testing.assert_allclose(limb_prior_cost(pose, mixtures, 1.0, 0.1),
                               limb_prior_cost(mirrored, mixtures, 1.0, 0.1), rtol=1e-12)
    # a weight interpolates between the Gaussian and the learned cost, limb by limb
    gauss = pose_prior(pose, 1.0) - pose_prior(pose, 1.0, dropped_joints=LimbPrior(mixtures, 1.0, 0.1).joints)
    learned = limb_prior_cost(pose, mixtures, 1.0, 0.1)
    np.testing.assert_allclose(limb_prior_cost(pose, mixtures, 1.0, 0.1, 0.0), gauss, rtol=1e-12)
    np.testing.assert_allclose(limb_prior_cost(pose, mixtures, 1.0, 0.1, 0.3),
                               gauss + 0.3 * (learned - gauss), rtol=1e-12)
    # and it is the sum of the four limbs' own costs
    one = sum(floored_cost(pose[:, LIMB_SLOTS[f"{s}_{k}"]] * (MIRROR if s == "r" else 1),
                           mixtures[k], 1.0, 0.1) for s in "lr" for k in ("arm", "leg"))
    np.testing.assert_allclose(limb_prior_cost(pose, mixtures, 1.0, 0.1), one, rtol=1e-12)


def test_in_the_energy_it_replaces_the_gaussian_on_the_limbs_upper_joints():
    """The energy with the learned prior differs from the plain one by the prior's cost less
    the Gaussian on the shoulders, elbows, hips and knees; with floor 1 not at all; the
    tracker builds it from the settings."""
    from depthtrack.body.model import BodyModel
    from depthtrack.camera import Camera
    from depthtrack.render.tiles import TileRenderer
    from depthtrack.track.energy import Energy
    from depthtrack.track.record import Recorder
    from depthtrack.track.settings import TrackerSettings

    camera = Camera.preset("sr4000")
    renderer = TileRenderer(BodyModel.default(), camera, tile=32)
    try:
        observed = np.zeros(camera.shape, np.float32)
        observed[20:120, 60:120] = 2.5
        renderer.set_observation(observed)
        rng = np.random.default_rng(6)
        poses = rng.normal(scale=0.4, size=(3, 48))
        poses[:, :6] = [0, 0, 2.5, 0, 0, 0]
        plain = Energy(renderer, 100.0, True, Recorder(), pose_prior_std=1.0)
        prior = LimbPrior(load_mixtures(), 1.0, 0.1)
        learned = plain.with_limb_prior(prior)
        assert prior.joints == (3, 4, 6, 7, 9, 10, 12, 13)
        gauss_on_limbs = pose_prior(poses, 1.0) - pose_prior(poses, 1.0, dropped_joints=prior.joints)
        np.testing.assert_allclose(learned(poses) - plain(poses), prior.cost(poses) - gauss_on_limbs,
                                   rtol=1e-9, atol=1e-9)
        flat = plain.with_limb_prior(LimbPrior(load_mixtures(), 1.0, 1.0))
        np.testing.assert_allclose(flat(poses), plain(poses), rtol=1e-12)
    finally:
        renderer.release()
    with pytest.raises(ValueError, match="limb_prior"):
        TrackerSettings(energy={"limb_prior": "gmm"})
    with pytest.raises(ValueError, match="limb_prior_floor"):
        TrackerSettings(energy={"limb_prior": "learned", "limb_prior_floor": 0.0})
    with pytest.raises(ValueError, match="pose_prior_std"):
        TrackerSettings(energy={"limb_prior": "learned", "pose_prior_std": 0.0})


def test_the_shipped_prior_prefers_an_arm_hanging_at_the_side_to_one_across_the_chest():
    """What the prior is for (README, the side view's far arm): the train motions hold an
    arm at the side far more often than across the chest, so the learned cost of the hanging
    arm is lower than the crossed one's by more than the Gaussian's difference."""
    from depthtrack.body.skeleton import POSE_INDEX

    hanging, crossed = np.zeros(48), np.zeros(48)
    crossed[POSE_INDEX["l_shoulder_ry"]] = -0.9          # upper arm swung in front of the chest
    crossed[POSE_INDEX["l_shoulder_rz"]] = 0.6
    crossed[POSE_INDEX["l_elbow_ry"]] = -1.2             # forearm across it
    poses = np.stack([hanging, crossed])
    learned = limb_prior_cost(poses, load_mixtures(), 1.0, 0.1)
    gauss = pose_prior(poses, 1.0)
    assert learned[1] - learned[0] > gauss[1] - gauss[0] + 2.0


def test_bad_data_dir_is_refused(tmp_path, capsys):
    out = tmp_path / "prior.npz"
    assert load_tool("make_limb_prior").main(["--data", str(tmp_path), "-o", str(out)]) == 2
    assert "train clips not found" in capsys.readouterr().err
    assert not out.exists()


@pytest.mark.skipif(not (DATA / "cmu-extra").is_dir(), reason="needs ../shared/data")
def test_the_shipped_prior_is_what_the_tool_makes(tmp_path):
    out = tmp_path / "prior.npz"
    assert load_tool("make_limb_prior").main(["--data", str(DATA), "-o", str(out)]) == 0
    made, shipped = np.load(out), np.load(prior_path())
    assert made.files == shipped.files
    for key in made.files:
        if made[key].dtype.kind == "f":
            # EM's sums may round differently on another numpy build
            np.testing.assert_allclose(made[key], shipped[key], rtol=1e-6, atol=1e-9)
        else:
            assert np.array_equal(made[key], shipped[key]), key


def test_a_start_kept_out_of_the_learned_prior_is_the_gaussians_start(squat):
    """With ``limb_prior_start`` False the automatic start and its front/back check score
    with the Gaussian: the same finalists, energies and pose as a tracker without the learned
    prior, though the learned prior scores that pose differently."""
    from conftest import FirstFrames

    from depthtrack.body import BodyModel
    from depthtrack.track.loop import start_overlay
    from depthtrack.track.settings import TrackerSettings
    from depthtrack.track.tracker import Tracker

    frames = FirstFrames(squat, 3)
    depths = [frames.depth(i) for i in range(len(frames))]
    body = BodyModel.default(height=1.75)
    check = {"frames": 2, "min_frames": 2, "retro_frames": 0}
    kept_out = {"energy": {"limb_prior": "learned", "limb_prior_start": False}, "heading": check}
    starts = {}
    for name, changes in (("gaussian", {"heading": check}), ("kept out", kept_out)):
        with Tracker(body, frames.camera, fps=frames.fps,
                     settings=TrackerSettings().updated(changes)) as tracker:
            poses = dict(tracker.stream(depths))
            starts[name] = (tracker.state.init_info, poses[0])
    assert starts["kept out"][0]["finalists"] == starts["gaussian"][0]["finalists"]
    np.testing.assert_array_equal(starts["kept out"][1], starts["gaussian"][1])
    # the learned prior would have scored the start's pose otherwise
    pose = starts["gaussian"][1][None]
    gauss_on_limbs = pose_prior(pose, 1.0) - pose_prior(pose, 1.0, dropped_joints=PRIOR_JOINTS)
    assert abs(limb_prior_cost(pose, load_mixtures(), 1.0, 0.1) - gauss_on_limbs)[0] > 0.1
    assert start_overlay(TrackerSettings().updated(kept_out)) == {"energy": {"limb_prior": "gaussian"}}
    assert start_overlay(TrackerSettings(energy={"limb_prior": "learned"})) == {}
    assert start_overlay(TrackerSettings()) == {}
