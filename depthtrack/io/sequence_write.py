"""Writing depth sequences: the ``SEQ/`` directory or its ``.npz`` twin, atomically.

The reading side, and the contract both follow, is :mod:`depthtrack.io.sequence`.
"""
from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np

from ..camera import Camera
from ..contract import JOINT_NAMES, SEQUENCE_FORMAT
from .atomic import atomic_path
from .points_csv import format_points_csv

#: Largest raw value a 16-bit PNG holds.
MAX_RAW = 65535


def _write_png16(path, raw: np.ndarray) -> None:
    import cv2

    if not cv2.imwrite(os.fspath(path), np.ascontiguousarray(raw, dtype=np.uint16),
                       [cv2.IMWRITE_PNG_COMPRESSION, 1]):
        raise OSError(f"could not write {path}")


def depth_to_raw(depth, depth_scale: float) -> np.ndarray:
    """Quantise metric depth to raw 16-bit values.

    Parameters
    ----------
    depth : (H, W) float
        Metres; 0, negative or non-finite = no reading.
    depth_scale : float
        Metres per raw unit.

    Returns
    -------
    raw : (H, W) uint16

    Raises
    ------
    ValueError
        A depth beyond what 16 bits hold at this scale.
    """
    depth = np.asarray(depth, dtype=np.float64)
    valid = np.isfinite(depth) & (depth > 0)
    raw = np.zeros(depth.shape, dtype=np.float64)
    raw[valid] = np.rint(depth[valid] / depth_scale)
    if raw.max(initial=0) > MAX_RAW:
        raise ValueError(f"depth {depth[valid].max():.3f} m exceeds the 16-bit range at "
                         f"depth_scale {depth_scale} ({MAX_RAW * depth_scale:.3f} m)")
    return raw.astype(np.uint16)


def _build_meta(camera: Camera, fps, depth_scale, subject=None, extra=None) -> dict:
    meta = {"format": SEQUENCE_FORMAT, "fps": float(fps), "depth_scale": float(depth_scale),
            "camera": camera.to_dict()}
    if subject is not None:
        meta["subject"] = {"height_m": float(subject)} if np.isscalar(subject) else dict(subject)
    if extra:
        for key, value in extra.items():
            if key in meta:
                raise ValueError(f"extra key {key!r} would overwrite a contract field")
            meta[key] = value
    return meta


def _check_points(name, points, n_frames, n_points=None):
    points = np.asarray(points, dtype=float)
    if points.ndim != 3 or points.shape[0] != n_frames or points.shape[2] != 3 or \
            (n_points is not None and points.shape[1] != n_points):
        want = f"({n_frames}, {n_points if n_points is not None else 'M'}, 3)"
        raise ValueError(f"{name} must be {want}, not {points.shape}")
    if np.any(np.isinf(points)):
        raise ValueError(f"{name} hold infinite values (use NaN for unknown)")
    return points


def write_sequence(path, depths, camera: Camera, fps: float, depth_scale: float = 0.001,
                   joints=None, markers=None, marker_names=None, subject=None, extra=None):
    """Write a depth sequence atomically (a directory, or one file if ``path`` ends in .npz).

    Parameters
    ----------
    path : path-like
        Output directory (replaced as a whole) or ``.npz`` file.
    depths : (F, H, W) float array or iterable of (H, W) float
        Metres; 0 or non-finite = no reading. An iterable is consumed frame by frame
        (directory form), so a long sequence need not fit in memory.
    camera : Camera
    fps : float
    depth_scale : float
        Metres per raw unit of the 16-bit PNGs.
    joints : (F, 15, 3) float or None
        Contract joints, camera frame, NaN = unknown.
    markers : (F, M, 3) float or None
    marker_names : sequence of str, (M,)
    subject : float or dict or None
        Subject height in metres, or the ``subject`` object.
    extra : dict or None
        More top-level sequence.json fields (e.g. ``{"synth": {...}}``).

    Returns
    -------
    pathlib.Path
    """
    path = Path(path)
    fps = float(fps)
    if not (math.isfinite(fps) and fps > 0):
        raise ValueError(f"fps must be positive, not {fps}")
    if not (math.isfinite(depth_scale) and depth_scale > 0):
        raise ValueError(f"depth_scale must be positive, not {depth_scale}")
    extra = dict(extra or {})
    if markers is not None:
        if marker_names is None:
            raise ValueError("markers need marker_names")
        marker_names = [str(n) for n in marker_names]
        if len(set(marker_names)) != len(marker_names) or any(
                not n or "," in n or n != n.strip() for n in marker_names):
            raise ValueError("marker names must be unique, non-empty, without commas or padding")
        # Keeps the column order when a marker is missing from the first frames.
        extra["marker_names"] = marker_names
    meta = _build_meta(camera, fps, depth_scale, subject, extra)

    def check_frame(i, depth):
        depth = np.asarray(depth)
        if depth.shape != camera.shape:
            raise ValueError(f"frame {i} is {depth.shape}, camera is {camera.shape}")
        return depth_to_raw(depth, depth_scale)

    if path.suffix.lower() == ".npz":
        frames = [check_frame(i, d) for i, d in enumerate(depths)]
        if not frames:
            raise ValueError("empty sequence: no frames")
        raw = np.stack(frames)
        n = len(raw)
        arrays = {"meta": np.array(json.dumps(meta, indent=1)), "depth": raw}
        if joints is not None:
            arrays["joints"] = _check_points("joints", joints, n, len(JOINT_NAMES))
        if markers is not None:
            arrays["markers"] = _check_points("markers", markers, n, len(marker_names))
            arrays["marker_names"] = np.array(marker_names)
        with atomic_path(path) as tmp:
            with open(tmp, "wb") as f:
                np.savez_compressed(f, **arrays)
        return path

    with atomic_path(path) as tmp:
        tmp = Path(tmp)
        (tmp / "depth").mkdir(parents=True)
        n = 0
        for i, depth in enumerate(depths):
            _write_png16(tmp / "depth" / f"{i:06d}.png", check_frame(i, depth))
            n += 1
        if n == 0:
            raise ValueError("empty sequence: no frames")
        if joints is not None or markers is not None:
            (tmp / "groundtruth").mkdir()
        if joints is not None:
            joints = _check_points("joints", joints, n, len(JOINT_NAMES))
            (tmp / "groundtruth" / "joints.csv").write_text(format_points_csv(joints, JOINT_NAMES, "joint"))
        if markers is not None:
            markers = _check_points("markers", markers, n, len(marker_names))
            (tmp / "groundtruth" / "markers.csv").write_text(format_points_csv(markers, marker_names, "marker"))
        (tmp / "sequence.json").write_text(json.dumps(meta, indent=1) + "\n")
    return path


__all__ = ["write_sequence", "depth_to_raw", "MAX_RAW"]
