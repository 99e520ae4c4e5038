"""Stages "judge" and "recover": is the track lost, and the global search that takes over.

The measure is the share of the observation a pose leaves unexplained, from the sensor
model's own bounds (:func:`depthtrack.likelihood.fixed_and_empty_costs`):
``(c(x) - c_fixed) / (c_empty - c_fixed)``, ``c(x)`` the pose's mean tile cost, ``c_empty`` the
cost with no body drawn, ``c_fixed`` the share no candidate can change (pixels without a
reading). About 0.1 - 0.3 on a good fit, near 1 when lost; independent of the ROI's size,
so comparable from frame to frame.

A second opinion comes from the part recogniser (:mod:`.proposals`): a pose whose trunk the
frame's joint proposals place elsewhere for :attr:`ProposalSettings.lost_frames` frames in a
row is lost too (reason ``"proposals"``), even when its silhouette fits -- an upside-down
or back-to-front body explains a depth image almost as well as the right one.
"""
from __future__ import annotations

import time

import numpy as np

from ..errors import InputError
from .energy import unexplained
from .twins import facing_direction, long_axis
from .proposals import disagreement, frame_proposals
from .start import global_search

#: Laid over the settings (``TrackerSettings.updated``) for the tracks that test one
#: hypothesis: the start check's two tracks and a re-track's backward track. A fresh look
#: (:attr:`JudgeSettings.look_every`) there asks the forward track's question of a test's
#: track and may turn the hypothesis under test into the other (dev 05_20 seed 3: a look
#: inside the backward track after a switch on frame 44 met the forward heading, so the
#: wrong switch stood; README, "A fresh look").
NO_LOOK = {"judge": {"look_every": 0}}


def is_lost(cost: float, recent, settings) -> bool:
    """Whether ``cost`` jumped above the ``recent`` unexplained shares (see :class:`JudgeSettings`)."""
    if len(recent) < 1:
        return False
    typical = float(np.median(recent))
    s = settings.judge
    return cost > s.lost_ratio * typical and cost > typical + s.lost_margin


def loss_reason(cost: float, recent, settings, proposal_misses: int = 0):
    """Why the track counts as lost on this frame, or None: ``"unexplained"`` when the
    explained share collapsed (:func:`is_lost`), ``"proposals"`` when the recogniser's
    proposals disagreed with the pose ``proposal_misses`` frames in a row (at least
    :attr:`ProposalSettings.lost_frames`)."""
    if is_lost(cost, recent, settings):
        return "unexplained"
    if proposal_misses >= settings.propose.lost_frames:
        return "proposals"
    return None


def proposal_check(tracker, frame, pose, misses: int):
    """The recogniser's opinion of ``pose (48,)`` on ``frame``: ``(disagreeing share or None,
    misses)``, ``misses`` counting the frames in a row it disagreed (:class:`ProposalSettings`)."""
    proposals = frame_proposals(tracker, frame)
    if proposals is None:
        return None, 0
    p = tracker.settings.propose
    off, checked = disagreement(tracker.body.joint_positions(pose), proposals, p.min_confidence,
                                p.distance)
    return float(off), (misses + 1 if checked >= 3 and off > p.lost_fraction else 0)


def judge_frame(state, cost: float, reason, settings, found=None):
    """The loss bookkeeping of one frame: ``(changes for the state, log fields)``.

    ``reason``: :func:`loss_reason` of the frame's final pose (after any recovery);
    ``found``: the reason the frame's tracked pose was judged lost, before a recovery. A
    loss opens on its first lost frame and closes on the first frame judged not lost (or,
    after :attr:`JudgeSettings.max_lost_frames`, unrecovered); each closed loss is appended
    to ``state.recoveries`` as ``{"frame", "reason", "frames_to_recover"}`` -- 0 frames
    when the recovery on the frame it was found already put the track right.
    """
    frame = state.frame
    lost = state.lost
    if lost is None and reason is None:
        if found is None:
            return {}, {}
        done = {"frame": frame, "reason": found, "frames_to_recover": 0}
        return {"recoveries": state.recoveries + (done,)}, {}
    if lost is None:
        lost = {"frame": frame, "reason": reason}
    if reason is None:
        done = {**lost, "frames_to_recover": frame - lost["frame"]}
        return {"lost": None, "recoveries": state.recoveries + (done,)}, {}
    if frame - lost["frame"] + 1 >= settings.judge.max_lost_frames:
        done = {**lost, "frames_to_recover": None}
        return {"lost": None, "recoveries": state.recoveries + (done,)}, {"reset": True}
    return {"lost": lost}, {"lost": True}


