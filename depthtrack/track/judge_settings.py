"""The settings groups of losing and finding the track: the loss judge and the fresh look
(``judge``) and the part recogniser's joint proposals (``propose``), which the judge, the
global search and the reach use; :class:`~.settings.TrackerSettings` nests them with the other
groups (:mod:`.settings`, which re-exports every name here)."""
from __future__ import annotations

from dataclasses import dataclass

from .setting_checks import check as _check
from .setting_checks import one_of as _one_of
from .setting_checks import positive as _positive


#: Which fresh looks their re-track takes back (:attr:`JudgeSettings.look_revoke`; the
#: rules of :func:`.retrack.revokes`).
LOOK_REVOKES = ("never", "refused", "unsupported", "outscored")
#: What a recovery's pose is judged by (:attr:`JudgeSettings.recover_by`).
RECOVER_BY = ("unexplained", "energy")


@dataclass(frozen=True)
class JudgeSettings:
    """Judge: whether the track is lost (then the recovery runs).

    The track counts as lost when the share of the observation the fitted pose leaves
    unexplained exceeds both ``lost_ratio`` times and ``lost_margin`` plus the median of the
    last ``window`` frames that were not themselves judged lost. While lost, the global
    search runs on every frame; a loss that lasts ``max_lost_frames`` frames is closed
    unrecovered (the scene has changed: the recent shares start afresh). Every loss is
    reported (:attr:`TrackingState.recoveries`, ``summary.json``).

    ``recover_by``: what a recovery's pose must beat the tracked pose on to replace it
    (where the track was lost by its unexplained share; a loss the proposals found is
    judged by them, :attr:`ProposalSettings.accept_margin`): ``"unexplained"``, a lower
    unexplained share, or ``"energy"``, a lower energy without the motion prior on the
    heading recheck judge's tiles (:attr:`HeadingSettings.judge_tile`), which also counts
    the body drawn where the image has no person. ``"energy"`` by default since 2026-11-27
    (dev, paired: +0.0 points, none lost more than 2, 1.4 % fewer candidates: the rule set
    before met; README, "Lost and found").

    ``look_every``: every that many frames (0 = never) a track not lost gets a
    fresh look: the recovery's global search runs as for a loss and its pose replaces the
    track when its energy (as ``recover_by``) is lower by the fraction ``look_margin``,
    reported as a recovery with reason ``"look"`` and re-tracked backwards like one. A track
    that settled a quarter turn off explains the image nearly as well as it can from there,
    so its unexplained share never jumps (dev probe: 105_05 from 90 degrees seed 1, 53.5 ->
    91.3 %; about a fifth more time a frame at 8; README, "A fresh look"). 8 by default
    since 2026-11-29 (dev, 72 tracks paired: +1.0 points, none lost more than 1.6, from 90
    degrees 80.5 -> 87.2 %; test 91.1 -> 91.7 %; ``--preset fast`` keeps it off).
    ``look_turn``:
    the most degrees the look's pose may be turned from the track's (the larger of the angles
    between their root forward directions and between their long axes) and be taken: a half
    turn front for back is the front/back recheck's call, made on its votes over frames and
    re-tracked, not one search's, and a body read head for feet (a cartwheel's star upside
    down: the forward direction kept) the proposals' (README, "A fresh look"). A look
    refused so counts in ``counts.looks_turned_away``. A look's re-track sets no floor for
    later re-tracks (:func:`.retrack.was_look`). ``look_revoke``: the :data:`LOOK_REVOKES` rule that takes a
    look back once its re-track (:attr:`HeadingSettings.retro_after` with ``"recovery"``) has
    tracked the frames before it from the look's pose, as ``retro_revoke`` does a heading
    switch: ``"outscored"``, taken back when those frames score worse in sum and better on
    fewer than half of them (a look is one frame's energy; the frames before it must bear it
    out: dev 90_05 seed 3, a look on frame 16 10 cm further from the truth on the frames it
    re-tracked, 82.4 -> 55.1 %); ``"never"``, as before 2026-11-29.
    """

    lost_ratio: float = 1.6
    lost_margin: float = 0.15
    window: int = 8
    max_lost_frames: int = 10
    recover_by: str = "energy"
    look_every: int = 8
    look_margin: float = 0.1
    look_turn: float = 120.0
    look_revoke: str = "outscored"

    def __post_init__(self):
        _positive(self, "lost_ratio", "window", "max_lost_frames")
        _positive(self, "lost_margin", "look_every", "look_margin", allow_zero=True)
        _one_of(self, "recover_by", RECOVER_BY)
        _one_of(self, "look_revoke", LOOK_REVOKES)
        _check(0.0 <= float(self.look_turn) <= 180.0,
               f"JudgeSettings.look_turn must be 0 to 180 degrees, not {self.look_turn!r}")


