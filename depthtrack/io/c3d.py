"""C3D motion-capture markers (via ezc3d) into the sequence's ``groundtruth/markers.csv``.

C3D stores marker trajectories in lab coordinates at the mocap rate (usually in mm).
:func:`read_c3d_markers` returns them in metres with NaN where a marker was not seen;
:func:`import_c3d_markers` maps them into a depth sequence's camera frame with a
given lab->camera transform, resamples them at the depth frame times and writes
``groundtruth/markers.csv`` atomically.
"""
from __future__ import annotations

import json
import math
import os
import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError

_UNITS = {"mm": 0.001, "cm": 0.01, "m": 1.0, "dm": 0.1, "in": 0.0254, "inch": 0.0254}


@dataclass
class C3dMarkers:
    """Marker trajectories from a C3D file.

    Attributes
    ----------
    positions : (F, M, 3) float
        Lab coordinates, metres; NaN where the marker was not reconstructed.
    names : list of str, (M,)
    rate : float
        Frames per second.
    units_m : float
        Metres per file unit.
    units_source : str
        Where ``units_m`` came from (the file's POINT:UNITS, the caller, or the C3D default).
    """

    positions: np.ndarray
    names: list
    rate: float
    units_m: float
    units_source: str


def _header_frames(path):
    """Frames the C3D header block claims (ezc3d reports what it could read instead), or None
    when the 16-bit header cannot say (65535 frames or more)."""
    with open(path, "rb") as f:
        head = f.read(512)
        param_block = head[0] if head else 0
        f.seek(max(param_block - 1, 0) * 512 + 3)
        processor = f.read(1)
    order = ">" if processor == bytes([86]) else "<"            # 86 = MIPS, big-endian
    first, last = struct.unpack(order + "HH", head[6:10])
    if last >= 65535 or last < first:
        return None
    return last - first + 1


def _probe(path) -> None:
    """Parse the file in a child process first: ezc3d crashes the process (SIGSEGV) on some
    corrupt parameter sections, which must end in one line, not a dead interpreter."""
    import subprocess
    import sys

    code = "import sys, ezc3d\ntry:\n    ezc3d.c3d(sys.argv[1])\nexcept Exception:\n    pass\n"
    try:
        child = subprocess.run([sys.executable, "-c", code, path], stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL, timeout=600)
    except subprocess.TimeoutExpired:
        raise InputError(path, "cannot read C3D (the reader did not finish in 10 minutes)") from None
    if child.returncode != 0:
        raise InputError(path, f"corrupt C3D (the C3D reader failed with status {child.returncode})")


def read_c3d_markers(path, units=None) -> C3dMarkers:
    """Read the 3D points of a C3D file.

    Parameters
    ----------
    path : path-like
    units : str or float or None
        Override for the file's POINT:UNITS ("mm", "m", ... or metres per unit).

    Raises
    ------
    InputError
        Unreadable file, no points, unknown units.
    """
    import ezc3d

    path = os.fspath(path)
    if not Path(path).is_file():
        raise InputError(path, "no such C3D file")
    _probe(path)
    try:
        c3d = ezc3d.c3d(path)
    except Exception as exc:  # ezc3d raises plain RuntimeError/IOError on bad files
        raise InputError(path, f"cannot read C3D ({str(exc).strip() or type(exc).__name__})") from None
    params = c3d["parameters"]["POINT"]
    points = np.asarray(c3d["data"]["points"], dtype=float)       # (4, M, F)
    if points.ndim != 3 or points.shape[1] == 0 or points.shape[2] == 0:
        raise InputError(path, "C3D file holds no 3D points")
    claimed = _header_frames(path)
    if claimed is not None and points.shape[2] < claimed:
        raise InputError(path, f"truncated C3D: the header says {claimed} frames, the file holds "
                               f"{points.shape[2]}")
    names = [str(n).strip() for n in params["LABELS"]["value"]][: points.shape[1]]
    names += [f"marker{i}" for i in range(len(names), points.shape[1])]
    rate = float(c3d["header"]["points"]["frame_rate"])
    if not (math.isfinite(rate) and rate > 0):
        raise InputError(path, f"C3D point rate is not positive ({rate})")

    if units is not None:
        if isinstance(units, str):
            if units.lower() not in _UNITS:
                raise InputError(path, f"unknown units {units!r}")
            units_m, source = _UNITS[units.lower()], f"given: '{units}'"
        else:
            units_m, source = float(units), f"given: {float(units):g} m/unit"
    else:
        file_units = [str(u).strip().lower() for u in params.get("UNITS", {}).get("value", [])]
        if file_units and file_units[0]:
            if file_units[0] not in _UNITS:
                raise InputError(path, f"unknown POINT:UNITS {file_units[0]!r}; pass units")
            units_m, source = _UNITS[file_units[0]], f"POINT:UNITS '{file_units[0]}'"
        else:
            units_m, source = 0.001, "POINT:UNITS absent; the C3D default 'mm' was used"

    xyz = np.transpose(points[:3], (2, 1, 0)) * units_m               # (F, M, 3)
    residuals = c3d["data"]["meta_points"].get("residuals")
    missing = ~np.all(np.isfinite(xyz), axis=-1)
    if residuals is not None and np.size(residuals):
        # C3D marks an invalid sample with a negative residual.
        missing |= np.asarray(residuals)[0].T < 0
    xyz[missing] = np.nan
    return C3dMarkers(positions=xyz, names=names, rate=rate, units_m=units_m, units_source=source)


