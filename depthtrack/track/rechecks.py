"""Stage "recheck": whether the tracked pose faces the right way, has its limbs on the
right sides, reaches where the recogniser sees the parts and (when asked) has a limb the
limb library would seat better, each where due; and the turned twin the start's
front/back check tracks (:func:`turned_start`).

The decisions are pure functions in :mod:`.heading`, :mod:`.reach` and :mod:`.reseat`;
this module hands them the tracker's climbers, renderers and body. Every recheck scores
without the motion prior (a switch breaks the motion) on tiles of
:attr:`HeadingSettings.recheck_tile` pixels; the front/back recheck judges its two
climbed poses on :attr:`HeadingSettings.judge_tile` tiles.
"""
from __future__ import annotations

import numpy as np

from .energy import margin_floor
from .heading import due, flip_search, recheck_by_search, recheck_heading, recheck_limb_sides
from .twins import limb_swapped_twins, swapped_twins, turned_pose
from .proposals import frame_proposals
from .reach import (blob_reach_candidates, hidden_limbs, reach_candidates, recheck_reach,
                    share_in_pixels, unexplained_blobs)
from .reseat import free_space_limbs, limb_climber, limb_library, recheck_reseat
from .search import climb, lowest_climb
from .start import global_search, start_up, wrong_side


def recheck_stage(tracker, state, energy, frame, x):
    """The rechecks of a frame, each where due: :func:`.heading.recheck_heading`, then
    :func:`.heading.recheck_limb_sides`, then with the recogniser
    :func:`.reach.recheck_reach`, then :func:`.reseat.recheck_reseat`, then
    :func:`.heading.recheck_by_search`; the first that replaces the pose ends them.

    ``energy``: the frame's energy (its prior is dropped here); ``x (48,)``: the tracked pose.

    Returns ``(pose (48,), state changes, switched)``: ``switched`` is None, or which
    recheck replaced the pose (``"heading"``, ``"limbs"``, ``"reach"``, ``"reseat"``,
    ``"search"``).
    """
    s, recorder = tracker.settings, tracker.recorder
    bare = energy.without_prior().on(tracker.renderers.at_tile(s.heading.recheck_tile))
    floor = margin_floor(bare, s.heading.margins_over)
    # the tracked pose is climbed once for every recheck
    refit = once_per_pose(lambda pose: climb(bare, tracker.climbers.start, pose, recorder,
                                             passes=s.heading.twin_passes,
                                             level_offset=s.heading.refit_level))

    pixels = float(np.count_nonzero(frame.foreground.mask))
    judge_tile = s.heading.judge_tile

    def judge(poses):                    # asked for only where the recheck runs
        return tracker.judge_energy()(poses)
    polish = close_call_polish(tracker) if judge_tile and s.heading.polish_within > 0 else None
    with recorder.timed("heading"):
        y, changes, turned = recheck_heading(
            state, x, refit, lambda pose: recheck_twins(tracker.body, s, bare, pose), pixels, s,
            judge=judge if judge_tile else None, polish=polish)
        if turned:
            return y, changes, "heading"
        y, more, swapped = recheck_limb_sides(
            state, x, refit, lambda pose: limb_swapped_twins(tracker.body, pose), s, floor)
        if swapped:
            return y, {**changes, **more}, "limbs"
    if tracker.forest is not None:
        with recorder.timed("reach"):
            y, more, reached = recheck_reach(
                state, x, refit, bare, lambda pose: reach_all(tracker, frame, pose), s, floor)
        if reached:
            return y, {**changes, **more}, "reach"
    if s.heading.reseat_every or s.heading.reseat_free or s.heading.reseat_hidden:
        climb_limb = limb_climber(bare, tracker.climbers.start, recorder, s.heading.refit_level)
        labels = once_per_pose(tracker.renderers.labels)     # for both looks
        with recorder.timed("reseat"):
            y, more, reseated = recheck_reseat(
                state, x, refit, bare, climb_limb, limb_library(), s, clip=tracker.body.clip,
                floor=floor,
                free_limbs=lambda pose: over_free_space(tracker, frame, pose, labels(pose)),
                hidden_limbs=lambda pose: tracked_hidden(tracker, frame, labels(pose)))
        if reseated:
            return y, {**changes, **more}, "reseat"
    if not due(state, s.heading.search_every):
        return x, changes, None
    with recorder.timed("heading"):
        _, e_x = refit(x)
        taken, more = recheck_by_search(state, x, e_x, flip_searcher(tracker, bare, frame),
                                        pixels, s)
    if taken is None:
        return x, changes, None
    return taken, {**changes, **more}, "search"


def once_per_pose(compute):
    """``compute`` (``pose (48,) -> anything``) remembered per pose: asked again for the same
    pose, the first answer."""
    done = {}

    def remembered(pose):
        key = np.asarray(pose, dtype=np.float64).tobytes()
        if key not in done:
            done[key] = compute(pose)
        return done[key]
    return remembered


