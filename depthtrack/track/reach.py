"""Reaching for a lost hand or foot: limbs re-fitted to the recogniser's far proposals.

Evidence propagation pulls a limb toward detections near where the pose has it (the
association prunes the rest), so a limb that has settled far from where it is -- a raised
forearm tracked pointing sideways, a foot behind the other leg -- stays there, while the
recogniser finds the hand within centimetres (dev: 01_08 on Azure NFOV from 240 degrees,
seed 3, the right wrist 31-46 cm off for the second half of the clip with a wrist proposal
1-8 cm from the truth on every frame looked at). So every
:attr:`~.settings.ProposalSettings.reach_every` frames each limb is also tried reaching to
the wrist or ankle proposals it could reach and that no hand (or foot) of the pose is at
(either side's: the recogniser's sides are at chance), its middle joint left to the fit or
placed at a proposal of its own class; the candidates are scored in one batch, the best is
climbed like the tracked pose, and it replaces the pose when its energy without the motion
prior is lower by :attr:`~.settings.ProposalSettings.reach_margin` (a fraction).

Where the recogniser sees no hand, the person's pixels the pose leaves unexplained can
(:attr:`~.settings.ProposalSettings.reach_unexplained`): a limb tracked hidden behind the
body, where it costs nothing, while the real one is raised in plain view, leaves a
limb-shaped blob of the person uncovered (dev: 90_05 seed 1, a jump kick on SR4000,
frames 18-34: an arm's worth of person pixels uncovered on every frame, no wrist
proposal). Each large enough blob (:func:`unexplained_blobs`) offers each limb its point
farthest from the limb's root within reach as one more end to reach to
(:func:`blob_reach_candidates`); the same energy test decides.
"""
from __future__ import annotations

import cv2
import numpy as np

from ..contract import JOINT_INDEX
from .energy import relative_lead
from .heading import due
from .twins import fit_joints
from .proposals import JOINT_CLASSES, confident

#: Each limb: (root, middle, end) joints.
LIMBS = {"l_arm": ("l_shoulder", "l_elbow", "l_wrist"),
         "r_arm": ("r_shoulder", "r_elbow", "r_wrist"),
         "l_leg": ("l_hip", "l_knee", "l_ankle"), "r_leg": ("r_hip", "r_knee", "r_ankle")}
#: Slack (m) on a limb's length when asking whether it can reach a proposal, and on a bone's
#: when asking whether a middle-joint proposal fits between root and end.
REACH_SLACK = 0.05


def _class_ids(name):
    """Both sides' contract indices of ``name``'s joint class (:data:`.proposals.JOINT_CLASSES`)."""
    return [JOINT_INDEX[n] for n in JOINT_CLASSES[name[2:]]]


def _class_proposals(pos, ok, name):
    """``(k, 3)``: the usable proposals of ``name``'s class, both sides' (``pos (15, k, 3)``,
    ``ok (15, k)`` from :func:`.proposals.confident`)."""
    ids = _class_ids(name)
    return pos[ids][ok[ids]].reshape(-1, 3)


def _end_at(body, pose, target, mid):
    """``pose (48,)`` fitted to the joints ``target (15, 3)`` with joint ``mid`` left free."""
    weights = np.ones(len(target))
    weights[mid] = 0.0
    return fit_joints(body, target, pose, weights=weights)


def reach_candidates(body, pose, proposals, min_confidence: float, near: float = 0.1):
    """Poses with one limb re-fitted to a proposal of its end joint's class.

    Parameters
    ----------
    body : BodyModel
    pose : (48,) float
        The tracked pose.
    proposals : JointProposals or None
        The frame's (:func:`.proposals.frame_proposals`).
    min_confidence : float
        Proposals below this (m^2) are left out.
    near : float
        A proposal within this (m) of the limb's end joint, or of the other side's, is
        already explained.

    Returns
    -------
    poses : (K, 48) float
        For each limb and each end-joint proposal within its reach (root joint to proposal
        at most the limb's length plus :data:`REACH_SLACK`) and farther than ``near`` from
        both ends of the limb's class: the pose fitted (:func:`~.twins.fit_joints`, from
        ``pose``) with every other joint kept and the end at the proposal, the middle joint
        free, and once more with the middle joint at each of its class's proposals that fits
        between.
    limbs : list of str
        Each candidate's limb (:data:`LIMBS` key).
    """
    if proposals is None:
        return np.zeros((0, len(pose))), []
    pose = np.asarray(pose, dtype=np.float64)
    joints = np.asarray(body.joint_positions(pose))
    rest = np.asarray(body.joint_positions(np.zeros(len(pose))))
    pos, ok = confident(proposals, min_confidence)
    out, limbs = [], []
    for limb, names in LIMBS.items():
        root, mid, end = (JOINT_INDEX[n] for n in names)
        upper = float(np.linalg.norm(rest[mid] - rest[root]))
        lower = float(np.linalg.norm(rest[end] - rest[mid]))
        ends = _class_proposals(pos, ok, names[2])
        mids = _class_proposals(pos, ok, names[1])
        both_ends = joints[_class_ids(names[2])]
        for p in ends:
            if (np.linalg.norm(both_ends - p, axis=1).min() < near
                    or np.linalg.norm(p - joints[root]) > upper + lower + REACH_SLACK):
                continue
            target = joints.copy()
            target[end] = p
            out.append(_end_at(body, pose, target, mid))
            limbs.append(limb)
            for m in mids:
                if (abs(np.linalg.norm(m - joints[root]) - upper) < REACH_SLACK
                        and abs(np.linalg.norm(p - m) - lower) < REACH_SLACK):
                    target[mid] = m
                    out.append(fit_joints(body, target, pose))
                    limbs.append(limb)
    return np.array(out).reshape(-1, len(pose)), limbs


