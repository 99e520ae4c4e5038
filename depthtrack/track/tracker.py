"""The per-frame tracker: MAP pose from the previous one, a depth frame and part detections.

Methods (``method=``), following the ToF paper's experiments:

``"hc"``
    Model-based search only: start from the better of the constant-velocity prediction and
    the previous pose, then hill climbing (:mod:`.hill_climb`) on the MAP energy.
``"ep"``
    The paper's "EP" baseline, i.e. the whole algorithm with local hill climbing removed:
    start from the better of the prediction and the previous pose, then the association
    loop (:mod:`.association`) proposes evidence-propagation modes and keeps one when its
    energy is lower. Nothing refines the pose against the image, so it drifts; the paper
    reports it far worse than both others.
``"hc+ep"`` (default)
    The paper's algorithm: hill climbing, then the association loop where each propagated
    pose is refined by hill climbing over the chain of the corresponded part before its
    energy is compared.

All three share the automatic initialisation (:meth:`Tracker.init`), which needs the
model-based search to find the body at all.

MAP energy of a candidate pose ``x`` with velocity ``v = x (-) x_{t-1}``::

    E(x) = w * A * mean_tile_cost(x) + 0.5 * sum(((v - v_pred) / sigma)^2)
                                     + 0.5 * sum((x_joints / pose_prior_std)^2)

``mean_tile_cost`` is :meth:`TileRenderer.costs` (smoothed or pixel likelihood, each pixel's
cost a negative log-likelihood), ``A`` the ROI's area in camera pixels, so ``A * mean`` is
the negative log-likelihood summed over the camera pixels the tile covers, and
``w = likelihood_weight`` (1 = pixels independent, as in the paper's model); the second term
is ``-log p(v_t | v_{t-1})`` of :class:`~depthtrack.motion.prior.ConstantVelocityPrior`; the
third a weak pose prior on the joint rotations (:attr:`TrackerSettings.pose_prior_std`,
our addition for hidden limbs).
"""
from __future__ import annotations

import copy
import time
from dataclasses import dataclass, field

import cv2
import numpy as np

from ..body.rotations import matrix_to_rotvec, rotation_about
from ..errors import InputError
from ..motion.prior import ConstantVelocityPrior, pose_velocity
from ..motion.retarget import rotation_between
from .association import associate
from .evidence import PartModel, propagate_evidence
from .hill_climb import HillClimber, default_blocks, restrict_blocks
from .observation import (estimate_height, observation_image, robust_points, square_roi,
                          visible_area)

METHODS = ("hc", "ep", "hc+ep")

#: Arm poses tried by the global search: (shoulder rx, left shoulder rz) in radians
#: (the right shoulder mirrors rz).
ARM_POSES = {"relaxed": (0.0, 0.0), "t-pose": (0.0, -1.13), "raised": (0.0, -2.6),
             "overhead": (-1.0, -2.4), "forward": (-1.4, 0.0), "down": (0.0, 0.35)}
#: Shifts (m) along the body's long axis tried by the global search.
AXIAL_SHIFTS = (0.0, -0.3, -0.15, 0.15, 0.3)
LIKELIHOODS = ("smoothed", "pixel")

#: Hill-climbing groups moved by each part's chain (root first).
PART_GROUPS = {
    "head": ("pelvis_t", "pelvis", "spine", "neck"),
    "l_hand": ("spine", "l_shoulder", "l_elbow", "l_wrist"),
    "r_hand": ("spine", "r_shoulder", "r_elbow", "r_wrist"),
    "l_foot": ("pelvis_t", "pelvis", "l_hip", "l_knee", "l_ankle"),
    "r_foot": ("pelvis_t", "pelvis", "r_hip", "r_knee", "r_ankle"),
}


