"""READY: BVH motion capture files: reading (CMU, Mixamo, DeepMimic skeletons) and writing.

Conventions
-----------
* A joint's local transform is ``Trans(offset + position channels) @ R`` where ``R``
  is the product of the elementary rotations in the order the ``CHANNELS`` line
  lists them (``Zrotation Yrotation Xrotation`` -> ``Rz @ Ry @ Rx``), angles in
  degrees. World transforms chain from the root: ``W_j = W_parent @ L_j``.
* Every length this module returns is in metres (the file's unit times
  :attr:`BvhMotion.units_m`), in the BVH world frame (y up for the usual files).
* Units are never guessed silently: either the caller names them, or they are
  inferred from the skeleton's size and :attr:`BvhMotion.units_source` says how.
"""
from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..contract import JOINT_NAMES
from ..errors import InputError

#: Metres per file unit for the unit names ``read_bvh(units=...)`` accepts.
UNIT_NAMES = {
    "m": 1.0,
    "cm": 0.01,
    "mm": 0.001,
    "inch": 0.0254,
    "in": 0.0254,
    "cmu": 0.0254 / 0.45,
}

#: The rotation that takes our camera/model frame (y down, z forward) to a y-up
#: BVH world frame (180 degrees about x); it is its own inverse.
BVH_FROM_CAMERA = np.diag([1.0, -1.0, -1.0])

_POSITION_CHANNELS = ("Xposition", "Yposition", "Zposition")
_ROTATION_CHANNELS = ("Xrotation", "Yrotation", "Zrotation")
_KNOWN_CHANNELS = _POSITION_CHANNELS + _ROTATION_CHANNELS

#: Typical standing height of an adult, used only to infer units.
_TYPICAL_HEIGHT_M = 1.7


def _strip_namespace(name: str) -> str:
    """``"mixamorig:LeftArm"`` -> ``"LeftArm"`` (any ``prefix:`` namespace)."""
    return name.rsplit(":", 1)[-1]


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
        key = _strip_namespace(name)
        if key not in index:
            raise KeyError(name)
        return index[key]

    def _name_index(self) -> dict:
        if "names" not in self._cache:
            self._cache["names"] = {_strip_namespace(n): i for i, n in enumerate(self.joint_names)}
        return self._cache["names"]

    def has_joint(self, name: str) -> bool:
        return _strip_namespace(name) in self._name_index()

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
        """How each contract joint is found: ``{name: ("joint", j) | ("mid", j, k) | ("end", e) | ("midend", j, e)}``.

        Raises
        ------
        InputError
            When the skeleton lacks a joint the mapping needs.
        """
        if "contract" in self._cache:
            return self._cache["contract"]

        def find(*names):
            for n in names:
                if self.has_joint(n):
                    return self.joint_index(n)
            return None

        def need(contract_name, *names):
            j = find(*names)
            if j is None:
                raise InputError(self.path, f"BVH skeleton has no joint for {contract_name!r} "
                                            f"(looked for {', '.join(names)})")
            return ("joint", j)

        mapping = {
            "pelvis": need("pelvis", "Hips", "Hip", "Pelvis"),
            "l_shoulder": need("l_shoulder", "LeftArm", "LeftUpArm"),
            "l_elbow": need("l_elbow", "LeftForeArm", "LeftLowArm"),
            "l_wrist": need("l_wrist", "LeftHand"),
            "r_shoulder": need("r_shoulder", "RightArm", "RightUpArm"),
            "r_elbow": need("r_elbow", "RightForeArm", "RightLowArm"),
            "r_wrist": need("r_wrist", "RightHand"),
            "l_hip": need("l_hip", "LeftUpLeg", "LeftThigh"),
            "l_knee": need("l_knee", "LeftLeg", "LeftShin", "LeftLowLeg"),
            "l_ankle": need("l_ankle", "LeftFoot"),
            "r_hip": need("r_hip", "RightUpLeg", "RightThigh"),
            "r_knee": need("r_knee", "RightLeg", "RightShin", "RightLowLeg"),
            "r_ankle": need("r_ankle", "RightFoot"),
        }
        # CMU has Neck (base, on Spine1) and Neck1 (at shoulder level); DeepMimic only
        # Neck1; Mixamo only Neck. The contract neck sits at shoulder level.
        mapping["neck"] = need("neck", "Neck1", "Neck")
        neck = mapping["neck"][1]
        head = find("Head")
        ends = {int(p): e for e, p in enumerate(self.end_site_parents)}
        if head is not None:
            # Head centre: halfway between the skull base (Head) and the top of the head.
            top = find("HeadTop_End", "HeadEnd", "HeadTop")
            if top is not None and self.parents[top] == head:
                mapping["head"] = ("mid", head, top)
            elif head in ends:
                mapping["head"] = ("midend", head, ends[head])
            else:
                mapping["head"] = ("joint", head)
        elif neck in ends:
            # DeepMimic: the neck's end site is the head centre.
            mapping["head"] = ("end", ends[neck])
        else:
            raise InputError(self.path, "BVH skeleton has no Head joint and no end site on the neck")
        self._cache["contract"] = mapping
        return mapping

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
        pos = self.joint_positions()
        last = min(self.n_frames - 1, int(round(within_s * self.fps)))
        if last < 1:
            return 0
        step = np.linalg.norm(np.diff(pos[:last + 1], axis=0), axis=2).max(axis=1)   # (last,)
        jumps = np.flatnonzero(step * self.fps > max_speed)
        return int(jumps[-1] + 1) if len(jumps) else 0


