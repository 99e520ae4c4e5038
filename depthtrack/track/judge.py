"""Stages "judge" and "recover": is the track lost, and the global search that takes over.

The measure is the share of the observation a pose leaves unexplained, from the sensor
model's own bounds (:func:`depthtrack.likelihood.fixed_and_empty_costs`):
``(c(x) - c_fixed) / (c_empty - c_fixed)``, ``c(x)`` the pose's mean tile cost, ``c_empty`` the
cost with no body drawn, ``c_fixed`` the share no candidate can change (pixels without a
reading). About 0.1 - 0.3 on a good fit, near 1 when lost; independent of the ROI's size,
so comparable from frame to frame.
"""
from __future__ import annotations

import time

import numpy as np

from ..body.rotations import rotvec_to_matrix
from ..body.skeleton import MODEL_FORWARD, MODEL_UP
from ..errors import InputError
from ..likelihood import fixed_and_empty_costs
from .start import global_search


def unexplained(energy, pose) -> float:
    """Share of the observation's cost that ``pose (48,)`` leaves unexplained (module docstring),
    against the observation held by ``energy``'s renderer."""
    c = float(energy.likelihood_costs(np.asarray(pose)[None])[0])
    r = energy.renderer
    fixed, empty = fixed_and_empty_costs(r.observed_tile, r.params, r.background_tile)
    return (c - fixed) / max(empty - fixed, 1e-9)


def is_lost(cost: float, recent, settings) -> bool:
    """Whether ``cost`` jumped above the ``recent`` unexplained shares (see :class:`JudgeSettings`)."""
    if len(recent) < 1:
        return False
    typical = float(np.median(recent))
    s = settings.judge
    return cost > s.lost_ratio * typical and cost > typical + s.lost_margin


def loss_reason(cost: float, recent, settings):
    """Why the track counts as lost on this frame, or None: ``"unexplained"`` when the
    explained share collapsed (:func:`is_lost`)."""
    return "unexplained" if is_lost(cost, recent, settings) else None


def judge_frame(state, cost: float, reason, settings):
    """The loss bookkeeping of one frame: ``(changes for the state, log fields)``.

    ``reason``: :func:`loss_reason` of the frame's final pose (after any recovery). A loss
    opens on its first lost frame and closes on the first frame judged not lost (or, after
    :attr:`JudgeSettings.max_lost_frames`, unrecovered); each closed loss is appended to
    ``state.recoveries`` as ``{"frame", "reason", "frames_to_recover"}``.
    """
    frame = state.frame
    lost = state.lost
    if lost is None and reason is None:
        return {}, {}
    if lost is None:
        lost = {"frame": frame, "reason": reason}
    if reason is None:
        done = {**lost, "frames_to_recover": frame - lost["frame"]}
        return {"lost": None, "recoveries": state.recoveries + (done,)}, {}
    if frame - lost["frame"] + 1 >= settings.judge.max_lost_frames:
        done = {**lost, "frames_to_recover": None}
        return {"lost": None, "recoveries": state.recoveries + (done,)}, {"reset": True}
    return {"lost": lost}, {"lost": True}


def recover(tracker, energy, frame, previous, x, cost):
    """Global search on ``frame``; taken when it explains more than the tracked ``x``.

    ``previous (48,)``: the last frame's pose, whose heading the search prefers.

    Returns
    -------
    recovered : bool
    pose : (48,) float
    cost : float
        Its unexplained share.
    """
    t = time.perf_counter()
    R = rotvec_to_matrix(previous[3:6])
    energy = energy.without_prior()
    try:
        # the search prefers the last heading and the last body axis (a cartwheel's
        # upside-down body is no less likely there than an upright one)
        y, _, _ = global_search(tracker, energy, frame, heading=R @ MODEL_FORWARD,
                                body_axis=R @ MODEL_UP)
    except InputError:
        return False, x, cost
    y_cost = unexplained(energy, y)
    tracker.recorder.add("recover", time.perf_counter() - t)
    tracker.recorder.count("recoveries_tried")
    if y_cost < cost:
        tracker.recorder.count("recoveries")
        return True, y, y_cost
    return False, x, cost