def over_free_space(tracker, frame, pose, labels):
    """:func:`.reseat.free_space_limbs` of ``pose (48,)`` on ``frame`` (one full-image depth
    render; ``labels (H, W)``: the pose's part labels), by :attr:`HeadingSettings.reseat_free`,
    ``reseat_free_pixels`` and ``reseat_free_gap``."""
    h = tracker.settings.heading
    r = tracker.renderers
    return free_space_limbs(r.depth(pose), labels, frame.depth, r.body.joint_names,
                            h.reseat_free, h.reseat_free_pixels, h.reseat_free_gap)


def tracked_hidden(tracker, frame, labels):
    """:func:`.reach.hidden_limbs` of a pose on ``frame`` from its part labels ``(H, W)``: the
    limbs whose lower segment shows on fewer than :attr:`HeadingSettings.reseat_hidden` of
    the person's pixels."""
    mask = frame.foreground.mask
    least = share_in_pixels(mask, tracker.settings.heading.reseat_hidden)
    return hidden_limbs(labels, mask, tracker.renderers.body.joint_names, least)


def close_call_polish(tracker):
    """``poses (K, 48) -> (poses (K, 48), energies (K,))``: each pose climbed by the final
    polish's climber (:attr:`~.search.Climbers.final`, from the search's finest rung) on the
    heading recheck's judge energy (:meth:`~.tracker.Tracker.judge_energy`), and its energy
    there (:attr:`HeadingSettings.polish_within`)."""
    def run(poses):
        energy = tracker.judge_energy()
        fits = [climb(energy, tracker.climbers.final, p, tracker.recorder,
                      level_offset=tracker.settings.search.levels - 1) for p in poses]
        return np.stack([f[0] for f in fits]), np.array([float(f[1]) for f in fits])
    return run


def reach_all(tracker, frame, pose):
    """The reach recheck's candidates for ``pose (48,)`` on ``frame``: to the recogniser's
    proposals (:func:`.reach.reach_candidates`) and, with
    :attr:`~.settings.ProposalSettings.reach_unexplained`, into the blobs of the person's
    pixels the pose leaves unexplained (:func:`.reach.blob_reach_candidates`, on the full
    image). Returns ``(poses (K, 48), limbs, sources)``."""
    s = tracker.settings.propose
    poses, limbs = reach_candidates(tracker.body, pose, frame_proposals(tracker, frame), s.min_confidence)
    sources = ["proposal"] * len(limbs)
    if s.reach_unexplained > 0:
        mask = frame.foreground.mask
        person = np.where(mask, frame.depth, 0.0)
        least = share_in_pixels(mask, s.reach_unexplained)
        blobs = unexplained_blobs(tracker.renderers.depth(pose), person, tracker.camera, least)
        free = None
        if blobs and s.reach_hidden_only:
            free = hidden_limbs(tracker.renderers.labels(pose), mask,
                                tracker.renderers.body.joint_names, least)
        more, more_limbs = blob_reach_candidates(tracker.body, pose, blobs, limbs_free=free)
        poses = np.concatenate([poses, more]) if len(more) else poses
        limbs, sources = limbs + more_limbs, sources + ["unexplained"] * len(more_limbs)
    return poses, limbs, sources


def heading_twins(body, settings, pose):
    """The swapped twins of ``pose (48,)`` the heading checks climb, ``(K, 48)``
    (:attr:`HeadingSettings.twin_starts`, ``twin_swaps``)."""
    return swapped_twins(body, pose, settings.heading.twin_starts, settings.heading.twin_swaps)


def recheck_twins(body, settings, energy, pose):
    """The twins of ``pose (48,)`` the heading recheck climbs, ``(k, 48)``: with
    :attr:`HeadingSettings.twin_climbs` ``k > 0``, the ``k`` of :func:`heading_twins` with
    the lowest unclimbed ``energy`` (``(N, 48) -> (N,)``, one batch); else all of them."""
    twins = heading_twins(body, settings, pose)
    k = settings.heading.twin_climbs
    if k <= 0 or k >= len(twins):
        return twins
    return twins[np.argsort(energy(twins), kind="stable")[:k]]


def flip_searcher(tracker, energy, frame):
    """``(heading, body_axis) -> (pose (48,), energy)``: the global search on ``frame`` with
    those priors (:func:`.heading.flip_search`)."""
    def run(heading, body_axis):
        x, e, _ = global_search(tracker, energy, frame, heading=heading, body_axis=body_axis)
        return x, e
    return run


def turned_start(tracker, frame):
    """``pose (48,) -> pose (48,) or None``: the turned twin of a pose, climbed on the start
    ``frame`` (re-uploaded; :attr:`HeadingSettings.start_twin` says which twin); None where
    it faces the other side than the user's :attr:`StartSettings.facing` by more than
    ``facing_margin``."""
    s = tracker.settings
    g = s.start

    def turn(pose):
        tracker.renderers.upload(frame)
        energy = tracker._energy(frame)
        kind = s.heading.start_twin
        if kind == "search":
            x, _ = flip_search(flip_searcher(tracker, energy, frame), pose)
        else:
            twins = (heading_twins(tracker.body, s, pose) if kind == "swapped"
                     else [turned_pose(pose)])
            x, _ = lowest_climb(energy, tracker.climbers.start, twins, tracker.recorder,
                                passes=g.passes)
        if x is None or wrong_side(x, g.facing, start_up(frame.foreground), g.facing_margin)[0]:
            return None
        return x
    return turn
