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

Motions for the held-out benchmark (``tools/benchmark.py``), the ground under the
lowest point of the body every frame (so a body lying down rests on the floor):

* ``spin-slow``, ``spin``, ``spin-fast`` -- turning in place: one turn in 4 s, two
  turns at one per 2 s, three turns at one per second (stepping arms and a bent knee);
* ``bend``       -- bending over at the hips to a flat back and up again, twice;
* ``squat-deep`` -- two deep squats with the arms held overhead;
* ``lie-down``   -- kneeling down, lying on the back, getting up again;
* ``lie-front``  -- kneeling down, lying on the front with the arms stretched past the head,
  getting up again;
* ``overhead``   -- arms raised forward to overhead, a side bend each way, lowered;
* ``sidestep``   -- walking sideways to the subject's left, then back;
* ``walk-back``  -- walking backwards, away from where it faces.
* ``cartwheel``  -- arms raised to a star, two cartwheels to the subject's left (a full
  turn about the forward axis each, upside down halfway), the arms lowered again.

Which of them may be used for what (:data:`PROCEDURAL_SPLIT`, the same rule as the
mocap clips in ``depthtrack/data/motion_split.json``): train -- fit priors and
classifiers (the part classifier is trained on wave, squat, turn and mixed); dev --
tune settings; test -- report only.

