"""Stroke cycles: segmentation, resampling to a common length, smoothing (thesis 2.2, 2.7).

A cycle starts at the stroke's distinctive pose (thesis Figure 2.6). For back
stroke and freestyle that is the upper arm pointing straight up out of the
water: the zenith angle of the shoulder->elbow segment reaches a local minimum
near zero. :func:`detect_cycle_starts` finds those minima; a manual list of
start frames overrides it (the only way for breast stroke and butterfly here).

Each angle of each cycle is resampled to ``length`` samples with a cubic spline
through the frames (thesis 2.7). The spline runs over the whole continuous
trajectory, so a cycle's resampled values see ``margin`` samples of context on
either side: the Gaussian smoothing and the derivative masks then need no
assumption about what lies beyond the cycle's ends, and are cropped afterwards.
"""
from __future__ import annotations

import numpy as np
from scipy import interpolate, ndimage, signal

from ..errors import InputError
from .stickfigure import ANGLE_NAMES, SEGMENTS, continue_angles, joints_to_angles

STROKES = ("back", "freestyle", "breast", "butterfly")


def upper_arm_zenith(joints, side: str = "right"):
    """``joints (F, 14, 3)`` -> ``(F,)`` zenith (rad) of the upper arm (0 = straight up)."""
    name = {"right": "r_elbow", "left": "l_elbow"}[side]
    j = SEGMENTS.index(name)
    return joints_to_angles(joints)[:, 2 * j]


def detect_cycle_starts(joints, fps: float, stroke: str = "back", side: str = "right",
                        max_zenith_deg: float = 45.0, min_period_s: float = 0.8):
    """Frames where the upper arm points straight up (back stroke, freestyle).

    Parameters
    ----------
    joints : (F, 14, 3) float
        Pool frame, y up.
    fps : float
    stroke : str
        ``back`` or ``freestyle``; the symmetric strokes need a manual list.
    side : str
        Arm whose up-pose starts a cycle.
    max_zenith_deg : float
        A minimum of the zenith counts only if below this.
    min_period_s : float
        Minima closer than this are merged (the lower one wins).

    Returns
    -------
    (K,) int, increasing.
    """
    if stroke not in ("back", "freestyle"):
        raise InputError(None, f"automatic cycle detection knows back stroke and freestyle, not {stroke!r}: "
                               "give the cycle-start frames")
    zenith = upper_arm_zenith(joints, side)
    distance = max(1, int(round(min_period_s * fps)))
    peaks, _ = signal.find_peaks(-zenith, height=-np.radians(max_zenith_deg), distance=distance)
    return peaks.astype(int)


def cycle_phase(n_frames: int, starts):
    """Cycle progress and speed of every frame from its cycle starts.

    Returns
    -------
    phase : (F,) float
        c in [0, 1) inside a known cycle, NaN outside.
    speed : (F,) float
        Cycles per frame (1 / cycle length), NaN outside.
    """
    starts = np.asarray(starts, dtype=int)
    phase = np.full(n_frames, np.nan)
    speed = np.full(n_frames, np.nan)
    for s, e in zip(starts[:-1], starts[1:]):
        f = np.arange(max(s, 0), min(e, n_frames))
        phase[f] = (f - s) / (e - s)
        speed[f] = 1.0 / (e - s)
    return phase, speed


def resample_cycles(angles, starts, length: int = 100, margin: int = 0):
    """Resample each cycle ``starts[i] .. starts[i+1]`` to ``length`` samples.

    Parameters
    ----------
    angles : (F, 26) float
        Continuous angles of consecutive frames (:func:`continue_angles`).
    starts : (K,) int
        Cycle-start frames; K - 1 cycles.
    length : int
        Samples per cycle; sample i sits at progress i / length.
    margin : int
        Extra samples before and after each cycle (same spacing), clamped to the take.

    Returns
    -------
    (K - 1, length + 2 margin, 26) float
    """
    angles = np.asarray(angles, dtype=float)
    starts = np.asarray(starts, dtype=int)
    spline = interpolate.CubicSpline(np.arange(len(angles)), angles, axis=0)
    out = []
    for s, e in zip(starts[:-1], starts[1:]):
        i = np.arange(-margin, length + margin)
        t = np.clip(s + i * (e - s) / length, 0, len(angles) - 1)
        out.append(spline(t))
    return np.array(out).reshape(-1, length + 2 * margin, angles.shape[1])


def smooth_cycles(cycles, sigma: float, axis: int = 1):
    """Gaussian smoothing of every angle along the time axis (``sigma`` in samples; 0 = none)."""
    if sigma <= 0:
        return np.asarray(cycles, dtype=float)
    return ndimage.gaussian_filter1d(np.asarray(cycles, dtype=float), sigma, axis=axis, mode="nearest")


