"""Front or back: the check after an automatic start, and the recheck while tracking.

A depth image barely tells a body's front from its back, and the start's heading prior
assumes the person faces the camera. Motion does tell them apart: knees and elbows bend one
way only. After a start both hypotheses are tracked through the next
:attr:`HeadingSettings.frames` frames, each from a copy of the start state; the other one
(by default the swapped twin, :func:`.twins.swapped_twin`; :attr:`HeadingSettings.start_twin`)
is kept only when its fit explains the frames clearly better: by default its mean unexplained
share is lower by :attr:`HeadingSettings.margin` (:attr:`HeadingSettings.start_by` for the
energy instead).

That check sees ten frames once: a start while the limbs are straight (the two twins
explain them equally well) decides by noise, and a wrong decision used to stand for the
whole clip. So the question stays open while tracking (:func:`recheck_heading`): every
:attr:`HeadingSettings.every` frames the tracked pose is compared with its twin facing the
other way with every joint left where it is (the sides exchanged, :func:`.twins.swapped_twin`),
climbed on that frame, by the energy without the motion prior (the likelihood plus the pose
prior, which charges a twin for the bent-backwards joints it needs), and the twin takes
over after :attr:`HeadingSettings.votes` clear wins in a row, or when its small wins add
up (a CUSUM test, :class:`~.settings.HeadingSettings`).

The same holds for the limbs alone: a track can settle with its legs (or arms) crossed,
each reaching where the other side's is, and every few frames twins with the legs' or the
arms' sides exchanged compete with the tracked pose (:func:`recheck_limb_sides`).

A twin is fitted to the exchanged joints from the pose turned half a turn and from the rest
pose (:func:`.twins.swapped_twins`): the first carries a wrong-facing pose's bends and twists over,
contorted; the lower-energy fit competes. Optionally (:func:`recheck_by_search`) the global
search also looks for the best pose facing the other way every few frames.
"""
from __future__ import annotations

import numpy as np

from .energy import relative_lead
from .twins import facing_direction, long_axis


def due(state, every: int) -> bool:
    """Whether a recheck run every ``every`` frames (0 = never) runs on ``state``'s frame."""
    return every > 0 and state.frame % every == 0


def settle_heading(start, depths, track, turn, settings, others=()):
    """Decide between the start pose and its turned twin by tracking both.

    Parameters
    ----------
    start : TrackingState
        Just after the start (its pose the initial one).
    depths : list of (H, W) float
        The next frames.
    track : callable ``(state, depths) -> (state, poses (K, 48), scores) or None``
        Tracks a state through the frames (None when the track was dropped); ``scores``
        holds the means over the frames of the unexplained share (``"unexplained"``) and
        of the energy without the motion prior per foreground pixel (``"energy"``).
    turn : callable ``(pose (48,)) -> (48,) or None``
        The turned twin of a pose, fitted to the start frame; None where the user's facing
        rules it out (then the initial pose is kept).
    settings : TrackerSettings
        :attr:`HeadingSettings.start_by` names the score that decides, and ``margin`` or
        ``energy_margin`` by how much (a fraction) the twin's must be lower.
    others : sequence of (48,) float
        Other start poses heard too (:attr:`StartSettings.displaced_checked`): each is
        settled against its own twin the same way, and the kept track of all starts with
        the lowest score wins (on the judge's tiles where every kept track has that score,
        else by ``start_by``).

    Returns
    -------
    None when the initial pose's track was dropped (no decision), else
    ``(state, poses (K+1, 48))``: the kept track, the start frame's pose first. Its
    ``init_info["heading_check"]`` holds both scores, the choice, and ``ambiguous``: whether
    the two scores were within the margin of each other (either way round), a decision the
    user may want to make (:attr:`StartSettings.facing`). With ``others``, ``"others"``
    lists each one's check the same way and ``"kept_start"`` the index of the start kept
    (0 = the initial pose, ``k`` = ``others[k - 1]``).
    """
    h = settings.heading
    first = _settle_pair(start, start.pose, depths, track, turn, h)
    if first is None:
        return None
    settled = [first]
    for x in others:
        other = _settle_pair(start, np.asarray(x, dtype=np.float64), depths, track, turn, h)
        if other is not None:
            settled.append(other)
    key = ("judged" if all("judged" in s["kept_score"] for s in settled) else h.start_by)
    kept = min(range(len(settled)), key=lambda k: settled[k]["kept_score"][key])
    state, poses = settled[kept]["state"], settled[kept]["poses"]
    info = {**state.init_info, "heading_check": settled[0]["info"]}
    if len(settled) > 1:
        info["heading_check"]["others"] = [s["info"] for s in settled[1:]]
        info["heading_check"]["kept_start"] = kept
        info["heading_check"]["starts_by"] = key
    return state.replace(init_info=info), poses


