"""What one frame hands the next: :class:`TrackingState` (frozen), and the per-frame output.

Stages take a state and return a new one (``dataclasses.replace``); trying an alternative
(the turned twin, a recovery, another body height) runs a stage on a state and keeps the
better result, with nothing to save or restore.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class TrackingState:
    """The track between frames.

    Attributes
    ----------
    pose : (48,) float or None
        Last tracked pose; None before the first person or after the track was dropped.
    velocity : (48,) float
        Last velocity ``x_t (-) x_{t-1}`` (zero after a start or a recovery).
    roi : (u0, v0, size) or None
        Last region of interest (kept when a frame's foreground is empty).
    floor : (4,) float or None
        Last floor plane the segmentation found.
    absent : int
        Frames in a row without a person while tracking.
    frames_without_person : int
        Counter: frames that got no pose.
    log : tuple of dict
        Per frame: ``energy``, ``cost`` (unexplained share), ``accepted``, ``recovered``;
        ``{"absent": True}`` when the track was dropped. The frame loop adds ``index``, the
        entry's frame in the sequence (:func:`.loop.stream_poses`).
    init_info : dict
        How the last start went (``mode``, candidates, finalists, ``heading_check``).
    lost : dict or None
        While the track is judged lost: ``frame`` and ``reason`` of the loss (:mod:`.judge`).
    recoveries : tuple of dict
        Every loss: ``frame``, ``reason``, ``frames_to_recover`` (0 = back on the frame it
        was lost; None = closed unrecovered after :attr:`JudgeSettings.max_lost_frames`).
    heading_votes : int
        Heading rechecks in a row that preferred the turned twin (:mod:`.heading`).
    proposal_misses : int
        Frames in a row whose pose the recogniser's proposals disagree with (:mod:`.proposals`).
    heading_evidence : float
        The rechecks' accumulated evidence for the twin (a CUSUM, :func:`.heading.recheck_heading`).
    polished_votes, polished_evidence : int, float
        The same from the polished close calls' leads, with
        :attr:`HeadingSettings.polish_evidence` ``"separate"`` (else 0).
    heading_switches : tuple of dict
        Each time a recheck replaced the track by its turned twin: ``frame``, energies.
    limb_swaps : tuple of dict
        Each time the sides recheck exchanged the legs' or the arms' sides: ``frame``,
        ``limbs``, energies (:func:`.heading.recheck_limb_sides`).
    reaches : tuple of dict
        Each time a limb was re-fitted to a far proposal: ``frame``, ``limb``, energies
        (:func:`.reach.recheck_reach`).
    reseats : tuple of dict
        Each time a limb was re-seated from the limb poses: ``frame``, ``limb``, energies
        (:func:`.reseat.recheck_reseat`).
    retracks : tuple of dict
        Each time the frames before a correction were tracked again backwards
        (:attr:`HeadingSettings.retro_frames`, ``retro_after``): its ``kind``
        (``"heading"``, ``"limbs"``, ``"recovery"``), ``index`` of the correction, ``frames``,
        ``first`` and ``last`` re-tracked frame, the mean energies ``energy_forward`` and
        ``energy_backward`` the choice compares, the mean unexplained shares
        ``share_forward`` and ``share_backward``, ``taken``, and why the backward track
        stopped (``stopped``).
    """

    pose: np.ndarray | None = None
    velocity: np.ndarray = field(default_factory=lambda: np.zeros(48))
    roi: tuple | None = None
    floor: np.ndarray | None = None
    absent: int = 0
    frames_without_person: int = 0
    log: tuple = ()
    init_info: dict = field(default_factory=dict)
    lost: dict | None = None
    recoveries: tuple = ()
    heading_votes: int = 0
    heading_evidence: float = 0.0
    polished_votes: int = 0
    polished_evidence: float = 0.0
    proposal_misses: int = 0
    heading_switches: tuple = ()
    limb_swaps: tuple = ()
    reaches: tuple = ()
    reseats: tuple = ()
    retracks: tuple = ()

    @property
    def frame(self) -> int:
        """Index of the next frame among those tracked (log entries): the sequence's frame
        index when the person is there from the first frame."""
        return len(self.log)

    def replace(self, **changes) -> "TrackingState":
        return dataclasses.replace(self, **changes)

    def logged(self, entry: dict, **changes) -> "TrackingState":
        """A copy with ``entry`` appended to the log (and ``changes``)."""
        return dataclasses.replace(self, log=self.log + (entry,), **changes)

    def recent_costs(self, window: int) -> list:
        """Unexplained shares of the last ``window`` log entries that have one, not counting
        frames judged lost (a lost track must not become the norm it is judged by) and
        nothing before a loss closed unrecovered (``"reset"`` in its entry)."""
        costs = []
        for f in reversed(self.log):
            if len(costs) >= window:
                break
            if "cost" in f and not f.get("lost"):
                costs.append(f["cost"])
            if f.get("reset"):
                break
        return costs[::-1]


@dataclass
class TrackedFrame:
    """One frame's output of :func:`~depthtrack.track.tracker.track_stream`.

    Attributes
    ----------
    index : int
        Frame number, from 0.
    pose : (48,) float or None
        None where there is no person.
    joints : (15, 3) float or None
        Contract joints (camera frame, metres).
    """

    index: int
    pose: np.ndarray | None
    joints: np.ndarray | None


@dataclass
class TrackResult:
    """Output of :meth:`Tracker.track_sequence`.

    Attributes
    ----------
    poses : (F, 48) float
    joints : (F, 15, 3) float
        Contract joints (camera frame, metres).
    timings : dict
        :meth:`Recorder.timing_summary`: initialisation seconds, milliseconds per tracked frame
        for each stage (``per_frame_ms``), frames per second, candidates per frame.
    info : dict
        Method, likelihood, settings, initialisation, per-frame energies and counts.
    """

    poses: np.ndarray
    joints: np.ndarray
    timings: dict
    info: dict = field(default_factory=dict)
