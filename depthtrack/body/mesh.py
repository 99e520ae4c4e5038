"""A triangle mesh with a linear-blend skin, and the numpy skinning reference."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class SkinnedMesh:
    """A closed triangle mesh bound to the skeleton.

    Attributes
    ----------
    vertices : (V, 3) float32
        Bind-pose positions in the model frame (metres).
    faces : (F, 3) int32
        Counter-clockwise seen from outside (outward normals).
    joints : (V, 4) int32
        Skeleton joint indices of the four influences per vertex.
    weights : (V, 4) float32
        Influence weights; rows sum to 1.
    inverse_bind : (J, 4, 4) float64
        Maps model-frame bind positions into each joint's frame.
    name : str
        Where the mesh came from ("default-full", a file name, ...).
    """

    vertices: np.ndarray
    faces: np.ndarray
    joints: np.ndarray
    weights: np.ndarray
    inverse_bind: np.ndarray
    name: str = field(default="mesh")

    def __post_init__(self):
        object.__setattr__(self, "vertices", np.ascontiguousarray(self.vertices, dtype=np.float32))
        object.__setattr__(self, "faces", np.ascontiguousarray(self.faces, dtype=np.int32))
        object.__setattr__(self, "joints", np.ascontiguousarray(self.joints, dtype=np.int32))
        object.__setattr__(self, "weights", np.ascontiguousarray(self.weights, dtype=np.float32))
        object.__setattr__(self, "inverse_bind", np.ascontiguousarray(self.inverse_bind, dtype=np.float64))
        v, f = self.vertices, self.faces
        if v.ndim != 2 or v.shape[1] != 3 or f.ndim != 2 or f.shape[1] != 3:
            raise ValueError("vertices must be (V, 3) and faces (F, 3)")
        if self.joints.shape != (len(v), 4) or self.weights.shape != (len(v), 4):
            raise ValueError("joints and weights must be (V, 4)")

    @property
    def num_vertices(self) -> int:
        return len(self.vertices)

    @property
    def num_faces(self) -> int:
        return len(self.faces)

    def vertex_normals(self, vertices=None):
        """Area-weighted unit vertex normals ``(V, 3)`` of ``vertices`` (default: bind pose)."""
        v = self.vertices if vertices is None else np.asarray(vertices)
        return vertex_normals(v, self.faces)

    def dominant_joint(self):
        """Index of the joint with the largest weight per vertex ``(V,)``."""
        return self.joints[np.arange(len(self.joints)), np.argmax(self.weights, axis=1)]


def vertex_normals(vertices, faces):
    """Area-weighted unit normals ``(..., V, 3)`` of ``vertices (..., V, 3)`` with ``faces (F, 3)``."""
    v = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64)
    n_vert = v.shape[-2]
    flat = v.reshape(-1, n_vert, 3)
    a, b, c = flat[:, faces[:, 0]], flat[:, faces[:, 1]], flat[:, faces[:, 2]]
    face_normals = np.cross(b - a, c - a)  # (B, F, 3), length = 2 * area
    batch = len(flat)
    # scatter every face normal onto its three corners, all batches at once
    target = (np.arange(batch)[:, None, None] * n_vert + faces[None]).reshape(-1)  # (B*F*3,)
    values = np.repeat(face_normals, 3, axis=1).reshape(-1, 3)
    n = np.stack([np.bincount(target, values[:, i], minlength=batch * n_vert) for i in range(3)], -1)
    n = n.reshape(v.shape)
    length = np.linalg.norm(n, axis=-1, keepdims=True)
    return n / np.where(length > 0, length, 1.0)


def linear_blend_skinning(vertices, joints, weights, skin_matrices):
    """Pose bind vertices with per-joint skin matrices (linear-blend skinning).

    Parameters
    ----------
    vertices : (V, 3) float
        Bind-pose positions.
    joints, weights : (V, K) int, (V, K) float
        Influences per vertex.
    skin_matrices : (N, J, 4, 4) float
        ``world @ scale @ inverse_bind`` per joint and pose.

    Returns
    -------
    (N, V, 3) float64: ``sum_k w_k * (M[j_k] @ [v, 1])``.
    """
    v = np.asarray(vertices, dtype=np.float64)
    m = np.asarray(skin_matrices, dtype=np.float64)
    w = np.asarray(weights, dtype=np.float64)
    joints = np.asarray(joints, dtype=np.int64)
    n_pose, n_joint = m.shape[:2]
    out = np.empty((n_pose, len(v), 3))
    rows = np.arange(len(v))
    # move every vertex by every joint (one matmul), then gather each vertex's influences;
    # chunks keep the (n, J, 3, V) intermediate to about 32 MB
    chunk = max(1, int(4e6 // max(1, n_joint * 3 * len(v))))
    for s in range(0, n_pose, chunk):
        mc = m[s:s + chunk]
        # one (n*J*3, 3) @ (3, V) product: much faster than a stack of 3x3 products
        moved = (mc[:, :, :3, :3].reshape(-1, 3) @ v.T).reshape(len(mc), n_joint, 3, len(v))
        moved += mc[:, :, :3, 3:4]  # (n, J, 3, V)
        acc = np.zeros((len(v), len(mc), 3))
        for k in range(joints.shape[1]):
            acc += w[:, k, None, None] * moved[:, joints[:, k], :, rows]  # (V, n, 3)
        out[s:s + chunk] = acc.transpose(1, 0, 2)
    return out
