"""Body-part detections (head, hand, foot) from a depth frame.

``detect_parts(depth, camera, foreground=None) -> list[Detection]``: geodesic extrema of
the segmented person (:mod:`depthtrack.detect.geodesic`), each labelled head / hand /
foot / other; "other" extrema are dropped.

Labelling: the trained patch classifier (:mod:`depthtrack.detect.classifier`, parameters
in ``depthtrack/data/part_classifier.npz``) when that file is present; otherwise a
documented geometric heuristic (:func:`heuristic_labels`) -- the fallback says so in
each detection's ``source``.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from .geodesic import geodesic_extrema
from .segment import check_depth, segment_foreground

#: Detection classes, in the classifier's output order ("other" is never reported).
PART_CLASSES = ("head", "hand", "foot", "other")
#: The body parts a detection of each reported class may be (the subject's own left/right).
CLASS_PARTS = {"head": ("head",), "hand": ("l_hand", "r_hand"), "foot": ("l_foot", "r_foot")}


@dataclass
class Detection:
    """One detected body part.

    Attributes
    ----------
    label : str
        'head' | 'hand' | 'foot'.
    position : (3,) float
        Camera-frame point on the visible surface of the part (metres).
    direction : (3,) float
        Unit vector along the limb toward its end (camera frame).
    pixel : (2,) int
        Pixel ``(u, v)`` of the extremum.
    score : float
        Class probability (classifier) or heuristic confidence, 0..1.
    tip : (3,) float
        The geodesic extremum itself (the limb's end point on the surface).
    source : str
        'classifier' or 'heuristic'; the tracker also makes 'recognizer' detections of the
        joint proposals (label a joint class, 'knee'; :func:`depthtrack.track.proposals.proposal_detections`).
    """

    label: str
    position: np.ndarray
    direction: np.ndarray
    pixel: np.ndarray
    score: float
    tip: np.ndarray = field(default_factory=lambda: np.zeros(3))
    source: str = "classifier"


def _up_vector(foreground):
    plane = getattr(foreground, "floor_plane", None)
    if plane is None:
        return np.array([0.0, -1.0, 0.0]), None
    plane = np.asarray(plane, float)
    return plane[:3] / np.linalg.norm(plane[:3]), plane


def heuristic_labels(extrema, foreground):
    """Label extrema by geometry alone (the fallback without a trained classifier).

    Heights are measured along the floor normal (camera -y without a floor). The
    highest extremum above the body's centroid by 0.3 m is the head; extrema within
    0.25 m of the floor (or, without a floor, in the lowest fifth of the body's
    height span) are feet (at most two, the lowest); of the other extrema farther than
    0.35 m (geodesic) from the earlier sources, the two found first are hands; the rest
    "other".

    Parameters
    ----------
    extrema : Extrema
    foreground : Foreground

    Returns
    -------
    labels : (K,) str
    scores : (K,) float
        Fixed confidences (0.6 head, 0.6 foot, 0.5 hand, 0 other).
    """
    k = len(extrema)
    labels = np.array(["other"] * k, dtype=object)
    scores = np.zeros(k)
    if k == 0:
        return labels, scores
    up, plane = _up_vector(foreground)
    h = extrema.positions @ up
    body_h = foreground.points @ up
    centre = float(np.mean(body_h))
    if plane is not None:
        feet = (extrema.positions @ plane[:3] + plane[3]) / np.linalg.norm(plane[:3]) < 0.25
    else:
        lo, hi = np.percentile(body_h, [1, 99])
        feet = h < lo + 0.2 * (hi - lo)
    feet = np.nonzero(feet)[0]
    feet = feet[np.argsort(h[feet])[:2]]
    labels[feet] = "foot"
    scores[feet] = 0.6
    feet = labels == "foot"
    rest = np.nonzero(~feet)[0]
    if len(rest):
        top = rest[np.argmax(h[rest])]
        if h[top] > centre + 0.3:
            labels[top] = "head"
            scores[top] = 0.6
    hands = np.nonzero((labels == "other") & (extrema.distances > 0.35))[0][:2]
    labels[hands] = "hand"
    scores[hands] = 0.5
    return labels, scores


def detect_parts(depth, camera, foreground=None, count: int = 7, min_score: float = 0.5,
                 classifier=None) -> list:
    """Head, hand and foot detections in a depth frame.

    Parameters
    ----------
    depth : (H, W) float
        Camera z, metres; 0 = no reading.
    camera : Camera
    foreground : Foreground, optional
        From :func:`~depthtrack.detect.segment.segment_foreground` (computed when None).
    count : int
        Geodesic extrema examined.
    min_score : float
        Detections with a lower class probability are not reported.
    classifier : PartClassifier or "heuristic", optional
        Default: the shipped one, or :func:`heuristic_labels` when none ships (or when
        ``"heuristic"`` is asked for).

    Returns
    -------
    list of Detection
        In the order the extrema were found.

    Raises
    ------
    InputError
        Bad depth image.
    """
    z = check_depth(depth, camera)
    fg = segment_foreground(z, camera) if foreground is None else foreground
    extrema = geodesic_extrema(fg, camera, count=count)
    if len(extrema) == 0:
        return []
    if classifier is None:
        from .classifier import default_classifier
        classifier = default_classifier()
    elif isinstance(classifier, str):
        if classifier != "heuristic":
            raise InputError(None, f"unknown part classifier {classifier!r} "
                                   f"(a PartClassifier or 'heuristic')")
        classifier = None
    if classifier is not None:
        labels, scores, positions = classifier.classify(z, camera, extrema, fg)
        source = "classifier"
    else:
        labels, scores = heuristic_labels(extrema, fg)
        positions = extrema.centres
        source = "heuristic"
    out = []
    for i in range(len(extrema)):
        if labels[i] == "other" or scores[i] < min_score:
            continue
        out.append(Detection(label=str(labels[i]), position=np.asarray(positions[i], float),
                             direction=np.asarray(extrema.directions[i], float),
                             pixel=np.asarray(extrema.pixels[i]), score=float(scores[i]),
                             tip=np.asarray(extrema.positions[i], float), source=source))
    return out
