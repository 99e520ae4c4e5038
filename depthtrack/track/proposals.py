"""Stage "propose": the part recogniser's joint proposals, and what the tracker does with them.

The per-pixel recogniser (:mod:`depthtrack.detect.recognizer`, after Shotton et al. 2011)
proposes up to three 3D positions per joint from the frame alone, with no previous pose.
Its sides are unreliable (left and right at about chance: a depth image hardly tells front
from back), its trunk joints are good (head, neck, pelvis and the shoulders within 10 cm
most of the time, whatever the body's orientation). So the tracker uses them side-free:

* **Start** (:func:`proposal_candidates`): poses fitted to the proposals, with the sides as
  labelled and exchanged, join the global search's candidates -- a start in any orientation
  (lying, upside down), confirmed by the likelihood.
* **Evidence** (:func:`proposal_detections`): the limb joints' proposals (elbows, knees,
  ...) join the association stage as detections of their joint's class, side-free, so
  evidence propagation can pull a lost elbow or knee back (:mod:`.association`).
* **Judge** (:func:`disagreement`): the share of the confident trunk proposals that no
  joint of the pose comes near. A track whose silhouette still fits but whose body is upside
  down, or turned into the wrong limb arrangement, explains the depth about as well as the
  right one; the proposals disagree with it, frame after frame.
"""
from __future__ import annotations

import numpy as np

from ..contract import JOINT_INDEX, JOINT_NAMES
from ..detect.parts import Detection
from .twins import (ARMS_SWAPPED, LEGS_SWAPPED, SIDES_SWAPPED, TRUNK_ROOT_JOINTS, fit_joints,
                    root_from_joints)

#: Joints the judge checks: the recogniser finds them reliably, side-free.
TRUNK = ("head", "neck", "pelvis", "l_shoulder", "r_shoulder")
TRUNK_INDEX = np.array([JOINT_INDEX[n] for n in TRUNK])
#: Joints that fix the root of a pose fitted to proposals (Kabsch): the trunk's.
ROOT_JOINTS = np.asarray(TRUNK_ROOT_JOINTS)
#: Joint classes whose proposals may feed evidence propagation -> the parts (joint-centre
#: parts of :class:`~.evidence.PartModel`) a proposal of that class may be, either side.
JOINT_CLASSES = {c: ("l_" + c, "r_" + c) for c in ("shoulder", "elbow", "wrist", "hip", "knee", "ankle")}
#: Proposals of one class closer than this (m) are one mode (a left joint holds its right
#: twin's modes too).
SAME_MODE = 0.01


def frame_proposals(tracker, frame):
    """The recogniser's :class:`~depthtrack.detect.recognizer.JointProposals` for ``frame``
    (computed once, then kept on it); None when the tracker runs without the recogniser."""
    if tracker.forest is None:
        return None
    if frame.proposals is None:
        from ..detect.recognizer import joint_proposals, recognize

        with tracker.recorder.timed("propose"):
            _, probs = recognize(frame.depth, frame.foreground.mask, tracker.camera,
                                 forest=tracker.forest)
            frame.proposals = joint_proposals(frame.depth, probs, tracker.camera,
                                              forest=tracker.forest)
    return frame.proposals


def hip_angle(neck, pelvis, l_knee, r_knee):
    """Degrees between pelvis-to-neck and pelvis-to-knees' midpoint: ``(..., 3)`` each ->
    ``(...)``; about 180 standing straight, about 90 folded at the hips or seated (the knees'
    midpoint is side-free)."""
    up = np.asarray(neck, dtype=np.float64) - pelvis
    down = 0.5 * (np.asarray(l_knee, dtype=np.float64) + r_knee) - pelvis
    cos = np.sum(up * down, axis=-1) / (np.linalg.norm(up, axis=-1) * np.linalg.norm(down, axis=-1))
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def proposal_hip_angle(proposals):
    """:func:`hip_angle` of the most confident proposal of neck, pelvis and each knee; None
    where one of them has no proposal. The recogniser's trunk is reliable and a knee's side
    does not matter here, so this tells a body folded at the hips from a straight one without
    fitting a pose (the start's bend gate, :attr:`~.start_settings.StartSettings.bend_hip_angle`)."""
    pos, usable = confident(proposals, np.finfo(np.float64).tiny)     # any confidence above 0
    conf = np.asarray(proposals.confidence, dtype=np.float64)
    tops = []
    for name in ("neck", "pelvis", "l_knee", "r_knee"):
        j = JOINT_INDEX[name]
        if not usable[j].any():
            return None
        tops.append(pos[j, int(np.argmax(np.where(usable[j], conf[j], -1.0)))])
    return float(hip_angle(*tops))


def confident(proposals, min_confidence: float):
    """``(positions (15, k, 3), usable (15, k) bool)``: proposals at least ``min_confidence``."""
    pos = np.asarray(proposals.positions, dtype=np.float64)
    ok = (np.asarray(proposals.confidence) >= min_confidence) & np.all(np.isfinite(pos), axis=2)
    return pos, ok


