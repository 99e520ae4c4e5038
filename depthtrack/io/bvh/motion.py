"""The BVH skeleton and motion in memory, and its forward kinematics.

Conventions
-----------
* A joint's local transform is ``Trans(offset + position channels) @ R`` where ``R``
  is the product of the elementary rotations in the order the joint's ``CHANNELS``
  line lists them (``Zrotation Yrotation Xrotation`` -> ``Rz @ Ry @ Rx``; every joint
  may have its own order), angles in degrees. The root's OFFSET is added to its
  position channels like any joint's (Reallusion files keep the hip height there).
  World transforms chain from the root: ``W_j = W_parent @ L_j``.
* Every length this module returns is in metres (the file's unit times
  :attr:`BvhMotion.units_m`), in the BVH world frame (y up for the usual files).
* The 15 contract joints are found by :mod:`depthtrack.io.bvh.names` (any common
  naming convention, or the caller's joint map).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...contract import JOINT_NAMES
from ...errors import InputError
from ...rotations import axis_rotations
from .names import map_joints, strip_namespace

#: The rotation that takes our camera/model frame (y down, z forward) to a y-up
#: BVH world frame (180 degrees about x); it is its own inverse.
BVH_FROM_CAMERA = np.diag([1.0, -1.0, -1.0])

_POSITION_CHANNELS = ("Xposition", "Yposition", "Zposition")
_ROTATION_CHANNELS = ("Xrotation", "Yrotation", "Zrotation")


@dataclass
class BvhMotion:
    """A BVH skeleton and its motion, lengths in metres.

    Attributes
    ----------
    joint_names : list of str, (J,)
        As written in the file (namespaces such as ``mixamorig:`` kept).
    parents : (J,) int
        Parent index, -1 for the root; parents come before children.
    offsets : (J, 3) float
        Joint offsets from the parent, metres.
    channels : list of tuple of str, (J,)
        Each joint's channel names in file order.
    channel_start : (J,) int
        Column of each joint's first channel in ``frames``.
    frame_time : float
        Seconds per frame.
    frames : (F, C) float
        The raw motion values as in the file (file units, degrees).
    end_site_parents : (E,) int
        Joint that carries each ``End Site``.
    end_site_offsets : (E, 3) float
        End-site offsets from their joint, metres.
    units_m : float
        Metres per file unit.
    units_source : str
        How ``units_m`` was chosen (given by the caller, or inferred and from what).
    path : str or None
    joint_map : dict or None
        ``{contract joint: file joint name}`` the caller gave (``--joint-map``); the
        joints it does not name are found from the names and the structure.
    """

    joint_names: list
    parents: np.ndarray
    offsets: np.ndarray
    channels: list
    channel_start: np.ndarray
    frame_time: float
    frames: np.ndarray
    end_site_parents: np.ndarray
    end_site_offsets: np.ndarray
    units_m: float
    units_source: str
    path: str | None = None
    joint_map: dict | None = None
    _cache: dict = field(default_factory=dict, repr=False)

    # ------------------------------------------------------------------ basics
    @property
    def n_frames(self) -> int:
        return int(self.frames.shape[0])

    @property
    def n_joints(self) -> int:
        return len(self.joint_names)

    @property
    def fps(self) -> float:
        return 1.0 / self.frame_time

    def __len__(self) -> int:
        return self.n_frames

    def joint_index(self, name: str) -> int:
        """Index of a joint by name, namespace-insensitive (``mixamorig:Hips`` = ``Hips``)."""
        index = self._name_index()
        key = strip_namespace(name)
        if key not in index:
            raise KeyError(name)
        return index[key]

    def _name_index(self) -> dict:
        if "names" not in self._cache:
            self._cache["names"] = {strip_namespace(n): i for i, n in enumerate(self.joint_names)}
        return self._cache["names"]

    def has_joint(self, name: str) -> bool:
        return strip_namespace(name) in self._name_index()

    def children(self, j: int) -> list:
        return [int(c) for c in np.flatnonzero(self.parents == j)]

    # --------------------------------------------------------------- kinematics
    def local_rotations(self) -> np.ndarray:
        """(F, J, 3, 3) float: each joint's rotation relative to its parent."""
        if "rot" not in self._cache:
            F, J = self.n_frames, self.n_joints
            rot = np.broadcast_to(np.eye(3), (F, J, 3, 3)).copy()
            for j, names in enumerate(self.channels):
                col = int(self.channel_start[j])
                for k, ch in enumerate(names):
                    if ch in _ROTATION_CHANNELS:
                        rot[:, j] = rot[:, j] @ axis_rotations(ch[0], self.frames[:, col + k])
            self._cache["rot"] = rot
        return self._cache["rot"]

    def local_translations(self) -> np.ndarray:
        """(F, J, 3) float: offset plus any position channels, metres."""
        if "trans" not in self._cache:
            F = self.n_frames
            trans = np.broadcast_to(self.offsets, (F,) + self.offsets.shape).copy()
            for j, names in enumerate(self.channels):
                col = int(self.channel_start[j])
                for k, ch in enumerate(names):
                    if ch in _POSITION_CHANNELS:
                        axis = _POSITION_CHANNELS.index(ch)
                        trans[:, j, axis] += self.frames[:, col + k] * self.units_m
            self._cache["trans"] = trans
        return self._cache["trans"]

    def root_positions(self) -> np.ndarray:
        """(F, 3) float: the root joint's world position, metres."""
        return self.local_translations()[:, 0].copy()

    def world_transforms(self) -> np.ndarray:
        """(F, J, 4, 4) float: joint frames in the BVH world, metres."""
        if "world" not in self._cache:
            rot, trans = self.local_rotations(), self.local_translations()
            F, J = self.n_frames, self.n_joints
            local = np.zeros((F, J, 4, 4))
            local[..., :3, :3] = rot
            local[..., :3, 3] = trans
            local[..., 3, 3] = 1.0
            world = np.empty_like(local)
            for j in range(J):
                p = self.parents[j]
                world[:, j] = local[:, j] if p < 0 else world[:, p] @ local[:, j]
            self._cache["world"] = world
        return self._cache["world"]

    def joint_positions(self) -> np.ndarray:
        """(F, J, 3) float: joint positions in the BVH world (y up), metres."""
        return self.world_transforms()[..., :3, 3].copy()

    def end_site_positions(self) -> np.ndarray:
        """(F, E, 3) float: end-site positions in the BVH world, metres."""
        world = self.world_transforms()[:, self.end_site_parents]
        return np.einsum("feij,ej->fei", world[..., :3, :3], self.end_site_offsets) + world[..., :3, 3]

    def rest_joint_positions(self) -> np.ndarray:
        """(J, 3) float: joint positions with every channel zero (the rest pose), metres."""
        pos = np.zeros((self.n_joints, 3))
        for j, p in enumerate(self.parents):
            pos[j] = self.offsets[j] + (pos[p] if p >= 0 else 0.0)
        return pos

    # ---------------------------------------------------------- contract joints
    def contract_joint_indices(self) -> dict:
        """How each contract joint is found (:func:`depthtrack.io.bvh.names.map_joints` recipes).

        Raises
        ------
        InputError
            When the skeleton lacks a joint the mapping needs (one line: the joints
            missing, the names looked for, the joints the file has).
        """
        if "contract" not in self._cache:
            self._cache["contract"] = map_joints(self.joint_names, self.parents, self.end_site_parents,
                                                 self.joint_map, self.path)
        return self._cache["contract"]

    def convention(self) -> str:
        """The naming convention of the skeleton's joints, in words (for reports)."""
        from .names import detect_convention
        return detect_convention(self.joint_names)

    def contract_joint_positions(self) -> np.ndarray:
        """(F, 15, 3) float: the contract joints (``JOINT_NAMES`` order) in the BVH world, metres."""
        mapping = self.contract_joint_indices()
        pos = self.joint_positions()
        ends = self.end_site_positions() if len(self.end_site_parents) else None
        out = np.empty((self.n_frames, len(JOINT_NAMES), 3))
        for c, name in enumerate(JOINT_NAMES):
            kind, *args = mapping[name]
            if kind == "joint":
                out[:, c] = pos[:, args[0]]
            elif kind == "mid":
                out[:, c] = 0.5 * (pos[:, args[0]] + pos[:, args[1]])
            elif kind == "midend":
                out[:, c] = 0.5 * (pos[:, args[0]] + ends[:, args[1]])
            elif kind == "eyes":
                # Daz, Reallusion: the head joint is the skull base, with the eyes above it
                # and in front; the head centre is at the eyes' height along the neck.
                head, neck, eyes = pos[:, args[0]], pos[:, args[1]], pos[:, list(args[2:])].mean(axis=1)
                axis = head - neck
                axis /= np.maximum(np.linalg.norm(axis, axis=-1, keepdims=True), 1e-12)
                out[:, c] = head + np.sum((eyes - head) * axis, axis=-1, keepdims=True) * axis
            else:
                out[:, c] = ends[:, args[0]]
        return out

    def leading_jump(self, max_speed: float = 20.0, within_s: float = 1.0) -> int:
        """Frames to drop at the start because the motion teleports out of them.

        Many CMU conversions open with a calibration pose (a T-pose, here standing) that
        the next frame leaves in one step; no body moves a joint faster than ``max_speed``
        m/s (a punching hand peaks near 10). Returns the index of the first frame after the
        last such jump within the first ``within_s`` seconds, or 0 when there is none.
        """
        # The contract joints only: helper bones (Reallusion's knee "share" bones) may
        # flip between frames in a motion that is otherwise smooth.
        try:
            pos = self.contract_joint_positions()
        except InputError:
            pos = self.joint_positions()
        last = min(self.n_frames - 1, int(round(within_s * self.fps)))
        if last < 1:
            return 0
        speed = np.sort(np.linalg.norm(np.diff(pos[:last + 1], axis=0), axis=2), axis=1) * self.fps
        # A calibration pose moves several joints at once (both arms); one joint alone
        # over the limit is a glitch of the data (a Reallusion knee flipping for a frame).
        jumps = np.flatnonzero((speed[:, -1] > max_speed) & (speed[:, -2] > 0.5 * max_speed))
        return int(jumps[-1] + 1) if len(jumps) else 0


