"""The frame loop: depth frames in, each frame's pose out as soon as it is final.

:func:`stream_poses` drives a :class:`~.tracker.Tracker` over any iterable of depth frames:
a start on the first frame with a person (then the front/back check, :mod:`.heading`),
:meth:`~.tracker.Tracker.advance` on every later frame, nothing on frames without a person,
a fresh start after the track is dropped. :func:`track_stream` is the public generator;
:meth:`Tracker.track_sequence` (and so ``depthtrack track``) runs the same loop.
"""
from __future__ import annotations

import collections
import itertools

import numpy as np

from ..body.facing import back_to_front, sides_exchanged
from .heading import LIMB_SWAPS, settle_heading
from .observation import cut_by_border
from .observe import as_depth, person_present, visible_area
from .settings import TrackerSettings
from .state import TrackedFrame
from .tracker import Tracker


def stream_poses(tracker, frames, init_pose=None):
    """Track depth frames from any iterable; yields ``(index, pose (48,) or None)`` in order.

    A pose is yielded as soon as it is final: at once, except around an automatic start
    (it reads the next :attr:`StartSettings.complete_frames` frames to see whether the
    person is still walking into view, and the front/back check tracks the next
    :attr:`HeadingSettings.frames` frames; a live stream that must not wait sets
    ``complete_fraction``, ``frames`` and ``retro_frames`` to 0)
    and while the segmentation misses the person (the track may yet be dropped, and
    then those frames get no pose), and with :attr:`HeadingSettings.retro_frames` that
    many frames late (a correction, :attr:`HeadingSettings.retro_after`, may yet re-track
    them: :func:`retrack_before_correction`). Frames without a person get None; tracking (re)starts
    with the automatic start on the next frame with a person.

    Parameters
    ----------
    frames : iterable of (H, W) float
    init_pose : (48,) float, optional
        Start from this pose on frame 0 (ablation: ground-truth initialisation).
    """
    s = tracker.settings
    source = iter(frames)
    pending = collections.deque()   # frames read ahead and given back
    held = []              # (index, pose) not yet yielded: the track may still drop them
    retro = s.heading.retro_frames
    recent = collections.deque(maxlen=max(retro, 1))   # (index, depth) a correction may re-track
    # the first frame each kind's re-track may reach: the start, or past an earlier correction
    lowest = dict.fromkeys(CORRECTION_ORDER, 0)

    def take(n):
        out = [pending.popleft() for _ in range(min(n, len(pending)))]
        return out + list(itertools.islice(source, n - len(out)))

    i = -1
    while True:
        got = take(1)
        if not got:
            break
        depth, i = got[0], i + 1
        if i == 0 and init_pose is not None:
            tracker.state, _, x = tracker.start(tracker.state, depth, pose=init_pose)
            held.append((i, x))
            recent.append((i, depth))
        elif tracker.state.pose is not None:
            before = tracker.state
            _advance_into(tracker, held, i, depth)
            kind = new_correction(before, tracker.state, s.heading.retro_after) if retro else None
            if kind is not None and tracker.state.pose is not None:
                retrack_before_correction(tracker, held, recent, lowest[kind], i, kind)
                lowest = reach_after(lowest, kind, i, s.heading.retro_stop)
            recent.append((i, depth))
        else:
            with tracker.recorder.timed("segment"):
                fg = tracker.segmenter(depth, tracker.camera)
            if not tracker.person_present(fg):
                tracker.state = tracker.state.replace(
                    frames_without_person=tracker.state.frames_without_person + 1)
                held.append((i, None))
            else:
                early = []
                if s.start.complete_fraction > 0:
                    depth, fg, early = _complete_view(tracker, depth, fg, take, pending)
                    i += len(early)
                tracker.state, frame, x = tracker.start(tracker.state, depth, foreground=fg)
                start_state = tracker.state
                recent.clear()
                recent.append((i, depth))
                lowest = dict.fromkeys(CORRECTION_ORDER, i)
                # no front/back check where the user said which way the person faces, unless
                # the start is near profile (StartSettings.facing_margin)
                clear = tracker.state.init_info.get("facing_clear") is True
                K = 0 if clear else s.heading.frames
                ahead = take(K) if K > 0 else []
                settled = None
                if K > 0 and len(ahead) >= min(K, s.heading.min_frames):
                    settled = settle_heading(tracker.state, ahead, tracker.track_through,
                                             tracker.turned_start(frame), s)
                if settled is not None:
                    tracker.state, poses = settled
                    started = [(i + k, p) for k, p in enumerate(poses)]
                    recent.extend((i + 1 + k, d) for k, d in enumerate(ahead))
                    i += len(ahead)
                else:                       # no check: the frames read ahead come next
                    started = [(i, x)]
                    pending.extendleft(reversed(ahead))
                if early:
                    back, events = _track_back(tracker, start_state.replace(pose=started[0][1]),
                                               early, started[0][0] - len(early))
                    held.extend(back)
                    tracker.state = tracker.state.replace(init_info={
                        **tracker.state.init_info, "deferred_frames": len(early)}, **{
                        key: getattr(tracker.state, key) + found for key, found in events.items()})
                held.extend(started)
        _stamp_indices(tracker.state.log, i)
        # frames of a streak without a person stay held: a dropped track drops them too
        # and the last retro_frames poses, which a correction may yet re-track
        keep = max(len(held) - max(tracker.state.absent if tracker.state.pose is not None
                                   else 0, retro), 0)
        yield from held[:keep]
        del held[:keep]
    yield from held


