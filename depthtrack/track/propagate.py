"""Stage "associate and propagate": part detections moved into the pose by evidence propagation.

The loop itself is :func:`.association.associate` (pure; tested without a renderer); this
module gives it the frame's detections and the recogniser's side-free joint proposals
(``ProposalSettings.evidence``), evidence propagation (:mod:`.evidence`) and, for "hc+ep",
the hill climbing of each propagated pose over its part's chain.
"""
from __future__ import annotations

import numpy as np

from .association import associate
from .evidence import PART_JOINT, propagate_evidence
from .hill_climb import restrict_blocks
from .proposals import JOINT_CLASSES, frame_proposals, proposal_detections
from .search import climb

#: Hill-climbing groups moved by each part's chain (root first).
PART_GROUPS = {
    "head": ("pelvis_t", "pelvis", "spine", "neck"),
    "l_hand": ("spine", "l_shoulder", "l_elbow", "l_wrist"),
    "r_hand": ("spine", "r_shoulder", "r_elbow", "r_wrist"),
    "l_foot": ("pelvis_t", "pelvis", "l_hip", "l_knee", "l_ankle"),
    "r_foot": ("pelvis_t", "pelvis", "r_hip", "r_knee", "r_ankle"),
}
# joint-centre parts (the recogniser's proposals): the joints that move them, and the limb
# below, which a moved joint carries along and the climb puts back on the image
for _side in ("l", "r"):
    PART_GROUPS.update({
        f"{_side}_shoulder": ("pelvis_t", "pelvis", "spine", f"{_side}_shoulder", f"{_side}_elbow"),
        f"{_side}_elbow": ("spine", f"{_side}_shoulder", f"{_side}_elbow", f"{_side}_wrist"),
        f"{_side}_wrist": ("spine", f"{_side}_shoulder", f"{_side}_elbow", f"{_side}_wrist"),
        f"{_side}_hip": ("pelvis_t", "pelvis", f"{_side}_hip", f"{_side}_knee"),
        f"{_side}_knee": ("pelvis_t", "pelvis", f"{_side}_hip", f"{_side}_knee", f"{_side}_ankle"),
        f"{_side}_ankle": ("pelvis_t", "pelvis", f"{_side}_hip", f"{_side}_knee", f"{_side}_ankle"),
    })


def evidence_parts(propose) -> tuple:
    """The joint-centre parts the association needs for ``propose`` (ProposalSettings):
    both sides of every ``evidence_joints`` class, or none when ``evidence`` is off."""
    if not (propose.enabled and propose.evidence and propose.evidence_max > 0):
        return ()
    return tuple(p for c in propose.evidence_joints for p in JOINT_CLASSES[c])


def frame_detections(tracker, frame) -> list:
    """The part detections of ``frame`` (detected once per frame, then kept on it)."""
    if frame.detections is None:
        with tracker.recorder.timed("detect"):
            frame.detections = list(tracker.detector(frame.depth, tracker.camera, frame.foreground))
        tracker.recorder.count("detections", len(frame.detections))
    return frame.detections


def associate_stage(tracker, energy, frame, pose, e):
    """Try the frame's detections on ``pose (48,)`` of energy ``e``.

    Parameters
    ----------
    tracker : Tracker
        Supplies body, parts, prior, settings, climbers, detector and recorder (read only).
    energy : Energy
        The current mode's energy (with the motion prior while tracking).

    Returns
    -------
    pose : (48,) float
    energy : float
    accepted : int
        Correspondences accepted.
    """
    rec = tracker.recorder
    s = tracker.settings.associate
    with rec.timed("association"):
        dets = frame_detections(tracker, frame)
        sp = tracker.settings.propose
        centres = evidence_parts(sp) if tracker.forest is not None else ()
        props = (proposal_detections(frame_proposals(tracker, frame), sp.evidence_joints,
                                     sp.min_confidence) if centres else [])
        if not dets and not props:
            return pose, e, 0
        names = tracker.parts.names
        positions = tracker.parts.positions(tracker.body, pose[None])[0]     # (P, 3)
        # the part detector's classes are confused with one another, never with a joint
        # centre: its detections are pruned against the surface parts only
        parts = positions[[names.index(n) for n in PART_JOINT]]
        base = e if s.accept == "map" else energy.likelihood(pose)
        refine_energy = energy if s.refine_with_prior else energy.without_prior()
        std = s.ep_prior_scale * tracker.prior.velocity_std
        dof = tracker.body.dof

        def propagate(x, part, detection):
            with rec.timed("evidence"):
                res = propagate_evidence(tracker.body, tracker.parts, part,
                                         np.asarray(detection.position, float), x, np.zeros(dof),
                                         std, obs_std=s.ep_obs_std)
            return res.pose

        def refine(x, part):
            # the paper accepts a correspondence when the likelihood improves: the prior,
            # centred on a possibly lost previous pose, would veto exactly the jumps evidence
            # propagation exists for
            if tracker.method != "ep":
                climber = tracker.climbers.frame
                blocks = (restrict_blocks(climber.blocks, PART_GROUPS[part])
                          if s.refine_scope == "chain" else None)
                x, _ = climb(refine_energy, climber, x, rec, blocks=blocks, level_offset=s.refine_level)
            if s.accept == "map":
                return x, energy.one(x)
            return x, energy.likelihood(x) + s.accept_margin

        res = associate(pose, base, dets, parts, propagate, refine, prune_distance=s.prune_distance,
                        max_correspondences=s.max_correspondences, proposals=props,
                        joint_positions=dict(zip(names, positions)),
                        proposal_classes={c: JOINT_CLASSES[c] for c in sp.evidence_joints},
                        proposal_distance=sp.evidence_distance,
                        max_proposal_correspondences=sp.evidence_max if centres else 0)
        rec.count("correspondences", len(res.tried))
        rec.count("accepted", len(res.accepted))
        rec.count("proposal_correspondences", sum(c.proposal for c in res.tried))
        rec.count("proposal_accepted", sum(c.proposal for c in res.accepted))
        if not res.accepted:
            return pose, e, 0
        return res.pose, energy.one(res.pose), len(res.accepted)
