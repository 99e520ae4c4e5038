"""The body-part classes of the per-pixel recogniser and how they are cut from the skin.

The renderer labels each visible pixel with the skeleton joint whose skinning weight
dominates there (:meth:`depthtrack.render.FrameRenderer.render_labels`: the bone from that
joint to its child). :func:`part_labels` cuts those bones into :data:`BODY_PARTS`, which
are centred on the contract joints (as Shotton et al.'s parts are) so that a mode of a
part's pixels lies next to its joint:

* ``head``, ``neck``: the neck bone beyond / before 35 % of the way from the neck joint to
  the head centre.
* ``l_/r_upper_torso``: the chest (spine bone), ``l_/r_lower_torso``: the pelvis bone,
  each split at the body's mid-plane (the subject's own left is ``l_``).
* ``l_shoulder``: the upper arm's proximal half plus the chest within
  :data:`JOINT_RADIUS` of the shoulder joint; ``l_elbow``: the upper arm's distal half and
  the forearm's proximal half; ``l_hand``: the forearm's distal half and the hand (centred
  on the wrist).
* ``l_hip``: the thigh's proximal half plus the pelvis bone within :data:`JOINT_RADIUS` of
  the hip joint; ``l_knee``: the thigh's distal half and the shin's proximal half;
  ``l_foot``: the shin's distal half and the foot (centred on the ankle).

:data:`JOINT_PARTS` names the parts whose pixels propose each contract joint.
"""
from __future__ import annotations

import numpy as np

from ..body.skeleton import JOINT_ID
from ..contract import JOINT_NAMES

#: The recogniser's per-pixel classes (index = class id; -1 = background). Separate from
#: the extremum classifier's ``PART_CLASSES`` (head / hand / foot).
BODY_PARTS = (
    "head", "neck",
    "l_upper_torso", "r_upper_torso", "l_lower_torso", "r_lower_torso",
    "l_shoulder", "l_elbow", "l_hand",
    "r_shoulder", "r_elbow", "r_hand",
    "l_hip", "l_knee", "l_foot",
    "r_hip", "r_knee", "r_foot",
)
PART_ID = {name: i for i, name in enumerate(BODY_PARTS)}
NUM_PARTS = len(BODY_PARTS)

#: Contract joint (``JOINT_NAMES`` order) -> the parts whose pixels vote for it.
JOINT_PARTS = {
    "head": ("head",), "neck": ("neck",), "pelvis": ("l_lower_torso", "r_lower_torso"),
    "l_shoulder": ("l_shoulder",), "l_elbow": ("l_elbow",), "l_wrist": ("l_hand",),
    "r_shoulder": ("r_shoulder",), "r_elbow": ("r_elbow",), "r_wrist": ("r_hand",),
    "l_hip": ("l_hip",), "l_knee": ("l_knee",), "l_ankle": ("l_foot",),
    "r_hip": ("r_hip",), "r_knee": ("r_knee",), "r_ankle": ("r_foot",),
}
assert tuple(JOINT_PARTS) == JOINT_NAMES

#: Chest / pelvis surface within this distance (m, for a 1.75 m body) of a shoulder / hip
#: joint belongs to that joint's part.
JOINT_RADIUS = 0.09
#: Fraction of the neck-to-head-centre segment below which the neck bone is "neck".
NECK_FRACTION = 0.35

# limb bone (skeleton joint) -> (part before the bone's midpoint, part after it)
_LIMB_HALVES = {}
for _s in ("l", "r"):
    _LIMB_HALVES.update({
        f"{_s}_shoulder": (f"{_s}_shoulder", f"{_s}_elbow"),
        f"{_s}_elbow": (f"{_s}_elbow", f"{_s}_hand"),
        f"{_s}_wrist": (f"{_s}_hand", f"{_s}_hand"),
        f"{_s}_hip": (f"{_s}_hip", f"{_s}_knee"),
        f"{_s}_knee": (f"{_s}_knee", f"{_s}_foot"),
        f"{_s}_ankle": (f"{_s}_foot", f"{_s}_foot"),
    })
_CHILD = {"l_shoulder": "l_elbow", "l_elbow": "l_wrist", "r_shoulder": "r_elbow", "r_elbow": "r_wrist",
          "l_hip": "l_knee", "l_knee": "l_ankle", "r_hip": "r_knee", "r_knee": "r_ankle"}


def part_labels(bone_labels, points, transforms, head, scale: float = 1.0) -> np.ndarray:
    """Cut a bone-label image into :data:`BODY_PARTS`.

    Parameters
    ----------
    bone_labels : (H, W) int
        Skeleton joint index (``depthtrack.body.skeleton.JOINTS``) per pixel, -1 = not the body.
    points : (H, W, 3) float
        The visible surface point of every pixel (camera frame; the ideal depth back-projected).
    transforms : (15, 4, 4) float
        Joint-to-camera transforms of the pose (``BodyModel.world_transforms``).
    head : (3,) float
        Head centre (the contract ``head`` joint), camera frame.
    scale : float
        Body height / 1.75 (scales :data:`JOINT_RADIUS`).

    Returns
    -------
    (H, W) int8
        Part index per pixel, -1 = background.
    """
    bone = np.asarray(bone_labels)
    out = np.full(bone.shape, -1, np.int8)
    pos = transforms[:, :3, 3]
    radius = JOINT_RADIUS * scale

    def along(mask, a, b):
        d = b - a
        return ((points[mask] - a) @ d) / max(float(d @ d), 1e-12)

    # head / neck
    m = bone == JOINT_ID["neck"]
    t = along(m, pos[JOINT_ID["neck"]], np.asarray(head, float))
    out[m] = np.where(t < NECK_FRACTION, PART_ID["neck"], PART_ID["head"])
    # torso halves, then the surface around shoulders and hips
    for joint, level, near in (("spine", "upper", ("l_shoulder", "r_shoulder")),
                               ("pelvis", "lower", ("l_hip", "r_hip"))):
        m = bone == JOINT_ID[joint]
        R, o = transforms[JOINT_ID[joint], :3, :3], pos[JOINT_ID[joint]]
        lateral = (points[m] - o) @ R[:, 0]           # model frame: the subject's left is +x
        lab = np.where(lateral > 0, PART_ID[f"l_{level}_torso"], PART_ID[f"r_{level}_torso"])
        for name in near:
            close = np.linalg.norm(points[m] - pos[JOINT_ID[name]], axis=1) < radius
            lab[close] = PART_ID[name]
        out[m] = lab
    # limbs: halves of each bone
    for joint, (before, after) in _LIMB_HALVES.items():
        m = bone == JOINT_ID[joint]
        if joint in _CHILD:
            t = along(m, pos[JOINT_ID[joint]], pos[JOINT_ID[_CHILD[joint]]])
            out[m] = np.where(t < 0.5, PART_ID[before], PART_ID[after])
        else:
            out[m] = PART_ID[before]
    return out


def mirror_parts() -> np.ndarray:
    """(NUM_PARTS,) int: the index of each part's left/right twin (itself when central)."""
    out = np.arange(NUM_PARTS)
    for i, name in enumerate(BODY_PARTS):
        for a, b in (("l_", "r_"), ("r_", "l_")):
            if name.startswith(a):
                out[i] = PART_ID[b + name[2:]]
    return out

