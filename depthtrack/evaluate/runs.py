"""Batch evaluation: track (or read tracks of) sequences with several methods and score them.

Each sequence is scored against its own ground truth (``groundtruth/joints.csv`` and,
when present, ``groundtruth/markers.csv``) when it has one, and always by how well the
fitted body explains the depth (:mod:`.fit`: silhouette IoU, unexplained share, depth
residual), so recordings without ground truth are scored too. The result is one :class:`MethodResult` per
(sequence, method) plus the per-sequence and overall summaries that ``depthtrack eval``
prints and writes.

Overall figures average over sequences, each sequence weighing the same
(:func:`depthtrack.evaluate.metrics.average_summaries`); ``frames`` is the total.
"""
from __future__ import annotations

import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError
# the paper's three trackers (hc, ep, hc+ep) and two likelihoods, as the tracker defines them
from ..track import LIKELIHOODS, METHODS
from . import metrics
from .markers import known_marker_names, marker_positions


@dataclass
class MethodResult:
    """One method's track of one sequence, and its errors.

    Attributes
    ----------
    sequence : str
        The sequence's name (its directory or file stem).
    method : str
    joints : (F, 15, 3) float
        Tracked contract joints, NaN where the track has none.
    joint_errors : (F, 15) float
        NaN where ground truth or estimate is unknown.
    marker_errors : (F, M) float or None
        ``None`` when the sequence has no (usable) markers.
    marker_names : list of str
        The M markers scored.
    seconds : float or None
        Tracking time.
    summary : dict
        :func:`depthtrack.evaluate.metrics.summarize` of the above.
    poses : (F, D) float or None
        Tracked poses, when known.
    body : BodyModel or None
        The body the poses belong to.
    track_summary : dict
        The tracker's own summary (its summary.json for ``--track`` outputs).
    fit : (F, 3) float or None
        Per-frame fit figures (:func:`depthtrack.evaluate.fit.track_fit`): silhouette IoU,
        unexplained share, median depth residual; NaN where undefined.
    """

    sequence: str
    method: str
    joints: np.ndarray
    joint_errors: np.ndarray
    marker_errors: np.ndarray | None
    marker_names: list
    seconds: float | None
    summary: dict = field(default_factory=dict)
    poses: np.ndarray | None = None
    body: object = None
    track_summary: dict = field(default_factory=dict)
    fit: np.ndarray | None = None


@dataclass
class Evaluation:
    """All results of one ``depthtrack eval`` run.

    Attributes
    ----------
    results : list of MethodResult
        In sequence order, then method order.
    likelihood : str or None
        The likelihood the tracks were made with (``None`` when read from ``--track``).
    failures : list of depthtrack.evaluate.batch.SequenceFailure
        Sequences that could not be evaluated (the others are in ``results``).
    """

    results: list
    likelihood: str | None = None
    failures: list = field(default_factory=list)

    @property
    def sequences(self) -> list:
        """Sequence names in first-seen order."""
        return list(dict.fromkeys(r.sequence for r in self.results))

    @property
    def methods(self) -> list:
        """Method names in first-seen order."""
        return list(dict.fromkeys(r.method for r in self.results))

    def get(self, sequence, method):
        for r in self.results:
            if r.sequence == sequence and r.method == method:
                return r
        return None

    def overall(self) -> dict:
        """{method: summary averaged over the sequences that method ran on}."""
        return {m: metrics.average_summaries(r.summary for r in self.results if r.method == m)
                for m in self.methods}

    def to_dict(self) -> dict:
        """``{"sequences": {NAME: {METHOD: M}}, "overall": {METHOD: M}}``, M as in :func:`metrics.summarize`."""
        sequences = {}
        for r in self.results:
            sequences.setdefault(r.sequence, {})[r.method] = dict(r.summary)
        out = {"sequences": sequences, "overall": self.overall()}
        if self.failures:
            out["failed"] = {f.name: f.message for f in self.failures}
        return out


# ------------------------------------------------------------------ inputs
def sequence_name(path) -> str:
    """A sequence's name: its directory name (or a ``.npz`` file's stem)."""
    path = Path(path)
    if path.suffix.lower() == ".npz":
        return path.stem
    return path.resolve().name or str(path)


