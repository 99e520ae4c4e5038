"""The body for a sequence: its height from ``sequence.json``, else fitted by the likelihood;
then its shape, fitted to the first frames (:func:`fit_body_shape`).

Every height tried is scored with one set of renderers (bodies of any height share the
default mesh; :meth:`~.renderers.RendererSet.set_body`), released when the fit ends. The
shape fit tracks the first frames with a tracker of its own and fits with one renderer of
its own (:func:`~.shape_fit.fit_shape`); both are released before it returns.
"""
from __future__ import annotations

import itertools
import time

import numpy as np

from ..errors import InputError
from .observation import estimate_height, robust_points, visible_area
from .renderers import RendererSet
from .settings import TrackerSettings

#: The settings groups that turn every recheck off while tracking (the shape fit's trial
#: without :attr:`ShapeSettings.trial_rechecks`); the start's front/back check stays.
NO_RECHECKS = {"heading": {"every": 0, "limb_every": 0, "search_every": 0, "reseat_every": 0,
                           "reseat_free": 0.0, "reseat_hidden": 0.0},
               "propose": {"reach_every": 0}}


def parabola_vertex(heights, energies, k: int) -> float:
    """Height at the vertex of the parabola through the best height ``k`` and its neighbours,
    in log height (the grid is geometric); the best height itself when the parabola opens down."""
    x0, x1, x2 = np.log(heights[k - 1:k + 2])
    e0, e1, e2 = energies[k - 1:k + 2]
    denom = (x0 - x1) * (x0 - x2) * (x1 - x2)
    a = (x2 * (e1 - e0) + x1 * (e0 - e2) + x0 * (e2 - e1)) / denom
    b = (x2 ** 2 * (e0 - e1) + x1 ** 2 * (e2 - e0) + x0 ** 2 * (e1 - e2)) / denom
    if a > 0:
        return float(np.exp(np.clip(-b / (2 * a), x0, x2)))
    return float(heights[k])


def fit_body_height(depth, foreground, camera, fps: float = 25.0, settings=None, segmenter=None):
    """The default body at the height whose automatic start explains ``depth`` best.

    A first guess from the foreground's extent (:func:`estimate_height`), which raised arms
    inflate and bent or foreshortened legs shrink; then the automatic start ("hc") runs on
    the frame for heights :attr:`HeightSettings.ratio` apart around the guess (further out
    while the best is at an edge), and the height of the lowest likelihood energy wins,
    refined by a parabola through its neighbours.

    Returns
    -------
    body : BodyModel
    info : dict
        ``height_m``, ``source``, ``foreground_guess_m``, ``seconds`` and ``candidates`` (the
        heights tried and their likelihood energies).
    """
    from ..body import BodyModel
    from .tracker import Tracker

    settings = settings or TrackerSettings()
    h_set = settings.height
    guess = estimate_height(robust_points(foreground.points))
    t0 = time.perf_counter()
    tried = {}
    renderers = None
    try:
        def energy_at(h):
            nonlocal renderers
            h = round(float(np.clip(h, h_set.min_m, h_set.max_m)), 3)
            if h not in tried:
                body = BodyModel.default(height=h)
                if renderers is None:
                    # the start never polishes: no fine renderer
                    renderers = RendererSet(body.with_mesh(settings.observe.render_mesh), camera,
                                            settings.observe.tile)
                tracker = Tracker(body, camera, method="hc", fps=fps, settings=settings,
                                  segmenter=segmenter, renderers=renderers)
                _, frame, x = tracker.start(tracker.state, depth, foreground=foreground)
                tried[h] = tracker.likelihood_energy(x, frame)
            return h

        for k in range(-h_set.steps, h_set.steps + 1):
            energy_at(guess * h_set.ratio ** k)
        # walk outwards while the best height is at an edge of what was tried
        for _ in range(h_set.walk):
            heights = sorted(tried)
            best = min(heights, key=tried.get)
            if best == heights[0] and best > h_set.min_m:
                energy_at(best / h_set.ratio)
            elif best == heights[-1] and best < h_set.max_m:
                energy_at(best * h_set.ratio)
            else:
                break
    finally:
        if renderers is not None:
            renderers.release()
    heights = np.array(sorted(tried))
    energies = np.array([tried[h] for h in heights])
    k = int(np.argmin(energies))
    h = float(heights[k])
    if 0 < k < len(heights) - 1:
        h = parabola_vertex(heights, energies, k)
    return BodyModel.default(height=h), {
        "height_m": round(h, 3),
        "source": "fitted to the first frame by the likelihood (no subject.height_m)",
        "foreground_guess_m": round(guess, 3),
        "seconds": round(time.perf_counter() - t0, 2),
        "candidates": [{"height_m": round(float(a), 3), "energy": round(float(b), 1)}
                       for a, b in zip(heights, energies)]}


