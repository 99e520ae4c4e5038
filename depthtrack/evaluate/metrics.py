"""Tracking error metrics: pure functions over arrays, NaN meaning "unknown".

Ground truth may miss rows (a joint or marker not recorded in a frame) and a tracker may
give no estimate for a frame; both are NaN and are left out of every statistic rather
than counted as zero or as failures.

Two families:

* joint metrics compare the 15 contract joints (``(F, 15, 3)``) of a track with the
  ground-truth joints;
* marker metrics are the paper's: for each frame the visible motion-capture markers
  ``m_i`` are compared with the corresponding points ``m^_i`` on the fitted surface mesh,
  ``avg = 1/M sum_i ||m_i - m^_i||`` and ``max = max_i ||m_i - m^_i||``; a sequence's
  figure is the mean of these per-frame values over the frames that have markers.

All distances are in the units of the inputs (metres throughout depthtrack).
"""
from __future__ import annotations

import numpy as np

from ..contract import JOINT_INDEX
from ..body.facing import TRUNK_SIDES, back_to_front  # noqa: F401 (part of this module's API)
from .fit import FIT_KEYS

#: A joint closer than this to its ground truth counts as "within" (metres).
WITHIN_THRESHOLD_M = 0.10


def point_errors(estimated, truth):
    """Euclidean distance of corresponding points.

    Parameters
    ----------
    estimated : (F, N, 3) float
        Estimated points; NaN where the estimate is unknown.
    truth : (F, N, 3) float
        Ground truth; NaN where unknown.

    Returns
    -------
    errors : (F, N) float
        ``||estimated - truth||``; NaN where the truth is unknown; ``+inf`` where the truth
        is known but the estimate is not (a frame the tracker reported nothing for). The
        summaries below leave NaN out everywhere; ``+inf`` counts as a miss in
        :func:`fraction_within` and is left out of the averages of distances.
    """
    estimated = np.asarray(estimated, dtype=np.float64)
    truth = np.asarray(truth, dtype=np.float64)
    if estimated.shape != truth.shape or estimated.ndim < 1 or estimated.shape[-1] != 3:
        raise ValueError(f"estimated {estimated.shape} and truth {truth.shape} must both be (..., 3)")
    # a NaN coordinate propagates through the norm, so unknown stays unknown
    errors = np.sqrt(np.sum((estimated - truth) ** 2, axis=-1))
    missing = ~np.all(np.isfinite(estimated), axis=-1) & np.all(np.isfinite(truth), axis=-1)
    return np.where(missing, np.inf, errors)


#: The per-joint errors are point errors over the 15 contract joints.
joint_errors = point_errors


def _known(errors):
    errors = np.asarray(errors, dtype=np.float64)
    return errors, np.isfinite(errors)


def mean_error(errors) -> float:
    """Mean over every known entry of ``errors (F, N)``; NaN when none is known."""
    errors, known = _known(errors)
    return float(errors[known].mean()) if known.any() else float("nan")


def per_frame_mean(errors):
    """``(F,)`` mean over the known entries of each frame; NaN for a frame with none."""
    errors, known = _known(errors)
    counts = known.sum(axis=1)
    sums = np.where(known, errors, 0.0).sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(counts > 0, sums / np.maximum(counts, 1), np.nan)


def per_frame_max(errors):
    """``(F,)`` largest known entry of each frame; NaN for a frame with none."""
    errors, known = _known(errors)
    worst = np.where(known, errors, -np.inf).max(axis=1, initial=-np.inf)
    return np.where(np.isfinite(worst), worst, np.nan)


def per_point_mean(errors):
    """``(N,)`` mean over frames of each column (joint or marker); NaN for a column never known."""
    errors, known = _known(errors)
    counts = known.sum(axis=0)
    sums = np.where(known, errors, 0.0).sum(axis=0)
    return np.where(counts > 0, sums / np.maximum(counts, 1), np.nan)


def mean_max_error(errors) -> float:
    """Mean over frames of the worst known entry in each frame.

    Frames with nothing known are left out; NaN when no frame has anything known.

    Parameters
    ----------
    errors : (F, N) float
    """
    worst = per_frame_max(errors)
    known = np.isfinite(worst)
    return float(worst[known].mean()) if known.any() else float("nan")


