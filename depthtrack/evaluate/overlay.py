"""Overlay videos: the depth frames with the fitted model's silhouette and skeleton drawn on.

Each frame shows the measured depth (colour-mapped, no reading = black), the fitted body
rendered with :class:`depthtrack.render.FrameRenderer` as a translucent fill with a solid
outline, and the 15 contract joints (``body.joint_positions`` projected with
``camera.project``) joined by bones: the subject's left in cyan, right in orange, the
trunk in yellow. Frames are upscaled (nearest neighbour) so a 176 x 144 image stays
readable.

``write_overlay`` writes MP4 (OpenCV's ``mp4v`` encoder) or GIF (Pillow), chosen by the
file extension.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..io.atomic import atomic_path

#: Contract-joint pairs drawn as bones.
BONES = (
    ("head", "neck"), ("neck", "pelvis"),
    ("neck", "l_shoulder"), ("l_shoulder", "l_elbow"), ("l_elbow", "l_wrist"),
    ("neck", "r_shoulder"), ("r_shoulder", "r_elbow"), ("r_elbow", "r_wrist"),
    ("pelvis", "l_hip"), ("l_hip", "l_knee"), ("l_knee", "l_ankle"),
    ("pelvis", "r_hip"), ("r_hip", "r_knee"), ("r_knee", "r_ankle"),
)

#: RGB colours.
SILHOUETTE_RGB = (60, 220, 90)
SILHOUETTE_ALPHA = 0.4
LEFT_RGB = (0, 220, 255)
RIGHT_RGB = (255, 140, 0)
TRUNK_RGB = (255, 230, 0)
JOINT_RGB = (255, 0, 200)
#: Joint dot radius in output pixels.
JOINT_RADIUS = 3
#: Overlays are upscaled until they are at least this wide.
MIN_WIDTH = 480


def upscale_factor(width: int) -> int:
    """Integer nearest-neighbour upscale that makes an image ``width`` pixels wide >= MIN_WIDTH."""
    return max(1, math.ceil(MIN_WIDTH / width))


def _side_colour(a: str, b: str):
    if a.startswith("l_") or b.startswith("l_"):
        return LEFT_RGB
    if a.startswith("r_") or b.startswith("r_"):
        return RIGHT_RGB
    return TRUNK_RGB


def colour_depth(depth, near: float, far: float) -> np.ndarray:
    """Colour-map a depth image: near bright, far dark, no reading black.

    Parameters
    ----------
    depth : (H, W) float
        Metres, 0 = no reading.
    near, far : float
        The depths mapped to the ends of the colour map.

    Returns
    -------
    rgb : (H, W, 3) uint8
    """
    from matplotlib import colormaps

    depth = np.asarray(depth, dtype=np.float64)
    valid = np.isfinite(depth) & (depth > 0)
    t = np.clip((far - depth) / max(far - near, 1e-6), 0.0, 1.0)
    # bone: grey-blue, leaves the green silhouette and bright skeleton colours distinct
    rgb = (colormaps["bone"](0.15 + 0.85 * t)[..., :3] * 255).astype(np.uint8)
    rgb[~valid] = 0
    return rgb


def to_output_pixels(uv, scale: int) -> np.ndarray:
    """Camera pixel coordinates ``(..., 2)`` to pixel centres of the ``scale``-times upscaled image."""
    return np.asarray(uv, dtype=np.float64) * scale + (scale - 1) / 2.0


def overlay_frame(depth_rgb, mask, joints_uv, scale: int, label: str | None = None) -> np.ndarray:
    """Draw one overlay frame.

    Parameters
    ----------
    depth_rgb : (H, W, 3) uint8
        The colour-mapped depth (:func:`colour_depth`).
    mask : (H, W) bool or None
        Where the fitted model is rendered; ``None`` = no model this frame.
    joints_uv : (15, 2) float or None
        Projected contract joints (camera pixels, ``JOINT_NAMES`` order); NaN rows are skipped.
    scale : int
        Nearest-neighbour upscale.
    label : str or None
        Text in the top-left corner.

    Returns
    -------
    rgb : (H * scale, W * scale, 3) uint8
        Inside the upscaled mask: the silhouette colour blended at SILHOUETTE_ALPHA over the
        depth, its inner boundary pixels solid; outside: the depth; skeleton on top.
    """
    import cv2

    from ..contract import JOINT_INDEX

    img = np.repeat(np.repeat(np.asarray(depth_rgb, np.uint8), scale, axis=0), scale, axis=1)
    if mask is not None:
        big = np.repeat(np.repeat(np.asarray(mask, bool), scale, axis=0), scale, axis=1)
        colour = np.array(SILHOUETTE_RGB, np.float64)
        blend = (1 - SILHOUETTE_ALPHA) * img[big] + SILHOUETTE_ALPHA * colour
        img[big] = np.rint(blend).astype(np.uint8)
        inner = cv2.erode(big.astype(np.uint8), np.ones((3, 3), np.uint8), borderValue=0).astype(bool)
        img[big & ~inner] = SILHOUETTE_RGB
    if joints_uv is not None:
        pts = to_output_pixels(joints_uv, scale)
        ok = np.all(np.isfinite(pts), axis=1) & np.all(np.abs(pts) < 1e5, axis=1)
        # cv2 draws in the array's own channel order, so RGB colours go in as given
        img = np.ascontiguousarray(img)
        thickness = max(1, scale // 2)
        for a, b in BONES:
            i, j = JOINT_INDEX[a], JOINT_INDEX[b]
            if ok[i] and ok[j]:
                cv2.line(img, _cv_point(pts[i]), _cv_point(pts[j]), _side_colour(a, b), thickness,
                         cv2.LINE_AA)
        for k in np.flatnonzero(ok):
            cv2.circle(img, _cv_point(pts[k]), JOINT_RADIUS, JOINT_RGB, -1, cv2.LINE_8)
    if label:
        cv2.putText(img, label, (4, 14), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (255, 255, 255), 1, cv2.LINE_AA)
    return img


def _cv_point(p):
    return int(round(p[0])), int(round(p[1]))


def depth_range(seq, frames=None):
    """``(near, far)`` metres for the colour map: 2nd and 98th percentile of the valid depths
    of up to 5 frames spread over the sequence."""
    n = len(seq)
    picks = np.unique(np.linspace(0, n - 1, min(5, n)).round().astype(int)) if frames is None else frames
    values = np.concatenate([d[d > 0] for d in (seq.depth(int(i)) for i in picks)] + [np.zeros(0)])
    if not len(values):
        return 0.5, 5.0
    near, far = np.percentile(values, [2, 98])
    return float(near), float(max(far, near + 0.1))


def overlay_frames(seq, poses, body, camera=None, label=True):
    """Yield the overlay frames of a sequence, one ``(H*s, W*s, 3)`` uint8 RGB image per frame.

    Parameters
    ----------
    seq : depthtrack.io.sequence.Sequence
    poses : (F, D) float
        Fitted poses, one per frame; a NaN row draws the depth alone.
    body : BodyModel
    camera : Camera or None
        Default ``seq.camera``.
    label : bool
        Write the frame number in the corner.
    """
    from ..render import FrameRenderer

    camera = camera or seq.camera
    poses = np.asarray(poses, dtype=np.float64)
    if poses.ndim != 2 or len(poses) != len(seq):
        raise InputError(getattr(seq, "path", None), f"poses must be ({len(seq)}, D), not {poses.shape}")
    if camera.shape != seq.camera.shape:
        raise InputError(getattr(seq, "path", None), f"camera is {camera.width} x {camera.height}, "
                                                     f"frames are {seq.camera.width} x {seq.camera.height}")
    scale = upscale_factor(camera.width)
    near, far = depth_range(seq)
    renderer = FrameRenderer(camera)
    valid = np.all(np.isfinite(poses), axis=1)
    joints_uv = np.full((len(poses), 15, 2), np.nan)
    if valid.any():
        joints_uv[valid] = camera.project(body.joint_positions(poses[valid]))
    try:
        for i in range(len(seq)):
            rgb = colour_depth(seq.depth(i), near, far)
            mask = renderer.render(body, poses[i]) > 0 if valid[i] else None
            yield overlay_frame(rgb, mask, joints_uv[i] if valid[i] else None, scale,
                                f"frame {i}" if label else None)
    finally:
        renderer.release()


def _even(img):
    """Pad to even width and height (many MP4 decoders want it)."""
    h, w = img.shape[:2]
    if h % 2 or w % 2:
        img = np.pad(img, ((0, h % 2), (0, w % 2), (0, 0)))
    return img


def _write_mp4(path: Path, frames, fps: float) -> bool:
    import cv2

    writer = None
    count = 0
    try:
        for rgb in frames:
            rgb = _even(rgb)
            if writer is None:
                writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), float(fps),
                                         (rgb.shape[1], rgb.shape[0]))
                if not writer.isOpened():
                    return False
            writer.write(cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))
            count += 1
    finally:
        if writer is not None:
            writer.release()
    return count > 0 and path.is_file() and path.stat().st_size > 0


def _write_gif(path: Path, frames, fps: float) -> None:
    from PIL import Image

    images = [Image.fromarray(rgb) for rgb in frames]
    if not images:
        raise ValueError("no frames to write")
    images[0].save(path, format="GIF", save_all=True, append_images=images[1:],
                   duration=max(20, int(round(1000.0 / fps))), loop=0)


class _NoEncoder(Exception):
    pass


def write_overlay(path, seq, poses, body, camera=None, fps=None) -> Path:
    """Write the overlay video of a track.

    Parameters
    ----------
    path : path-like
        ``.mp4`` (OpenCV ``mp4v``) or ``.gif``; written atomically.
    seq : Sequence
    poses : (F, D) float
        Fitted poses, NaN rows where the track has none.
    body : BodyModel
        The tracked body.
    camera : Camera or None
        Default ``seq.camera``.
    fps : float or None
        Playback rate; default ``seq.fps``.

    Returns
    -------
    pathlib.Path
        The file written. If this OpenCV build cannot encode MP4, a GIF beside it
        (``path`` with the suffix ``.gif``).
    """
    path = Path(path)
    fps = float(fps or seq.fps)
    suffix = path.suffix.lower()
    if suffix not in (".mp4", ".gif"):
        raise InputError(path, "overlay must be a .mp4 or .gif file")
    if suffix == ".mp4":
        try:
            with atomic_path(path) as tmp:
                # frames stream straight into the encoder: long sequences need no memory
                if not _write_mp4(Path(tmp), overlay_frames(seq, poses, body, camera), fps):
                    raise _NoEncoder()
            return path
        except _NoEncoder:
            # this OpenCV build has no MP4 encoder: say so through the returned name
            path = path.with_suffix(".gif")
    with atomic_path(path) as tmp:
        _write_gif(Path(tmp), overlay_frames(seq, poses, body, camera), fps)
    return path


__all__ = ["write_overlay", "overlay_frames", "overlay_frame", "colour_depth", "depth_range",
           "upscale_factor", "to_output_pixels", "BONES"]
