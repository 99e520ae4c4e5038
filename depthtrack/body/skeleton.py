"""The kinematic tree, the 48-parameter pose vector and batched forward kinematics.

Skeleton (index: name, parent). The pelvis is the root with free translation and
rotation; every other joint is a ball joint (3 rotation parameters)::

     0 pelvis      (-1)        8 r_wrist   (7)
     1 spine       (0)         9 l_hip     (0)
     2 neck        (1)        10 l_knee    (9)
     3 l_shoulder  (1)        11 l_ankle   (10)
     4 l_elbow     (3)        12 r_hip     (0)
     5 l_wrist     (4)        13 r_knee    (12)
     6 r_shoulder  (1)        14 r_ankle   (13)
     7 r_elbow     (6)

A joint rotates the body part that hangs below it: ``l_shoulder`` turns the upper
arm, ``l_elbow`` the forearm, ``neck`` the neck and head, ``spine`` the chest.

Pose vector ``(D,) = (48,)``, :data:`POSE_NAMES`:

* ``[0:3]``  ``pelvis_tx, pelvis_ty, pelvis_tz``  -- pelvis position (camera frame, metres)
* ``[3:6]``  ``pelvis_rx, pelvis_ry, pelvis_rz``  -- pelvis rotation vector
* ``[3+3j : 6+3j]`` for j = 1..14: ``<joint>_rx, <joint>_ry, <joint>_rz`` -- rotation
  vector of joint j relative to its parent, applied in the joint's rest frame.

World transforms: ``T_root = Trans(t) @ Rot(r_0)``;
``T_j = T_parent @ Trans(offset_j) @ Rot(r_j)``. Rest frames are aligned with the
model frame (no rest rotations), so rotation-vector components are about the model
axes at the zero pose.

Model frame (camera-friendly): at the zero pose the body stands upright with the
head toward -y (camera y is down), faces -z (toward a camera looking along +z),
its own left toward +x, the pelvis at the origin, arms in a relaxed A-pose.

Sign conventions that follow (zero pose, right-handed rotations):

* spine / neck ``rx > 0`` bends forward (head toward -z); ``ry`` twists about the
  vertical axis; ``rz`` bends sideways.
* elbow flexion (forearm forward, toward -z) is ``rx < 0``; hip flexion (thigh
  forward) is ``rx < 0``; knee flexion (shank backward, toward +z) is ``rx > 0``.
* left hip abduction (leg toward +x) is ``rz < 0``; right hip abduction ``rz > 0``.

Joint limits (:data:`LOWER`, :data:`UPPER`) are bounds on the individual
rotation-vector components, +-inf where there is none. They are **approximate**:
a rotation-vector component equals an anatomical angle only when the rotation is
mainly about that axis. They keep a search away from impossible poses (a knee bent
forwards, an elbow bent backwards); they are not a biomechanical range-of-motion model.
"""
from __future__ import annotations

import numpy as np

from .rotations import rotvec_to_matrix

JOINTS = (
    "pelvis", "spine", "neck",
    "l_shoulder", "l_elbow", "l_wrist",
    "r_shoulder", "r_elbow", "r_wrist",
    "l_hip", "l_knee", "l_ankle",
    "r_hip", "r_knee", "r_ankle",
)
PARENTS = np.array([-1, 0, 1, 1, 3, 4, 1, 6, 7, 0, 9, 10, 0, 12, 13], dtype=np.int64)
PARENTS.setflags(write=False)
JOINT_ID = {name: i for i, name in enumerate(JOINTS)}
NUM_JOINTS = len(JOINTS)
DOF = 6 + 3 * (NUM_JOINTS - 1)  # 48

POSE_NAMES = tuple(
    ["pelvis_tx", "pelvis_ty", "pelvis_tz", "pelvis_rx", "pelvis_ry", "pelvis_rz"]
    + [f"{name}_{axis}" for name in JOINTS[1:] for axis in ("rx", "ry", "rz")]
)
POSE_INDEX = {name: i for i, name in enumerate(POSE_NAMES)}

#: The model frame's axes at the zero pose (module docstring): the body faces
#: ``MODEL_FORWARD`` (-z) and its head points along ``MODEL_UP`` (-y). A root rotation R
#: turns them into the body's forward and up: ``R @ MODEL_FORWARD``, ``R @ MODEL_UP``.
MODEL_FORWARD = np.array([0.0, 0.0, -1.0])
MODEL_UP = np.array([0.0, -1.0, 0.0])
MODEL_FORWARD.setflags(write=False)
MODEL_UP.setflags(write=False)