def fraction_within(errors, threshold: float = WITHIN_THRESHOLD_M) -> float:
    """Fraction of the known entries of ``errors (F, N)`` that are ``<= threshold``.

    Missing estimates (``+inf``, see :func:`point_errors`) count as misses. NaN when
    nothing is known.
    """
    errors = np.asarray(errors, dtype=np.float64)
    known = ~np.isnan(errors)
    return float(np.mean(errors[known] <= threshold)) if known.any() else float("nan")


def marker_errors(model_markers, measured_markers):
    """Per-frame, per-marker distance between model and measured markers.

    Parameters
    ----------
    model_markers : (F, M, 3) float
        The markers on the fitted surface mesh (NaN where the track has no pose).
    measured_markers : (F, M, 3) float
        Motion-capture markers; NaN where a marker was not visible.

    Returns
    -------
    errors : (F, M) float, NaN where either side is unknown.
    """
    return point_errors(model_markers, measured_markers)


def average_marker_error(errors) -> float:
    """The paper's *avg* metric: per frame the mean over visible markers, then the mean over frames.

    Parameters
    ----------
    errors : (F, M) float
        From :func:`marker_errors`.

    Returns
    -------
    float; NaN when no marker is known in any frame.
    """
    per_frame = per_frame_mean(errors)
    known = np.isfinite(per_frame)
    return float(per_frame[known].mean()) if known.any() else float("nan")


def max_marker_error(errors) -> float:
    """The paper's *max* metric: per frame the worst visible marker, then the mean over frames."""
    return mean_max_error(errors)


def frames_per_second(frames: int, seconds) -> float:
    """Processing rate; NaN when the time is unknown or not positive."""
    if seconds is None:
        return float("nan")
    seconds = float(seconds)
    return float(frames) / seconds if np.isfinite(seconds) and seconds > 0 else float("nan")


def trunk_twist(joints):
    """``(F,)`` twist (degrees) of the shoulders against the hips about the trunk's long axis.

    The signed angle (right-handed about the axis from the pelvis to the neck) from the
    hips' left-to-right line to the shoulders', both projected onto the plane across that
    axis.
    A person twists a few degrees (the train split's clips: 4 at the median, 22 at the 95th
    percentile); a tracked pose can twist far more where its pelvis lags the chest (the
    hips then off while pelvis and shoulders are right).

    Parameters
    ----------
    joints : (F, 15, 3) float
        Contract joints; NaN where unknown (then NaN).
    """
    j = np.asarray(joints, dtype=np.float64)
    axis = j[:, JOINT_INDEX["neck"]] - j[:, JOINT_INDEX["pelvis"]]
    axis = axis / np.linalg.norm(axis, axis=-1, keepdims=True)

    def across(lft, r):
        v = j[:, JOINT_INDEX[r]] - j[:, JOINT_INDEX[lft]]
        return v - np.sum(v * axis, axis=-1, keepdims=True) * axis

    (hl, hr), (sl, sr) = TRUNK_SIDES
    hips, shoulders = across(hl, hr), across(sl, sr)
    sin = np.sum(np.cross(hips, shoulders) * axis, axis=-1)
    return np.degrees(np.arctan2(sin, np.sum(hips * shoulders, axis=-1)))


def twist_errors(estimated, truth):
    """``(F,)`` absolute difference (degrees, wrapped to 0..180) between the tracked and the
    true :func:`trunk_twist`; NaN where either is unknown."""
    d = trunk_twist(estimated) - trunk_twist(truth)
    return np.abs((d + 180.0) % 360.0 - 180.0)


