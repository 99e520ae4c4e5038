"""Stage "re-track": after a correction -- a heading switch, a limb swap, a recovery -- the
frames before it tracked again backwards in time from the corrected pose, and the energy
rule that decides how many of the backward poses replace the forward ones
(:attr:`HeadingSettings.retro_frames`, ``retro_after``, ``retro_take``, ``retro_give_up``,
``retro_stop``). With ``retro_revoke`` a heading switch whose backward track does not bear
it out is taken back (:func:`revokes`, :func:`revoke_switch`). The frame loop (:mod:`.loop`)
calls these.
"""
from __future__ import annotations

import numpy as np

from ..body.facing import back_to_front, sides_exchanged
from .heading import CHANNELS_CLEARED
from .twins import LIMB_SWAPS
from .judge import NO_LOOK


#: Which corrections :func:`new_correction` reports, first the one a frame's re-track
#: follows when it has several: a recovery replaces the whole pose.
CORRECTION_ORDER = ("heading", "recovery", "limbs")

#: What the backward track after each kind of correction runs without: the recheck that
#: made the correction (it must keep the correction's choice; after a limb swap or a
#: recovery the heading recheck too: the forward track's own checks found nothing there).
_HEADING_OFF = {"every": 0, "search_every": 0}
RETRO_OFF = {"heading": _HEADING_OFF,
             "limbs": {**_HEADING_OFF, "limb_every": 0},
             "recovery": {**_HEADING_OFF, "limb_every": 0},
             "settle": {**_HEADING_OFF, "limb_every": 0}}

#: Mean joint distance (m) under which a backward track after a recovery agrees with the
#: forward one: from there back the forward track was found already.
RETRO_AGREE_M = 0.05

#: ``stopped`` of a re-track entry where the forward track had the correction already.
STOP_LABELS = {"heading": "same heading", "limbs": "same sides", "recovery": "agrees"}


def reach_after(lowest: dict, kind: str, at: int, stop: str) -> dict:
    """``{kind: first frame}`` a later re-track of each kind (:data:`CORRECTION_ORDER`) may
    reach once the frames before a correction of ``kind`` on frame ``at`` were re-tracked:
    past ``at`` for every kind (``stop`` ``"any"``) or for ``kind`` and the kinds after it in
    the order (``"rank"``; :attr:`HeadingSettings.retro_stop`), the others as they were."""
    rank = CORRECTION_ORDER.index(kind)
    return {k: at + 1 if stop == "any" or CORRECTION_ORDER.index(k) >= rank else first
            for k, first in lowest.items()}


def _corrections(state) -> dict:
    """How many corrections of each kind :data:`CORRECTION_ORDER` ``state`` has had: a
    recovery counts where a loss closed with the track found again."""
    return {"heading": len(state.heading_switches), "limbs": len(state.limb_swaps),
            "recovery": sum(r.get("frames_to_recover") is not None for r in state.recoveries)}


def new_correction(before, after, kinds):
    """The kind of correction (of ``kinds``, :attr:`HeadingSettings.retro_after`) that
    ``after`` has and ``before`` had not -- the first in :data:`CORRECTION_ORDER` -- or None."""
    was, now = _corrections(before), _corrections(after)
    return next((k for k in CORRECTION_ORDER if k in kinds and now[k] > was[k]), None)


def _forward_agrees(kind, detail, backward, forward) -> bool:
    """Whether the forward track's joints ``forward (15, 3)`` already have what the
    correction of ``kind`` gave the backward track's ``backward (15, 3)``: the heading
    (trunks less than a quarter turn apart), the limb pair ``detail``'s sides, or (after a
    recovery) the pose, within :data:`RETRO_AGREE_M` on average. Never after a start
    settled (``"settle"``): the forward track agrees next to the frame it settled on and
    may differ only near the start, so the backward track runs back to it."""
    if kind == "settle":
        return False
    b, f = backward[None], forward[None]
    if kind == "heading":
        return not back_to_front(f, b)[0]
    if kind == "limbs":
        return not sides_exchanged(f, b, LIMB_SWAPS[detail])[0]
    return float(np.mean(np.linalg.norm(f - b, axis=-1))) < RETRO_AGREE_M


