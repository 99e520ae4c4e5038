"""Write our body model's poses as BVH (CMU/Mixamo joint names, y up, ZYX Euler angles)."""
from __future__ import annotations

import numpy as np

from ...contract import JOINT_INDEX as CONTRACT
from ...rotations import matrix_to_euler, rotvec_to_matrix
from ..atomic import write_text_atomic
from .motion import BVH_FROM_CAMERA

#: BVH joint names written for our body model's joints (CMU/Mixamo style, so that
#: :meth:`BvhMotion.contract_joint_positions` maps them back; the head centre is the
#: neck's end site, as in DeepMimic files).
BODY_BVH_NAMES = {
    "pelvis": "Hips", "spine": "Spine", "neck": "Neck",
    "l_shoulder": "LeftArm", "l_elbow": "LeftForeArm", "l_wrist": "LeftHand",
    "r_shoulder": "RightArm", "r_elbow": "RightForeArm", "r_wrist": "RightHand",
    "l_hip": "LeftUpLeg", "l_knee": "LeftLeg", "l_ankle": "LeftFoot",
    "r_hip": "RightUpLeg", "r_knee": "RightLeg", "r_ankle": "RightFoot",
}


def _fmt(values) -> str:
    return " ".join(f"{v:.6f}" for v in values)


def body_end_sites(body) -> dict:
    """End-site offsets (model frame, metres) of the body's leaf joints and the head.

    Returns
    -------
    dict : {joint index: (3,) float}
        neck -> head centre (exact, from the body's contract head); wrists -> hand
        tip (half a hand length along the forearm); ankles -> toe (forward, -z).
    """

    names = list(body.joint_names)
    zero = np.zeros(body.dof)
    rest = np.asarray(body.joint_positions(zero))
    height = float(body.height)
    offsets = np.asarray(body.offsets, float)
    ends = {names.index("neck"): rest[CONTRACT["head"]] - rest[CONTRACT["neck"]]}
    for side in "lr":
        w = names.index(f"{side}_wrist")
        forearm = offsets[w] / np.linalg.norm(offsets[w])
        ends[w] = 0.054 * height * forearm
        ends[names.index(f"{side}_ankle")] = np.array([0.0, 0.015, -0.1]) * height
    return ends


def skeleton_and_poses(body, poses):
    """``poses`` as a checked (F, D) float array, with the body's joint names and parents.

    Raises
    ------
    ValueError
        Poses of the wrong shape for the body, or non-finite ones (a BVH has no "unknown").
    """
    poses = np.atleast_2d(np.asarray(poses, dtype=float))
    names = list(body.joint_names)
    parents = np.asarray(body.parents)
    D = 6 + 3 * (len(names) - 1)
    if poses.ndim != 2 or poses.shape[1] != D:
        raise ValueError(f"poses must be (F, {D}), not {poses.shape}")
    if not np.all(np.isfinite(poses)):
        raise ValueError("poses hold non-finite values")
    return poses, names, parents


def write_bvh(path, body, poses, fps: float, units_m: float = 1.0) -> None:
    """Write pose vectors of our body model as a BVH file (atomically).

    The skeleton is the body's 15 joints with CMU/Mixamo names (:data:`BODY_BVH_NAMES`);
    the head centre is the neck's end site. The file is y up: every length and
    rotation is taken from the camera frame to the BVH world by
    :data:`BVH_FROM_CAMERA` (180 degrees about x), so ``read_bvh(path).joint_positions()``
    equals ``body joint positions @ BVH_FROM_CAMERA.T``. Rotations are written as
    ``Zrotation Yrotation Xrotation`` degrees, unwrapped over time.

    Parameters
    ----------
    path : path-like
    body : BodyModel
    poses : (F, D) float
        Pose vectors (camera frame).
    fps : float
    units_m : float
        Metres per written unit (1.0 = metres, 0.01 = centimetres).
    """

    poses, names, parents = skeleton_and_poses(body, poses)
    J = len(names)
    C = BVH_FROM_CAMERA
    offsets = np.asarray(body.offsets, float) @ C.T / units_m
    ends = {j: (C @ e) / units_m for j, e in body_end_sites(body).items()}
    F = poses.shape[0]
    rot = rotvec_to_matrix(poses[:, 3:].reshape(F, J, 3))
    rot_bvh = C @ rot @ C                      # C is its own inverse
    euler = np.unwrap(matrix_to_euler(rot_bvh, "ZYX"), period=360.0, axis=0)
    root = poses[:, :3] @ C.T / units_m
    write_text_atomic(path, format_bvh(names, parents, offsets, ends, root, euler, fps))


def format_bvh(names, parents, offsets, ends, root, euler, fps: float) -> str:
    """The text of a BVH file for our skeleton, every number already in the file's frame.

    Parameters
    ----------
    names : sequence of str, (J,)
        Our joint names (written as :data:`BODY_BVH_NAMES`).
    parents : (J,) int
        Parent index, -1 for the root.
    offsets : (J, 3) float
        Each joint's offset from its parent in the file's units and axes.
    ends : dict {joint index: (3,) float}
        End-site offsets.
    root : (F, 3) float
        Root positions.
    euler : (F, J, 3) float
        ``Zrotation Yrotation Xrotation`` channels per joint, degrees.
    fps : float
    """
    parents = np.asarray(parents)
    children = [[] for _ in range(len(names))]
    for j, p in enumerate(parents):
        if p >= 0:
            children[p].append(j)
    lines, order = ["HIERARCHY"], []

    def emit(j, depth):
        order.append(j)
        pad = "\t" * depth
        lines.append(f"{pad}{'ROOT' if parents[j] < 0 else 'JOINT'} {BODY_BVH_NAMES.get(names[j], names[j])}")
        lines.append(f"{pad}{{")
        lines.append(f"{pad}\tOFFSET {_fmt(offsets[j] if parents[j] >= 0 else np.zeros(3))}")
        if parents[j] < 0:
            lines.append(f"{pad}\tCHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation")
        else:
            lines.append(f"{pad}\tCHANNELS 3 Zrotation Yrotation Xrotation")
        if j in ends:
            lines.extend([f"{pad}\tEnd Site", f"{pad}\t{{", f"{pad}\t\tOFFSET {_fmt(ends[j])}", f"{pad}\t}}"])
        for c in children[j]:
            emit(c, depth + 1)
        lines.append(f"{pad}}}")

    emit(int(np.flatnonzero(parents < 0)[0]), 0)
    columns = []
    for j in order:
        if parents[j] < 0:
            columns.append(root)
        columns.append(euler[:, j])
    table = np.concatenate(columns, axis=1)
    lines += ["MOTION", f"Frames: {len(table)}", f"Frame Time: {1.0 / fps:.8f}"]
    lines += [_fmt(row) for row in table]
    return "\n".join(lines) + "\n"