def summarize(joint_err, frames: int, seconds=None, marker_err=None,
              threshold: float = WITHIN_THRESHOLD_M, fit=None, shape=None, wall_seconds=None,
              reversed_frames=None, twist_err=None) -> dict:
    """The summary figures of one track of one sequence.

    Parameters
    ----------
    joint_err : (F, 15) float
        From :func:`joint_errors`.
    frames : int
        Frames tracked.
    seconds : float or None
        Tracking time, for the rate.
    wall_seconds : float or None
        The whole tracking work (the body height and shape fits too), for ``wall_fps``.
    marker_err : (F, M) float or None
        From :func:`marker_errors`; ``None`` when the sequence has no markers.
    fit : dict or None
        :func:`depthtrack.evaluate.fit.summarize_fit` (no ground truth needed).
    shape : dict or None
        :func:`depthtrack.evaluate.fit.shape_errors` (synthetic sequences with a shape).
    reversed_frames : (F,) float or None
        :func:`back_to_front`; its mean over the known frames is ``back_to_front_fraction``.
    twist_err : (F,) float or None
        :func:`twist_errors`; its mean over the known frames is ``trunk_twist_error_deg``.

    Returns
    -------
    dict with ``frames, fps, wall_fps, mean_error_m, max_error_m, within_10cm,
    marker_mean_error_m, marker_max_error_m, silhouette_iou, unexplained_fraction,
    median_depth_residual_m, segment_length_error_m, back_to_front_fraction,
    trunk_twist_error_deg``
    (:data:`METRIC_KEYS`) and, with
    ``shape``, ``segment_length_errors_m`` {segment: metres}; unknown values are ``None``.
    """
    def finite_or_none(x):
        return float(x) if x is not None and np.isfinite(x) else None

    return {
        "frames": int(frames),
        "fps": finite_or_none(frames_per_second(frames, seconds)),
        "wall_fps": finite_or_none(frames_per_second(frames, wall_seconds)),
        "mean_error_m": finite_or_none(mean_error(joint_err)),
        "max_error_m": finite_or_none(mean_max_error(joint_err)),
        "within_10cm": finite_or_none(fraction_within(joint_err, threshold)),
        "marker_mean_error_m": None if marker_err is None else finite_or_none(average_marker_error(marker_err)),
        "marker_max_error_m": None if marker_err is None else finite_or_none(max_marker_error(marker_err)),
        **{k: finite_or_none((fit or {}).get(k)) for k in FIT_KEYS},
        "segment_length_error_m": finite_or_none((shape or {}).get("segment_length_error_m")),
        **({"segment_length_errors_m": shape.get("segment_length_errors_m")} if shape else {}),
        # the share of the frames known on both sides (mean_error's mean over known entries)
        "back_to_front_fraction": None if reversed_frames is None else finite_or_none(
            mean_error(reversed_frames)),
        "trunk_twist_error_deg": None if twist_err is None else finite_or_none(mean_error(twist_err)),
    }


#: Keys of :func:`summarize`'s result, in report order.
METRIC_KEYS = ("frames", "fps", "wall_fps", "mean_error_m", "max_error_m", "within_10cm",
               "marker_mean_error_m", "marker_max_error_m", *FIT_KEYS, "segment_length_error_m",
               "back_to_front_fraction", "trunk_twist_error_deg")


def average_summaries(summaries) -> dict:
    """Average per-sequence summaries into an overall one, each sequence weighing the same.

    ``frames`` is the total; every other figure is the mean over the sequences where it is
    known (``None`` where none knows it). Sequence-weighted, as the paper's "averaged over
    sequences": a long easy sequence does not drown a short hard one.

    Parameters
    ----------
    summaries : sequence of dict from :func:`summarize`
    """
    summaries = list(summaries)
    out = {"frames": int(sum(s["frames"] for s in summaries))}
    for key in METRIC_KEYS[1:]:
        values = [s[key] for s in summaries if s.get(key) is not None]
        out[key] = float(np.mean(values)) if values else None
    return out


__all__ = ["WITHIN_THRESHOLD_M", "point_errors", "joint_errors", "mean_error", "per_frame_mean",
           "per_frame_max", "per_point_mean", "mean_max_error", "fraction_within", "marker_errors",
           "back_to_front", "TRUNK_SIDES", "trunk_twist", "twist_errors",
           "average_marker_error", "max_marker_error", "frames_per_second", "summarize",
           "METRIC_KEYS", "average_summaries"]