#: Contract joints (depthtrack.contract.JOINT_NAMES) that move with the torso: a rigid
#: frame to fit a root rotation to.
TORSO_CONTRACT_JOINTS = ("neck", "pelvis", "l_shoulder", "r_shoulder", "l_hip", "r_hip")

#: Skeleton joint index of each contract joint (depthtrack.contract.JOINT_NAMES),
#: -1 for "head" which is a point fixed in the neck's frame.
CONTRACT_SOURCE = np.array([-1, 2, 0, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14], dtype=np.int64)


def _limits():
    inf = np.inf
    lo = np.full(DOF, -inf)
    hi = np.full(DOF, inf)

    def put(joint, rx, ry, rz):
        i = POSE_INDEX[f"{joint}_rx"]
        lo[i:i + 3] = np.radians([rx[0], ry[0], rz[0]])
        hi[i:i + 3] = np.radians([rx[1], ry[1], rz[1]])

    # degrees, (lower, upper) per component; mirrored components swap sign for the right side
    put("spine", (-35, 80), (-50, 50), (-40, 40))
    put("neck", (-60, 70), (-80, 80), (-50, 50))
    for side, m in (("l", 1), ("r", -1)):
        put(f"{side}_shoulder", (-180, 180), (-180, 180), (-180, 180))
        # the A-pose forearm hangs 25 deg out, so flexion also has an rz part of sign m
        rz = (-25, 70) if m > 0 else (-70, 25)
        put(f"{side}_elbow", (-155, 10), (-95, 95), rz)
        put(f"{side}_wrist", (-80, 80), (-40, 40), (-80, 80))
        rz = (-60, 35) if m > 0 else (-35, 60)
        put(f"{side}_hip", (-130, 35), (-50, 50), rz)
        put(f"{side}_knee", (-8, 155), (-30, 30), (-15, 15))
        put(f"{side}_ankle", (-50, 45), (-35, 35), (-35, 35))
    return lo, hi


LOWER, UPPER = _limits()
LOWER.setflags(write=False)
UPPER.setflags(write=False)


def as_batch(poses, dof=DOF):
    """Return ``poses`` as ``(N, dof)`` float64 and whether the input had no batch axis."""
    p = np.asarray(poses, dtype=np.float64)
    single = p.ndim == 1
    p = p.reshape(-1, p.shape[-1]) if p.ndim > 0 else p
    if p.ndim != 2 or p.shape[1] != dof:
        raise ValueError(f"poses must have shape (N, {dof}) or ({dof},), got {np.shape(poses)}")
    return p, single


def forward_kinematics(poses, offsets, parents=PARENTS):
    """World transforms of every joint for a batch of poses.

    Parameters
    ----------
    poses : (N, D) float
        Pose vectors (layout above).
    offsets : (J, 3) float
        Position of each joint in its parent's frame (the root's is ignored).
    parents : (J,) int
        Parent index, -1 for the root; parents come before children.

    Returns
    -------
    (N, J, 4, 4) float64 homogeneous world transforms.
    """
    poses = np.asarray(poses, dtype=np.float64)
    n = poses.shape[0]
    num = len(parents)
    local_rot = rotvec_to_matrix(poses[:, 3:].reshape(n, num, 3))  # (N, J, 3, 3)
    rot = np.empty((n, num, 3, 3))
    pos = np.empty((n, num, 3))
    offsets = np.asarray(offsets, dtype=np.float64)
    for j, p in enumerate(parents):
        if p < 0:
            rot[:, j] = local_rot[:, j]
            pos[:, j] = poses[:, 0:3]
        else:
            rot[:, j] = rot[:, p] @ local_rot[:, j]
            pos[:, j] = pos[:, p] + rot[:, p] @ offsets[j]
    out = np.zeros((n, num, 4, 4))
    out[:, :, :3, :3] = rot
    out[:, :, :3, 3] = pos
    out[:, :, 3, 3] = 1.0
    return out


def children_of(parents=PARENTS):
    """List of child indices for each joint: ``[[...], ...]`` of length J."""
    kids = [[] for _ in parents]
    for j, p in enumerate(parents):
        if p >= 0:
            kids[p].append(j)
    return kids
