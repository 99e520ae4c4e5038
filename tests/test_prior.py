"""The temporal prior: relative velocities, fps scaling, and the shipped mocap statistics."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from depthtrack.body.rotations import rotvec_to_matrix
from depthtrack.motion.prior import (ConstantVelocityPrior, accelerations_of, apply_velocity,
                                     pose_velocity)

REPO = Path(__file__).resolve().parents[1]


def _random_poses(rng, n):
    poses = rng.normal(scale=0.6, size=(n, 48))
    poses[:, :3] = rng.normal(size=(n, 3))
    return poses


def test_velocity_round_trip_and_local_frame():
    rng = np.random.default_rng(1)
    a, b = _random_poses(rng, 50), _random_poses(rng, 50)
    v = pose_velocity(a, b)
    back = apply_velocity(a, v)
    Ra = rotvec_to_matrix(back[:, 3:].reshape(50, 15, 3))
    Rb = rotvec_to_matrix(b[:, 3:].reshape(50, 15, 3))
    np.testing.assert_allclose(Ra, Rb, atol=1e-10)
    np.testing.assert_allclose(back[:, :3], b[:, :3], atol=1e-12)
    # relative: R(x_t) = R(x_{t-1}) R(v), the velocity is in the joint's own frame
    Rv = rotvec_to_matrix(v[:, 3:].reshape(50, 15, 3))
    np.testing.assert_allclose(rotvec_to_matrix(a[:, 3:].reshape(50, 15, 3)) @ Rv, Rb, atol=1e-10)


def test_constant_angular_acceleration_is_measured_exactly():
    # theta(t) = 0.5 alpha t^2 about a fixed axis: (v_t - v_{t-1}) fps^2 == alpha for every t
    fps, alpha = 30.0, 12.0
    t = np.arange(20) / fps
    axis = np.array([0.0, 0.6, 0.8])
    poses = np.zeros((20, 48))
    poses[:, 3 + 3 * 4: 6 + 3 * 4] = (0.5 * alpha * t ** 2)[:, None] * axis
    poses[:, 0] = 0.5 * 2.0 * t ** 2            # 2 m/s^2 along x
    acc = accelerations_of(poses, fps)
    np.testing.assert_allclose(acc[:, 15:18], np.tile(alpha * axis, (18, 1)), atol=1e-7)
    np.testing.assert_allclose(acc[:, 0], 2.0, atol=1e-9)
    assert np.abs(np.delete(acc, [0, 15, 16, 17], axis=1)).max() < 1e-9


def test_sigma_scales_with_dt_squared():
    std = np.linspace(1.0, 48.0, 48)
    p25 = ConstantVelocityPrior(std, fps=25.0)
    p50 = ConstantVelocityPrior(std, fps=50.0)
    np.testing.assert_allclose(p25.velocity_std, std / 625.0)
    np.testing.assert_allclose(p50.velocity_std * 4.0, p25.velocity_std)
    np.testing.assert_allclose(np.diag(p25.covariance), (std / 625.0) ** 2)


def test_prediction_and_penalty():
    prior = ConstantVelocityPrior(np.full(48, 25.0), fps=25.0, damping=0.5)  # sigma = 0.04 / frame
    x_prev = np.zeros(48)
    x_prev[2] = 3.0
    v_prev = np.zeros(48)
    v_prev[0] = 0.02
    v_prev[15] = 0.2
    x_pred, v_pred = prior.predict(x_prev, v_prev)
    assert x_pred[0] == pytest.approx(0.01) and x_pred[15] == pytest.approx(0.1)
    assert prior.penalty(x_pred, x_prev, v_pred) == pytest.approx(0.0, abs=1e-18)
    moved = x_pred.copy()
    moved[0] += 0.08                              # two sigmas away: penalty 0.5 * 2^2
    assert prior.penalty(moved[None], x_prev, v_pred)[0] == pytest.approx(2.0)


def test_huber_penalty_is_quadratic_inside_and_linear_beyond():
    """Huber's loss against its closed form: the Gaussian's penalty up to k standard
    deviations, a straight line of slope k beyond, so a 10-sigma change of velocity costs
    25.5 instead of 50 at k = 3; k = 0 is the Gaussian prior exactly."""
    from depthtrack.motion.prior import huber_penalty
    assert huber_penalty(np.array([[0.0, 1.0, -3.0, 10.0]]), 3.0)[0] == pytest.approx(
        0.0 + 0.5 + 4.5 + (30.0 - 4.5))
    gaussian = ConstantVelocityPrior(np.full(48, 25.0), fps=25.0, damping=0.5)   # sigma 0.04
    robust = ConstantVelocityPrior(np.full(48, 25.0), fps=25.0, damping=0.5, huber=3.0)
    x_prev, v_prev = np.zeros(48), np.zeros(48)
    x_pred, v_pred = robust.predict(x_prev, v_prev)
    near, far = x_pred.copy(), x_pred.copy()
    near[0] += 0.08                               # 2 sigmas: inside, both 2.0
    far[0] += 0.4                                 # 10 sigmas: 50 against 25.5
    assert robust.penalty(near[None], x_prev, v_pred)[0] == pytest.approx(2.0)
    assert gaussian.penalty(far[None], x_prev, v_pred)[0] == pytest.approx(50.0)
    assert robust.penalty(far[None], x_prev, v_pred)[0] == pytest.approx(25.5)
    assert robust.to_dict()["huber"] == 3.0 and "huber" not in gaussian.to_dict()


def test_prior_huber_setting_layers_and_is_checked():
    from depthtrack.errors import InputError
    from depthtrack.track.settings import EnergySettings, TrackerSettings
    assert EnergySettings().prior_huber == 3.0                   # the default since 2026-11-30
    assert TrackerSettings().updated({"energy": {"prior_huber": 0.0}}).energy.prior_huber == 0.0
    assert TrackerSettings().updated({"energy": {"prior_huber": 3.0}}).energy.prior_huber == 3.0
    with pytest.raises(InputError, match="prior_huber"):
        EnergySettings(prior_huber=-1.0)


def test_shipped_prior_loads():
    prior = ConstantVelocityPrior.load(fps=25.0)
    assert prior.accel_std.shape == (48,) and np.all(prior.accel_std > 0)
    # limbs accelerate faster than the pelvis translates (rad/s^2 vs m/s^2 at body scale)
    assert prior.accel_std[3 + 3 * 4] > prior.accel_std[0]


def test_shipped_prior_is_what_the_tool_computes(shared_data, tmp_path):
    out = tmp_path / "prior.json"
    shipped = json.loads((REPO / "depthtrack" / "data" / "motion_prior.json").read_text())
    # the clips the shipped prior was made from, by name: shared/data grows (held-out clips
    # must never leak into the prior), so the tool is handed exactly those files
    inputs = [str(next(shared_data.rglob(c["file"]))) for c in shipped["clips"]]
    subprocess.run([sys.executable, str(REPO / "tools" / "make_motion_prior.py"), *inputs,
                    "-o", str(out)], check=True, capture_output=True)
    made = json.loads(out.read_text())
    names = shipped["pose_names"]
    # 1 % absorbs small changes of the default body's proportions (they scale the pelvis path)
    np.testing.assert_allclose([made["accel_std"][n] for n in names],
                               [shipped["accel_std"][n] for n in names], rtol=0.01)
    assert [c["file"] for c in made["clips"]] == [c["file"] for c in shipped["clips"]]
