"""Model markers: the motion-capture markers' places on the fitted surface mesh.

The marker set (Plug-in Gait names, one fixed mesh vertex each) is defined once, in
:mod:`depthtrack.body.markers`, where the synthesizer places the "measured" markers;
here the same vertices are read off the tracked body so the paper's marker errors
compare like with like.
"""
from __future__ import annotations

import numpy as np

from ..body import linear_blend_skinning
from ..body.markers import MARKER_NAMES, marker_vertices


def known_marker_names(names) -> list:
    """The names in ``names`` that the model's marker set defines, in the given order."""
    defined = set(MARKER_NAMES)
    return [n for n in names if n in defined]


def marker_positions(body, poses, names) -> np.ndarray:
    """Model marker positions for poses.

    Parameters
    ----------
    body : BodyModel
        The tracked (scaled) body; its mesh's vertices carry the markers.
    poses : (N, D) float
        NaN rows (no estimate) give NaN markers.
    names : sequence of str, (M,)
        Marker names as in the ground truth; a name the marker set does not define
        gives NaN (it is then left out of the marker errors).

    Returns
    -------
    markers : (N, M, 3) float, camera frame.
    """
    poses = np.atleast_2d(np.asarray(poses, dtype=np.float64))
    names = list(names)
    out = np.full((len(poses), len(names), 3), np.nan)
    index = {n: i for i, n in enumerate(MARKER_NAMES)}
    columns = [k for k, n in enumerate(names) if n in index]
    valid = np.all(np.isfinite(poses), axis=1)
    if not columns or not valid.any():
        return out
    vertices = marker_vertices(body)[[index[names[k]] for k in columns]]
    mesh = body.mesh
    # skin only the marker vertices: the same float32 matrices as body.posed_vertices
    posed = linear_blend_skinning(mesh.vertices[vertices], np.asarray(mesh.joints)[vertices],
                                  mesh.weights[vertices], body.skin_matrices(poses[valid]))
    out[np.ix_(np.flatnonzero(valid), columns)] = posed
    return out


__all__ = ["marker_positions", "known_marker_names"]
