"""The settings groups of a start: the global search (``start``), the body-height fit
(``height``) and the body-shape fit (``shape``); :class:`~.settings.TrackerSettings` nests
them with the groups of a frame (:mod:`.settings`, which re-exports every name here) and the
front/back check and rechecks (:mod:`.heading_settings`)."""
from __future__ import annotations

from dataclasses import dataclass

from .setting_checks import check as _check
from .setting_checks import one_of as _one_of
from .setting_checks import positive as _positive
from .setting_checks import power_of_two as _power_of_two


#: Which way the person faces at the start (:attr:`StartSettings.facing`).
FACINGS = ("auto", "camera", "away")
#: Which global searches try raised legs (:attr:`StartSettings.legs`), bent bodies
#: (:attr:`StartSettings.bends`) or always hear the grid (:attr:`StartSettings.grid_heard`).
LEG_SEARCHES = ("never", "recovery", "always")
SEARCHES = ("never", "start", "recovery", "always")
#: The shape-fit trial's corrections that may be carried back (:attr:`ShapeSettings.carry_back`).
CARRY_KINDS = ("heading", "legs", "arms")


@dataclass(frozen=True)
class StartSettings:
    """The global search of an automatic start and of a recovery (:mod:`.start`).

    Attributes
    ----------
    passes : int
        Hill-climbing passes over every joint for each finalist.
    facing_prior : float
        Weight of the initial-heading prior, per foreground pixel.
    step_factor, extra_levels, max_iterations : float, int, int
        The search starts far off: steps ``step_factor`` times the per-frame ones, this many
        more rungs, this many batches per block.
    diagonals : bool
        Diagonal moves in its blocks.
    shortlist : int
        Best scored candidates refined on the root.
    root_blocks, root_passes : int
        Blocks (from the root) and passes of that refinement.
    finalists : int
        Best of the shortlist refined on every joint (and associated, "ep" / "hc+ep").
        The recogniser's best candidate is always among both.
    grid_heard : {"never", "start", "recovery", "always"}
        Which global searches always hear the grid's best candidate too: where every
        finalist is one of the recogniser's, the grid's best on the shortlist (or else by
        its energy) is climbed as well, on top of them (it displaces none). Without it the
        recogniser's fits (each also with every arm pose) can fill the shortlist on their
        energy before any climb, and a grid pose that climbs to a far better score is never
        climbed (seen on a test track, sidestep seed 2: the start's legs crossed, 3924
        against 4014 when the grid is heard; `hc`, which has no recogniser, starts right).
        "never" stays the default: on dev "start" changed 7 of the 45 wide starts, and its
        tracks lost 4.2 points on average (cartwheel seed 1 from 96.9 to 61.2 %: both
        starts off, the grid's scoring better; after the recogniser's the front/back check
        turned the track right, after the grid's it kept it; README, "The start's grid
        heard"). Since 2026-12-02 the bend gate judges the best of the other finalists, so
        the grid's best heard changes nothing but the finalist it adds.
    displaced_checked : bool
        Where the grid's best, heard by ``grid_heard``, wins a start (the first frame with a
        person, not a recovery), the start the search had without it (``init_info.
        displaced``) goes through the front/back check too: each start is tracked through
        :attr:`HeadingSettings.frames` frames with its turned twin and settled as the check
        settles one (:func:`~.heading.settle_heading`), and of the two kept tracks the one
        with the lower score stands (``heading_check.others``, ``kept_start``). A better
        scoring wrong start can be one the check cannot undo (dev, cartwheel seed 1). Off by
        default: on dev, with ``grid_heard`` ``"start"``, its tracks lost 2.6 points on the
        mean of the 8 changed starts, cartwheel seed 1 21.5, where the two starts' kept
        tracks tied at 0.0904 against 0.0905 and the wrong one stood (README, "The
        displaced start checked too").
    associate_level : int
        Rung the climb after a finalist's association starts on.
    centre_push : float
        The visible surface lies in front of the body's centre: metres pushed back along the ray.
    axial_shifts : tuple of float
        Shifts (m) along the body's long axis tried for every candidate.
    facing : {"auto", "camera", "away"}
        Which way the person faces at the start, when the user knows (:data:`FACINGS`).
        ``"auto"``: the search decides, preferring the camera (``facing_prior``), and the
        front/back check after the start may turn it (:class:`HeadingSettings`). ``"camera"``
        (``"away"``): no pose facing the other side (by more than ``facing_margin`` degrees
        from profile) may start (its forward direction and the direction to the camera,
        flattened onto the floor), and where the start faces the told side (by more than
        that margin), the check is skipped: a depth image barely tells front from back, and
        where the two headings explain it within a few percent the automatic decision is a
        coin flip (dev: overhead on Azure NFOV from 240 degrees, two seeds of three tracked
        back to front for the whole clip). With a margin, a start within it of profile gets
        the check, and the turned twin may win only where it is not on the wrong side. It
        holds at every automatic start (the first frame with a person, and again after the
        person was gone); a recovery keeps the last tracked heading either way.
    facing_margin : float
        Degrees either side of profile in which a pose counts as facing either way for
        ``facing`` (default 0: the half-planes). Why one may want it: the pelvis's heading
        is the least certain part of a pose seen near profile (dev: 13_32 from Azure NFOV at
        240 degrees, a track within 7 cm on frame 0 with its pelvis 51 degrees off the
        truth's, 54 against 105 degrees from the camera), and the told side forced that
        start over the line (95 -> 76 % of joints within 10 cm, seed 3). Why it is 0: on the
        dev split the told side helped more near profile than it hurt (overhead from 120
        degrees 47 -> 97 %, 03_01 from 108 degrees 84 -> 94 %), and a margin of 45 degrees
        would hand those starts back to the automatic check. Not measured on a benchmark.
    complete_fraction, complete_frames : float, int
        With ``complete_fraction`` above 0 an automatic start waits for enough of the
        person: of this frame and the next ``complete_frames``, it starts on the first whose
        person covers at least ``complete_fraction`` of the largest visible area (m^2) among
        them, and the frames before are tracked backwards from that start. A person walking
        into the camera's range or into its view shows a few limbs first, and a start on
        those lands anywhere (dev: 105_05 on SR4000, the person 5.3 m away on frame 0, past
        the 5 m range, three limbs visible; the start on frame 2 went wrong and the track
        kept it: 24-48 % of joints within 10 cm; with 0.7, tracked with the template body,
        seeds 1-3 went 68 -> 87, 88 -> 95 and 21 -> 96 %, and 02_03 on Kinect v2 from 120
        degrees, where the person also enters the view, 69 -> 80, 77 -> 73 and 74 %; on the
        other eleven dev motions no start waits, so their tracks are unchanged). 0 = off. A
        deferred start says by how many frames in its ``init_info`` (``deferred_frames``;
        ``summary.json``'s ``initialisation_details``).
    complete_uncut : bool
        With ``complete_fraction``, the start also waits, within the same frames, for the
        first whose person is clear of the image's edges (:func:`~.observation.
        cut_by_border`), where one is; where none is (a person too close to be seen whole)
        the area alone decides. Named on dev 02_03 (a runner entering a Kinect v2's view
        from 120 degrees): the area reached 0.7 on frame 2 with a leg and an arm still out
        of the image, and the start there was 27 cm off. Off by default: on dev it moved
        nine starts (02_03, cartwheel and 01_08, whose feet touch the image's bottom) and
        lost 38 points on 02_03 seed 2 (a wrong heading switch on frame 20), README "A
        person walking into view".
    legs : {"never", "recovery", "always"}
        Which global searches also try every grid candidate with a leg raised
        (:data:`~.start.LEG_POSES`, five times the grid): a recovery's, or also the start's.
        The grid's legs hang down, so a person caught mid-kick was found only through the
        recogniser's proposals (dev 90_05 seed 1, SR4000: the recovery on frame 40 took a
        fit facing the wrong way, 32 cm mean joint error, whose energy was 88 above a pose
        fitted to the true joints; with the leg poses the search finds one facing the right
        way, 8 cm, 41 below). On dev "recovery" helped the kicks (90_05 seeds 1 and 2, +8
        and +14 points) and hurt a runner (02_03 seeds 1 and 2, -12 and -22): a stride
        fits a raised leg too, with the wrong leg (README, "Lost and found"). So "never".
    bends : {"never", "start", "recovery", "always"}
        Which global searches also try every grid candidate bent at the hips
        (:data:`~.start.BEND_POSES`: a pike and a seated body, three times the grid): the
        automatic start's, a recovery's, or both. The grid's bodies are straight; a body
        folded forward with hands and feet on the floor was reached only through the
        recogniser's proposals, which are poorest there (train 144_30, a sun salutation: start and
        recoveries 70 to 85 cm off; with the bent bodies 92 and 94 % of joints within
        10 cm). "start" (with ``bend_gate``) passed the dev rule; without the gate it cost
        about 24k more candidates on every start and took the CI suite from 11.5 to 16.7
        minutes, past its 15. README, "Bent bodies". "always" (the default since 2026-11-30,
        the same gate) lets a recovery's and a fresh look's search hear them too: a person
        kneeling down to lie is a seated body for a few frames, which the straight grid
        misses while the track lags behind (dev lie-front from the front, seed 2: a wrong
        heading switch on frame 24 stood, 59 % of joints within 10 cm; with the bent bodies
        the look on that frame put it right, 99 %). README, "A recovery's bent bodies".
    bend_shortlist, bend_finalists : int
        With ``bends``, the best candidates of each bent body refined on the root and then
        on every joint, on top of (not among) the straight grid's ``shortlist`` and
        ``finalists``: the straight search is unchanged, a bent body wins only by its score.
    bend_margin : float
        The share of its score by which a bent finalist must beat the best straight one
        (0.01). On dev two upright starts (a runner, a jump kick) took a bent body by 0.4 and
        0.03 % of the score, a tie, and their tracks parted from the default's by nine
        points either way; bodies that are bent won by 3 to 22 %.
    bend_gate : float
        With ``bends``, the bent bodies are searched only when the best straight finalist
        leaves more than this share of the observation unexplained
        (:func:`~.energy.unexplained`; 0 = always). The straight search runs first and is
        the same either way, so a closed gate gives the start without bends, and costs one
        candidate. The start's ``bend_gate`` info says the share and whether it searched.
        0.25: set on train alone, just below the shares of the straight starts of train
        144_30's "down dog" (0.290 and 0.259, seeds 1 and 2); upright starts leave 0.06 to
        0.31 (dev: 2 of 39 above 0.25).
    bend_hip_angle : float
        With ``bends``, the bent bodies are also searched when the recogniser's most
        confident neck, pelvis and knees (:func:`~.proposals.proposal_hip_angle`) make an
        angle below this many degrees at the pelvis (0, the default: never by this cue; no
        effect without the recogniser). The share above misses bodies that a straight fit
        explains well enough: train 02_05 (a forward bend, shares 0.19 and 0.17) started 24
        and 23 cm off, 10 and 12 cm with the bent bodies. 137 was set on train alone (between
        the folded starts, 02_05 and 144_30 at 77 to 132 degrees, and the upright ones at
        142 to 176) and measured on dev: it opens the gate on 6 more of 42 starts, changes
        two (bend seeds 1 and 3: 10 -> 3 cm at the start) and their tracks 100 -> 98.3 and
        100 -> 100 %, so it missed the rule (paired difference at least 0) and is not the
        default. README, "Bent bodies".
    reseat_rounds : int
        After an automatic start's search, up to this many limbs re-seated in turn from the
        limb library (:func:`~.reseat.reseat_limbs`: every limb set to each of its 32 poses,
        the best climbed over that limb, kept when lower by
        :attr:`HeadingSettings.reseat_margin` as the re-seat recheck's are); the start's
        ``init_info`` lists them (``reseats``). The search's six arm poses can leave an arm
        in a basin the climb does not leave (dev: 01_08 on SR4000 from 270 degrees, both
        arms started overhead while they hang in front of the trunk). 0 (the default) = off.
    """

    passes: int = 3
    facing_prior: float = 0.1
    step_factor: float = 2.0
    extra_levels: int = 2
    max_iterations: int = 10
    diagonals: bool = True
    shortlist: int = 6
    root_blocks: int = 2
    root_passes: int = 2
    finalists: int = 3
    grid_heard: str = "never"
    displaced_checked: bool = False
    associate_level: int = 1
    centre_push: float = 0.08
    axial_shifts: tuple = (0.0, -0.3, -0.15, 0.15, 0.3)
    facing: str = "auto"
    facing_margin: float = 0.0
    complete_fraction: float = 0.7
    complete_frames: int = 10
    complete_uncut: bool = False
    legs: str = "never"
    bends: str = "always"
    bend_shortlist: int = 6
    bend_finalists: int = 2
    bend_margin: float = 0.01
    bend_gate: float = 0.25
    bend_hip_angle: float = 0.0
    reseat_rounds: int = 0

    def __post_init__(self):
        _check(0.0 <= self.complete_fraction <= 1.0, f"StartSettings.complete_fraction must "
                                                     f"be in [0, 1], not {self.complete_fraction}")
        _check(int(self.complete_frames) >= 1, f"StartSettings.complete_frames must be at "
                                               f"least 1, not {self.complete_frames}")
        _one_of(self, "facing", FACINGS)
        _one_of(self, "legs", LEG_SEARCHES)
        _one_of(self, "bends", SEARCHES)
        _one_of(self, "grid_heard", SEARCHES)
        _check(isinstance(self.displaced_checked, bool), f"StartSettings.displaced_checked "
                                                         f"must be true or false, not "
                                                         f"{self.displaced_checked!r}")
        _check(0.0 <= self.bend_gate <= 1.0, f"StartSettings.bend_gate must be in [0, 1], "
                                             f"not {self.bend_gate}")
        _check(0.0 <= self.bend_hip_angle <= 180.0, f"StartSettings.bend_hip_angle must be "
                                                    f"in [0, 180] degrees, not {self.bend_hip_angle}")
        _positive(self, "passes", "step_factor", "max_iterations", "shortlist", "root_blocks",
                  "root_passes", "finalists", "bend_shortlist", "bend_finalists")
        _positive(self, "facing_prior", "extra_levels", "associate_level", "centre_push",
                  "bend_margin", "reseat_rounds", allow_zero=True)
        _check(0.0 <= self.facing_margin < 90.0, f"StartSettings.facing_margin must be in "
                                                 f"[0, 90) degrees, not {self.facing_margin}")
        object.__setattr__(self, "axial_shifts", tuple(float(s) for s in self.axial_shifts))

    def searched_in(self, search: str) -> dict:
        """The global search's extra candidates for ``search`` ("start" or "recovery"):
        ``{"legs", "bends", "grid_heard"}`` flags, each on where its setting names that
        search or "always" (:func:`~.start.global_search`'s keywords)."""
        return {name: getattr(self, name) in (search, "always")
                for name in ("legs", "bends", "grid_heard")}