def retrack_before_correction(tracker, held, recent, lowest: int, at: int,
                              kind: str = "heading") -> bool:
    """After a correction of ``kind`` (:data:`CORRECTION_ORDER`) on frame ``at``: the
    frames before it tracked again backwards from the corrected pose
    (:attr:`HeadingSettings.retro_frames`, ``retro_after``). Or, ``kind`` ``"settle"``,
    :attr:`HeadingSettings.retro_settle` frames after a start: the frames back to the start
    tracked again from the pose the track has settled into (a start wrong in a limb that the
    track found by itself a few frames later, with no correction to re-track from).

    The backward track runs with the recheck that made the correction off (it must keep the
    correction's choice, :data:`RETRO_OFF`) and without fresh looks (:data:`.judge.NO_LOOK`)
    through ``recent`` ``[(index, depth), ...]``
    from the newest down, and stops at ``lowest`` (the start, or the frame after an earlier
    re-tracked correction, :func:`reach_after`), at a pose already yielded or dropped, at a
    lost track, or where the forward track already has what the correction gave
    (:func:`_forward_agrees`: after a heading switch, faces the way the backward track does,
    their trunks' left-to-right axes less than a quarter turn apart,
    :func:`~depthtrack.body.facing.back_to_front`; after a limb swap, has the swapped limbs
    on the backward track's sides, :func:`~depthtrack.body.facing.sides_exchanged`; after a
    recovery, agrees with it): from there back the forward track had it already, and its
    poses stay.
    Its poses replace those in ``held`` unless their energy without the motion prior on the
    recheck judge's tiles (:meth:`.tracker.Tracker.judge_energy`), summed over the frames,
    exceeds the forward poses' on the same frames by more than the fraction
    ``retro_margin`` (after a start, ``kind`` ``"settle"``, the frames from the start on
    where the backward track did better, with no margin, :func:`settled_frames`: nothing was
    corrected, so it has only its energy to go by). The correction is the evidence: frames
    before it where one heading (or one side for the limbs) explained the image clearly
    better would have been corrected sooner, so there the two score alike, and the backward track's continuity with the
    corrected pose is what tells them apart; the margin only refuses a backward track that
    lost the person. Either way ``tracker.state.retracks`` gets an entry.
    The tracker's state is the corrected forward state again afterwards: the forward track
    goes on as it would have. The entry's ``frames_better`` counts the frames next to the
    correction where the backward track did better (:func:`best_prefix` without a margin).

    Returns whether the correction, a heading switch or a fresh look, is to be taken back
    (:attr:`HeadingSettings.retro_revoke`, :attr:`JudgeSettings.look_revoke`, :func:`revokes`;
    then no frame is taken, and the caller runs :func:`revoke_switch`).
    """
    settings = tracker.settings
    h = settings.heading
    # after a start the frames next to the settled pose score alike, noise either way: no
    # giving up on them before the backward track reaches the start
    give_up = 0 if kind == "settle" else h.retro_give_up
    corrected = tracker.state
    detail = corrected.limb_swaps[-1]["limbs"] if kind == "limbs" else None
    where = {index: k for k, (index, _) in enumerate(held)}
    shares = {e["index"]: e.get("cost") for e in corrected.log[-(len(recent) + 2):] if "index" in e}
    state, poses, indices, backward, judged = corrected, [], [], [], []
    stopped = None
    with tracker.settings_overlaid({"heading": RETRO_OFF[kind], **NO_LOOK}):
        for index, depth in reversed(recent):
            k = where.get(index)
            stopped = ("start or switch" if index < lowest else "yielded" if k is None else
                       "no person" if held[k][1] is None else
                       "unscored" if shares.get(index) is None else None)
            if stopped:
                break
            state, x = tracker.advance(state, depth)
            if x is None:
                stopped = "lost"
                break
            forward = held[k][1]
            joints = np.asarray(tracker.body.joint_positions(np.stack([x, forward])))
            if _forward_agrees(kind, detail, joints[0], joints[1]):
                stopped = STOP_LABELS[kind]
                break
            poses.append(x)
            indices.append(index)
            backward.append(state.log[-1]["cost"])
            judged.append(tracker.judge_energy()(np.stack([x, forward])))   # this frame's
            if gave_up(judged, h.retro_margin, give_up):
                stopped = "worse"
                break
    entry = {"kind": kind, "index": at, "frames": len(indices),
             "stopped": stopped or "window", "taken": False}
    revoke = False
    if indices:
        e_back, e_forward = np.mean(judged, axis=0)
        better = best_prefix(judged, 0.0)
        n = frames_to_take(judged, kind, h.retro_margin, h.retro_take)
        rule = (revoke_rule(h, corrected.heading_switches[-1]) if kind == "heading" else
                settings.judge.look_revoke if was_look(corrected, kind) else "never")
        revoke = revokes(rule, n, better, len(indices), outscored=e_back > e_forward,
                         met=stopped == STOP_LABELS["heading"])
        n = 0 if revoke else n
        # the frames taken (indices run newest first): from the correction back, or, after a
        # start, the oldest
        chosen = slice(len(indices) - n, None) if kind == "settle" else slice(0, n)
        taken = indices[chosen]
        entry.update(first=indices[-1], last=indices[0], taken=n > 0, frames_better=better,
                     energy_forward=round(float(e_forward), 1),
                     energy_backward=round(float(e_back), 1),
                     share_forward=round(float(np.mean([shares[j] for j in indices])), 4),
                     share_backward=round(float(np.mean(backward)), 4),
                     frames_taken=n, **({"first_taken": taken[-1], "last_taken": taken[0]}
                                        if n else {}))
        for index, x in zip(taken, poses[chosen]):
            held[where[index]] = (index, x)
    tracker.state = corrected.replace(retracks=corrected.retracks + (entry,))
    return revoke


