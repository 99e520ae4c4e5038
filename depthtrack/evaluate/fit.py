"""Fit figures: how well the fitted body explains the depth, with no ground truth needed.

For every frame of a track, the person's foreground (the segmentation the tracker uses,
:func:`depthtrack.detect.segment_foreground`) is compared with the fitted body rendered
alone at the camera's full resolution (:class:`depthtrack.render.FrameRenderer`):

* ``silhouette_iou`` = |person AND body| / |person OR body|: 1 when the body covers
  exactly the person's pixels; a body too small, too large or misplaced lowers it.
* ``unexplained_fraction``: the share of the person's pixels with a reading that the body
  does not explain -- not covered, or covered at a depth more than
  :data:`EXPLAINED_TOLERANCE_M` away (the likelihood's saturation distance).
* ``median_depth_residual_m``: median ``|observed - rendered|`` over the pixels both
  have (person pixels with a reading that the body covers).

A frame without a person (empty foreground) has no figures (NaN); a frame with a person
that the track gave no pose for scores IoU 0 and unexplained 1. A sequence's figures are
the mean over frames of the IoU and of the unexplained share, and the median over frames
of the per-frame median residual.

The math is in the pure functions :func:`frame_fit` and :func:`summarize_fit`;
:func:`track_fit` reads frames, segments and renders (one renderer, released).
"""
from __future__ import annotations

import numpy as np

#: A covered person pixel counts as explained when the body is within this depth (m).
EXPLAINED_TOLERANCE_M = 0.10
#: Keys of :func:`summarize_fit` (added to each method's figures by ``depthtrack eval``).
FIT_KEYS = ("silhouette_iou", "unexplained_fraction", "median_depth_residual_m")


def frame_fit(person, depth, rendered, tolerance: float = EXPLAINED_TOLERANCE_M):
    """Fit figures of one frame.

    Parameters
    ----------
    person : (H, W) bool
        The person's foreground.
    depth : (H, W) float
        Observed depth (m), 0 = no reading.
    rendered : (H, W) float or None
        The fitted body's depth (m), 0 where it is not drawn; None = no pose this frame.
    tolerance : float
        Depth (m) within which a covered pixel counts as explained.

    Returns
    -------
    (iou, unexplained, median_residual) floats; NaN where undefined (no person; no pixel
    both have).
    """
    person = np.asarray(person, dtype=bool)
    depth = np.asarray(depth, dtype=np.float64)
    if not person.any():
        return float("nan"), float("nan"), float("nan")
    model = np.zeros(person.shape, bool) if rendered is None else np.asarray(rendered) > 0
    r = np.zeros(person.shape) if rendered is None else np.asarray(rendered, dtype=np.float64)
    union = np.count_nonzero(person | model)
    iou = np.count_nonzero(person & model) / union
    reading = person & (depth > 0)
    both = reading & model
    residual = np.abs(depth[both] - r[both])
    n_reading = np.count_nonzero(reading)
    unexplained = (1.0 - np.count_nonzero(residual <= tolerance) / n_reading) if n_reading else float("nan")
    median = float(np.median(residual)) if len(residual) else float("nan")
    return float(iou), float(unexplained), median


#: Keys of :func:`unexplained_parts`, in order.
PART_KEYS = ("uncovered_near_outline", "uncovered_inside", "off_near_outline", "off_inside",
             "body_off_person")


def unexplained_parts(person, depth, rendered, band: int = 2,
                      tolerance: float = EXPLAINED_TOLERANCE_M):
    """Where one frame's unexplained person pixels are, as counts ``(6,)``: the person's
    pixels with a reading, then :data:`PART_KEYS`.

    "Uncovered" pixels are not drawn by the body, "off" ones are drawn more than
    ``tolerance`` from their reading; each is "near the outline" within ``band`` pixels of
    the body's outline (a body laid a pixel or two off its person), else inside/away.
    ``body_off_person`` counts the body's pixels outside the person's foreground. The
    unexplained share of :func:`frame_fit` is the sum of the first four over the first.

    Parameters
    ----------
    person : (H, W) bool
    depth : (H, W) float
        Observed depth (m), 0 = no reading.
    rendered : (H, W) float
        The body's depth (m), 0 where it is not drawn.
    """
    import cv2

    person = np.asarray(person, dtype=bool)
    depth = np.asarray(depth, dtype=np.float64)
    rendered = np.asarray(rendered, dtype=np.float64)
    model = rendered > 0
    square = np.ones((3, 3), np.uint8)
    m8 = model.astype(np.uint8)
    outline = (cv2.dilate(m8, square, iterations=band).astype(bool)
               & ~cv2.erode(m8, square, iterations=band, borderValue=1).astype(bool))
    reading = person & (depth > 0)
    uncovered = reading & ~model
    off = reading & model & (np.abs(depth - rendered) > tolerance)
    return np.array([np.count_nonzero(reading),
                     np.count_nonzero(uncovered & outline), np.count_nonzero(uncovered & ~outline),
                     np.count_nonzero(off & outline), np.count_nonzero(off & ~outline),
                     np.count_nonzero(model & ~person)], dtype=np.int64)


