"""The front/back check after an automatic start: track the pose and its turned twin, keep the better.

A depth image barely tells a body's front from its back, and the start's heading prior
assumes the person faces the camera. Motion does tell them apart: knees and elbows bend one
way only. Both hypotheses are tracked through the next :attr:`HeadingSettings.frames`
frames, each from a copy of the start state; the turned one is kept only when its fit
explains the frames clearly better (mean unexplained share lower by
:attr:`HeadingSettings.margin`).
"""
from __future__ import annotations

import numpy as np

from ..body.rotations import matrix_to_rotvec, rotation_about, rotvec_to_matrix
from ..body.skeleton import MODEL_UP


def turned_pose(pose):
    """``pose (48,)`` turned half a turn about the body's long axis through the pelvis:
    the same silhouette seen from the other side (front and back swapped)."""
    x = np.array(pose, dtype=np.float64)
    R = rotvec_to_matrix(x[3:6])
    axis = R @ MODEL_UP
    x[3:6] = matrix_to_rotvec((rotation_about(axis, np.pi) @ R)[None])[0]
    return x


def settle_heading(start, depths, track, turn, settings):
    """Decide between the start pose and its turned twin by tracking both.

    Parameters
    ----------
    start : TrackingState
        Just after the start (its pose the initial one).
    depths : list of (H, W) float
        The next frames.
    track : callable ``(state, depths) -> (state, poses (K, 48), mean cost) or None``
        Tracks a state through the frames (None when the track was dropped).
    turn : callable ``(pose (48,)) -> (48,)``
        The turned twin of a pose, fitted to the start frame.
    settings : TrackerSettings

    Returns
    -------
    None when the initial pose's track was dropped (no decision), else
    ``(state, poses (K+1, 48))``: the kept track, the start frame's pose first.
    """
    a = track(start, depths)
    if a is None:
        return None
    state_a, track_a, cost_a = a
    x_front = start.pose
    x_turned = turn(x_front)
    b = track(start.replace(pose=x_turned), depths)
    cost_b = None if b is None else b[2]
    if b is not None and cost_b < (1.0 - settings.heading.margin) * cost_a:
        choice, state, poses = "turned", b[0], np.concatenate([x_turned[None], b[1]])
    else:
        choice, state, poses = "initial", state_a, np.concatenate([x_front[None], track_a])
    info = {**state.init_info, "heading_check": {
        "frames": len(depths), "unexplained_initial": round(cost_a, 4),
        "unexplained_turned": None if cost_b is None else round(cost_b, 4), "kept": choice}}
    return state.replace(init_info=info), poses