# ---------------------------------------------------------------------- reading
class _Tokens:
    """Whitespace tokens with their 1-based line numbers."""

    def __init__(self, lines, path):
        self.path = path
        self.items = []
        for number, line in enumerate(lines, start=1):
            for tok in line.split():
                self.items.append((tok, number))
        self.pos = 0

    def peek(self):
        return self.items[self.pos][0] if self.pos < len(self.items) else None

    def line(self):
        if self.pos < len(self.items):
            return self.items[self.pos][1]
        return self.items[-1][1] if self.items else 1

    def next(self, what="a token"):
        if self.pos >= len(self.items):
            raise InputError(self.path, f"line {self.line()}: file ends where {what} was expected")
        tok = self.items[self.pos]
        self.pos += 1
        return tok

    def expect(self, word):
        tok, line = self.next(repr(word))
        if tok != word:
            raise InputError(self.path, f"line {line}: expected {word!r}, found {tok!r}")
        return line

    def number(self, what):
        tok, line = self.next(what)
        try:
            value = float(tok)
        except ValueError:
            raise InputError(self.path, f"line {line}: {what} is not a number ({tok!r})") from None
        if not math.isfinite(value):
            raise InputError(self.path, f"line {line}: {what} is not finite ({tok!r})")
        return value


def _parse_hierarchy(tokens: _Tokens):
    names, parents, offsets, channels = [], [], [], []
    end_parents, end_offsets = [], []
    tok, line = tokens.next("'HIERARCHY'")
    if tok != "HIERARCHY":
        raise InputError(tokens.path, f"line {line}: not a BVH file (expected 'HIERARCHY', found {tok!r})")
    tok, line = tokens.next("'ROOT'")
    if tok != "ROOT":
        raise InputError(tokens.path, f"line {line}: expected 'ROOT', found {tok!r}")

    def parse_joint(parent, is_end=False):
        if is_end:
            line = tokens.expect("{")
            tokens.expect("OFFSET")
            off = [tokens.number("End Site offset") for _ in range(3)]
            end_parents.append(parent)
            end_offsets.append(off)
            tokens.expect("}")
            return
        name, line = tokens.next("a joint name")
        if name in ("{", "}"):
            raise InputError(tokens.path, f"line {line}: joint has no name")
        if name in names:
            raise InputError(tokens.path, f"line {line}: joint name {name!r} appears twice")
        j = len(names)
        names.append(name)
        parents.append(parent)
        tokens.expect("{")
        tokens.expect("OFFSET")
        offsets.append([tokens.number(f"OFFSET of {name}") for _ in range(3)])
        chans = ()
        if tokens.peek() == "CHANNELS":
            tokens.next()
            count_tok, count_line = tokens.next("channel count")
            if not count_tok.isdigit():
                raise InputError(tokens.path, f"line {count_line}: channel count is not a whole number ({count_tok!r})")
            chans = []
            for _ in range(int(count_tok)):
                ch, ch_line = tokens.next("a channel name")
                if ch not in _KNOWN_CHANNELS:
                    raise InputError(tokens.path, f"line {ch_line}: unknown channel {ch!r} of {name} "
                                                  f"(CHANNELS says {count_tok})")
                chans.append(ch)
            chans = tuple(chans)
        channels.append(chans)
        while True:
            tok, line = tokens.next(f"'}}' closing {name}")
            if tok == "}":
                return
            if tok == "JOINT":
                parse_joint(j)
            elif tok.lower() == "end":
                site, site_line = tokens.next("'Site'")
                if site.lower() != "site":
                    raise InputError(tokens.path, f"line {site_line}: expected 'Site', found {site!r}")
                parse_joint(j, is_end=True)
            else:
                raise InputError(tokens.path, f"line {line}: unexpected {tok!r} inside joint {name}")

    parse_joint(-1)
    return names, parents, offsets, channels, end_parents, end_offsets


