"""Tracking depth sequences: hill climbing, evidence propagation, data association (the ToF paper).

A frame is a pipeline of stages over a :class:`TrackingState` (:mod:`.state`):

* :mod:`.observe` -- segment, ROI, the observed image (:mod:`.observation`: pure image functions);
* :mod:`.search` -- predict with the motion prior, hill-climb (:mod:`.hill_climb`) the MAP
  energy (:mod:`.energy`), and the final polish at finer tiles;
* :mod:`.propagate` -- part detections and the recogniser's side-free joint proposals
  (:mod:`.proposals`) through evidence propagation (:mod:`.evidence`) in the association
  loop (:mod:`.association`);
* :mod:`.judge` -- the unexplained share, lost or not, recovery by the global search;
* :mod:`.start` -- the global search of a start; :mod:`.heading` -- the front/back check;
  :mod:`.height` -- the body height;
* :mod:`.tracker` -- :class:`Tracker` (owns the renderers, :mod:`.renderers`; runs the
  stages; ``init`` / ``step`` / ``track_sequence``); :mod:`.loop` -- the frame loop and
  :func:`track_stream`; :mod:`.run` -- :func:`run_tracking`; :mod:`.settings` -- the settings, one group per
  stage (:mod:`.flat_names` -- their earlier flat names); :mod:`.record` -- timings and counts.
"""
from .association import associate, expand_correspondences, prune_explained
from .evidence import PartModel, iterated_unscented_update, propagate_evidence, sigma_points
from .height import body_for_sequence, fit_body_height, fit_body_shape
from .hill_climb import HillClimber, SearchGroup, default_blocks
from .settings import (AssociateSettings, EnergySettings, HeadingSettings, HeightSettings,
                       JudgeSettings, ObserveSettings, PolishSettings, SearchSettings,
                       ShapeSettings, StartSettings, TrackerSettings)
from .state import TrackedFrame, TrackingState, TrackResult
from .tracker import LIKELIHOODS, METHODS, Tracker  # before .loop and .run (it re-exports them)
from .loop import track_stream  # noqa: E402
from .run import fit_pose_to_joints, run_tracking  # noqa: E402

__all__ = ["Tracker", "TrackerSettings", "TrackResult", "TrackingState", "TrackedFrame", "METHODS",
           "LIKELIHOODS", "run_tracking", "track_stream", "body_for_sequence", "fit_body_height",
           "fit_pose_to_joints", "HillClimber", "SearchGroup", "default_blocks", "PartModel",
           "propagate_evidence", "iterated_unscented_update", "sigma_points", "associate",
           "prune_explained", "expand_correspondences", "ObserveSettings", "EnergySettings",
           "SearchSettings", "AssociateSettings", "PolishSettings", "JudgeSettings",
           "StartSettings", "HeadingSettings", "HeightSettings", "ShapeSettings",
           "fit_body_shape"]
