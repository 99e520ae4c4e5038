"""Occlusion gaps: measurements withheld for stretches of frames, the baselines, and errors in and after gaps.

A swimmer's limbs vanish under water, in the splash or behind the body; a
motion model is worth having if it predicts through such gaps. The schedule
(:func:`gap_mask`): gaps of ``K`` frames starting at test frame ``first``
(default 20) and then every ``K + spacing`` frames (default spacing 40: room to
pick up again and to measure that). The baselines, which know nothing of swimming:

* ``hold``: the last measurement before the gap;
* ``constant_velocity``: a straight line fitted (least squares) to the last
  ``window`` measurements before the gap (default 5; a two-point difference
  would double the noise), extrapolated;
* ``interpolation`` (offline, it sees the first measurement after the gap):
  linear between the last measurement before and the first after.

Outside the gaps every baseline is the measurement itself.
"""
from __future__ import annotations

import numpy as np

from ..filters.angles import wrap


def gap_mask(frames: int, length: int, first: int = 20, spacing: int = 40):
    """``(frames + 1,)`` bool: True where test frame t (0 .. frames) is withheld; frame 0 never is."""
    mask = np.zeros(frames + 1, bool)
    t = max(1, first)
    while t <= frames:
        mask[t:min(frames + 1, t + length)] = True
        t += length + spacing
    return mask


def gap_runs(mask):
    """``[(start, stop), ...]`` of the True runs of ``mask`` (stop exclusive)."""
    m = np.concatenate([[False], np.asarray(mask, bool), [False]])
    d = np.flatnonzero(np.diff(m.astype(int)))
    return list(zip(d[0::2], d[1::2]))


def withhold(z, mask):
    """Copy of ``z (T + 1, A)`` with the withheld rows set to NaN."""
    out = np.array(z, dtype=float)
    out[np.asarray(mask, bool)] = np.nan
    return out


def gap_baselines(z, mask, window: int = 5) -> dict:
    """The three baselines as ``(T + 1, A)`` estimates of every frame (see module docstring)."""
    z = np.asarray(z, dtype=float)
    mask = np.asarray(mask, bool)
    hold, cv, interp = z.copy(), z.copy(), z.copy()
    T = len(z)
    for a, b in gap_runs(mask):
        before = np.flatnonzero(~mask[:a])[-window:]
        last = z[before[-1]]
        hold[a:b] = last
        if len(before) >= 2:
            # unwrap the fitted stretch next to the last measurement, fit a line per angle
            pts = last + wrap(z[before] - last)
            tt = before - before.mean()
            slope = (tt[:, None] * (pts - pts.mean(axis=0))).sum(axis=0) / (tt ** 2).sum()
            line0 = pts.mean(axis=0) - slope * before.mean()
            cv[a:b] = line0 + slope * np.arange(a, b)[:, None]
        else:
            cv[a:b] = last
        if b < T:
            nxt = last + wrap(z[b] - last)
            u = (np.arange(a, b) - (a - 1)) / (b - (a - 1))
            interp[a:b] = (1 - u)[:, None] * last + u[:, None] * nxt
        else:
            interp[a:b] = last
    return {"hold": hold, "constant_velocity": cv, "interpolation": interp}


def after_mask(mask, after: int = 10):
    """``(T + 1,)`` bool: the ``after`` measured frames that follow each gap."""
    mask = np.asarray(mask, bool)
    out = np.zeros_like(mask)
    for _, b in gap_runs(mask):
        out[b:min(len(mask), b + after)] = True
    return out & ~mask


def gap_errors(sq, mask, phase, after: int = 10, bins: int = 4, joint=None) -> dict:
    """Errors inside and after the gaps, overall and per stroke phase.

    Parameters
    ----------
    sq : (T,) float
        Squared angle error of test frames 1 .. T.
    mask : (T + 1,) bool
        Withheld frames (frame 0 first).
    phase : (T,) float
        True cycle progress of frames 1 .. T (the phase bins are quarters of the cycle by default).
    joint : (T,) float, optional
        Mean joint-position error (m) of frames 1 .. T: adds ``inside_cm`` and ``after_cm``.

    Returns
    -------
    dict: ``inside``, ``after`` (mean error, rad^2 per frame), ``inside_per_phase``,
    ``after_per_phase`` (lists of ``bins``; None where a bin has no frame), ``frames_inside``,
    ``frames_after``.
    """
    sq = np.asarray(sq, dtype=float)
    inside = np.asarray(mask, bool)[1:]
    post = after_mask(mask, after)[1:]
    b = np.clip((np.mod(np.asarray(phase, float), 1.0) * bins).astype(int), 0, bins - 1)

    def mean(sel):
        return float(sq[sel].mean()) if sel.any() else None

    out = {"inside": mean(inside), "after": mean(post),
            "inside_per_phase": [mean(inside & (b == k)) for k in range(bins)],
            "after_per_phase": [mean(post & (b == k)) for k in range(bins)],
            "frames_inside": int(inside.sum()), "frames_after": int(post.sum())}
    if joint is not None:
        joint = 100 * np.asarray(joint, dtype=float)
        out["inside_cm"] = float(joint[inside].mean()) if inside.any() else None
        out["after_cm"] = float(joint[post].mean()) if post.any() else None
    return out
