"""C3D export (via ezc3d): virtual Plug-in Gait markers and the 15 joints of a track.

Points, in this order: the 39 Plug-in Gait markers of the fitted body
(:data:`depthtrack.body.markers.MARKER_NAMES`, each a fixed vertex of the skinned mesh,
as the synthesizer and ``eval`` place them), then the 15 contract joints
(:data:`depthtrack.contract.JOINT_NAMES`, ``head`` ... ``r_ankle``). ``POINT:LABELS``
holds those names, ``POINT:RATE`` the track's frame rate, ``POINT:UNITS`` ``mm``.

Axes: z up, as biomechanics tools expect (Visual3D, OpenSim via its importers, Mokka):
``Z_UP_FROM_CAMERA`` -- x right, y along the camera's viewing direction, z up; origin at
the depth camera. Frames without a pose are invalid samples: coordinates NaN and
residual -1 (the C3D convention readers check).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..body.markers import MARKER_NAMES, marker_vertices
from ..body.mesh import linear_blend_skinning
from ..contract import JOINT_NAMES
from ..io.atomic import atomic_path
from .axes import Z_UP_FROM_CAMERA

#: Millimetres per metre: C3D files from labs are in mm.
MM = 1000.0


def model_markers(body, poses) -> np.ndarray:
    """``(F, 39, 3)`` camera-frame Plug-in Gait markers of the body for ``poses (F, D)``; NaN rows give NaN."""
    poses = np.atleast_2d(np.asarray(poses, float))
    out = np.full((len(poses), len(MARKER_NAMES), 3), np.nan)
    valid = np.all(np.isfinite(poses), axis=1)
    if valid.any():
        v = marker_vertices(body)
        mesh = body.mesh
        # skin only the marker vertices (the whole mesh would be F x V x 3)
        out[valid] = linear_blend_skinning(mesh.vertices[v], mesh.joints[v], mesh.weights[v],
                                           body.skin_matrices(poses[valid]))
    return out


def c3d_points(body, poses, joints):
    """The C3D point table.

    Parameters
    ----------
    body : BodyModel
    poses : (F, D) float
    joints : (F, 15, 3) float
        Contract joints, camera frame, metres.

    Returns
    -------
    labels : list of str, (39 + 15,)
    points : (F, 54, 3) float
        z up, millimetres; NaN where unknown.
    """
    joints = np.asarray(joints, float)
    pts = np.concatenate([model_markers(body, poses), joints], axis=1)
    return list(MARKER_NAMES) + list(JOINT_NAMES), (pts @ Z_UP_FROM_CAMERA.T) * MM


def write_c3d(path, body, poses, joints, fps: float) -> Path:
    """Write markers and joints as a C3D file (atomically). See the module docstring."""
    import ezc3d

    labels, pts = c3d_points(body, poses, joints)
    F, N = pts.shape[:2]
    known = np.all(np.isfinite(pts), axis=-1)                     # (F, N)
    data = np.ones((4, N, F))
    data[:3] = np.transpose(pts, (2, 1, 0))
    residuals = np.where(known.T, 0.0, -1.0)[None]                # (1, N, F)
    c3d = ezc3d.c3d()
    c3d["parameters"]["POINT"]["RATE"]["value"] = [float(fps)]
    c3d["parameters"]["POINT"]["LABELS"]["value"] = tuple(labels)
    c3d["parameters"]["POINT"]["UNITS"]["value"] = ["mm"]
    c3d["data"]["points"] = data
    c3d["data"]["meta_points"] = {"residuals": residuals}
    path = Path(path)
    with atomic_path(path) as tmp:
        c3d.write(str(tmp))
    return path