def body_for_sequence(seq, segmenter=None, frame: int = 0, settings=None, fit_height: bool = True):
    """The default body scaled to the subject, and where its height came from.

    Height from ``sequence.json`` ``subject.height_m`` when present. Otherwise a first
    guess from the foreground extent of the first frame (from ``frame`` on) with a person
    (:func:`estimate_height`); with ``fit_height`` the height is then chosen by the
    likelihood (:func:`fit_body_height`; within :class:`HeightSettings`' range).

    Returns
    -------
    body : BodyModel
    height : dict
        ``{"height_m": float, "source": str}`` and, when fitted, ``"candidates"``: the heights
        tried and their likelihood energies.
    """
    from ..body import BodyModel

    if seq.subject_height:
        h = float(seq.subject_height)
        return BodyModel.default(height=h), {"height_m": h, "source": "sequence.json subject.height_m"}
    if segmenter is None:
        from ..detect import segment_foreground as segmenter
    min_area = (settings or TrackerSettings()).observe.min_person_area
    for frame in range(frame, len(seq)):       # the first frame with a person in it
        depth = seq.depth(frame)
        fg = segmenter(depth, seq.camera)
        if visible_area(fg, seq.camera) >= min_area:
            break
    else:
        raise InputError(seq.path, "no person found in any frame")
    if not fit_height:
        guess = estimate_height(robust_points(fg.points))
        return BodyModel.default(height=guess), {"height_m": round(guess, 3),
                                                 "source": "estimated from the first frame's foreground"}
    return fit_body_height(depth, fg, seq.camera, fps=seq.fps, settings=settings, segmenter=segmenter)


def trial_settings(settings):
    """The settings the shape fit's trial tracks with (:func:`fit_body_shape`), from the
    track's ``settings`` (:class:`TrackerSettings`)."""
    if not settings.shape.trial_rechecks:
        settings = settings.updated(NO_RECHECKS)
    # the trial yields its frames as it goes: no pose held back for a re-track after a switch
    # nor a final polish: the fit refines the trial's poses itself; nor a reach into
    # unexplained blobs, which the template's misfit makes of every limb
    # nor a re-seat of a limb over free space or tracked hidden: the trial, whose start the
    # track takes over, stays as it was measured (README, "A limb over free space")
    return settings.updated({"heading": {"retro_frames": 0, "reseat_free": 0.0,
                                         "reseat_hidden": 0.0},
                             "polish": {"final_tile": 0},
                             "propose": {"reach_unexplained": 0.0}})