def frames_to_take(judged, kind: str, margin: float, take: str) -> int:
    """How many frames of a backward track replace the forward ones, before any revoke.

    ``judged (n, 2)``: per frame, nearest the correction first, the backward and the forward
    pose's energy. After a start (``kind`` ``"settle"``) :func:`settled_frames`; else all
    ``n`` when the backward track's energy (mean over the frames) is at most the forward's
    times ``1 + margin`` (:attr:`HeadingSettings.retro_margin`), or else, with ``take``
    ``"prefix"`` (:attr:`HeadingSettings.retro_take`), the :func:`best_prefix` with no margin
    (a track given up on scores above the margin over the frames it reached), with
    ``"all"`` none."""
    if kind == "settle":
        return settled_frames(judged)
    e_back, e_forward = np.mean(np.asarray(judged).reshape(-1, 2), axis=0)
    if e_back <= e_forward * (1.0 + margin):
        return len(judged)
    return best_prefix(judged, 0.0) if take == "prefix" else 0


def was_look(state, kind: str = "recovery") -> bool:
    """Whether the correction of ``kind`` (:data:`CORRECTION_ORDER`) that ``state`` has
    just had is a fresh look: a recovery whose entry, the newest, has reason ``"look"``
    (after a heading switch or a limb swap, False whatever the recoveries before). A look's
    re-track sets no floor for later re-tracks (:func:`reach_after` is not called for it):
    a look is one frame's energy, and a later correction on its own evidence may go back past
    it (dev wide cartwheel seed 2: the proposals' recovery on frame 21 re-tracked only to frame
    17, past a look on 16 that had kept the star upside down, 89.4 -> 72.8 %)."""
    return (kind == "recovery" and bool(state.recoveries)
            and state.recoveries[-1].get("reason") == "look")


def revoke_rule(heading, switch: dict) -> str:
    """The :data:`~.heading_settings.RETRO_REVOKES` rule that judges the heading ``switch``
    (an entry of ``heading_switches``): :attr:`HeadingSettings.polish_revoke` for one made on
    polished close calls (``"polished"`` in it), unless that is ``"same"``; else
    :attr:`HeadingSettings.retro_revoke`. ``"outscored"`` judges the backward track by
    unpolished energies, which from the side differ by 1-2 % between the two headings: a
    switch the polish found is read at a finer grain than that."""
    if switch.get("polished") and heading.polish_revoke != "same":
        return heading.polish_revoke
    return heading.retro_revoke


def revokes(rule: str, taken: int, better: int, frames: int = 0,
            outscored: bool = False, met: bool = False) -> bool:
    """Whether a heading switch is taken back by ``rule`` (:data:`~.heading_settings.
    RETRO_REVOKES`, :attr:`HeadingSettings.retro_revoke`) when its re-track took ``taken``
    of the ``frames`` it re-tracked and did better on the ``better`` frames next to it, and
    its energy summed over all ``frames`` was (``outscored``) or was not above the forward
    track's: ``"refused"``, none taken; ``"unsupported"``, none better (even where the
    whole backward track was within the margin and so taken); ``"outscored"``, none better,
    or outscored and better on fewer than half the frames; ``"never"``, never.

    ``"outscored"`` reads the whole stretch where the two headings differ: a turn the
    image bears out only next to the switch (a back bend seen from the side reads as a
    forward bend facing the other way, which the pose prior likes better) is not one the
    frames before it bear out, though each lies within the take margin.

    ``"outscored_unless_met"``: ``"outscored"``, but ``"unsupported"`` for a switch whose
    backward track ``met`` the forward track's heading (stopped ``"same heading"``): it
    found where the turn began, inside the window, and a fast turn's frames are explained
    poorly by either track, so their summed energy says little about the switch."""
    if rule == "outscored_unless_met":
        rule = "unsupported" if met else "outscored"
    if rule == "refused":
        return taken == 0
    if rule in ("unsupported", "outscored") and better == 0:
        return True
    return rule == "outscored" and outscored and 2 * better < frames