==========  =====================================================
train       wave, squat, turn, mixed, spin-slow
dev         spin-fast, bend, overhead, walk-back, cartwheel, lie-front
test        spin, squat-deep, lie-down, sidestep
==========  =====================================================
"""
from __future__ import annotations

import numpy as np

#: Names accepted by :func:`procedural_motion`, with their default durations (s).
PROCEDURAL_MOTIONS = {"wave": 4.0, "squat": 4.0, "turn": 4.0, "mixed": 8.0,
                      "spin-slow": 4.0, "spin": 4.0, "spin-fast": 3.0, "bend": 6.0, "squat-deep": 5.0,
                      "lie-down": 10.0, "lie-front": 10.0, "overhead": 6.0, "sidestep": 6.0,
                      "walk-back": 5.0, "cartwheel": 6.0}

#: Train / dev / test assignment of the procedural motions (see the module docstring).
PROCEDURAL_SPLIT = {
    "train": ["wave", "squat", "turn", "mixed", "spin-slow"],
    "dev": ["spin-fast", "bend", "overhead", "walk-back", "cartwheel", "lie-front"],
    "test": ["spin", "squat-deep", "lie-down", "sidestep"],
}


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


def _spin(P, t, T, turns, period):
    """``turns`` turns in place, ``period`` s each, starting and ending at rest."""
    ramp = min(0.5, 0.25 * T)
    speed = _smooth(t / ramp) * _smooth((T - t) / ramp)              # 0 -> 1 -> 0
    yaw = np.cumsum(speed) * (t[1] - t[0] if len(t) > 1 else 0.0)
    yaw *= 2 * np.pi * turns / max(yaw[-1], 1e-9)
    P.add("pelvis_ry", yaw)
    step = np.sin(2 * np.pi * t / (0.5 * period)) * speed            # alternate the feet
    P.add("l_hip_rx", -np.radians(20) * np.clip(step, 0, None))
    P.add("l_knee_rx", np.radians(35) * np.clip(step, 0, None))
    P.add("r_hip_rx", -np.radians(20) * np.clip(-step, 0, None))
    P.add("r_knee_rx", np.radians(35) * np.clip(-step, 0, None))
    P.add("l_shoulder_rz", -np.radians(30) * speed)                  # arms out for balance
    P.add("r_shoulder_rz", np.radians(30) * speed)
    P.add("l_elbow_rx", -np.radians(40) * np.ones_like(t))
    P.add("r_elbow_rx", -np.radians(40) * np.ones_like(t))


def _bend(P, t, T):
    depth = 0.5 - 0.5 * np.cos(2 * np.pi * t / (T / 2.0))            # two bends
    a = np.radians(85) * depth
    P.add("pelvis_rx", a)                                              # the trunk goes forward ...
    P.add("l_hip_rx", -a)                                              # ... the legs stay upright
    P.add("r_hip_rx", -a)
    P.add("spine_rx", np.radians(15) * depth)
    P.add("neck_rx", -np.radians(20) * depth)                          # look ahead a little
    P.add("l_shoulder_rx", -a)                                         # arms hang toward the floor
    P.add("r_shoulder_rx", -a)


def _squat_deep(P, t, T):
    depth = 0.5 - 0.5 * np.cos(2 * np.pi * t / (T / 2.0))
    P.add("l_hip_rx", -np.radians(115) * depth)
    P.add("r_hip_rx", -np.radians(115) * depth)
    P.add("l_knee_rx", np.radians(135) * depth)
    P.add("r_knee_rx", np.radians(135) * depth)
    P.add("l_ankle_rx", -np.radians(30) * depth)
    P.add("r_ankle_rx", -np.radians(30) * depth)
    P.add("spine_rx", np.radians(25) * depth)
    up = _smooth(t / 1.2) * _smooth((T - t) / 1.2)
    P.add("l_shoulder_rx", -np.radians(165) * up)                      # arms overhead throughout
    P.add("r_shoulder_rx", -np.radians(165) * up)


def _lying(t, T):
    """The lying motions' phases: ``(down, knees)``, each ``(F,)``. ``down`` is 0 standing
    and 1 lying: 0-15 % stand, 15-40 % go down, 40-60 % lie, 60-85 % get up, stand;
    ``knees`` peaks on the way down and up, and is 0 standing and lying."""
    down = _smooth((t / T - 0.15) / 0.25) * _smooth((0.85 - t / T) / 0.25)
    return down, np.sin(np.pi * down)


def _lie_down(P, t, T):
    # down onto the back, the knees bent on the way and straight lying
    down, knees = _lying(t, T)
    P.add("pelvis_rx", -np.radians(90) * down)                         # on the back, face up
    P.add("l_hip_rx", -np.radians(100) * knees)
    P.add("r_hip_rx", -np.radians(100) * knees)
    P.add("l_knee_rx", np.radians(120) * knees)
    P.add("r_knee_rx", np.radians(120) * knees)
    P.add("spine_rx", np.radians(40) * knees)                          # curled while sitting
    P.add("l_shoulder_rx", -np.radians(60) * knees)                    # arms reach forward to balance
    P.add("r_shoulder_rx", -np.radians(60) * knees)
    P.add("l_shoulder_rz", -np.radians(20) * down)                     # and lie beside the body
    P.add("r_shoulder_rz", np.radians(20) * down)


def _lie_front(P, t, T):
    # kneel and go down onto the front, lie with the arms stretched past the head, get up.
    # Dev's lying body (lie-down, on the back, is test).
    down, knees = _lying(t, T)
    P.add("pelvis_rx", np.radians(90) * down)                          # on the front, face down
    P.add("l_hip_rx", -np.radians(80) * knees)
    P.add("r_hip_rx", -np.radians(80) * knees)
    P.add("l_knee_rx", np.radians(100) * knees)
    P.add("r_knee_rx", np.radians(100) * knees)
    reach = np.radians(60) * knees + np.radians(170) * down ** 3      # to the floor, then past the head
    P.add("l_shoulder_rx", -reach)
    P.add("r_shoulder_rx", -reach)


def _overhead(P, t, T):
    up = _smooth(t / 1.2) * _smooth((T - t) / 1.2)
    P.add("l_shoulder_rx", -np.radians(170) * up)
    P.add("r_shoulder_rx", -np.radians(170) * up)
    P.add("l_elbow_rx", -np.radians(15) * up)
    P.add("r_elbow_rx", -np.radians(15) * up)
    side = np.sin(2 * np.pi * np.clip(t - 1.2, 0, None) / max(T - 2.4, 1e-6)) * up
    P.add("spine_rz", np.radians(25) * side)                           # lean left, then right
    P.add("neck_rx", -np.radians(15) * up)


def _walk(P, t, T, direction, speed=0.45):
    """Steps in ``direction`` ("left" or "back") at ``speed`` m/s, there and back."""
    half = T / 2.0
    phase = 2 * np.pi * t / 1.0                                        # one stride per second
    gait = _smooth(t / 0.5) * _smooth((T - t) / 0.5)
    sign = 1.0 - 2.0 * _smooth((t - half + 0.5) / 1.0)                # reverse over 1 s midway
    dt = t[1] - t[0] if len(t) > 1 else 0.0
    dist = np.cumsum(speed * sign * gait) * dt
    s, c = np.sin(phase) * gait, np.cos(phase) * gait
    lift_l, lift_r = np.clip(s, 0, None), np.clip(-s, 0, None)
    P.add("l_knee_rx", np.radians(40) * lift_l)
    P.add("r_knee_rx", np.radians(40) * lift_r)
    P.add("l_hip_rx", -np.radians(15) * lift_l)
    P.add("r_hip_rx", -np.radians(15) * lift_r)
    if direction == "left":
        P.add("pelvis_tx", dist)                                       # the subject's left is +x
        P.add("l_hip_rz", -np.radians(14) * c * sign)                  # legs open and close
        P.add("r_hip_rz", -np.radians(14) * c * sign)
        P.add("l_shoulder_rz", -np.radians(10) * gait)
        P.add("r_shoulder_rz", np.radians(10) * gait)
    else:
        P.add("pelvis_tz", dist)                                       # it faces -z: backwards is +z
        P.add("l_hip_rx", np.radians(20) * c * sign)                   # swing legs back in turn
        P.add("r_hip_rx", -np.radians(20) * c * sign)
        P.add("l_shoulder_rx", -np.radians(15) * c * sign)
        P.add("r_shoulder_rx", np.radians(15) * c * sign)


def _cartwheel(P, t, T, wheels=2, turn_time=1.3, stride=1.5):
    """Star pose, then ``wheels`` cartwheels to the subject's left, ``turn_time`` s each,
    ``stride`` m of travel per turn, a pause of a third of a turn between them."""
    star = _smooth(t / 0.8) * _smooth((T - t) / 0.8)
    P.add("l_shoulder_rz", -np.radians(150) * star)   # arms up sideways (left arm: rz < 0)
    P.add("r_shoulder_rz", np.radians(150) * star)
    P.add("l_hip_rz", -np.radians(30) * star)          # legs apart (left leg: rz < 0)
    P.add("r_hip_rz", np.radians(30) * star)
    gap = turn_time / 3.0
    start = 0.5 * (T - wheels * turn_time - (wheels - 1) * gap)
    turns = np.zeros_like(t)
    for k in range(wheels):
        t0 = start + k * (turn_time + gap)
        # the wheel speeds up into the hands and slows onto the feet, like a person's
        x = np.clip((t - t0) / turn_time, 0.0, 1.0)
        turns += x - np.sin(2 * np.pi * x) / (2 * np.pi) * 0.5
    P.add("pelvis_rz", 2 * np.pi * turns)              # the head goes to the left (+x) first
    P.add("pelvis_tx", stride * turns)
    P.add("spine_rx", np.radians(10) * np.sin(np.pi * (turns % 1.0)))   # a slight pike


_BENCHMARK_MOTIONS = {
    "spin-slow": lambda P, t, T: _spin(P, t, T, 1.0, 4.0),
    "spin": lambda P, t, T: _spin(P, t, T, 2.0, 2.0),
    "spin-fast": lambda P, t, T: _spin(P, t, T, 3.0, 1.0),
    "bend": _bend, "squat-deep": _squat_deep, "lie-down": _lie_down, "lie-front": _lie_front,
    "overhead": _overhead,
    "sidestep": lambda P, t, T: _walk(P, t, T, "left"),
    "walk-back": lambda P, t, T: _walk(P, t, T, "back"),
    "cartwheel": _cartwheel,
}


def procedural_motion(name: str, body, fps: float = 25.0, seconds=None) -> np.ndarray:
    """Pose sequence of a built-in motion.

    Parameters
    ----------
    name : str
        A key of :data:`PROCEDURAL_MOTIONS`.
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
    if name in _BENCHMARK_MOTIONS:
        _BENCHMARK_MOTIONS[name](P, t, T)
        P.add("spine_rz", np.radians(2.0) * np.sin(2 * np.pi * 0.3 * t))
        return ground_lock(body, P.p)
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


def ground_lock(body, poses) -> np.ndarray:
    """Shift the pelvis vertically so the lowest point of the body is where the soles are at rest.

    Like :func:`foot_lock`, but for motions where something other than a foot touches
    the floor (lying, kneeling): the lowest mesh vertex of every frame goes to the
    height of the lowest vertex at rest.

    Parameters
    ----------
    poses : (F, D) float
        Model frame (y down).

    Returns
    -------
    (F, D) float
    """
    poses = np.array(poses, dtype=float)
    rest = np.asarray(body.posed_vertices(np.zeros((1, body.dof))))[0, :, 1].max()
    for s in range(0, len(poses), 128):
        lowest = np.asarray(body.posed_vertices(poses[s:s + 128]))[..., 1].max(axis=1)
        poses[s:s + 128, 1] += rest - lowest
    return poses
