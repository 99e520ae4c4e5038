"""Predicting through gaps on the sphere of segment directions, where a pass near the pole is a straight line.

The filters' motion model (:func:`depthtrack.swim.tracking.decaying_transition`)
moves the angles ``(theta, phi)`` of each segment. Near the pole (``theta``
small: in back stroke the upper arm pointing straight up) the azimuth ``phi``
of a segment that passes the pole at a small distance ``d`` turns by about pi
within the few frames it takes to travel ``2 d``, while the segment's direction
itself moves along a nearly straight line. Extrapolated in angles, such a pass
keeps ``phi`` (and takes ``theta`` through zero, a pass exactly over the pole),
so ``phi`` is wrong by up to pi for those frames; on the later part of 126_01
one such pass of the left upper arm held a third of the tuned UKF's error in
10-frame gaps (README, "Why 10-frame gaps are hard").

Here the same model (velocity decay ``rho``, pull towards the mean stroke's
velocity, the mean stroke's acceleration) is integrated on the unit sphere of
each segment's direction ``u = directions(angles)``, the representation in
which rigid-segment motion has no coordinate singularity (the usual remedy for
the singularity of spherical coordinates in orientation tracking, e.g.
Grassia 1998, "Practical parameterization of rotations using the exponential
map", J. Graphics Tools 3(3)):

* state: ``u`` (13, 3) unit directions and ``w = J(theta, phi) omega``, their
  velocities (tangent to the sphere), with ``J`` the Jacobian of ``u`` with
  respect to ``(theta, phi)`` (:func:`direction_jacobian`);
* learned tables in 3-D: ``V(c) = J(m(c)) d(c)`` and
  ``Acc(c) = J(m(c)) a(c) + (dJ/dc)(c) d(c)`` (product rule; ``m, d, a`` the
  mean stroke's pose, velocity and acceleration per reference sample), which
  are free of the branch question of :func:`zenith_sign` (``J`` at the mean
  pose maps the tables from the mean pose's own representation);
* one frame: ``w_rho = rho w + (1 - rho) V(c) v L``,
  ``u' = normalise(u + w_rho + Acc(c) (v L)^2 / 2)``,
  ``w' = w_rho + Acc(c) (v L)^2`` projected onto the tangent plane at ``u'``,
  ``c' = c + v`` — the angle model's step with the sphere's geometry.

:func:`sphere_transition` maps angle states ``[angles, velocities, c, v]`` to
the sphere and back each frame (the round trip is exact away from ``theta = 0``),
so it is a drop-in batched transition. :func:`gap_predictions` replaces a
filter's estimates inside withheld stretches by the deterministic roll-out of
its posterior mean at the last measured frame (online: nothing after the gap's
start is used).
"""
from __future__ import annotations

import numpy as np

from ..motion.cyclic import CyclicMotionModel
from .gaps import gap_runs
from .stickfigure import directions, nearest_equivalent

N_SEGMENTS = 13


def direction_jacobian(angles):
    """``angles (..., 26)`` -> ``(..., 13, 3, 2)``: columns ``du/dtheta`` (unit length) and ``du/dphi``
    (length ``|sin theta|``) of :func:`depthtrack.swim.stickfigure.directions`."""
    a = np.asarray(angles, dtype=float)
    a = a.reshape(a.shape[:-1] + (N_SEGMENTS, 2))
    th, ph = a[..., 0], a[..., 1]
    ct, st, cp, sp = np.cos(th), np.sin(th), np.cos(ph), np.sin(ph)
    d_theta = np.stack([ct * sp, -st, ct * cp], axis=-1)
    d_phi = np.stack([st * cp, np.zeros_like(th), -st * sp], axis=-1)
    return np.stack([d_theta, d_phi], axis=-1)


def angles_from_directions(u):
    """``u (..., 13, 3)`` (any length) -> ``(..., 26)`` angles, the inverse of ``directions`` (theta in
    [0, pi], phi in (-pi, pi], as :func:`depthtrack.swim.stickfigure.joints_to_angles`)."""
    u = np.asarray(u, dtype=float)
    theta = np.arctan2(np.hypot(u[..., 0], u[..., 2]), u[..., 1])
    phi = np.arctan2(u[..., 0], u[..., 2])
    return np.stack([theta, phi], axis=-1).reshape(u.shape[:-2] + (2 * N_SEGMENTS,))


def to_direction_velocity(angles, omega):
    """``w = J omega``: angular velocities ``omega (..., 26)`` at ``angles (..., 26)`` -> ``(..., 13, 3)``."""
    o = np.asarray(omega, dtype=float)
    o = o.reshape(o.shape[:-1] + (N_SEGMENTS, 2))
    return np.einsum("...ij,...j->...i", direction_jacobian(angles), o)


