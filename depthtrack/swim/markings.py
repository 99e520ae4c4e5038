"""The CSV format for 2D joint markings, and reconstruction from it.

Format (one header line, comment lines start with ``#``)::

    frame,joint,u,v,view,nearer
    0,hips,412.0,301.5,side,
    0,r_knee,530.2,318.0,side,1
    0,r_knee,529.0,140.3,top,
    12,cycle_start,,,side,

* ``frame``: integer frame of that view's recording;
* ``joint``: one of the 14 stick-figure joints (``hips, l_hip, l_knee, l_foot,
  r_hip, r_knee, r_foot, neck, l_shoulder, l_elbow, l_hand, r_shoulder,
  r_elbow, r_hand``), or ``cycle_start`` (u and v empty) to label the frame where
  the stroke's distinctive pose occurs;
* ``u, v``: pixels, u to the right, v downwards;
* ``view``: ``side`` (under water, or the whole swimmer), ``side_above`` (a
  second, above-water camera of the same side view: joined to ``side`` through
  the joints marked in both), ``top`` or ``bottom``;
* ``nearer`` (side view only, optional): 1 when the joint is nearer the camera
  than its parent joint, 0 or empty when farther (Taylor's ambiguity).

Unsynchronised views are aligned by their first ``cycle_start`` (thesis 2.6).
Segment lengths come as JSON: ``{"l_knee": 0.41, ...}`` keyed by the child
joint of each segment, or a list of the 13 in stick-figure order.
"""
from __future__ import annotations

import csv
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..io.atomic import atomic_path
from .reconstruct import (complete_other_half, join_above_below, reconstruct_single_view, reconstruct_two_views,
                          sync_offset)
from .stickfigure import N_JOINTS, SEGMENTS, SWIM_INDEX, SWIM_JOINTS

VIEWS = ("side", "side_above", "top", "bottom")


@dataclass
class Markings:
    """Markings of one take.

    Attributes
    ----------
    uv : dict view -> (F, 14, 2) float, NaN where unmarked (frames 0 .. F-1 of that view)
    nearer : (F, 13) bool for the side view
    cycle_starts : dict view -> list of int
    frames : (F,) int frame numbers of the side view (output rows)
    """

    uv: dict
    nearer: np.ndarray
    cycle_starts: dict = field(default_factory=dict)
    frames: np.ndarray | None = None


def read_markings(path) -> Markings:
    """Parse a markings CSV; raises :class:`InputError` naming the line on bad content."""
    path = Path(path)
    if not path.is_file():
        raise InputError(path, "no such markings file")
    rows = []
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            lines = [ln for ln in fh if ln.strip() and not ln.lstrip().startswith("#")]
    except UnicodeDecodeError:
        raise InputError(path, "not a text CSV file (binary content)") from None
    if any("\0" in ln for ln in lines):
        raise InputError(path, "not a text CSV file (binary content)")
    reader = csv.DictReader(lines)
    need = {"frame", "joint", "u", "v", "view"}
    if reader.fieldnames is None or not need <= set(reader.fieldnames):
        raise InputError(path, f"header must have the columns {', '.join(sorted(need))}")
    starts = {}
    for n, row in enumerate(reader, start=2):
        try:
            frame = int(row["frame"])
        except (TypeError, ValueError):
            raise InputError(path, f"line {n}: frame {row['frame']!r} is not an integer") from None
        if not 0 <= frame <= 10**7:
            raise InputError(path, f"line {n}: frame {frame} is outside 0 to 10000000")
        view = (row["view"] or "side").strip()
        if view not in VIEWS:
            raise InputError(path, f"line {n}: unknown view {view!r} ({', '.join(VIEWS)})")
        joint = row["joint"].strip()
        if joint == "cycle_start":
            starts.setdefault(view, []).append(frame)
            continue
        if joint not in SWIM_INDEX:
            raise InputError(path, f"line {n}: unknown joint {joint!r}")
        try:
            u, v = float(row["u"]), float(row["v"])
        except (TypeError, ValueError):
            raise InputError(path, f"line {n}: u, v must be numbers") from None
        if not (np.isfinite(u) and np.isfinite(v)):
            raise InputError(path, f"line {n}: u, v must be finite numbers")
        nearer = str(row.get("nearer") or "").strip() in ("1", "true", "True", "yes")
        rows.append((view, frame, SWIM_INDEX[joint], u, v, nearer))
    if not rows:
        raise InputError(path, "no joint markings")
    n_frames = max(r[1] for r in rows) + 1
    uv = {}
    nearer = np.zeros((n_frames, N_JOINTS - 1), bool)
    for view, frame, j, u, v, near in rows:
        arr = uv.setdefault(view, np.full((n_frames, N_JOINTS, 2), np.nan))
        arr[frame, j] = (u, v)
        if view == "side" and j > 0:
            nearer[frame, j - 1] = near
    side = uv.get("side")
    frames = np.flatnonzero(np.isfinite(side).any(axis=(1, 2))) if side is not None else np.arange(n_frames)
    return Markings(uv, nearer, {k: sorted(v) for k, v in starts.items()}, frames)


