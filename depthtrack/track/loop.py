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

from .heading import settle_heading
from .judge import NO_LOOK
from .observation import cut_by_border
from .observe import as_depth, person_present, visible_area
from .retrack import (CORRECTION_ORDER, new_correction, reach_after, retrack_before_correction,
                      revoke_switch, was_look)
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
    them: :func:`.retrack.retrack_before_correction`). Frames without a person get None; tracking (re)starts
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
    # the frame whose pose the frames back to the last start are re-tracked from (-1: none)
    settle, settle_at = s.heading.retro_settle, -1
    at_start = start_overlay(s)   # laid over each automatic start and its front/back check

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
            settle_at = i + settle if settle else -1
        elif tracker.state.pose is not None:
            before = tracker.state
            _advance_into(tracker, held, i, depth)
            kind = new_correction(before, tracker.state, s.heading.retro_after) if retro else None
            if kind is not None and tracker.state.pose is not None:
                look = was_look(tracker.state, kind)
                revoked = (retrack_before_correction(tracker, held, recent, lowest[kind], i, kind)
                           and revoke_switch(tracker, held, before, depth, i, kind))
                # a look's re-track sets no floor: a later correction's re-track, on its own
                # evidence, may go back past it (JudgeSettings.look_every)
                if not revoked and not look:
                    lowest = reach_after(lowest, kind, i, s.heading.retro_stop)
            elif i == settle_at and retro and tracker.state.pose is not None:
                # back to the start, or to the last correction re-tracked since
                retrack_before_correction(tracker, held, recent, max(lowest.values()), i, "settle")
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
                with tracker.settings_overlaid(at_start):
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
                    displaced = tracker.state.init_info.get("displaced")
                    others = ([displaced["pose"]] if displaced and s.start.displaced_checked
                              else [])
                    with tracker.settings_overlaid(at_start):
                        settled = settle_heading(tracker.state, ahead, _test_track(tracker),
                                                 tracker.turned_start(frame), s, others)
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
                settle_at = max(started[0][0] + settle, i + 1) if settle else -1
        _stamp_indices(tracker.state.log, i)
        # frames of a streak without a person stay held: a dropped track drops them too
        # and the last retro_frames poses, which a correction may yet re-track
        keep = max(len(held) - max(tracker.state.absent if tracker.state.pose is not None
                                   else 0, retro), 0)
        yield from held[:keep]
        del held[:keep]
    yield from held


def start_overlay(settings) -> dict:
    """The settings laid over an automatic start and its front/back check: the Gaussian limb
    prior where the learned one is kept out of them (:attr:`EnergySettings.limb_prior_start`
    False), else nothing."""
    e = settings.energy
    if e.limb_prior == "learned" and not e.limb_prior_start:
        return {"energy": {"limb_prior": "gaussian"}}
    return {}


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


def _test_track(tracker):
    """``tracker.track_through`` without fresh looks (:data:`.judge.NO_LOOK`), for the start
    check's two tracks: each tests one heading."""
    def track(state, depths):
        with tracker.settings_overlaid(NO_LOOK):
            return tracker.track_through(state, depths)
    return track


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
