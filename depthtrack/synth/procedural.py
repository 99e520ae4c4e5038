"""Built-in parametric motions as pose sequences of our body model (no outside data).

Each motion is a smooth function of time written directly in pose parameters (model
frame: left = +x, up = -y, facing -z; sign conventions in
:mod:`depthtrack.body.skeleton`). The pelvis starts at the origin; its height is
set every frame so that the lower ankle stays at its rest height ("foot lock"), so
squats go down rather than lifting the feet.

* ``wave``  -- both arms raised sideways and waved overhead, elbows bending.
* ``squat`` -- knee bends to about 100 degrees with the arms reaching forward.
* ``turn``  -- a full turn on the spot with a little arm swing.
* ``mixed`` -- a wave, a squat and a half turn one after another.
"""
from __future__ import annotations

import numpy as np

#: Names accepted by :func:`procedural_motion`, with their default durations (s).
PROCEDURAL_MOTIONS = {"wave": 4.0, "squat": 4.0, "turn": 4.0, "mixed": 8.0}


def _smooth(x):
    """Smoothstep of ``x`` clipped to [0, 1]: 0 -> 0, 1 -> 1, zero slope at both ends."""
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


class _Poses:
    """(F, D) pose array with access by parameter name."""

    def __init__(self, body, n):
        self.index = {name: i for i, name in enumerate(body.pose_names)}
        self.p = np.zeros((n, body.dof))

    def set(self, name, values, mask=None):
        i = self.index[name]
        if mask is None:
            self.p[:, i] = values
        else:
            self.p[mask, i] = np.broadcast_to(values, self.p.shape[:1])[mask]

    def add(self, name, values):
        self.p[:, self.index[name]] += values


def _wave(P, t, T):
    # Raise (1 s), wave (until T - 1), lower (last 1 s).
    up = _smooth(t / 1.0) * _smooth((T - t) / 1.0)
    wave = np.sin(2 * np.pi * 1.2 * t)
    P.add("l_shoulder_rz", -np.radians(130) * up)     # left arm up sideways (rz < 0)
    P.add("r_shoulder_rz", np.radians(130) * up)
    P.add("l_elbow_rz", -np.radians(35) * up * (0.5 + 0.5 * wave))
    P.add("r_elbow_rz", np.radians(35) * up * (0.5 - 0.5 * wave))
    P.add("neck_rx", np.radians(-10) * up)             # look up a little


def _squat(P, t, T):
    period = T / 2.0                                   # two squats
    depth = 0.5 - 0.5 * np.cos(2 * np.pi * np.clip(t, 0, T) / period)
    P.add("l_hip_rx", -np.radians(95) * depth)         # thighs forward
    P.add("r_hip_rx", -np.radians(95) * depth)
    P.add("l_knee_rx", np.radians(110) * depth)        # shanks back
    P.add("r_knee_rx", np.radians(110) * depth)
    P.add("l_ankle_rx", -np.radians(25) * depth)
    P.add("r_ankle_rx", -np.radians(25) * depth)
    P.add("spine_rx", np.radians(30) * depth)          # lean forward for balance
    P.add("l_shoulder_rx", -np.radians(80) * depth)    # arms reach forward
    P.add("r_shoulder_rx", -np.radians(80) * depth)


def _turn(P, t, T, turns=1.0):
    yaw = 2 * np.pi * turns * _smooth(t / T)
    P.add("pelvis_ry", yaw)
    swing = np.sin(2 * np.pi * 1.0 * t) * np.radians(15)
    P.add("l_shoulder_rx", swing)
    P.add("r_shoulder_rx", -swing)
    P.add("l_elbow_rx", -np.radians(20) * np.ones_like(t))
    P.add("r_elbow_rx", -np.radians(20) * np.ones_like(t))


def procedural_motion(name: str, body, fps: float = 25.0, seconds=None) -> np.ndarray:
    """Pose sequence of a built-in motion.

    Parameters
    ----------
    name : {"wave", "squat", "turn", "mixed"}
    body : BodyModel
        Sets the pose layout and the leg lengths for the foot lock.
    fps : float
    seconds : float or None
        Duration; ``None`` = :data:`PROCEDURAL_MOTIONS` default.

    Returns
    -------
    poses : (F, 48) float
        Model frame, pelvis starting at the origin, facing -z.
    """
    if name not in PROCEDURAL_MOTIONS:
        raise ValueError(f"unknown procedural motion {name!r}; known: {', '.join(PROCEDURAL_MOTIONS)}")
    T = float(PROCEDURAL_MOTIONS[name] if seconds is None else seconds)
    n = max(2, int(round(T * fps)))
    t = np.arange(n) / fps
    P = _Poses(body, n)
    if name == "wave":
        _wave(P, t, T)
    elif name == "squat":
        _squat(P, t, T)
    elif name == "turn":
        _turn(P, t, T)
    else:
        third = T / 3.0
        for k, part in enumerate((_wave, _squat, lambda P_, t_, T_: _turn(P_, t_, T_, 0.5))):
            local = np.clip(t - k * third, 0.0, third)
            sub = _Poses(body, n)
            part(sub, local, third)
            if k == 2:      # the half turn stays turned
                P.p += sub.p
            else:           # waves and squats return to rest at the end of their third
                active = (t >= k * third) & (t < (k + 1) * third)
                P.p[active] += sub.p[active]
    # Gentle breathing-like sway so no two frames are identical.
    P.add("spine_rz", np.radians(2.0) * np.sin(2 * np.pi * 0.3 * t))
    return foot_lock(body, P.p)


def foot_lock(body, poses) -> np.ndarray:
    """Shift the pelvis vertically so the lower ankle is at its rest height every frame.

    Parameters
    ----------
    poses : (F, D) float
        Model frame (y down).

    Returns
    -------
    (F, D) float
    """
    poses = np.array(poses, dtype=float)
    names = list(body.joint_names)
    ankles = [names.index("l_ankle"), names.index("r_ankle")]
    rest_y = np.asarray(body.world_transforms(np.zeros(body.dof)))[ankles, 1, 3].max()
    posed = np.asarray(body.world_transforms(poses))[:, ankles, 1, 3].max(axis=1)
    poses[:, 1] += rest_y - posed
    return poses
