"""Batched 3D rotation helpers on rotation vectors, matrices and quaternions.

Every function takes arrays with any leading batch shape ``(...)``.
A rotation vector ``r (..., 3)`` is axis * angle (radians, right-handed).
Quaternions are scalar-last ``(x, y, z, w)``, like scipy.

These are the one place in depthtrack where rotations are converted; other
modules import them rather than re-deriving Rodrigues' formula. The module sits in the
package's bottom layer (it imports only numpy), so every package may use it;
``depthtrack.body.rotations`` re-exports it. Euler angles (BVH channels) are here too:
:func:`axis_rotations` and :func:`matrix_to_euler`.
"""
from __future__ import annotations

import numpy as np

__all__ = ["skew", "rotvec_to_matrix", "rotvec_to_quat", "quat_to_rotvec", "matrix_to_quat",
           "quat_to_matrix", "matrix_to_rotvec", "quat_multiply", "compose_rotvec", "invert_rotvec",
           "slerp_quat", "slerp", "rotation_about", "axis_rotations", "matrix_to_euler"]

# Below this angle the Taylor series of sin(t)/t and (1-cos t)/t^2 are exact
# to double precision, and the closed forms would lose digits to cancellation.
_SMALL_ANGLE = 1e-4


def _sinc_terms(theta):
    """Return ``sin(t)/t`` and ``(1 - cos t)/t^2`` for ``theta (...)``, stable at 0."""
    small = theta < _SMALL_ANGLE
    t = np.where(small, 1.0, theta)
    t2 = theta * theta
    a = np.where(small, 1.0 - t2 / 6.0, np.sin(t) / t)
    b = np.where(small, 0.5 - t2 / 24.0, (1.0 - np.cos(t)) / (t * t))
    return a, b


def skew(v):
    """Cross-product matrices: ``v (..., 3) -> (..., 3, 3)`` with ``skew(v) @ u = v x u``."""
    v = np.asarray(v, dtype=np.float64)
    z = np.zeros(v.shape[:-1])
    x, y, w = v[..., 0], v[..., 1], v[..., 2]
    return np.stack([
        np.stack([z, -w, y], -1),
        np.stack([w, z, -x], -1),
        np.stack([-y, x, z], -1),
    ], -2)


def rotvec_to_matrix(rotvec):
    """Rodrigues' formula: ``rotvec (..., 3) -> (..., 3, 3)`` float64 rotation matrices.

    Stable for angles near 0 (Taylor series) and exact up to and beyond pi.
    """
    r = np.asarray(rotvec, dtype=np.float64)
    x, y, z = r[..., 0], r[..., 1], r[..., 2]
    xx, yy, zz = x * x, y * y, z * z
    a, b = _sinc_terms(np.sqrt(xx + yy + zz))
    # I + a K + b K^2 with K = skew(r), written out entry by entry (K^2 = r r^T - |r|^2 I):
    # the same sums as the matrix form, without its temporaries
    ax, ay, az = a * x, a * y, a * z
    bxy, bxz, byz = b * (x * y), b * (x * z), b * (y * z)
    out = np.empty(r.shape[:-1] + (3, 3))
    out[..., 0, 0] = 1.0 - b * (zz + yy)
    out[..., 0, 1] = bxy - az
    out[..., 0, 2] = bxz + ay
    out[..., 1, 0] = bxy + az
    out[..., 1, 1] = 1.0 - b * (zz + xx)
    out[..., 1, 2] = byz - ax
    out[..., 2, 0] = bxz - ay
    out[..., 2, 1] = byz + ax
    out[..., 2, 2] = 1.0 - b * (yy + xx)
    return out


def rotvec_to_quat(rotvec):
    """``rotvec (..., 3) -> (..., 4)`` unit quaternions ``(x, y, z, w)``, ``w >= 0`` for angles <= pi."""
    r = np.asarray(rotvec, dtype=np.float64)
    theta = np.linalg.norm(r, axis=-1)
    small = theta < _SMALL_ANGLE
    t = np.where(small, 1.0, theta)
    # sin(t/2)/t, with its Taylor series near 0
    s = np.where(small, 0.5 - theta * theta / 48.0, np.sin(0.5 * t) / t)
    return np.concatenate([r * s[..., None], np.cos(0.5 * theta)[..., None]], axis=-1)


def quat_to_rotvec(quat):
    """``quat (..., 4)`` (x, y, z, w; need not be unit) ``-> (..., 3)`` rotation vectors, angle in [0, pi]."""
    q = np.asarray(quat, dtype=np.float64)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    q = np.where(q[..., 3:4] < 0, -q, q)  # the shorter of the two equivalent rotations
    v = q[..., :3]
    s = np.linalg.norm(v, axis=-1)
    w = q[..., 3]
    angle = 2.0 * np.arctan2(s, w)  # accurate at both 0 and pi, unlike arccos(w)
    small = s < 1e-12
    scale = np.where(small, 2.0 / np.where(w == 0, 1.0, w), angle / np.where(small, 1.0, s))
    return v * scale[..., None]


