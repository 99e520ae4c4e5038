"""The observation a candidate pose is scored against, and what the first frame tells.

Pure functions over numpy arrays: the ROI around the person, the depth image the
likelihood compares with (person pixels raw, background marked, open no-reading space
marked), the person's visible area, and the standing height guessed from a point cloud.
"""
from __future__ import annotations

import cv2
import numpy as np

from ..likelihood import BACKGROUND, NO_READING


def square_roi(mask, margin: float, min_size: int = 16):
    """Square ROI ``(u0, v0, size)`` around the True pixels of ``mask (H, W)``, or None if empty."""
    rows = np.flatnonzero(mask.any(axis=1))
    cols = np.flatnonzero(mask.any(axis=0))
    if len(rows) == 0:
        return None
    h = rows[-1] - rows[0] + 1
    w = cols[-1] - cols[0] + 1
    size = max(float(max(h, w)) * (1.0 + 2.0 * margin), float(min_size))
    cu = 0.5 * (cols[0] + cols[-1])
    cv = 0.5 * (rows[0] + rows[-1])
    return (cu - 0.5 * (size - 1), cv - 0.5 * (size - 1), size)


def visible_area(foreground, camera) -> float:
    """Surface area (m^2) a foreground's pixels cover: sum of ``z^2 / (fx fy)`` per pixel.

    Independent of the camera's resolution and of the distance: a whole adult seen from the
    front covers about 0.5 m^2, one entering at the image edge less.
    """
    points = np.asarray(foreground.points, dtype=np.float64).reshape(-1, 3)
    z = points[:, 2][points[:, 2] > 0]
    return float(np.sum(camera.pixel_area(z)))


def cut_by_border(mask, min_pixels: int = 3) -> bool:
    """Whether a person's foreground ``mask (H, W) bool`` runs off the image: at least
    ``min_pixels`` of it on the outermost rows and columns (a limb or half the body out of
    view; a stray pixel or two is not)."""
    mask = np.asarray(mask, dtype=bool)
    edge = (int(mask[0].sum()) + int(mask[-1].sum()) + int(mask[1:-1, 0].sum())
            + int(mask[1:-1, -1].sum()))
    return edge >= min_pixels


def out_of_range(depth, mask, clearance: int = 2, min_area: float = 0.005):
    """No-reading pixels that are open space rather than missing readings: ``(H, W) bool``.

    In the sensor model (:data:`depthtrack.likelihood.SENSOR_MODEL`) these pixels move from
    the "no reading" row (neutral) to the "background" row (a drawn model pays the silhouette
    cost): :func:`observation_image` writes them as ``BACKGROUND``.

    A ToF camera returns no reading both where the signal was lost on a surface (isolated
    dropouts, dark or grazing patches of the person) and where nothing lies within its
    range (the open background of a room deeper than the camera's range). The latter is
    evidence that no body is there; left neutral, a limb could hide in it for free. A
    no-reading pixel counts as open space when it lies more than ``clearance`` pixels from
    the segmented person ``mask (H, W) bool`` and belongs to a 4-connected no-reading
    region of at least ``min_area`` of the image (dropouts are specks, open space is not).
    """
    zero = ~(np.asarray(depth) > NO_READING)       # NaN too
    k = 2 * int(clearance) + 1
    away = cv2.dilate(np.asarray(mask, np.uint8), np.ones((k, k), np.uint8)) == 0
    candidates = (zero & away).astype(np.uint8)
    count, labels, stats, _ = cv2.connectedComponentsWithStats(candidates, connectivity=4)
    big = stats[:, cv2.CC_STAT_AREA] >= min_area * zero.size
    big[0] = False
    return big[labels]


