"""Stage "associate and propagate": part detections moved into the pose by evidence propagation.

The loop itself is :func:`.association.associate` (pure; tested without a renderer); this
module gives it the frame's detections, evidence propagation (:mod:`.evidence`) and, for
"hc+ep", the hill climbing of each propagated pose over its part's chain.
"""
from __future__ import annotations

import numpy as np

from .association import associate
from .evidence import propagate_evidence
from .hill_climb import restrict_blocks
from .search import climb

#: Hill-climbing groups moved by each part's chain (root first).
PART_GROUPS = {
    "head": ("pelvis_t", "pelvis", "spine", "neck"),
    "l_hand": ("spine", "l_shoulder", "l_elbow", "l_wrist"),
    "r_hand": ("spine", "r_shoulder", "r_elbow", "r_wrist"),
    "l_foot": ("pelvis_t", "pelvis", "l_hip", "l_knee", "l_ankle"),
    "r_foot": ("pelvis_t", "pelvis", "r_hip", "r_knee", "r_ankle"),
}


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
        if not dets:
            return pose, e, 0
        parts = tracker.parts.positions(tracker.body, pose[None])[0]
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
                        max_correspondences=s.max_correspondences)
        rec.count("correspondences", len(res.tried))
        rec.count("accepted", len(res.accepted))
        if not res.accepted:
            return pose, e, 0
        return res.pose, energy.one(res.pose), len(res.accepted)
