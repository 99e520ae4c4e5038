"""Depth sequences: the ``SEQ/`` directory contract and its single-file ``.npz`` twin.

Directory form (see ARCHITECTURE.md, "Depth sequence")::

    SEQ/sequence.json
    SEQ/depth/000000.png ...        16-bit single-channel PNG; value * depth_scale = z (m)
    SEQ/groundtruth/joints.csv      optional: frame,joint,x,y,z  (the 15 contract joints)
    SEQ/groundtruth/markers.csv     optional: frame,marker,x,y,z

``.npz`` form: ``meta`` (the sequence.json text), ``depth`` (F, H, W) uint16 raw
values, and optionally ``joints`` (F, 15, 3), ``markers`` (F, M, 3), ``marker_names``
(M,). Directory frames load lazily, one PNG per :meth:`Sequence.depth` call; only the
PNG headers are read when the sequence is opened. A ``.npz`` is read whole on first use.
Writing (:func:`write_sequence`) is in :mod:`depthtrack.io.sequence_write`.
"""
from __future__ import annotations

import json
import os
import re
import struct
from pathlib import Path

import numpy as np

from ..camera import Camera
from ..contract import JOINT_NAMES, SEQUENCE_FORMAT
from ..errors import InputError
from .points_csv import format_points_csv, read_points_csv, write_points_csv
# The writer lives in sequence_write; its names stay importable from here, where callers look.
from .sequence_write import _write_png16, depth_to_raw, write_sequence  # noqa: F401
from .validation import (PNG_SIGNATURE as _PNG_SIGNATURE, check_camera_fields, check_covers, check_png_chunks,
                         finite_positive, in_range, stderr_silenced)

_FRAME_NAME = re.compile(r"^(\d+)\.png$")


# ------------------------------------------------------------------ PNG helpers
def png_header(path):
    """``(width, height, bit_depth, colour_type)`` from a PNG's IHDR chunk (reads 33 bytes).

    Raises
    ------
    InputError
        Not a PNG, or unreadable.
    """
    try:
        with open(path, "rb") as f:
            head = f.read(33)
    except OSError as exc:
        raise InputError(path, f"cannot read ({exc.strerror or exc})") from None
    if len(head) < 33 or head[:8] != _PNG_SIGNATURE or head[12:16] != b"IHDR":
        raise InputError(path, "not a PNG file")
    width, height, bit_depth, colour_type = struct.unpack(">IIBB", head[16:26])
    return width, height, bit_depth, colour_type


def _read_png16(path) -> np.ndarray:
    import cv2

    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise InputError(path, f"cannot read ({exc.strerror or exc})") from None
    check_png_chunks(path, data)
    with stderr_silenced():                    # libpng reports bad data on stderr too
        raw = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED)
    if raw is None:
        raise InputError(path, "cannot decode PNG")
    if raw.dtype != np.uint16 or raw.ndim != 2:
        raise InputError(path, f"PNG is not 16-bit single channel ({raw.dtype}, shape {raw.shape})")
    return raw


# ------------------------------------------------------------------- metadata
def _parse_meta(text: str, path):
    try:
        meta = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(path, f"invalid JSON (line {exc.lineno}: {exc.msg})") from None
    if not isinstance(meta, dict):
        raise InputError(path, "sequence.json must hold a JSON object")
    fmt = meta.get("format")
    if fmt != SEQUENCE_FORMAT:
        raise InputError(path, f"unknown format version {fmt!r} (expected {SEQUENCE_FORMAT!r})")
    for key in ("fps", "depth_scale", "camera"):
        if key not in meta:
            raise InputError(path, f"missing {key!r}")
    fps = in_range(finite_positive(meta["fps"], "fps", path), "fps", path)
    depth_scale = in_range(finite_positive(meta["depth_scale"], "depth_scale", path), "depth_scale", path)
    if not isinstance(meta["camera"], dict):
        raise InputError(path, "camera must be an object")
    check_camera_fields(meta["camera"], path)
    try:
        camera = Camera.from_dict(meta["camera"], path)
    except InputError as exc:
        raise InputError(path, exc.problem) from None
    height = None
    subject = meta.get("subject")
    if subject is not None:
        if not isinstance(subject, dict):
            raise InputError(path, "subject must be an object")
        if subject.get("height_m") is not None:
            height = in_range(finite_positive(subject["height_m"], "subject.height_m", path),
                               "subject.height_m", path)
    return meta, camera, fps, depth_scale, height


# ------------------------------------------------------------------- sequence
class FrameIteration:
    """What every sequence class derives from ``len``, ``depth(i)``, ``path``, ``fps`` and
    ``camera``: iteration over the depth frames, a repr and the duration."""

    def __iter__(self):
        for i in range(len(self)):
            yield self.depth(i)

    def __repr__(self):
        return (f"{type(self).__name__}({str(self.path)!r}, frames={len(self)}, fps={self.fps:g}, "
                f"camera={self.camera.width}x{self.camera.height})")

    @property
    def duration(self) -> float:
        """Seconds covered by the frames."""
        return len(self) / self.fps