def disagreement(joints, proposals, min_confidence: float, distance: float,
                 joint_ids=TRUNK_INDEX):
    """How far a pose's joints are from the frame's proposals, side-free.

    Parameters
    ----------
    joints : (N, 15, 3) or (15, 3) float
        The poses' contract joints.
    proposals : JointProposals
        A left joint's proposals hold its right twin's modes too (``merge_sides``), so the
        nearest of them matches the joint whichever side the recogniser gave it.
    min_confidence, distance : float
        Proposals below ``min_confidence`` are ignored; a joint farther than ``distance`` (m)
        from every usable proposal of its own disagrees.

    Returns
    -------
    fraction : (N,) or () float
        Share of the checked joints with a usable proposal that disagree (0 when none has one).
    checked : int
        Joints with a usable proposal.
    """
    J = np.asarray(joints, dtype=np.float64)
    single = J.ndim == 2
    J = J[None] if single else J
    pos, ok = confident(proposals, min_confidence)
    ids = np.asarray(joint_ids)
    has = ok[ids].any(axis=1)                                     # (n,)
    if not has.any():
        out = np.zeros(len(J))
        return (out[0] if single else out), 0
    ids = ids[has]
    d = np.linalg.norm(J[:, ids, None, :] - pos[ids][None], axis=3)   # (N, n, k)
    d = np.where(ok[ids][None], d, np.inf).min(axis=2)
    fraction = np.mean(d > distance, axis=1)
    return (fraction[0] if single else fraction), int(len(ids))


def pose_from_joints(body, target, weights):
    """A pose ``(48,)`` whose joints match ``target (15, 3)`` where ``weights (15,) > 0``:
    the root by Kabsch on the trunk joints, then Levenberg-Marquardt on every joint
    (:func:`~.twins.fit_joints`). None with fewer than three trunk joints known."""
    w = np.asarray(weights, dtype=np.float64)
    root = ROOT_JOINTS[w[ROOT_JOINTS] > 0]
    if len(root) < 3:
        return None
    x0 = root_from_joints(body, target, root)
    return fit_joints(body, np.where(w[:, None] > 0, target, 0.0), x0, weights=w)


#: The side assignments tried: as labelled, all exchanged, only the legs, only the arms.
SIDE_ORDERS = (np.arange(len(JOINT_NAMES)), np.asarray(SIDES_SWAPPED), np.asarray(LEGS_SWAPPED),
               np.asarray(ARMS_SWAPPED))


def proposal_candidates(body, proposals, min_confidence: float):
    """Start candidates from the proposals: ``(K, 48)`` poses fitted to each joint's best
    proposal, with the sides as the recogniser labelled them, all exchanged, and only the
    legs' or only the arms' exchanged (its sides are at chance; K <= 4)."""
    if proposals is None:
        return np.zeros((0, body.dof))
    pos, ok = confident(proposals, min_confidence)
    target = np.where(ok[:, :1], pos[:, 0], 0.0)                        # (15, 3)
    weights = ok[:, 0].astype(np.float64)
    out = []
    for order in SIDE_ORDERS:
        x = pose_from_joints(body, target[order], weights[order])
        if x is not None:
            out.append(x)
    return np.array(out).reshape(-1, body.dof)


def proposal_detections(proposals, classes, min_confidence: float) -> list:
    """The proposals of the joint ``classes`` as side-free detections for the association.

    Parameters
    ----------
    proposals : JointProposals or None
        ``positions (15, k, 3)``, ``confidence (15, k)``.
    classes : sequence of str
        Keys of :data:`JOINT_CLASSES` (``"elbow"``, ``"knee"``, ...).
    min_confidence : float
        Proposals below this (m^2) are left out.

    Returns
    -------
    list of Detection
        ``label`` the class, ``position`` the mode (a joint centre), ``score`` the summed
        confidence of both sides' proposals at that mode (m^2), ``source`` "recognizer";
        per class, the modes of the left and the right joint merged (within
        :data:`SAME_MODE`), most confident first.
    """
    if proposals is None:
        return []
    pos, ok = confident(proposals, min_confidence)
    conf = np.asarray(proposals.confidence, dtype=np.float64)
    out = []
    for c in classes:
        modes, scores = [], []
        for name in JOINT_CLASSES[c]:
            j = JOINT_INDEX[name]
            for p, w in zip(pos[j][ok[j]], conf[j][ok[j]]):
                near = [i for i, m in enumerate(modes) if np.linalg.norm(m - p) < SAME_MODE]
                if near:
                    scores[near[0]] += w
                else:
                    modes.append(p.copy())
                    scores.append(float(w))
        for i in np.argsort(-np.asarray(scores), kind="stable"):
            out.append(Detection(c, modes[i], np.zeros(3), np.array([-1, -1]), float(scores[i]),
                                 tip=modes[i].copy(), source="recognizer"))
    return out