def _settle_pair(start, x_front, depths, track, turn, h):
    """The front/back check of one start pose ``x_front (48,)`` from ``start``'s state
    (:func:`settle_heading`): None when its track was dropped, else ``{"state", "poses",
    "kept_score", "info"}``."""
    a = track(start.replace(pose=x_front), depths)
    if a is None:
        return None
    state_a, track_a, score_a = a
    x_turned = turn(x_front)
    b = None if x_turned is None else track(start.replace(pose=x_turned), depths)
    score_b = None if b is None else b[2]
    margin = h.margin if h.start_by == "unexplained" else h.energy_margin
    # a close call either way: the kept heading's score within the margin of the other's
    ambiguous = b is not None and abs(score_b[h.start_by] - score_a[h.start_by]) < \
        margin * max(score_a[h.start_by], score_b[h.start_by])
    # a close call settled on finer tiles (HeadingSettings.judge_start): the lower wins
    judged = ambiguous and "judged" in score_a and "judged" in score_b
    if judged:
        turned = score_b["judged"] < score_a["judged"]
    else:
        turned = b is not None and score_b[h.start_by] < (1.0 - margin) * score_a[h.start_by]
    if turned:
        choice, state, poses = "turned", b[0], np.concatenate([x_turned[None], b[1]])
    else:
        choice, state, poses = "initial", state_a, np.concatenate([x_front[None], track_a])

    def rounded(score, key):
        return None if score is None or key not in score else round(score[key], 4)
    info = {"frames": len(depths), "by": h.start_by,
            "unexplained_initial": rounded(score_a, "unexplained"),
            "unexplained_turned": rounded(score_b, "unexplained"),
            "energy_initial": rounded(score_a, "energy"),
            "energy_turned": rounded(score_b, "energy"), "kept": choice,
            "ambiguous": bool(ambiguous), "turned_ruled_out": x_turned is None,
            **({"judged_initial": rounded(score_a, "judged"),
                "judged_turned": rounded(score_b, "judged"),
                "decided_by": "judge"} if judged else {})}
    return {"state": state, "poses": poses, "info": info,
            "kept_score": score_b if turned else score_a}


def recheck_heading(state, pose, refit, swapped_twin_of, pixels: float, settings, judge=None,
                    polish=None):
    """The heading recheck of one frame (module docstring): keep ``pose`` or its turned twin.

    Parameters
    ----------
    state : TrackingState
        Before this frame is logged (``state.frame`` is this frame's index).
    pose : (48,) float
        The frame's tracked pose.
    refit : callable ``(pose (48,)) -> (pose (48,), float)``
        A pose climbed on this frame by the energy without the motion prior, and that
        energy. Both hypotheses are climbed alike: the tracked pose was fitted with the
        motion prior, and a twin fitted without it would win by that alone.
    swapped_twin_of : callable ``(pose (48,)) -> (48,) or (K, 48)``
        The other-facing twin of a pose (:func:`.twins.swapped_twin`), or several fits of it
        (:func:`.twins.swapped_twins`): each is climbed, the lowest energy competes.
    pixels : float
        The foreground's pixel count (the margin's scale).
    settings : TrackerSettings
    judge : callable ``(poses (2, 48)) -> (2,)``, optional
        The energies the two climbed hypotheses are compared by, when not the climbs' own
        (:attr:`HeadingSettings.judge_tile`: the same energy on finer tiles).
    polish : callable ``(poses (2, 48)) -> (poses (2, 48), energies (2,))``, optional
        With ``judge``, a close call's two poses polished and judged again
        (:attr:`HeadingSettings.polish_within`): with ``polish_evidence`` "replace" the
        polished lead and twin stand for the judged ones; with "separate" they feed the
        second set of votes and sum, whose switch takes the polished twin.

    Returns
    -------
    pose : (48,) float
        The twin when it took over, else ``pose``.
    changes : dict
        For the state (``heading_votes``, ``heading_evidence``, ``polished_votes``,
        ``polished_evidence``, ``heading_switches``).
    switched : bool
    """
    h = settings.heading
    if not due(state, h.every):
        return pose, {}, False
    kept, e_pose = refit(pose)
    fits = [refit(t) for t in np.asarray(swapped_twin_of(pose)).reshape(-1, len(pose))]
    y, e_twin = min(fits, key=lambda f: float(f[1]))
    polished = None                      # a polished close call: (twin, its energies)
    if judge is not None:
        e_pose, e_twin = (float(e) for e in judge(np.stack([kept, y])))
        if polish is not None and close_call((e_pose - e_twin) / max(pixels, 1.0), h):
            (_, y_polished), energies = polish(np.stack([kept, y]))
            polished = (y_polished, *(float(e) for e in energies))
    if polished is not None and h.polish_evidence == "replace":
        (y, e_pose, e_twin), polished = polished, None
    lead = (e_pose - float(e_twin)) / max(pixels, 1.0)
    votes, evidence, by = _channel(state.heading_votes, state.heading_evidence, lead, h)
    changes = {"heading_votes": votes, "heading_evidence": evidence}
    from_polish = False
    if h.polish_evidence == "separate":
        # the polished leads' own votes and sum; the judged lead where no close call was polished
        if polished is not None:
            lead = (polished[1] - polished[2]) / max(pixels, 1.0)
        p_votes, p_evidence, p_by = _channel(state.polished_votes, state.polished_evidence, lead, h)
        changes.update(polished_votes=p_votes, polished_evidence=p_evidence)
        if by is None and p_by is not None:
            by, evidence, from_polish = p_by, p_evidence, True
            if polished is not None:
                y, e_pose, e_twin = polished
    if by is None:
        return pose, changes, False
    switch = {"frame": state.frame, "energy_kept": round(float(e_pose), 1),
              "energy_turned": round(float(e_twin), 1), "by": by,
              "evidence": round(evidence, 4), **({"polished": True} if from_polish else {})}
    return np.asarray(y, dtype=np.float64), {
        **CHANNELS_CLEARED, "heading_switches": state.heading_switches + (switch,)}, True