class Sequence(FrameIteration):
    """A depth sequence opened from a directory or a ``.npz``; frames load on demand.

    Attributes
    ----------
    path : pathlib.Path
    camera : Camera
    fps : float
    depth_scale : float
        Metres per raw 16-bit unit.
    subject_height : float or None
        Metres, from ``subject.height_m``.
    meta : dict
        The whole sequence.json (``"synth"`` included when present).
    """

    def __init__(self, path, meta, camera, fps, depth_scale, subject_height, n_frames,
                 frame_files=None, npz_path=None, joints_path=None, markers_path=None):
        self.path = Path(path)
        self.meta = meta
        self.camera = camera
        self.fps = fps
        self.depth_scale = depth_scale
        self.subject_height = subject_height
        self._n = n_frames
        self._frame_files = frame_files
        self._npz_path = npz_path
        self._npz = None
        self._joints_path = joints_path
        self._markers_path = markers_path
        self._joints = self._markers = self._marker_names = None
        self._loaded_gt = False

    def __len__(self) -> int:
        return self._n

    @property
    def timestamps(self) -> np.ndarray:
        """(F,) float seconds: the source recording's times when ``convert`` kept them, else i / fps."""
        source = self.meta.get("source")
        kept = source.get("timestamps") if isinstance(source, dict) else None
        if isinstance(kept, list) and len(kept) == self._n:
            return np.asarray(kept, dtype=float)
        return np.arange(self._n) / self.fps

    def _npz_data(self):
        if self._npz is None:
            with np.load(self._npz_path, allow_pickle=False) as data:
                self._npz = {k: data[k] for k in data.files}
        return self._npz

    def raw_depth(self, i: int) -> np.ndarray:
        """(H, W) uint16: frame ``i`` as stored."""
        if not -self._n <= i < self._n:
            raise IndexError(f"frame {i} out of range ({self._n} frames)")
        i %= self._n
        if self._frame_files is not None:
            path = self._frame_files[i]
            raw = _read_png16(path)
            if raw.shape != self.camera.shape:
                raise InputError(path, f"frame is {raw.shape[1]} x {raw.shape[0]}, camera is "
                                       f"{self.camera.width} x {self.camera.height}")
            return raw
        return self._npz_data()["depth"][i]

    def depth(self, i: int) -> np.ndarray:
        """(H, W) float32: camera-frame z of frame ``i`` in metres, 0 = no reading."""
        return (self.raw_depth(i).astype(np.float64) * self.depth_scale).astype(np.float32)

    def _load_ground_truth(self):
        if self._loaded_gt:
            return
        if self._frame_files is not None:
            if self._joints_path is not None:
                self._joints, _ = read_points_csv(self._joints_path, self._n, "joint", JOINT_NAMES)
                check_covers(self._joints_path, self._joints)
            if self._markers_path is not None:
                # sequence.json may fix the marker order; otherwise first appearance.
                names = self.meta.get("marker_names")
                self._markers, self._marker_names = read_points_csv(
                    self._markers_path, self._n, "marker",
                    names if isinstance(names, list) and names else None)
        else:
            data = self._npz_data()
            if "joints" in data:
                self._joints = data["joints"].astype(float)
                check_covers(self._npz_path, self._joints)
            if "markers" in data:
                self._markers = data["markers"].astype(float)
                self._marker_names = [str(n) for n in data.get("marker_names", [])]
        self._loaded_gt = True

    @property
    def joints(self):
        """(F, 15, 3) float ground-truth joints (NaN where unknown), or None."""
        self._load_ground_truth()
        return self._joints

    @property
    def markers(self):
        """(F, M, 3) float ground-truth markers (NaN where unknown), or None."""
        self._load_ground_truth()
        return self._markers

    @property
    def marker_names(self):
        """list of str, (M,), or None."""
        self._load_ground_truth()
        return self._marker_names