def look_turn_deg(a, b) -> float:
    """Degrees (0 to 180) poses ``a`` and ``b`` (48,) are turned from each other: the larger
    of the angles between their root forward directions and between their long axes
    (:func:`.twins.facing_direction`, :func:`.twins.long_axis`). About 180 for a pose
    and its turned twin (front and back swapped) and for the pose upside down in the image
    plane (a cartwheel's star read head for feet: the forward direction kept)."""
    def angle(u, v):
        cos = float(u @ v) / max(float(np.linalg.norm(u) * np.linalg.norm(v)), 1e-12)
        return float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))
    return max(angle(facing_direction(a), facing_direction(b)),
               angle(long_axis(a), long_axis(b)))


def recover(tracker, energy, frame, previous, x, cost, reason: str = "unexplained", off=None,
            margin: float = 0.0, max_turn: float = 180.0):
    """Global search on ``frame``; taken when it explains more than the tracked ``x``
    (:attr:`JudgeSettings.recover_by`: a lower unexplained share, or a lower energy).

    ``previous (48,)``: the last frame's pose, whose heading and body axis the search prefers
    -- unless ``reason`` is ``"proposals"``: then the track's orientation is what is in
    doubt, the search starts as a first frame does, and its pose is taken when the proposals
    disagree with it less and it leaves at most :attr:`ProposalSettings.accept_margin` more
    of the observation unexplained (``off``: ``x``'s disagreeing share, :func:`proposal_check`).
    ``margin``: by what fraction the search's score must be lower than ``x``'s (0 for a
    loss; :attr:`JudgeSettings.look_margin` for a fresh look, ``reason`` ``"look"``, whose
    searches count in ``recoveries_tried`` and time under ``recover`` like a loss's).
    ``max_turn``: the most degrees the search's pose may be turned from ``x`` (root forward
    directions and long axes, :func:`look_turn_deg`) and be taken (180 = any; a fresh look's is
    :attr:`JudgeSettings.look_turn`; one refused so counts in ``looks_turned_away``).

    Returns
    -------
    recovered : bool
    pose : (48,) float
    cost : float
        Its unexplained share.
    """
    t = time.perf_counter()
    energy = energy.without_prior()
    doubted = reason == "proposals"
    try:
        # the search prefers the last heading and the last body axis (a cartwheel's
        # upside-down body is no less likely there than an upright one)
        y, _, _ = global_search(tracker, energy, frame,
                                heading=None if doubted else facing_direction(previous),
                                body_axis=None if doubted else long_axis(previous),
                                **tracker.settings.start.searched_in("recovery"))
    except InputError:
        return False, x, cost
    y_cost = unexplained(energy, y)
    tracker.recorder.add("recover", time.perf_counter() - t)
    tracker.recorder.count("recoveries_tried")
    if look_turn_deg(y, x) > max_turn:
        tracker.recorder.count("looks_turned_away")
        return False, x, cost
    if doubted:
        p = tracker.settings.propose
        off_y, _ = proposal_check(tracker, frame, y, 0)
        better = off_y < off and y_cost < cost + p.accept_margin
    elif tracker.settings.judge.recover_by == "energy":
        e_y, e_x = tracker.judge_energy()(np.stack([y, x]))
        better = bool(e_y < (1.0 - margin) * e_x)
    else:
        better = y_cost < (1.0 - margin) * cost
    if better:
        tracker.recorder.count("recoveries")
        return True, y, y_cost
    return False, x, cost
