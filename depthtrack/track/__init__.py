"""Tracking depth sequences: hill climbing, evidence propagation, data association (the ToF paper).

* :mod:`.tracker` -- :class:`Tracker` (``init`` / ``step`` / ``track_sequence``), the methods
  "hc", "ep", "hc+ep", the MAP energy, automatic initialisation and recovery;
* :mod:`.hill_climb` -- coarse-to-fine, block-parallel search down the kinematic chain;
* :mod:`.evidence` -- evidence propagation by iterated unscented statistical linearisation;
* :mod:`.association` -- prune, expand and greedily try part-detection correspondences;
* :mod:`.observation` -- the ROI, the observed image the likelihood compares with, open space,
  the visible area and the height guess (pure functions).
"""
from .association import associate, expand_correspondences, prune_explained
from .evidence import PartModel, iterated_unscented_update, propagate_evidence, sigma_points
from .hill_climb import HillClimber, SearchGroup, default_blocks
from .tracker import (METHODS, LIKELIHOODS, Tracker, TrackerSettings, TrackResult, body_for_sequence,
                      fit_pose_to_joints, run_tracking)

__all__ = ["Tracker", "TrackerSettings", "TrackResult", "METHODS", "LIKELIHOODS", "run_tracking",
           "body_for_sequence", "fit_pose_to_joints", "HillClimber", "SearchGroup", "default_blocks",
           "PartModel", "propagate_evidence", "iterated_unscented_update", "sigma_points",
           "associate", "prune_explained", "expand_correspondences"]