def unexplained_blobs(model_depth, person_depth, camera, min_pixels: int, gap: float = 0.1,
                      max_blobs: int = 3) -> list:
    """The person's pixels a pose leaves unexplained, in connected blobs, as 3D points.

    Parameters
    ----------
    model_depth : (H, W) float
        The pose rendered (camera z, metres), 0 where nothing is drawn.
    person_depth : (H, W) float
        The person's observed depth on the same pixels, 0 elsewhere and where the camera
        read nothing.
    camera : Camera
        Of those pixels.
    min_pixels : int
        Smaller blobs are left out.
    gap : float
        A person pixel the model covers but lies behind by more than this (m) is
        unexplained too: an arm in front of the body where the model has the body.
    max_blobs : int

    Returns
    -------
    list of (n_i, 3) float
        Camera-frame points of each blob, the largest first.
    """
    model = np.asarray(model_depth, dtype=np.float64)
    person = np.asarray(person_depth, dtype=np.float64)
    miss = (person > 0) & ((model <= 0) | (model > person + gap))
    _, labels, stats, _ = cv2.connectedComponentsWithStats(miss.astype(np.uint8), connectivity=8)
    areas = stats[1:, cv2.CC_STAT_AREA]
    out = []
    for k in np.argsort(-areas, kind="stable")[:max_blobs] + 1:
        if stats[k, cv2.CC_STAT_AREA] < max(1, min_pixels):
            break
        v, u = np.nonzero(labels == k)
        out.append(camera.backproject(person[v, u], np.stack([u, v], axis=1)))
    return out


def share_in_pixels(mask, share: float) -> int:
    """The fewest pixels that make the fraction ``share`` of ``mask``'s (``(H, W)`` bool; at
    least one where ``share`` > 0 and the mask has any): the threshold of
    :func:`hidden_limbs` and :func:`unexplained_blobs` given as a share of the person."""
    return int(np.ceil(share * np.count_nonzero(mask)))


def hidden_limbs(labels, person, joint_names, min_pixels: int) -> set:
    """The limbs whose lower segment (forearm and hand, shin and foot) shows on fewer than
    ``min_pixels`` of the person's pixels: hidden behind the body or off the person.

    Parameters
    ----------
    labels : (H, W) int
        The pose's part labels (:meth:`depthtrack.render.FrameRenderer.render_labels`:
        index into ``joint_names``, -1 none).
    person : (H, W) bool
        The person's pixels.
    joint_names : sequence of str
    min_pixels : int

    Returns
    -------
    set of str
        :data:`LIMBS` keys.
    """
    labels = np.asarray(labels)[np.asarray(person, bool)]
    index = {n: i for i, n in enumerate(joint_names)}
    out = set()
    for limb, (_, mid, end) in LIMBS.items():
        shown = np.count_nonzero((labels == index[mid]) | (labels == index[end]))
        if shown < min_pixels:
            out.add(limb)
    return out