#: The heading recheck's votes and sums, cleared when the track turns or starts again.
CHANNELS_CLEARED = {"heading_votes": 0, "heading_evidence": 0.0,
                    "polished_votes": 0, "polished_evidence": 0.0}


def _channel(votes: int, evidence: float, lead: float, heading):
    """One channel of the heading recheck's decision: ``(votes, evidence, by)`` after a
    ``lead`` (per foreground pixel, positive: the twin's), ``by`` ``"votes"`` or
    ``"evidence"`` when the twin takes over on it, else None (:class:`HeadingSettings`:
    ``recheck_margin`` and ``votes``; Page's CUSUM with ``evidence_drift`` and
    ``evidence_threshold``)."""
    evidence = max(0.0, evidence + lead - heading.evidence_drift)
    votes = votes + 1 if lead > heading.recheck_margin else 0
    if votes >= heading.votes:
        return votes, evidence, "votes"
    if heading.evidence_threshold > 0 and evidence > heading.evidence_threshold:
        return votes, evidence, "evidence"
    return votes, evidence, None


def close_call(lead: float, heading) -> bool:
    """Whether the heading recheck's judged ``lead`` (per foreground pixel, positive: the
    twin's) is a close call to polish (:attr:`HeadingSettings.polish_within`,
    ``polish_side``): above ``-polish_within`` (``"above"``), or within ``polish_within``
    of zero (``"both"``: a clear lead either way is left as judged)."""
    if heading.polish_side == "both":
        return abs(lead) < heading.polish_within
    return lead > -heading.polish_within


def recheck_limb_sides(state, pose, refit, limb_twins_of, settings, floor: float = 0.0):
    """The sides recheck of one frame: keep ``pose`` or a twin with the legs' or the arms'
    sides exchanged.

    Seen from the side or from behind, the legs overlap in the image, and a track can settle
    with them crossed: the left knee and ankle where the right ones are and the reverse,
    each thigh crossing over -- a local minimum the climb does not leave, since moving one
    leg across the other explains the image worse on the way (dev: bend on Kinect v2 from 120
    degrees, seed 1, its upper body right and no knee or ankle within 10 cm for the whole
    clip; the legs-swapped twin of frame 25, climbed, had 21 % lower energy and 3.0 instead of
    7.3 cm mean joint error). Every :attr:`HeadingSettings.limb_every` frames both twins are
    climbed on the frame like the tracked pose, and the lower one replaces the track when its
    energy is lower by the fraction :attr:`HeadingSettings.limb_margin`.

    Parameters
    ----------
    state : TrackingState
        Before this frame is logged.
    pose : (48,) float
        The frame's tracked pose.
    refit : callable ``(pose (48,)) -> (pose (48,), float)``
        As for :func:`recheck_heading`.
    limb_twins_of : callable ``(pose (48,)) -> [(name, (48,)), ...]``
        :func:`.twins.limb_swapped_twins`.
    settings : TrackerSettings
    floor : float
        The energy every pose pays (:attr:`HeadingSettings.margins_over`); the margin is a
        fraction of the kept energy above it.

    Returns
    -------
    pose : (48,) float
        The twin when it took over, else ``pose``.
    changes : dict
        For the state (``limb_swaps``).
    switched : bool
    """
    if not due(state, settings.heading.limb_every):
        return pose, {}, False
    _, e_pose = refit(pose)
    fits = [(name, *refit(twin)) for name, twin in limb_twins_of(pose)]
    name, y, e_twin = min(fits, key=lambda f: float(f[2]))
    lead = relative_lead(e_pose, e_twin, floor)
    if lead <= settings.heading.limb_margin:
        return pose, {}, False
    swap = {"frame": state.frame, "limbs": name, "energy_kept": round(float(e_pose), 1),
            "energy_swapped": round(float(e_twin), 1)}
    return np.asarray(y, dtype=np.float64), {"limb_swaps": state.limb_swaps + (swap,)}, True