def _open_directory(path: Path) -> Sequence:
    meta_path = path / "sequence.json"
    try:
        text = meta_path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError(meta_path, "missing sequence.json (not a depth sequence directory)") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(meta_path, f"cannot read ({getattr(exc, 'strerror', None) or exc})") from None
    meta, camera, fps, depth_scale, height = _parse_meta(text, meta_path)

    depth_dir = path / "depth"
    if not depth_dir.is_dir():
        raise InputError(depth_dir, "missing depth/ directory")
    numbered = []
    for entry in os.scandir(depth_dir):
        if not entry.name.lower().endswith(".png"):
            continue
        match = _FRAME_NAME.match(entry.name)
        if not match:
            raise InputError(entry.path, "frame file name is not a frame number (NNNNNN.png)")
        numbered.append((int(match.group(1)), entry.path))
    if not numbered:
        raise InputError(depth_dir, "empty sequence: no depth frames")
    numbered.sort()
    numbers = np.array([n for n, _ in numbered])
    expected = np.arange(len(numbers))
    if np.any(numbers != expected):
        k = int(np.flatnonzero(numbers != expected)[0])
        if k < len(numbers) and k > 0 and numbers[k] == numbers[k - 1]:
            raise InputError(numbered[k][1], f"frame number {numbers[k]} appears twice")
        raise InputError(depth_dir, f"gap in frame numbering: frame {k} is missing "
                                    f"(next is {numbers[k]})")
    files = [p for _, p in numbered]
    for f in files:
        width, height_px, bit_depth, colour = png_header(f)
        if bit_depth != 16 or colour != 0:
            raise InputError(f, f"PNG is not 16-bit single channel (bit depth {bit_depth}, colour type {colour})")
        if (width, height_px) != (camera.width, camera.height):
            raise InputError(f, f"frame is {width} x {height_px}, camera is {camera.width} x {camera.height}")
    gt = path / "groundtruth"
    joints = gt / "joints.csv"
    markers = gt / "markers.csv"
    return Sequence(path, meta, camera, fps, depth_scale, height, len(files), frame_files=files,
                    joints_path=joints if joints.is_file() else None,
                    markers_path=markers if markers.is_file() else None)


def _open_npz(path: Path) -> Sequence:
    try:
        with np.load(path, allow_pickle=False) as data:
            files = set(data.files)
            if "meta" not in files or "depth" not in files:
                raise InputError(path, "not a depth sequence .npz (needs 'meta' and 'depth')")
            text = str(data["meta"])
            depth = data["depth"]
            arrays = {k: data[k] for k in files}
    except InputError:
        raise
    except Exception as exc:  # zipfile / format errors from numpy
        raise InputError(path, f"cannot read .npz ({exc})") from None
    meta, camera, fps, depth_scale, height = _parse_meta(text, path)
    if depth.dtype != np.uint16 or depth.ndim != 3:
        raise InputError(path, f"depth must be (F, H, W) uint16, not {depth.dtype} {depth.shape}")
    if depth.shape[0] == 0:
        raise InputError(path, "empty sequence: no depth frames")
    if depth.shape[1:] != camera.shape:
        raise InputError(path, f"frames are {depth.shape[2]} x {depth.shape[1]}, camera is "
                               f"{camera.width} x {camera.height}")
    n = depth.shape[0]
    if "joints" in arrays and arrays["joints"].shape != (n, len(JOINT_NAMES), 3):
        raise InputError(path, f"joints must be ({n}, 15, 3), not {arrays['joints'].shape}")
    if "markers" in arrays:
        m = arrays["markers"]
        names = arrays.get("marker_names")
        if m.ndim != 3 or m.shape[0] != n or m.shape[2] != 3 or names is None or len(names) != m.shape[1]:
            raise InputError(path, f"markers must be ({n}, M, 3) with M marker_names")
    for key in ("joints", "markers"):
        if key in arrays:
            a = arrays[key]
            if a.dtype.kind not in "fiu":
                raise InputError(path, f"{key} must hold numbers, not {a.dtype}")
            if np.any(np.isinf(a)):
                raise InputError(path, f"{key} hold infinite values")
    seq = Sequence(path, meta, camera, fps, depth_scale, height, n, npz_path=path)
    seq._npz = arrays
    return seq


def open_native(path) -> Sequence:
    """Open a depth sequence directory or ``.npz`` file (our own formats only).

    Validates everything that can be checked cheaply: sequence.json, frame numbering,
    every PNG header (16-bit single channel, camera size). Pixels and ground truth are
    read on first use.

    Raises
    ------
    InputError
        One line naming the file and the problem.
    """
    path = Path(path)
    if path.is_dir():
        return _open_directory(path)
    if path.suffix.lower() == ".npz":
        if not path.is_file():
            raise InputError(path, "no such file")
        return _open_npz(path)
    if not path.exists():
        raise InputError(path, "no such sequence directory or .npz file")
    raise InputError(path, "not a sequence directory or .npz file")


def open_sequence(path, **options):
    """Open any readable depth recording: our directory or ``.npz``, or what a reader in
    :mod:`depthtrack.io.registry` reads (``.mkv``, ROS bags, TUM folders, plugins)."""
    from .registry import open_sequence as open_any

    return open_any(path, **options)


__all__ = ["Sequence", "open_sequence", "open_native", "write_sequence", "read_points_csv", "format_points_csv",
           "write_points_csv", "png_header", "depth_to_raw"]
