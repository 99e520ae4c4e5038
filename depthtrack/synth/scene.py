"""The synthetic scene: where the camera stands, the floor and the back wall.

Poses arrive in a *world* frame with our model's axes (y down, so "up" is -y) and
a horizontal floor ``y = floor_y``. The camera stands in front of the subject's
initial heading (:func:`initial_heading`: its left side when it lies; turned by
``azimuth`` about the vertical), at about chest height,
looking slightly down at the middle of the body; the distance grows until the
whole body stays in view (inside the image and the sensor's range) in every frame, or,
for a motion that travels further than the view holds, is the one at which the camera
sees the most of the body, unless the caller fixes it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..body.rotations import matrix_to_rotvec, rotation_about, rotvec_to_matrix
from ..body.skeleton import MODEL_FORWARD

_DOWN = np.array([0.0, 1.0, 0.0])


def transform_poses(poses, world_to_camera) -> np.ndarray:
    """Move pose sequences rigidly: only the pelvis translation and rotation change.

    Parameters
    ----------
    poses : (F, D) float
    world_to_camera : (4, 4) float

    Returns
    -------
    (F, D) float
    """
    T = np.asarray(world_to_camera, float)
    out = np.array(poses, dtype=float)
    out[:, :3] = out[:, :3] @ T[:3, :3].T + T[:3, 3]
    out[:, 3:6] = matrix_to_rotvec(T[:3, :3] @ rotvec_to_matrix(out[:, 3:6]))
    return out


def initial_heading(poses) -> np.ndarray:
    """(3,) unit horizontal direction the camera looks at the subject from (world frame).

    The direction the subject faces in the first frame; when the subject lies (faces the
    ceiling or the floor, so its facing direction is nearly vertical) the direction its
    left side faces instead, so a lying body is seen from the side, as a swimmer is filmed,
    rather than end-on along its length.
    """
    R = rotvec_to_matrix(np.asarray(poses, float)[0, 3:6])
    forward = R @ MODEL_FORWARD
    if abs(forward[1]) > 0.7:
        forward = R @ np.array([1.0, 0.0, 0.0])
    forward[1] = 0.0
    n = np.linalg.norm(forward)
    return forward / n if n > 1e-6 else np.array([0.0, 0.0, -1.0])


def floor_level(body, poses, sample: int = 60) -> float:
    """World y of the floor: where the lowest point of the body is in most frames.

    The 90th percentile over frames of the per-frame lowest vertex (largest y), so
    the feet touch the floor when they should and a jump leaves it.
    """
    poses = np.asarray(poses, float)
    idx = np.unique(np.linspace(0, len(poses) - 1, min(sample, len(poses))).astype(int))
    lowest = np.asarray(body.posed_vertices(poses[idx]))[..., 1].max(axis=1)
    return float(np.percentile(lowest, 90))


@dataclass
class Placement:
    """Camera pose in the world and the scene around the subject.

    Attributes
    ----------
    world_to_camera : (4, 4) float
    position : (3,) float
        Camera centre, world frame.
    distance : float
        Horizontal distance camera to the centre of the ground the pelvis covers, metres.
    height : float
        Camera height above the floor, metres.
    pitch_deg : float
        Downward tilt of the optical axis.
    azimuth_deg : float
    floor_y : float
    wall_distance : float
        Horizontal distance camera to back wall along the view direction, metres: 1 m
        behind the body's farthest point, or nearer (down to 0.3 m behind it) so that
        it stays within the sensor's range.
    in_view : float
        Fraction of (sampled) frames with every body vertex inside the image and range.
    visible : float
        Fraction of the body's vertices over the (sampled) frames inside the image and range.
    """

    world_to_camera: np.ndarray
    position: np.ndarray
    distance: float
    height: float
    pitch_deg: float
    azimuth_deg: float
    floor_y: float
    wall_distance: float
    in_view: float
    visible: float

    def to_dict(self) -> dict:
        return {"world_to_camera": np.round(self.world_to_camera, 6).tolist(),
                "distance_m": round(self.distance, 4), "height_m": round(self.height, 4),
                "pitch_deg": round(self.pitch_deg, 3), "azimuth_deg": self.azimuth_deg,
                "wall_distance_m": round(self.wall_distance, 4), "frames_in_view": round(self.in_view, 4),
                "body_visible": round(self.visible, 4)}


def look_from(position, target) -> np.ndarray:
    """(4, 4) world->camera transform of a camera at ``position`` looking at ``target``, image up = world up."""
    position = np.asarray(position, float)
    z = np.asarray(target, float) - position
    z /= np.linalg.norm(z)
    x = np.cross(_DOWN, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    R = np.stack([x, y, z])              # rows: camera axes in world coordinates
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = -R @ position
    return T


def _visibility(camera, points, margin=2.0, max_depth=np.inf):
    """How much of the body a camera sees, for points (N, V, 3) in the camera frame.

    Returns
    -------
    in_view : float
        Fraction of frames whose points all project inside the image (``margin`` pixels
        in) and lie nearer than ``max_depth``.
    visible : float
        Fraction of all points (every frame) that do.
    """
    z = points[..., 2]
    uv = camera.project(points)
    inside = (z > 0.05) & (z < max_depth) & (uv[..., 0] >= margin) \
        & (uv[..., 0] <= camera.width - 1 - margin) \
        & (uv[..., 1] >= margin) & (uv[..., 1] <= camera.height - 1 - margin)
    return float(np.mean(np.all(inside, axis=1))), float(np.mean(inside))


def place_camera(camera, body, poses, distance=None, azimuth_deg=0.0, height=None,
                 min_distance=2.5, max_distance=12.0, step=0.25, sample=40,
                 max_depth=np.inf, pitch_deg=None) -> Placement:
    """Choose the camera pose for a world-frame pose sequence.

    The camera looks along the reverse of the subject's initial heading (turned by
    ``azimuth_deg``) at the centre of the ground area the pelvis covers, at the middle
    of the body's vertical extent over the motion.

    Parameters
    ----------
    camera : Camera
    body : BodyModel
    poses : (F, D) float
        World frame (y down).
    distance : float or None
        Horizontal distance from the camera to the centre of the motion; ``None`` =
        the smallest multiple of ``step`` from ``min_distance`` at which the whole body
        is in view (and nearer than ``max_depth``) in every sampled frame, or else (a
        motion that travels further than the view holds) the distance at which the
        camera sees the largest share of the body's surface over the motion (up to
        ``max_distance``; ties to the one with the most frames wholly in view). Counting
        whole frames alone would trade a hand leaving the image for the whole body
        beyond the sensor's range.
    azimuth_deg : float
        Turns the camera about the subject (vertical axis) from straight in front.
    height : float or None
        Camera height above the floor; ``None`` = 0.72 x body height (chest).
    max_depth : float
        The sensor's range: a frame with body surface beyond it is not "in view".
    pitch_deg : float or None
        Downward tilt of the optical axis from horizontal (negative: upward); ``None``
        = aim at the middle of the body.
    """
    poses = np.asarray(poses, float)
    H = float(body.height)
    floor_y = floor_level(body, poses)
    heading = initial_heading(poses)
    heading = rotation_about(_DOWN, np.radians(azimuth_deg)) @ heading
    idx = np.unique(np.linspace(0, len(poses) - 1, min(sample, len(poses))).astype(int))
    verts = np.asarray(body.posed_vertices(poses[idx]))
    path = poses[:, :3]
    centre = 0.5 * (path.min(axis=0) + path.max(axis=0))
    centre[1] = floor_y
    cam_height = 0.72 * H if height is None else float(height)
    # Aim at the middle of the body's vertical extent over the motion (raised arms included).
    target = centre.copy()
    target[1] = 0.5 * (verts[..., 1].min() + verts[..., 1].max())

    def build(d):
        position = centre + heading * d - _DOWN * cam_height
        if pitch_deg is None:
            T = look_from(position, target)
        else:
            p = np.radians(float(pitch_deg))
            T = look_from(position, position - np.cos(p) * heading + np.sin(p) * _DOWN)
        pts = verts @ T[:3, :3].T + T[:3, 3]
        return (T, position) + _visibility(camera, pts, max_depth=max_depth)

    if distance is not None:
        d = float(distance)
        T, position, in_view, visible = build(d)
    else:
        best = None
        for d in np.arange(min_distance, max_distance + 1e-9, step):
            candidate = build(float(d)) + (float(d),)
            if candidate[2] >= 1.0:
                best = candidate
                break
            # the share seen to the percent first, then whole frames in view
            if best is None or (round(candidate[3], 2), candidate[2]) > (round(best[3], 2), best[2]):
                best = candidate
        T, position, in_view, visible, d = best
    view = T[2, :3]
    horizontal = view - view[1] * _DOWN
    horizontal /= np.linalg.norm(horizontal)
    # Back wall: 1 m behind the farthest the body gets along the view direction, pulled in
    # to stay inside the sensor's range where that still leaves 0.3 m behind the body.
    reach = float(np.max((verts.reshape(-1, 3) - position) @ horizontal))
    wall = reach + 1.0
    if np.isfinite(max_depth):
        wall = max(min(wall, max_depth - 0.15), reach + 0.3)
    pitch = np.degrees(np.arcsin(np.clip(view @ _DOWN, -1, 1)))
    return Placement(world_to_camera=T, position=position, distance=d, height=cam_height,
                     pitch_deg=float(pitch), azimuth_deg=float(azimuth_deg), floor_y=floor_y,
                     wall_distance=wall, in_view=in_view, visible=visible)


def scene_meshes(placement: Placement, half_width: float = 10.0, wall_height: float = 4.0):
    """Floor and back wall as triangle meshes in the camera frame.

    Returns
    -------
    list of (vertices (4, 3) float32, faces (2, 3) int32)
    """
    T = placement.world_to_camera
    view = T[2, :3]
    forward = view - view[1] * _DOWN
    forward /= np.linalg.norm(forward)
    side = np.cross(_DOWN, forward)
    base = placement.position.copy()
    base[1] = placement.floor_y
    far = base + forward * placement.wall_distance
    up = -_DOWN
    floor = np.stack([base - side * half_width - forward * 1.0, base + side * half_width - forward * 1.0,
                      far + side * half_width, far - side * half_width])
    wall = np.stack([far - side * half_width, far + side * half_width,
                     far + side * half_width + up * wall_height, far - side * half_width + up * wall_height])
    faces = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32)
    out = []
    for quad in (floor, wall):
        cam = quad @ T[:3, :3].T + T[:3, 3]
        out.append((cam.astype(np.float32), faces))
    return out