def flip_search(search, pose):
    """The global search's best pose facing away from ``pose (48,)``'s heading.

    ``search``: callable ``(heading (3,), body_axis (3,)) -> (pose (48,), energy)``, the global
    search (:func:`~.start.global_search`) with its heading prior turned to ``heading`` and its
    body-axis prior to ``body_axis``. The prior only prefers the other heading: where the
    image clearly says otherwise the search may return a pose facing the same way.
    Returns ``(pose (48,), energy)``.
    """
    return search(-facing_direction(pose), long_axis(pose))


def sort_by_heading(pose, energy: float, found):
    """The searches' poses sorted by the way they face, against the tracked ``pose (48,)``.

    ``found``: ``[(pose (48,), energy)]``. A search that prefers one heading may still
    return the other, so each result counts for the heading it has. Returns
    ``(flipped (48,) or None, its energy, the best energy facing as pose does)``: the
    lowest-energy result facing away from ``pose`` (None when none does), and the lowest of
    ``energy`` and the results facing the same way.
    """
    forward = facing_direction(pose)
    same = [float(energy)] + [float(e) for y, e in found if facing_direction(y) @ forward >= 0]
    away = [(y, float(e)) for y, e in found if facing_direction(y) @ forward < 0]
    if not away:
        return None, None, min(same)
    y, e = min(away, key=lambda f: f[1])
    return y, e, min(same)


def search_switch(state, e_pose: float, flipped, e_flipped: float, pixels: float, settings):
    """The periodic flip search's decision (:class:`~.settings.HeadingSettings`).

    Parameters
    ----------
    state : TrackingState
        Before this frame is logged.
    e_pose : float
        The tracked pose's energy without the motion prior, climbed on this frame.
    flipped : (48,) float
        :func:`flip_search`'s pose; ``e_flipped`` its energy, the same energy.
    pixels : float
        The foreground's pixel count.

    Returns ``(pose (48,) or None, changes for the state)``: the flipped pose when it takes
    over (the switch recorded ``by: "search"``), else None.
    """
    lead = (e_pose - float(e_flipped)) / max(pixels, 1.0)
    if lead <= settings.heading.search_margin:
        return None, {}
    switch = {"frame": state.frame, "energy_kept": round(float(e_pose), 1),
              "energy_turned": round(float(e_flipped), 1), "by": "search",
              "evidence": round(float(lead), 4)}
    return np.asarray(flipped, dtype=np.float64), {
        **CHANNELS_CLEARED, "heading_switches": state.heading_switches + (switch,)}


def recheck_by_search(state, pose, e_pose: float, search, pixels: float, settings):
    """The periodic flip search of one frame (:attr:`HeadingSettings.search_every`).

    ``search``: as :func:`flip_search`'s; ``e_pose``: the tracked ``pose (48,)``'s energy
    without the motion prior, climbed on this frame. The search runs for the other heading
    and, with :attr:`HeadingSettings.search_both`, for this one too (a fresh global search
    beats a tracked pose by its effort alone, whichever way it faces); each result counts
    for the heading it has (:func:`sort_by_heading`). Returns :func:`search_switch`'s
    ``(pose (48,) or None, changes)``.
    """
    found = [flip_search(search, pose)]
    if settings.heading.search_both:
        found.append(search(facing_direction(pose), long_axis(pose)))
    flipped, e_flipped, e_same = sort_by_heading(pose, e_pose, found)
    if flipped is None:
        return None, {}
    return search_switch(state, e_same, flipped, e_flipped, pixels, settings)
