"""Geodesic extrema of the person's surface: candidate head, hand and foot locations.

The paper's interest points (after Plagemann et al., "Real-time identification and
localization of body parts from depth images", ICRA 2010): build a graph over the
foreground points (8-neighbour pixel adjacency, 3D edge lengths, edges cut at depth
jumps), take geodesic distances from the point nearest the centroid, then repeatedly
take the point of largest geodesic distance as an extremum and add it as a further
zero-distance source. Hands, feet and the head come out first because they are the
ends of the body's longest surface paths. Each extremum's *direction* is the unit
vector from the point ``orientation_length`` metres back along its geodesic path to the
extremum: for a hand, roughly the forearm's direction.

Surfaces cut off by a depth jump (a hand in front of the torso) are linked to the rest
at their 3D-nearest point pair, so every foreground point gets a finite distance.
Frames larger than ``max_nodes`` foreground points are subsampled on a coarser pixel grid.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import sparse
from scipy.sparse import csgraph
from scipy.spatial import cKDTree

from ..errors import InputError
from .graph import surface_graph


@dataclass
class Extrema:
    """Geodesic extrema of one foreground.

    Attributes
    ----------
    positions : (K, 3) float
        Camera-frame points, in the order found.
    directions : (K, 3) float
        Unit vectors: the geodesic path's direction arriving at each extremum.
    centres : (K, 3) float
        Centroid of the surface within ``cap_radius`` (geodesic) of each extremum: the
        visible part's centre for a hand (hand centroid), a foot or the head (upper face).
    pixels : (K, 2) int
        Pixel ``(u, v)`` of each extremum.
    distances : (K,) float
        Geodesic distance of each extremum from the sources before it (metres).
    nodes : (K,) int
        Index of each extremum among the graph's nodes.
    reach : (K,) float
        Geodesic distance of each extremum from the body's central point (metres).
    cap_areas : (K, 2) float
        Surface area (m^2) within half the cap radius and within the cap radius (geodesic)
        of each extremum: a hand is small, a head larger.
    """

    positions: np.ndarray
    directions: np.ndarray
    centres: np.ndarray
    pixels: np.ndarray
    distances: np.ndarray
    nodes: np.ndarray
    reach: np.ndarray
    cap_areas: np.ndarray

    def __len__(self):
        return len(self.positions)


@dataclass
class SurfaceGraph:
    """The foreground's (possibly subsampled) surface graph.

    Attributes
    ----------
    graph : (M, M) csr_matrix
        Symmetric edge lengths (m); cut surfaces already linked.
    points : (M, 3) float
    pixels : (M, 2) int
        Full-resolution pixel ``(u, v)`` of each node.
    stride : int
        Pixel subsampling step used.
    """

    graph: sparse.csr_matrix
    points: np.ndarray
    pixels: np.ndarray
    stride: int


def _link_components(graph, points, min_nodes: int):
    """Join the graph's components to the largest one at their 3D-nearest node pairs.

    Components smaller than ``min_nodes`` are returned as dropped (noise).

    Returns
    -------
    graph : csr_matrix
    keep : (M,) bool
        Nodes that belong to the linked graph.
    """
    keep = np.ones(len(points), bool)
    if len(points) == 0:
        return graph, keep
    count, labels = csgraph.connected_components(graph, directed=False)
    if count == 1:
        return graph, keep
    sizes = np.bincount(labels, minlength=count)
    main = int(np.argmax(sizes))
    heads, tails, lengths = [], [], []
    joined = labels == main
    for c in np.argsort(-sizes):
        if c == main:
            continue
        members = np.nonzero(labels == c)[0]
        if sizes[c] < min_nodes:
            keep[members] = False
            continue
        tree = cKDTree(points[members])
        others = np.nonzero(joined)[0]
        d, i = tree.query(points[others])
        k = int(np.argmin(d))
        heads.append(others[k])
        tails.append(members[i[k]])
        lengths.append(max(float(d[k]), 1e-9))
        joined[members] = True
    if heads:
        extra = sparse.coo_matrix((np.r_[lengths, lengths], (np.r_[heads, tails], np.r_[tails, heads])),
                                  shape=graph.shape)
        graph = (graph + extra).tocsr()
    return graph, keep


def build_surface_graph(foreground, camera, max_nodes: int = 4000, jump: float = 0.08,
                        min_component: int = 5) -> SurfaceGraph:
    """Surface graph of a foreground (see the module docstring).

    Parameters
    ----------
    foreground : Foreground
        With ``mask (H, W)`` and ``points (M, 3)`` (row-major order of the mask).
    camera : Camera
    max_nodes : int
        Subsample the mask on every ``s``-th pixel (rows and columns) until at most this
        many nodes remain.
    jump : float
        Depth jump floor, see :func:`~depthtrack.detect.graph.jump_threshold`.
    min_component : int
        Cut-off surfaces with fewer nodes are dropped as noise.
    """
    mask = np.asarray(foreground.mask, bool)
    H, W = mask.shape
    n = int(mask.sum())
    stride = 1
    while n / (stride * stride) > max_nodes:
        stride += 1
    cloud = np.zeros((H, W, 3))
    cloud[mask] = foreground.points
    sub_mask = mask[::stride, ::stride]
    sub_cloud = cloud[::stride, ::stride]
    graph, rows, cols = surface_graph(sub_cloud, sub_mask, camera.fx / stride, base=jump)
    points = sub_cloud[rows, cols]
    pixels = np.stack([cols * stride, rows * stride], axis=1)
    graph, keep = _link_components(graph, points, min_component)
    if not keep.all():
        idx = np.nonzero(keep)[0]
        graph = graph[idx][:, idx]
        points, pixels = points[idx], pixels[idx]
    return SurfaceGraph(graph.tocsr(), points, pixels, stride)


def _path_direction(predecessors, points, node, length):
    """Unit direction arriving at ``node`` along its shortest-path tree over the last ``length`` metres."""
    here = points[node]
    k = node
    travelled = 0.0
    prev_point = here
    while True:
        p = predecessors[k]
        if p < 0:
            break
        travelled += float(np.linalg.norm(points[p] - prev_point))
        prev_point = points[p]
        k = p
        if travelled >= length:
            break
    v = here - points[k]
    n = np.linalg.norm(v)
    return v / n if n > 1e-9 else np.zeros(3)


def geodesic_extrema(foreground, camera, count: int = 6, orientation_length: float = 0.15,
                     cap_radius: float = 0.20,
                     min_distance: float = 0.10, max_nodes: int = 4000, jump: float = 0.08,
                     surface: SurfaceGraph | None = None) -> Extrema:
    """The first ``count`` geodesic extrema of the person's surface.

    Parameters
    ----------
    foreground : Foreground
    camera : Camera
    count : int
        Extrema to find (the paper's incremental extrema; 5-7 covers head, hands, feet).
    orientation_length : float
        Metres of geodesic path behind an extremum that set its direction.
    cap_radius : float
        Geodesic radius (m) of the surface cap whose centroid is the extremum's centre.
    min_distance : float
        Stop early when the farthest point is nearer than this to every source.
    max_nodes, jump : see :func:`build_surface_graph`.
    surface : SurfaceGraph, optional
        A graph already built for this foreground.

    Returns
    -------
    Extrema
        Possibly fewer than ``count`` (small or empty foreground).
    """
    if count < 1:
        raise InputError(None, f"extrema count must be at least 1, got {count}")
    g = build_surface_graph(foreground, camera, max_nodes, jump) if surface is None else surface
    empty = Extrema(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 2), int),
                    np.zeros(0), np.zeros(0, int), np.zeros(0), np.zeros((0, 2)))
    if len(g.points) < 2:
        return empty
    centre = g.points.mean(axis=0)
    source = int(np.argmin(np.linalg.norm(g.points - centre, axis=1)))
    dist, pred = csgraph.dijkstra(g.graph, directed=False, indices=source, return_predecessors=True)
    from_centre = dist.copy()
    # surface area each node stands for: its pixel footprint, times stride^2
    node_area = camera.pixel_area(g.points[:, 2]) * g.stride ** 2
    nodes, found, dirs, centres, areas = [], [], [], [], []
    for _ in range(count):
        finite = np.where(np.isfinite(dist), dist, -1.0)
        k = int(np.argmax(finite))
        if finite[k] < min_distance:
            break
        nodes.append(k)
        found.append(finite[k])
        dirs.append(_path_direction(pred, g.points, k, orientation_length))
        d_new, p_new = csgraph.dijkstra(g.graph, directed=False, indices=k, return_predecessors=True)
        cap = d_new <= cap_radius
        centres.append(g.points[cap].mean(axis=0))
        areas.append((node_area[d_new <= 0.5 * cap_radius].sum(), node_area[cap].sum()))
        closer = d_new < dist
        dist = np.where(closer, d_new, dist)
        pred = np.where(closer, p_new, pred)
    if not nodes:
        return empty
    nodes = np.array(nodes)
    return Extrema(g.points[nodes], np.array(dirs), np.array(centres), g.pixels[nodes],
                   np.array(found), nodes, from_centre[nodes], np.array(areas))
