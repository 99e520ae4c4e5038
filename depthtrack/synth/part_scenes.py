"""Synthetic depth frames with known answers, for training and testing the detectors.

A body pose (world frame, y down, floor horizontal) is placed in front of a camera the
way the synthesizer does it (:func:`depthtrack.synth.scene.place_camera`: chest-high
camera looking slightly down, a floor and a back wall), rendered with
:class:`depthtrack.render.FrameRenderer`, optionally made noisy, and returned with the
true person mask, the floor plane and the contract joints in the camera frame.

:func:`render_part_frame` renders a camera-frame pose alone (no room) with the per-pixel
body-part labels of :mod:`depthtrack.detect.recognizer_parts`, for the recogniser.

Only the training tools (``tools/train_part_classifier.py``, ``tools/train_recognizer.py``)
and the tests use this module; run-time detection never imports it (it needs OpenGL).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class SceneFrame:
    """One rendered frame with its ground truth.

    Attributes
    ----------
    depth : (H, W) float32
        Camera z, metres (noisy when noise was asked for); 0 = no reading.
    mask : (H, W) bool
        Pixels where the body is the visible surface.
    floor_plane : (4,) float
        Unit normal pointing up and offset, camera frame: ``n . p + d`` = height above floor.
    joints : (15, 3) float
        Contract joints (JOINT_NAMES order), camera frame.
    pose : (48,) float
        The body pose in the camera frame.
    labels : (H, W) int16 or None
        Skeleton joint whose bone is seen per pixel (-1 = not the body), when asked for.
    ideal : (H, W) float32 or None
        The depth before noise (None when no noise was applied: ``depth`` is ideal).
    """

    depth: np.ndarray
    mask: np.ndarray
    floor_plane: np.ndarray
    joints: np.ndarray
    pose: np.ndarray
    labels: np.ndarray | None = None
    ideal: np.ndarray | None = None

    def readable_mask(self, tolerance: float = 0.05) -> np.ndarray:
        """(H, W) bool: person pixels whose (noisy) reading stayed within ``tolerance`` m of the
        ideal depth -- the mask a segmenter can be asked to find (flying pixels and dropouts
        on the person read something else)."""
        if self.ideal is None:
            return self.mask.copy()
        return self.mask & (self.depth > 0) & (np.abs(self.depth - self.ideal) < tolerance)


def floor_plane_of(placement) -> np.ndarray:
    """The floor ``(4,)`` of a :class:`~depthtrack.synth.scene.Placement` in its camera frame."""
    T = placement.world_to_camera
    up_world = np.array([0.0, -1.0, 0.0])
    n = T[:3, :3] @ up_world
    on_floor = T[:3, :3] @ np.array([0.0, placement.floor_y, 0.0]) + T[:3, 3]
    return np.append(n, -n @ on_floor)


def render_scene_frames(body, world_poses, camera, renderer=None, noise=None, rng=None, distance=None,
                        azimuth=0.0, camera_height=None, roll_deg=0.0, scenery=True, labels=False):
    """Render world-frame poses in a room seen by one fixed camera placement.

    Parameters
    ----------
    body : BodyModel
    world_poses : (F, 48) float
        World frame (y down, facing -z at rest), feet near the floor.
    camera : Camera
    renderer : FrameRenderer, optional
    noise : ToFNoise or None
        Applied to the depth with ``rng``.
    distance, azimuth, camera_height : see :func:`depthtrack.synth.scene.place_camera`.
    roll_deg : float
        Extra camera roll about its optical axis (the floor then tilts sideways in the image).
    scenery : bool
        Draw the floor and the back wall.
    labels : bool
        Also render the per-pixel bone labels.

    Returns
    -------
    list of SceneFrame
    """
    from ..render import FrameRenderer

    world_poses = np.atleast_2d(np.asarray(world_poses, dtype=float))
    owned = FrameRenderer(camera) if renderer is None else None
    renderer = owned or renderer
    try:
        return _render_frames(body, world_poses, camera, renderer, noise, rng, distance, azimuth,
                              camera_height, roll_deg, scenery, labels)
    finally:
        if owned is not None:               # a renderer the caller gave stays the caller's
            owned.release()


def _render_frames(body, world_poses, camera, renderer, noise, rng, distance, azimuth,
                   camera_height, roll_deg, scenery, labels):
    from .scene import place_camera, scene_meshes, transform_poses

    rng = np.random.default_rng(0) if rng is None else rng
    placement = place_camera(camera, body, world_poses, distance=distance, azimuth_deg=azimuth,
                             height=camera_height,
                             max_depth=getattr(noise, "max_range", np.inf) if noise is not None else np.inf)
    if roll_deg:
        from ..body.rotations import rotvec_to_matrix

        roll = np.eye(4)
        roll[:3, :3] = rotvec_to_matrix(np.array([0.0, 0.0, np.radians(roll_deg)]))
        placement.world_to_camera = roll @ placement.world_to_camera
    poses = transform_poses(world_poses, placement.world_to_camera)
    meshes = scene_meshes(placement) if scenery else []
    plane = floor_plane_of(placement)
    joints = np.asarray(body.joint_positions(poses))
    frames = []
    for pose, joint in zip(poses, joints):
        body_only = renderer.render(body, pose)
        depth = renderer.render(body, pose, extra_meshes=meshes) if scenery else body_only
        mask = (body_only > 0) & (np.abs(depth - body_only) < 1e-4)
        ideal = None
        if noise is not None:
            ideal = np.asarray(depth, np.float32)
            depth = noise.apply(depth, rng)
        label_image = renderer.render_labels(body, pose) if labels else None
        frames.append(SceneFrame(np.asarray(depth, np.float32), mask, plane, joint, pose, label_image, ideal))
    return frames


#: Skeleton joints (BodyModel order) whose bones make up each detectable part.
PART_BONES = {"head": ("neck",), "hand": ("l_wrist", "r_wrist"), "foot": ("l_ankle", "r_ankle")}


def extremum_truth(label_image, pixels, joint_names, window: int = 2) -> np.ndarray:
    """True class of extrema from a bone-label image: head, hand, foot or other.

    The majority bone label among body pixels in a ``(2 window + 1)^2`` window around each
    extremum pixel decides (flying pixels at the silhouette carry no label themselves).

    Parameters
    ----------
    label_image : (H, W) int
        Skeleton joint index per pixel, -1 = not the body.
    pixels : (K, 2) int
        Extremum pixels ``(u, v)``.
    joint_names : sequence of str
        The skeleton's joint names (``body.joint_names``).

    Returns
    -------
    (K,) str array
    """
    names = list(joint_names)
    bone_class = np.array(["other"] * len(names), dtype=object)
    for part, bones in PART_BONES.items():
        for b in bones:
            bone_class[names.index(b)] = part
    H, W = label_image.shape
    out = np.array(["other"] * len(pixels), dtype=object)
    for i, (u, v) in enumerate(np.asarray(pixels, int)):
        w = label_image[max(0, v - window):v + window + 1, max(0, u - window):u + window + 1]
        w = w[w >= 0]
        if len(w):
            out[i] = bone_class[np.bincount(w).argmax()]
    return out


def render_part_frame(body, pose, camera, renderer, noise=None, rng=None, wall_gap=None) -> SceneFrame:
    """Render a camera-frame pose with per-pixel body-part labels (the recogniser's training frames).

    Parameters
    ----------
    body : BodyModel
    pose : (48,) float
        Camera frame.
    camera : Camera
    renderer : FrameRenderer
    noise : ToFNoise or None
        Applied with ``rng``; a wall ``wall_gap`` m behind the body's farthest joint gives
        the silhouette its flying pixels, and is then removed (the person mask excludes it).
    wall_gap : float or None
        None = no wall.

    Returns
    -------
    SceneFrame
        ``labels`` holds :data:`depthtrack.detect.recognizer_parts.BODY_PARTS` indices (int8,
        -1 off the person); ``mask`` the person pixels whose reading stayed within 5 cm of the
        ideal depth; ``depth`` has readings on the person only (0 elsewhere).
    """
    from ..detect.recognizer_parts import part_labels

    pose = np.asarray(pose, float)
    rng = np.random.default_rng(0) if rng is None else rng
    bones = renderer.render_labels(body, pose)
    body_depth = renderer.render(body, pose)
    joints = np.asarray(body.joint_positions(pose))
    meshes = []
    if wall_gap is not None:
        z = float(joints[:, 2].max() + wall_gap)
        half = 20.0 * z
        quad = np.array([[-half, -half, z], [half, -half, z], [half, half, z], [-half, half, z]], np.float32)
        meshes = [(quad, np.array([[0, 1, 2], [0, 2, 3]], np.int32))]
    depth = renderer.render(body, pose, extra_meshes=meshes) if meshes else body_depth
    body_mask = bones >= 0
    ideal = np.asarray(depth, np.float32)
    if noise is not None:
        depth = noise.apply(depth, rng)
    depth = np.asarray(depth, np.float32)
    mask = body_mask & (depth > 0) & (np.abs(depth - body_depth) < 0.05)
    transforms = np.asarray(body.world_transforms(pose))
    points = camera.backproject(np.where(body_mask, body_depth, 0.0))
    parts = part_labels(bones, points, transforms, joints[0], scale=float(body.height) / 1.75)
    parts[~body_mask] = -1
    depth = np.where(mask, depth, np.float32(0.0))
    plane = np.full(4, np.nan)       # no floor in these frames
    return SceneFrame(depth, mask, plane, joints, pose, parts, ideal)
