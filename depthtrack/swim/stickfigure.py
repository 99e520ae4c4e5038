"""The thesis's 14-joint swimmer stick figure and its 26 spherical angles.

The figure (thesis section 2.1, Figure 2.2) has its root at the hip centre; every
other joint hangs off its parent by a segment of known length, and is described
by two angles of the segment direction in the *global* pool frame (y up, out of
the water), equation 2.1::

    phi   = atan2(x_child - x_parent, z_child - z_parent)          azimuth from +z
    theta = atan2(hypot(dx, dz), y_child - y_parent)               zenith from +y

so ``child = parent + length * (sin(theta) sin(phi), cos(theta), sin(theta) cos(phi))``.

Poles: where a segment points straight up or down (``hypot(dx, dz) == 0``) the
azimuth is undefined; equation 2.2 gives ``atan2(0, 0) = 0``, so
:func:`joints_to_angles` returns ``phi = 0`` there. The joints are still
recovered exactly by :func:`angles_to_joints` (``sin(theta) = 0`` removes phi), but
the angles do not round-trip: any phi went in, 0 comes out.

Trajectories that pass over a pole (the back-stroke arm swings straight up every
cycle) flip phi by pi in one frame. :func:`continue_angles` picks, frame by
frame, the equivalent representation ``(-theta, phi + pi)`` or ``phi + 2 pi k``
nearest the previous frame, so the angles stay continuous in time (theta may
then leave [0, pi]); :func:`canonical_angles` maps back to equation 2.1's ranges.
"""
from __future__ import annotations

import numpy as np

from ..filters.angles import wrap

#: The 14 joints, parents before children (hierarchy of thesis Figure 2.2).
SWIM_JOINTS = (
    "hips",                                   # root: hip centre
    "l_hip", "l_knee", "l_foot",
    "r_hip", "r_knee", "r_foot",
    "neck",                                   # shoulder centre (top of the torso)
    "l_shoulder", "l_elbow", "l_hand",
    "r_shoulder", "r_elbow", "r_hand",
)
#: (14,) int parent of each joint, -1 for the root.
SWIM_PARENTS = np.array([-1, 0, 1, 2, 0, 4, 5, 0, 7, 8, 9, 7, 11, 12])
SWIM_INDEX = {name: i for i, name in enumerate(SWIM_JOINTS)}
#: The 13 segments, named by their child joint (segment j+1 ends at joint j+1).
SEGMENTS = SWIM_JOINTS[1:]
N_JOINTS = 14
N_ANGLES = 26
#: (26,) names: for each non-root joint its zenith then its azimuth.
ANGLE_NAMES = tuple(f"{j}_{a}" for j in SEGMENTS for a in ("theta", "phi"))
#: Left/right joint pairs (used when mirroring one body half onto the other).
MIRROR_PAIRS = (("l_hip", "r_hip"), ("l_knee", "r_knee"), ("l_foot", "r_foot"),
                ("l_shoulder", "r_shoulder"), ("l_elbow", "r_elbow"), ("l_hand", "r_hand"))

TWO_PI = 2.0 * np.pi


def wrap_angle(angles):
    """Angles mapped to [-pi, pi] (:func:`depthtrack.filters.angles.wrap`, the one wrap)."""
    return wrap(angles)


def segment_vectors(joints):
    """``joints (..., 14, 3)`` -> ``(..., 13, 3)`` child minus parent for every segment."""
    joints = np.asarray(joints)
    return joints[..., 1:, :] - joints[..., SWIM_PARENTS[1:], :]


def segment_lengths(joints):
    """``joints (..., 14, 3)`` -> ``(..., 13)`` segment lengths."""
    return np.linalg.norm(segment_vectors(joints), axis=-1)


def joints_to_angles(joints):
    """Equation 2.1 for every segment.

    Parameters
    ----------
    joints : (..., 14, 3) float
        Joint positions in the pool frame (y up).

    Returns
    -------
    angles : (..., 26) float
        ``[theta_1, phi_1, ..., theta_13, phi_13]``; theta in [0, pi], phi in
        (-pi, pi], phi = 0 at the poles.
    """
    d = segment_vectors(joints)
    phi = np.arctan2(d[..., 0], d[..., 2])
    theta = np.arctan2(np.hypot(d[..., 0], d[..., 2]), d[..., 1])
    return np.stack([theta, phi], axis=-1).reshape(d.shape[:-2] + (N_ANGLES,))


def directions(angles):
    """``angles (..., 26)`` -> ``(..., 13, 3)`` unit segment directions."""
    angles = np.asarray(angles)
    a = angles.reshape(angles.shape[:-1] + (13, 2))
    theta, phi = a[..., 0], a[..., 1]
    s = np.sin(theta)
    return np.stack([s * np.sin(phi), np.cos(theta), s * np.cos(phi)], axis=-1)


def angles_to_joints(angles, lengths, root=None):
    """Inverse of :func:`joints_to_angles` given the segment lengths.

    Parameters
    ----------
    angles : (..., 26) float
    lengths : (13,) or (..., 13) float
        Segment lengths, broadcast against the leading axes of ``angles``.
    root : (3,) or (..., 3) float, optional
        Hip-centre position (origin when omitted).

    Returns
    -------
    joints : (..., 14, 3) float
    """
    seg = directions(angles) * np.asarray(lengths)[..., None]
    out = np.zeros(seg.shape[:-2] + (N_JOINTS, 3), dtype=seg.dtype)
    if root is not None:
        out[..., 0, :] = root
    for j in range(1, N_JOINTS):
        out[..., j, :] = out[..., SWIM_PARENTS[j], :] + seg[..., j - 1, :]
    return out


