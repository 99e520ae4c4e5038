"""The tracker's settings, one frozen group per stage, validated when made.

:class:`TrackerSettings` nests one group per stage of a frame (see :mod:`.tracker` for the
stages): ``observe``, ``energy``, ``search``, ``associate``, ``polish``, ``judge``,
``propose`` (the part recogniser's joint proposals, used by the start and the judge), and the
starts: ``start`` (the global search of the first frame and of a recovery), ``heading``
(the front/back check after an automatic start), ``height`` (the body-height fit) and
``shape`` (the body-shape fit from the first frames).
Every number of the search schedule lives here; ``TrackerSettings.to_dict()`` is written
whole into ``summary.json``. One set serves every sequence; never tune it per clip.

The groups of a frame are defined here but for ``energy`` (in :mod:`.energy_settings`),
``judge`` and ``propose`` (in :mod:`.judge_settings`); those of a start in :mod:`.start_settings` and :mod:`.heading_settings`
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
from .energy_settings import EnergySettings  # noqa: F401


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
