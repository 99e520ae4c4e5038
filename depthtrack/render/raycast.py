"""CPU ray casting: the independent reference the GL renderers are tested against."""
from __future__ import annotations

import numpy as np

from ..camera import Camera


def raycast_depth(vertices, faces, camera: Camera, return_faces: bool = False):
    """Camera z of the first surface hit through every pixel centre (trimesh ray cast).

    Parameters
    ----------
    vertices : (V, 3) float
        Triangle mesh vertices in the camera frame.
    faces : (F, 3) int
    camera : Camera
    return_faces : bool
        Also return the index of the face hit per pixel (-1 = none).

    Returns
    -------
    depth : (H, W) float64, 0 where no surface is hit
    face : (H, W) int, only with ``return_faces``
    """
    import trimesh

    mesh = trimesh.Trimesh(np.asarray(vertices, float), np.asarray(faces), process=False)
    rays = camera.rays().reshape(-1, 3)
    locations, ray_index, face_index = mesh.ray.intersects_location(
        np.zeros_like(rays), rays, multiple_hits=False)
    depth = np.zeros(len(rays))
    depth[ray_index] = locations[:, 2]
    face = np.full(len(rays), -1)
    face[ray_index] = face_index
    if return_faces:
        return depth.reshape(camera.shape), face.reshape(camera.shape)
    return depth.reshape(camera.shape)