def canonical_angles(angles):
    """Map any equivalent angles to equation 2.1's ranges: theta in [0, pi], phi in [-pi, pi).

    ``angles (..., 26)`` -> same shape.
    """
    angles = np.asarray(angles, dtype=float)
    a = angles.reshape(angles.shape[:-1] + (13, 2)).copy()
    theta = wrap_angle(a[..., 0])
    flip = theta < 0
    a[..., 0] = np.abs(theta)
    a[..., 1] = wrap_angle(a[..., 1] + np.where(flip, np.pi, 0.0))
    return a.reshape(angles.shape)


def continue_angles(angles, reference=None):
    """Make an angle trajectory continuous in time, through the poles.

    Each frame keeps the pose but picks, among ``(theta, phi)`` and
    ``(-theta, phi + pi)`` with phi and theta shifted by multiples of 2 pi, the
    representation nearest (in summed squared angle) to the previous frame.

    Parameters
    ----------
    angles : (F, 26) float
        Angles of consecutive frames (e.g. from :func:`joints_to_angles`).
    reference : (26,) float, optional
        Angles the first frame is made nearest to (default: the first frame as is).

    Returns
    -------
    (F, 26) float
    """
    angles = np.asarray(angles, dtype=float)
    out = np.empty_like(angles)
    prev = angles[0] if reference is None else np.asarray(reference, dtype=float)
    for f in range(len(angles)):                      # loop over frames, not particles
        out[f] = nearest_equivalent(angles[f], prev)
        prev = out[f]
    return out


def nearest_equivalent(angles, reference):
    """The representation of the pose ``angles (..., 26)`` nearest to ``reference (..., 26)``."""
    return equivalent_branch(angles, reference)[0]


def zenith_sign(angles, reference):
    """``(..., 26)`` of +-1: -1 on the zenith of each segment whose representation in ``angles`` is the
    ``(-theta, phi + pi)`` branch of the one in ``reference`` (both ``(..., 26)``, broadcast).

    A velocity or acceleration learned in the reference's representation (the mean
    stroke's) acts on a state in the other branch with its zenith part negated; the
    azimuth part is the same in both branches.
    """
    _, flipped = equivalent_branch(angles, reference)
    sign = np.ones(flipped.shape[:-1] + (13, 2))
    sign[..., 0] = np.where(flipped, -1.0, 1.0)
    return sign.reshape(flipped.shape[:-1] + (26,))


def equivalent_branch(angles, reference):
    """Nearest representation of ``angles`` to ``reference`` and which branch it took.

    Parameters
    ----------
    angles, reference : (..., 26) float (broadcast)

    Returns
    -------
    aligned : (..., 26) float
        Same pose as ``angles``, each segment as ``(theta, phi)`` or ``(-theta, phi + pi)``
        shifted by multiples of 2 pi, whichever is nearer to ``reference``.
    flipped : (..., 13) bool
        True where the ``(-theta, phi + pi)`` branch was taken.
    """
    angles = np.asarray(angles, dtype=float)
    reference = np.asarray(reference, dtype=float)
    shape = np.broadcast_shapes(angles.shape, reference.shape)
    a = np.broadcast_to(angles, shape).reshape(shape[:-1] + (13, 2))
    r = np.broadcast_to(reference, shape).reshape(shape[:-1] + (13, 2))
    cands, dists = [], []
    for sign, shift in ((1.0, 0.0), (-1.0, np.pi)):
        theta = r[..., 0] + wrap_angle(sign * a[..., 0] - r[..., 0])
        phi = r[..., 1] + wrap_angle(a[..., 1] + shift - r[..., 1])
        cand = np.stack([theta, phi], axis=-1)
        cands.append(cand)
        dists.append(((cand - r) ** 2).sum(axis=-1))
    flipped = dists[1] < dists[0]
    best = np.where(flipped[..., None], cands[1], cands[0])
    return best.reshape(shape), flipped


def angle_error_sq(estimate, truth):
    """Squared angle error per segment, the same pose in any representation counting as equal.

    ``min(wrap(dtheta)^2 + wrap(dphi)^2, wrap(theta_e + theta_t)^2 + wrap(dphi - pi)^2)``
    for each segment, so 2 pi shifts and the pole equivalence ``(-theta, phi + pi)``
    cost nothing.

    Parameters
    ----------
    estimate, truth : (..., 26) float (broadcast; float32 stays float32)

    Returns
    -------
    (..., 13) float
    """
    e = np.asarray(estimate)
    t = np.asarray(truth, dtype=e.dtype if e.dtype.kind == "f" else float)
    te, pe = e[..., 0::2], e[..., 1::2]
    tt, pt = t[..., 0::2], t[..., 1::2]
    dphi = wrap_angle(pe - pt)
    same = wrap_angle(te - tt) ** 2 + dphi ** 2
    other = wrap_angle(te + tt) ** 2 + (np.pi - np.abs(dphi)) ** 2
    return np.minimum(same, other)


def mirror_joints(joints, axis=0):
    """Swap left and right and reflect across the plane ``axis = hips[axis]``.

    ``joints (..., 14, 3)`` -> same shape. Used for the symmetric strokes.
    """
    joints = np.asarray(joints, dtype=float)
    out = joints.copy()
    for left, right in MIRROR_PAIRS:
        out[..., SWIM_INDEX[left], :] = joints[..., SWIM_INDEX[right], :]
        out[..., SWIM_INDEX[right], :] = joints[..., SWIM_INDEX[left], :]
    centre = joints[..., 0:1, axis]
    out[..., axis] = 2 * centre - out[..., axis]
    return out