def open_with_ground_truth(path, require: bool = True, **options):
    """Open a sequence and (with ``require``) check that it carries ground truth to score against.

    Raises
    ------
    InputError
        Missing/malformed sequence, or (with ``require``) no known ground-truth joint or marker.
    """
    from ..io.sequence import open_sequence

    seq = open_sequence(path, **options)
    if not require:
        return seq
    joints, markers = seq.joints, seq.markers
    has_joints = joints is not None and np.isfinite(joints).all(axis=-1).any()
    has_markers = markers is not None and np.isfinite(markers).all(axis=-1).any()
    if not (has_joints or has_markers):
        raise InputError(path, "no ground truth to evaluate against (groundtruth/joints.csv "
                               "or markers.csv with at least one known row)")
    return seq


def check_methods(methods) -> list:
    """Validate method names; returns them as a list without duplicates.

    Raises
    ------
    InputError
        An unknown method.
    """
    methods = list(dict.fromkeys(m.strip() for m in methods if m.strip()))
    if not methods:
        raise InputError(None, f"no method given; choose from {', '.join(METHODS)}")
    for m in methods:
        if m not in METHODS:
            raise InputError(None, f"unknown method {m!r}; choose from {', '.join(METHODS)}")
    return methods


def body_for_track_dir(track_dir, track):
    """The body of a track output: its ``body.json`` (the fitted shape) when present, else
    :func:`body_for_track`."""
    from ..body import BodyModel

    path = Path(track_dir) / "body.json"
    return BodyModel.from_json(path) if path.is_file() else body_for_track(track)


def body_for_track(track):
    """The body a track was made with, rebuilt from its height and bone offsets.

    Parameters
    ----------
    track : depthtrack.io.track_output.Track

    Returns
    -------
    BodyModel
        The default body at ``track.body_height`` with per-bone stretch recovered from
        ``track.body_offsets`` (the head's own stretch is not stored and stays 1).
    """
    from ..body import BodyModel

    body = BodyModel.default(height=track.body_height)
    offsets = np.asarray(track.body_offsets, float)
    if offsets.shape != body.offsets.shape or np.allclose(offsets, body.offsets, atol=1e-6):
        return body
    lengths, base = np.linalg.norm(offsets, axis=1), np.linalg.norm(body.base_offsets, axis=1)
    bones = [j for j in range(1, len(base)) if base[j] > 0]
    ratio = {j: lengths[j] / base[j] for j in bones}
    # the uniform scale is what most bones share; the height then fixes it exactly
    uniform = float(np.median(list(ratio.values())))
    stretch = {body.joint_names[j]: float(r / uniform) for j, r in ratio.items()
               if abs(r / uniform - 1.0) > 1e-6}
    return body.scaled(height=track.body_height, segment_scale=stretch)


def _positive(value) -> bool:
    """Whether a summary.json field holds a finite positive number."""
    return isinstance(value, (int, float)) and bool(np.isfinite(value)) and value > 0


def summary_seconds(summary: dict, frames: int):
    """Tracking time from a track's summary.json: ``seconds``; else ``frames / fps`` only if
    the summary says the fps is a processing rate (``processing_fps``); else ``None``."""
    if _positive(summary.get("seconds")):
        return float(summary["seconds"])
    if _positive(summary.get("processing_fps")):
        return frames / float(summary["processing_fps"])
    return None


def summary_wall_seconds(summary: dict):
    """The whole tracking work from a track's summary.json (``wall_seconds``: the body
    height and shape fits too); None in summaries written before it existed."""
    return float(summary["wall_seconds"]) if _positive(summary.get("wall_seconds")) else None


