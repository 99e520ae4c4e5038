"""Per-frame JSON of the contract joints (``joints.json``)::

    {"format": "depthtrack-joints/1", "fps": 25.0, "units": "m",
     "axes": "camera: x right, y down, z forward (OpenCV)",
     "joint_names": ["head", ...],
     "frames": [{"frame": 0, "time": 0.0, "joints": {"head": [x, y, z], ...}}, ...]}

One object per frame, in order; a joint the track does not know is ``null``. Coordinates
are those of ``joints.csv`` (the camera frame, metres), so the two files agree.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..contract import JOINT_NAMES
from ..io.atomic import write_text_atomic

JOINTS_JSON_FORMAT = "depthtrack-joints/1"


def joints_document(joints, fps: float) -> dict:
    """The JSON document (a dict) for ``joints (F, 15, 3)`` at ``fps``."""
    joints = np.asarray(joints, float)
    frames = []
    for f, frame in enumerate(joints):
        known = np.all(np.isfinite(frame), axis=-1)
        frames.append({"frame": f, "time": round(f / float(fps), 9),
                       "joints": {name: ([round(float(v), 6) for v in frame[k]] if known[k] else None)
                                  for k, name in enumerate(JOINT_NAMES)}})
    return {"format": JOINTS_JSON_FORMAT, "fps": float(fps), "units": "m",
            "axes": "camera: x right, y down, z forward (OpenCV)",
            "joint_names": list(JOINT_NAMES), "frames": frames}


def write_joints_json(path, joints, fps: float) -> Path:
    """Write :func:`joints_document` to ``path`` atomically."""
    write_text_atomic(path, json.dumps(joints_document(joints, fps), separators=(",", ":")) + "\n")
    return Path(path)