def summed_excess(judged, margin: float) -> np.ndarray:
    """``(n,)``: the backward track's energy less the forward's times ``1 + margin``, summed
    from the correction back over ``judged (n, 2)`` (per frame, nearest the correction
    first, backward then forward) -- what :func:`best_prefix` and :func:`gave_up` read."""
    e = np.asarray(judged, dtype=np.float64).reshape(-1, 2)
    return np.cumsum(e[:, 0] - (1.0 + margin) * e[:, 1])


def best_prefix(judged, margin: float) -> int:
    """How many frames of a refused backward track to take after all, from the correction
    back (:attr:`HeadingSettings.retro_take` ``"prefix"``, called with ``margin`` 0).

    ``judged (n, 2)``: per frame, nearest the correction first, the backward and the forward
    pose's energy. The answer is the ``k`` that minimises ``sum_{j<k} (backward_j - (1 +
    margin) forward_j)``, 0 when no such sum is below zero (the first of equal minima):
    the frames up to where the backward track stopped doing better than the forward one.
    """
    d = summed_excess(judged, margin)
    if len(d) == 0:
        return 0
    k = int(np.argmin(d))
    return k + 1 if d[k] <= 0 else 0


def settled_frames(judged) -> int:
    """How many frames of a backward track after a start (``"settle"``,
    :attr:`HeadingSettings.retro_settle`) replace the forward ones, counted from the start:
    :func:`best_prefix` with no margin, read from the start's end of ``judged (n, 2)`` (per
    frame, nearest the settled frame first, backward then forward energy). The two tracks
    can differ only near the start; next to the settled frame they hold the same pose and
    score alike, so the taken frames are those from the start up to where the backward
    track stopped doing better."""
    return best_prefix(np.asarray(judged, dtype=np.float64).reshape(-1, 2)[::-1], 0.0)


def gave_up(judged, margin: float, frames: int) -> bool:
    """Whether a backward track is refused before its window ends
    (:attr:`HeadingSettings.retro_give_up`): its energy less the forward's times ``1 +
    margin``, summed from the correction over ``judged (n, 2)`` (per frame, nearest the
    correction first, backward then forward), is above zero and has not reached a new
    minimum for ``frames`` frames (0 = never). The refusal is not certain -- later frames
    could bring the sum back below zero -- but a backward track that scores worse frame
    after frame has lost the person or follows a wrong correction."""
    if frames <= 0 or len(judged) <= frames:
        return False
    d = summed_excess(judged, margin)
    return bool(d[-1] > 0 and len(d) - 1 - int(np.argmin(d)) >= frames)


def revoke_switch(tracker, held, before, depth, index: int, kind: str = "heading") -> bool:
    """Take back the heading switch or fresh look (``kind`` ``"heading"`` or ``"recovery"``,
    the correction re-tracked) on frame ``index`` whose re-track
    :func:`revokes` it (:attr:`HeadingSettings.retro_revoke`, :attr:`JudgeSettings.look_revoke`):
    frame ``index`` tracked again from ``before`` (the state before it) -- after a switch
    with the heading recheck off and the recheck's votes and evidence cleared, so the twin
    must win again from nothing to switch again; after a look without the look.

    A right switch is continuous with the frames before it: tracked back from the turned
    pose, they score about as well as the forward poses (before a switch the two headings
    explain a frame alike, or the recheck would have turned sooner), and the frames next to
    it better (:func:`best_prefix`). A switch whose backward track scores worse from the
    first frame back says the twin's lead on the switch's frame was noise. So for a look:
    one frame's energy lower by the margin, but the frames before it explained worse from
    its pose than the track explained them.

    ``held[-1]`` (frame ``index``'s pose) is replaced; the tracker's state becomes the
    unswitched one with the re-track entry, ``revoked: true`` and the ``switch`` (or the
    look's ``recovery`` entry), appended to its ``retracks``. Returns False, the correction
    standing (and no backward frame taken), when the track without it is dropped on that
    frame.
    """
    look = was_look(tracker.state, kind)
    corrected = (tracker.state.recoveries[-1] if look else tracker.state.heading_switches[-1])
    entry = {**tracker.state.retracks[-1], "revoked": True,
             ("recovery" if look else "switch"): {k: v for k, v in corrected.items()
                                                  if k != "frame"}}
    with tracker.settings_overlaid(NO_LOOK if look else {"heading": RETRO_OFF["heading"]}):
        state, x = tracker.advance(before, depth)
    if x is None:
        return False
    held[-1] = (index, x)
    cleared = {} if look else CHANNELS_CLEARED
    tracker.state = state.replace(**cleared, retracks=state.retracks + (entry,))
    return True