def summarize_fit(per_frame) -> dict:
    """Sequence figures from per-frame ``(F, 3)`` (iou, unexplained, residual) rows.

    Returns
    -------
    dict with :data:`FIT_KEYS`: mean IoU, mean unexplained share, median residual over the
    frames that have them; None where no frame has one.
    """
    a = np.asarray(per_frame, dtype=np.float64).reshape(-1, 3)

    def reduce(col, fn):
        known = col[np.isfinite(col)]
        return float(fn(known)) if len(known) else None

    return {"silhouette_iou": reduce(a[:, 0], np.mean),
            "unexplained_fraction": reduce(a[:, 1], np.mean),
            "median_depth_residual_m": reduce(a[:, 2], np.median)}


def person_masks(seq, segmenter=None, progress=None) -> list:
    """The person's foreground mask ``(H, W) bool`` of every frame of ``seq``."""
    if segmenter is None:
        from ..detect import segment_foreground as segmenter
    out = []
    for i in range(len(seq)):
        out.append(np.asarray(segmenter(seq.depth(i), seq.camera).mask, dtype=bool))
        if progress is not None:
            progress.update(1)
    return out


def track_fit(seq, poses, body, masks=None, renderer=None) -> np.ndarray:
    """Per-frame fit figures ``(F, 3)`` of a track: (iou, unexplained, residual), NaN = none.

    Parameters
    ----------
    seq : Sequence
    poses : (F, D) float
        NaN rows = no pose that frame.
    body : BodyModel
    masks : list of (H, W) bool or None
        :func:`person_masks` of ``seq`` (computed when None).
    renderer : FrameRenderer or None
        Reused when given; otherwise one is made and released here.
    """
    poses = np.asarray(poses, dtype=np.float64)
    if masks is None:
        masks = person_masks(seq)
    own = renderer is None
    if own:
        from ..render import FrameRenderer
        renderer = FrameRenderer(seq.camera)
    try:
        out = np.full((len(seq), 3), np.nan)
        for i in range(len(seq)):
            if not masks[i].any():
                continue
            pose = poses[i]
            rendered = renderer.render(body, pose) if np.all(np.isfinite(pose)) else None
            out[i] = frame_fit(masks[i], seq.depth(i), rendered)
        return out
    finally:
        if own:
            renderer.release()


def shape_truth(seq):
    """The synthetic subject's segment lengths (m) from ``sequence.json`` ``synth.shape``, or None."""
    synth = (getattr(seq, "meta", None) or {}).get("synth") or {}
    shape = synth.get("shape") if isinstance(synth, dict) else None
    lengths = shape.get("segment_lengths_m") if isinstance(shape, dict) else None
    return dict(lengths) if isinstance(lengths, dict) and lengths else None


def shape_errors(body, truth) -> dict:
    """Segment-length errors of ``body`` against ``truth`` lengths (m).

    Returns
    -------
    dict: ``segment_length_errors_m`` {segment: fitted - true} and
    ``segment_length_error_m`` (median of their absolute values); both None without truth.
    """
    if body is None or not truth:
        return {"segment_length_error_m": None, "segment_length_errors_m": None}
    from ..body.shape import length_errors

    errors = length_errors(body.segment_lengths(), truth)
    median = float(np.median(np.abs(list(errors.values())))) if errors else None
    return {"segment_length_error_m": median, "segment_length_errors_m": errors or None}


__all__ = ["EXPLAINED_TOLERANCE_M", "FIT_KEYS", "PART_KEYS", "frame_fit", "unexplained_parts",
           "summarize_fit", "person_masks", "track_fit", "shape_truth", "shape_errors"]
