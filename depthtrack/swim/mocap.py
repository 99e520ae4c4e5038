"""The 14 stick-figure joints from motion capture (BVH), in the pool frame.

The pool frame is the BVH world frame in metres, y up (out of the water); CMU
and Mixamo BVH are y-up already. Joints come from the BVH reader's contract
joints (``depthtrack.io.bvh``): hip joints, knees, ankles (the thesis's "foot"),
shoulders, elbows, wrists ("hand"); the root is the midpoint of the two hip
joints and the neck the midpoint of the two shoulders, so the hip and shoulder
segments are symmetric as in thesis Figure 2.1.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..contract import JOINT_INDEX
from ..errors import InputError
from .stickfigure import N_JOINTS, SWIM_INDEX

_FROM_CONTRACT = {
    "l_hip": "l_hip", "l_knee": "l_knee", "l_foot": "l_ankle",
    "r_hip": "r_hip", "r_knee": "r_knee", "r_foot": "r_ankle",
    "l_shoulder": "l_shoulder", "l_elbow": "l_elbow", "l_hand": "l_wrist",
    "r_shoulder": "r_shoulder", "r_elbow": "r_elbow", "r_hand": "r_wrist",
}


def stick_figure_from_contract(contract_joints):
    """``contract_joints (F, 15, 3)`` (JOINT_NAMES order) -> ``(F, 14, 3)`` stick-figure joints."""
    c = np.asarray(contract_joints, dtype=float)
    out = np.empty(c.shape[:-2] + (N_JOINTS, 3))
    for swim, contract in _FROM_CONTRACT.items():
        out[..., SWIM_INDEX[swim], :] = c[..., JOINT_INDEX[contract], :]
    out[..., SWIM_INDEX["hips"], :] = 0.5 * (c[..., JOINT_INDEX["l_hip"], :] + c[..., JOINT_INDEX["r_hip"], :])
    out[..., SWIM_INDEX["neck"], :] = 0.5 * (c[..., JOINT_INDEX["l_shoulder"], :]
                                             + c[..., JOINT_INDEX["r_shoulder"], :])
    return out


class SwimMocap:
    """Stick-figure joints of a BVH take.

    Attributes
    ----------
    joints : (F, 14, 3) float
        Pool frame, metres.
    fps : float
    path : str
    units_m : float
        Metres per BVH unit the reader used.
    units_source : str
    """

    def __init__(self, joints, fps, path=None, units_m=1.0, units_source=""):
        self.joints = np.asarray(joints, dtype=float)
        self.fps = float(fps)
        self.path = None if path is None else str(path)
        self.units_m = float(units_m)
        self.units_source = units_source

    def __len__(self):
        return len(self.joints)


def load_swim_mocap(path, units=None, joint_map=None) -> SwimMocap:
    """Read a BVH with :func:`depthtrack.io.bvh.read_bvh` and extract the stick figure.

    ``joint_map`` (``{our joint: file joint}`` or a JSON file) names joints that the
    BVH reader's naming conventions do not find (``--joint-map``).

    Raises
    ------
    InputError
        Missing or malformed file, or a skeleton without the needed joints.
    """
    from ..io.bvh import read_bvh

    path = Path(path)
    if not path.is_file():
        raise InputError(path, "no such BVH file")
    motion = read_bvh(path, units=units, joint_map=joint_map)
    if motion.n_frames < 2:
        raise InputError(path, "BVH has fewer than 2 frames")
    joints = stick_figure_from_contract(motion.contract_joint_positions())
    return SwimMocap(joints, motion.fps, path, motion.units_m, motion.units_source)
