"""File formats: depth sequences and recordings (one reader registry), ground truth, BVH, C3D
markers, track outputs and exports.

``io`` sits below ``body``: it imports nothing from it (the BVH writer takes a body object
and reads its attributes; rotations come from :mod:`depthtrack.rotations`), while
``body`` may use ``io`` (its glTF writer writes through :mod:`depthtrack.io.atomic`).
"""
from .bvh import BvhMotion, read_bvh, write_bvh
from .c3d import import_c3d_markers, read_c3d_markers
from .sequence import Sequence, open_sequence, write_sequence
from .track_output import Track, read_track, write_track
from .registry import DepthSequence, Reader, choose_reader, readers, register_reader
from .arrays import sequence_from_arrays
from .convert import convert_sequence

__all__ = ["BvhMotion", "read_bvh", "write_bvh", "import_c3d_markers", "read_c3d_markers",
           "Sequence", "open_sequence", "write_sequence", "Track", "read_track", "write_track",
           "DepthSequence", "Reader", "choose_reader", "readers", "register_reader",
           "sequence_from_arrays", "convert_sequence"]
