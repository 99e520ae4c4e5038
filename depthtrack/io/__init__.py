"""File formats: depth sequences and recordings (one reader registry), ground truth, BVH, C3D
markers, track outputs."""
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
