"""Body-part detection from depth: foreground segmentation, geodesic extrema, part classifier.

``from depthtrack.detect import segment_foreground, detect_parts``

* :func:`segment_foreground` ``(depth, camera) -> Foreground`` -- the person's pixels and
  points without floor and background, plus the floor plane (:mod:`.segment`).
* :func:`geodesic_extrema` ``(foreground, camera, count=6) -> Extrema`` -- the incremental
  geodesic extrema with their directions (:mod:`.geodesic`).
* :func:`detect_parts` ``(depth, camera, foreground=None) -> list[Detection]`` -- extrema
  labelled head / hand / foot by the trained patch classifier (:mod:`.parts`,
  :mod:`.classifier`).
"""
from .geodesic import Extrema, geodesic_extrema
from .parts import PART_CLASSES, Detection, detect_parts, heuristic_labels
from .segment import Foreground, check_depth, fit_floor, segment_foreground

__all__ = ["Foreground", "segment_foreground", "check_depth", "fit_floor", "Extrema",
           "geodesic_extrema", "Detection", "detect_parts", "heuristic_labels", "PART_CLASSES"]
