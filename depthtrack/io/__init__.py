"""File formats: depth sequences, ground truth, BVH, C3D markers, track outputs."""
from .bvh import BvhMotion, read_bvh, write_bvh
from .c3d import import_c3d_markers, read_c3d_markers
from .sequence import Sequence, open_sequence, write_sequence
from .track_output import Track, read_track, write_track

__all__ = ["BvhMotion", "read_bvh", "write_bvh", "import_c3d_markers", "read_c3d_markers",
           "Sequence", "open_sequence", "write_sequence", "Track", "read_track", "write_track"]