def _infer_units(rest_positions, end_positions, names):
    """Metres per unit from the skeleton's size; returns (units_m, text)."""
    pts = np.concatenate([rest_positions, end_positions]) if len(end_positions) else rest_positions
    # Prefer the leg length (hip -> knee -> ankle): it does not depend on the rest pose
    # of the arms; fall back to the skeleton's extent along its longest axis.
    index = {_strip_namespace(n): i for i, n in enumerate(names)}
    chain = [index.get(n) for n in ("LeftUpLeg", "LeftLeg", "LeftFoot")]
    if None not in chain:
        leg = (np.linalg.norm(rest_positions[chain[1]] - rest_positions[chain[0]])
               + np.linalg.norm(rest_positions[chain[2]] - rest_positions[chain[1]]))
        size, what, typical = leg, "leg (hip to ankle)", 0.245 * _TYPICAL_HEIGHT_M * 2.0  # ~0.83 m
    else:
        size = float(np.max(pts.max(axis=0) - pts.min(axis=0)))
        what, typical = "rest-pose extent", _TYPICAL_HEIGHT_M
    if not size > 0:
        raise InputError(None, "cannot infer BVH units: the skeleton has zero size; give units")
    candidates = ("m", "cm", "mm", "inch", "cmu")
    errors = [abs(math.log(size * UNIT_NAMES[c] / typical)) for c in candidates]
    best = candidates[int(np.argmin(errors))]
    units = UNIT_NAMES[best]
    text = (f"inferred from the skeleton's size: {what} is {size:.4g} units, which as "
            f"'{best}' ({units:.6g} m/unit) is {size * units:.3f} m")
    return units, text


def _resolve_units(units, path):
    if isinstance(units, str):
        key = units.strip().lower()
        if key in UNIT_NAMES:
            return UNIT_NAMES[key], f"given: '{key}' ({UNIT_NAMES[key]:.6g} m/unit)"
        try:
            value = float(key)
        except ValueError:
            raise InputError(path, f"unknown BVH units {units!r}; use metres per unit or one of "
                                   f"{', '.join(sorted(UNIT_NAMES))}") from None
    else:
        value = float(units)
    if not (math.isfinite(value) and 1e-6 <= value <= 100):
        raise InputError(path, f"BVH units must be a positive number of metres per unit (1e-06 to 100), not {units!r}")
    return value, f"given: {value:.6g} m/unit"


