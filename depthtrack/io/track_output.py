"""Track outputs: the ``OUT/`` directory a tracker writes (see ARCHITECTURE.md, "Track").

::

    OUT/joints.csv     frame,joint,x,y,z  (camera frame, metres; same schema as ground truth)
    OUT/poses.npz      poses (F, D), pose_names (D,), joint_names (J,), body_height,
                       body_offsets (J, 3), fps
    OUT/track.bvh      the motion on our skeleton, y up (see depthtrack.io.bvh.write_bvh)
    OUT/summary.json   method, settings, frames, seconds, fps, ... (whatever the caller adds)
    OUT/body.json      the body the poses belong to (BodyModel.to_json; BodyModel.from_json
                       rebuilds it): height, shape, segment lengths

The directory is written as a whole and renamed into place, so a failed run leaves
no partial output.
"""
from __future__ import annotations

import json
import math
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..contract import JOINT_NAMES
from ..errors import InputError
from .atomic import atomic_path
from .bvh import write_bvh
from .sequence import format_points_csv, read_points_csv


@dataclass
class Track:
    """A track read back from ``OUT/``.

    Attributes
    ----------
    joints : (F, 15, 3) float
        Contract joints, NaN where the tracker gave none.
    poses : (F, D) float
    pose_names : list of str, (D,)
    joint_names : list of str, (J,)
        The body model's skeleton joints.
    body_height : float
    body_offsets : (J, 3) float
    fps : float
    summary : dict
    """

    joints: np.ndarray
    poses: np.ndarray
    pose_names: list
    joint_names: list
    body_height: float
    body_offsets: np.ndarray
    fps: float
    summary: dict


def write_track(out_dir, joints, poses, pose_names, body, fps: float, summary: dict | None = None) -> Path:
    """Write a tracking result directory atomically.

    Parameters
    ----------
    out_dir : path-like
        Replaced as a whole.
    joints : (F, 15, 3) float
        Contract joints in the camera frame; NaN rows are left out of joints.csv.
    poses : (F, D) float
        The body model's pose vectors.
    pose_names : sequence of str, (D,)
    body : BodyModel
        The (scaled) body the poses belong to.
    fps : float
    summary : dict or None
        Method, settings, timing...; ``frames`` and ``fps`` are filled in when absent.

    Returns
    -------
    pathlib.Path
    """
    joints = np.asarray(joints, dtype=float)
    poses = np.asarray(poses, dtype=float)
    F = len(poses)
    if joints.shape != (F, len(JOINT_NAMES), 3):
        raise ValueError(f"joints must be ({F}, 15, 3), not {joints.shape}")
    if poses.ndim != 2 or poses.shape[1] != len(pose_names):
        raise ValueError(f"poses must be (F, {len(pose_names)}), not {poses.shape}")
    if not (math.isfinite(fps) and fps > 0):
        raise ValueError(f"fps must be positive, not {fps}")
    summary = dict(summary or {})
    summary.setdefault("frames", F)
    summary.setdefault("fps", float(fps))
    out_dir = Path(out_dir)
    with atomic_path(out_dir) as tmp:
        tmp = Path(tmp)
        tmp.mkdir()
        (tmp / "joints.csv").write_text(format_points_csv(joints, JOINT_NAMES, "joint"))
        with open(tmp / "poses.npz", "wb") as f:
            np.savez(f, poses=poses, pose_names=np.array(list(pose_names)),
                     joint_names=np.array(list(body.joint_names)),
                     body_height=np.float64(body.height), body_offsets=np.asarray(body.offsets, float),
                     fps=np.float64(fps))
        # A BVH has no "unknown": frames without a pose repeat the last known one.
        filled = hold_last_pose(poses)
        if filled is not None:
            write_bvh(tmp / "track.bvh", body, filled, fps)
        (tmp / "summary.json").write_text(summary_json_text(summary))
        if hasattr(body, "to_json"):
            (tmp / "body.json").write_text(body.to_json())
    return out_dir


def summary_json_text(summary: dict) -> str:
    """The text of ``summary.json`` for ``summary`` (numpy values and paths converted)."""
    return json.dumps(summary, indent=1, default=_json_default) + "\n"


def hold_last_pose(poses):
    """Poses with every unknown (non-finite) row replaced by the last known one.

    Leading unknown rows take the first known pose. Used wherever a format has no
    "unknown" (BVH, glTF animations).

    Parameters
    ----------
    poses : (F, D) float

    Returns
    -------
    (F, D) float64, or None when no row is known.
    """
    poses = np.asarray(poses, dtype=float)
    finite = np.all(np.isfinite(poses), axis=1)
    if not finite.any():
        return None
    known = np.where(finite, np.arange(len(poses)), -1)
    last = np.maximum.accumulate(known)
    last[last < 0] = int(np.argmax(finite))
    return poses[last].copy()


def _json_default(value):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"{type(value).__name__} is not JSON serialisable")


def read_track(out_dir) -> Track:
    """Read a directory written by :func:`write_track`.

    Raises
    ------
    InputError
        A missing or malformed file.
    """
    out_dir = Path(out_dir)
    if not out_dir.is_dir():
        raise InputError(out_dir, "no such track directory")
    npz_path = out_dir / "poses.npz"
    try:
        with np.load(npz_path, allow_pickle=False) as data:
            poses = data["poses"].astype(float)
            pose_names = [str(n) for n in data["pose_names"]]
            joint_names = [str(n) for n in data["joint_names"]]
            body_height = float(data["body_height"])
            body_offsets = data["body_offsets"].astype(float)
            fps = float(data["fps"])
    except FileNotFoundError:
        raise InputError(npz_path, "missing poses.npz") from None
    except (KeyError, ValueError, OSError, TypeError, zipfile.BadZipFile) as exc:
        raise InputError(npz_path, f"not a track poses file ({exc})") from None
    if poses.ndim != 2 or not (math.isfinite(fps) and fps > 0):
        raise InputError(npz_path, f"not a track poses file (poses {poses.shape}, fps {fps})")
    summary_path = out_dir / "summary.json"
    try:
        summary = json.loads(summary_path.read_text())
    except FileNotFoundError:
        raise InputError(summary_path, "missing summary.json") from None
    except json.JSONDecodeError as exc:
        raise InputError(summary_path, f"invalid JSON (line {exc.lineno}: {exc.msg})") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(summary_path, f"cannot read ({getattr(exc, 'strerror', None) or exc})") from None
    if not isinstance(summary, dict):
        raise InputError(summary_path, f"must hold a JSON object, not {type(summary).__name__}")
    joints_path = out_dir / "joints.csv"
    if not joints_path.is_file():
        raise InputError(joints_path, "missing joints.csv")
    joints, _ = read_points_csv(joints_path, len(poses), "joint", JOINT_NAMES)
    return Track(joints=joints, poses=poses, pose_names=pose_names, joint_names=joint_names,
                 body_height=body_height, body_offsets=body_offsets, fps=fps, summary=summary)