def resample_markers(positions, src_rate: float, times) -> np.ndarray:
    """Linear interpolation of marker trajectories at given times.

    Parameters
    ----------
    positions : (F, M, 3) float
        NaN = not seen; an output sample next to a NaN source sample is NaN.
    src_rate : float
        Source frames per second (sample k at ``k / src_rate``).
    times : (K,) float
        Seconds.

    Returns
    -------
    (K, M, 3) float
    """
    positions = np.asarray(positions, float)
    F = positions.shape[0]
    t = np.asarray(times, float) * src_rate
    inside = (t >= 0) & (t <= F - 1)
    tc = np.clip(t, 0, F - 1)
    i0 = np.floor(tc).astype(int)
    i1 = np.minimum(i0 + 1, F - 1)
    a = (tc - i0)[:, None, None]
    # Exact hits take one sample, so a NaN neighbour does not spoil them.
    out = np.where(a == 0, positions[i0], (1 - a) * positions[i0] + a * positions[i1])
    out[~inside] = np.nan
    return out


def import_c3d_markers(c3d_path, sequence_dir, lab_to_camera=None, time_offset: float = 0.0,
                       units=None, names=None) -> Path:
    """Write a C3D file's markers as ``groundtruth/markers.csv`` of a sequence directory.

    Parameters
    ----------
    c3d_path : path-like
    sequence_dir : path-like
        An existing sequence directory (its fps and frame count set the sample times).
    lab_to_camera : (4, 4) float or None
        Rigid transform from lab to camera coordinates, metres; ``None`` = identity
        (the C3D is already in the camera frame).
    time_offset : float
        Mocap time (s) of depth frame 0.
    units : str or float or None
        Override for the C3D's units.
    names : sequence of str or None
        Markers to keep (default: all).

    Returns
    -------
    pathlib.Path of the CSV written.
    """
    from .atomic import write_text_atomic
    from .sequence import format_points_csv, open_native

    seq = open_native(sequence_dir)  # our own directory: the markers are written into it
    if seq._frame_files is None:
        raise InputError(sequence_dir, "markers can be imported into a sequence directory only, not a .npz")
    markers = read_c3d_markers(c3d_path, units=units)
    keep = list(range(len(markers.names)))
    if names is not None:
        index = {n: i for i, n in enumerate(markers.names)}
        unknown = [n for n in names if n not in index]
        if unknown:
            raise InputError(c3d_path, f"no marker named {unknown[0]!r}")
        keep = [index[n] for n in names]
    positions = markers.positions[:, keep]
    kept_names = [markers.names[i] for i in keep]
    if len(set(kept_names)) != len(kept_names):
        raise InputError(c3d_path, "marker labels are not unique")
    if lab_to_camera is not None:
        T = np.asarray(lab_to_camera, float)
        positions = positions @ T[:3, :3].T + T[:3, 3]
    times = time_offset + np.arange(len(seq)) / seq.fps
    sampled = resample_markers(positions, markers.rate, times)
    out = Path(sequence_dir) / "groundtruth" / "markers.csv"
    out.parent.mkdir(exist_ok=True)
    write_text_atomic(out, format_points_csv(sampled, kept_names, "marker"))
    # sequence.json fixes the marker column order when it lists marker names.
    meta = dict(seq.meta)
    meta["marker_names"] = kept_names
    write_text_atomic(Path(sequence_dir) / "sequence.json", json.dumps(meta, indent=1) + "\n")
    return out