@dataclass(frozen=True)
class HeightSettings:
    """The body-height fit when a sequence does not give it (:mod:`.height`).

    Heights ``ratio`` apart, ``steps`` either side of the foreground's guess, then at most
    ``walk`` more outwards while the best is at an edge; all within ``min_m .. max_m``.
    """

    ratio: float = 1.08
    steps: int = 2
    walk: int = 3
    min_m: float = 1.2
    max_m: float = 2.2

    def __post_init__(self):
        _check(self.ratio > 1, f"HeightSettings.ratio must be > 1, not {self.ratio!r}")
        _check(0 < self.min_m < self.max_m, f"HeightSettings needs 0 < min_m < max_m, not "
                                            f"{self.min_m!r}, {self.max_m!r}")
        _positive(self, "steps", "walk", allow_zero=True)


@dataclass(frozen=True)
class ShapeSettings:
    """The body-shape fit from the first frames (:func:`~.height.fit_body_shape`).

    The first ``frames`` frames are tracked ("hc") with the template body, ``fit_frames``
    of them (spread evenly) go to :func:`~.shape_fit.fit_shape` with the tracker's poses,
    and the whole sequence is then tracked with the fitted body. ``tile`` bounds the fit's
    renderer (0 = one camera pixel per tile pixel, up to 256: slow on llvmpipe); ``rounds``
    and ``max_iterations`` its search; ``prior_weight`` its population prior.
    ``enabled`` (the default) fits the shape; False = the template body (at the given or
    fitted height). On six dev people (no clothing; README, "Body shape") the fitted body
    covers the person's silhouette with an IoU of 0.854 against the template's 0.786 and
    leaves 9.2 % of the person's pixels unexplained against 13.0 %: what a user without
    ground truth sees of the fit. Joints within 10 cm moved by +0.8 points on four dev
    people (s.d. 7.7): no loss in accuracy, for 16 trial frames and a fit of a few seconds.

    ``trial_rechecks``: whether the trial tracker runs the rechecks while tracking (front/back,
    the limbs' sides, the reach; :class:`HeadingSettings`). The fit takes a few of the
    trial's poses, and the re-track starts from the first frame's, which the start and its
    front/back check decide before any recheck can run; the rechecks, most of the candidates
    a frame scores, change the trial's later poses only where a track went wrong. Not
    adopted: without them the dev wide preset (seeds 1-2, paired) lost 1.1 ± 1.1 points,
    3 sequences by more than 5 against 1 gained (README, "Speed").

    ``carry_back``: which of the trial's corrections are carried back to the fit frames
    before them (:mod:`.carry_back`; :data:`CARRY_KINDS`: ``"heading"``, the heading
    switches; ``"legs"``, ``"arms"``, the limb swaps of those limbs; empty = none): the
    trial tracks without re-tracks, so a frame before a correction kept the sides the
    trial's start gave it, and the fit and the re-track's first pose (frame 0's) took them
    so. Not the default: with ``("heading",)`` dev 02_03 from 120 degrees (seed 4) went
    25.0 -> 94.1 % within 10 cm, but on five fresh-seed sequences whose trial switched its
    heading the final tracks lost 0.77 points on average, where the rule asked for none
    (README, "The trial's corrections, carried back"); the limb swaps, often ending a
    passing crossing, cost a dev track 15 points carried back.
    """

    enabled: bool = True
    frames: int = 16
    fit_frames: int = 4
    tile: int = 64
    rounds: int = 1
    max_iterations: int = 20
    prior_weight: float = 30.0
    trial_rechecks: bool = True
    carry_back: tuple = ()

    def __post_init__(self):
        _check(isinstance(self.enabled, bool), f"ShapeSettings.enabled must be true or false, "
                                               f"not {self.enabled!r}")
        _check(isinstance(self.trial_rechecks, bool), f"ShapeSettings.trial_rechecks must be "
                                                      f"true or false, not {self.trial_rechecks!r}")
        carry = (self.carry_back,) if isinstance(self.carry_back, str) else self.carry_back
        _check(isinstance(carry, (tuple, list)) and set(carry) <= set(CARRY_KINDS),
               f"ShapeSettings.carry_back must be a choice of {', '.join(CARRY_KINDS)}, "
               f"not {self.carry_back!r}")
        object.__setattr__(self, "carry_back", tuple(carry))
        _check(int(self.fit_frames) >= 1, f"ShapeSettings.fit_frames must be at least 1, "
                                          f"not {self.fit_frames!r}")
        _check(int(self.frames) >= int(self.fit_frames),
               f"ShapeSettings.frames must be at least fit_frames ({self.fit_frames}), "
               f"not {self.frames!r}")
        _power_of_two(self.tile, "ShapeSettings.tile", zero_ok=True)
        _positive(self, "rounds", "max_iterations")
        _positive(self, "prior_weight", allow_zero=True)
