"""Data association of part detections (the ToF paper's tracking algorithm, its figure "tracking algorithm").

Given the hill-climbed pose ``x_best`` and the frame's part detections:

1. *Prune* detections already explained: within ``prune_distance`` of any part of ``x_best``
   (of any class, since the part classifiers confuse classes). Detections are needed when
   the model-based search has lost a part, and then they lie far from every part.
2. *Expand* each remaining detection into correspondences with every body part of its
   class: a "hand" may be the left or the right hand.
   The recogniser's joint *proposals* (elbows, knees, ...) join as detections of their
   joint's class, side-free: a "knee" may be the left or the right knee. A proposal is
   explained when it lies within its own distance of the model's joint of its class (the
   recogniser's classes are good, its sides are not); the kept ones are tried after the
   detections, at most ``max_proposal_correspondences`` of them, most confident first.
3. *Greedy*: for each correspondence (best detection score first), evidence propagation
   from ``x_best`` conditioned on that correspondence alone gives a pose far from
   ``x_best``; local hill climbing refines it; it replaces ``x_best`` when its energy is
   lower. An accepted correspondence only acts through ``x_best``: later correspondences
   are propagated alone, so a better one can override an earlier one.

The functions take the energy, evidence propagation and hill climbing as callables, so the
loop is tested without a renderer.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..detect.parts import CLASS_PARTS


@dataclass
class Correspondence:
    """One hypothesis: body part ``part`` is seen at detection ``detection``.

    Attributes
    ----------
    part : str
        ``head, l_hand, r_hand, l_foot, r_foot``.
    detection : object
        Anything with ``label``, ``position (3,)`` and ``score``.
    energy : float
        Energy after evidence propagation (and hill climbing), NaN until tried.
    accepted : bool
    proposal : bool
        From a joint proposal of the recogniser (not from the part detector).
    """

    part: str
    detection: object
    energy: float = float("nan")
    accepted: bool = False
    proposal: bool = False


@dataclass
class AssociationResult:
    """Outcome of :func:`associate`.

    Attributes
    ----------
    pose : (48,) float
    energy : float
    pruned : int
        Detections (and proposals) dropped as already explained.
    tried : list of Correspondence
    """

    pose: np.ndarray
    energy: float
    pruned: int = 0
    tried: list = field(default_factory=list)

    @property
    def accepted(self):
        return [c for c in self.tried if c.accepted]


def prune_explained(detections, part_positions, distance: float):
    """Detections farther than ``distance`` from every model part.

    Parameters
    ----------
    detections : sequence of objects with ``position (3,)``
    part_positions : (P, 3) float
        Parts of the current best pose.
    distance : float
        Metres.

    Returns
    -------
    list
        The detections that are *not* explained, in input order.
    """
    part_positions = np.asarray(part_positions, dtype=np.float64).reshape(-1, 3)
    kept = []
    for det in detections:
        d = np.linalg.norm(part_positions - np.asarray(det.position, dtype=np.float64), axis=1)
        if d.size == 0 or d.min() > distance:
            kept.append(det)
    return kept


def prune_by_class(detections, joint_positions, classes, distance: float):
    """Detections farther than ``distance`` from every model part of their own class.

    Parameters
    ----------
    detections : sequence of objects with ``label`` (a key of ``classes``) and ``position (3,)``
    joint_positions : dict {str: (3,) float}
        Positions of the current best pose's parts, by part name.
    classes : dict {str: tuple of str}
        The parts a detection of each label may be (``{"knee": ("l_knee", "r_knee")}``).
    distance : float
        Metres.

    Returns
    -------
    list
        The detections that are *not* explained, in input order.
    """
    kept = []
    for det in detections:
        names = [n for n in classes.get(det.label, ()) if n in joint_positions]
        near = np.array([joint_positions[n] for n in names], dtype=np.float64).reshape(-1, 3)
        d = np.linalg.norm(near - np.asarray(det.position, dtype=np.float64), axis=1)
        if d.size == 0 or d.min() > distance:
            kept.append(det)
    return kept


def expand_correspondences(detections, part_names=None, classes=CLASS_PARTS):
    """Every (part, detection) pair whose classes match, best detection score first.

    Parameters
    ----------
    detections : sequence with ``label`` in ``classes`` and ``score``
    part_names : collection of str, optional
        Parts that may be matched (default: all of ``classes``).

    Returns
    -------
    list of Correspondence
    """
    order = sorted(range(len(detections)), key=lambda i: -float(getattr(detections[i], "score", 0.0)))
    out = []
    for i in order:
        det = detections[i]
        for part in classes.get(det.label, ()):
            if part_names is None or part in part_names:
                out.append(Correspondence(part, det))
    return out


def associate(pose, energy_value, detections, part_positions, propagate, evaluate,
              prune_distance: float = 0.15, max_correspondences: int = 8, proposals=(),
              joint_positions=None, proposal_classes=None, proposal_distance: float = 0.15,
              max_proposal_correspondences: int = 0) -> AssociationResult:
    """The greedy association loop (module docstring).

    Parameters
    ----------
    pose : (48,) float
        ``x_best`` after hill climbing.
    energy_value : float
        Its energy (lower is better).
    detections : sequence of Detection
        With ``label`` ('head' | 'hand' | 'foot'), ``position (3,)``, ``score``.
    part_positions : (P, 3) float
        Parts of ``pose`` (any order) used for pruning.
    propagate : callable ``(pose (48,), part str, detection) -> pose (48,)``
        Evidence propagation from ``pose`` given one correspondence.
    evaluate : callable ``(pose (48,), part str) -> (pose (48,), energy float)``
        Scores a propagated pose, after local hill climbing for "hc+ep", as it is for "ep".
    prune_distance : float
        Metres.
    max_correspondences : int
        Most correspondences of ``detections`` tried per frame (best scores first), bounding
        the time.
    proposals : sequence of Detection-like
        Joint proposals, ``label`` a key of ``proposal_classes``, ``score`` their confidence.
    joint_positions : dict {str: (3,) float}
        The model's parts by name (at least those of ``proposal_classes``), for their pruning.
    proposal_classes : dict {str: tuple of str}
        The parts a proposal of each label may be.
    proposal_distance : float
        A proposal this near (m) a model part of its class is explained.
    max_proposal_correspondences : int
        Most proposal correspondences tried per frame (after the detections').

    Returns
    -------
    AssociationResult
    """
    best = np.asarray(pose, dtype=np.float64).copy()
    best_energy = float(energy_value)
    kept = prune_explained(detections, part_positions, prune_distance)
    todo = expand_correspondences(kept)[:max_correspondences]
    pruned = len(detections) - len(kept)
    if len(proposals) and max_proposal_correspondences > 0:
        kept_p = prune_by_class(proposals, joint_positions, proposal_classes, proposal_distance)
        pruned += len(proposals) - len(kept_p)
        extra = expand_correspondences(kept_p, classes=proposal_classes)[:max_proposal_correspondences]
        for corr in extra:
            corr.proposal = True
        todo += extra
    result = AssociationResult(best, best_energy, pruned=pruned)
    for corr in todo:
        proposal = propagate(best, corr.part, corr.detection)
        candidate, e = evaluate(proposal, corr.part)
        corr.energy = float(e)
        if e < best_energy:
            best, best_energy = np.asarray(candidate, dtype=np.float64), float(e)
            corr.accepted = True
        result.tried.append(corr)
    result.pose, result.energy = best, best_energy
    return result