def write_markings(path, uv_by_view: dict, nearer=None, cycle_starts=None) -> None:
    """Write markings (``uv_by_view[view] : (F, 14, 2)``, NaN = unmarked) in the CSV format."""
    with atomic_path(path) as tmp:
        with open(tmp, "w", newline="") as fh:
            fh.write("# depthtrack-swim-markings/1\n")
            w = csv.writer(fh)
            w.writerow(["frame", "joint", "u", "v", "view", "nearer"])
            for view, uv in uv_by_view.items():
                for f in range(len(uv)):
                    for j in range(N_JOINTS):
                        if not np.isfinite(uv[f, j]).all():
                            continue
                        near = ""
                        if view == "side" and nearer is not None and j > 0:
                            near = "1" if nearer[f, j - 1] else "0"
                        w.writerow([f, SWIM_JOINTS[j], f"{uv[f, j, 0]:.3f}", f"{uv[f, j, 1]:.3f}", view, near])
            for view, starts in (cycle_starts or {}).items():
                for s in starts:
                    w.writerow([int(s), "cycle_start", "", "", view, ""])


def read_lengths(path) -> np.ndarray:
    """Segment lengths (13,) from JSON (dict by child joint, or list)."""
    path = Path(path)
    if not path.is_file():
        raise InputError(path, "no such lengths file")
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except UnicodeDecodeError:
        raise InputError(path, "not a JSON text file") from None
    except json.JSONDecodeError as exc:
        raise InputError(path, f"not JSON: {exc.msg}") from None
    try:
        if isinstance(data, dict):
            missing = [s for s in SEGMENTS if s not in data]
            if missing:
                raise InputError(path, f"lengths missing for {', '.join(missing)}")
            lengths = np.array([float(data[s]) for s in SEGMENTS])
        else:
            lengths = np.asarray(data, dtype=float)
    except (TypeError, ValueError):
        raise InputError(path, "lengths must be numbers") from None
    if lengths.shape != (len(SEGMENTS),):
        raise InputError(path, f"expected {len(SEGMENTS)} lengths, got {lengths.size}")
    if not (np.isfinite(lengths) & (lengths > 0)).all():
        raise InputError(path, "lengths must be positive finite numbers")
    return lengths


def _shift(uv, offset):
    """Re-index a view's frames by ``offset`` (frame f of the result = frame f + offset of ``uv``)."""
    out = np.full_like(uv, np.nan)
    F = len(uv)
    src = np.arange(F) + offset
    ok = (src >= 0) & (src < F)
    out[ok] = uv[src[ok]]
    return out


def reconstruct_markings(markings: Markings, lengths, stroke: str = "back"):
    """3D joints of every frame from the markings: two views when a top/bottom view exists,
    else Taylor's single view; the missing body half completed by mirror or half-cycle shift.

    Returns
    -------
    joints : (F, 14, 3) float
        Frames 0 .. F-1 of the side view (NaN in frames it did not mark).
    info : str
    """
    if "side" not in markings.uv:
        raise InputError(None, "markings need a side view")
    side = markings.uv["side"]
    if "side_above" in markings.uv:
        side = join_above_below(side, markings.uv["side_above"])
    other = "top" if "top" in markings.uv else "bottom" if "bottom" in markings.uv else None
    if other is not None:
        top = markings.uv[other]
        if markings.cycle_starts.get("side") and markings.cycle_starts.get(other):
            top = _shift(top, sync_offset(markings.cycle_starts["side"], markings.cycle_starts[other]))
        joints, info = reconstruct_two_views(side, top, lengths, other)
        text = f"two views, view scale {info['view_scale']:.4g}"
    else:
        joints, scale = reconstruct_single_view(side, lengths, markings.nearer)
        text = f"single view, scale {scale:.4g} px per unit"
    marked = np.isfinite(joints).all(-1).any(-1)          # frames the side view marked
    if not np.isfinite(joints[marked]).all():
        joints = complete_other_half(joints, stroke, markings.cycle_starts.get("side"))
        text += f", other half by {'half-cycle shift' if stroke in ('back', 'freestyle') else 'mirroring'}"
    return joints, text


def write_joints_csv(path, joints, frames=None) -> None:
    """``frame,joint,x,y,z`` rows of ``joints (F, 14, 3)`` for ``frames`` (default all; NaN joints left out)."""
    frames = np.arange(len(joints)) if frames is None else np.asarray(frames)
    with atomic_path(path) as tmp:
        with open(tmp, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["frame", "joint", "x", "y", "z"])
            for f in frames:
                for j in range(N_JOINTS):
                    if np.isfinite(joints[f, j]).all():
                        w.writerow([int(f), SWIM_JOINTS[j], *(f"{x:.5f}" for x in joints[f, j])])
