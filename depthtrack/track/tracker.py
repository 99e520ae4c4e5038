"""The per-frame tracker: a pipeline of stages over a :class:`~.state.TrackingState`.

One frame (:meth:`Tracker.advance`)::

    observe (observe.py) -> predict, search (search.py) -> associate and propagate
    (propagate.py) -> polish (search.py) -> recheck (rechecks.py) -> judge, recover
    (judge.py)

and a start (:meth:`Tracker.start`): observe -> global search (start.py), then the
front/back check (heading.py). A state goes in and a new one comes out; the stages read the
tracker's fixed parts (body, camera, settings, climbers, renderers, recorder) and never
change them. Timings and counts go to a :class:`~.record.Recorder`.

Methods (``method=``), following the ToF paper's experiments:

``"hc"``
    Model-based search only: start from the better of the constant-velocity prediction and
    the previous pose, then hill climbing (:mod:`.hill_climb`) on the MAP energy
    (:mod:`.energy`).
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

All three share the automatic start (:mod:`.start`), which needs the model-based search to
find the body at all. The frame loop is :mod:`.loop`: :func:`~.loop.track_stream` tracks depth
frames from any iterable and yields each frame's pose as soon as it is known;
:meth:`Tracker.track_sequence` and :func:`~.run.run_tracking` run the same loop over a sequence.
"""
from __future__ import annotations

import time
from contextlib import contextmanager

import numpy as np

from ..body.skeleton import JOINT_ID
from ..errors import InputError
from ..motion.prior import ConstantVelocityPrior, pose_velocity
from .energy import Energy, margin_floor, unexplained
from .evidence import PartModel
from .heading import CHANNELS_CLEARED, due
from .judge import judge_frame, loss_reason, proposal_check, recover
from .observe import as_depth, observe, person_present
from .propagate import associate_stage, evidence_parts
from .limb_prior import LimbPrior, load_mixtures
from .reach import LIMBS, far_side_limbs
from .rechecks import recheck_stage, tracked_hidden, turned_start
from .record import Recorder
from .renderers import RendererSet
from .reseat import limb_climber, limb_library, reseat_limbs
from .search import Climbers, polish, predict, search
from .settings import TrackerSettings
from .start import global_search
from .state import TrackingState, TrackResult

METHODS = ("hc", "ep", "hc+ep")
LIKELIHOODS = ("smoothed", "pixel")