def to_angular_velocity(angles, w, eps: float = 1e-9):
    """Inverse of :func:`to_direction_velocity` for tangent ``w (..., 13, 3)``: ``theta' = w . e_theta``,
    ``phi' = w . e_phi / sin^2 theta`` -> ``(..., 26)``. At the pole itself (``sin^2 theta < eps``)
    the azimuth rate is undefined and set to 0."""
    J = direction_jacobian(angles)
    dth = np.einsum("...i,...i->...", w, J[..., 0])
    s2 = np.sin(np.asarray(angles, dtype=float)[..., 0::2]) ** 2
    dph = np.where(s2 > eps, np.einsum("...i,...i->...", w, J[..., 1]) / np.maximum(s2, eps), 0.0)
    return np.stack([dth, dph], axis=-1).reshape(dth.shape[:-1] + (2 * N_SEGMENTS,))


def sphere_tables(model: CyclicMotionModel):
    """The mean stroke's velocity and acceleration in direction space (module docstring).

    Returns
    -------
    V : (L, 39) float
        ``J(m) d`` per reference sample, flattened ``(13, 3)``.
    Acc : (L, 39) float
        ``J(m) a + (dJ/dc) d`` per reference sample^2 (``dJ/dc`` by periodic central differences).
    """
    L = model.length
    J = direction_jacobian(model.mean_angles)                      # (L, 13, 3, 2)
    d = model.mean_velocities.reshape(L, N_SEGMENTS, 2)
    a = model.mean_acceleration.reshape(L, N_SEGMENTS, 2)
    dJ = 0.5 * (np.roll(J, -1, axis=0) - np.roll(J, 1, axis=0))
    V = np.einsum("lsij,lsj->lsi", J, d)
    Acc = np.einsum("lsij,lsj->lsi", J, a) + np.einsum("lsij,lsj->lsi", dJ, d)
    return V.reshape(L, -1), Acc.reshape(L, -1)


def sphere_transition(model: CyclicMotionModel, rho: float):
    """One frame of the decaying model on the sphere, for angle states ``x (K, 2A + 2)`` -> ``(K, 2A + 2)``.

    The same signature as :func:`depthtrack.swim.tracking.decaying_transition`; the new
    angles are the representation nearest the old ones (continuous through the pole).
    """
    A, L = model.n_angles, model.length
    V, Acc = sphere_tables(model)

    def fx(x):
        x = np.array(np.atleast_2d(x), dtype=float)
        K = len(x)
        ang, om, c, v = x[:, :A], x[:, A:2 * A], x[:, 2 * A], x[:, 2 * A + 1]
        u = directions(ang)
        w = to_direction_velocity(ang, om)
        r = (v * L)[:, None, None]
        vel = model.interpolated_rows(V, c).reshape(K, N_SEGMENTS, 3) * r
        acc = model.interpolated_rows(Acc, c).reshape(K, N_SEGMENTS, 3) * r ** 2
        drift = rho * w + (1 - rho) * vel
        u = u + drift + 0.5 * acc
        u /= np.linalg.norm(u, axis=-1, keepdims=True)
        w = drift + acc
        w -= np.sum(w * u, axis=-1, keepdims=True) * u               # tangent at the new direction
        new = nearest_equivalent(angles_from_directions(u), ang)
        x[:, :A] = new
        x[:, A:2 * A] = to_angular_velocity(new, w)
        x[:, 2 * A] = c + v
        return x

    return fx


def rollout(fx, x0, steps: int):
    """Deterministic predictions ``fx`` applied ``steps`` times to ``x0 (B, D)`` -> ``(steps, B, D)``."""
    x = np.array(np.atleast_2d(x0), dtype=float)
    out = np.empty((steps,) + x.shape)
    for k in range(steps):
        x = fx(x)
        out[k] = x
    return out


def gap_predictions(fx, states, mask, estimates):
    """A filter's estimates with each withheld stretch replaced by the roll-out of its state at the
    last measured frame before it (all stretches rolled out together).

    Parameters
    ----------
    fx : callable
        Batched transition (:func:`sphere_transition`).
    states : (T + 1, D) float
        The filter's posterior mean state ``[angles, velocities, c, v]`` of frames 0 .. T.
    mask : (T + 1,) bool
        Withheld frames (frame 0 never is).
    estimates : (T, A) float
        The filter's angle estimates of frames 1 .. T.

    Returns
    -------
    (T, A) float: ``estimates`` outside the stretches, the roll-out inside.
    """
    out = np.array(estimates, dtype=float)
    runs = gap_runs(mask)
    if not runs:
        return out
    A = out.shape[1]
    starts = np.array([states[a - 1] for a, _ in runs])
    pred = rollout(fx, starts, max(b - a for a, b in runs))
    for i, (a, b) in enumerate(runs):
        out[a - 1:b - 1] = pred[:b - a, i, :A]
    return out
