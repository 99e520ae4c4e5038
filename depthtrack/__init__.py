"""depthtrack: markerless human motion capture from depth cameras.

The public names are re-exported here; see the README for a tour::

    import depthtrack as dt
    body = dt.BodyModel.default()
    camera = dt.Camera.preset("sr4000")
    renderer = dt.TileRenderer(body, camera, tile=64)
    costs = renderer.costs(poses, observed_depth)           # (N,) float

Subpackages, one concern each: ``body`` (kinematics, skinned mesh), ``render`` (GL tiles),
``io`` (sequences, BVH, C3D, track outputs), ``synth`` (synthetic ToF sequences), ``detect``
(segmentation, geodesic extrema, part classifier), ``motion`` (priors, retargeting, cyclic
model), ``track`` (hill climbing, evidence propagation), ``evaluate`` (metrics, reports),
``filters`` (particle, Kalman, unscented), ``swim`` (the swimmer motion model).
"""
# Before anything imports numpy: the same OpenBLAS kernels on every x86-64 machine, so that a
# track is the same number everywhere (depthtrack.environment, README "The same figures on
# another machine").
from .environment import pin_blas_kernels

pin_blas_kernels()

from .contract import JOINT_INDEX, JOINT_NAMES
from .errors import InputError
from .camera import Camera
from .body import BodyModel
from .likelihood import LikelihoodParams
from .render import FrameRenderer, TileRenderer, gl_context
from .io import (BvhMotion, Sequence, Track, import_c3d_markers, open_sequence, read_bvh,
                 read_track, write_bvh, write_sequence, write_track)
from .io import DepthSequence, Reader, convert_sequence, register_reader, sequence_from_arrays
from .motion.retarget import resample_poses, retarget
from .synth import MARKER_NAMES, ToFNoise, procedural_motion, synthesize_bvh, synthesize_procedural
from .detect import detect_parts, geodesic_extrema, segment_foreground
from .track import Tracker, TrackerSettings, run_tracking, track_stream

from .filters import KalmanFilter, ParticleFilter, UnscentedKalmanFilter

__version__ = "0.1.0"

__all__ = ["JOINT_NAMES", "JOINT_INDEX", "InputError", "Camera", "BodyModel", "LikelihoodParams",
           "TileRenderer", "FrameRenderer", "gl_context", "BvhMotion", "Sequence", "Track",
           "open_sequence", "write_sequence", "read_bvh", "write_bvh", "read_track", "write_track",
           "import_c3d_markers", "DepthSequence", "Reader", "register_reader", "sequence_from_arrays",
           "convert_sequence", "retarget", "resample_poses", "MARKER_NAMES", "ToFNoise",
           "procedural_motion", "synthesize_bvh", "synthesize_procedural", "segment_foreground",
           "geodesic_extrema", "detect_parts", "Tracker", "TrackerSettings", "run_tracking", "track_stream",
           "KalmanFilter", "ParticleFilter", "UnscentedKalmanFilter", "__version__"]