def read_bvh(path, units=None) -> BvhMotion:
    """Read a BVH file.

    Parameters
    ----------
    path : str or os.PathLike
    units : float or str or None
        Metres per file unit, or a name in :data:`UNIT_NAMES` (``"cmu"``, ``"m"``,
        ``"cm"``, ``"mm"``, ``"inch"``); ``None`` infers it from the skeleton's size
        (see ``motion.units_source``).

    Returns
    -------
    BvhMotion

    Raises
    ------
    InputError
        Unreadable or malformed file (with the line number), a frame count that
        disagrees with the ``Frames:`` header, non-finite values.
    """
    path = os.fspath(path)
    try:
        text = Path(path).read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise InputError(path, f"cannot read BVH file ({exc.strerror or exc})") from None
    lines = text.splitlines()
    motion_line = next((i for i, l in enumerate(lines) if l.strip() == "MOTION"), None)
    if motion_line is None:
        if not text.strip():
            raise InputError(path, "empty BVH file")
        if not text.lstrip().startswith("HIERARCHY"):
            raise InputError(path, "line 1: not a BVH file (expected 'HIERARCHY')")
        raise InputError(path, f"line {len(lines)}: no MOTION section")

    tokens = _Tokens(lines[:motion_line], path)
    names, parents, offsets, channels, end_parents, end_offsets = _parse_hierarchy(tokens)
    if tokens.peek() is not None:
        tok, line = tokens.next()
        raise InputError(path, f"line {line}: unexpected {tok!r} after the hierarchy "
                               f"(more than one ROOT?)")

    # Header lines "Frames: N" and "Frame Time: t".
    def header(index, label):
        if index >= len(lines):
            raise InputError(path, f"line {index + 1}: file ends where '{label}' was expected")
        line = lines[index].strip()
        match = re.fullmatch(rf"{label}\s*(\S+)", line)
        if not match:
            raise InputError(path, f"line {index + 1}: expected '{label} ...', found {line[:40]!r}")
        return match.group(1)

    frames_text = header(motion_line + 1, "Frames:")
    if not frames_text.isdigit():
        raise InputError(path, f"line {motion_line + 2}: frame count is not a whole number ({frames_text!r})")
    n_frames = int(frames_text)
    time_text = header(motion_line + 2, "Frame Time:")
    try:
        frame_time = float(time_text)
    except ValueError:
        raise InputError(path, f"line {motion_line + 3}: frame time is not a number ({time_text!r})") from None
    if not (math.isfinite(frame_time) and frame_time > 0):
        raise InputError(path, f"line {motion_line + 3}: frame time must be positive, not {time_text}")

    n_channels = sum(len(c) for c in channels)
    first = motion_line + 3
    body = lines[first:]
    while body and not body[-1].strip():
        body.pop()
    counts = np.fromiter((len(l.split()) for l in body), dtype=int, count=len(body))
    bad = np.flatnonzero(counts != n_channels)
    if len(bad):
        i = int(bad[0])
        raise InputError(path, f"line {first + i + 1}: motion line has {counts[i]} values, "
                               f"the hierarchy has {n_channels} channels")
    if len(body) != n_frames:
        raise InputError(path, f"frame count mismatch: header says {n_frames} frames, "
                               f"the file has {len(body)} motion lines")
    if n_frames == 0:
        raise InputError(path, "BVH file has no frames")
    try:
        values = np.array(" ".join(body).split(), dtype=float)
    except ValueError:
        for i, l in enumerate(body):
            try:
                np.array(l.split(), dtype=float)
            except ValueError:
                raise InputError(path, f"line {first + i + 1}: motion line holds a value that is "
                                       f"not a number") from None
        raise
    frames = values.reshape(n_frames, n_channels)
    if not np.all(np.isfinite(frames)):
        i = int(np.flatnonzero(~np.all(np.isfinite(frames), axis=1))[0])
        raise InputError(path, f"line {first + i + 1}: motion line holds a non-finite value")

    offsets_u = np.asarray(offsets, float).reshape(-1, 3)
    end_offsets_u = np.asarray(end_offsets, float).reshape(-1, 3)
    parents_a = np.asarray(parents, dtype=int)
    if units is None:
        rest = np.zeros_like(offsets_u)
        for j, p in enumerate(parents_a):
            rest[j] = offsets_u[j] + (rest[p] if p >= 0 else 0.0)
        ends = rest[np.asarray(end_parents, int)] + end_offsets_u if end_parents else np.zeros((0, 3))
        try:
            units_m, source = _infer_units(rest, ends, names)
        except InputError as exc:
            raise InputError(path, exc.problem) from None
    else:
        units_m, source = _resolve_units(units, path)

    starts = np.cumsum([0] + [len(c) for c in channels])[:-1].astype(int)
    return BvhMotion(
        joint_names=list(names),
        parents=parents_a,
        offsets=offsets_u * units_m,
        channels=list(channels),
        channel_start=starts,
        frame_time=frame_time,
        frames=frames,
        end_site_parents=np.asarray(end_parents, dtype=int),
        end_site_offsets=end_offsets_u * units_m,
        units_m=units_m,
        units_source=source,
        path=path,
    )


# ---------------------------------------------------------------------- writing
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
    from ..contract import JOINT_INDEX as CONTRACT

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
    from ..body.rotations import rotvec_to_matrix
    from .atomic import write_text_atomic

    poses = np.atleast_2d(np.asarray(poses, dtype=float))
    names = list(body.joint_names)
    parents = np.asarray(body.parents)
    J = len(names)
    if poses.ndim != 2 or poses.shape[1] != 6 + 3 * (J - 1):
        raise ValueError(f"poses must be (F, {6 + 3 * (J - 1)}), not {poses.shape}")
    if not np.all(np.isfinite(poses)):
        raise ValueError("poses hold non-finite values")
    C = BVH_FROM_CAMERA
    offsets = np.asarray(body.offsets, float) @ C.T / units_m
    ends = {j: (C @ e) / units_m for j, e in body_end_sites(body).items()}
    F = poses.shape[0]
    rot = rotvec_to_matrix(poses[:, 3:].reshape(F, J, 3))
    rot_bvh = C @ rot @ C                      # C is its own inverse
    euler = np.unwrap(matrix_to_euler(rot_bvh, "ZYX"), period=360.0, axis=0)
    root = poses[:, :3] @ C.T / units_m

    children = [[] for _ in range(J)]
    for j, p in enumerate(parents):
        if p >= 0:
            children[p].append(j)
    lines = ["HIERARCHY"]

    def emit(j, depth):
        pad = "\t" * depth
        bvh_name = BODY_BVH_NAMES.get(names[j], names[j])
        lines.append(f"{pad}{'ROOT' if parents[j] < 0 else 'JOINT'} {bvh_name}")
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
    order = []

    def walk(j):
        order.append(j)
        for c in children[j]:
            walk(c)

    walk(int(np.flatnonzero(parents < 0)[0]))
    columns = []
    for j in order:
        if parents[j] < 0:
            columns.append(root)
        columns.append(euler[:, j])
    table = np.concatenate(columns, axis=1)
    lines += ["MOTION", f"Frames: {F}", f"Frame Time: {1.0 / fps:.8f}"]
    lines += [_fmt(row) for row in table]
    write_text_atomic(path, "\n".join(lines) + "\n")
