"""Stage "observe": from a depth frame and its foreground to what candidates are scored on.

:func:`observe` is pure (numpy in, a :class:`Frame` out); the GL parts around it (the
predicted pose's silhouette, the upload into the renderers) are the tracker's
(:class:`~.renderers.RendererSet`). The image functions themselves are in :mod:`.observation`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

from ..errors import InputError
from .observation import observation_image, square_roi, visible_area


@dataclass
class Frame:
    """One observed frame.

    Attributes
    ----------
    depth : (H, W) float32
        Metres, 0 = no reading.
    foreground : Foreground
        The segmentation (``mask``, ``points``, ``floor_plane``).
    observed : (H, W) float32
        The observation image (:func:`~.observation.observation_image`).
    roi : (u0, v0, size)
        Square region of interest in camera pixels.
    weight : float
        ``likelihood_weight * size^2``: the energy's weight of the mean tile cost.
    detections : list of Detection or None
        Filled once by the associate stage (:func:`~.propagate.frame_detections`).
    proposals : JointProposals or None
        The recogniser's joint proposals, filled once (:func:`~.proposals.frame_proposals`).
    """

    depth: np.ndarray
    foreground: object
    observed: np.ndarray
    roi: tuple
    weight: float
    detections: list | None = field(default=None, repr=False)
    proposals: object = field(default=None, repr=False)


def as_depth(depth, camera) -> np.ndarray:
    """``depth`` as (H, W) float32, checked against the camera."""
    depth = np.asarray(depth, dtype=np.float32)
    if depth.shape != camera.shape:
        raise InputError(None, f"depth frame is {depth.shape[1]} x {depth.shape[0]}, camera is "
                               f"{camera.width} x {camera.height}")
    return depth


def person_present(foreground, camera, settings) -> bool:
    """Whether a foreground holds a person (:attr:`ObserveSettings.min_person_area`)."""
    return visible_area(foreground, camera) >= settings.observe.min_person_area


def observe(depth, foreground, camera, settings, roi=None, floor=None, predicted_joints=None,
            predicted_silhouette=None):
    """The observation of one frame.

    The observation keeps the raw depth of every pixel that may be the person, so a
    segmentation that misses a limb does not forbid the model to cover it: only pixels on
    the floor plane or outside the person's depth band are background
    (:func:`observation_image`). The ROI covers the foreground's box and the predicted
    joints (when given), with a margin.

    Parameters
    ----------
    depth : (H, W) float32
    foreground : Foreground
    camera : Camera
    settings : TrackerSettings
    roi : (u0, v0, size) or None
        The previous ROI, kept when the foreground is empty.
    floor : (4,) float or None
        The previous floor plane, kept when the segmentation found none.
    predicted_joints : (J, 3) float or None
    predicted_silhouette : (H, W) bool or None
        Where the predicted pose covers the image.

    Returns
    -------
    frame : Frame
    floor : (4,) float or None
        The floor plane now known.
    """
    s = settings.observe
    mask = np.asarray(foreground.mask, dtype=bool)
    plane = getattr(foreground, "floor_plane", None)
    if plane is not None:
        floor = np.asarray(plane, dtype=np.float64)
    joints = predicted_joints
    box = mask.copy()
    if joints is not None:
        uv = camera.project(joints)
        ok = np.all(np.isfinite(uv), axis=1) & (joints[:, 2] > 0)
        if ok.any():
            pad = s.predicted_margin * camera.fx / float(np.median(joints[ok, 2]))
            lo = np.floor(uv[ok].min(axis=0) - pad).astype(int)
            hi = np.ceil(uv[ok].max(axis=0) + pad).astype(int)
            lo = np.clip(lo, 0, [camera.width - 1, camera.height - 1])
            hi = np.clip(hi, 0, [camera.width - 1, camera.height - 1])
            box[lo[1]:hi[1] + 1, lo[0]] = True
            box[lo[1]:hi[1] + 1, hi[0]] = True
    new_roi = square_roi(box, s.roi_margin)
    if new_roi is None:
        new_roi = roi if roi is not None else (0.0, 0.0, float(max(camera.shape)))
    z = depth[mask]
    z = z[z > 0]
    bounds = [np.percentile(z, list(s.depth_percentiles))] if len(z) > 10 else []
    if joints is not None:
        bounds.append([joints[:, 2].min(), joints[:, 2].max()])
    z_range = None
    if bounds:
        bounds = np.array(bounds)
        far = s.depth_band if s.far_band is None else float(s.far_band)
        z_range = (float(bounds[:, 0].min()) - s.depth_band, float(bounds[:, 1].max()) + far)
    near = mask.copy()
    if predicted_silhouette is not None:
        near |= predicted_silhouette
    k = int(s.near_dilation)
    near = cv2.dilate(near.astype(np.uint8), np.ones((k, k), np.uint8)) > 0
    walls = getattr(foreground, "wall_planes", None) if s.wall_background else None
    observed = observation_image(depth, mask, camera, floor, z_range, near, walls)
    weight = settings.energy.likelihood_weight * new_roi[2] * new_roi[2]
    return Frame(depth, foreground, observed, new_roi, weight), floor
