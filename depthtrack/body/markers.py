"""Surface markers placed like a Plug-in Gait motion-capture suit on the body mesh.

Each marker is one fixed mesh vertex, so it moves with the skin exactly as the
rendered surface does. The vertex is chosen once, on the zero pose: among the
vertices skinned mainly to the marker's body part(s), the one nearest to a point
0.3 m outside the body from an anatomical anchor in a given direction (so it lies
on the surface facing that way). Names follow Vicon Plug-in Gait (full body, 39).
"""
from __future__ import annotations

import numpy as np

from ..contract import JOINT_INDEX as C

# Model frame: left = +x, up = -y, forward = -z.
_L, _R, _UP, _DOWN, _FWD, _BACK = (1, 0, 0), (-1, 0, 0), (0, -1, 0), (0, 1, 0), (0, 0, -1), (0, 0, 1)


def _mix(*terms):
    v = np.zeros(3)
    for w, d in terms:
        v += w * np.asarray(d, float)
    return v / np.linalg.norm(v)


def _side_markers(s, lat):
    """Marker table rows for one side: s = "l"/"r", lat = its outward direction."""
    S = s.upper()
    return [
        (f"{S}FHD", ("neck",), ("head",), _mix((0.45, lat), (0.35, _UP), (1, _FWD))),
        (f"{S}BHD", ("neck",), ("head",), _mix((0.45, lat), (0.35, _UP), (1, _BACK))),
        (f"{S}SHO", (f"{s}_shoulder", "spine"), (f"{s}_shoulder",), _mix((1, _UP), (0.3, lat), (0.2, _BACK))),
        (f"{S}UPA", (f"{s}_shoulder",), (f"{s}_shoulder", f"{s}_elbow"), _mix((1, lat), (0.6, _BACK))),
        (f"{S}ELB", (f"{s}_shoulder", f"{s}_elbow"), (f"{s}_elbow",), _mix((0.6, lat), (1, _BACK))),
        (f"{S}FRM", (f"{s}_elbow",), (f"{s}_elbow", f"{s}_wrist"), _mix((1, lat), (0.3, _BACK))),
        (f"{S}WRA", (f"{s}_elbow", f"{s}_wrist"), (f"{s}_wrist",), _mix((1, _FWD), (0.3, lat))),
        (f"{S}WRB", (f"{s}_elbow", f"{s}_wrist"), (f"{s}_wrist",), _mix((1, _BACK), (0.3, lat))),
        (f"{S}FIN", (f"{s}_wrist",), (f"{s}_wrist", "+hand"), _mix((1, lat), (0.5, _DOWN))),
        (f"{S}ASI", ("pelvis",), (f"{s}_hip", "+up"), _mix((0.5, lat), (1, _FWD))),
        (f"{S}PSI", ("pelvis",), (f"{s}_hip", "+up"), _mix((0.25, lat), (1, _BACK))),
        (f"{S}THI", (f"{s}_hip",), (f"{s}_hip", f"{s}_knee"), _mix((1, lat), (0.3, _FWD))),
        (f"{S}KNE", (f"{s}_hip", f"{s}_knee"), (f"{s}_knee",), _mix((1, lat),)),
        (f"{S}TIB", (f"{s}_knee",), (f"{s}_knee", f"{s}_ankle"), _mix((1, lat), (0.3, _FWD))),
        (f"{S}ANK", (f"{s}_knee", f"{s}_ankle"), (f"{s}_ankle",), _mix((1, lat),)),
        (f"{S}HEE", (f"{s}_ankle",), (f"{s}_ankle",), _mix((1, _BACK), (0.4, _DOWN))),
        (f"{S}TOE", (f"{s}_ankle",), (f"{s}_ankle", "+toe"), _mix((1, _FWD), (0.3, _UP))),
    ]


#: (name, skeleton joints whose vertices may carry it, anchor, outward direction).
#: The anchor is the mean of contract joints, with "+hand" / "+toe" / "+up"
#: shifting it along the hand, to the toes, or up to the pelvic crest.
MARKER_TABLE = (
    _side_markers("l", _L)[:2] + _side_markers("r", _R)[:2] + [
        ("C7", ("neck", "spine"), ("neck",), _mix((1, _BACK), (0.4, _UP))),
        ("T10", ("spine",), ("spine",), _mix((1, _BACK),)),
        ("CLAV", ("spine", "neck"), ("neck",), _mix((1, _FWD), (0.5, _DOWN))),
        ("STRN", ("spine",), ("spine",), _mix((1, _FWD),)),
        ("RBAK", ("spine",), ("r_shoulder", "spine"), _mix((1, _BACK), (0.3, _R))),
    ] + _side_markers("l", _L)[2:] + _side_markers("r", _R)[2:]
)

MARKER_NAMES = tuple(row[0] for row in MARKER_TABLE)


def _anchor(spec, rest, spine, height):
    """Anchor point (3,) of a marker from rest contract joints ``rest (15, 3)``."""
    points, shift = [], np.zeros(3)
    for name in spec:
        if name == "+hand":       # half a hand past the wrist named before it
            wrist = spec[0]
            elbow = wrist.replace("wrist", "elbow")
            shift += 0.05 * height * _unit(rest[C[wrist]] - rest[C[elbow]])
        elif name == "+toe":
            shift += np.array([0.0, 0.02, -0.09]) * height
        elif name == "+up":
            shift += np.array([0.0, -0.06, 0.0]) * height
        elif name == "spine":
            points.append(spine)
        else:
            points.append(rest[C[name]])
    return np.mean(points, axis=0) + shift


def _unit(v):
    return v / np.linalg.norm(v)


def marker_vertices(body) -> np.ndarray:
    """(M,) int: the mesh vertex of each marker in :data:`MARKER_NAMES` for this body.

    The choice is made on the body's own zero pose, so a rescaled body (same mesh)
    gets the same vertices.
    """
    zero = np.zeros(body.dof)
    verts = np.asarray(body.posed_vertices(zero), float)
    rest = np.asarray(body.joint_positions(zero), float)
    spine = np.asarray(body.world_transforms(zero))[body.joint_names.index("spine"), :3, 3]
    weights = np.asarray(body.mesh.weights)
    owners = np.asarray(body.mesh.joints)[np.arange(len(verts)), np.argmax(weights, axis=1)]
    height = float(body.height)
    names = list(body.joint_names)
    chosen = []
    for name, parts, anchor_spec, direction in MARKER_TABLE:
        allowed = np.isin(owners, [names.index(p) for p in parts])
        target = _anchor(anchor_spec, rest, spine, height) + 0.3 * direction
        distance = np.linalg.norm(verts - target, axis=1)
        distance[~allowed] = np.inf
        chosen.append(int(np.argmin(distance)))
    return np.asarray(chosen)


def marker_positions(body, poses, vertices=None) -> np.ndarray:
    """(N, M, 3) float: marker positions (camera frame) for poses ``(N, D)``."""
    vertices = marker_vertices(body) if vertices is None else vertices
    return np.asarray(body.posed_vertices(np.atleast_2d(poses)))[:, vertices]


def vertex_normals(vertices, faces) -> np.ndarray:
    """Area-weighted unit vertex normals.

    Parameters
    ----------
    vertices : (V, 3) float
    faces : (F, 3) int

    Returns
    -------
    (V, 3) float
    """
    v = np.asarray(vertices, float)
    f = np.asarray(faces)
    face_n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    normals = np.zeros_like(v)
    for k in range(3):
        np.add.at(normals, f[:, k], face_n)
    return normals / np.maximum(np.linalg.norm(normals, axis=-1, keepdims=True), 1e-12)