class Tracker:
    """Track a body through depth frames: ``init(depth0)`` then ``step(depth)`` per frame.

    Owns its GL renderers: ``close()`` (or ``with Tracker(...) as t:``) releases them.

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
        The candidate renderer; it stays the caller's (not released by :meth:`close`).
    renderers : RendererSet, optional
        A whole set shared with other trackers (the height fit); it stays the caller's.
    """

    def __init__(self, body, camera, method: str = "hc+ep", likelihood: str = "smoothed", prior=None,
                 fps: float = 25.0, settings: TrackerSettings | None = None, segmenter=None,
                 detector=None, renderer=None, renderers=None):
        if method not in METHODS:
            raise InputError(None, f"unknown method {method!r}; choose one of {', '.join(METHODS)}")
        if likelihood not in LIKELIHOODS:
            raise InputError(None, f"unknown likelihood {likelihood!r}; choose one of "
                                   f"{', '.join(LIKELIHOODS)}")
        if settings is not None and not isinstance(settings, TrackerSettings):
            raise InputError(None, "settings must be a TrackerSettings")
        self.settings = s = settings or TrackerSettings()
        self.body = body
        try:
            self.render_body = body.with_mesh(s.observe.render_mesh)
        except (ValueError, AttributeError):
            self.render_body = body
        self.camera = camera
        self.method = method
        self.likelihood = likelihood
        self.smoothed = likelihood == "smoothed"
        self.fps = float(fps)
        self.prior = prior or ConstantVelocityPrior.load(fps=self.fps, damping=s.energy.damping,
                                                         huber=s.energy.prior_huber)
        if segmenter is None:
            from ..detect import segment_foreground as segmenter
        self.segmenter = segmenter
        if detector is None and method != "hc":
            from ..detect import detect_parts as detector
        self.detector = detector
        self.forest = None
        if method != "hc" and s.propose.enabled:
            from ..detect.recognizer import load_forest
            self.forest = load_forest()
        self.parts = PartModel.from_body(body, centres=evidence_parts(s.propose)
                                         if self.forest is not None else ())
        self.climbers = Climbers.build(s, self.fps, clip=body.clip)
        self.recorder = Recorder()
        self.state = TrackingState(velocity=np.zeros(body.dof))
        self._owns_renderers = renderers is None
        if renderers is None:
            renderers = RendererSet(self.render_body, camera, s.observe.tile, s.polish.fine_tile,
                                    coarse=renderer)
        else:
            renderers.set_body(self.render_body)
        self.renderers = renderers

    # ------------------------------------------------------------------ GL ownership
    def close(self) -> None:
        """Release the renderers this tracker made (idempotent)."""
        if self._owns_renderers and self.renderers is not None:
            self.renderers.release()
        self.renderers = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # ------------------------------------------------------------------ views of the state
    @property
    def pose(self):
        return self.state.pose

    @property
    def init_info(self) -> dict:
        return self.state.init_info

    @property
    def frame_log(self) -> list:
        return list(self.state.log)

    @property
    def counts(self) -> dict:
        return {**self.recorder.counts, "frames_without_person": self.state.frames_without_person}

    @property
    def timings(self) -> dict:
        return self.recorder.timings

    # ------------------------------------------------------------------ observe / energy
    def _observe(self, state, depth, predicted=None, foreground=None):
        """Segment (unless ``foreground`` is given), observe and upload; returns ``(frame, state)``."""
        if foreground is None:
            with self.recorder.timed("segment"):
                foreground = self.segmenter(depth, self.camera)
        joints = silhouette = None
        if predicted is not None:
            joints = np.asarray(self.body.joint_positions(predicted))
            silhouette = self.renderers.silhouette(predicted)
        frame, floor = observe(depth, foreground, self.camera, self.settings, roi=state.roi,
                               floor=state.floor, predicted_joints=joints,
                               predicted_silhouette=silhouette)
        self.renderers.upload(frame)
        return frame, state.replace(roi=frame.roi, floor=floor)

    def _energy(self, frame, hidden_of=None) -> Energy:
        """The energy of ``frame`` (uploaded) without the motion prior, on the coarse tiles.

        With :attr:`EnergySettings.limb_prior` ``"learned"``: the learned limb prior
        (:mod:`.limb_prior`) on the limbs. With ``hidden_of`` (a pose ``(48,)``) and
        :attr:`EnergySettings.hidden_prior_std`: the pose prior of that std on the limbs
        ``hidden_of`` shows hidden on ``frame`` (:meth:`hidden_joints`)."""
        s = self.settings.energy
        energy = Energy(self.renderers.coarse, frame.weight, self.smoothed, self.recorder,
                        s.pose_prior_std, s.twist_std)
        if s.limb_prior == "learned":
            energy = energy.with_limb_prior(
                LimbPrior(load_mixtures(), s.pose_prior_std, s.limb_prior_floor,
                          s.limb_prior_weight))
        if s.hidden_prior_std > 0 and hidden_of is not None:
            energy = energy.with_hidden(self.hidden_joints(frame, hidden_of), s.hidden_prior_std)
        return energy

    def hidden_joints(self, frame, pose) -> list:
        """The joints (skeleton indices) of the limbs ``pose (48,)`` shows hidden on ``frame``
        (:func:`.rechecks.tracked_hidden`: its lower segment on fewer than
        :attr:`HeadingSettings.reseat_hidden` of the person's pixels), or with
        :attr:`EnergySettings.hidden_prior_gate` ``"side"`` those on the far side of a trunk
        seen from the side (:func:`.reach.far_side_limbs`); only the arms with
        :attr:`EnergySettings.hidden_prior_limbs` ``"arms"``; counted in ``hidden_limbs``."""
        s = self.settings.energy
        if s.hidden_prior_gate == "side":
            limbs = far_side_limbs(self.body.joint_positions(pose), s.hidden_side_deg)
        else:
            limbs = tracked_hidden(self, frame, self.renderers.labels(pose))
        if s.hidden_prior_limbs == "arms":
            limbs = {limb for limb in limbs if limb.endswith("_arm")}
        self.recorder.count("hidden_limbs", len(limbs))
        return sorted(JOINT_ID[j] for limb in limbs for j in LIMBS[limb])

    @contextmanager
    def settings_overlaid(self, changes: dict):
        """The tracker with ``changes`` laid over its settings (:meth:`TrackerSettings.updated`)
        inside the block, its own settings again after it -- for the tracks that run with a
        recheck or the fresh look off (a re-track's backward track, a revoke, the start
        check's two tracks)."""
        settings = self.settings
        self.settings = settings.updated(changes)
        try:
            yield self
        finally:
            self.settings = settings

    def judge_energy(self) -> Energy:
        """The energy without the motion prior of the frame uploaded last, on the tiles the
        heading recheck judges on (:attr:`HeadingSettings.judge_tile`; 0 = the search's)."""
        return self._energy(self.renderers.uploaded).on(
            self.renderers.at_tile(self.settings.heading.judge_tile))

    def person_present(self, foreground) -> bool:
        """Whether a :class:`~depthtrack.detect.Foreground` holds a person."""
        return person_present(foreground, self.camera, self.settings)

    # ------------------------------------------------------------------ the stages of a frame
    def start(self, state, depth, pose=None, foreground=None):
        """A start on ``depth``: the global search (or ``pose (48,)`` when given).

        Returns ``(state, frame, pose (48,))``.
        """
        t0 = time.perf_counter()
        depth = as_depth(depth, self.camera)
        frame, state = self._observe(state, depth, foreground=foreground)
        energy = self._energy(frame)
        if pose is not None:
            x = np.asarray(pose, dtype=np.float64).copy()
            e = energy.one(x)
            info = {"mode": "given pose"}
        else:
            x, e, info = global_search(self, energy, frame,
                                       **self.settings.start.searched_in("start"))
            if self.settings.start.reseat_rounds:
                x, e, info["reseats"] = self._reseat_start(energy, x, e)
            info = {"mode": "automatic", **info, "energy": float(e)}
        state = state.logged({"energy": e, "cost": unexplained(energy, x)}, pose=x,
                             velocity=np.zeros(self.body.dof), init_info=info,
                             **CHANNELS_CLEARED, proposal_misses=0)
        self.recorder.add("init", time.perf_counter() - t0)
        if not self.recorder.initialised():
            self.recorder.count("reinitialisations")
        return state, frame, x.copy()

    def _reseat_start(self, energy, x, e):
        """The automatic start's limbs re-seated (:attr:`StartSettings.reseat_rounds`,
        :func:`.reseat.reseat_limbs`): ``(pose (48,), energy, events)``."""
        s = self.settings
        climb_limb = limb_climber(energy, self.climbers.start, self.recorder, s.heading.refit_level)
        floor = margin_floor(energy, s.heading.margins_over)
        return reseat_limbs(x, e, energy, climb_limb, limb_library(), s.start.reseat_rounds,
                            s.heading.reseat_margin, s.heading.reseat_climbs, self.body.clip, floor)

    def advance(self, state, depth):
        """Track one frame from ``state``; returns ``(state, pose (48,) or None)``.

        None when the track was dropped (no person for
        :attr:`ObserveSettings.absent_frames` frames in a row).
        """
        state, x, _ = self._advance(state, depth)
        return state, x

    def _advance(self, state, depth, score: bool = False):
        """:meth:`advance`, plus (with ``score``) the frame's scores at the tracked pose, else
        None (None too when the track was dropped): what the start's front/back check compares
        (:func:`.heading.settle_heading`). ``{"energy": the energy without the motion prior
        per foreground pixel}``, and ``"judged"``, the same on :attr:`HeadingSettings.
        judge_tile` tiles, with :attr:`HeadingSettings.judge_start`."""
        if state.pose is None:
            raise RuntimeError("call init(depth0) before step()")
        depth = as_depth(depth, self.camera)
        s = self.settings
        x_prev = state.pose
        x_pred, v_pred = predict(self.prior, self.body, x_prev, state.velocity)
        frame, state = self._observe(state, depth, predicted=x_pred)
        absent = 0 if self.person_present(frame.foreground) else state.absent + 1
        if absent >= s.observe.absent_frames:
            return state.logged({"absent": True}, pose=None, absent=0,
                                velocity=np.zeros(self.body.dof),
                                frames_without_person=state.frames_without_person + 1), None, None
        energy = self._energy(frame, hidden_of=x_pred).with_prior(self.prior, x_prev, v_pred)
        x, e = search(energy, self.climbers, s, self.recorder, x_pred, x_prev,
                      climb_it=self.method in ("hc", "hc+ep"))
        accepted = 0
        if self.method in ("ep", "hc+ep"):
            x, e, accepted = associate_stage(self, energy, frame, x, e)
        if self.method != "ep":
            with self.recorder.timed("polish"):
                x, e = polish(energy, self.renderers.fine, self.climbers, s, self.recorder, x)
        switched = None
        if self.method != "ep":
            x, changes, switched = recheck_stage(self, state, energy, frame, x)
            state = state.replace(**changes)
            if switched:
                e = energy.one(x)
        cost = unexplained(energy, x)
        recovered = False
        recent = state.recent_costs(s.judge.window)
        off, misses = proposal_check(self, frame, x, state.proposal_misses)
        reason = found = loss_reason(cost, recent, s, misses) if self.method != "ep" else None
        if reason is not None:
            recovered, x, cost = recover(self, energy, frame, x_prev, x, cost, reason, off)
            if recovered:
                off, misses = proposal_check(self, frame, x, 0)
                reason = loss_reason(cost, recent, s, misses)
        elif self.method != "ep" and state.lost is None and due(state, s.judge.look_every):
            # a fresh look: the global search replaces a track it beats by the margin
            recovered, x, cost = recover(self, energy, frame, x_prev, x, cost, "look", off,
                                         margin=s.judge.look_margin, max_turn=s.judge.look_turn)
            if recovered:
                found = "look"
                off, misses = proposal_check(self, frame, x, 0)
        changes, flags = judge_frame(state, cost, reason, s, found)
        velocity = (np.zeros(self.body.dof) if recovered or switched
                    else pose_velocity(x_prev, x))
        state = state.logged({"energy": e, "cost": cost, "accepted": accepted,
                              "recovered": recovered, "turned": switched in ("heading", "search"),
                              "switched": switched, "disagreement": off,
                              **flags},
                             pose=x, velocity=velocity, absent=absent, proposal_misses=misses,
                             **changes)
        if not score:
            return state, x.copy(), None
        pixels = max(float(np.count_nonzero(frame.foreground.mask)), 1.0)
        bare = energy.without_prior()
        scores = {"energy": bare.one(x) / pixels}
        h = s.heading
        if h.judge_start and h.judge_tile:
            scores["judged"] = self.judge_energy().one(x) / pixels
        return state, x.copy(), scores

    def track_through(self, state, depths):
        """``advance`` through ``depths``; ``(state, poses (K, 48), scores)``, or None when
        the track is dropped on the way. ``scores``: the means over the frames of the
        unexplained share (``"unexplained"``) and of the energy without the motion prior
        per foreground pixel (``"energy"``; and ``"judged"``, the same on tiles of
        :attr:`HeadingSettings.judge_tile` pixels, with :attr:`HeadingSettings.judge_start`)."""
        out, scores = [], []
        for d in depths:
            state, x, e = self._advance(state, d, score=True)
            if x is None:
                return None
            out.append(x)
            scores.append(e)
        costs = [f["cost"] for f in state.log[-len(depths):]]
        return state, np.array(out), {"unexplained": float(np.mean(costs)),
                                      **{k: float(np.mean([e[k] for e in scores])) for k in scores[0]}}

    def turned_start(self, frame):
        """:func:`.rechecks.turned_start` on the start ``frame``."""
        return turned_start(self, frame)

    # ------------------------------------------------------------------ the classic interface
    def init(self, depth0, pose=None, foreground=None):
        """Find the body in the first frame (automatic), or start from ``pose`` (48,) when given.

        ``foreground``: the frame's segmentation when the caller already has it.

        Returns
        -------
        (48,) float pose.
        """
        self.state, _, x = self.start(self.state, depth0, pose=pose, foreground=foreground)
        return x

    def step(self, depth):
        """Track one frame; returns the pose ``(48,)`` (None when the track was dropped)."""
        self.state, x = self.advance(self.state, depth)
        return x

    def unexplained(self, pose) -> float:
        """Share of the current observation that ``pose (48,)`` leaves unexplained."""
        return unexplained(Energy(self.renderers.coarse, 1.0, self.smoothed, self.recorder), pose)

    def likelihood_energy(self, pose, frame) -> float:
        """The likelihood term of the energy of ``pose (48,)`` on ``frame`` (uploaded)."""
        return self._energy(frame).likelihood(pose)

    # ------------------------------------------------------------------ the frame loop
    def stream(self, frames, init_pose=None):
        """Track depth frames from any iterable; yields ``(index, pose (48,) or None)`` in order
        (:func:`.loop.stream_poses`; each pose final-polished where
        :attr:`~.settings.PolishSettings.final_tile` asks, :mod:`.final_polish`)."""
        from .final_polish import final_polished
        from .loop import stream_poses

        if self.settings.polish.final_tile and self.method != "ep":
            return final_polished(self, frames, init_pose)
        return stream_poses(self, frames, init_pose)

    def track_sequence(self, seq, progress=None, init_pose=None) -> TrackResult:
        """Track every frame of a :class:`~depthtrack.io.sequence.Sequence` (:meth:`stream`).

        Frames without a person get NaN poses and joints.

        Parameters
        ----------
        seq : Sequence
        progress : Progress or None
            ``update(1)`` after each frame.
        init_pose : (48,) float, optional
            Start from this pose (ablation: ground-truth initialisation) instead of the
            automatic start.
        """
        F = len(seq)
        poses = np.full((F, self.body.dof), np.nan)
        t0 = time.perf_counter()
        for i, x in self.stream((seq.depth(j) for j in range(F)), init_pose=init_pose):
            if x is not None:
                poses[i] = x
            if progress is not None:
                progress.update(1)
        total = time.perf_counter() - t0
        joints = np.asarray(self.body.joint_positions(poses))
        return TrackResult(poses, joints, self.timing_summary(total, F), self.describe())

    def timing_summary(self, total, frames) -> dict:
        """:meth:`Recorder.timing_summary` of this tracker."""
        return self.recorder.timing_summary(total, frames)

    def describe(self) -> dict:
        return {"method": self.method, "likelihood": self.likelihood,
                "settings": self.settings.to_dict(), "prior": self.prior.to_dict(),
                "initialisation": self.state.init_info, "counts": self.counts,
                # a loss still open at the end: not recovered
                "recoveries": self._indexed(list(self.state.recoveries) + (
                    [{**self.state.lost, "frames_to_recover": None}] if self.state.lost else [])),
                "heading_switches": self._indexed(self.state.heading_switches),
                "limb_swaps": self._indexed(self.state.limb_swaps),
                "reaches": self._indexed(self.state.reaches),
                "reseats": self._indexed(self.state.reseats),
                # the heading switches' re-tracks, as before there were other kinds
                "heading_retracks": [r for r in self.state.retracks if r["kind"] == "heading"],
                "retracks": list(self.state.retracks),
                "energies": [f.get("energy") for f in self.state.log]}

    def _indexed(self, events) -> list:
        """Copies of ``events`` with ``index``, the sequence frame of the log entry ``frame``:
        the loop (:func:`.loop.stream_poses`) stamps each entry; ``frame`` counts only the
        frames tracked forwards, so it differs from ``index`` after frames without a person
        or a deferred start. With ``init``/``step`` the two are the same."""
        log = self.state.log
        out = []
        for e in events:
            f = e.get("frame")
            logged = f is not None and 0 <= f < len(log)
            # init/step stamp nothing: there the log index is the frames stepped
            index = log[f].get("index", f) if logged else e.get("index", f)
            out.append({**e, "index": index})
        return out


# the whole-sequence entry points, importable from here as before the split into stages
from .height import body_for_sequence  # noqa: E402,F401
from .loop import track_stream  # noqa: E402,F401
from .run import fit_pose_to_joints, run_tracking  # noqa: E402,F401