def first_complete(areas, fraction: float, cut=None) -> int:
    """The frame a start waits for (:attr:`StartSettings.complete_fraction`): the index of
    the first of ``areas`` (the person's visible area, m^2, frame by frame) that reaches
    ``fraction`` of the largest -- and, with ``cut`` (one bool per frame: the person runs off
    the image, :func:`~.observation.cut_by_border`), the first such frame not cut, where
    there is one (:attr:`StartSettings.complete_uncut`)."""
    need = fraction * max(areas)
    enough = [k for k, a in enumerate(areas) if a >= need]
    if cut is not None:
        whole = [k for k in enough if not cut[k]]
        if whole:
            return whole[0]
    return enough[0]


def _complete_view(tracker, depth, foreground, take, pending):
    """Where an automatic start waits for more of the person (:attr:`StartSettings.
    complete_fraction`): ``(depth, foreground, early)``, the frame to start on (and its
    segmentation, made here) and the frames before it, from this one, to be tracked
    backwards from the start.

    The next :attr:`StartSettings.complete_frames` frames are read ahead; the start is the
    first of this frame and them whose person covers at least ``complete_fraction`` of the
    largest visible area (m^2) among them (with ``complete_uncut``, the first such whose
    person is clear of the image's edges, where one is: :func:`first_complete`). Those after
    it are given back (``pending``).
    """
    g = tracker.settings.start
    camera = tracker.camera
    ahead = take(g.complete_frames)
    with tracker.recorder.timed("segment"):
        foregrounds = [foreground] + [tracker.segmenter(d, camera) for d in ahead]
    k = first_complete([visible_area(f, camera) for f in foregrounds], g.complete_fraction,
                       [cut_by_border(f.mask) for f in foregrounds] if g.complete_uncut else None)
    pending.extendleft(reversed(ahead[k:]))
    if k == 0:
        return depth, foreground, []
    return ahead[k - 1], foregrounds[k], [depth, *ahead[:k - 1]]


#: The state's event lists (each entry a dict with the log index ``frame``) that a backward
#: track's events join.
EVENT_LISTS = ("recoveries", "heading_switches", "limb_swaps", "reaches", "reseats")