@dataclass(frozen=True)
class ProposalSettings:
    """The part recogniser's joint proposals in the tracker (:mod:`.proposals`; "ep" and "hc+ep").

    ``enabled``: run the recogniser on every frame. Its side-free proposals of at least
    ``min_confidence`` (m^2 of part surface) give the global search candidates
    (``start_candidates``) and the judge a second opinion: a pose with more than
    ``lost_fraction`` of its checked trunk joints farther than ``distance`` (m) from every
    proposal disagrees; ``lost_frames`` such frames in a row and the track counts as lost
    (reason ``"proposals"``), and a recovered pose replaces it when it disagrees less and
    leaves at most ``accept_margin`` more of the observation unexplained. ``start_weight``
    times the foreground's pixel count times the disagreeing share is added to every start
    finalist's score.

    ``evidence``: the proposals of the ``evidence_joints`` classes (of ``shoulder, elbow,
    wrist, hip, knee, ankle``) also join the association stage as side-free detections of
    the joint-centre parts (a knee proposal may be either knee), so evidence propagation
    can pull a lost elbow or knee back. A proposal within ``evidence_distance`` (m) of the
    model's joint of its class counts as explained; of the others at most
    ``evidence_max`` correspondences are tried per frame, most confident first, after the
    part detector's.

    ``reach_every``: every so many frames (0 = never) each limb is also tried re-fitted to the
    wrist or ankle proposals it can reach and is not at; the best, climbed, replaces the pose
    when its energy without the motion prior is lower by the fraction ``reach_margin``
    (:mod:`.reach`: a hand or foot tracked far from where it is, which the association's
    pruning never brings back). ``reach_unexplained`` > 0 also offers each limb the farthest
    reachable point of each blob of the person's pixels the pose leaves unexplained that
    holds at least that share of the person's pixels (on the full image; 0 = off):
    a limb tracked hidden while the real one is in plain view, with no proposal for it
    (0.02 on dev, 2026-11-29: worse on the whole, README "Reaching into what the pose
    leaves unexplained"); with ``reach_hidden_only`` only a limb whose forearm and hand
    (shin and foot) show on fewer pixels than that share may reach so.
    """

    enabled: bool = True
    min_confidence: float = 0.002
    distance: float = 0.3
    lost_fraction: float = 0.5
    lost_frames: int = 3
    accept_margin: float = 0.1
    start_candidates: bool = True
    start_weight: float = 0.1
    evidence: bool = True
    evidence_joints: tuple = ("elbow", "knee")
    evidence_distance: float = 0.2
    evidence_max: int = 4
    reach_every: int = 2
    reach_margin: float = 0.03
    reach_unexplained: float = 0.0
    reach_hidden_only: bool = False

    def __post_init__(self):
        for name in ("enabled", "evidence", "reach_hidden_only"):
            _check(isinstance(getattr(self, name), bool),
                   f"ProposalSettings.{name} must be true or false, not {getattr(self, name)!r}")
        object.__setattr__(self, "evidence_joints", tuple(self.evidence_joints))
        known = ("shoulder", "elbow", "wrist", "hip", "knee", "ankle")
        _check(all(j in known for j in self.evidence_joints),
               f"ProposalSettings.evidence_joints must be of {', '.join(known)}, not "
               f"{self.evidence_joints!r}")
        _check(isinstance(self.evidence_max, int) and self.evidence_max >= 0,
               f"ProposalSettings.evidence_max must be an integer >= 0, not {self.evidence_max!r}")
        _positive(self, "evidence_distance")
        _check(isinstance(self.start_candidates, bool),
               f"ProposalSettings.start_candidates must be true or false, not {self.start_candidates!r}")
        _positive(self, "distance", "lost_frames")
        _positive(self, "min_confidence", "lost_fraction", "accept_margin", "start_weight",
                  "reach_every", "reach_margin", "reach_unexplained", allow_zero=True)
