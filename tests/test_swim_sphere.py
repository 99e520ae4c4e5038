"""Gap prediction on the sphere of segment directions (depthtrack.swim.sphere): the Jacobian and the velocity
round trip, a pass near the pole predicted exactly where the angle model spins the azimuth wrongly, agreement
with the angle model away from the poles, and an online roll-out that uses only the state before the gap."""
import numpy as np

from depthtrack.motion.cyclic import CyclicMotionModel
from depthtrack.swim.sphere import (angles_from_directions, direction_jacobian, gap_predictions, rollout,
                                    sphere_transition, to_angular_velocity, to_direction_velocity)
from depthtrack.swim.stickfigure import angle_error_sq, directions, nearest_equivalent
from depthtrack.swim.tracking import decaying_transition

A, L = 26, 100


def _angles(rng, n):
    a = rng.uniform(-np.pi, np.pi, (n, A))
    a[:, 0::2] = rng.uniform(0.2, np.pi - 0.2, (n, 13))
    return a


def test_jacobian_matches_finite_differences_and_velocities_round_trip():
    rng = np.random.default_rng(0)
    ang, om = _angles(rng, 5), 0.03 * rng.standard_normal((5, A))
    J = direction_jacobian(ang)
    h = 1e-6
    for j in range(2):
        e = np.zeros(A)
        e[j::2] = h
        fd = (directions(ang + e) - directions(ang - e)) / (2 * h)
        np.testing.assert_allclose(J[..., j], fd, atol=1e-8)
    w = to_direction_velocity(ang, om)
    np.testing.assert_allclose(np.sum(w * directions(ang), axis=-1), 0, atol=1e-12)    # tangent
    np.testing.assert_allclose(to_angular_velocity(ang, w), om, atol=1e-10)
    np.testing.assert_allclose(angle_error_sq(angles_from_directions(directions(ang)), ang), 0, atol=1e-20)


def _static_model():
    """No learned motion (zero velocity and acceleration tables): both models then coast on the state."""
    mean = np.tile(np.where(np.arange(A) % 2 == 0, 1.2, 0.3), (L, 1))
    return CyclicMotionModel(mean, np.zeros((L, A)), np.zeros((2, L, A)))


def test_a_pass_near_the_pole_is_predicted_on_the_great_circle():
    """Closed form: a segment moving at constant angular speed w on the great circle whose closest approach to
    the pole is d = 0.05 rad. Its azimuth turns by pi within about 2 d / w = 3 frames. From the exact state
    five frames before the pass, the sphere model stays on the great circle (error below 1e-4 rad^2 per
    frame), the angle model keeps the azimuth rate and misses the turn (error above 0.5 rad^2 per frame)."""
    model = _static_model()
    d, w, n = 0.05, 0.03, 10
    p, q = np.array([np.sin(d), np.cos(d), 0.0]), np.array([0.0, 0.0, 1.0])
    t = np.arange(-5, n - 4)
    u = np.cos(w * t)[:, None] * p + np.sin(w * t)[:, None] * q            # (n + 1, 3), t = -5 .. n - 5
    dirs = np.tile(directions(model.mean_angles[0]), (n + 1, 1, 1))
    dirs[:, 4] = u                                                          # segment 4 makes the pass
    truth = angles_from_directions(dirs)
    for k in range(1, n + 1):                                               # continuous through the pole
        truth[k] = nearest_equivalent(truth[k], truth[k - 1])
    wdir = np.zeros((13, 3))
    wdir[4] = w * (-np.sin(w * t[0]) * p + np.cos(w * t[0]) * q)
    x0 = np.concatenate([truth[0], to_angular_velocity(truth[0], wdir), [0.0, 1.0 / L]])
    sphere = rollout(sphere_transition(model, 1.0), x0[None], n)[:, 0, :A]
    angle = rollout(decaying_transition(model, 1.0), x0[None], n)[:, 0, :A]
    err_sphere = angle_error_sq(sphere, truth[1:]).sum(-1)
    err_angle = angle_error_sq(angle, truth[1:]).sum(-1)
    assert np.degrees(np.abs(truth[:, 8]).min()) < 3.0                     # it does pass near the pole
    assert err_sphere.mean() < 1e-4
    assert err_angle.mean() > 0.5


def _cycle_model():
    """A smooth stroke away from the poles (thetas in (0.6, 2.4))."""
    s = np.arange(L) / L

    def pose(c, k):
        base = np.where(np.arange(A) % 2 == 0, 1.5, 0.3)
        return base + 0.25 * np.sin(2 * np.pi * c[:, None] + 0.3 * np.arange(A) + 0.05 * k)

    cycles = np.stack([pose(s, k) for k in range(3)])
    vel = np.gradient(cycles, axis=1)
    acc = np.gradient(vel, axis=1)
    return CyclicMotionModel(cycles.mean(0), vel.mean(0), acc), pose


def test_away_from_the_poles_the_sphere_model_follows_the_angle_model():
    model, pose = _cycle_model()
    c, v = 0.3, 1.0 / 90
    x = np.concatenate([pose(np.array([c]), 1)[0], 0.004 * np.ones(A), [c, v]])
    for rho in (0.77, 1.0):
        s = rollout(sphere_transition(model, rho), x[None], 20)[:, 0]
        a = rollout(decaying_transition(model, rho), x[None], 20)[:, 0]
        moved = np.abs(a[-1, :A] - x[:A]).max()
        assert moved > 0.1
        # the same model in other coordinates: a coordinate-straight step and a step along the sphere differ
        # at second order (the curvature of the coordinate lines): nothing after one frame, a few percent
        # of the motion after 20
        assert np.abs(s[0, :A] - a[0, :A]).max() < 1e-4
        assert np.abs(s[:, :A] - a[:, :A]).max() < 0.06 * moved
        np.testing.assert_allclose(s[:, 2 * A:], a[:, 2 * A:])


def test_gap_predictions_use_only_the_state_before_each_gap():
    model, pose = _cycle_model()
    T = 60
    c = (0.1 + np.arange(T + 1) / 90) % 1.0
    states = np.concatenate([pose(c, 1), 0.004 * np.ones((T + 1, A)), c[:, None], np.full((T + 1, 1), 1 / 90)], 1)
    est = states[1:, :A] + 0.01
    mask = np.zeros(T + 1, bool)
    mask[[10, 11, 12, 40, 41]] = True
    out = gap_predictions(sphere_transition(model, 0.8), states, mask, est)
    np.testing.assert_array_equal(out[~mask[1:]], est[~mask[1:]])
    expected = rollout(sphere_transition(model, 0.8), states[[9, 39]], 3)
    np.testing.assert_allclose(out[9:12], expected[:, 0, :A])
    np.testing.assert_allclose(out[39:41], expected[:2, 1, :A])
    # online: what the filter held at and after the gap's frames changes nothing inside it
    later = states.copy()
    later[10:13] += 0.3
    later[40:] -= 0.2
    np.testing.assert_array_equal(gap_predictions(sphere_transition(model, 0.8), later, mask, est)[mask[1:]],
                                  out[mask[1:]])

