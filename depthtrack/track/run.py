"""Whole sequences: :func:`run_tracking` (what ``depthtrack track`` runs) and the
ground-truth initialisation ablation (:func:`fit_pose_to_joints`)."""
from __future__ import annotations

import time

import numpy as np

from ..body.skeleton import TORSO_CONTRACT_JOINTS
from ..contract import JOINT_INDEX
from ..environment import blas_kernels, software_versions
from ..errors import InputError
from ..render.context import gl_info
from .height import body_for_sequence, fit_body_shape
from .settings import TrackerSettings
from .tracker import Tracker

#: Contract-joint indices of the torso (the root's rigid frame).
TORSO = tuple(JOINT_INDEX[n] for n in TORSO_CONTRACT_JOINTS)


def fit_pose_to_joints(body, joints, regularisation: float = 0.01):
    """Least-squares pose whose contract joints match ``joints (15, 3)`` (NaN rows ignored).

    Used only by the ground-truth initialisation ablation (``--init-from-groundtruth``). The
    root comes first from the torso points (Kabsch), then every parameter is fitted with a
    small pull ``regularisation`` toward the zero pose, which fixes the twists that joint
    positions leave free.

    Returns
    -------
    (48,) float
    """
    from scipy.optimize import least_squares

    from .twins import root_from_joints

    target = np.asarray(joints, dtype=np.float64)
    known = np.all(np.isfinite(target), axis=1)
    if known.sum() < 4:
        raise InputError(None, "ground truth has fewer than 4 known joints in the first frame")
    torso = [i for i in TORSO if known[i]]
    if len(torso) < 3:
        torso = list(np.flatnonzero(known))
    x0 = root_from_joints(body, target, torso)

    def residual(p):
        d = (np.asarray(body.joint_positions(p)) - target)[known].ravel()
        return np.concatenate([d, regularisation * p[6:]])

    lo = np.where(np.isfinite(body.lower), body.lower, -np.inf)
    hi = np.where(np.isfinite(body.upper), body.upper, np.inf)
    x0 = np.clip(x0, lo + 1e-9, hi - 1e-9)
    fit = least_squares(residual, x0, bounds=(lo, hi), x_scale=0.3, max_nfev=200)
    return fit.x


