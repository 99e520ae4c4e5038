"""Ground-truth point files: ``frame,<kind>,x,y,z`` CSV (joints or markers), read and written.

The contract (README, "File contracts"): one row per known (frame, point); a missing row
means unknown (NaN in the array); names are the contract joint names for joints and any
non-empty names, in order of first appearance, for markers.
"""
from __future__ import annotations

import csv
import io
import math
from pathlib import Path

import numpy as np

from ..errors import InputError


def read_points_csv(path, n_frames: int, kind: str, names=None):
    """Read ``frame,<kind>,x,y,z`` rows into a (F, N, 3) array.

    Parameters
    ----------
    path : path-like
    n_frames : int
        F; a frame outside ``0..F-1`` is an error.
    kind : {"joint", "marker"}
        The header's second column.
    names : sequence of str or None
        Allowed names in array order (joints); ``None`` = names in order of first
        appearance (markers).

    Returns
    -------
    points : (F, N, 3) float
        NaN where a row is absent (unknown).
    names : list of str, (N,)
    """
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(path, f"cannot read ({getattr(exc, 'strerror', None) or exc})") from None
    rows = list(csv.reader(io.StringIO(text)))
    while rows and not rows[-1]:
        rows.pop()
    expected = ["frame", kind, "x", "y", "z"]
    if not rows or [c.strip() for c in rows[0]] != expected:
        raise InputError(path, f"line 1: header must be {','.join(expected)}")
    fixed = names is not None
    index = {n: i for i, n in enumerate(names)} if fixed else {}
    order = list(names) if fixed else []
    frames, slots, values = [], [], []
    for line, row in enumerate(rows[1:], start=2):
        if len(row) != 5:
            raise InputError(path, f"line {line}: expected 5 fields, found {len(row)}")
        frame_text, name = row[0].strip(), row[1].strip()
        if not frame_text.isdigit():
            raise InputError(path, f"line {line}: frame {frame_text!r} is not a whole number")
        frame = int(frame_text)
        if frame >= n_frames:
            raise InputError(path, f"line {line}: frame {frame} is beyond the sequence ({n_frames} frames)")
        if name not in index:
            if fixed:
                raise InputError(path, f"line {line}: unknown {kind} name {name!r}")
            if not name:
                raise InputError(path, f"line {line}: empty {kind} name")
            index[name] = len(order)
            order.append(name)
        try:
            xyz = [float(v) for v in row[2:]]
        except ValueError:
            raise InputError(path, f"line {line}: coordinate is not a number") from None
        if not all(math.isfinite(v) for v in xyz):
            raise InputError(path, f"line {line}: non-finite coordinate")
        frames.append(frame)
        slots.append(index[name])
        values.append(xyz)
    points = np.full((n_frames, len(order), 3), np.nan)
    if frames:
        frames_a, slots_a = np.asarray(frames), np.asarray(slots)
        key = frames_a * len(order) + slots_a
        uniq, counts = np.unique(key, return_counts=True)
        if np.any(counts > 1):
            dup = uniq[counts > 1][0]
            raise InputError(path, f"frame {dup // len(order)} lists {kind} "
                                   f"{order[dup % len(order)]!r} twice")
        points[frames_a, slots_a] = np.asarray(values)
    return points, order


def format_points_csv(points, names, kind: str) -> str:
    """``frame,<kind>,x,y,z`` text for (F, N, 3) points; NaN rows are left out."""
    points = np.asarray(points, dtype=float)
    out = io.StringIO()
    out.write(f"frame,{kind},x,y,z\n")
    known = np.all(np.isfinite(points), axis=-1)
    for f, n in zip(*np.nonzero(known)):
        x, y, z = points[f, n]
        out.write(f"{f},{names[n]},{x:.6f},{y:.6f},{z:.6f}\n")
    return out.getvalue()



def write_points_csv(path, points, names, kind: str) -> None:
    """Write ``frame,<kind>,x,y,z`` rows atomically (NaN rows left out)."""
    from .atomic import write_text_atomic

    write_text_atomic(path, format_points_csv(points, names, kind))