def fit_body_shape(frames, body, camera, fps: float = 25.0, settings=None, segmenter=None,
                   fit_scale: bool = True, log=None, method: str = "hc"):
    """The body with the shape (and, with ``fit_scale``, the size) that explains the first
    frames best; no ground truth.

    The frames are tracked (by ``method``, the automatic start and the front/back check
    included) with ``body``; :attr:`ShapeSettings.fit_frames` of the frames that got a pose (spread
    evenly) go with the tracker's poses, their segmentation and floor plane to
    :func:`~.shape_fit.fit_shape` on the full mesh (the decimated one misplaces the
    forearm by centimetres).

    Parameters
    ----------
    frames : iterable of (H, W) float
        The sequence's frames from the first (or at least its first
        :attr:`ShapeSettings.frames`). The trial tracks the first ``ShapeSettings.frames``;
        the frames after them are read only where the start looks ahead past them (a
        deferred start, the front/back check's :attr:`HeadingSettings.frames`), so that the
        trial starts as the track would: with only the first frames, a start late in them
        had no frames left for its front/back check and skipped it.
    body : BodyModel
        The template at the subject's height (given or fitted).
    camera : Camera
    fit_scale : bool
        Also fit the size; False when the height is given.
    method : {"hc", "hc+ep"}
        The trial tracker's method. The re-track starts from the trial's frame-0 pose, so
        a tracker that uses the part recogniser (``"hc+ep"``) should start the trial with
        it too: its proposals join the start's candidates and judge the first frames.

    Returns
    -------
    body : BodyModel
        The fitted body (``body`` itself when too few frames had a person: ``info`` says so).
    info : dict
        ``fitted`` (bool), ``frames_tracked``, ``trial_recoveries`` (the trial's
        ``recoveries_tried`` and ``recoveries``), ``trial_heading_switches``,
        ``trial_limb_swaps``, ``trial_reaches``, ``trial_reseats`` (the trial's corrections,
        entries as in ``summary.json``'s lists of the same names), ``frames_used``, with
        :attr:`ShapeSettings.carry_back` ``trial_carried_back`` (``[{"index", "exchanged"}]``:
        the fit frames whose poses took the trial's later corrections, and which sides),
        ``seconds`` (tracking and fit), the fit's summary (:meth:`ShapeFit.to_dict`) or ``reason``; when frame 0 got
        a pose, ``start_pose``: its pose (48 floats) refined with the fitted body, and
        ``start_info``: how the trial's start went (its ``init_info``: candidates, finalists,
        the front/back check).
    """
    from .carry_back import carry_back_frames
    from .shape_fit import fit_shape
    from .tracker import Tracker

    settings = trial_settings(settings or TrackerSettings())
    s = settings.shape
    if segmenter is None:
        from ..detect import segment_foreground as segmenter
    t0 = time.perf_counter()
    depths = []                       # every frame read, the look-ahead's included

    def read():
        for d in frames:
            depths.append(np.asarray(d, dtype=np.float32))
            yield depths[-1]

    with Tracker(body, camera, method=method, fps=fps, settings=settings,
                 segmenter=segmenter) as tracker:
        stream = tracker.stream(read())
        try:
            # the first s.frames frames, in order (the stream yields every index once)
            trial = list(itertools.islice(stream, s.frames))
        finally:
            stream.close()
        tracked = [(i, x) for i, x in trial if x is not None]
        start = dict(tracker.state.init_info)
        recoveries = {k: tracker.recorder.counts[k] for k in ("recoveries_tried", "recoveries")}
        described = tracker.describe()
        # the trial's own corrections: they shape its poses and so the fit and the start
        corrections = {f"trial_{k}": described[k] for k in ("heading_switches", "limb_swaps",
                                                             "reaches", "reseats")}
        info = {"fitted": False, "frames_tracked": len(trial), "trial_recoveries": recoveries,
                **corrections}
        if len(tracked) < s.fit_frames:
            info.update(reason=f"{len(tracked)} of the first {len(trial)} frames got a pose; "
                               f"the fit needs {s.fit_frames}",
                        seconds=round(time.perf_counter() - t0, 2))
            return body, info
        pick = np.unique(np.linspace(0, len(tracked) - 1, s.fit_frames).round().astype(int))
        index = [tracked[k][0] for k in pick]
        poses = np.array([tracked[k][1] for k in pick])
        fgs = [segmenter(depths[i], camera) for i in index]
        if s.carry_back:
            # the trial yields its frames with no re-track: its later corrections, carried back
            poses, info["trial_carried_back"] = carry_back_frames(
                tracker, described, index, poses, [depths[i] for i in index], fgs, s.carry_back)
    try:
        full = body.with_mesh("full")
    except ValueError:
        full = body
    fit = fit_shape(full, camera, [depths[i] for i in index], [f.mask for f in fgs], poses,
                    [f.floor_plane for f in fgs], tile=s.tile or None, rounds=s.rounds,
                    max_iterations=s.max_iterations, prior_weight=s.prior_weight,
                    fit_scale=fit_scale, log=log)
    info.update(fitted=True, frames_used=index, **fit.to_dict())
    info.update(fit_seconds=info.pop("seconds"), seconds=round(time.perf_counter() - t0, 2))
    if index[0] == 0:
        # the first frame's pose, refined with the fitted body: the re-track starts from it
        # and so keeps the trial's front/back decision (re-deciding it with a body a few
        # millimetres different flipped whole tracks on near-ties; README "Body shape")
        info["start_pose"] = fit.poses[0].tolist()
        info["start_info"] = start
    return fit.body.with_mesh(body.mesh_name) if full is not body else fit.body, info

