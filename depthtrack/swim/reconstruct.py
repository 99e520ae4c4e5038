"""3D stick figures from 2D joint markings (thesis 2.4 to 2.6).

Conventions. A *side* view sees the pool's x (along the lane, image u to the
right) and y (up, image v downwards); its camera looks along +z, so a joint
"nearer to the camera" has the smaller z. A *top* view sees x (image u) and z
(image v); a *bottom* view sees x and -z. Image units are pixels, the scene is
in the units of the segment lengths (metres).

Single view (Taylor 2000, thesis 2.4.2): scaled orthographic projection
``(u, v) = s (X, -Y)``. With known segment lengths l, each segment's depth
difference is ``dZ = sqrt(l^2 - (du^2 + dv^2) / s^2)`` (eq. 2.6), its sign given
by a per-segment flag saying whether the child joint is nearer the camera. Real
depths need ``s >= sqrt(du^2 + dv^2) / l`` for every segment (eq. 2.7, the
printed form lost its square root); the smallest scale that satisfies all
segments of all frames is used (a fixed camera has one scale).

Two views (thesis 2.5.3): the scale between the views comes from the
pseudo-inverse ``s = (dx^T dx')/(dx^T dx)`` of one segment's extent along the
shared axis x in both views over all frames (eq. 2.11, 2.12: the torso); the
top view's second coordinate, divided by s, is the depth.

Missing body half (thesis 2.4.2): for breast stroke and butterfly the marked
half is mirrored across the body's plane of symmetry (z -> -z about the root in
a side view); for freestyle and back stroke the other half at frame f is the
mirrored marked half of frame ``f - T/2`` (T the cycle length from the
cycle-start frames; ``f + T/2`` early in the take), attached to the hip and
shoulder of frame f.
"""
from __future__ import annotations

import numpy as np

from ..errors import InputError
from .stickfigure import MIRROR_PAIRS, N_JOINTS, SWIM_INDEX, SWIM_JOINTS, SWIM_PARENTS

_OTHER = {}
for _l, _r in MIRROR_PAIRS:
    _OTHER[_l], _OTHER[_r] = _r, _l


def taylor_scale(uv, lengths, quantile: float = 1.0):
    """Smallest scale with real depths for every segment (eq. 2.7).

    Parameters
    ----------
    uv : (F, 14, 2) float
        Image coordinates (NaN where not marked).
    lengths : (13,) float
    quantile : float
        1 (the thesis): the maximum of ``|d| / l`` over all segments and frames.
        Marking noise only ever raises that maximum; a quantile below 1 (taken
        per segment over the frames, then the maximum over segments) trades a
        few clipped depths for a less inflated scale.

    Returns
    -------
    float
    """
    uv = np.asarray(uv, dtype=float)
    d = uv[:, 1:] - uv[:, SWIM_PARENTS[1:]]
    proj = np.hypot(d[..., 0], d[..., 1]) / np.asarray(lengths)[None]
    if not np.isfinite(proj).any():
        raise InputError(None, "no marked segment (a joint and its parent in the same frame)")
    if quantile >= 1.0:
        return float(np.nanmax(proj))
    per_segment = np.nanquantile(proj, quantile, axis=0)
    return float(np.nanmax(per_segment))


def taylor_depths(uv, lengths, nearer, scale):
    """Per-segment depth differences ``Z_child - Z_parent`` (eq. 2.6).

    Parameters
    ----------
    uv : (F, 14, 2) float
    lengths : (13,) float
    nearer : (F, 13) bool
        True where the child joint is nearer the camera (smaller z) than its parent.
    scale : float

    Returns
    -------
    (F, 13) float (NaN where a joint is missing)
    """
    d = uv[:, 1:] - uv[:, SWIM_PARENTS[1:]]
    planar = (d[..., 0] ** 2 + d[..., 1] ** 2) / scale ** 2
    dz = np.sqrt(np.clip(np.asarray(lengths)[None] ** 2 - planar, 0.0, None))
    return np.where(nearer, -dz, dz)


def reconstruct_single_view(uv, lengths, nearer, scale=None, quantile: float = 1.0):
    """Taylor's reconstruction of the marked joints of a side view.

    Parameters
    ----------
    uv : (F, 14, 2) float
        Pixels; NaN for unmarked joints. A joint is placed when its parent is.
    lengths : (13,) float
    nearer : (F, 13) bool
    scale : float, optional
        Pixels per length unit; default the lower bound of eq. 2.7 (see :func:`taylor_scale`).
    quantile : float
        Passed to :func:`taylor_scale`.

    Returns
    -------
    joints : (F, 14, 3) float
        Pool frame (x along the lane, y up, z depth), root at depth 0; NaN where unmarked.
    scale : float
    """
    uv = np.asarray(uv, dtype=float)
    if scale is None:
        scale = taylor_scale(uv, lengths, quantile)
    dz = taylor_depths(uv, lengths, nearer, scale)
    out = np.full(uv.shape[:2] + (3,), np.nan)
    out[:, :, 0] = uv[:, :, 0] / scale
    out[:, :, 1] = -uv[:, :, 1] / scale
    out[:, 0, 2] = 0.0
    for j in range(1, N_JOINTS):
        out[:, j, 2] = out[:, SWIM_PARENTS[j], 2] + dz[:, j - 1]
    out[~np.isfinite(uv).all(axis=-1)] = np.nan
    return out, float(scale)


