"""Depth sequences that are not our directory: the common base of the recording readers,
and a sequence made from numpy arrays in Python.

A reader subclasses :class:`RecordingSequence` and implements ``_read(start, stop)``,
returning the frames ``start..stop-1`` as stored: (H, W) uint16 in units of
``depth_scale``, or (H, W) float metres (NaN, 0 or negative = no reading). Frames are
read in small batches and the last batch is kept, so a sequential pass opens the
recording once per batch and no file stays open between calls.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..camera import Camera
from ..contract import JOINT_NAMES
from .sequence import FrameIteration, depth_to_raw

#: Frames read per visit to the recording file.
BATCH = 16


class RecordingSequence(FrameIteration):
    """Frames by index from a recording; implements :class:`~depthtrack.io.registry.DepthSequence`.

    Attributes
    ----------
    path : pathlib.Path
    camera : Camera
    fps : float
    depth_scale : float
        Metres per raw unit: the recording's units for 16-bit data; the quantum
        ``raw_depth`` and ``convert`` use for float data (1 mm by default).
    subject_height : float or None
    meta : dict
        What the reader knows about the source (format, device, topic, ...).
    """

    def __init__(self, path, camera: Camera, fps: float, depth_scale: float, timestamps,
                 meta=None, subject_height=None):
        self.path = Path(path)
        self.camera = camera
        self.fps = float(fps)
        self.depth_scale = float(depth_scale)
        self.subject_height = subject_height
        self.meta = dict(meta or {})
        self._timestamps = np.asarray(timestamps, dtype=float)
        self._cache_start = -1
        self._cache = []

    # -- to implement
    def _read(self, start: int, stop: int) -> list:
        """Frames ``start..stop-1`` as stored: list of (H, W) uint16 or float arrays."""
        raise NotImplementedError

    # -- the interface
    def __len__(self) -> int:
        return len(self._timestamps)

    @property
    def timestamps(self) -> np.ndarray:
        """(F,) float seconds of each frame."""
        return self._timestamps.copy()

    def _stored(self, i: int) -> np.ndarray:
        n = len(self)
        if not -n <= i < n:
            raise IndexError(f"frame {i} out of range ({n} frames)")
        i %= n
        if not (self._cache_start <= i < self._cache_start + len(self._cache)):
            self._cache = self._read(i, min(n, i + BATCH))
            self._cache_start = i
        return self._cache[i - self._cache_start]

    def depth(self, i: int) -> np.ndarray:
        """(H, W) float32: camera-frame z of frame ``i`` in metres, 0 = no reading."""
        frame = self._stored(i)
        if frame.dtype == np.uint16:
            return (frame.astype(np.float64) * self.depth_scale).astype(np.float32)
        depth = np.asarray(frame, dtype=np.float32)
        return np.where(np.isfinite(depth) & (depth > 0), depth, np.float32(0))

    def raw_depth(self, i: int) -> np.ndarray:
        """(H, W) uint16: frame ``i`` in units of ``depth_scale`` (float data quantised)."""
        frame = self._stored(i)
        if frame.dtype == np.uint16:
            return frame
        return depth_to_raw(frame, self.depth_scale)

    # Recordings carry no ground truth; subclasses may set these.
    joints = None
    markers = None
    marker_names = None


class ArraySequence(RecordingSequence):
    """A sequence held in memory (see :func:`sequence_from_arrays`)."""

    def __init__(self, frames, camera, fps, depth_scale, timestamps, joints=None, markers=None,
                 marker_names=None, subject_height=None, path="<arrays>"):
        super().__init__(path, camera, fps, depth_scale, timestamps,
                         meta={"source": {"format": "arrays"}}, subject_height=subject_height)
        self._frames = frames
        self.joints = joints
        self.markers = markers
        self.marker_names = marker_names

    def _read(self, start, stop):
        return [self._frames[i] for i in range(start, stop)]


def sequence_from_arrays(depths, camera: Camera, fps: float = 30.0, depth_scale=None,
                         timestamps=None, joints=None, markers=None, marker_names=None,
                         subject_height=None) -> ArraySequence:
    """A depth sequence from numpy arrays, for the tracker, ``write_sequence`` or export.

    Parameters
    ----------
    depths : (F, H, W) uint16 or float
        uint16: raw values, ``depth_scale`` metres each (required), 0 = no reading.
        float: metres; NaN, 0 or negative = no reading (``depth_scale``, default 0.001,
        is then only the quantum used when written as 16-bit PNGs).
    camera : Camera
        Intrinsics; its size must be (W, H).
    fps : float
    timestamps : (F,) float or None
        Seconds; default ``arange(F) / fps``.
    joints : (F, 15, 3) float or None
        Ground truth (NaN = unknown); ``markers`` (F, M, 3) with ``marker_names`` (M,).
    subject_height : float or None
        Metres.

    Raises
    ------
    ValueError
        Shapes or types that do not fit.
    """
    depths = np.asarray(depths)
    if depths.ndim != 3 or depths.shape[0] == 0:
        raise ValueError(f"depths must be (F, H, W) with F >= 1, not {depths.shape}")
    if depths.shape[1:] != camera.shape:
        raise ValueError(f"frames are {depths.shape[2]} x {depths.shape[1]}, camera is "
                         f"{camera.width} x {camera.height}")
    if depths.dtype == np.uint16:
        if depth_scale is None:
            raise ValueError("uint16 depths need depth_scale (metres per unit)")
    elif np.issubdtype(depths.dtype, np.floating):
        depth_scale = 0.001 if depth_scale is None else depth_scale
    else:
        raise ValueError(f"depths must be uint16 (with depth_scale) or float metres, not {depths.dtype}")
    depth_scale = float(depth_scale)
    fps = float(fps)
    if not (np.isfinite(depth_scale) and depth_scale > 0 and np.isfinite(fps) and fps > 0):
        raise ValueError(f"depth_scale and fps must be positive, not {depth_scale}, {fps}")
    n = depths.shape[0]
    if timestamps is None:
        timestamps = np.arange(n) / fps
    timestamps = np.asarray(timestamps, dtype=float)
    if timestamps.shape != (n,):
        raise ValueError(f"timestamps must be ({n},), not {timestamps.shape}")
    if joints is not None:
        joints = np.asarray(joints, dtype=float)
        if joints.shape != (n, len(JOINT_NAMES), 3):
            raise ValueError(f"joints must be ({n}, 15, 3), not {joints.shape}")
    if markers is not None:
        markers = np.asarray(markers, dtype=float)
        if marker_names is None or markers.ndim != 3 or markers.shape[0] != n \
                or markers.shape[1] != len(marker_names) or markers.shape[2] != 3:
            raise ValueError(f"markers must be ({n}, M, 3) with M marker_names")
        marker_names = [str(m) for m in marker_names]
    return ArraySequence(depths, camera, fps, depth_scale, timestamps, joints, markers,
                         marker_names, subject_height)


__all__ = ["RecordingSequence", "ArraySequence", "sequence_from_arrays", "BATCH"]
