"""Carry a track's later side corrections back to the frames tracked before them.

A heading switch (:func:`.heading.recheck_heading`) or a limb swap
(:func:`.heading.recheck_limb_sides`) corrects the frame it runs on and those after; the
frames before it keep the sides the track had. While tracking, a re-track carries the
correction back (:mod:`.retrack`). The shape fit's trial tracks without re-tracks (it
yields its frames as it goes, :func:`.height.fit_body_shape`), and the fit then took the
poses of frames before a correction as they were, and the re-track after the fit started
from its frame-0 pose: back to front wherever the trial's own recheck had turned it. In
all 14 dev, parity and fresh-seed tracks whose trial switched its heading, the trial's start
was back to front and the switch right (frames before it 136 to 180 degrees off, after it 0
to 21); 13 final tracks turned again by themselves, one (02_03 from 120 degrees, Kinect v2,
seed 4) stayed back to front for the whole clip (README, "The tracker").

Both corrections exchange sides: the twin puts each joint where the other side's was
(:data:`.twins.SIDES_SWAPPED`, :data:`.twins.LEGS_SWAPPED`,
:data:`.twins.ARMS_SWAPPED`). The exchanges are involutions over disjoint pairs of
joints, so they commute: a frame before corrections carries the exchange of every kind
corrected an odd number of times after it (:func:`exchanged_after`), fitted to its joints
as the recheck fits its twins (:func:`carried_twins`) and climbed on its own frame
(:func:`carry_back`). A loss (a recovery) cuts the track: a correction after it says
nothing of the frames before it.
"""
from __future__ import annotations

import numpy as np

from .twins import ARMS_SWAPPED, LEGS_SWAPPED, SIDES_SWAPPED, fit_joints, twins_to
from .search import lowest_climb

#: The joint exchange of each kind of correction (contract joint order).
EXCHANGES = {"heading": SIDES_SWAPPED, "legs": LEGS_SWAPPED, "arms": ARMS_SWAPPED}


def corrections_of(described: dict) -> list:
    """``[(index, kind), ...]`` in frame order: the heading switches (kind ``"heading"``)
    and limb swaps (``"legs"``, ``"arms"``) of a tracker's :meth:`~.tracker.Tracker.describe`
    (or a ``summary.json``), at their sequence frames (``index``)."""
    found = [(int(e["index"]), "heading") for e in described.get("heading_switches", [])]
    found += [(int(e["index"]), e["limbs"]) for e in described.get("limb_swaps", [])]
    return sorted(found, key=lambda c: c[0])


def exchanged_after(index: int, corrections, cuts=()) -> frozenset:
    """The kinds of :data:`EXCHANGES` corrected an odd number of times after frame ``index``
    (``corrections``: :func:`corrections_of`'s list), counting only up to the first of ``cuts``
    (sequence frames where the track was found again) after it. A correction on frame
    ``index`` itself already holds there."""
    stop = min([c for c in cuts if c > index], default=None)
    odd = set()
    for at, kind in corrections:
        if at > index and (stop is None or at < stop):
            odd ^= {kind}
    return frozenset(odd)


def exchange_order(kinds) -> list:
    """The contract joint order with the sides of every kind in ``kinds`` exchanged."""
    order = np.arange(len(SIDES_SWAPPED))
    for kind in kinds:
        order = order[EXCHANGES[kind]]
    return order.tolist()


def carried_twins(body, pose, kinds, starts) -> np.ndarray:
    """``(K, 48)``: ``pose (48,)`` with the sides of ``kinds`` exchanged, its joints where the
    pose's are. With ``"heading"`` the body faces the other way, fitted from each of
    ``starts`` (:func:`.twins.twins_to`); limbs alone are fitted from the pose itself
    (as :func:`.twins.limb_swapped_twins`)."""
    pose = np.asarray(pose, dtype=np.float64)
    target = np.asarray(body.joint_positions(pose))[exchange_order(kinds)]
    if "heading" in kinds:
        return twins_to(body, pose, target, starts)
    return fit_joints(body, target, pose)[None]


def carry_back(tracker, depth, foreground, pose, kinds):
    """``pose (48,)`` of the frame ``depth (H, W)`` (its segmentation ``foreground``) with
    the sides of ``kinds`` exchanged (:func:`carried_twins`), each fit climbed on that frame
    as the rechecks climb their twins (the energy without the motion prior,
    ``heading.twin_passes``, from ``refit_level``); returns the lowest, ``(48,)``. Uploads
    the frame to ``tracker``'s renderers."""
    h = tracker.settings.heading
    frame, _ = tracker._observe(tracker.state, depth, predicted=np.asarray(pose, dtype=np.float64),
                                foreground=foreground)
    x, _ = lowest_climb(tracker._energy(frame), tracker.climbers.start,
                        carried_twins(tracker.body, pose, kinds, h.twin_starts), tracker.recorder,
                        passes=h.twin_passes, level_offset=h.refit_level)
    return np.asarray(x, dtype=np.float64)


def carry_back_frames(tracker, described, index, poses, depths, foregrounds, kinds):
    """The poses ``(K, 48)`` of the sequence frames ``index`` (their ``depths`` and
    ``foregrounds``, K each) with the later corrections of ``kinds`` in ``described`` (the
    tracker's :meth:`~.tracker.Tracker.describe`) carried back, up to its recoveries; and
    ``[{"index", "exchanged"}]`` for each frame changed."""
    corrections = [c for c in corrections_of(described) if c[1] in kinds]
    cuts = [int(e["index"]) for e in described["recoveries"]]
    out, changed = np.array(poses, dtype=np.float64), []
    for k, i in enumerate(index):
        exchanged = exchanged_after(i, corrections, cuts)
        if exchanged:
            out[k] = carry_back(tracker, depths[k], foregrounds[k], out[k], exchanged)
            changed.append({"index": int(i), "exchanged": sorted(exchanged)})
    return out, changed