def run_tracking(seq, method: str = "hc+ep", likelihood: str = "smoothed",
                 init_from_groundtruth: bool = False, progress=None, settings=None,
                 segmenter=None, detector=None):
    """Track a whole sequence as ``depthtrack track`` does; no ground truth unless asked.

    Parameters
    ----------
    seq : Sequence
    method, likelihood : str
    init_from_groundtruth : bool
        ABLATION: start from a pose fitted to frame 0's ground-truth joints
        (:func:`fit_pose_to_joints`); recorded in the summary.
    progress : Progress or None
    settings : TrackerSettings or None
    segmenter, detector : callables or None (defaults from :mod:`depthtrack.detect`)

    Returns
    -------
    result : TrackResult
    body : BodyModel
        The body the poses belong to: the template at the given or fitted height, then
        (:attr:`TrackerSettings.shape` enabled) the shape fitted to the first frames.
    summary : dict
        For ``summary.json``: method, likelihood, initialisation, body height and its source,
        settings, prior, timings per stage, ``seconds`` and ``processing_fps`` (the tracking
        pass), ``wall_seconds`` and ``wall_fps`` (the height and shape fits too), and ``body``
        (:meth:`BodyModel.to_dict` with ``shape_fit``: how the shape fit went, or why not).

    With the shape fit (on sequences of at least :attr:`ShapeSettings.frames` frames)
    the first :attr:`ShapeSettings.frames` frames are tracked twice:
    once with the template to fit the shape, then, like every frame, with the fitted body
    (so no frame's pose belongs to another body), starting from the trial's frame-0 pose
    as the fit refined it (the trial's automatic start and front/back check carry over).
    Its time is in ``timings["shape_fit_s"]``.
    """
    started = time.perf_counter()
    init_pose = None
    settings = settings or TrackerSettings()
    if init_from_groundtruth and seq.joints is None:
        raise InputError(seq.path, "--init-from-groundtruth needs groundtruth/joints.csv")
    body, height = body_for_sequence(seq, segmenter, settings=settings)
    shape_info = {"fitted": False, "reason": "off (settings.shape.enabled false)"}
    n = settings.shape.frames
    if settings.shape.enabled and len(seq) < n:
        # a clip shorter than the fit's frames would be tracked twice over for little
        shape_info["reason"] = f"the sequence has {len(seq)} frames, the fit needs {n}"
    elif settings.shape.enabled:
        # the trial starts as the track would (with the part recogniser unless "hc"); "ep"
        # alone drifts, so its trial climbs too
        # the whole sequence on offer: the trial's start may look ahead past its n frames
        frames = (seq.depth(i) for i in range(len(seq)))
        body, shape_info = fit_body_shape(frames, body, seq.camera, fps=seq.fps,
                                          settings=settings, segmenter=segmenter,
                                          fit_scale=not seq.subject_height,
                                          method="hc" if method == "hc" else "hc+ep")
    start_pose = shape_info.pop("start_pose", None)
    trial_start = shape_info.pop("start_info", None)
    if init_from_groundtruth:
        init_pose = fit_pose_to_joints(body, seq.joints[0])
    elif start_pose is not None:
        # the trial track already started (and checked front/back) on frame 0
        init_pose = np.array(start_pose)
    with Tracker(body, seq.camera, method=method, likelihood=likelihood, fps=seq.fps,
                 settings=settings, segmenter=segmenter, detector=detector) as tracker:
        t0 = time.perf_counter()
        result = tracker.track_sequence(seq, progress=progress, init_pose=init_pose)
        seconds = time.perf_counter() - t0
    wall = time.perf_counter() - started
    info = result.info
    source = height["source"]
    if shape_info["fitted"] and not seq.subject_height:
        source += "; then scaled with the shape fitted to the first frames"
    summary = {
        "method": method,
        "likelihood": likelihood,
        "init_from_groundtruth": bool(init_from_groundtruth),
        "initialisation": ("ground truth of frame 0 (ABLATION: --init-from-groundtruth)"
                           if init_from_groundtruth else "automatic (no ground truth used)"
                           + ("; the re-track after the shape fit starts from the trial "
                              "track's frame-0 pose" if init_pose is not None else "")),
        # the re-track's own start is the given pose; the trial's start says how it was found
        "initialisation_details": {**info["initialisation"],
                                   **({"trial_start": trial_start}
                                      if init_pose is not None and trial_start else {})},
        "body_height_m": round(float(body.height), 3) if shape_info["fitted"] else height["height_m"],
        "body_height_source": source,
        "body_height_fit": {k: v for k, v in height.items() if k not in ("height_m", "source")} or None,
        "seconds": round(seconds, 3),
        "processing_fps": round(len(seq) / seconds, 3) if seconds > 0 else None,
        # the whole command's tracking work: the height and shape fits too (what the user waits)
        "wall_seconds": round(wall, 3),
        "wall_fps": round(len(seq) / wall, 3) if wall > 0 else None,
        "timings": {**result.timings, "shape_fit_s": shape_info.get("seconds", 0.0)},
        "counts": info["counts"],
        "recoveries": info["recoveries"],
        "heading_switches": info["heading_switches"],
        "limb_swaps": info["limb_swaps"],
        "reaches": info["reaches"],
        "reseats": info["reseats"],
        "heading_retracks": info["heading_retracks"],
        "retracks": info["retracks"],
        "settings": info["settings"],
        "prior": info["prior"],
        "body": {**body.to_dict(), "height_source": source, "shape_fit": shape_info},
        # which rasteriser drew: a track can follow its last bits (README, "On a GPU")
        "renderer": gl_info(),
        # and with which numeric libraries (README, "Benchmark": a fresh install moves tracks)
        "software": software_versions(),
        # and with which matrix kernels (README, "The same figures on another machine")
        "blas": blas_kernels(),
    }
    return result, body, summary
