"""Pixel-adjacency graphs over depth images: depth-aware connectivity and surface distances.

One graph serves two purposes: segmentation joins pixels into connected surfaces
(:func:`surface_components`), and the geodesic extrema walk over the same surface with
3D edge lengths (:func:`surface_graph`). Neighbouring pixels are joined only when their
depths differ by less than a *jump threshold*: a hand held in front of the torso, or an
arm seen against the back wall, is then a separate surface even where it touches the
other in the image.
"""
from __future__ import annotations

import numpy as np
from scipy import sparse
from scipy.sparse import csgraph

#: (row, column) steps to the 4 "forward" 8-neighbours; the other 4 are the same edges reversed.
_FORWARD_STEPS = ((0, 1), (1, -1), (1, 0), (1, 1))


def jump_threshold(z, fx: float, base: float = 0.08, pixels: float = 6.0):
    """Largest depth difference (m) between neighbouring pixels on one surface.

    ``max(base, pixels * z / fx)``: a fixed floor above the sensor noise, growing with
    the pixel footprint ``z / fx`` so that slanted surfaces stay connected far away.

    Parameters
    ----------
    z : (...) float
        Depth of the nearer pixel of each pair, metres.
    fx : float
        Focal length in pixels.
    """
    return np.maximum(base, pixels * np.asarray(z, dtype=float) / fx)


def flying_pixels(depth, valid, fx: float, base: float = 0.08, pixels: float = 6.0):
    """Mixed ("flying") pixels: readings part way across a depth discontinuity.

    A time-of-flight pixel whose footprint straddles an edge reports a depth between the
    near and the far surface. Such a pixel steps by more than the jump threshold to
    *both* of its neighbours along some line (horizontal, vertical or diagonal), in the
    same direction (one nearer, one farther) -- a real surface, even a slanted one,
    does not. These pixels would otherwise chain a person to the wall behind.

    Parameters
    ----------
    depth : (H, W) float
    valid : (H, W) bool
    fx : float
        Focal length in pixels, for :func:`jump_threshold`.

    Returns
    -------
    (H, W) bool
    """
    z = np.asarray(depth, dtype=float)
    valid = np.asarray(valid, dtype=bool)
    pad_z = np.pad(z, 1)
    pad_v = np.pad(valid, 1)
    H, W = z.shape
    t = jump_threshold(z, fx, base, pixels)
    out = np.zeros_like(valid)
    for dr, dc in _FORWARD_STEPS:
        fwd = (slice(1 + dr, 1 + dr + H), slice(1 + dc, 1 + dc + W))
        back = (slice(1 - dr, 1 - dr + H), slice(1 - dc, 1 - dc + W))
        ok = valid & pad_v[fwd] & pad_v[back]
        step_f = pad_z[fwd] - z
        step_b = z - pad_z[back]
        out |= ok & (np.abs(step_f) > t) & (np.abs(step_b) > t) & (step_f * step_b > 0)
    return out


def _edges(valid, depth, fx, base, pixels):
    """Flat indices ``(a (E,), b (E,))`` of 8-neighbour pairs of ``valid`` pixels on one surface."""
    H, W = valid.shape
    idx = np.arange(H * W).reshape(H, W)
    heads, tails = [], []
    for dr, dc in _FORWARD_STEPS:
        r0, r1 = 0, H - dr
        c0, c1 = max(0, -dc), W - max(0, dc)
        a = (slice(r0, r1), slice(c0, c1))
        b = (slice(r0 + dr, r1 + dr), slice(c0 + dc, c1 + dc))
        za, zb = depth[a], depth[b]
        ok = valid[a] & valid[b]
        ok &= np.abs(za - zb) < jump_threshold(np.minimum(za, zb), fx, base, pixels)
        heads.append(idx[a][ok])
        tails.append(idx[b][ok])
    return np.concatenate(heads), np.concatenate(tails)


def surface_components(depth, valid, fx: float, base: float = 0.08, pixels: float = 6.0):
    """Label connected surfaces: 8-neighbour pixels whose depths differ by less than the jump threshold.

    Parameters
    ----------
    depth : (H, W) float
        Camera z, metres.
    valid : (H, W) bool
        Pixels that take part.
    fx : float
        Focal length (pixels), for :func:`jump_threshold`.

    Returns
    -------
    labels : (H, W) int
        Component index per pixel, -1 where not ``valid``.
    count : int
        Number of components.
    """
    valid = np.asarray(valid, dtype=bool)
    depth = np.asarray(depth, dtype=float)
    n = valid.size
    a, b = _edges(valid, depth, fx, base, pixels)
    graph = sparse.coo_matrix((np.ones(len(a), np.int8), (a, b)), shape=(n, n)).tocsr()
    count, flat = csgraph.connected_components(graph, directed=False)
    labels = np.full(n, -1)
    keep = valid.ravel()
    # renumber the components of valid pixels 0..count-1 in the order of their ids (invalid
    # pixels are singletons): np.unique's numbering, without its sort of every pixel
    present = np.zeros(count, dtype=bool)
    present[flat[keep]] = True
    labels[keep] = (np.cumsum(present) - 1)[flat[keep]]
    return labels.reshape(valid.shape), int(present.sum())


def surface_graph(points_image, valid, fx: float, base: float = 0.08, pixels: float = 6.0):
    """Sparse graph over the ``valid`` pixels with 3D edge lengths (depth jumps cut).

    Parameters
    ----------
    points_image : (H, W, 3) float
        Camera-frame point per pixel.
    valid : (H, W) bool
    fx : float
        Focal length in pixels of the image the points are laid out on.

    Returns
    -------
    graph : (M, M) scipy.sparse.csr_matrix
        Symmetric; entry = Euclidean distance between neighbouring points (>= 1e-9).
    rows, cols : (M,) int
        Pixel of each node, in row-major order of ``valid``.
    """
    valid = np.asarray(valid, dtype=bool)
    H, W = valid.shape
    node = np.full(H * W, -1)
    rows, cols = np.nonzero(valid)
    node[rows * W + cols] = np.arange(len(rows))
    a, b = _edges(valid, points_image[..., 2], fx, base, pixels)
    flat = points_image.reshape(-1, 3)
    length = np.maximum(np.linalg.norm(flat[a] - flat[b], axis=1), 1e-9)
    m = len(rows)
    graph = sparse.coo_matrix((np.concatenate([length, length]),
                               (np.concatenate([node[a], node[b]]), np.concatenate([node[b], node[a]]))),
                              shape=(m, m)).tocsr()
    return graph, rows, cols