# ------------------------------------------------------------------ scoring
def score(name, method, seq, joints, poses=None, body=None, seconds=None, masks=None,
          wall_seconds=None) -> MethodResult:
    """Score one track of one sequence.

    Parameters
    ----------
    name, method : str
    seq : depthtrack.io.sequence.Sequence
        With ground truth.
    joints : (F, 15, 3) float
        Tracked contract joints.
    poses : (F, D) float or None
        Tracked poses; needed (with ``body``) for the marker errors.
    body : BodyModel or None
    seconds : float or None
        Tracking time.
    wall_seconds : float or None
        The whole tracking work, body fits included (``summary.json``'s ``wall_seconds``).
    masks : list of (H, W) bool or None
        The person's foreground per frame (:func:`depthtrack.evaluate.fit.person_masks`),
        for the fit figures; computed when None and ``poses`` and ``body`` are given.
    """
    from . import fit as fit_figures

    F = len(seq)
    joints = np.asarray(joints, float)
    if joints.shape != (F, 15, 3):
        raise InputError(seq.path, f"track has {joints.shape[0]} frames, the sequence {F}")
    truth = seq.joints if seq.joints is not None else np.full((F, 15, 3), np.nan)
    joint_err = metrics.joint_errors(joints, truth)
    marker_err, names = None, []
    if seq.markers is not None and poses is not None and body is not None:
        names = known_marker_names(seq.marker_names or [])
        if names:
            cols = [list(seq.marker_names).index(n) for n in names]
            model = marker_positions(body, poses, names)
            marker_err = metrics.marker_errors(model, seq.markers[:, cols])
    per_frame = None
    if poses is not None and body is not None:
        per_frame = fit_figures.track_fit(seq, poses, body, masks)
    shape = fit_figures.shape_errors(body, fit_figures.shape_truth(seq))
    summary = metrics.summarize(joint_err, F, seconds, marker_err, wall_seconds=wall_seconds,
                                reversed_frames=metrics.back_to_front(joints, truth),
                                twist_err=metrics.twist_errors(joints, truth),
                                fit=None if per_frame is None else fit_figures.summarize_fit(per_frame),
                                shape=shape if shape["segment_length_errors_m"] else None)
    return MethodResult(name, method, joints, joint_err, marker_err, names, seconds, summary, poses, body,
                        fit=per_frame)


def track_sequence(seq, method: str, likelihood: str = "smoothed", quiet: bool = True,
                   settings=None):
    """Track a sequence as ``depthtrack track`` does (:func:`depthtrack.track.run.run_tracking`:
    automatic initialisation, body height from sequence.json or estimated; no ground truth),
    with ``settings`` (:class:`~depthtrack.track.TrackerSettings`; None = the defaults).

    Returns
    -------
    joints : (F, 15, 3) float
    poses : (F, D) float
    body : BodyModel
    seconds : float
        Wall-clock tracking time, initialisation included.
    summary : dict
        The tracker's summary (method, settings, timings...), as ``depthtrack track`` writes it.
    """
    from ..progress import Progress
    from ..track import run_tracking

    start = time.perf_counter()
    with Progress(len(seq), f"{method} frames", quiet=quiet) as progress:
        result, body, summary = run_tracking(seq, method=method, likelihood=likelihood,
                                             progress=progress, settings=settings)
    seconds = summary.get("seconds") or (time.perf_counter() - start)
    return (np.asarray(result.joints, float), np.asarray(result.poses, float), body, float(seconds),
            summary)


