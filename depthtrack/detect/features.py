"""Depth-invariant depth-difference features (Shotton et al., CVPR 2011, equation 1).

``f(I, x) = d(x + u / d(x)) - d(x + v / d(x))`` with the offsets ``u``, ``v`` in metres on a
surface facing the camera: in pixels a probe lies ``(fx u_x / d(x), fy u_y / d(x))`` from
``x``, so a feature measures the same body-relative place at any distance and with any of
the cameras (the focal length converts metres to pixels). Probes that leave the image or
land off the person read :data:`BACKGROUND`, a large constant, as in the paper.
"""
from __future__ import annotations

import numpy as np

#: Depth (m) read by probes off the person or outside the image.
BACKGROUND = 10.0


def probe_image(depth, mask) -> np.ndarray:
    """(H, W) float32 depth with everything but the person's readable pixels at :data:`BACKGROUND`.

    Parameters
    ----------
    depth : (H, W) float
        Metres, 0 = no reading.
    mask : (H, W) bool
        The person (foreground).
    """
    depth = np.asarray(depth, np.float32)
    return np.where(np.asarray(mask, bool) & (depth > 0), depth, np.float32(BACKGROUND)).astype(np.float32)


def sample_offsets(count: int, rng, radius: float = 0.5, unary_fraction: float = 0.5) -> np.ndarray:
    """Random offset pairs for candidate features.

    Parameters
    ----------
    count : int
    rng : numpy.random.Generator
    radius : float
        Largest offset, metres; offsets are uniform over the disc.
    unary_fraction : float
        Share of pairs with ``v = 0`` (the probe compared with the pixel itself).

    Returns
    -------
    (count, 4) float32
        ``u_x, u_y, v_x, v_y`` in metres.
    """
    r = radius * np.sqrt(rng.random((count, 2)))
    a = rng.uniform(0, 2 * np.pi, (count, 2))
    out = np.stack([r[:, 0] * np.cos(a[:, 0]), r[:, 0] * np.sin(a[:, 0]),
                    r[:, 1] * np.cos(a[:, 1]), r[:, 1] * np.sin(a[:, 1])], axis=1)
    out[rng.random(count) < unary_fraction, 2:] = 0.0
    return out.astype(np.float32)


def _probe(image, rows, cols, d, ox, oy, fx, fy):
    """Depth at ``(row + fy oy / d, col + fx ox / d)``, BACKGROUND outside the image; any broadcast shape."""
    H, W = image.shape
    c = np.rint(cols + fx * ox / d).astype(np.int32)
    r = np.rint(rows + fy * oy / d).astype(np.int32)
    inside = (c >= 0) & (c < W) & (r >= 0) & (r < H)
    vals = image[np.clip(r, 0, H - 1), np.clip(c, 0, W - 1)]
    return np.where(inside, vals, np.float32(BACKGROUND))


def depth_features(image, pixels, offsets, fx: float, fy: float) -> np.ndarray:
    """All features of ``offsets`` at ``pixels``: ``(N, K)`` values (training).

    Parameters
    ----------
    image : (H, W) float32
        From :func:`probe_image`.
    pixels : (N, 2) int
        ``(row, col)`` of person pixels.
    offsets : (K, 4) float
        From :func:`sample_offsets`.
    fx, fy : float
        Focal lengths (pixels).

    Returns
    -------
    (N, K) float32
    """
    rows = pixels[:, 0:1].astype(np.float32)
    cols = pixels[:, 1:2].astype(np.float32)
    d = image[pixels[:, 0], pixels[:, 1]][:, None]
    off = np.asarray(offsets, np.float32)[None]
    a = _probe(image, rows, cols, d, off[..., 0], off[..., 1], fx, fy)
    b = _probe(image, rows, cols, d, off[..., 2], off[..., 3], fx, fy)
    return (a - b).astype(np.float32)


