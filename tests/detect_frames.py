"""Shared synthetic frames for the detect tests (rendered once per test session)."""
from __future__ import annotations

from functools import lru_cache

import numpy as np


@lru_cache(maxsize=None)
def body():
    from depthtrack.body import BodyModel

    return BodyModel.default()


@lru_cache(maxsize=None)
def camera():
    from depthtrack.camera import Camera

    return Camera.preset("sr4000")


def pose(**angles):
    """Zero (A-)pose with some rotation-vector components set by name, e.g. l_shoulder_rz=-0.6."""
    b = body()
    p = np.zeros(b.dof)
    index = {n: i for i, n in enumerate(b.pose_names)}
    for name, value in angles.items():
        p[index[name]] = value
    return p


#: Named test poses (world frame).
POSES = {
    "a_pose": {},
    "t_pose": {"l_shoulder_rz": -0.65, "r_shoulder_rz": 0.65},
    "reach": {"l_shoulder_rz": -0.6, "l_shoulder_ry": 0.5, "r_shoulder_rz": 0.3, "r_elbow_rz": 0.6,
              "spine_ry": 0.3, "l_hip_rx": -0.3},
}


@lru_cache(maxsize=None)
def frame(name, noisy=False, roll_deg=0.0, seed=0):
    """SceneFrame of a named pose in a room (floor + back wall), SR4000 camera."""
    from depthtrack.synth.part_scenes import render_scene_frames
    from depthtrack.synth.noise import ToFNoise

    noise = ToFNoise.for_camera("sr4000") if noisy else None
    return render_scene_frames(body(), pose(**POSES[name])[None], camera(), noise=noise,
                               rng=np.random.default_rng(seed), roll_deg=roll_deg)[0]
