"""Stroke cycles: segmentation, resampling to a common length, smoothing (thesis 2.2, 2.7).

A cycle starts at the stroke's distinctive pose (thesis Figure 2.6). For back
stroke and freestyle that is the upper arm pointing straight up out of the
water: the zenith angle of the shoulder->elbow segment reaches a local minimum
near zero. :func:`detect_cycle_starts` finds those minima; a manual list of
start frames overrides it. For breast stroke, butterfly or any other periodic
motion (``stroke="auto"``) nothing about the stroke is assumed: the period comes
from the autocorrelation of the whole angle vector and the cycles start at the
returns to one distinctive (extreme) pose (:func:`periodic_cycle_starts`).

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
    """Cycle starts: where the upper arm points straight up (back stroke, freestyle), else by periodicity.

    Breast stroke, butterfly and ``auto`` (any periodic motion) use
    :func:`periodic_cycle_starts`, which assumes nothing about the stroke.

    Parameters
    ----------
    joints : (F, 14, 3) float
        Pool frame, y up.
    fps : float
    stroke : str
        ``back``, ``freestyle`` (distinctive pose), ``breast``, ``butterfly`` or ``auto`` (periodicity).
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
    if stroke not in STROKES + ("auto",):
        raise InputError(None, f"unknown stroke {stroke!r} (choose from {', '.join(STROKES + ('auto',))})")
    if stroke not in ("back", "freestyle"):
        return periodic_cycle_starts(joints_to_angles(joints), fps, min_period_s=min_period_s)
    zenith = upper_arm_zenith(joints, side)
    distance = max(1, int(round(min_period_s * fps)))
    peaks, _ = signal.find_peaks(-zenith, height=-np.radians(max_zenith_deg), distance=distance)
    return peaks.astype(int)


def stroke_period(angles, fps: float, min_period_s: float = 0.8, max_period_s: float = 5.0):
    """Cycle length in frames of a periodic angle trajectory, by autocorrelation.

    The angles ``(F, A)`` are embedded as ``(cos, sin)`` (so wrapping does not
    matter), centred, and the autocorrelation of the whole vector,
    ``r(tau) = sum_t <x_t, x_{t+tau}> / sum_t |x_t|^2`` (FFT, normalised by the
    overlap), is searched for peaks between the period bounds; the period is the
    first peak within 90 % of the highest one (so a multiple of the period does
    not win by noise).

    Returns
    -------
    period : int (frames), strength : float (r at the period, 1 = perfectly periodic)
    """
    a = np.asarray(angles, dtype=float)
    x = np.concatenate([np.cos(a), np.sin(a)], axis=1)
    x = x - x.mean(axis=0)
    n = len(x)
    lo = max(1, int(round(min_period_s * fps)))
    hi = min(n - 2, int(round(max_period_s * fps)))
    if hi <= lo + 1:
        raise InputError(None, f"{n} frames are too few to find a cycle of at least {min_period_s} s")
    size = 1 << int(np.ceil(np.log2(2 * n)))
    spec = np.fft.rfft(x, size, axis=0)
    r = np.fft.irfft((spec * spec.conj()).real.sum(axis=1), size)[:n]
    r = r / (n - np.arange(n)) / (r[0] / n)
    peaks, _ = signal.find_peaks(r[lo:hi + 1])
    if len(peaks) == 0:
        raise InputError(None, "no periodic motion found (no autocorrelation peak between "
                               f"{min_period_s} and {max_period_s} s)")
    peaks = peaks + lo
    best = r[peaks].max()
    period = int(peaks[np.flatnonzero(r[peaks] >= 0.9 * best)[0]])
    return period, float(r[period])


def periodic_cycle_starts(angles, fps: float, min_period_s: float = 0.8, max_period_s: float = 5.0):
    """Cycle starts of any periodic motion (no stroke assumed): the returns to one distinctive pose.

    The period P comes from :func:`stroke_period`. The distinctive pose is the
    frame, among the middle period of the take, farthest from the take's mean pose
    (an extreme of the stroke: returns to it are sharp minima of the distance);
    the starts are the local minima of the distance to it at least 0.6 P apart
    and closer than the median distance (frames where the swimmer does something
    else do not count).

    Parameters
    ----------
    angles : (F, A) float
    fps : float

    Returns
    -------
    (K,) int, increasing.
    """
    a = np.asarray(angles, dtype=float)
    period, _ = stroke_period(a, fps, min_period_s, max_period_s)
    x = np.concatenate([np.cos(a), np.sin(a)], axis=1)
    mid = len(x) // 2
    span = np.arange(max(0, mid - period // 2), min(len(x), mid + period // 2 + 1))
    far = span[np.argmax(np.sum((x[span] - x.mean(axis=0)) ** 2, axis=1))]
    d = np.sum((x - x[far]) ** 2, axis=1)
    peaks, _ = signal.find_peaks(-d, distance=max(1, int(0.6 * period)), height=-np.median(d))
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
                          last_frame: int | None = None, margin: int = 12, starts_other=None, exclude=None):
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
    exclude : (int, int), optional
        Frames ``[first, stop)`` no training cycle may overlap (a test window).

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
        pairs = [(int(s), int(e)) for s, e in zip(st[:-1], st[1:])]
        if last_frame is not None:
            pairs = [(s, e) for s, e in pairs if e <= last_frame]
        if exclude is not None:
            pairs = [(s, e) for s, e in pairs if e <= exclude[0] or s >= exclude[1]]
        for s, e in pairs:
            cyc = smooth_cycles(resample_cycles(ang, [s, e], length, margin), smooth_sigma)
            extended.extend(cyc)
            sources.append((s, e, sd))
    if not extended:
        raise InputError(None, "no complete stroke cycle found for training")
    # Each cycle keeps its own continuous representation; the motion model maps them
    # onto one branch after differentiating (see CyclicMotionModel.train).
    return TrainingCycles(np.array(extended), margin, sources)


__all__ = ["ANGLE_NAMES", "STROKES", "TrainingCycles", "build_training_cycles", "cycle_phase",
           "detect_cycle_starts", "periodic_cycle_starts", "stroke_period", "mirror_angles", "resample_cycles",
           "smooth_cycles", "upper_arm_zenith"]