def matrix_to_quat(matrix):
    """``matrix (..., 3, 3) -> (..., 4)`` quaternions (x, y, z, w), w >= 0.

    Uses the largest-diagonal branch (Shepperd's method), so it is stable near pi.
    """
    m = np.asarray(matrix, dtype=np.float64)
    shape = m.shape[:-2]
    m = m.reshape(-1, 3, 3)
    tr = m[:, 0, 0] + m[:, 1, 1] + m[:, 2, 2]
    # candidates 4*q_i^2 for i = x, y, z, w; pick the largest per matrix
    cand = np.stack([1 + 2 * m[:, 0, 0] - tr, 1 + 2 * m[:, 1, 1] - tr,
                     1 + 2 * m[:, 2, 2] - tr, 1 + tr], axis=-1)
    best = np.argmax(cand, axis=-1)
    q = np.empty((m.shape[0], 4))
    # w largest
    sel = best == 3
    s = np.sqrt(np.maximum(cand[sel, 3], 1e-300)) * 2
    q[sel] = np.stack([(m[sel, 2, 1] - m[sel, 1, 2]) / s, (m[sel, 0, 2] - m[sel, 2, 0]) / s,
                       (m[sel, 1, 0] - m[sel, 0, 1]) / s, 0.25 * s], -1)
    sel = best == 0
    s = np.sqrt(np.maximum(cand[sel, 0], 1e-300)) * 2
    q[sel] = np.stack([0.25 * s, (m[sel, 0, 1] + m[sel, 1, 0]) / s,
                       (m[sel, 0, 2] + m[sel, 2, 0]) / s, (m[sel, 2, 1] - m[sel, 1, 2]) / s], -1)
    sel = best == 1
    s = np.sqrt(np.maximum(cand[sel, 1], 1e-300)) * 2
    q[sel] = np.stack([(m[sel, 0, 1] + m[sel, 1, 0]) / s, 0.25 * s,
                       (m[sel, 1, 2] + m[sel, 2, 1]) / s, (m[sel, 0, 2] - m[sel, 2, 0]) / s], -1)
    sel = best == 2
    s = np.sqrt(np.maximum(cand[sel, 2], 1e-300)) * 2
    q[sel] = np.stack([(m[sel, 0, 2] + m[sel, 2, 0]) / s, (m[sel, 1, 2] + m[sel, 2, 1]) / s,
                       0.25 * s, (m[sel, 1, 0] - m[sel, 0, 1]) / s], -1)
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    q = np.where(q[:, 3:4] < 0, -q, q)
    return q.reshape(shape + (4,))


def quat_to_matrix(quat):
    """``quat (..., 4)`` (x, y, z, w) ``-> (..., 3, 3)`` rotation matrices."""
    q = np.asarray(quat, dtype=np.float64)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
        np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
        np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
    ], -2)


def matrix_to_rotvec(matrix):
    """``matrix (..., 3, 3) -> (..., 3)`` rotation vectors with angle in [0, pi]; stable near 0 and pi."""
    return quat_to_rotvec(matrix_to_quat(matrix))


