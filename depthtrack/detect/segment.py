"""Foreground segmentation of a depth frame: the person, without floor and background.

Steps (:func:`segment_foreground`):

1. **Floor.** A RANSAC plane over the back-projected points, restricted to planes whose
   upward normal lies within ``max_floor_tilt`` of the camera's up axis (-y), so the
   floor may be tilted relative to the camera but a back wall can never win; scored by
   inliers minus points *below* the plane (the floor is the lowest large plane), then
   refined by least squares on its inliers. Points within a depth-dependent distance of
   it (3 sigma of the ToF noise, at least 2 cm) are removed, as is anything below it.
2. **Surfaces.** Mixed ("flying") pixels part way across a depth edge are dropped
   (:func:`~depthtrack.detect.graph.flying_pixels`); the remaining pixels are joined
   into connected surfaces by 8-neighbour adjacency, cutting where neighbouring depths jump by more than
   :func:`~depthtrack.detect.graph.jump_threshold` -- so an arm seen against the back
   wall in the image is still separate from the wall.
3. **Background.** Surfaces that are planar (a RANSAC plane explains at least
   ``planar_fraction_min`` of their points) and larger than a person (``min_planar_extent``
   along one in-plane direction, or ``min_planar_area``) are walls and are dropped, as
   are smaller surfaces lying on a wall's plane (the wall seen between arms or legs).
4. **Person.** The remaining surface with the most pixels is the person; smaller
   surfaces that touch it in 3D (within ``merge_distance``) and lie at most
   ``merge_behind`` behind it join it, repeatedly: a hand held in front of the torso, a
   thigh and shin seen end-on, the far leg of a person seen side-on -- each cut off by
   its depth jump.

All thresholds are in metres and documented on :func:`segment_foreground`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from ..errors import InputError
from .graph import flying_pixels, surface_components

#: The ToF noise standard deviation assumed for inlier thresholds: sigma(z) = a + b z^2 (m),
#: the SR4000 data-sheet magnitudes (about 1 cm at 3 m).
NOISE_SIGMA = (0.003, 0.001)


@dataclass
class Foreground:
    """The person's pixels and points in one depth frame.

    Attributes
    ----------
    mask : (H, W) bool
        The person's pixels.
    points : (M, 3) float
        Camera-frame points of the mask's pixels (row-major order).
    pixels : (M, 2) int
        Pixel ``(u, v)`` = (column, row) of each point.
    floor_plane : (4,) float or None
        ``(nx, ny, nz, d)`` with unit normal ``n`` pointing up (toward the person):
        ``n . p + d`` is the height of point ``p`` above the floor. None when no floor was found.
    wall_planes : (K, 4) float or None
        The planes of the surfaces dropped as walls (unit normal, offset), those larger than
        the person; None when there were none.
    """

    mask: np.ndarray
    points: np.ndarray
    pixels: np.ndarray
    floor_plane: np.ndarray | None = None
    wall_planes: np.ndarray | None = None

    @property
    def count(self) -> int:
        return int(len(self.points))


def check_depth(depth, camera, path=None) -> np.ndarray:
    """Validate a depth image against a camera.

    Parameters
    ----------
    depth : (H, W) array-like
        Camera z in metres, 0 = no reading.
    camera : Camera

    Returns
    -------
    (H, W) float64

    Raises
    ------
    InputError
        Wrong shape, non-numeric, NaN / infinite or negative values.
    """
    try:
        z = np.asarray(depth, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(path, "depth image is not numeric") from None
    if z.ndim != 2:
        raise InputError(path, f"depth image must be 2-D (H, W), got shape {z.shape}")
    if z.shape != camera.shape:
        raise InputError(path, f"depth image is {z.shape[1]} x {z.shape[0]} (w x h), camera is "
                               f"{camera.width} x {camera.height}")
    if not np.all(np.isfinite(z)):
        raise InputError(path, f"depth image has {int(np.count_nonzero(~np.isfinite(z)))} NaN or "
                               f"infinite values (use 0 for 'no reading')")
    if np.any(z < 0):
        raise InputError(path, "depth image has negative values")
    return z


def noise_sigma(z) -> np.ndarray:
    """Assumed depth noise standard deviation (m) at range ``z (...)``; see :data:`NOISE_SIGMA`."""
    return NOISE_SIGMA[0] + NOISE_SIGMA[1] * np.asarray(z, dtype=float) ** 2


def inlier_distance(z, minimum: float = 0.02) -> np.ndarray:
    """Plane inlier threshold (m) at range ``z``: ``max(minimum, 3 sigma(z))``."""
    return np.maximum(minimum, 3.0 * noise_sigma(z))


# ---------------------------------------------------------------------------------- planes
def plane_through(p0, p1, p2):
    """Planes through point triples.

    Parameters
    ----------
    p0, p1, p2 : (K, 3) float

    Returns
    -------
    planes : (K, 4) float
        Unit normal and offset (``n . p + d = 0``); rows of NaN for degenerate triples.
    """
    n = np.cross(p1 - p0, p2 - p0)
    norm = np.linalg.norm(n, axis=1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        n = np.where(norm > 1e-9, n / norm, np.nan)
    return np.concatenate([n, -np.sum(n * p0, axis=1, keepdims=True)], axis=1)


def fit_plane(points, weights=None) -> np.ndarray:
    """Least-squares plane ``(4,)`` (unit normal, offset) through ``points (n, 3)``."""
    points = np.asarray(points, dtype=float)
    w = np.ones(len(points)) if weights is None else np.asarray(weights, float)
    centre = (w[:, None] * points).sum(0) / w.sum()
    _, _, vt = np.linalg.svd((points - centre) * np.sqrt(w)[:, None], full_matrices=False)
    n = vt[2]
    return np.append(n, -n @ centre)


def _ransac_planes(points, rng, hypotheses):
    """``hypotheses`` random planes (K, 4) through triples of ``points (n, 3)``."""
    idx = rng.integers(0, len(points), size=(hypotheses, 3))
    return plane_through(points[idx[:, 0]], points[idx[:, 1]], points[idx[:, 2]])


def surface_normals(cloud, valid, step: int = 2, rows=None, cols=None) -> np.ndarray:
    """Unit surface normals of an organised point cloud from central differences.

    Parameters
    ----------
    cloud : (H, W, 3) float
    valid : (H, W) bool
    step : int
        Pixels to either side the differences span (larger = smoother, less noisy).
    rows, cols : (n,) int, optional
        Only these pixels (default: every pixel).

    Returns
    -------
    normals : (H, W, 3) float, or (n, 3) with ``rows, cols``
        Pointing toward the camera; NaN where a neighbour is missing or degenerate.
    """
    H, W = valid.shape
    if rows is None:
        rows, cols = np.mgrid[0:H, 0:W]
    rows, cols = np.asarray(rows), np.asarray(cols)
    s = step

    def at(dr, dc):
        r = np.clip(rows + dr, 0, H - 1)
        c = np.clip(cols + dc, 0, W - 1)
        inside = (rows + dr >= 0) & (rows + dr < H) & (cols + dc >= 0) & (cols + dc < W)
        return cloud[r, c], valid[r, c] & inside

    (right, ok_r), (left, ok_l) = at(0, s), at(0, -s)
    (down, ok_d), (up, ok_u) = at(s, 0), at(-s, 0)
    n = np.cross(right - left, down - up)
    norm = np.linalg.norm(n, axis=-1, keepdims=True)
    good = valid[rows, cols] & ok_r & ok_l & ok_d & ok_u & (norm[..., 0] > 1e-12)
    with np.errstate(invalid="ignore", divide="ignore"):
        n = np.where(good[..., None], n / norm, np.nan)
    flip = np.sum(n * cloud[rows, cols], axis=-1) > 0          # face the camera
    n[flip] *= -1.0
    return n


def fit_floor(points, up=(0.0, -1.0, 0.0), max_tilt_deg: float = 60.0, hypotheses: int = 128,
              sample: int = 1500, min_inliers: int = 150, min_fraction: float = 0.03, rng=None,
              normals=None, max_normal_deg: float = 30.0):
    """The floor plane in a point cloud, or None.

    Parameters
    ----------
    points : (n, 3) float
        Camera-frame points of one frame.
    up : (3,) float
        Roughly "up" in the camera frame (camera -y for an upright camera).
    max_tilt_deg : float
        Largest angle between the floor normal and ``up``.
    hypotheses, sample : int
        RANSAC planes tried, points they are scored on.
    min_inliers, min_fraction : float
        A floor has at least this many inlier points and this fraction of all points.
    rng : numpy.random.Generator, optional
        Default: seeded, so the result is reproducible.
    normals : (n, 3) float or callable, optional
        Local surface normals (:func:`surface_normals`), or a function of point indices
        ``(k,) int -> (k, 3)`` normals (computed only where needed). When given, plane
        hypotheses come from points facing up (within ``max_tilt_deg``), and the least-squares
        refinement uses only points whose normal is within ``max_normal_deg`` of the
        plane's, so the foot of a wall (in the floor's inlier band far away, where the
        noise allowance is wide) does not tilt the floor toward it.

    Returns
    -------
    plane : (4,) float or None
        Unit normal pointing along ``up`` and offset: ``n . p + d`` = height above the floor.
    """
    points = np.asarray(points, dtype=float)
    if len(points) < max(3, min_inliers):
        return None
    rng = np.random.default_rng(0) if rng is None else rng
    up = np.asarray(up, float) / np.linalg.norm(up)
    pick = rng.choice(len(points), size=min(sample, len(points)), replace=False)
    scored = points[pick]
    pool = scored
    if normals is not None:
        # draw the plane hypotheses from points that face up: a floor seen as a thin strip at
        # the bottom of the image is then still sampled often enough
        n_scored = normals(pick) if callable(normals) else np.asarray(normals)[pick]
        facing = n_scored @ up >= np.cos(np.radians(max_tilt_deg))
        if facing.sum() >= max(10, min_inliers // 10):
            pool = scored[facing]
    planes = _ransac_planes(pool, rng, hypotheses)
    planes[np.sum(planes[:, :3] * up, axis=1) < 0] *= -1.0          # normals point up
    ok = np.sum(planes[:, :3] * up, axis=1) >= np.cos(np.radians(max_tilt_deg))
    planes = planes[ok & np.all(np.isfinite(planes), axis=1)]
    if len(planes) == 0:
        return None
    tol = inlier_distance(scored[:, 2])
    height = scored @ planes[:, :3].T + planes[:, 3]                  # (n, K)
    inliers = np.abs(height) < tol[:, None]
    below = height < -tol[:, None]
    # the floor is the lowest large plane: points under a candidate count against it
    score = inliers.sum(0) - 2 * below.sum(0)
    plane = planes[np.argmax(score)]
    tol_all = inlier_distance(points[:, 2])
    aligned = np.ones(len(points), bool)
    if normals is not None:
        # only points in a generous band around the plane can matter for the refinement
        band = np.nonzero(np.abs(points @ plane[:3] + plane[3]) < 2.0 * tol_all)[0]
        n_band = normals(band) if callable(normals) else np.asarray(normals)[band]
        aligned[band] = ~(np.abs(n_band @ plane[:3]) < np.cos(np.radians(max_normal_deg)))
    for _ in range(3):
        near = (np.abs(points @ plane[:3] + plane[3]) < tol_all) & aligned
        if near.sum() < 3:
            return None
        plane = fit_plane(points[near])
        if plane[:3] @ up < 0:
            plane = -plane
    near = np.abs(points @ plane[:3] + plane[3]) < tol_all
    if near.sum() < max(min_inliers, min_fraction * len(points)) \
            or plane[:3] @ up < np.cos(np.radians(max_tilt_deg)):
        return None
    return plane


def planar_fraction(points, rng, hypotheses: int = 64, sample: int = 1500) -> tuple:
    """Best RANSAC plane of ``points (n, 3)``: (fraction of points within the inlier distance, plane (4,))."""
    pts = points if len(points) <= sample else points[rng.choice(len(points), sample, replace=False)]
    planes = _ransac_planes(pts, rng, hypotheses)
    planes = planes[np.all(np.isfinite(planes), axis=1)]
    if len(planes) == 0:
        return 0.0, None
    inl = np.abs(pts @ planes[:, :3].T + planes[:, 3]) < inlier_distance(pts[:, 2])[:, None]
    k = int(np.argmax(inl.sum(0)))
    return float(inl[:, k].mean()), planes[k]


def _on_planes(points, planes) -> float:
    """Fraction of ``points (n, 3)`` within the inlier distance of any of ``planes (k, 4)``."""
    planes = np.asarray(planes, float)
    pts = points[:: max(1, len(points) // 1500)]
    dist = np.abs(pts @ planes[:, :3].T + planes[:, 3]).min(axis=1)
    return float(np.mean(dist < inlier_distance(pts[:, 2])))


def _in_plane_extent(points, plane) -> np.ndarray:
    """(2,) spread (5th-95th percentile, m) of ``points`` along two in-plane axes (principal)."""
    points = points[:: max(1, len(points) // 2000)]
    centred = points - points.mean(0)
    flat = centred - np.outer(centred @ plane[:3], plane[:3])
    _, _, vt = np.linalg.svd(flat, full_matrices=False)
    coords = flat @ vt[:2].T
    lo, hi = np.percentile(coords, [5, 95], axis=0)
    return hi - lo


# ---------------------------------------------------------------------------------- segmentation
def segment_foreground(depth, camera, floor: bool = True, up=(0.0, -1.0, 0.0), max_floor_tilt: float = 60.0,
                       jump: float = 0.08, min_pixels: int = 30, planar_fraction_min: float = 0.85,
                       min_planar_extent: float = 2.5, min_planar_area: float = 1.5,
                       merge_distance: float = 0.25, merge_behind: float = 0.40,
                       seed: int = 0) -> Foreground:
    """Segment the person in a depth frame.

    Parameters
    ----------
    depth : (H, W) float
        Camera z in metres; 0 = no reading.
    camera : Camera
    floor : bool
        Find and remove a floor plane.
    up, max_floor_tilt : see :func:`fit_floor`.
    jump : float
        Smallest depth jump (m) that separates neighbouring pixels
        (:func:`~depthtrack.detect.graph.jump_threshold`; it grows with range).
    min_pixels : int
        Surfaces with fewer pixels are noise (flying pixels, floor remnants).
    planar_fraction_min, min_planar_extent, min_planar_area : float
        A surface is background when this fraction of it lies on one plane and it either
        spans at least ``min_planar_extent`` metres along an in-plane axis or covers at
        least ``min_planar_area`` square metres (seen from the camera) -- more than a person
        shows (a 1.95 m tall person with the arms spread shows about 0.7 m^2; a far,
        side-on person can be planar to within the noise).
    merge_distance, merge_behind : float
        Smaller surfaces with points within ``merge_distance`` (m, 3D) of the person, those
        points lying (median) at most ``merge_behind`` m behind their nearest person points,
        join the person; repeated until nothing more joins. (The far leg of a person seen
        side-on is cut from the near side by an occlusion as deep as the body.)
    seed : int
        Seeds the RANSAC sampling (results are reproducible).

    Returns
    -------
    Foreground

    Raises
    ------
    InputError
        Bad depth image (see :func:`check_depth`).
    """
    z = check_depth(depth, camera)
    rng = np.random.default_rng(seed)
    cloud = camera.backproject(z)                                    # (H, W, 3)
    valid = z > 0
    plane = None
    if floor and valid.sum() >= 3:
        rows, cols = np.nonzero(valid)
        plane = fit_floor(cloud[rows, cols], up=up, max_tilt_deg=max_floor_tilt, rng=rng,
                          normals=lambda i: surface_normals(cloud, valid, rows=rows[i], cols=cols[i]))
        if plane is not None:
            height = cloud @ plane[:3] + plane[3]
            valid &= height > inlier_distance(z)
    valid &= ~flying_pixels(z, valid, camera.fx, base=jump)
    flat_cloud = cloud.reshape(-1, 3)

    def pick(valid, walls):
        """Components of ``valid`` and the person among them (largest non-wall surface)."""
        labels, count = surface_components(z, valid, camera.fx, base=jump)
        sizes = np.bincount(labels[valid], minlength=count)
        flat_labels = labels.ravel()
        order = np.argsort(flat_labels, kind="stable")
        starts = np.searchsorted(flat_labels[order], np.arange(count + 1))

        def members(c):
            return order[starts[c]:starts[c + 1]]

        # metric area of each surface (for the wall test)
        area = np.bincount(labels[valid], weights=camera.pixel_area(z[valid]), minlength=count)
        person, background = None, set()
        for c in np.argsort(-sizes, kind="stable"):
            if sizes[c] < min_pixels:
                break                                      # size order: the rest are smaller still
            pts = flat_cloud[members(c)]
            if walls and _on_planes(pts, walls) >= planar_fraction_min:
                background.add(int(c))                     # a piece of a wall seen between limbs
                continue
            frac, pl = planar_fraction(pts, rng)
            if frac >= planar_fraction_min and (area[c] >= min_planar_area
                                                or _in_plane_extent(pts, pl).max() >= min_planar_extent):
                background.add(int(c))                     # a wall
                walls.append(pl)
                continue
            person = int(c)
            break
        return labels, sizes, members, person, background

    walls = []
    labels, sizes, members, person, background = pick(valid, walls)
    if person is None and walls:
        # A person close to a wall can join it through flying or noisy pixels and vanish in
        # the "wall" surface. Drop the walls' plane inliers and look again: what stands off
        # the planes separates from them.
        planes = np.asarray(walls, dtype=np.float64)
        on_wall = np.isin(labels, list(background)) & valid
        dist = np.abs(cloud[on_wall] @ planes[:, :3].T + planes[:, 3]).min(axis=1)
        inlier = np.zeros(z.shape, dtype=bool)
        inlier[on_wall] = dist < inlier_distance(z[on_wall])
        if (on_wall & ~inlier).sum() >= min_pixels:
            valid = valid & ~inlier
            labels, sizes, members, person, background = pick(valid, walls)
    mask = np.zeros(z.shape, dtype=bool)
    if person is not None:
        keep = [person]
        pending = [int(c) for c in np.nonzero(sizes >= min(min_pixels, 10))[0]
                   if c != person and c not in background]
        added = [person]
        # grow the person by the surfaces that touch it in 3D; repeat so chains join
        # (a shin cut from its thigh, cut from the torso, when the legs point at the camera)
        while added and pending:
            tree = cKDTree(flat_cloud[np.concatenate([members(c) for c in added])])
            body_z = tree.data[:, 2]
            added = []
            for c in pending:
                pts = flat_cloud[members(c)]
                dist, near = tree.query(pts, distance_upper_bound=merge_distance)
                hit = np.isfinite(dist)
                if hit.any() and np.median(pts[hit, 2] - body_z[near[hit]]) <= merge_behind:
                    added.append(c)
            keep += added
            pending = [c for c in pending if c not in added]
        mask = np.isin(labels, keep) & valid
    rows, cols = np.nonzero(mask)
    return Foreground(mask=mask, points=cloud[rows, cols], pixels=np.stack([cols, rows], axis=1),
                      floor_plane=plane,
                      wall_planes=np.asarray(walls, dtype=np.float64) if walls else None)