def _track_back(tracker, state, early, first):
    """The frames ``early`` (sequence indices ``first`` on) before a deferred start, tracked
    backwards in time from the start ``state``.

    Returns ``(frames, events)``: ``frames`` ``[(index, pose or None), ...]``, None for all
    of them when that track is dropped; ``events`` the backward track's new entries of
    :data:`EVENT_LISTS` (a recovery, a heading switch on the way), each with
    ``"backward": True``, its sequence ``index``, and ``frame`` None (it counts the forward
    track's frames).
    """
    back = tracker.track_through(state, list(reversed(early)))
    if back is None:
        return [(first + k, None) for k in range(len(early))], {}
    start_log = state.frame - 1         # the start's log index; frame k back is at start_log + k
    start_index = first + len(early)

    def moved(event):
        f = event.get("frame")
        index = None if f is None else start_index - (f - start_log)
        return {**event, "frame": None, "index": index, "backward": True}
    events = {key: tuple(moved(e) for e in getattr(back[0], key)[len(getattr(state, key)):])
              for key in EVENT_LISTS}
    return [(first + k, p) for k, p in enumerate(back[1][::-1])], events


#: Which corrections :func:`new_correction` reports, first the one a frame's re-track
#: follows when it has several: a recovery replaces the whole pose.
CORRECTION_ORDER = ("heading", "recovery", "limbs")

