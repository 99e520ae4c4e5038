"""tools/free_space_limbs.py --prior: where a Gaussian over the train poses puts a hidden limb."""
import numpy as np
import pytest
from tool_module import load_tool

from depthtrack.body import BodyModel
from depthtrack.contract import JOINT_INDEX


def _tool():
    return load_tool("free_space_limbs")


def test_the_conditional_mean_is_the_closed_form_of_a_two_dimensional_gaussian():
    tool = _tool()
    mean = np.array([1.0, -2.0])
    cov = np.array([[4.0, 1.2], [1.2, 0.9]])
    # E[x0 | x1 = 0] = mu0 + s01 / s11 * (0 - mu1)
    got = tool.conditional_mean(mean, cov, np.array([123.0, 0.0]), [0])
    assert got == pytest.approx([1.0 + 1.2 / 0.9 * 2.0])
    # with nothing learnt between them the rest says nothing
    assert tool.conditional_mean(mean, np.diag([4.0, 0.9]), np.array([5.0, 7.0]), [0]) == pytest.approx([1.0])


def test_a_substitute_moves_only_the_limb_it_names():
    tool = _tool()
    assert list(tool.limb_parameters("l_arm")) == list(range(12, 18))   # l_shoulder, l_elbow
    rng = np.random.default_rng(0)
    train = np.zeros((200, 48))
    train[:, 6:] = rng.normal(0.0, 0.3, (200, 42))
    body = BodyModel.default(height=1.75)
    pose = np.zeros(48)
    pose[6:] = rng.normal(0.0, 0.3, 42)
    conditional, plain = tool.prior_substitutes(*tool.rotation_gaussian(train))(pose, "r_leg")
    changed = np.flatnonzero(np.abs(conditional - pose) > 0)
    assert set(changed) <= set(tool.limb_parameters("r_leg")) and len(changed)
    moved = np.linalg.norm(body.joint_positions(plain) - body.joint_positions(pose), axis=1)
    r_leg = [JOINT_INDEX[n] for n in ("r_knee", "r_ankle")]
    assert moved[r_leg].min() > 0.01
    assert np.delete(moved, r_leg).max() < 1e-9


def test_prior_without_hidden_is_refused(tmp_path, capsys):
    assert _tool().main([str(tmp_path), str(tmp_path), "--prior"]) == 2
    assert "give --hidden" in capsys.readouterr().err