def pair_features(image, rows, cols, d, offsets, fx: float, fy: float) -> np.ndarray:
    """One feature per pixel: ``(N,)`` values of ``offsets[i]`` at pixel i (tree traversal).

    Parameters
    ----------
    image : (H, W) float32
    rows, cols : (N,) int
    d : (N,) float32
        ``image[rows, cols]``.
    offsets : (N, 4) float32
    """
    a = _probe(image, rows, cols, d, offsets[:, 0], offsets[:, 1], fx, fy)
    b = _probe(image, rows, cols, d, offsets[:, 2], offsets[:, 3], fx, fy)
    return a - b


#: Per-pixel inputs of a forest trained with ``extras="centroid"``: the pixel's camera-frame
#: offset (m) from the centre of the person's points (see :func:`centroid_features`).
CENTROID_NAMES = ("dx", "dy", "dz")


def centroid_features(points, centre) -> np.ndarray:
    """Each point's camera-frame offset from the person's centre, as extra split inputs.

    Depth differences see only the pixel's neighbourhood (within the offsets' reach); where
    the pixel lies in the whole silhouette (above the centre on an upright body: head and
    shoulders; far from it: hands and feet; nearer the camera than it: what is held out in
    front) is one cheap column each, in metres so it does not change with distance.

    Parameters
    ----------
    points : (N, 3) float
        Camera-frame points of the pixels.
    centre : (3,) float
        Mean of all the person's points.

    Returns
    -------
    (N, 3) float32
        :data:`CENTROID_NAMES`.
    """
    return (np.asarray(points, np.float64) - np.asarray(centre, np.float64)).astype(np.float32)


#: Per-pixel inputs a forest with a side stage adds to :data:`CENTROID_NAMES`.
SIDE_NAMES = ("left_x", "left_y", "along_left")


def side_features(offsets, left) -> np.ndarray:
    """The frame's estimated image-plane direction of the subject's left and each pixel's
    place along it.

    Parameters
    ----------
    offsets : (N, 3) float
        From :func:`centroid_features`.
    left : (2,) float
        Camera x and y components of the subject's left axis, as the side stage estimates
        them for the whole frame (averaged over its pixels, so short of unit length where
        the pixels disagree).

    Returns
    -------
    (N, 3) float32
        :data:`SIDE_NAMES`: ``left_x, left_y`` and ``dx left_x + dy left_y`` (m).
    """
    offsets = np.asarray(offsets, np.float32)
    left = np.asarray(left, np.float32)
    n = len(offsets)
    return np.column_stack([np.broadcast_to(left, (n, 2)), offsets[:, :2] @ left]).astype(np.float32)


#: Per-pixel inputs besides the offset pairs: the frame's estimated body axes and the
#: pixel's place along them (see :func:`body_frame_features`).
BODY_FRAME_NAMES = ("forward_x", "forward_y", "forward_z", "up_x", "up_y", "up_z", "along_left", "along_up")


def body_frame_features(points, centroid, forward, up) -> np.ndarray:
    """The body's axes and each point's coordinates along them, as extra split inputs.

    A depth-difference feature tells the front of a body from its back only through small
    depth cues far from most pixels; given the body's axes (estimated for the whole frame
    first), the side of a pixel is where it lies along the subject's left axis.

    Parameters
    ----------
    points : (N, 3) float
        Camera-frame points of the pixels.
    centroid : (3,) float
        Centre of the person's points.
    forward, up : (3,) float
        Unit vectors: the direction the torso faces and its head-ward axis (camera frame).

    Returns
    -------
    (N, 8) float32
        :data:`BODY_FRAME_NAMES`: ``forward``, ``up``, then ``(p - c) . left`` and
        ``(p - c) . up`` in metres, ``left = up x forward`` (the subject's own left).
    """
    forward = np.asarray(forward, float)
    up = np.asarray(up, float)
    left = np.cross(up, forward)
    rel = np.asarray(points, float) - np.asarray(centroid, float)
    n = len(rel)
    return np.column_stack([np.broadcast_to(forward, (n, 3)), np.broadcast_to(up, (n, 3)),
                            rel @ left, rel @ up]).astype(np.float32)
