"""Fit the person's body shape (proportions and size) to a few depth frames by the likelihood.

Given the camera, K depth frames with the person segmented and a pose per frame (from the
tracker's first frames), :func:`fit_shape` finds the :class:`~depthtrack.body.shape.BodyShape`
and the uniform scale (hence the height) that explain the frames best, alternating

1. **shape**: a coordinate search over the 12 log-parameters (11 shape fields and the log
   scale): each iteration scores ``x +- step_i e_i`` for every parameter in one batch per
   frame on the GL :class:`~depthtrack.render.TileRenderer`, takes the best move (or the
   sum of all improving moves when that is better still), and halves the step of a
   parameter whose moves do not help, until every step is below its finest rung;
2. **pose**: the existing :class:`~depthtrack.track.hill_climb.HillClimber` on each frame's
   pose with the new body (finer steps only: the poses are nearly right).

Energy of a shape ``s`` with poses ``x_k`` (camera pixels' worth, as the tracker's)::

    E(s) = sum_k A_k * mean_tile_cost(s, x_k | frame k) + 0.5 * w * sum_i (log s_i / sd_i)^2

``A_k`` the area of frame k's ROI in camera pixels, ``w`` the prior weight, ``sd_i`` the population spread
(:data:`~depthtrack.body.shape.LOG_SD`): a weak prior that settles what the frames cannot
tell (the split of a straight arm into upper arm and forearm, the foot seen from the
front) toward average proportions. Shape fields stay within
:data:`~depthtrack.body.shape.SHAPE_RANGES`; the scale within 0.75 - 1.25 of the start.

Candidates of different shapes are scored in one batch with a stand-in body
(:class:`_MatrixBody`) whose skin matrices are precomputed per candidate, so the renderer
needs nothing new. One renderer is created per call and released before it returns.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import cv2
import numpy as np

from ..body.shape import LOG_SD, SHAPE_FIELDS, SHAPE_RANGES, BodyShape
from ..errors import InputError
from .hill_climb import HillClimber, default_blocks
from .observation import observation_image, square_roi

#: Coarsest and finest steps of the shape search (log units: 0.04 = 4 %).
SHAPE_STEPS = (0.04, 0.005)
#: Bounds of the log scale relative to the starting body.
SCALE_BOUNDS = (np.log(0.75), np.log(1.25))


@dataclass
class ShapeFit:
    """Result of :func:`fit_shape`.

    Attributes
    ----------
    body : BodyModel
        The starting body with the fitted shape and scale (same mesh).
    shape : BodyShape
    height_m : float
    poses : (K, 48) float
        The refined poses of the frames.
    energy, start_energy : float
        ``E`` (module docstring) at the end and at the start.
    evaluations : int
        Candidate renders scored (shape and pose searches, all frames).
    seconds : float
    history : list of dict
        Per round: energy after the shape search and after the pose refinement.
    tile : int
        Tile side the candidates were rendered at.
    """

    body: object
    shape: BodyShape
    height_m: float
    poses: np.ndarray
    energy: float
    start_energy: float
    evaluations: int
    seconds: float
    history: list = field(default_factory=list)
    tile: int = 0

    def to_dict(self) -> dict:
        """A JSON-serialisable summary (for ``summary.json`` ``body``)."""
        return {"height_m": round(self.height_m, 4), "shape": self.shape.to_dict(),
                "segment_lengths_m": self.body.segment_lengths(),
                "energy": round(self.energy, 2), "start_energy": round(self.start_energy, 2),
                "frames": int(len(self.poses)), "evaluations": int(self.evaluations),
                "seconds": round(self.seconds, 2), "tile": int(self.tile), "rounds": self.history}


class _MatrixBody:
    """Stand-in body for :class:`TileRenderer`: "poses" are row indices into stored skin
    matrices ``(N, J, 4, 4)``, so candidates of different shapes share one batch."""

    def __init__(self, mesh):
        self.mesh = mesh
        self.matrices = None

    def skin_matrices(self, index):
        idx = np.asarray(index, dtype=np.float64)[:, 0].astype(np.int64)
        return self.matrices[idx]


def frame_observation(depth, mask, camera, floor_plane=None, depth_band: float = 0.4,
                      margin: float = 0.1, tile=None):
    """The observed image and ROI of one frame for the shape fit.

    Only the segmented person (grown by one pixel) may be body: everything else with a
    reading within the person's depth band is background too, so the silhouette bounds
    the shape (:func:`~depthtrack.track.observation.observation_image` with ``near`` = the
    grown mask). When the person's box (with ``margin``) fits in ``tile`` camera pixels,
    the ROI is exactly ``tile`` pixels wide at whole-pixel corners, so every tile pixel is
    a camera pixel: no resampling, whose half-pixel misalignments at silhouettes would
    otherwise cost more than a centimetre of segment length.

    Returns
    -------
    observed : (H, W) float32
    roi : (u0, v0, size)
    """
    depth = np.asarray(depth, dtype=np.float32)
    mask = np.asarray(mask, dtype=bool)
    if depth.shape != camera.shape or mask.shape != camera.shape:
        raise InputError(None, f"depth {depth.shape} and mask {mask.shape} must be the camera's "
                               f"{camera.shape}")
    z = depth[mask]
    z = z[z > 0]
    if len(z) < 20:
        raise InputError(None, "the shape fit needs frames with a person in them (mask too small)")
    lo, hi = np.percentile(z, [2.0, 98.0])
    near = cv2.dilate(mask.astype(np.uint8), np.ones((3, 3), np.uint8)) > 0
    observed = observation_image(depth, mask, camera, floor_plane,
                                 (float(lo) - depth_band, float(hi) + depth_band), near)
    roi = square_roi(mask, margin)
    if tile is not None and roi[2] <= tile:
        centre = (roi[0] + 0.5 * (roi[2] - 1), roi[1] + 0.5 * (roi[2] - 1))
        roi = (float(round(centre[0] - 0.5 * (tile - 1))), float(round(centre[1] - 0.5 * (tile - 1))),
               float(tile))
    return observed, roi


def _lower_upper():
    lo = np.array([np.log(SHAPE_RANGES[f][0]) for f in SHAPE_FIELDS] + [SCALE_BOUNDS[0]])
    hi = np.array([np.log(SHAPE_RANGES[f][1]) for f in SHAPE_FIELDS] + [SCALE_BOUNDS[1]])
    return lo, hi


def auto_tile(masks, margin: float = 0.1, largest: int = 256) -> int:
    """The smallest power-of-two tile (>= 64, <= ``largest``) that holds every mask's box
    with ``margin`` at one camera pixel per tile pixel (:func:`frame_observation`)."""
    size = max(square_roi(np.asarray(m, bool), margin)[2] for m in masks)
    tile = 64
    while tile < size and tile < largest:
        tile *= 2
    return tile


def fit_shape(body, camera, depths, masks, poses, floor_planes=None, tile: int | None = None,
              rounds: int = 2, max_iterations: int = 40, refine_poses: bool = True,
              smoothed: bool = False, prior_weight: float = 30.0, fit_scale: bool = True,
              log=None) -> ShapeFit:
    """Fit shape and scale of ``body`` to K segmented depth frames (module docstring).

    Parameters
    ----------
    body : BodyModel
        The starting body (its current shape and scale are the start; its mesh is used).
        Pass the decimated mesh for speed (``body.with_mesh("decimated")``).
    camera : Camera
    depths : sequence of (H, W) float
        Depth frames (metres, 0 = no reading), K of them; 3 to 6 frames with the limbs in
        different poses (bent elbows and knees) tell the segment lengths apart best.
    masks : sequence of (H, W) bool
        The person's pixels in each frame (:func:`depthtrack.detect.segment_foreground`).
    poses : (K, 48) float
        The body's pose in each frame (the tracker's).
    floor_planes : sequence of (4,) float or None, optional
        Each frame's floor plane (pixels on it are background).
    tile : int or None
        Tile side of the renderer; None = :func:`auto_tile` (one camera pixel per tile
        pixel up to 256: an SR4000 person at 3 m needs 256, at 4.6 m 128).
    rounds : int
        Shape-then-pose alternations.
    max_iterations : int
        Most batches of the shape search per round.
    refine_poses : bool
        Run the pose refinement after each shape search.
    smoothed : bool
        Smoothed likelihood (True) or the per-pixel sensor cost (False, default: the
        neighbour tolerance of the smoothed one blurs silhouettes by a pixel).
    prior_weight : float
        Weight of the population prior (0 = none). 30 was chosen on the dev motions
        (``tools/shape_fit_bench.py --split dev --people 4``: median segment-length error
        0.7 cm against 0.9 cm with weight 1; a 1-s.d. field then costs 15 pixels' worth).
    fit_scale : bool
        Also fit the uniform scale (the height); False keeps the body's height (the scale
        follows the shape).
    log : callable(str) or None
        Receives one line per round.

    Returns
    -------
    ShapeFit
    """
    from ..render import TileRenderer

    t0 = time.perf_counter()
    poses = np.array(poses, dtype=np.float64).reshape(-1, body.dof)
    K = len(poses)
    if K == 0 or len(depths) != K or len(masks) != K:
        raise InputError(None, f"fit_shape needs as many depth frames and masks as poses "
                               f"({len(depths)}, {len(masks)}, {K})")
    planes = list(floor_planes) if floor_planes is not None else [None] * K
    if any(not np.asarray(m).any() for m in masks):
        raise InputError(None, "the shape fit needs frames with a person in them (an empty mask)")
    tile = auto_tile(masks) if tile is None else int(tile)
    frames = [frame_observation(d, m, camera, p, tile=tile) for d, m, p in zip(depths, masks, planes)]
    areas = np.array([roi[2] ** 2 for _, roi in frames])
    base_scale = float(body.scale)
    lo, hi = _lower_upper()
    n_par = len(lo)
    x = np.append(np.log(body.shape.as_array()), 0.0)
    x = np.clip(x, lo, hi)
    x0 = x.copy()
    active = np.ones(n_par, bool)
    active[-1] = fit_scale
    sd = np.append(LOG_SD, np.inf)
    stand_in = _MatrixBody(body.mesh)
    renderer = TileRenderer(stand_in, camera, tile=tile)
    evaluations = 0

    # without fit_scale the height stays the body's: the scale follows the shape through
    # the height's log-gradient (an exact rescale per candidate costs 8x the candidate)
    gradient = np.zeros(n_par - 1) if fit_scale else _log_height_gradient(body, x[:-1])

    def body_at(params):
        log_scale = params[-1] - float(gradient @ (params[:-1] - x0[:-1]))
        return body._copy(shape=BodyShape.from_array(np.exp(params[:-1])),
                          scale=base_scale * float(np.exp(log_scale)))

    def prior(params):
        return 0.5 * prior_weight * float(np.sum((params[:-1] / sd[:-1]) ** 2))

    def frame_costs(k, matrices):
        nonlocal evaluations
        stand_in.matrices = matrices
        renderer.set_observation(frames[k][0], roi=frames[k][1])
        evaluations += len(matrices)
        return areas[k] * renderer.costs(np.arange(len(matrices), dtype=np.float64)[:, None],
                                         smoothed=smoothed)

    def shape_energies(candidates):
        """(C,) energy of shape-parameter vectors ``(C, 12)`` at the current poses."""
        bodies = [body_at(c) for c in candidates]
        total = np.array([prior(c) for c in candidates])
        for k in range(K):
            mats = np.stack([b.skin_matrices(poses[k]) for b in bodies])
            total += frame_costs(k, mats)
        return total

    try:
        e = float(shape_energies(x[None])[0])
        start_energy = e
        history = []
        for r in range(rounds):
            x, e = _coordinate_search(x, e, shape_energies, lo, hi, active, max_iterations)
            round_info = {"round": r + 1, "shape_energy": round(e, 2)}
            if refine_poses:
                current = body_at(x)
                climber = HillClimber(blocks=default_blocks(0.5), levels=3, max_iterations=4,
                                      clip=current.clip)
                for k in range(K):
                    def energy(p, k=k):
                        return frame_costs(k, current.skin_matrices(np.atleast_2d(p)))
                    res = climber.climb(poses[k], energy, level_offset=1)
                    poses[k] = res.pose
                e = float(shape_energies(x[None])[0])
                round_info["pose_energy"] = round(e, 2)
            history.append(round_info)
            if log is not None:
                log(f"shape fit round {r + 1}: energy {e:.1f} (start {start_energy:.1f})")
    finally:
        renderer.release()
    fitted = body_at(x)
    if not fit_scale:                     # the first-order height correction made exact
        fitted = fitted.scaled(height=float(body.height))
    return ShapeFit(fitted, fitted.shape, float(fitted.height), poses, e, start_energy,
                    evaluations, time.perf_counter() - t0, history, tile)


def _log_height_gradient(body, log_shape, step: float = 0.02):
    """(11,) d log(height) / d log(shape field) at ``log_shape`` (central differences)."""
    out = np.zeros(len(log_shape))
    for i in range(len(log_shape)):
        h = []
        for sign in (1.0, -1.0):
            y = np.array(log_shape, dtype=float)
            y[i] += sign * step
            h.append(np.log(body._copy(shape=BodyShape.from_array(np.exp(y))).height))
        out[i] = (h[0] - h[1]) / (2 * step)
    return out


def _coordinate_search(x, e, energies, lo, hi, active, max_iterations):
    """Coarse-to-fine coordinate descent over the active parameters (module docstring)."""
    step = np.where(active, SHAPE_STEPS[0], 0.0)
    finest = SHAPE_STEPS[1]
    for _ in range(max_iterations):
        live = np.flatnonzero(active & (step >= finest))
        if len(live) == 0:
            break
        moves = np.zeros((2 * len(live), len(x)))
        moves[np.arange(len(live)), live] = step[live]
        moves[len(live) + np.arange(len(live)), live] = -step[live]
        candidates = np.clip(x + moves, lo, hi)
        values = energies(candidates)
        gains = e - values
        improving = []
        for i, p in enumerate(live):
            best = i if values[i] <= values[len(live) + i] else len(live) + i
            if gains[best] > 1e-9:
                improving.append(best)
            else:
                step[p] *= 0.5
        if not improving:
            continue
        best = min(improving, key=lambda i: values[i])
        x_new, e_new = candidates[best], float(values[best])
        if len(improving) > 1:
            combined = np.clip(x + moves[improving].sum(axis=0), lo, hi)
            e_combined = float(energies(combined[None])[0])
            if e_combined < e_new:
                x_new, e_new = combined, e_combined
        x, e = x_new, e_new
    return x, e


def write_body_json(path, body, fit: ShapeFit | None = None) -> None:
    """Write ``body.json`` atomically: :meth:`BodyModel.to_dict` plus, when given, how the fit went.

    :meth:`depthtrack.BodyModel.from_json` rebuilds the body from it.
    """
    import json

    from ..io.atomic import write_text_atomic

    data = body.to_dict()
    if fit is not None:
        data["fit"] = {k: v for k, v in fit.to_dict().items()
                       if k not in ("shape", "segment_lengths_m", "height_m")}
    write_text_atomic(path, json.dumps(data, indent=1) + "\n")


__all__ = ["ShapeFit", "fit_shape", "auto_tile", "frame_observation", "write_body_json", "SHAPE_STEPS"]