def evaluate(sequence_paths, methods=METHODS, likelihood: str = "smoothed", track_dirs=None,
             quiet: bool = True, log=None, open_options=None, executor: str = "serial",
             workers: int | None = None, dask_address: str | None = None, tracks_out=None,
             keep_going: bool = False, settings=None) -> Evaluation:
    """Track and score sequences (or score existing tracks).

    Parameters
    ----------
    sequence_paths : sequence of path-like
        Sequence directories or ``.npz`` files; without ground truth only the fit figures
        are known (accuracy fields None).
    methods : sequence of str
        Tracking methods from :data:`METHODS` (ignored with ``track_dirs``).
    likelihood : {"smoothed", "pixel"}
    track_dirs : sequence of path-like or None
        Existing track outputs, one per entry of ``sequence_paths`` (paired in order;
        repeat a sequence to score several tracks of it). The method name is the track's
        ``summary.json`` ``method`` (``"track"`` when absent).
    quiet : bool
        No progress on stderr.
    log : callable(str) or None
        Receives one line per finished (sequence, method).
    open_options : dict or None
        Reader options for :func:`depthtrack.io.registry.open_sequence` (``topic``, ...).
    executor, workers, dask_address : see :func:`depthtrack.evaluate.batch.run_tasks`
        How the sequences are tracked (one task per sequence): ``"serial"``, ``"workers"``
        (a spawned process pool) or ``"dask"``. Scoring ``track_dirs`` always runs here.
    tracks_out : path-like or None
        Also write every track to ``tracks_out/NAME/METHOD/`` (atomically, per track).
    keep_going : bool
        False (default): the first sequence that fails raises. True (``depthtrack eval``):
        it is recorded in ``Evaluation.failures`` and the others run on.
    settings : TrackerSettings or None
        The tracker's settings for every sequence (None = the defaults).

    Raises
    ------
    InputError
        Before any work is done: an unknown method or likelihood, two sequences with one
        name; with ``track_dirs`` also a missing sequence, one without ground truth, a
        track that does not match its sequence. When tracking, a sequence that cannot be
        read raises when it is reached (with ``keep_going``: see above).
    """
    if likelihood not in LIKELIHOODS:
        raise InputError(None, f"unknown likelihood {likelihood!r}; choose from {', '.join(LIKELIHOODS)}")
    sequence_paths = [Path(p) for p in sequence_paths]
    if not sequence_paths:
        raise InputError(None, "no sequence given")
    names = {}
    for p in sequence_paths:
        name = sequence_name(p)
        other = names.setdefault(name, str(p.resolve()))
        if other != str(p.resolve()):
            raise InputError(p, f"another sequence is also named {name!r}; names must be unique")
    log = log or (lambda line: None)
    masks = {}

    def masks_of(seq):
        """The person's foreground per frame, segmented once per sequence for all methods."""
        from .fit import person_masks

        key = str(seq.path)
        if key not in masks:
            masks[key] = person_masks(seq)
        return masks[key]

    results = []
    if track_dirs is not None:
        from ..io.track_output import read_track

        sequences = {}
        for p in sequence_paths:
            key = str(p.resolve())
            if key not in sequences:
                sequences[key] = open_with_ground_truth(p, require=False, **(open_options or {}))

        track_dirs = [Path(t) for t in track_dirs]
        if len(track_dirs) != len(sequence_paths):
            raise InputError(None, f"{len(track_dirs)} --track outputs for {len(sequence_paths)} "
                                   "sequences; give one per sequence, in order")
        jobs, seen = [], set()
        for seq_path, track_dir in zip(sequence_paths, track_dirs):
            seq = sequences[str(seq_path.resolve())]
            track = read_track(track_dir)
            if len(track.poses) != len(seq):
                raise InputError(track_dir, f"track has {len(track.poses)} frames, sequence "
                                            f"{seq_path} has {len(seq)}")
            method = str(track.summary.get("method") or "track")
            key = (sequence_name(seq_path), method)
            if key in seen:
                raise InputError(track_dir, f"a second {method!r} track of {key[0]!r}")
            seen.add(key)
            jobs.append((key, seq, track, track_dir))
        for (name, method), seq, track, track_dir in jobs:
            body = body_for_track_dir(track_dir, track) if track.poses.shape[1] == 48 else None
            result = score(name, method, seq, track.joints, track.poses, body,
                           summary_seconds(track.summary, len(track.poses)),
                           masks=masks_of(seq) if body is not None else None,
                           wall_seconds=summary_wall_seconds(track.summary))
            result.track_summary = dict(track.summary)
            log(_line(result))
            results.append(result)
        return Evaluation(results, likelihood=None)

    methods = check_methods(methods)
    from .batch import SequenceTask, run_tasks

    unique = list(dict.fromkeys(str(p.resolve()) for p in sequence_paths))
    tasks = [SequenceTask(i, p, sequence_name(p), tuple(methods), likelihood,
                          None if tracks_out is None else str(Path(tracks_out)),
                          progress=executor == "serial" and not quiet,
                          open_options=dict(open_options or {}), settings=settings)
             for i, p in enumerate(unique)]
    results, failures = run_tasks(tasks, executor, workers=workers, address=dask_address, log=log,
                                  keep_going=keep_going)
    return Evaluation(results, likelihood=likelihood, failures=failures)


def _fmt(value, scale=1.0, unit="", digits=1):
    return "n/a" if value is None else f"{value * scale:.{digits}f}{unit}"


def _line(r: MethodResult) -> str:
    s = r.summary
    return (f"{r.sequence} {r.method}: mean {_fmt(s['mean_error_m'], 100, ' cm')}, "
            f"max {_fmt(s['max_error_m'], 100, ' cm')}, within 10 cm {_fmt(s['within_10cm'], 100, '%', 0)}, "
            f"markers {_fmt(s['marker_mean_error_m'], 100, ' cm')}/{_fmt(s['marker_max_error_m'], 100, ' cm')}, "
            f"IoU {_fmt(s.get('silhouette_iou'), 1, '', 2)}, "
            f"unexplained {_fmt(s.get('unexplained_fraction'), 100, '%', 0)}, "
            f"{_fmt(s['fps'], 1, ' fps')}")


def print_line(line: str) -> None:
    """Progress line on stderr (stdout stays for results)."""
    print(line, file=sys.stderr, flush=True)


__all__ = ["METHODS", "LIKELIHOODS", "MethodResult", "Evaluation", "sequence_name",
           "open_with_ground_truth", "check_methods", "body_for_track", "body_for_track_dir", "summary_seconds", "summary_wall_seconds", "score",
           "track_sequence", "evaluate"]