def on_planes(points, planes, tolerance) -> np.ndarray:
    """Whether each point lies within ``tolerance`` of any of the planes.

    Parameters
    ----------
    points : (..., 3) float
    planes : (K, 4) float
        ``n . p + d = 0`` (``n`` need not be a unit vector).
    tolerance : (...) float or float
        Metres.

    Returns
    -------
    (...) bool
    """
    planes = np.asarray(planes, dtype=np.float64).reshape(-1, 4)
    off = np.abs(np.asarray(points) @ planes[:, :3].T + planes[:, 3])
    off /= np.linalg.norm(planes[:, :3], axis=1)
    return off.min(axis=-1) < tolerance


def observation_image(depth, mask, camera, floor_plane=None, z_range=None, near=None,
                      wall_planes=None):
    """The depth image the likelihood compares against: person pixels raw, background marked.

    Parameters
    ----------
    depth : (H, W) float
        Metres, 0 = no reading.
    mask : (H, W) bool
        Segmented person (always kept).
    near : (H, W) bool or None
        Where the person may be besides the mask (the dilated mask and predicted silhouette);
        readings outside ``mask | near`` are background. None: everywhere.
    camera : Camera
    floor_plane : (4,) float or None
        ``n . p + d`` = height above the floor; pixels within the segmenter's floor tolerance
        (:func:`depthtrack.detect.segment.inlier_distance`) of it, or below it, are background.
    z_range : (near, far) or None
        The person's depth band; readings outside it are background.
    wall_planes : (K, 4) float or None
        Planes of the walls the segmentation dropped; readings within its inlier distance of
        one are background, as on the floor.

    Returns
    -------
    (H, W) float32
        Raw depth where the person may be, ``BACKGROUND`` (inf) elsewhere, ``NO_READING`` (0)
        where the camera read nothing.
        No-reading pixels of open space (:func:`out_of_range`) are background too.
    """
    depth = np.asarray(depth, dtype=np.float64)
    reading = depth > 0
    background = np.zeros(depth.shape, bool)
    if z_range is not None:
        background |= (depth < z_range[0]) | (depth > z_range[1])
    if floor_plane is not None or (wall_planes is not None and len(wall_planes)):
        from ..detect.segment import inlier_distance

        pts = camera.backproject(depth)
        tolerance = inlier_distance(depth)
        if floor_plane is not None:
            plane = np.asarray(floor_plane, dtype=np.float64)
            height = (pts @ plane[:3] + plane[3]) / np.linalg.norm(plane[:3])
            background |= height < tolerance
        if wall_planes is not None and len(wall_planes):
            background |= on_planes(pts, wall_planes, tolerance)
    if near is not None:
        background |= ~np.asarray(near, bool)
    background &= reading & ~np.asarray(mask, bool)
    background |= out_of_range(depth, mask)
    out = np.where(background, BACKGROUND, np.where(reading, depth, NO_READING))
    return out.astype(np.float32)


def robust_points(points, keep=(5.0, 95.0)):
    """Foreground points ``(M, 3)`` without readings (z > 0 only) and without the depth tails
    (mixed "flying" pixels at silhouette edges lie between body and background)."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    pts = pts[pts[:, 2] > 0]
    if len(pts) < 20:
        return pts
    lo, hi = np.percentile(pts[:, 2], keep)
    return pts[(pts[:, 2] >= lo) & (pts[:, 2] <= hi)]


def estimate_height(points, up=None) -> float:
    """Standing height (m) guessed from a foreground point cloud ``(M, 3)`` of the first frame.

    The extent along the body's long axis (the first principal axis of the points; the
    ``up`` direction when given and the body is upright), plus 3 % for the sole and crown
    that a depth camera misses. Clipped to 1.2 .. 2.1 m.
    """
    pts = np.asarray(points, dtype=np.float64)
    centred = pts - pts.mean(axis=0)
    _, _, vt = np.linalg.svd(centred, full_matrices=False)
    axis = vt[0]
    if up is not None and abs(np.dot(axis, up)) > 0.8:
        axis = np.asarray(up, dtype=np.float64)
    extent = np.ptp(centred @ axis)
    return float(np.clip(extent * 1.03, 1.2, 2.1))