@dataclass
class TrackerSettings:
    """Tuning of :class:`Tracker` (one set for every sequence; never tuned per clip).

    Attributes
    ----------
    tile : int
        Tile side of the candidate renderer (pixels).
    fine_tile : int
        Tile side of the final polish (the finest step rung once more, at this resolution);
        0 = no polish.
    fine_iterations : int
        Most batches per block of the polish.
    levels : int
        Rungs of the hill-climbing step ladder.
    max_iterations : int
        Most batches per block of the schedule.
    step_scale : float
        Factor on the coarsest steps of :func:`default_blocks` (at 25 fps; scaled by 25/fps).
    passes : int
        Times the hill-climbing schedule runs per frame.
    diagonals : bool
        Include the diagonal moves of the per-frame search.
    damping : float
        Velocity damping of the prediction (1 = constant velocity).
    likelihood_weight : float
        ``w`` of the energy (module docstring).
    roi_margin : float
        Margin around the foreground box, as a fraction of its larger side.
    depth_band : float
        Readings farther than this (m) in front of or behind the person count as background.
    prune_distance : float
        Detections within this distance (m) of a model part count as explained.
    ep_obs_std : float
        Detection noise (m) in evidence propagation.
    ep_prior_scale : float
        Evidence propagation's prior: ``N(x_best, (scale * sigma)^2)`` in velocity space.
    max_correspondences : int
        Most correspondences tried per frame.
    pose_prior_std : float
        Standard deviation (rad) of a weak Gaussian on every joint rotation about the zero
        pose (0 = off). Not in the paper: where a limb is hidden the likelihood is flat and
        the search would let it drift into any pose; this keeps it plausible while costing
        a visible limb almost nothing (a 1.5 rad bend costs 1.1, a mismatched pixel 1).
    refine_level : int
        Rung of the step ladder the hill climbing of a propagated pose ("hc+ep") starts on
        (0 = coarsest).
    refine_with_prior : bool
        Whether that hill climbing includes the velocity prior. Off by default: evidence
        propagation has already weighed the prior against the detection, and the prior,
        centred on a track that may be lost, would pull the hypothesis back before the
        likelihood could judge it (measured on ``make benchmark``: 92 % of joints within
        10 cm on punch/run/walk/jump without it, 91 % with it).
    refine_scope : {"chain", "body"}
        What that hill climbing moves: the corresponded part's chain (:data:`PART_GROUPS`,
        the paper's local search) or every joint (about three times the candidates; on
        ``make benchmark``'s clips no better on average).
    accept : {"likelihood", "map"}
        What a propagated-and-refined pose must improve to replace the best one: the
        likelihood (the paper) or the MAP energy (likelihood + motion prior).
    accept_margin : float
        With "likelihood": the improvement needed, in energy units (camera pixels' worth of
        a full mismatch), so noise-level gains do not swap in a wrong correspondence.
    init_passes : int
        Hill-climbing passes of the initialisation on the first frame.
    facing_prior : float
        Weight of the initial-heading prior of the global search (see
        :meth:`Tracker._facing_penalty`), per foreground pixel.
    min_person_area : float
        A frame whose foreground covers less than this (m^2, :func:`visible_area`) has no
        person in it. Before the first person, such frames get no pose; during tracking,
        the track is dropped after ``absent_frames`` such frames in a row (a segmentation
        that fails for a frame or two must not end a good track), those frames get no pose,
        and tracking starts afresh (automatic initialisation) on the next frame with a person.
    absent_frames : int
        See ``min_person_area``.
    heading_frames, heading_margin : int, float
        After an automatic initialisation, the pose and its twin turned to face the other
        way are both tracked through this many frames, and the turned one replaces the first
        when its unexplained share (:meth:`Tracker.unexplained`) is lower by this fraction
        (:meth:`Tracker._settle_heading`); 0 frames = off.
    lost_ratio, lost_margin : float
        Track counts as lost when the share of the observation the fitted pose leaves
        unexplained (:meth:`Tracker.unexplained`) exceeds both
        ``lost_ratio`` times and ``lost_margin`` plus the median of the last 8 frames; the
        global search of the initialisation then runs on the frame ("hc", "hc+ep").
    """

    tile: int = 64
    fine_tile: int = 128
    fine_iterations: int = 4
    levels: int = 3
    max_iterations: int = 8
    step_scale: float = 1.0
    passes: int = 2
    diagonals: bool = False
    damping: float = 0.7
    likelihood_weight: float = 1.0
    roi_margin: float = 0.15
    depth_band: float = 0.4
    prune_distance: float = 0.15
    ep_obs_std: float = 0.04
    ep_prior_scale: float = 4.0
    max_correspondences: int = 6
    pose_prior_std: float = 1.0
    refine_level: int = 1
    refine_with_prior: bool = False
    refine_scope: str = "chain"
    accept: str = "likelihood"
    accept_margin: float = 0.0
    init_passes: int = 3
    facing_prior: float = 0.1
    lost_ratio: float = 1.6
    lost_margin: float = 0.15
    min_person_area: float = 0.08
    heading_frames: int = 10
    heading_margin: float = 0.1
    absent_frames: int = 3

    def to_dict(self) -> dict:
        return dict(self.__dict__)


@dataclass
class TrackResult:
    """Output of :meth:`Tracker.track_sequence`.

    Attributes
    ----------
    poses : (F, 48) float
    joints : (F, 15, 3) float
        Contract joints (camera frame, metres).
    timings : dict
        :meth:`Tracker.timing_summary`: initialisation seconds, milliseconds per tracked frame
        for each stage (``per_frame_ms``), frames per second, candidates per frame.
    info : dict
        Method, likelihood, settings, initialisation, per-frame energies and counts.
    """

    poses: np.ndarray
    joints: np.ndarray
    timings: dict
    info: dict = field(default_factory=dict)