def view_scale(extent_a, extent_b):
    """Least-squares factor s with ``extent_a * s ~ extent_b`` (pseudo-inverse, eq. 2.11-2.12).

    ``extent_a, extent_b : (F,)`` one segment's extent along the shared axis in each view.
    """
    a = np.asarray(extent_a, dtype=float)
    b = np.asarray(extent_b, dtype=float)
    ok = np.isfinite(a) & np.isfinite(b)
    if ok.sum() == 0 or np.dot(a[ok], a[ok]) == 0:
        raise InputError(None, "the scale segment is not marked in both views")
    phi = a[ok][:, None]
    return float((np.linalg.pinv(phi) @ b[ok])[0])


def reconstruct_two_views(side_uv, top_uv, lengths=None, view: str = "top", scale_segment=("hips", "neck")):
    """Combine a side view (x, y) with a top or bottom view (x, z).

    Parameters
    ----------
    side_uv, top_uv : (F, 14, 2) float
        Pixels, NaN where unmarked; the views must be synchronised (see :func:`sync_offset`).
    lengths : (13,) float, optional
        When given, the result is scaled to these units (least squares over all marked segments).
    view : str
        ``top`` or ``bottom``.
    scale_segment : (str, str)
        Segment visible in every frame of both views whose x extent fixes the view scale.

    Returns
    -------
    joints : (F, 14, 3) float, root at the origin.
    info : dict with ``view_scale`` (top pixels per side pixel) and ``unit_scale``.
    """
    side = np.asarray(side_uv, dtype=float)
    top = np.asarray(top_uv, dtype=float)
    a, b = SWIM_INDEX[scale_segment[0]], SWIM_INDEX[scale_segment[1]]
    s = view_scale(side[:, b, 0] - side[:, a, 0], top[:, b, 0] - top[:, a, 0])
    sign = 1.0 if view == "top" else -1.0
    root_side = side[:, :1]
    root_top = top[:, :1]
    joints = np.empty(side.shape[:2] + (3,))
    joints[..., 0] = side[..., 0] - root_side[..., 0]
    joints[..., 1] = -(side[..., 1] - root_side[..., 1])
    joints[..., 2] = sign * (top[..., 1] - root_top[..., 1]) / s
    unit = 1.0
    if lengths is not None:
        seg = np.linalg.norm(joints[:, 1:] - joints[:, SWIM_PARENTS[1:]], axis=-1)
        lengths = np.broadcast_to(np.asarray(lengths, float), seg.shape)
        ok = np.isfinite(seg)
        unit = float(np.dot(seg[ok], lengths[ok]) / np.dot(seg[ok], seg[ok]))
        joints *= unit
    return joints, {"view_scale": s, "unit_scale": unit}


def sync_offset(starts_a, starts_b) -> int:
    """Frames to add to recording a's frame numbers to reach b's (thesis 2.6):
    the difference of the first cycle-start frames."""
    if len(starts_a) == 0 or len(starts_b) == 0:
        raise InputError(None, "both recordings need a cycle-start frame to be synchronised")
    return int(starts_b[0]) - int(starts_a[0])


def join_above_below(below_uv, above_uv):
    """Join joints marked in an above-water camera to the below-water marking (thesis 2.4.2).

    For each frame the above-water points are translated so that the joints
    marked in both views coincide (mean offset of the common joints), then
    fill the joints only the above-water view saw.

    ``below_uv, above_uv : (F, 14, 2)`` with NaN where unmarked -> ``(F, 14, 2)``.
    """
    below = np.asarray(below_uv, dtype=float).copy()
    above = np.asarray(above_uv, dtype=float)
    common = np.isfinite(below).all(-1) & np.isfinite(above).all(-1)
    for f in range(len(below)):
        if not common[f].any():
            continue
        offset = (below[f, common[f]] - above[f, common[f]]).mean(axis=0)
        fill = ~np.isfinite(below[f]).all(-1) & np.isfinite(above[f]).all(-1)
        below[f, fill] = above[f, fill] + offset
    return below


def complete_other_half(joints, stroke: str, cycle_starts=None):
    """Fill the unmarked body half from the marked one (thesis 2.2, 2.4.2).

    Parameters
    ----------
    joints : (F, 14, 3) float
        NaN for the missing half's joints (side-view pool frame: the lateral axis is z).
    stroke : str
        ``breast``/``butterfly``: mirror in the same frame; ``back``/``freestyle``: mirror
        the marked half of half a cycle earlier (later near the start of the take).
    cycle_starts : (K,) int
        Needed for back stroke and freestyle (K >= 2).

    Returns
    -------
    (F, 14, 3) float
    """
    joints = np.asarray(joints, dtype=float).copy()
    F = len(joints)
    missing = ~np.isfinite(joints).all(-1)
    source_frame = np.arange(F)
    if stroke in ("back", "freestyle"):
        if cycle_starts is None or len(cycle_starts) < 2:
            raise InputError(None, f"{stroke}: the half-cycle shift needs at least two cycle-start frames")
        starts = np.asarray(cycle_starts, dtype=int)
        half = np.round(np.diff(starts).mean() / 2).astype(int)
        source_frame = np.where(np.arange(F) - half >= 0, np.arange(F) - half, np.arange(F) + half)
        source_frame = np.clip(source_frame, 0, F - 1)
    elif stroke not in ("breast", "butterfly"):
        raise InputError(None, f"unknown stroke {stroke!r}")
    src = joints.copy()
    for j in range(1, N_JOINTS):             # parents first, so attachments exist
        name = SWIM_JOINTS[j]
        if name not in _OTHER:
            continue
        twin = SWIM_INDEX[_OTHER[name]]
        p, tp = SWIM_PARENTS[j], SWIM_PARENTS[twin]
        todo = missing[:, j]
        if not todo.any():
            continue
        seg = src[source_frame, twin] - src[source_frame, tp]
        seg[:, 2] *= -1.0                    # mirror across the body's plane (side view: z)
        joints[todo, j] = joints[todo, p] + seg[todo]
    return joints
