"""Which way a body faces and which side its limbs are on, from its contract joints (a
metric of the evaluation, and the tracker's test of whether two tracks face the same way or
have a limb pair's sides exchanged)."""
from __future__ import annotations

import numpy as np

from ..contract import JOINT_INDEX

#: The contract joint pairs whose left-to-right vectors, summed, are a trunk's sideways axis.
TRUNK_SIDES = (("l_hip", "r_hip"), ("l_shoulder", "r_shoulder"))


def back_to_front(estimated, truth):
    """Which frames a track has back to front: its trunk facing away from the true one.

    A body seen from the wrong side is the tracker's costliest mistake (every joint's side
    exchanged; the hips and shoulders a trunk's width off while head, neck and pelvis are
    right), and the one a depth image hides best. The trunk's sideways axis is the sum of
    the left-to-right vectors of the hips and the shoulders (:data:`TRUNK_SIDES`); a frame is
    back to front when the tracked axis points against the true one (their angle over 90
    degrees: the trunk turned more than a quarter turn about its long axis, or mirrored).

    Parameters
    ----------
    estimated, truth : (F, 15, 3) float
        Contract joints; NaN where unknown.

    Returns
    -------
    (F,) float
        1.0 back to front, 0.0 not, NaN where either side's joints are unknown.
    """
    dot = np.sum(trunk_sideways(estimated) * trunk_sideways(truth), axis=-1)
    return np.where(np.isfinite(dot), (dot < 0).astype(np.float64), np.nan)


def trunk_sideways(joints):
    """``(F, 3)``: the trunk's sideways axis of contract ``joints (F, 15, 3)``, the sum of
    the left-to-right vectors of the hips and the shoulders (:data:`TRUNK_SIDES`; not
    normalised)."""
    j = np.asarray(joints, dtype=np.float64)
    return sum(j[:, JOINT_INDEX[r]] - j[:, JOINT_INDEX[lft]] for lft, r in TRUNK_SIDES)


def facing_error_deg(estimated, truth):
    """``(F,)``: the angle (degrees, 0 to 180) between the trunks' sideways axes
    (:func:`trunk_sideways`) of ``estimated`` and ``truth`` ``(F, 15, 3)``: how far a
    tracked trunk is turned from the true one (over 90: :func:`back_to_front`; 45 to 135: a
    quarter turn off, the body seen in profile where it faces the camera or the reverse).
    NaN where either is unknown."""
    a, b = trunk_sideways(estimated), trunk_sideways(truth)
    cos = np.sum(a * b, axis=-1) / (np.linalg.norm(a, axis=-1) * np.linalg.norm(b, axis=-1))
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def sides_exchanged(estimated, truth, order):
    """Which frames have a limb pair's sides exchanged: ``estimated``'s joints that ``order``
    moves lie nearer ``truth``'s with left and right exchanged than as they are (the legs
    crossed over, each knee and ankle where the other side's are).

    Parameters
    ----------
    estimated, truth : (F, 15, 3) float
        Contract joints.
    order : sequence of int
        Contract joint order with the pair's sides exchanged (e.g. ``LEGS_SWAPPED`` of
        :mod:`depthtrack.track.heading`); the joints it keeps in place do not count.

    Returns
    -------
    (F,) bool
    """
    order = np.asarray(order)
    moved = order != np.arange(len(order))
    est = np.asarray(estimated, dtype=np.float64)
    tru = np.asarray(truth, dtype=np.float64)
    as_is = np.linalg.norm(est[:, moved] - tru[:, moved], axis=-1).sum(axis=-1)
    exchanged = np.linalg.norm(est[:, order][:, moved] - tru[:, moved], axis=-1).sum(axis=-1)
    return exchanged < as_is
