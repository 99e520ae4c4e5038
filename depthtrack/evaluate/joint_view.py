"""Where a track's joints miss, as the camera saw them: which true joints it could not see,
each elbow in the chest's own frame, and arm points inside the trunk.

Diagnostics for looking at failures (``tools/joint_errors.py``; README, "Figures: parity
preset on the test split"); the tracker does not use them. Joints are ``(F, 15, 3)`` in
camera coordinates (metres, :data:`depthtrack.contract.JOINT_NAMES` order), the track's or
the ground truth's alike.
"""
from __future__ import annotations

import numpy as np

from ..contract import JOINT_INDEX as J

#: A true joint counts as hidden where the depth read at its pixel is this much in front of
#: it (m): a body part (or anything else) lies between it and the camera. Joints are inside
#: the body, so a visible limb's joint reads a few centimetres behind its surface. Meant for
#: the limbs' joints: the trunk's and the head's lie deeper than that in their own body and
#: read hidden where they face the camera too.
HIDDEN_GAP_M = 0.08

#: Half axes (m) of the elliptic trunk that :func:`trunk_penetration` tests, across and
#: front to back, for a pelvis-to-neck length of :data:`TRUNK_LENGTH_M` (scaled with it):
#: inside the template's trunk, whose cross-sections between pelvis and neck are 0.14 to
#: 0.19 m by 0.10 to 0.12 m half-wide, so that an arm resting against the side does not count.
TRUNK_HALF_AXES_M = (0.12, 0.08)
TRUNK_LENGTH_M = 0.485

#: The arm points tested against the trunk: fractions along shoulder -> elbow -> wrist
#: (0.5 = the middle of the upper arm, 1 the elbow, 1.5 the middle of the forearm, 2 the wrist).
ARM_POINTS = (0.5, 1.0, 1.5, 2.0)


def hidden_joints(depth, camera, joints, gap: float = HIDDEN_GAP_M) -> np.ndarray:
    """``(15,)`` bool: the joints ``(15, 3)`` of one frame the camera does not see, because
    ``depth (H, W)`` reads more than ``gap`` in front of them at their pixel. A joint
    outside the image or at a pixel without a reading is not counted as hidden."""
    joints = np.asarray(joints, dtype=np.float64)
    depth = np.asarray(depth)
    uv = np.asarray(camera.project(joints), dtype=np.float64)
    u, v = np.round(uv[:, 0]), np.round(uv[:, 1])
    inside = (u >= 0) & (v >= 0) & (u < depth.shape[1]) & (v < depth.shape[0]) & (joints[:, 2] > 0)
    z = np.zeros(len(joints))
    z[inside] = depth[v[inside].astype(int), u[inside].astype(int)]
    return inside & (z > 0) & (z < joints[:, 2] - gap)


def chest_axes(joints):
    """The chest's frame per frame of ``joints (F, 15, 3)``: ``(lateral, up, forward)``,
    each ``(F, 3)`` unit vectors. ``up`` from the pelvis to the neck, ``lateral`` from the
    right shoulder to the left made perpendicular to it, ``forward = lateral x up`` (the
    way the chest faces, as :func:`tools.benchmark.truth_facing_cosines` takes the pelvis's)."""
    x = np.asarray(joints, dtype=np.float64)
    up = x[:, J["neck"]] - x[:, J["pelvis"]]
    up /= np.linalg.norm(up, axis=1, keepdims=True)
    lateral = x[:, J["l_shoulder"]] - x[:, J["r_shoulder"]]
    lateral -= np.sum(lateral * up, axis=1, keepdims=True) * up
    lateral /= np.linalg.norm(lateral, axis=1, keepdims=True)
    return lateral, up, np.cross(lateral, up)


def elbow_offsets(joints, side: str) -> np.ndarray:
    """``(F, 3)``: the ``side`` ("l" or "r") elbow's offset from its shoulder in the chest's
    frame (:func:`chest_axes`), as ``(forward, outward, up)`` metres: ``outward`` away from
    the body's midline for either arm, so a left and a right arm held alike read alike."""
    if side not in ("l", "r"):
        raise ValueError(f"side must be 'l' or 'r', not {side!r}")
    x = np.asarray(joints, dtype=np.float64)
    lateral, up, forward = chest_axes(x)
    d = x[:, J[f"{side}_elbow"]] - x[:, J[f"{side}_shoulder"]]
    outward = lateral if side == "l" else -lateral
    return np.stack([np.sum(d * a, axis=1) for a in (forward, outward, up)], axis=1)


def trunk_penetration(joints, half_axes=TRUNK_HALF_AXES_M) -> np.ndarray:
    """``(F, 2)``: how deep (m) each arm (left, right) reaches into the trunk, per frame of
    ``joints (F, 15, 3)``: the deepest of its :data:`ARM_POINTS` inside an elliptic cylinder
    about the pelvis-neck line (between 5 % and 95 % of it), ``half_axes`` across and front
    to back (scaled by the pelvis-neck length over :data:`TRUNK_LENGTH_M`); 0 outside.

    The cylinder's across axis turns from the hips' line at the pelvis to the shoulders'
    at the neck. Depth is ``(1 - rho) * b``, ``rho`` the point's elliptic radius, ``b`` the
    front-to-back half axis: the axis itself reads ``b``.
    """
    x = np.asarray(joints, dtype=np.float64)
    pelvis = x[:, J["pelvis"]]
    axis = x[:, J["neck"]] - pelvis
    length = np.linalg.norm(axis, axis=1)
    unit = axis / length[:, None]
    a, b = (np.asarray(half_axes, dtype=np.float64)[:, None] * length / TRUNK_LENGTH_M)
    shoulders = x[:, J["l_shoulder"]] - x[:, J["r_shoulder"]]
    hips = x[:, J["l_hip"]] - x[:, J["r_hip"]]
    out = np.zeros((len(x), 2))
    for k, side in enumerate("lr"):
        s, e, w = (x[:, J[f"{side}_{j}"]] for j in ("shoulder", "elbow", "wrist"))
        for f in ARM_POINTS:
            p = s + f * (e - s) if f <= 1 else e + (f - 1) * (w - e)
            d = p - pelvis
            t = np.sum(d * unit, axis=1) / length
            tc = np.clip(t, 0.0, 1.0)[:, None]
            across = tc * shoulders + (1.0 - tc) * hips
            across -= np.sum(across * unit, axis=1, keepdims=True) * unit
            across /= np.linalg.norm(across, axis=1, keepdims=True)
            front = np.cross(across, unit)
            radial = d - (t * length)[:, None] * unit
            rho = np.hypot(np.sum(radial * across, axis=1) / a, np.sum(radial * front, axis=1) / b)
            depth = np.where((t > 0.05) & (t < 0.95), np.maximum(0.0, 1.0 - rho) * b, 0.0)
            out[:, k] = np.maximum(out[:, k], depth)
    return out