#: What the backward track after each kind of correction runs without: the recheck that
#: made the correction (it must keep the correction's choice; after a limb swap or a
#: recovery the heading recheck too: the forward track's own checks found nothing there).
_HEADING_OFF = {"every": 0, "search_every": 0}
RETRO_OFF = {"heading": _HEADING_OFF,
             "limbs": {**_HEADING_OFF, "limb_every": 0},
             "recovery": {**_HEADING_OFF, "limb_every": 0}}

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
    recovery) the pose, within :data:`RETRO_AGREE_M` on average."""
    b, f = backward[None], forward[None]
    if kind == "heading":
        return not back_to_front(f, b)[0]
    if kind == "limbs":
        return not sides_exchanged(f, b, LIMB_SWAPS[detail])[0]
    return float(np.mean(np.linalg.norm(f - b, axis=-1))) < RETRO_AGREE_M


def retrack_before_correction(tracker, held, recent, lowest: int, at: int,
                              kind: str = "heading") -> None:
    """After a correction of ``kind`` (:data:`CORRECTION_ORDER`) on frame ``at``: the
    frames before it tracked again backwards from the corrected pose
    (:attr:`HeadingSettings.retro_frames`, ``retro_after``).

    The backward track runs with the recheck that made the correction off (it must keep the
    correction's choice, :data:`RETRO_OFF`) through ``recent`` ``[(index, depth), ...]``
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
    ``retro_margin``. The correction is the evidence: frames before it where one heading
    (or one side for the limbs) explained the image clearly better would have been corrected
    sooner, so there the two score alike, and the backward track's continuity with the
    corrected pose is what tells them apart; the margin only refuses a backward track that
    lost the person. Either way ``tracker.state.retracks`` gets an entry.
    The tracker's state is the corrected forward state again afterwards: the forward track
    goes on as it would have.
    """
    settings = tracker.settings
    h = settings.heading
    corrected = tracker.state
    detail = corrected.limb_swaps[-1]["limbs"] if kind == "limbs" else None
    where = {index: k for k, (index, _) in enumerate(held)}
    shares = {e["index"]: e.get("cost") for e in corrected.log[-(len(recent) + 2):] if "index" in e}
    state, poses, indices, backward, judged = corrected, [], [], [], []
    stopped = None
    tracker.settings = settings.updated({"heading": RETRO_OFF[kind]})
    try:
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
            if gave_up(judged, h.retro_margin, h.retro_give_up):
                stopped = "worse"
                break
    finally:
        tracker.settings = settings
    entry = {"kind": kind, "index": at, "frames": len(indices),
             "stopped": stopped or "window", "taken": False}
    if indices:
        e_back, e_forward = np.mean(judged, axis=0)
        # (a track given up on scores above the margin over the frames it reached)
        n = (len(indices) if e_back <= e_forward * (1.0 + h.retro_margin) else
             best_prefix(judged, 0.0) if h.retro_take == "prefix" else 0)
        entry.update(first=indices[-1], last=indices[0], taken=n > 0,
                     energy_forward=round(float(e_forward), 1),
                     energy_backward=round(float(e_back), 1),
                     share_forward=round(float(np.mean([shares[j] for j in indices])), 4),
                     share_backward=round(float(np.mean(backward)), 4),
                     frames_taken=n, **({"first_taken": indices[n - 1]} if n else {}))
        for index, x in zip(indices[:n], poses[:n]):
            held[where[index]] = (index, x)
    tracker.state = corrected.replace(retracks=corrected.retracks + (entry,))


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


def _stamp_indices(log, last) -> None:
    """Give the log entries that have none their sequence frame ``index``: the newest
    entries are the frames up to ``last``, in order. (In place: an entry's frame never
    changes, and a twin's log shares its entries with the track it came from.)"""
    k = len(log)
    while k > 0 and "index" not in log[k - 1]:
        k -= 1
    for j, entry in enumerate(log[k:]):
        entry["index"] = last - (len(log) - k - 1) + j


def _advance_into(tracker, held, i, depth) -> None:
    """``advance`` on frame ``i`` as the loop does it, appending to ``held``: when the
    track is dropped, the frames of the streak without a person lose their poses too."""
    tracker.state, x = tracker.advance(tracker.state, depth)
    if x is not None:
        held.append((i, x))
        return
    streak = tracker.settings.observe.absent_frames - 1
    tracker.state = tracker.state.replace(
        frames_without_person=tracker.state.frames_without_person + streak)
    first = max(len(held) - streak, 0)
    held[first:] = [(j, None) for j, _ in held[first:]]
    held.append((i, None))


def track_stream(frames, camera, body=None, method: str = "hc+ep", likelihood: str = "smoothed",
                 fps: float = 25.0, settings: TrackerSettings | None = None, segmenter=None,
                 detector=None, init_pose=None, height: float | None = None):
    """Track depth frames one at a time; yield each frame's pose and joints as soon as known.

    The same loop as ``depthtrack track`` (:meth:`Tracker.stream`), over any iterable: a
    camera driver, a file reader, a list.

    Parameters
    ----------
    frames : iterable of (H, W) float
        Depth in metres, 0 = no reading.
    camera : Camera
    body : BodyModel, optional
        Default: the default body at ``height``, or, without ``height``, at the height fitted
        to the first frame with a person (:func:`~.height.fit_body_height`).
    method, likelihood, fps, settings, segmenter, detector, init_pose
        As :class:`Tracker` and :meth:`Tracker.stream`.

    Yields
    ------
    TrackedFrame
        ``index``, ``pose (48,)`` and ``joints (15, 3)`` (None where there is no person).

    Example
    -------
    >>> for f in track_stream(depth_frames, Camera.preset("sr4000"), height=1.75):  # doctest: +SKIP
    ...     print(f.index, f.joints[0] if f.joints is not None else "nobody")
    """
    from ..body import BodyModel

    frames = iter(frames)
    settings = settings or TrackerSettings()
    if body is None and height is not None:
        body = BodyModel.default(height=float(height))
    if body is None:
        from .height import fit_body_height

        seg = segmenter
        if seg is None:
            from ..detect import segment_foreground as seg
        before = []
        for depth in frames:
            depth = as_depth(depth, camera)
            before.append(depth)
            fg = seg(depth, camera)
            if person_present(fg, camera, settings):
                body, _ = fit_body_height(depth, fg, camera, fps=fps, settings=settings,
                                          segmenter=segmenter)
                break
        if body is None:
            body = BodyModel.default()        # nobody in any frame: every frame gets None
        frames = itertools.chain(before, frames)
    with Tracker(body, camera, method=method, likelihood=likelihood, fps=fps, settings=settings,
                 segmenter=segmenter, detector=detector) as tracker:
        for i, x in tracker.stream(frames, init_pose=init_pose):
            joints = None if x is None else np.asarray(body.joint_positions(x))
            yield TrackedFrame(i, x, joints)
