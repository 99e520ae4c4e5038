"""Exports of a track for other tools: one registry, one module per format.

* ``glb``  -> ``track.glb``: skinned body and animation (:mod:`.gltf`); y up, metres
* ``gltf`` -> ``track.gltf``: the same as JSON glTF, buffer embedded
* ``c3d``  -> ``track.c3d``: 39 Plug-in Gait markers and 15 joints (:mod:`.c3d`); z up, mm
* ``json`` -> ``joints.json``: per-frame joints (:mod:`.joints_json`); camera frame, metres
* ``bvh``  -> ``track.bvh``: T-pose rest skeleton (:mod:`.bvh`); ``up`` y or z, metres
* ``csv``  -> ``joints.csv``: ``frame,joint,x,y,z`` as the track's own; camera frame, metres

A ``suffix`` (``"_smoothed"`` for smoothed exports) goes before the extension, so smoothed
files sit beside raw ones. Frames without a pose are NaN/absent/``null`` where the format
knows "unknown" (C3D residual -1, JSON ``null``, CSV rows left out) and hold the last
pose where it does not (glTF, BVH).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..contract import JOINT_NAMES
from ..errors import InputError
from ..io.atomic import write_text_atomic
from .axes import UP_AXES
from ..io.sequence import format_points_csv
from ..io.track_output import hold_last_pose


@dataclass(frozen=True)
class Exporter:
    """One export format: its file name and its writer ``write(path, body, poses, joints, fps, up)``."""

    filename: str
    write: object
    description: str


def _glb(path, body, poses, joints, fps, up):
    from .gltf import write_gltf
    return write_gltf(path, body, poses, fps)


def _c3d(path, body, poses, joints, fps, up):
    from .c3d import write_c3d
    return write_c3d(path, body, poses, joints, fps)


def _json(path, body, poses, joints, fps, up):
    from .joints_json import write_joints_json
    return write_joints_json(path, joints, fps)


def _bvh(path, body, poses, joints, fps, up):
    from .bvh import write_bvh_export
    filled = hold_last_pose(poses)
    if filled is None:
        raise ValueError("the track has no frame with a pose")
    return write_bvh_export(path, body, filled, fps, rest="tpose", up=up)


def _csv(path, body, poses, joints, fps, up):
    write_text_atomic(path, format_points_csv(joints, JOINT_NAMES, "joint"))
    return Path(path)


#: Format name -> :class:`Exporter`; other packages may add entries.
EXPORTERS = {
    "glb": Exporter("track.glb", _glb, "glTF 2.0 binary: skinned body and animation, y up, metres"),
    "gltf": Exporter("track.gltf", _glb, "glTF 2.0 JSON (buffer embedded): the same as glb"),
    "c3d": Exporter("track.c3d", _c3d, "C3D: 39 Plug-in Gait markers and 15 joints, z up, millimetres"),
    "json": Exporter("joints.json", _json, "per-frame joints, camera frame, metres"),
    "bvh": Exporter("track.bvh", _bvh, "BVH with a T-pose rest, y or z up (--up), metres"),
    "csv": Exporter("joints.csv", _csv, "frame,joint,x,y,z, camera frame, metres"),
}


def parse_formats(text) -> list:
    """``"glb,c3d"`` -> ``["glb", "c3d"]`` (order kept, duplicates dropped).

    Raises
    ------
    InputError
        An empty list or an unknown format (naming the known ones).
    """
    items = [t.strip().lower() for t in (text.split(",") if isinstance(text, str) else text)]
    items = list(dict.fromkeys(t for t in items if t))
    if not items:
        raise InputError(None, f"no export format given; choose from {', '.join(EXPORTERS)}")
    for t in items:
        if t not in EXPORTERS:
            raise InputError(None, f"unknown export format {t!r}; choose from {', '.join(EXPORTERS)}")
    return items


def export_name(fmt: str, suffix: str = "") -> str:
    """The file name a format is written under, with ``suffix`` before the extension."""
    stem, dot, ext = EXPORTERS[fmt].filename.rpartition(".")
    return f"{stem}{suffix}{dot}{ext}"


def write_exports(out_dir, body, poses, fps: float, formats, joints=None, up: str = "y",
                  suffix: str = "") -> dict:
    """Write a track in several formats into ``out_dir`` (each file atomically).

    Parameters
    ----------
    out_dir : path-like
        Created when missing; only the files named by the formats are written.
    body : BodyModel
        The tracked (scaled) body.
    poses : (F, D) float
        NaN rows = frames without a pose.
    fps : float
    formats : sequence of str
        Keys of :data:`EXPORTERS`.
    joints : (F, 15, 3) float or None
        Contract joints (camera frame); ``None`` computes them from ``poses``.
    up : {"y", "z"}
        Up axis of the BVH (glTF is always y up, C3D z up, JSON/CSV the camera frame).
    suffix : str
        Added to every file name before its extension.

    Returns
    -------
    dict {format: pathlib.Path}
    """
    if up not in UP_AXES:
        raise InputError(None, f"unknown up axis {up!r}; choose from {', '.join(UP_AXES)}")
    formats = parse_formats(formats)
    poses = np.asarray(poses, float)
    if joints is None:
        joints = np.full((len(poses), len(JOINT_NAMES), 3), np.nan)
        valid = np.all(np.isfinite(poses), axis=1)
        if valid.any():
            joints[valid] = body.joint_positions(poses[valid])
    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise InputError(out_dir, "exists and is not a directory")
    out_dir.mkdir(parents=True, exist_ok=True)
    written = {}
    for fmt in formats:
        path = out_dir / export_name(fmt, suffix)
        try:
            written[fmt] = Path(EXPORTERS[fmt].write(path, body, poses, joints, float(fps), up))
        except ValueError as exc:
            if isinstance(exc, InputError):
                raise
            raise InputError(path, str(exc)) from None
    return written
