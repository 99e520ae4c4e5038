"""BVH motion capture files: reading any common skeleton, and writing our body's poses.

Modules, one concern each:

* :mod:`.parse` -- the text: hierarchy, per-joint channel orders, motion table
  (:func:`read_bvh`);
* :mod:`.units` -- lengths in metres: given, or inferred from the skeleton and reported;
* :mod:`.names` -- which joint is which, for every common naming convention, decided
  by structure where a name is ambiguous, or by the caller's joint map;
* :mod:`.motion` -- :class:`BvhMotion` and its forward kinematics, the 15 contract joints;
* :mod:`.write` -- :func:`write_bvh` for our body model's poses.

``io`` imports nothing from ``body``: the writer takes a body object and uses only its
attributes; rotations come from :mod:`depthtrack.rotations`.
"""
from ...rotations import axis_rotations, matrix_to_euler
from .motion import BVH_FROM_CAMERA, BvhMotion
from .names import detect_convention, map_joints, read_joint_map, split_name
from .parse import read_bvh
from .units import UNIT_NAMES
from .write import BODY_BVH_NAMES, body_end_sites, write_bvh

__all__ = ["BVH_FROM_CAMERA", "BODY_BVH_NAMES", "BvhMotion", "UNIT_NAMES", "axis_rotations",
           "body_end_sites", "detect_convention", "map_joints", "matrix_to_euler", "read_bvh",
           "read_joint_map", "split_name", "write_bvh"]