class Tracker:
    """Track a body through depth frames: ``init(depth0)`` then ``step(depth)`` per frame.

    Parameters
    ----------
    body : BodyModel
        Scaled to the subject; its decimated mesh is used for the candidate renderer.
    camera : Camera
    method : {"hc", "ep", "hc+ep"}
    likelihood : {"smoothed", "pixel"}
    prior : ConstantVelocityPrior, optional
        Default: the shipped prior at ``fps``.
    fps : float
    settings : TrackerSettings, optional
    segmenter : callable ``(depth, camera) -> Foreground``, optional
        Default :func:`depthtrack.detect.segment_foreground`.
    detector : callable ``(depth, camera, foreground) -> list of Detection``, optional
        Default :func:`depthtrack.detect.detect_parts`.
    renderer : TileRenderer, optional
    """

    def __init__(self, body, camera, method: str = "hc+ep", likelihood: str = "smoothed", prior=None,
                 fps: float = 25.0, settings: TrackerSettings | None = None, segmenter=None,
                 detector=None, renderer=None):
        if method not in METHODS:
            raise InputError(None, f"unknown method {method!r}; choose one of {', '.join(METHODS)}")
        if likelihood not in LIKELIHOODS:
            raise InputError(None, f"unknown likelihood {likelihood!r}; choose one of "
                                   f"{', '.join(LIKELIHOODS)}")
        self.settings = s = settings or TrackerSettings()
        self.body = body
        try:
            self.render_body = body.with_mesh("decimated")
        except (ValueError, AttributeError):
            self.render_body = body
        self.camera = camera
        self.method = method
        self.likelihood = likelihood
        self.smoothed = likelihood == "smoothed"
        self.fps = float(fps)
        self.prior = prior or ConstantVelocityPrior.load(fps=self.fps, damping=s.damping)
        if renderer is None:
            from ..render import TileRenderer
            renderer = TileRenderer(self.render_body, camera, tile=s.tile)
        self.coarse_renderer = self.renderer = renderer
        self.fine_renderer = None
        if s.fine_tile and s.fine_tile != renderer.tile:
            from ..render import TileRenderer
            self.fine_renderer = TileRenderer(self.render_body, camera, tile=s.fine_tile)
        if segmenter is None:
            from ..detect import segment_foreground as segmenter
        self.segmenter = segmenter
        if detector is None and method != "hc":
            from ..detect import detect_parts as detector
        self.detector = detector
        if int(s.absent_frames) < 1:
            raise InputError(None, f"absent_frames must be at least 1, not {s.absent_frames}")
        if s.refine_scope not in ("chain", "body"):
            raise InputError(None, f"refine_scope must be 'chain' or 'body', not {s.refine_scope!r}")
        self.parts = PartModel.from_body(body)
        step_scale = s.step_scale * 25.0 / self.fps
        self.climber = HillClimber(blocks=default_blocks(step_scale, s.diagonals), levels=s.levels,
                                   max_iterations=s.max_iterations, clip=body.clip)
        self.fine_climber = HillClimber(blocks=default_blocks(step_scale, s.diagonals), levels=s.levels,
                                        max_iterations=s.fine_iterations, clip=body.clip)
        # the global search (first frame, lost track) starts far off: twice the steps, two
        # more rungs, more iterations per block
        self.search_climber = HillClimber(blocks=default_blocks(2.0 * step_scale), levels=s.levels + 2,
                                          max_iterations=10, clip=body.clip)
        self.pose = None
        self.velocity = np.zeros(body.dof)
        self._v_pred = np.zeros(body.dof)
        self._use_prior = False
        self._weight = 1.0
        self.roi = None
        self.foreground = None
        self.timings = {k: 0.0 for k in ("segment", "render", "detect", "evidence", "search",
                                         "association", "init", "recover")}
        self.counts = {"candidates": 0, "render_calls": 0, "detections": 0, "correspondences": 0,
                       "accepted": 0, "recoveries_tried": 0, "recoveries": 0,
                       "frames_without_person": 0, "reinitialisations": 0}
        self.frame_log = []
        self.init_info = {}
        self._after_init = None
        self._absent = 0
        self._counts_after_init = {}
        self._up = None
        self._floor = None
        self._frame_renderer = None
        self._detections = None
        self._heading = None

    # ------------------------------------------------------------------ observation / energy
    def _observe(self, depth, predicted=None, foreground=None):
        """Segment the frame (unless its ``foreground`` is given), set the ROI, upload the
        observation; returns the Foreground.

        The observation keeps the raw depth of every pixel that may be the person, so a
        segmentation that misses a limb does not forbid the model to cover it: only pixels
        on the floor plane or outside the person's depth band are background
        (:func:`observation_image`). The ROI covers the foreground's box and the
        ``predicted (48,)`` pose's joints (when given), with a margin.
        """
        depth = np.asarray(depth, dtype=np.float32)
        if depth.shape != self.camera.shape:
            raise InputError(None, f"depth frame is {depth.shape[1]} x {depth.shape[0]}, camera is "
                                   f"{self.camera.width} x {self.camera.height}")
        if foreground is None:
            t = time.perf_counter()
            foreground = self.segmenter(depth, self.camera)
            self.timings["segment"] += time.perf_counter() - t
        fg = foreground
        mask = np.asarray(fg.mask, dtype=bool)
        plane = getattr(fg, "floor_plane", None)
        if plane is not None:
            self._floor = np.asarray(plane, dtype=np.float64)
        joints = None if predicted is None else np.asarray(self.body.joint_positions(predicted))
        box = mask.copy()
        if joints is not None:
            uv = self.camera.project(joints)
            ok = np.all(np.isfinite(uv), axis=1) & (joints[:, 2] > 0)
            if ok.any():
                pad = 0.15 * self.camera.fx / float(np.median(joints[ok, 2]))
                lo = np.floor(uv[ok].min(axis=0) - pad).astype(int)
                hi = np.ceil(uv[ok].max(axis=0) + pad).astype(int)
                lo = np.clip(lo, 0, [self.camera.width - 1, self.camera.height - 1])
                hi = np.clip(hi, 0, [self.camera.width - 1, self.camera.height - 1])
                box[lo[1]:hi[1] + 1, lo[0]] = True
                box[lo[1]:hi[1] + 1, hi[0]] = True
        roi = square_roi(box, self.settings.roi_margin)
        if roi is None:
            roi = self.roi if self.roi is not None else (0.0, 0.0, float(max(self.camera.shape)))
        z = depth[mask]
        z = z[z > 0]
        bounds = [np.percentile(z, [2.0, 98.0])] if len(z) > 10 else []
        if joints is not None:
            bounds.append([joints[:, 2].min(), joints[:, 2].max()])
        z_range = None
        if bounds:
            bounds = np.array(bounds)
            z_range = (float(bounds[:, 0].min()) - self.settings.depth_band,
                       float(bounds[:, 1].max()) + self.settings.depth_band)
        near = mask.copy()
        if predicted is not None:
            near |= self._silhouette(predicted)
        near = cv2.dilate(near.astype(np.uint8), np.ones((7, 7), np.uint8)) > 0
        observed = observation_image(depth, mask, self.camera, self._floor, z_range, near)
        self.coarse_renderer.set_observation(observed, roi=roi)
        if self.fine_renderer is not None:
            self.fine_renderer.set_observation(observed, roi=roi)
        self.renderer = self.coarse_renderer
        self.roi = roi
        self.foreground = fg
        self._weight = self.settings.likelihood_weight * roi[2] * roi[2]
        return fg

    def _silhouette(self, pose):
        """(H, W) bool: where ``pose (48,)`` covers the full camera image (one GL render)."""
        if self._frame_renderer is None:
            from ..render import FrameRenderer
            self._frame_renderer = FrameRenderer(self.camera)
        return self._frame_renderer.render(self.render_body, np.asarray(pose)) > 0

    def likelihood_costs(self, poses):
        """(N,) mean tile costs of ``poses (N, 48)`` against the current observation."""
        t = time.perf_counter()
        c = self.renderer.costs(np.asarray(poses, dtype=np.float64), smoothed=self.smoothed)
        self.timings["render"] += time.perf_counter() - t
        self.counts["candidates"] += len(c)
        self.counts["render_calls"] += 1
        return c

    def unexplained(self, pose) -> float:
        """Share of the observation's cost that ``pose (48,)`` leaves unexplained.

        ``(c(x) - c0) / (c_empty - c0)``: ``c(x)`` the mean tile cost, ``c_empty`` the cost
        with no body drawn (every foreground pixel ``missing_cost``), ``c0`` the constant
        share of pixels without a reading. About 0.1 - 0.3 on a good fit, near 1 when lost;
        independent of the ROI's size, so comparable from frame to frame.
        """
        c = float(self.likelihood_costs(np.asarray(pose)[None])[0])
        obs = np.asarray(self.renderer.observed_tile, dtype=np.float64)
        p = self.renderer.params
        n = obs.size
        c0 = p.no_reading_cost * np.count_nonzero(obs == 0) / n
        fg = np.isfinite(obs) & (obs > 0) & (obs < p.max_depth)
        empty = c0 + p.missing_cost * np.count_nonzero(fg) / n
        return (c - c0) / max(empty - c0, 1e-9)

    def energy(self, poses):
        """(N,) MAP energy of ``poses (N, 48)`` (module docstring)."""
        poses = np.atleast_2d(poses)
        e = self._weight * self.likelihood_costs(poses)
        if self._use_prior:
            e = e + self.prior.penalty(poses, self.pose, self._v_pred)
        if self.settings.pose_prior_std > 0:
            e = e + 0.5 * np.sum((poses[:, 6:] / self.settings.pose_prior_std) ** 2, axis=1)
        return e

    # ------------------------------------------------------------------ search pieces
    def _climb(self, pose, start_energy=None, blocks=None, passes=1, level_offset=0, climber=None):
        t = time.perf_counter()
        r0 = self.timings["render"]
        res = (climber or self.climber).climb(pose, self.energy, start_energy=start_energy, blocks=blocks,
                                 passes=passes, level_offset=level_offset)
        self.timings["search"] += (time.perf_counter() - t) - (self.timings["render"] - r0)
        return res.pose, res.energy

    def _propagate(self, pose, part, detection):
        t = time.perf_counter()
        std = self.settings.ep_prior_scale * self.prior.velocity_std
        res = propagate_evidence(self.body, self.parts, part, np.asarray(detection.position, float),
                                 pose, np.zeros(self.body.dof), std, obs_std=self.settings.ep_obs_std)
        self.timings["evidence"] += time.perf_counter() - t
        return res.pose

    def _likelihood_energy(self, pose) -> float:
        return self._weight * float(self.likelihood_costs(np.asarray(pose)[None])[0])

    def _refine_part(self, pose, part):
        """Hill-climb a propagated pose over its part's chain ("hc+ep"; on the likelihood and
        pose prior, plus the velocity prior only with :attr:`TrackerSettings.refine_with_prior`),
        then return it with its *likelihood* energy: the paper accepts a correspondence when the
        likelihood improves (the prior, centred on a possibly lost previous pose, would veto
        exactly the jumps evidence propagation exists for)."""
        if self.method != "ep":
            blocks = (restrict_blocks(self.climber.blocks, PART_GROUPS[part])
                      if self.settings.refine_scope == "chain" else None)
            use_prior = self._use_prior
            self._use_prior = use_prior and self.settings.refine_with_prior
            try:
                pose, e = self._climb(pose, blocks=blocks, level_offset=self.settings.refine_level)
            finally:
                self._use_prior = use_prior
        if self.settings.accept == "map":
            return pose, float(self.energy(pose[None])[0])
        return pose, self._likelihood_energy(pose) + self.settings.accept_margin

    def _detect(self, depth, fg):
        if self._detections is not None and self._detections[0] is fg:
            return self._detections[1]
        t = time.perf_counter()
        dets = list(self.detector(depth, self.camera, fg))
        self._detections = (fg, dets)
        self.timings["detect"] += time.perf_counter() - t
        self.counts["detections"] += len(dets)
        return dets

    def _associate(self, pose, e, depth, fg):
        t = time.perf_counter()
        try:
            dets = self._detect(depth, fg)
            if not dets:
                return pose, e, 0
            parts = self.parts.positions(self.body, pose[None])[0]
            base = e if self.settings.accept == "map" else self._likelihood_energy(pose)
            res = associate(pose, base, dets, parts, self._propagate,
                            self._refine_part,
                            prune_distance=self.settings.prune_distance,
                            max_correspondences=self.settings.max_correspondences)
            self.counts["correspondences"] += len(res.tried)
            self.counts["accepted"] += len(res.accepted)
            if not res.accepted:
                return pose, e, 0
            return res.pose, float(self.energy(res.pose[None])[0]), len(res.accepted)
        finally:
            self.timings["association"] += time.perf_counter() - t

    # ------------------------------------------------------------------ initialisation
    def initial_orientations(self, points, up):
        """Candidate root rotations ``(K, 3, 3)`` for a foreground cloud ``points (M, 3)``.

        The body's long axis (head direction) along ``up`` (standing), along +- the cloud's
        principal axis, and along +- that axis laid parallel to the floor (lying, where the
        visible surface is foreshortened), each turned about the axis in 45 degree steps.
        """
        up = np.asarray(up, dtype=np.float64)
        centred = points - points.mean(axis=0)
        _, _, vt = np.linalg.svd(centred, full_matrices=False)
        flat = vt[0] - np.dot(vt[0], up) * up
        options = [up, vt[0], -vt[0]]
        if np.linalg.norm(flat) > 0.2:
            flat = flat / np.linalg.norm(flat)
            options += [flat, -flat]
        axes = []
        for a in options:
            if all(np.dot(a, b) < 0.97 for b in axes):
                axes.append(a)
        model_up = np.array([0.0, -1.0, 0.0])
        out = []
        for axis in axes:
            base = rotation_between(model_up, axis)
            for k in range(8):
                out.append(rotation_about(axis, k * np.pi / 4) @ base)
        return np.array(out)

    def init(self, depth0, pose=None, foreground=None):
        """Find the body in the first frame (automatic), or start from ``pose`` (48,) when given.

        ``foreground``: the frame's segmentation when the caller already has it.

        Returns
        -------
        (48,) float pose.
        """
        t0 = time.perf_counter()
        fg = self._observe(depth0, foreground=foreground)
        self._use_prior = False
        if pose is not None:
            x = np.asarray(pose, dtype=np.float64).copy()
            e = float(self.energy(x[None])[0])
            self.init_info = {"mode": "given pose"}
        else:
            x, e = self._automatic_init(depth0, fg)
        self.pose = x
        self.velocity = np.zeros(self.body.dof)
        self.frame_log.append({"energy": e, "cost": self.unexplained(x)})
        self.timings["init"] += time.perf_counter() - t0
        if self._after_init is None:
            self._after_init = dict(self.timings)
            self._counts_after_init = dict(self.counts)
        else:
            self.counts["reinitialisations"] += 1
        return x.copy()

    def _automatic_init(self, depth0, fg):
        x, e, info = self.global_search(fg, depth0)
        self.init_info = {"mode": "automatic", **info, "energy": float(e)}
        return x, e

    def _floor_up(self, fg, points):
        """Unit 'up' vector: the floor normal toward the person, else camera -y."""
        plane = getattr(fg, "floor_plane", None)
        if plane is None:
            return np.array([0.0, -1.0, 0.0])
        plane = np.asarray(plane, dtype=np.float64)
        norm = np.linalg.norm(plane[:3])
        n, d = plane[:3] / norm, plane[3] / norm
        return n if float(np.mean(points @ n) + d) > 0 else -n

    def _facing_penalty(self, poses, fg):
        """Initial-heading prior ``kappa (1 - cos theta) / 2`` for poses ``(N, 48) -> (N,)``.

        ``theta``: angle between the body's forward direction (model -z) and the direction
        from the pelvis to the camera (first frame) or the last tracked forward direction
        (recovery after a lost track: bodies keep their heading); plus the same term for the angle between the head
        direction and "up" (upside-down bodies are rare). A depth image barely tells a
        body's front from its back; people mostly face the camera when a capture starts, so
        among fits of nearly equal likelihood the one facing the camera wins. ``kappa`` is
        :attr:`TrackerSettings.facing_prior` times the foreground's pixel count, i.e. a
        fraction of the pixels' worth of likelihood.
        """
        from ..body.rotations import rotvec_to_matrix

        poses = np.atleast_2d(poses)
        R = rotvec_to_matrix(poses[:, 3:6])
        forward = R @ np.array([0.0, 0.0, -1.0])
        head = R @ np.array([0.0, -1.0, 0.0])
        if self._heading is None:
            reference = -poses[:, 0:3] / np.linalg.norm(poses[:, 0:3], axis=1, keepdims=True)
        else:
            reference = self._heading[None]
        cos_face = np.sum(forward * reference, axis=1)
        cos_up = head @ self._up if self._up is not None else np.ones(len(poses))
        kappa = self.settings.facing_prior * float(np.count_nonzero(fg.mask))
        return kappa * 0.5 * ((1.0 - cos_face) + (1.0 - cos_up))

    def global_search(self, fg, depth=None):
        """Find the body without a previous pose: root orientations x arm poses, scored, then climbed.

        Candidates: every orientation of :meth:`initial_orientations` with the arms in four
        poses (relaxed A-pose, T-pose, raised, forward), placed so the model's extent along
        its long axis matches the foreground's and its centre lies behind the foreground's
        median point. The best 6 after scoring are refined on the root, the best 3 on every
        joint (with :attr:`search_climber`, coarser and longer than the per-frame search),
        and for "ep" / "hc+ep" given ``depth``, the association loop with the frame's part
        detections and a climb; the lowest energy (plus the heading prior) wins.

        Returns
        -------
        pose : (48,) float
        energy : float
        info : dict
        """
        points = robust_points(fg.points)
        if len(points) < 20:
            raise InputError(None, "no person found in the frame (foreground is empty)")
        up = self._floor_up(fg, points)
        self._up = up
        centre = np.median(points, axis=0)
        # the visible surface lies in front of the body's centre: push back along the ray
        centre = centre + 0.08 * centre / np.linalg.norm(centre)
        rotations = self.initial_orientations(points, up)
        arms = np.zeros((len(ARM_POSES), self.body.dof))
        for k, (rx, rz) in enumerate(ARM_POSES.values()):
            arms[k, [12, 14, 21, 23]] = rx, rz, rx, -rz
        poses = np.repeat(arms, len(rotations), axis=0)
        R = np.tile(rotations, (len(ARM_POSES), 1, 1))
        poses[:, 3:6] = matrix_to_rotvec(R)
        body_axis = R @ np.array([0.0, -1.0, 0.0])                      # (K, 3) head direction
        # model vertices at pelvis = 0, then shift so the centre and the axial extent match
        verts = np.asarray(self.render_body.posed_vertices(poses))         # (K, V, 3)
        proj_model = np.einsum("kvi,ki->kv", verts, body_axis)
        proj_cloud = (points - centre) @ body_axis.T                     # (M, K)
        mid_model = 0.5 * (proj_model.min(axis=1) + proj_model.max(axis=1))
        lo, hi = np.percentile(proj_cloud, [2.0, 98.0], axis=0)
        mid_cloud = 0.5 * (lo + hi)
        # pelvis t = (I - a a^T)(centre - mean_model) + a (a.centre + mid_cloud - mid_model)
        offset = centre - verts.mean(axis=1)
        offset -= np.einsum("ki,ki->k", offset, body_axis)[:, None] * body_axis
        poses[:, 0:3] = offset + (body_axis @ centre + mid_cloud - mid_model)[:, None] * body_axis
        # the visible extent is foreshortened and partly hidden: also try shifts along the axis
        shifted = [poses]
        for shift in AXIAL_SHIFTS:
            if shift:
                moved = poses.copy()
                moved[:, 0:3] += shift * body_axis
                shifted.append(moved)
        poses = np.concatenate(shifted)
        energies = self.energy(poses)
        facing = self._facing_penalty(poses, fg)
        order = np.argsort(energies + facing)
        root_blocks = self.search_climber.blocks[:2]
        coarse = []
        for i in order[:6]:
            x, e = self._climb(poses[i], start_energy=energies[i], blocks=root_blocks, passes=2,
                               climber=self.search_climber)
            coarse.append((e, int(i), x))
        coarse.sort(key=lambda c: c[0])
        best = None
        finalists = []
        for e, i, x in coarse[:3]:
            x, e = self._climb(x, start_energy=e, passes=self.settings.init_passes,
                               climber=self.search_climber)
            if depth is not None and self.method != "hc" and self.detector is not None:
                x, e, _ = self._associate(x, e, depth, fg)
                x, e = self._climb(x, start_energy=e, level_offset=1, climber=self.search_climber)
            score = e + float(self._facing_penalty(x[None], fg)[0])
            finalists.append({"candidate": int(i), "energy": round(float(e), 1),
                              "score": round(score, 1)})
            if best is None or score < best[0]:
                best = (score, i, x, e)
        _, i, x, e = best
        info = {"candidates": int(len(poses)), "orientations": int(len(rotations)),
                "chosen_orientation": int(i % len(rotations)),
                "chosen_arms": list(ARM_POSES)[(i // len(rotations)) % len(ARM_POSES)],
                "finalists": finalists}
        return x, e, info

    # ------------------------------------------------------------------ tracking
    def step(self, depth):
        """Track one frame; returns the pose ``(48,)``."""
        if self.pose is None:
            raise RuntimeError("call init(depth0) before step()")
        x_prev = self.pose
        x_pred, self._v_pred = self.prior.predict(x_prev, self.velocity)
        x_pred = self.body.clip(x_pred)
        fg = self._observe(depth, predicted=x_pred)
        self._absent = 0 if self.person_present(fg) else self._absent + 1
        if self._absent >= self.settings.absent_frames:
            return self._lose_person()
        self._use_prior = True
        starts = np.stack([x_pred, x_prev])
        e_starts = self.energy(starts)
        k = int(np.argmin(e_starts))
        x, e = starts[k], float(e_starts[k])
        if self.method in ("hc", "hc+ep"):
            x, e = self._climb(x, start_energy=e, passes=self.settings.passes)
        accepted = 0
        if self.method in ("ep", "hc+ep"):
            x, e, accepted = self._associate(x, e, depth, fg)
        if self.method != "ep":
            x, e = self._polish(x)
        cost = self.unexplained(x)
        recovered = False
        if self.method != "ep" and self._lost(cost):
            recovered, x, cost = self._recover(x, cost, depth, fg)
        self.velocity = np.zeros(self.body.dof) if recovered else pose_velocity(x_prev, x)
        self.pose = x
        self.frame_log.append({"energy": e, "cost": cost, "accepted": accepted, "recovered": recovered})
        return x.copy()

    def person_present(self, foreground) -> bool:
        """Whether a :class:`~depthtrack.detect.Foreground` holds a person (see
        :attr:`TrackerSettings.min_person_area`)."""
        return visible_area(foreground, self.camera) >= self.settings.min_person_area

    def _lose_person(self):
        """No person for :attr:`TrackerSettings.absent_frames` frames: forget the track (the
        next person starts afresh)."""
        self.pose = None
        self._absent = 0
        self.velocity = np.zeros(self.body.dof)
        self.counts["frames_without_person"] += 1
        self.frame_log.append({"absent": True})
        return None

    def _polish(self, x):
        """Finest rung of the search again at the fine tile resolution (when configured)."""
        if self.fine_renderer is None:
            return x, float(self.energy(x[None])[0])
        self.renderer = self.fine_renderer
        try:
            return self._climb(x, level_offset=self.settings.levels - 1, climber=self.fine_climber)
        finally:
            self.renderer = self.coarse_renderer

    def _lost(self, cost) -> bool:
        """Whether the fit ``cost`` (mean tile cost) jumped above the recent ones (lost track)."""
        recent = [f["cost"] for f in self.frame_log[-8:] if "cost" in f]
        if len(recent) < 1:
            return False
        typical = float(np.median(recent))
        s = self.settings
        return cost > s.lost_ratio * typical and cost > typical + s.lost_margin

    def _recover(self, x, cost, depth, fg):
        """Global search on this frame; taken when its likelihood beats the tracked pose's."""
        t = time.perf_counter()
        self._use_prior = False
        from ..body.rotations import rotvec_to_matrix
        self._heading = rotvec_to_matrix(self.pose[3:6]) @ np.array([0.0, 0.0, -1.0])
        try:
            y, _, _ = self.global_search(fg, depth)
        except InputError:
            return False, x, cost
        finally:
            self._heading = None
        y_cost = self.unexplained(y)
        self.timings["recover"] += time.perf_counter() - t
        self.counts["recoveries_tried"] += 1
        if y_cost < cost:
            self.counts["recoveries"] += 1
            return True, y, y_cost
        return False, x, cost

    def track_sequence(self, seq, progress=None, init_pose=None) -> TrackResult:
        """Track every frame of a :class:`~depthtrack.io.sequence.Sequence`.

        Frames without a person (:meth:`person_present`) get NaN poses and joints; tracking
        (re)starts with the automatic initialisation on the next frame with a person, so a
        recording may open on an empty room and the subject may leave and come back.

        Parameters
        ----------
        seq : Sequence
        progress : Progress or None
            ``update(1)`` after each frame.
        init_pose : (48,) float, optional
            Start from this pose (ablation: ground-truth initialisation) instead of the
            automatic initialisation.
        """
        F = len(seq)
        poses = np.full((F, self.body.dof), np.nan)
        t0 = time.perf_counter()
        i = -1
        while i + 1 < F:
            i += 1
            depth = seq.depth(i)
            if i == 0 and init_pose is not None:
                x = self.init(depth, pose=init_pose)
            elif self.pose is None:
                fg = self.segmenter(depth, self.camera)
                x = self.init(depth, foreground=fg) if self.person_present(fg) else None
                if x is None:
                    self.counts["frames_without_person"] += 1
                elif self.settings.heading_frames > 0 and i + self.settings.heading_frames < F:
                    last = self._settle_heading(seq, i, depth, poses, progress)
                    if last > i:
                        i = last
                        continue
            else:
                x = self.step(depth)
                if x is None:                       # the track was dropped: its empty frames too
                    poses[i - self.settings.absent_frames + 1:i + 1] = np.nan
                    self.counts["frames_without_person"] += self.settings.absent_frames - 1
            if x is not None:
                poses[i] = x
            if progress is not None:
                progress.update(1)
        total = time.perf_counter() - t0
        joints = np.asarray(self.body.joint_positions(poses))
        return TrackResult(poses, joints, self.timing_summary(total, F), self.describe())

    #: Tracker attributes that make up the state of a track (saved and restored by
    #: :meth:`_settle_heading`; timings and counts keep accumulating).
    _TRACK_STATE = ("pose", "velocity", "_v_pred", "_use_prior", "_weight", "roi", "foreground",
                    "frame_log", "init_info", "_up", "_floor", "_heading", "_detections", "_absent")

    def _save_state(self) -> dict:
        state = {k: copy.deepcopy(getattr(self, k)) for k in self._TRACK_STATE}
        state["frames_without_person"] = self.counts["frames_without_person"]
        return state

    def _restore_state(self, state: dict) -> None:
        for k, v in state.items():
            if k == "frames_without_person":
                self.counts[k] = v
            else:
                setattr(self, k, v)

    def turned_pose(self, pose):
        """``pose (48,)`` turned half a turn about the body's long axis through the pelvis:
        the same silhouette seen from the other side (front and back swapped)."""
        from ..body.rotations import rotvec_to_matrix

        x = np.array(pose, dtype=np.float64)
        R = rotvec_to_matrix(x[3:6])
        axis = R @ np.array([0.0, -1.0, 0.0])
        x[3:6] = matrix_to_rotvec((rotation_about(axis, np.pi) @ R)[None])[0]
        return x

    def _settle_heading(self, seq, first, depth, poses, progress) -> int:
        """Decide between the initial pose and its turned twin by tracking both.

        A depth image barely tells a body's front from its back, and the initial heading
        prior (:meth:`_facing_penalty`) assumes the person faces the camera. Motion does tell
        them apart: knees and elbows bend one way only. Both hypotheses are tracked through
        the next :attr:`TrackerSettings.heading_frames` frames; the turned one is kept only
        when its fit explains the frames clearly better (mean :meth:`unexplained` share lower
        by :attr:`TrackerSettings.heading_margin`). ``depth`` is frame ``first``, where the
        track started. Fills ``poses`` and returns the last frame index processed (``first``
        when the check could not run).
        """
        K = self.settings.heading_frames
        depths = [seq.depth(j) for j in range(first + 1, first + K + 1)]
        start = self._save_state()

        def run(x0):
            self.pose = x0
            out = []
            for d in depths:
                x = self.step(d)
                if x is None:
                    return None, None
                out.append(x)
            costs = [f["cost"] for f in self.frame_log[-K:]]
            return np.array(out), float(np.mean(costs))

        x_front = self.pose.copy()
        track_a, cost_a = run(x_front)
        if track_a is None:
            self._restore_state(start)
            return first
        after_a = self._save_state()
        self._restore_state(start)
        self._observe(depth, foreground=self.foreground)     # the renderer holds the last frame
        self._use_prior = False
        x_turned, _ = self._climb(self.turned_pose(x_front), passes=self.settings.init_passes,
                                  climber=self.search_climber)
        track_b, cost_b = run(x_turned)
        choice = "initial"
        if track_b is not None and cost_b < (1.0 - self.settings.heading_margin) * cost_a:
            choice = "turned"
            poses[first] = x_turned
            poses[first + 1:first + K + 1] = track_b
        else:
            self._restore_state(after_a)
            poses[first] = x_front
            poses[first + 1:first + K + 1] = track_a
        self.init_info = {**self.init_info, "heading_check": {
            "frames": K, "unexplained_initial": round(cost_a, 4),
            "unexplained_turned": None if cost_b is None else round(cost_b, 4), "kept": choice}}
        if progress is not None:
            progress.update(K + 1)           # the initial frame too
        return first + K

    def timing_summary(self, total, frames) -> dict:
        """Where the time went: totals, and per tracked frame (initialisation excluded).

        Stages (seconds): ``segment`` foreground segmentation; ``render`` candidate rendering
        and scoring on the GPU path (TileRenderer.costs); ``search`` hill-climbing work on
        the CPU (candidate generation, kinematics, prior); ``detect`` part detection;
        ``evidence`` evidence propagation (unscented transform); ``association`` the whole
        association loop (includes its detect, evidence, render and search time);
        ``recover`` global searches after a lost track (includes their render time);
        ``other`` = per-frame total minus segment, render, search, detect, evidence (frame
        loading, bookkeeping).
        """
        base = self._after_init or {k: 0.0 for k in self.timings}
        tracked = max(frames - 1, 1)
        init = self.timings["init"]
        per = {k: round(1000 * (v - base.get(k, 0.0)) / tracked, 2)
               for k, v in self.timings.items() if k != "init"}
        tracking = max(total - init, 1e-9)
        per["total"] = round(1000 * tracking / tracked, 2)
        per["other"] = round(per["total"] - sum(per[k] for k in ("segment", "render", "search",
                                                                 "detect", "evidence")), 2)
        cands = self.counts["candidates"] - self._counts_after_init.get("candidates", 0)
        return {"total_s": round(total, 3), "init_s": round(init, 3), "frames": int(frames),
                "per_frame_ms": per,
                "fps": round(frames / total, 3) if total > 0 else None,
                "fps_excluding_init": round(tracked / tracking, 3) if frames > 1 else None,
                "candidates_per_frame": round(cands / tracked, 1),
                "init_candidates": int(self._counts_after_init.get("candidates", 0))}

    def describe(self) -> dict:
        return {"method": self.method, "likelihood": self.likelihood,
                "settings": self.settings.to_dict(), "prior": self.prior.to_dict(),
                "initialisation": self.init_info, "counts": dict(self.counts),
                "energies": [f.get("energy") for f in self.frame_log]}


# ---------------------------------------------------------------------- helpers for callers
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

    from ..motion.retarget import best_rotation

    target = np.asarray(joints, dtype=np.float64)
    known = np.all(np.isfinite(target), axis=1)
    if known.sum() < 4:
        raise InputError(None, "ground truth has fewer than 4 known joints in the first frame")
    rest = np.asarray(body.joint_positions(np.zeros(body.dof)))
    torso = [i for i in (1, 2, 3, 6, 9, 12) if known[i]]
    if len(torso) < 3:
        torso = list(np.flatnonzero(known))
    R = best_rotation(rest[torso] - rest[torso].mean(0), target[torso] - target[torso].mean(0))
    x0 = np.zeros(body.dof)
    x0[3:6] = matrix_to_rotvec(R)
    x0[0:3] = target[torso].mean(0) - R @ rest[torso].mean(0)

    def residual(p):
        d = (np.asarray(body.joint_positions(p)) - target)[known].ravel()
        return np.concatenate([d, regularisation * p[6:]])

    lo = np.where(np.isfinite(body.lower), body.lower, -np.inf)
    hi = np.where(np.isfinite(body.upper), body.upper, np.inf)
    x0 = np.clip(x0, lo + 1e-9, hi - 1e-9)
    fit = least_squares(residual, x0, bounds=(lo, hi), x_scale=0.3, max_nfev=200)
    return fit.x


def body_for_sequence(seq, segmenter=None, frame: int = 0, settings=None, fit_height: bool = True):
    """The default body scaled to the subject, and where its height came from.

    Height from ``sequence.json`` ``subject.height_m`` when present. Otherwise a first
    guess from the foreground extent of the first frame (from ``frame`` on) with a person, (:func:`estimate_height`), which raised arms
    inflate and bent or foreshortened legs shrink; with ``fit_height`` the height is then
    chosen by the likelihood: the automatic initialisation ("hc") runs on the frame for
    heights 8 % apart around the guess (five, then further out while the best is at an
    edge; within 1.2 .. 2.2 m), and the height whose fitted pose explains the frame best
    wins, refined by a parabola through its neighbours.

    Returns
    -------
    body : BodyModel
    height : dict
        ``{"height_m": float, "source": str}`` and, when fitted, ``"candidates"``: the heights
        tried and their likelihood energies.
    """
    from ..body import BodyModel

    if seq.subject_height:
        h = float(seq.subject_height)
        return BodyModel.default(height=h), {"height_m": h, "source": "sequence.json subject.height_m"}
    if segmenter is None:
        from ..detect import segment_foreground as segmenter
    min_area = (settings or TrackerSettings()).min_person_area
    for frame in range(frame, len(seq)):       # the first frame with a person in it
        depth = seq.depth(frame)
        fg = segmenter(depth, seq.camera)
        if visible_area(fg, seq.camera) >= min_area:
            break
    else:
        raise InputError(seq.path, "no person found in any frame")
    points = robust_points(fg.points)
    guess = estimate_height(points)
    if not fit_height:
        return BodyModel.default(height=guess), {"height_m": round(guess, 3),
                                                 "source": "estimated from the first frame's foreground"}
    t0 = time.perf_counter()
    tried = {}

    def energy_at(h):
        h = round(float(np.clip(h, 1.2, 2.2)), 3)
        if h not in tried:
            tracker = Tracker(BodyModel.default(height=h), seq.camera, method="hc", fps=seq.fps,
                              settings=settings, segmenter=segmenter)
            tried[h] = tracker._likelihood_energy(tracker.init(depth, foreground=fg))
        return h

    ratio = 1.08
    grid = [energy_at(guess * ratio ** k) for k in (-2, -1, 0, 1, 2)]
    # walk outwards while the best height is at an edge of what was tried
    for _ in range(3):
        heights = sorted(tried)
        best = min(heights, key=tried.get)
        if best == heights[0] and best > 1.2:
            energy_at(best / ratio)
        elif best == heights[-1] and best < 2.2:
            energy_at(best * ratio)
        else:
            break
    heights = np.array(sorted(tried))
    energies = np.array([tried[h] for h in heights])
    k = int(np.argmin(energies))
    h = float(heights[k])
    if 0 < k < len(heights) - 1:
        # vertex of the parabola through the best height and its neighbours, in log height
        # (the grid is geometric)
        x0, x1, x2 = np.log(heights[k - 1:k + 2])
        e0, e1, e2 = energies[k - 1:k + 2]
        denom = (x0 - x1) * (x0 - x2) * (x1 - x2)
        a = (x2 * (e1 - e0) + x1 * (e0 - e2) + x0 * (e2 - e1)) / denom
        b = (x2 ** 2 * (e0 - e1) + x1 ** 2 * (e2 - e0) + x0 ** 2 * (e1 - e2)) / denom
        if a > 0:
            h = float(np.exp(np.clip(-b / (2 * a), x0, x2)))
    return BodyModel.default(height=h), {
        "height_m": round(h, 3),
        "source": "fitted to the first frame by the likelihood (no subject.height_m)",
        "foreground_guess_m": round(guess, 3),
        "seconds": round(time.perf_counter() - t0, 2),
        "candidates": [{"height_m": round(float(a), 3), "energy": round(float(b), 1)}
                       for a, b in zip(heights, energies)]}


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
    summary : dict
        For ``summary.json``: method, likelihood, initialisation, body height and its source,
        settings, prior, timings per stage, ``seconds`` and ``processing_fps``.
    """
    body, height = body_for_sequence(seq, segmenter, settings=settings)
    tracker = Tracker(body, seq.camera, method=method, likelihood=likelihood, fps=seq.fps,
                      settings=settings, segmenter=segmenter, detector=detector)
    init_pose = None
    if init_from_groundtruth:
        joints = seq.joints
        if joints is None:
            raise InputError(seq.path, "--init-from-groundtruth needs groundtruth/joints.csv")
        init_pose = fit_pose_to_joints(body, joints[0])
    t0 = time.perf_counter()
    result = tracker.track_sequence(seq, progress=progress, init_pose=init_pose)
    seconds = time.perf_counter() - t0
    info = result.info
    summary = {
        "method": method,
        "likelihood": likelihood,
        "init_from_groundtruth": bool(init_from_groundtruth),
        "initialisation": ("ground truth of frame 0 (ABLATION: --init-from-groundtruth)"
                           if init_from_groundtruth else "automatic (no ground truth used)"),
        "initialisation_details": info["initialisation"],
        "body_height_m": height["height_m"],
        "body_height_source": height["source"],
        "body_height_fit": {k: v for k, v in height.items() if k not in ("height_m", "source")} or None,
        "seconds": round(seconds, 3),
        "processing_fps": round(len(seq) / seconds, 3) if seconds > 0 else None,
        "timings": result.timings,
        "counts": info["counts"],
        "settings": info["settings"],
        "prior": info["prior"],
    }
    return result, body, summary