def mirror_angles(angles, heading):
    """Reflect poses across the vertical plane through the body axis, swapping left and right.

    Parameters
    ----------
    angles : (..., 26) float
    heading : float or (...,) float
        Azimuth of the body axis (the plane of symmetry).

    Returns
    -------
    (..., 26) float
    """
    angles = np.asarray(angles, dtype=float)
    a = angles.reshape(angles.shape[:-1] + (13, 2))
    out = a.copy()
    out[..., 1] = 2 * np.asarray(heading)[..., None] - a[..., 1]
    swap = {n: SEGMENTS.index(n) for n in SEGMENTS}
    for name in SEGMENTS:
        if name.startswith("l_"):
            li, ri = swap[name], swap["r_" + name[2:]]
            out[..., [li, ri], :] = out[..., [ri, li], :]
    return out.reshape(angles.shape)


def torso_heading(angles):
    """Azimuth of the torso (hips -> neck) of ``angles (..., 26)``: ``(...,)``."""
    return np.asarray(angles)[..., 2 * SEGMENTS.index("neck") + 1]


class TrainingCycles:
    """Resampled, smoothed training cycles and where they came from.

    Attributes
    ----------
    cycles : (n, L, 26) float
        Angles per reference sample.
    extended : (n, L + 2 margin, 26) float
        The same with ``margin`` samples of context each side (for derivatives).
    margin : int
    sources : list of (int, int, str)
        (first frame, end frame, side) of each cycle in the take.
    """

    def __init__(self, extended, margin, sources):
        self.extended = np.asarray(extended, dtype=float)
        self.margin = int(margin)
        self.sources = list(sources)

    @property
    def cycles(self):
        m = self.margin
        return self.extended[:, m:self.extended.shape[1] - m]

    @property
    def length(self) -> int:
        return self.extended.shape[1] - 2 * self.margin

    def __len__(self):
        return len(self.extended)


def build_training_cycles(joints, fps: float, starts=None, length: int = 100, smooth_sigma: float = 2.0,
                          stroke: str = "back", side: str = "right", use_other_side: bool = True,
                          last_frame: int | None = None, margin: int = 12, starts_other=None):
    """Training cycles from a take (thesis 2.7), with the half-cycle symmetry as extra cycles.

    Parameters
    ----------
    joints : (F, 14, 3) float
    fps : float
    starts : (K,) int, optional
        Manual cycle-start frames (overrides detection).
    length : int
        Reference cycle length L.
    smooth_sigma : float
        Gaussian width in reference samples.
    stroke, side : str
    use_other_side : bool
        For back stroke and freestyle, also use the other arm's cycles, mirrored
        onto this side (thesis 2.2: the halves move alike, half a cycle apart).
    last_frame : int, optional
        Only cycles that end at or before this frame.
    margin : int
        Context samples kept each side.
    starts_other : (K,) int, optional
        Manual starts for the other side.

    Returns
    -------
    TrainingCycles
    """
    joints = np.asarray(joints, dtype=float)
    angles = continue_angles(joints_to_angles(joints))
    if starts is None:
        starts = detect_cycle_starts(joints, fps, stroke, side)
    elif len(starts) and not 0 <= min(starts) <= max(starts) < len(joints):
        raise InputError(None, f"cycle starts must be frames of the take (0 to {len(joints) - 1}), "
                               f"not {', '.join(map(str, starts))}")
    sets = [(np.asarray(starts, int), angles, side)]
    if use_other_side and stroke in ("back", "freestyle"):
        other = "left" if side == "right" else "right"
        if starts_other is None:
            starts_other = detect_cycle_starts(joints, fps, stroke, other)
        heading = np.angle(np.exp(1j * torso_heading(angles)).mean())
        mirrored = continue_angles(mirror_angles(angles, heading))
        sets.append((np.asarray(starts_other, int), mirrored, other))
    extended, sources = [], []
    for st, ang, sd in sets:
        if last_frame is not None:
            keep = st <= last_frame
            st = st[keep]
        if len(st) < 2:
            continue
        cyc = resample_cycles(ang, st, length, margin)
        cyc = smooth_cycles(cyc, smooth_sigma)
        extended.extend(cyc)
        sources.extend((int(s), int(e), sd) for s, e in zip(st[:-1], st[1:]))
    if not extended:
        raise InputError(None, "no complete stroke cycle found for training")
    # Each cycle keeps its own continuous representation; the motion model maps them
    # onto one branch after differentiating (see CyclicMotionModel.train).
    return TrainingCycles(np.array(extended), margin, sources)


__all__ = ["ANGLE_NAMES", "STROKES", "TrainingCycles", "build_training_cycles", "cycle_phase",
           "detect_cycle_starts", "mirror_angles", "resample_cycles", "smooth_cycles", "upper_arm_zenith"]