def quat_multiply(a, b):
    """Hamilton product ``a * b`` of quaternions ``(..., 4)`` (x, y, z, w): rotation b first, then a."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    ax, ay, az, aw = a[..., 0], a[..., 1], a[..., 2], a[..., 3]
    bx, by, bz, bw = b[..., 0], b[..., 1], b[..., 2], b[..., 3]
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = aw * bx + ax * bw + ay * bz - az * by
    out[..., 1] = aw * by - ax * bz + ay * bw + az * bx
    out[..., 2] = aw * bz + ax * by - ay * bx + az * bw
    out[..., 3] = aw * bw - ax * bx - ay * by - az * bz
    return out


def compose_rotvec(a, b):
    """Rotation vector of ``R(a) @ R(b)`` (apply b first, then a): ``(..., 3), (..., 3) -> (..., 3)``."""
    return quat_to_rotvec(quat_multiply(rotvec_to_quat(a), rotvec_to_quat(b)))


def invert_rotvec(r):
    """Rotation vector of the inverse rotation: ``(..., 3) -> (..., 3)``."""
    return -np.asarray(r, dtype=np.float64)


def slerp_quat(q0, q1, t):
    """Spherical linear interpolation of unit quaternions along the shorter arc.

    Parameters
    ----------
    q0, q1 : (..., 4) float
        Quaternions (x, y, z, w) at ``t = 0`` and ``t = 1``.
    t : float or (...) float
        Interpolation parameter, broadcast against the batch shape.

    Returns
    -------
    (..., 4) float unit quaternions.
    """
    q0 = np.asarray(q0, dtype=np.float64)
    q1 = np.asarray(q1, dtype=np.float64)
    q0 = q0 / np.linalg.norm(q0, axis=-1, keepdims=True)
    q1 = q1 / np.linalg.norm(q1, axis=-1, keepdims=True)
    t = np.asarray(t, dtype=np.float64)[..., None]
    dot = np.sum(q0 * q1, axis=-1, keepdims=True)
    q1 = np.where(dot < 0, -q1, q1)
    dot = np.abs(dot)
    omega = np.arccos(np.clip(dot, -1.0, 1.0))
    near = dot > 1.0 - 1e-10
    so = np.where(near, 1.0, np.sin(omega))
    w0 = np.where(near, 1.0 - t, np.sin((1.0 - t) * omega) / so)
    w1 = np.where(near, t, np.sin(t * omega) / so)
    q = w0 * q0 + w1 * q1
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def slerp(r0, r1, t):
    """Interpolate rotations given as rotation vectors, along the shorter great arc.

    Parameters
    ----------
    r0, r1 : (..., 3) float
        Rotation vectors at ``t = 0`` and ``t = 1``.
    t : float or (...) float
        Fraction in [0, 1] (extrapolation works too), broadcast against the batch shape.

    Returns
    -------
    (..., 3) float rotation vectors, angle in [0, pi].
    """
    return quat_to_rotvec(slerp_quat(rotvec_to_quat(r0), rotvec_to_quat(r1), t))


def rotation_about(axis, angle):
    """Rotation matrices about ``axis (3,)`` by ``angle (...)`` radians: ``(..., 3, 3)``."""
    axis = np.asarray(axis, dtype=np.float64)
    axis = axis / np.linalg.norm(axis)
    return rotvec_to_matrix(np.asarray(angle, dtype=np.float64)[..., None] * axis)


def axis_rotations(axis: str, degrees) -> np.ndarray:
    """Elementary rotation matrices about a coordinate axis.

    Parameters
    ----------
    axis : {"X", "Y", "Z"}
    degrees : (...,) float

    Returns
    -------
    R : (..., 3, 3) float
    """
    a = np.radians(np.asarray(degrees, dtype=float))
    c, s = np.cos(a), np.sin(a)
    o, z = np.ones_like(a), np.zeros_like(a)
    if axis == "X":
        rows = [[o, z, z], [z, c, -s], [z, s, c]]
    elif axis == "Y":
        rows = [[c, z, s], [z, o, z], [-s, z, c]]
    elif axis == "Z":
        rows = [[c, -s, z], [s, c, z], [z, z, o]]
    else:
        raise ValueError(f"unknown axis {axis!r}")
    return np.stack([np.stack(r, axis=-1) for r in rows], axis=-2)


def matrix_to_euler(R, order: str = "ZYX") -> np.ndarray:
    """Euler angles (degrees) such that ``R = R_a0 @ R_a1 @ R_a2`` for ``order = a0 a1 a2``.

    Parameters
    ----------
    R : (..., 3, 3) float
        Rotation matrices.
    order : str
        Three distinct axes, e.g. ``"ZYX"`` (the BVH ``Zrotation Yrotation Xrotation``).

    Returns
    -------
    angles : (..., 3) float
        Degrees, in ``order``; the middle angle lies in [-90, 90].
    """
    R = np.asarray(R, dtype=float)
    idx = {"X": 0, "Y": 1, "Z": 2}
    i, j, k = (idx[a] for a in order)
    if len({i, j, k}) != 3:
        raise ValueError(f"order {order!r} must name three distinct axes")
    # Tait-Bryan decomposition for R = R_i(a) R_j(b) R_k(c); sign from the axes' parity.
    sign = 1.0 if (j - i) % 3 == 1 else -1.0
    sin_b = np.clip(sign * R[..., i, k], -1.0, 1.0)
    b = np.arcsin(sin_b)
    a = np.arctan2(-sign * R[..., j, k], R[..., k, k])
    c = np.arctan2(-sign * R[..., i, j], R[..., i, i])
    # Gimbal lock: c is free; put everything into a.
    lock = np.abs(sin_b) > 1.0 - 1e-9
    if np.any(lock):
        a_lock = np.arctan2(sign * R[..., k, j], R[..., j, j])
        a = np.where(lock, a_lock, a)
        c = np.where(lock, 0.0, c)
    return np.degrees(np.stack([a, b, c], axis=-1))
