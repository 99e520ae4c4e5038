"""The tracker's settings, one frozen group per stage, validated when made.

:class:`TrackerSettings` nests one group per stage of a frame (see :mod:`.tracker` for the
stages): ``observe``, ``energy``, ``search``, ``associate``, ``polish``, ``judge``,
``propose`` (the part recogniser's joint proposals, used by the start and the judge), and the
starts: ``start`` (the global search of the first frame and of a recovery), ``heading``
(the front/back check after an automatic start), ``height`` (the body-height fit) and
``shape`` (the body-shape fit from the first frames).
Every number of the search schedule lives here; ``TrackerSettings.to_dict()`` is written
whole into ``summary.json``. One set serves every sequence; never tune it per clip.

The groups of a frame are defined here but for ``judge`` and ``propose`` (in
:mod:`.judge_settings`); those of a start in :mod:`.start_settings` and :mod:`.heading_settings`
(all re-exported here), the shared value checks in :mod:`.setting_checks`.

The flat names of the earlier single-level settings still construct and read
(``TrackerSettings(heading_frames=0)``, ``settings.lost_ratio``): :data:`FLAT_NAMES` maps
each to its group and field.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

from ..errors import InputError
from .flat_names import FLAT_NAMES  # noqa: F401  (re-exported: the flat names' one place)
from .setting_checks import check as _check
from .setting_checks import one_of as _one_of
from .setting_checks import positive as _positive
from .setting_checks import power_of_two as _power_of_two
# the groups of a start are defined in start_settings.py and heading_settings.py, the
# judge's and the proposals' in judge_settings.py; import every group from here
from .heading_settings import (START_SCORES, START_TWINS, TWIN_STARTS, TWIN_SWAPS,  # noqa: F401
                               HeadingSettings)
from .start_settings import (CARRY_KINDS, FACINGS, HeightSettings, ShapeSettings,  # noqa: F401
                             StartSettings)
from .judge_settings import RECOVER_BY, JudgeSettings, ProposalSettings  # noqa: F401


#: Levels of detail of the default body a tracker can render candidates with
#: (:attr:`ObserveSettings.render_mesh`; ``depthtrack.body.model.DEFAULT_MESH_FILES``).
RENDER_MESHES = ("decimated", "coarse", "full")


@dataclass(frozen=True)
class ObserveSettings:
    """Observe: the ROI, the observed image and whether a person is there.

    Attributes
    ----------
    tile : int
        Tile side of the candidate renderer (pixels, a power of two).
    render_mesh : str
        The level of detail of the default body's mesh that candidates are rendered with
        (:data:`RENDER_MESHES`): "decimated" (about 1,000 triangles, the default), "coarse"
        (500: a candidate costs about a fifth less on llvmpipe, where half of it is the
        triangles' geometry work) or "full" (6,000). A body of the user's own (a glTF) has
        one mesh and renders with it.
    roi_margin : float
        Margin around the foreground box, as a fraction of its larger side.
    predicted_margin : float
        Margin (m at the joints' median depth) around the predicted joints that the ROI covers.
    depth_band : float
        Readings farther than this (m) in front of or behind the person count as background.
    far_band : float or None
        Behind the person, this margin (m) instead of ``depth_band`` (None: ``depth_band``).
        Readings kept inside the band and near the person are what the model must explain,
        so a wall closer behind the person than the band lets a misplaced limb explain the
        wall (a leg folded back onto it, an arm laid on it: dev probe, a frontal cartwheel on
        SR4000 with the wall 0.3 - 0.4 m behind). The near side's margin stays
        ``depth_band``: an arm reaching toward the camera that the segmentation misses.
    depth_percentiles : (float, float)
        Percentiles of the foreground depth that bound the person's depth band.
    wall_background : bool
        Readings on the plane of a wall the segmentation dropped (``Foreground.wall_planes``,
        within its inlier distance) are background, as on the floor, also inside the depth
        band and near the person (README "A frontal cartwheel before a wall"; on by default for
        an hour of 2026-11-28, off again after a test sequence lying down lost 36 points).
        Off (the default): a wall closer behind the person than ``depth_band`` is part of the
        observation near the person, and a misplaced limb can explain it (dev probe: a
        frontal cartwheel on SR4000 with the wall 0.3 - 0.4 m behind: a leg folded back onto
        the wall while upside down, an arm laid on it).
    near_dilation : int
        Side (pixels) of the square that dilates the mask and the predicted silhouette into
        the region where readings may belong to the person.
    min_person_area : float
        A frame whose foreground covers less than this (m^2) has no person in it.
    absent_frames : int
        During tracking the track is dropped after this many such frames in a row (a
        segmentation that fails for a frame or two must not end a good track); those frames
        get no pose and tracking starts afresh on the next frame with a person.
    """

    tile: int = 64
    render_mesh: str = "decimated"
    roi_margin: float = 0.15
    predicted_margin: float = 0.15
    depth_band: float = 0.4
    far_band: float | None = None
    depth_percentiles: tuple = (2.0, 98.0)
    wall_background: bool = False
    near_dilation: int = 7
    min_person_area: float = 0.08
    absent_frames: int = 3

    def __post_init__(self):
        _power_of_two(self.tile, "tile")
        _one_of(self, "render_mesh", RENDER_MESHES)
        _positive(self, "roi_margin", "predicted_margin", "depth_band", "min_person_area",
                  allow_zero=True)
        _check(int(self.absent_frames) >= 1,
               f"absent_frames must be at least 1, not {self.absent_frames}")
        _check(self.near_dilation >= 1, f"near_dilation must be >= 1, not {self.near_dilation}")
        _check(isinstance(self.wall_background, bool),
               f"wall_background must be true or false, not {self.wall_background!r}")
        _check(self.far_band is None or float(self.far_band) >= 0,
               f"far_band must be None or >= 0, not {self.far_band}")
        object.__setattr__(self, "depth_percentiles", tuple(float(p) for p in self.depth_percentiles))
        lo, hi = self.depth_percentiles
        _check(0 <= lo < hi <= 100, f"depth_percentiles must be 0 <= lo < hi <= 100, not "
                                    f"{self.depth_percentiles}")


@dataclass(frozen=True)
class EnergySettings:
    """Predict and score: the motion prior and the MAP energy (:mod:`.energy`).

    Attributes
    ----------
    damping : float
        Velocity damping of the prediction (1 = constant velocity).
    prior_huber : float
        0: the motion prior's Gaussian penalty. Above 0: Huber's loss at that many
        standard deviations (:class:`~depthtrack.motion.prior.ConstantVelocityPrior`,
        ``huber``): a change of velocity beyond it costs linearly, not quadratically. 3 on
        dev at the default of 2026-11-30: +1.9 points over 42 tracks, but one lost 5.5, so
        not the default (README, "A kick's accelerations, again"); on top of the hidden
        re-seat +0.7 over the 42 and +2.5 over the 27 off-front parity tracks, one dev
        track lost 6.0, still not ("A kick's accelerations, a third time"). That loss was
        a start handed on wrong in one arm, which :attr:`HeadingSettings.retro_settle`
        re-tracks: 3 by default since 2026-11-30 with ``retro_settle`` 12 (dev 42 +1.65,
        none lost more than 5, off-front parity +3.0; README, "The frames back to a start").
    likelihood_weight : float
        ``w`` of the energy.
    pose_prior_std : float
        Standard deviation (rad) of a weak Gaussian on every joint rotation about the zero
        pose (0 = off). Not in the paper: where a limb is hidden the likelihood is flat and
        the search would let it drift into any pose; this keeps it plausible while costing
        a visible limb almost nothing (a 1.5 rad bend costs 1.1, a mismatched pixel 1).
        0.5 was tried on dev for the hidden far arm of a side view (2026-12-01): +1.4
        points on the 27 off-front parity tracks, but -0.5 over 69 dev tracks, one tracked
        back to front from the start; not adopted (README, "A stronger pose prior, for the
        hidden far arm").
    hidden_prior_std : float
        Standard deviation (rad) of the pose prior on the rotations of the limbs the frame's
        predicted pose shows hidden, in place of ``pose_prior_std`` there (0 = off, every
        joint ``pose_prior_std``): a limb whose forearm and hand (shin and foot) show on
        fewer than :attr:`HeadingSettings.reseat_hidden` of the person's pixels in the
        predicted pose's render (:func:`.reach.hidden_limbs`; one full-image label render a
        frame), its root, middle and end joints. The global 0.5 helped the far arm of a side
        view but moved visible limbs and starts too; this asks it only where the image is
        silent (while tracking and in the final polish, not at a start). 0.5 on dev
        (2026-12-01), not adopted: a trap -- the prior pulls a hidden arm to the zero pose,
        where it stays hidden, so a raised arm hidden for a few frames is held down for
        good (105_05 from 90 degrees 98.5 -> 55.9 %; README, "The pose prior on the hidden
        limbs only").
    hidden_prior_limbs : {"all", "arms"}
        Which hidden limbs take ``hidden_prior_std``: every limb, or the arms only (a far
        leg hidden behind the near one still walks: a prior toward the standing pose bends
        it wrong).
    hidden_prior_gate : {"shown", "side"}
        How a frame's hidden limbs are found. ``"shown"``: those the predicted pose's render
        shows hidden (above). ``"side"``: those on the far side of the predicted pose's trunk
        where the camera sees it from the side, within ``hidden_side_deg`` of a pure side
        view (:func:`.reach.far_side_limbs`; the arm whose shoulder, the leg whose hip, lies
        farther from the camera): the trunk's orientation, which the image settles, decides,
        not the limb's own place, so a limb held out of sight by the prior does not keep the
        prior on (the trap of ``"shown"``).
    hidden_side_deg : float
        With ``hidden_prior_gate`` ``"side"``: how far (degrees, 0 to 90) the line between
        the shoulders (hips) may point from the camera's ray and the trunk still count as
        seen from the side.
    limb_prior : {"gaussian", "learned"}
        How the pose prior scores each limb's root and middle joint (shoulder and elbow,
        hip and knee): the Gaussian of ``pose_prior_std``, or the learned mixture of the
        train motions' limb poses floored by that Gaussian (:mod:`.limb_prior`,
        ``depthtrack/data/limb_prior.npz``): a common limb pose costs less than the
        Gaussian says, an uncommon one at most ``log(1 / limb_prior_floor)`` more.
        "learned" on dev (2026-12-01): +2.0 points on the 27 off-front parity tracks (the
        side view's far arm where the true one hangs), but a dancer's hidden arm held back
        was tracked hanging in front (05_20 on Kinect v2 from 120 degrees 90.8 -> 69.5 %);
        not adopted (README, "A learned limb prior").
    limb_prior_floor : float
        The broad Gaussian's weight in the learned prior (0 < floor <= 1; 1 = the Gaussian).
    limb_prior_weight : float
        How far the learned prior goes from the Gaussian toward the learned cost, per limb
        ``gauss + w * (learned - gauss)`` (0 = the Gaussian, 1 = the learned; >= 0): a
        weaker pull toward the common limb poses. 0.5 on dev, not adopted: one of the
        first 8 parity tracks lost 11 points (README, "The learned limb prior, halfway").
    limb_prior_start : bool
        Whether the learned limb prior (``limb_prior`` "learned") also scores the automatic
        start and its front/back check (:func:`.loop.stream_poses`); False gives them the
        Gaussian, so which way the person faces is decided as without the learned prior
        (with it, one dev cartwheel started back to front). False on dev (2026-12-01,
        stopped by its rule after 49 of the 69 tracks): the cartwheel 20.8 -> 98.4 %, the
        27 off-front parity tracks +1.74 points, but two wide tracks lost more than 10
        (a hidden arm held tucked in, legs lost); not adopted (README, "The learned limb
        prior, after the start").
    twist_std : float
        Standard deviation (rad) of a Gaussian on the twist of the chest against the pelvis
        (:func:`~.energy.spine_twist`; 0 = off; default 0.3, about 17 degrees, between the
        train split's RMS twist of 10 degrees and its 95th percentile of 22). Not in the
        paper: with the chest and legs where the image puts them, the likelihood barely
        tells which way the pelvis points (:mod:`.energy`).
    """

    damping: float = 0.7
    prior_huber: float = 3.0
    likelihood_weight: float = 1.0
    pose_prior_std: float = 1.0
    twist_std: float = 0.3
    hidden_prior_std: float = 0.0
    hidden_prior_limbs: str = "all"
    hidden_prior_gate: str = "shown"
    hidden_side_deg: float = 45.0
    limb_prior: str = "gaussian"
    limb_prior_floor: float = 0.1
    limb_prior_weight: float = 1.0
    limb_prior_start: bool = True

    def __post_init__(self):
        _check(self.limb_prior in ("gaussian", "learned"),
               f"limb_prior must be 'gaussian' or 'learned', not {self.limb_prior!r}")
        _check(0.0 < self.limb_prior_floor <= 1.0,
               f"limb_prior_floor must be in (0, 1], not {self.limb_prior_floor!r}")
        _positive(self, "limb_prior_weight", allow_zero=True)
        _check(self.limb_prior == "gaussian" or self.pose_prior_std > 0,
               "limb_prior 'learned' needs pose_prior_std above 0 (its floor's std)")
        _check(self.hidden_prior_limbs in ("all", "arms"),
               f"hidden_prior_limbs must be 'all' or 'arms', not {self.hidden_prior_limbs!r}")
        _check(self.hidden_prior_gate in ("shown", "side"),
               f"hidden_prior_gate must be 'shown' or 'side', not {self.hidden_prior_gate!r}")
        _check(0.0 <= self.hidden_side_deg <= 90.0,
               f"hidden_side_deg must be within 0 to 90, not {self.hidden_side_deg!r}")
        _positive(self, "damping", "likelihood_weight", "pose_prior_std", "twist_std",
                  "prior_huber", "hidden_prior_std", allow_zero=True)


@dataclass(frozen=True)
class SearchSettings:
    """Search: the per-frame hill climbing (:mod:`.hill_climb`).

    Attributes
    ----------
    levels : int
        Rungs of the step ladder.
    max_iterations : int
        Most batches per block.
    step_scale : float
        Factor on the coarsest steps of :func:`~.hill_climb.default_blocks` (at 25 fps;
        scaled by 25/fps).
    passes : int
        Times the schedule runs per frame.
    diagonals : bool
        Include the diagonal moves.
    pelvis_alone : bool
        Also turn the pelvis alone, the chest and the legs kept (six more candidates in the
        pelvis's batches; :attr:`~.hill_climb.SearchGroup.isolate`).
    untwist : tuple of float
        Fractions of the chest's twist against the pelvis by which the pelvis may turn back,
        alone, in one move (one candidate each in the pelvis's batches;
        :attr:`~.hill_climb.SearchGroup.untwist`; empty = none; default half and all).
    """

    levels: int = 3
    max_iterations: int = 8
    step_scale: float = 1.0
    passes: int = 2
    diagonals: bool = False
    pelvis_alone: bool = False
    untwist: tuple = (0.5, 1.0)

    def __post_init__(self):
        _positive(self, "levels", "max_iterations", "step_scale", "passes")
        object.__setattr__(self, "untwist", tuple(float(f) for f in self.untwist))
        _check(all(0.0 < f <= 1.0 for f in self.untwist),
               f"untwist fractions must lie in (0, 1], not {self.untwist}")


@dataclass(frozen=True)
class AssociateSettings:
    """Associate and propagate: part detections, evidence propagation, local refinement.

    Attributes
    ----------
    prune_distance : float
        Detections within this distance (m) of a model part count as explained.
    ep_obs_std : float
        Detection noise (m) in evidence propagation.
    ep_prior_scale : float
        Evidence propagation's prior: ``N(x_best, (scale * sigma)^2)`` in velocity space.
    max_correspondences : int
        Most correspondences tried per frame.
    refine_level : int
        Rung of the step ladder the hill climbing of a propagated pose ("hc+ep") starts on.
    refine_with_prior : bool
        Whether that hill climbing includes the velocity prior. Off by default: evidence
        propagation has already weighed the prior against the detection, and the prior,
        centred on a track that may be lost, would pull the hypothesis back before the
        likelihood could judge it.
    refine_scope : {"chain", "body"}
        What that hill climbing moves: the corresponded part's chain or every joint.
    accept : {"likelihood", "map"}
        What a propagated-and-refined pose must improve to replace the best one.
    accept_margin : float
        With "likelihood": the improvement needed, in energy units.
    """

    prune_distance: float = 0.15
    ep_obs_std: float = 0.04
    ep_prior_scale: float = 4.0
    max_correspondences: int = 6
    refine_level: int = 1
    refine_with_prior: bool = False
    refine_scope: str = "chain"
    accept: str = "likelihood"
    accept_margin: float = 0.0

    def __post_init__(self):
        _check(self.refine_scope in ("chain", "body"),
               f"refine_scope must be 'chain' or 'body', not {self.refine_scope!r}")
        _check(self.accept in ("likelihood", "map"),
               f"accept must be 'likelihood' or 'map', not {self.accept!r}")
        _positive(self, "prune_distance", "ep_obs_std", "ep_prior_scale")
        _positive(self, "max_correspondences", "refine_level", "accept_margin", allow_zero=True)


#: How the final polish's tile follows the ROI's side (:func:`.final_polish.final_tile`).
TILE_ROUNDINGS = ("nearest", "up")


@dataclass(frozen=True)
class PolishSettings:
    """Polish: the finest rung of the search once more at a finer tile resolution, and the
    final polish of each finished pose (:mod:`.final_polish`).

    Attributes
    ----------
    fine_tile : int
        Tile side of the polish (pixels); 0 = no polish.
    fine_iterations : int
        Most batches per block.
    final_tile : int
        Largest tile side (pixels) of the final polish: each pose, once no correction can
        change it any more, climbed again without the motion prior on tiles as fine as the
        camera's own pixels (a power of two by the ROI's side, as ``final_tile_round``
        says, at most this); 0 = none.
    final_tile_round : {"nearest", "up"}
        How the final polish's tile follows the ROI's side: the power of two nearest it
        (in log scale; the default before 2026-12-01), or the smallest at least it (one
        tile pixel per camera pixel or finer: an SR4000 person on 256 rather than 128;
        README "Final polish, at every camera pixel").
    final_levels : int
        Rungs the final polish adds below the search's finest (each halves the steps).
    final_iterations : int
        Most batches per block of the final polish.
    final_passes : int
        Times the final polish climbs each pose, every climb from the search's finest rung
        again (a climb stops long before it converges: each further one lays the limbs
        closer to their pixels; README "Final polish, climbed again"). Changes only the
        poses reported, never a decision (the heading recheck's close-call polish climbs
        once).
    """

    fine_tile: int = 128
    fine_iterations: int = 4
    final_tile: int = 256
    final_levels: int = 2
    final_iterations: int = 4
    final_passes: int = 3
    final_tile_round: str = "up"

    def __post_init__(self):
        _power_of_two(self.fine_tile, "fine_tile", zero_ok=True)
        _power_of_two(self.final_tile, "final_tile", zero_ok=True)
        _positive(self, "fine_iterations", "final_iterations", "final_passes")
        _check(isinstance(self.final_passes, int) and not isinstance(self.final_passes, bool),
               f"PolishSettings.final_passes must be a whole number, not {self.final_passes!r}")
        _positive(self, "final_levels", allow_zero=True)
        _one_of(self, "final_tile_round", TILE_ROUNDINGS)


#: Group name -> settings class, in the order of a frame.
GROUPS = {"observe": ObserveSettings, "energy": EnergySettings, "search": SearchSettings,
          "associate": AssociateSettings, "polish": PolishSettings, "judge": JudgeSettings,
          "propose": ProposalSettings,
          "start": StartSettings, "heading": HeadingSettings, "height": HeightSettings,
          "shape": ShapeSettings}

@dataclass(frozen=True, init=False)
class TrackerSettings:
    """Every setting of the tracker, one group per stage (module docstring).

    ``TrackerSettings(search=SearchSettings(passes=3))`` sets a group;
    ``TrackerSettings(heading_frames=0)`` sets a field by its flat name (:data:`FLAT_NAMES`);
    ``TrackerSettings(**json.load(f)["settings"])`` rebuilds the settings of a summary.json;
    an unknown name or a bad value raises :class:`~depthtrack.errors.InputError`.
    """

    observe: ObserveSettings = field(default_factory=ObserveSettings)
    energy: EnergySettings = field(default_factory=EnergySettings)
    search: SearchSettings = field(default_factory=SearchSettings)
    associate: AssociateSettings = field(default_factory=AssociateSettings)
    polish: PolishSettings = field(default_factory=PolishSettings)
    judge: JudgeSettings = field(default_factory=JudgeSettings)
    propose: ProposalSettings = field(default_factory=ProposalSettings)
    start: StartSettings = field(default_factory=StartSettings)
    heading: HeadingSettings = field(default_factory=HeadingSettings)
    height: HeightSettings = field(default_factory=HeightSettings)
    shape: ShapeSettings = field(default_factory=ShapeSettings)

    def __init__(self, **kwargs):
        groups = {}
        for name, cls in GROUPS.items():
            given = kwargs.pop(name, None)
            if isinstance(given, dict):             # as to_dict() writes it (summary.json)
                try:
                    given = cls(**given)
                except TypeError as exc:
                    raise InputError(None, f"settings group {name!r}: {exc}") from None
            if given is not None and not isinstance(given, cls):
                raise InputError(None, f"settings group {name!r} must be a {cls.__name__}")
            groups[name] = given if given is not None else cls()
        changes = {}
        for key, value in kwargs.items():
            if key not in FLAT_NAMES:
                raise InputError(None, f"unknown tracker setting {key!r}")
            group, name = FLAT_NAMES[key]
            changes.setdefault(group, {})[name] = value
        for group, values in changes.items():
            groups[group] = dataclasses.replace(groups[group], **values)
        for name, value in groups.items():
            object.__setattr__(self, name, value)

    def __getattr__(self, name):
        # only reached for names that are not groups: the flat names read through
        if name in FLAT_NAMES:
            group, key = FLAT_NAMES[name]
            return getattr(getattr(self, group), key)
        raise AttributeError(name)

    def replace(self, **kwargs) -> "TrackerSettings":
        """A copy with groups or flat-named fields changed."""
        current = {name: getattr(self, name) for name in GROUPS}
        flat = {k: v for k, v in kwargs.items() if k not in GROUPS}
        current.update({k: v for k, v in kwargs.items() if k in GROUPS})
        out = TrackerSettings(**current)
        return TrackerSettings(**{name: getattr(out, name) for name in GROUPS}, **flat) if flat else out

    def updated(self, data: dict) -> "TrackerSettings":
        """A copy with ``data`` laid over it: each group given as a dict changes only the
        fields it names (``{"heading": {"every": 8}}`` keeps the rest of this ``heading``),
        a group object or a flat name replaces as in :meth:`replace`. What ``--settings``
        does on top of a ``--preset``."""
        changes = {}
        for key, value in data.items():
            if key in GROUPS and isinstance(value, dict):
                try:
                    value = dataclasses.replace(getattr(self, key), **value)
                except TypeError as exc:
                    raise InputError(None, f"settings group {key!r}: {exc}") from None
            changes[key] = value
        return self.replace(**changes)

    def to_dict(self) -> dict:
        """The flat names (as ``summary.json`` always had them) and every group whole."""
        out = {key: getattr(self, key) for key in FLAT_NAMES}
        for name in GROUPS:
            out[name] = {k: list(v) if isinstance(v, tuple) else v
                         for k, v in dataclasses.asdict(getattr(self, name)).items()}
        return out


#: Named starting points for the settings (``depthtrack track --preset``), each as the groups
#: it changes from the defaults. ``"default"``: the most accurate tracker. ``"fast"``: a few
#: points less accurate, a 2-s clip about twice as fast (mostly the shape fit left out; each
#: frame 3 to 20 % faster; README, "Speed"): the template
#: body (no shape fit: 16 trial frames and a re-track fewer), one pass of the per-frame search
#: instead of two, no polish at the finer tile nor final polish, and the rechecks half as often (front/back
#: and the limbs' sides every 8th frame, the reach every 4th) -- the rechecks climb two or
#: three poses from the coarsest rung each and were two thirds of the candidates scored; and
#: no fresh look (``judge.look_every`` 0: a fifth of a frame's time; the preset as measured)
#: nor re-seat of a limb over free space or tracked hidden (``heading.reseat_free`` and
#: ``reseat_hidden`` 0, the defaults since 2026-11-30; the preset as measured).
PRESETS = {
    "default": {},
    "fast": {"shape": {"enabled": False}, "search": {"passes": 1},
             "polish": {"fine_tile": 0, "final_tile": 0},
             "heading": {"every": 8, "limb_every": 8, "reseat_free": 0.0, "reseat_hidden": 0.0},
             "propose": {"reach_every": 4},
             "judge": {"look_every": 0}},
}


def preset(name: str) -> TrackerSettings:
    """The settings of the preset ``name`` (:data:`PRESETS`)."""
    if name not in PRESETS:
        raise InputError(None, f"unknown preset {name!r}; choose from {', '.join(PRESETS)}")
    return TrackerSettings().updated(PRESETS[name])