def far_side_limbs(joints, within_deg: float) -> set:
    """The limbs on the far side of a body the camera sees from the side: where the line
    from one shoulder to the other (one hip to the other) points within ``within_deg`` of
    the ray from the camera to its middle, the arm (leg) whose root lies farther from the
    camera. Unlike :func:`hidden_limbs` it asks the trunk, not the limb, so a limb cannot
    vanish into it by being tracked out of sight.

    Parameters
    ----------
    joints : (15, 3) float
        Joint positions in camera coordinates (the camera at the origin),
        :data:`depthtrack.contract.JOINT_NAMES` order.
    within_deg : float
        How far from a pure side view (degrees) the trunk may face.

    Returns
    -------
    set of str
        :data:`LIMBS` keys.
    """
    x = np.asarray(joints, dtype=np.float64)
    least = np.cos(np.radians(within_deg))
    out = set()
    for root, kind in (("shoulder", "arm"), ("hip", "leg")):
        left, right = x[JOINT_INDEX[f"l_{root}"]], x[JOINT_INDEX[f"r_{root}"]]
        line, ray = left - right, 0.5 * (left + right)
        norms = np.linalg.norm(line) * np.linalg.norm(ray)
        if norms > 0 and abs(float(line @ ray)) / norms >= least:
            out.add(f"l_{kind}" if np.linalg.norm(left) > np.linalg.norm(right) else f"r_{kind}")
    return out


def blob_reach_candidates(body, pose, blobs, near: float = 0.1, limbs_free=None):
    """Poses with one limb re-fitted to reach into an unexplained blob.

    Parameters
    ----------
    body : BodyModel
    pose : (48,) float
    blobs : list of (n_i, 3) float
        :func:`unexplained_blobs`.
    near : float
        As in :func:`reach_candidates`.
    limbs_free : set of str or None
        Only these limbs reach (:func:`hidden_limbs`); None: every limb.

    Returns
    -------
    poses : (K, 48) float
        For each limb and blob: the pose fitted with the limb's end at the blob's point
        farthest from the limb's root that the limb can reach (root to point at most its
        length plus :data:`REACH_SLACK`), the middle joint free, every other joint kept;
        none where that point is within ``near`` of an end of the limb's class.
    limbs : list of str
    """
    pose = np.asarray(pose, dtype=np.float64)
    joints = np.asarray(body.joint_positions(pose))
    rest = np.asarray(body.joint_positions(np.zeros(len(pose))))
    out, limbs = [], []
    for limb, names in LIMBS.items():
        if limbs_free is not None and limb not in limbs_free:
            continue
        root, mid, end = (JOINT_INDEX[n] for n in names)
        length = float(np.linalg.norm(rest[mid] - rest[root]) + np.linalg.norm(rest[end] - rest[mid]))
        both_ends = joints[_class_ids(names[2])]
        for points in blobs:
            d = np.linalg.norm(points - joints[root], axis=1)
            within = d <= length + REACH_SLACK
            if not within.any():
                continue
            p = points[within][np.argmax(d[within])]
            if np.linalg.norm(both_ends - p, axis=1).min() < near:
                continue
            target = joints.copy()
            target[end] = p
            out.append(_end_at(body, pose, target, mid))
            limbs.append(limb)
    return np.array(out).reshape(-1, len(pose)), limbs


def recheck_reach(state, pose, refit, energy_of, candidates, settings, floor: float = 0.0):
    """The reach recheck of one frame (module docstring): keep ``pose`` or the best limb
    re-fitted to a far proposal.

    Parameters
    ----------
    state : TrackingState
        Before this frame is logged.
    pose : (48,) float
    refit : callable ``(pose (48,)) -> (pose (48,), float)``
        A pose climbed on the frame by the energy without the motion prior, and that energy.
    energy_of : callable ``(poses (K, 48)) -> (K,)``
        That energy, unclimbed, in one batch.
    candidates : callable ``(pose (48,)) -> (poses (K, 48), limbs list of str[, sources list of str])``
        :func:`reach_candidates` on this frame (and :func:`blob_reach_candidates`; each
        candidate's source, ``"proposal"`` or ``"unexplained"``, goes into the record).
    settings : TrackerSettings
    floor : float
        The energy every pose pays (:attr:`~.heading_settings.HeadingSettings.margins_over`);
        the margin is a fraction of the kept energy above it.

    Returns
    -------
    pose : (48,) float
        The re-fitted pose when it took over, else ``pose``.
    changes : dict
        For the state (``reaches``).
    switched : bool
    """
    if not due(state, settings.propose.reach_every):
        return pose, {}, False
    poses, limbs, *sources = candidates(pose)
    if not len(poses):
        return pose, {}, False
    best = int(np.argmin(energy_of(poses)))
    _, e_pose = refit(pose)
    y, e_y = refit(poses[best])
    if relative_lead(e_pose, e_y, floor) <= settings.propose.reach_margin:
        return pose, {}, False
    reach = {"frame": state.frame, "limb": limbs[best], "energy_kept": round(float(e_pose), 1),
             "energy_reached": round(float(e_y), 1)}
    if sources:
        reach["from"] = sources[0][best]
    return np.asarray(y, dtype=np.float64), {"reaches": state.reaches + (reach,)}, True
