"""BVH export with a choice of rest pose and up axis (``depthtrack export --format bvh``).

``track.bvh`` (written by every ``depthtrack track``, :func:`depthtrack.io.bvh.write_bvh`)
keeps our zero pose as the rest pose (a relaxed A-pose) and y up. Animation tools
retarget best from a T-pose, and some scenes are z up, so this writer adds:

* ``rest="tpose"`` (default): with every channel zero the skeleton stands in a T-pose --
  arms straight out sideways (upper arm, forearm and hand along the shoulder line), legs
  straight down; pelvis, spine, neck and feet as in our rest. Each joint's frame is
  re-based by a fixed rotation ``G_j`` (the smallest one taking the T-pose bone to our
  rest bone), so the channels are ``G_parent^T L_j G_j`` and every posed joint lands
  exactly where the track has it. ``rest="zero"`` writes our A-pose rest, as track.bvh.
* ``up="y"`` (default; x right, y up, the body faces +z at rest) or ``up="z"`` (x right,
  y along the camera's view, z up: the body faces -y, as in Blender's front view); the
  axes are :data:`depthtrack.export.axes.UP_AXES`, origin at the depth camera.

Joint names are :data:`depthtrack.io.bvh.BODY_BVH_NAMES` (CMU/Mixamo style); the head
centre is the neck's end site; rotations are ``Zrotation Yrotation Xrotation`` degrees,
unwrapped over time; lengths in metres (``units_m`` to change). Frames without a pose
must be filled by the caller (:func:`depthtrack.io.track_output.hold_last_pose`).
With ``rest="zero", up="y"`` the text equals :func:`depthtrack.io.bvh.write_bvh`'s.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..body.rotations import rotvec_to_matrix
from ..io.atomic import write_text_atomic
from ..io.bvh import body_end_sites, matrix_to_euler
from ..io.bvh.write import format_bvh, skeleton_and_poses
from ..motion.retarget import rotation_between
from .axes import UP_AXES

REST_POSES = ("tpose", "zero")

#: T-pose bone directions in the model frame (+x = the body's left, +y = down) for the
#: joints whose bone (to their one child, or to their end site) is re-aimed.
_TPOSE_DIRECTIONS = {
    "l_shoulder": (1, 0, 0), "l_elbow": (1, 0, 0), "l_wrist": (1, 0, 0),
    "r_shoulder": (-1, 0, 0), "r_elbow": (-1, 0, 0), "r_wrist": (-1, 0, 0),
    "l_hip": (0, 1, 0), "l_knee": (0, 1, 0), "r_hip": (0, 1, 0), "r_knee": (0, 1, 0),
}


def rest_rotations(body, rest: str = "tpose") -> np.ndarray:
    """``(J, 3, 3)`` rotations ``G_j`` taking each joint's T-pose bone to our rest bone (identity for ``"zero"``)."""
    names = list(body.joint_names)
    G = np.tile(np.eye(3), (len(names), 1, 1))
    if rest == "zero":
        return G
    if rest not in REST_POSES:
        raise ValueError(f"rest must be one of {REST_POSES}, not {rest!r}")
    parents = np.asarray(body.parents)
    ends = body_end_sites(body)
    offsets = np.asarray(body.offsets, float)
    for name, target in _TPOSE_DIRECTIONS.items():
        j = names.index(name)
        kids = np.flatnonzero(parents == j)
        bone = offsets[kids[0]] if len(kids) else ends[j]
        G[j] = rotation_between(np.asarray(target, float), bone)
    return G


def bvh_text(body, poses, fps: float, rest: str = "tpose", up: str = "y", units_m: float = 1.0) -> str:
    """The BVH file's text for finite ``poses (F, D)``; see the module docstring."""
    if up not in UP_AXES:
        raise ValueError(f"up must be one of {sorted(UP_AXES)}, not {up!r}")
    poses, names, parents = skeleton_and_poses(body, poses)
    J = len(names)
    V = UP_AXES[up]
    G = rest_rotations(body, rest)
    base = np.asarray(body.offsets, float)
    offsets = np.zeros_like(base)
    for j in range(J):
        if parents[j] >= 0:
            offsets[j] = G[parents[j]].T @ base[j]
    offsets = offsets @ V.T / units_m
    ends = {j: (V @ (G[j].T @ e)) / units_m for j, e in body_end_sites(body).items()}
    F = poses.shape[0]
    local = rotvec_to_matrix(poses[:, 3:].reshape(F, J, 3))
    Gp = G[np.where(parents < 0, 0, parents)]
    Gp[parents < 0] = np.eye(3)
    local = np.swapaxes(Gp, -1, -2) @ local @ G          # channels relative to the re-based rest
    euler = np.unwrap(matrix_to_euler(V @ local @ V.T, "ZYX"), period=360.0, axis=0)
    root = poses[:, :3] @ V.T / units_m

    return format_bvh(names, parents, offsets, ends, root, euler, fps)


def write_bvh_export(path, body, poses, fps: float, rest: str = "tpose", up: str = "y",
                     units_m: float = 1.0) -> Path:
    """Write :func:`bvh_text` to ``path`` atomically."""
    write_text_atomic(path, bvh_text(body, poses, fps, rest=rest, up=up, units_m=units_m))
    return Path(path)
