"""The settings of the front/back check after a start and of the rechecks and re-tracks
while tracking (``heading``, :class:`HeadingSettings`); :class:`~.settings.TrackerSettings`
nests it with the other groups (:mod:`.settings` re-exports every name here)."""
from __future__ import annotations

from dataclasses import dataclass

from .setting_checks import check as _check
from .setting_checks import one_of as _one_of
from .setting_checks import positive as _positive
from .setting_checks import power_of_two as _power_of_two

#: The start check's other hypothesis: the pose turned half a turn about its long axis
#: (limbs turned with it), or its swapped twin (the joints kept, the sides exchanged, as the
#: recheck while tracking uses).
START_TWINS = ("turned", "swapped", "search")
#: How the swapped twins may be fitted (:func:`.twins.swapped_twins`; ``twin_starts``).
TWIN_STARTS = ("turned", "rest")
#: Which sides the swapped twins exchange (:attr:`HeadingSettings.twin_swaps`,
#: :data:`.twins.TWIN_ORDERS`).
TWIN_SWAPS = ("all", "all_but_legs")
#: The corrections whose earlier frames :attr:`HeadingSettings.retro_after` may re-track.
RETRO_KINDS = ("heading", "limbs", "recovery")
#: How much of a backward track :attr:`HeadingSettings.retro_take` may take.
RETRO_TAKES = ("all", "prefix")
#: Which earlier corrections a re-track stops at (:attr:`HeadingSettings.retro_stop`).
RETRO_STOPS = ("any", "rank")
#: Which heading switches their re-track takes back (:attr:`HeadingSettings.retro_revoke`).
RETRO_REVOKES = ("never", "refused", "unsupported", "outscored", "outscored_unless_met")
#: Which judged leads are close calls (:attr:`HeadingSettings.polish_side`).
POLISH_SIDES = ("above", "both")
#: What a polished close call's lead feeds (:attr:`HeadingSettings.polish_evidence`).
POLISH_EVIDENCES = ("replace", "separate")
#: Which switches a polished switch's re-track takes back (:attr:`HeadingSettings.polish_revoke`).
POLISH_REVOKES = ("same",) + RETRO_REVOKES
#: What the rechecks' relative margins are fractions of (:attr:`HeadingSettings.margins_over`).
MARGIN_BASES = ("energy", "explainable")
#: What the start's front/back check compares (``start_by``; :func:`.heading.settle_heading`).
START_SCORES = ("energy", "unexplained")


@dataclass(frozen=True)
class HeadingSettings:
    """The front/back check after an automatic start (:mod:`.heading`).

    The pose and its twin turned to face the other way are both tracked through ``frames``
    frames (0 = off); the turned one replaces the first when its mean score over those frames
    is lower by a fraction: with ``start_by="unexplained"`` (the default) the unexplained
    share of the foreground, lower by ``margin``; with ``"energy"`` the energy without the
    motion prior (likelihood plus pose prior) per foreground pixel at the tracked poses, lower
    by ``energy_margin``. The share decides by default: on the 93 dev starts of the wide and
    parity presets the energy (margin 0) kept the heading whose ten frames were clearly
    worse (by 20 points of joints within 10 cm) 14 times, the share with its 10 % margin 11
    times; the energy's wrong leads reached 36 %, seen from 270 degrees. ``summary.json``
    keeps both scores under ``heading_check``.

    Then, while tracking, every ``every`` frames (0 = never) the tracked pose and its twin
    facing the other way are both climbed on the frame (``twin_passes`` passes with the
    start's steps; :func:`.heading.recheck_heading`): the twin gets a vote when its energy
    without the motion prior (likelihood plus pose prior) is lower by ``recheck_margin``
    times the foreground's pixel count, and replaces the track after ``votes`` votes in a
    row.

    Small wins add up too: each recheck adds the twin's lead (energy difference per
    foreground pixel) less ``evidence_drift`` to a running sum that never goes below zero
    (Page's CUSUM test), and the twin takes over when the sum passes ``evidence_threshold``
    (0 = off). A profile view gives the right heading a steady small lead, below
    ``recheck_margin``; a frontal view, where the twins explain the image equally well,
    gives leads of either sign that the drift cancels.

    Where fewer than ``frames`` frames follow the start, the check runs on those there are
    when they are at least ``min_frames`` (else it is skipped), so a longer look does not
    leave short clips unchecked.

    ``start_twin``: the start check's other hypothesis (:data:`START_TWINS`), by default the
    swapped twin, as the recheck's: a twin turned with its limbs competes with a different
    fit of the limbs, not only with the other heading, and on dev clips seen from the front
    that made the check keep the wrong one. ``"search"``: the global search's best pose
    facing the other way (:func:`.heading.flip_search`).

    A twin keeps the tracked pose's limb errors: a wrong-facing track places the limbs where
    its own knees and elbows can bend, and exchanging the sides does not put them where the
    image has them, so the right heading's twin can lose to the wrong heading's fit. So every
    ``search_every`` frames (0 = never) the global search looks for the best pose facing the
    other way (:func:`.heading.flip_search`); it takes over when its energy without the
    motion prior is lower than the tracked pose's, climbed alike, by ``search_margin`` times
    the foreground's pixel count -- and, with ``search_both``, lower than the same search's
    best pose facing the tracked way too (the tracked pose is fitted by a local climb only, so
    a fresh global search would beat it by its effort alone, whichever way it faces).

    The sides of the limbs too: every ``limb_every`` frames (0 = never) twins of the tracked
    pose with the legs' or the arms' sides exchanged are climbed alike, and the lower one
    replaces the track when its energy is lower by the fraction ``limb_margin``
    (:func:`.heading.recheck_limb_sides`: a track with its legs crossed).

    ``twin_starts``: where the swapped twin's fit starts (:data:`TWIN_STARTS`, one or both;
    :func:`.twins.swapped_twins`); every twin is climbed and the lowest energy competes,
    in the recheck and in the start check. Both by default: a twin fitted from the turned
    pose inherits its contortions; from the rest pose it does not (dev 05_20, Kinect v2 from
    120 degrees, seed 2: 20 % -> 88 % of joints within 10 cm, the start check now keeping
    the twin; 105_05 seed 3 62 -> 72 %; five other dev sequences unchanged).

    ``twin_swaps``: which sides the twins exchange (:data:`TWIN_SWAPS`, one or more; each
    fitted from every ``twin_starts``, :data:`.twins.TWIN_ORDERS`): ``"all"``, the body
    facing the other way with every limb where the image put it; ``"all_but_legs"``, facing
    the other way with the knees and ankles kept on their sides (no arms' counterpart: an
    elbow kept on its side while the shoulders exchange theirs is out of reach). A track can
    face the wrong way with its thighs crossed so that the legs are on their right sides
    (from the side the legs' bend says which side is which, the trunk's front does not): its
    all-sides twin puts the legs wrong and loses, the legs' recheck keeps the trunk wrong.
    Relabelling the tracked joints against the truth on the dev tracks of the default
    (parity and wide presets; ``tools/relabel_modes.py``): of 72 sequences, four had frames
    nearer the truth turned with every side exchanged (192 frames), three turned with the legs
    kept (70 frames: 01_08 from 90 degrees seed 3, 47 of 50), 19 frames with the legs' sides
    alone, 9 the arms' (README, "A twin turned with its legs kept"). Off: a probe on those
    three put 105_05 right (26.8 -> 92.9 %) and left 01_08 seed 3 as it was (38.3 %).

    ``refit_level``: the rung of the start's step ladder (``SearchSettings.levels +
    extra_levels`` rungs, the coarsest ``step_factor`` times the per-frame steps) on which
    every recheck's climbs -- the tracked pose's, the twins', the reach candidates' -- begin
    (0 = the coarsest). The tracked pose and the twins fitted to its joints start near a
    minimum; the coarsest steps are for a search that starts far off, and the rechecks'
    climbs were about two thirds of the candidates scored (README, "Speed").

    ``twin_climbs``: how many of the front/back twin's fits (one per ``twin_starts``) the
    recheck climbs, those of lowest unclimbed energy first (0 = all). The fits are one
    hypothesis, the same joints reached from two starts; on eight dev sequences the one
    lower before climbing was the lower after it in 94 of 132 rechecks, and where it was
    not, the two leads differed by a median 0.005 of energy per pixel (once 0.12); one
    climb fewer per recheck scored 10 % fewer candidates per frame on the dev wide preset
    with the same accuracy (82.3 against 82.2 %), so 1 is the default (README, "Speed").

    ``recheck_tile``: the tile side (pixels) every recheck's climbs and comparisons are
    rendered at (0 = the search's, :attr:`ObserveSettings.tile`). The rechecks ask which of
    a few whole-body hypotheses explains a frame better -- facing, the limbs' sides, a reach
    -- and are most of the candidates a frame scores; a coarser tile costs about half as
    much per candidate on llvmpipe (``depthtrack bench``). Every hypothesis of one recheck is
    scored at the same tile, and the energy is a mean per pixel times the ROI's area, so the
    margins keep their meaning. Not adopted: at 32 the dev wide preset (seeds 1-2, paired)
    lost 3.3 points, 8 sequences by more than 5 against 1 gained (README, "Speed").

    ``judge_tile``: the tile side (pixels) at which the front/back recheck compares the
    tracked pose and its twin once both are climbed (0 = the climbs' own tile, no second
    render). A body's front and back differ in centimetre-sized shapes (toes, face, chest
    against buttocks) that a 64-pixel tile of a whole person blurs: on a dev track held back
    to front (overhead, Azure NFOV from 240 degrees, seed 1) the twin, climbed, led by 0.2
    to 3.4 % on 64-pixel tiles, under the recheck's margins, and by 1.9 to 5.1 % on 256-pixel
    tiles; on a track facing the right way the twin trailed by more on the finer tiles too
    (README, "Front or back at a finer tile"). Two renders per recheck. 256 by default:
    on 19 dev sequences paired with 0, +6.1 ± 4.1 points, none lost, overhead seeds 2 and 3
    20 -> 79 and 73 %, the ten control sequences identical (README).

    ``polish_within``: with ``judge_tile``, a close call -- the twin's judged lead per
    foreground pixel above ``-polish_within`` -- is judged again after both climbed poses
    are polished on the judge's tiles (:attr:`Climbers.final`: the final polish's climber,
    from the search's finest rung); the polished twin is the one that may take over (0 =
    off). Both were climbed on the tracker's 64-pixel tiles, which blur the centimetres the
    judge's tiles see (a chest against a back): replayed
    on the dev parity tracks held back to front from the side and from behind, the twin
    (within 10 cm of the truth on 73 to 100 % of its joints) led on 5 to 9 of 12 rechecks
    before the polish and on 8 to 12 after it, while on three tracks facing the right way
    the polished twin led once in 36. Two polishes per close call. 0.05 by default since
    2026-11-29, with ``polish_evidence`` "separate" and ``polish_revoke`` "unsupported"
    (below). Alone (``"replace"``) it put those three right (20.9 -> 93.6, 26.8 -> 93.6,
    20.4 -> 98.1 %) and lost overhead seed 3 (Azure NFOV from 240 degrees), 98.5 -> 20.0 %,
    whose right switch the default made by a summed evidence of 0.1165 and the polished
    leads, smaller, never made; with ``retro_revoke`` "outscored" it also lost overhead seed
    1, whose polished right switches the revoke took back (README, "A close front/back
    call, polished").

    ``polish_side``: which judged leads ``polish_within`` takes for close calls
    (:data:`POLISH_SIDES`, :func:`.heading.close_call`): ``"above"``, every lead above
    ``-polish_within`` (the measurement above); ``"both"``, only those within
    ``polish_within`` of zero, a clear lead for the twin left as judged (the polish shrank
    overhead seed 3's first lead, +0.114 -> +0.039 per pixel in the replay). A probe, not
    adopted: it kept overhead seed 3 right and turned two right parity tracks wrong
    (spin-fast from 90 degrees seed 2, 95.5 -> 46.4 %; from 180 degrees seed 1, 96.7 ->
    20.1 %) on the clear wrong leads the ``"above"`` polish had shrunk.

    ``polish_evidence``: what a polished close call's lead feeds (:data:`POLISH_EVIDENCES`).
    ``"replace"``: it stands for the judged lead in the one set of votes and CUSUM (the
    figures above). ``"separate"`` (the default since 2026-11-29): the judged leads keep
    their own votes and sum, exactly as without the polish, and the polished leads (the
    judged lead where no close call was polished) build a second set (``polished_votes``,
    ``polished_evidence`` in the state);
    the twin takes over when either crosses, the judged set first (its switch takes the
    unpolished twin), the polished set's switch the polished twin, marked ``"polished":
    true`` in ``heading_switches``. The polish then adds switches and takes none away: the
    polish shrinks some right leads (overhead seed 3) and finds others (105_05 from 90
    degrees). With ``polish_revoke`` "unsupported", paired with the earlier default on dev:
    the 27 off-front parity tracks +8.0 +- 4.5 points (81.0 -> 89.1 %, three back-to-front
    tracks put right, none lost more than 2.1), the 45 dev wide sequences +0.03 +- 0.06
    (two changed, none lost more than 1.1; overhead seed 3 keeps its judged switch), the
    candidates per frame unchanged (README, "Polished leads beside the judged ones").

    ``polish_revoke``: the :data:`RETRO_REVOKES` rule for a switch made on polished leads
    (:func:`.retrack.revoke_rule`; ``"same"``: ``retro_revoke``'s; ``"unsupported"`` by
    default since 2026-11-29). ``"outscored"`` judges the re-tracked frames unpolished,
    where from the side or behind the two headings' energies are within 1 to 2 % of each
    other: it took back overhead seed 1's polished right switches.

    ``judge_start``: with ``judge_tile``, a start check whose two tracks came out within the
    margin of each other (``heading_check.ambiguous``) is decided by their mean energy per
    pixel on ``judge_tile`` tiles, the lower kept (``heading_check.decided_by = "judge"``),
    instead of keeping the initial heading. One render per checked frame and track. Not
    adopted: on nine dev sequences it put overhead seed 1 right (23 -> 99 %) and 05_20 seed
    1 wrong (77 -> 54 %, a 0.2 % lead) (README, "Front or back at a finer tile").

    ``reseat_every``: every that many frames (0 = never) each limb of the tracked pose is set
    to every pose of the limb library (k-means centres of the train motions' arm and leg
    poses, one batch), the ``reseat_climbs`` lowest of each limb are climbed over that limb,
    and the lowest replaces the track when its energy is lower than the tracked pose's,
    climbed alike, by the fraction ``reseat_margin`` (:func:`.reseat.recheck_reseat`: a limb
    held in the wrong basin, which the climb's small steps do not leave). Off by default:
    judged by the truth on 19 dev tracks each decision helps the frame it acts on (margin
    0.01: 9 of 38 frames taken better by more than 2 cm, 1 worse), but tracked, paired with
    the default, one sequence lost more than 5 points at margin 0.01 and at 0.05 (90_05
    seed 3, 05_20 seed 1), the rule set before (README, "Re-seating a limb").

    ``reseat_free``: a limb over free space is re-seated (0 = never), looked for every
    ``reseat_free_every`` frames (4: the frames the front/back and limb-side rechecks climb
    the tracked pose on, so the re-seat's comparison costs no climb of its own): where at
    least ``reseat_free_pixels`` of the camera pixels its forearm and hand (shin and foot)
    cover read more than ``reseat_free_gap`` metres behind them, and they are at least the
    fraction ``reseat_free`` of those segments' pixels with a reading, the camera sees
    through the limb (:func:`.reseat.free_space_limbs`); those limbs alone are re-seated as
    above, at ``reseat_margin``. Named from the dev tracks (every frame of the 72 kept
    default tracks, 2026-11-30): a lower limb half over free space had its end joint more
    than 15 cm off on 68 % of such limb-frames (share 0.5, 5 pixels; 8 % of all limb-frames
    are that far off), and a re-seat of that limb alone, climbed, led by more than 1 % on 18
    of 75 sampled, bringing the end joint closer by more than 2 cm on 13 of them and taking
    it further on 3 (mean joint error there 8.3 -> 6.5 cm). 0.5 by default since 2026-11-30
    (dev, 72 tracks paired: +0.47 points, none lost more than 1.1, from 90 degrees 87.2 ->
    90.4 %, candidates a frame the same; looked for every frame it cost 12 % more; README,
    "A limb over free space"); ``--preset fast`` leaves it out.

    ``reseat_free_climbed``: where a limb over free space is looked at and no library pose
    wins, the tracked pose climbed without the motion prior (the rechecks' shared climb)
    replaces it when it no longer holds any of those limbs over free space: the prior held
    the limb where the camera sees through it, and the image alone pulls it in. Its
    ``reseats`` entry says ``"climbed": true``. Off by default (README, "A limb over free
    space").

    ``reseat_hidden``: a limb tracked hidden is re-seated too (0 = never): on the frames the
    free-space look runs (``reseat_free_every``), a limb whose forearm and hand (shin and
    foot) show on fewer than the fraction ``reseat_hidden`` of the person's pixels in the
    pose's render (:func:`.reach.hidden_limbs`: behind the body, where it costs nothing,
    or off the person) is re-seated as above, at ``reseat_margin`` (``reseats`` entry
    ``"trigger": "hidden"`` and the ``"hidden"`` limbs). A truly hidden limb stays where it
    is unless a library pose explains the image better by the margin. Named from the dev
    tracks: a limb tracked hidden behind the body while the real one is in view is the
    commoner miss, and the free-space look never sees it (README, "A limb tracked hidden").
    0.01 by default since 2026-11-30 (dev, 42 paired: see the README); ``--preset fast``
    leaves it out.

    ``margins_over``: what ``limb_margin``, ``reseat_margin`` and
    :attr:`~.settings.ProposalSettings.reach_margin` are fractions of (:data:`MARGIN_BASES`,
    :func:`.energy.relative_lead`): ``"energy"``, the tracked pose's whole energy;
    ``"explainable"``, that energy less the share every pose pays (the ROI's pixels without a
    reading, :func:`.energy.fixed_energy`), so that a person near the image's edge, whose
    ROI reaches out of the image, needs no larger gain than one in mid-image (dev probe: a
    frontal cartwheel on SR4000, its right arm tracked folded at the head for 20 frames while
    the recogniser's wrist proposal was 4 cm from the truth; the reach, climbed, scored 2.0 %
    lower than the kept pose, 3.1 % of what was not fixed). ``"energy"`` stays the default:
    the probe's three seeds gained 8.2, 0 and 9.8 points, but the first six dev seed-1
    sequences lost 2.3 on average, 02_03 8.7 (README, "A frontal cartwheel before a wall").

    ``retro_frames``: after a recheck turns the track (a heading switch), the frames before
    the switch were tracked facing the wrong way too, since the evidence took frames to add
    up: up to that many of them (default 50 since 2026-11-27; 0 = off) are tracked again backwards in time from the
    turned pose, the heading recheck off on the way, until the forward track faces the way
    the backward one does (their trunks less than a quarter turn apart) or the backward
    track reaches the last start or switch; the backward poses replace the forward ones unless their energy
    summed over those frames, judged as the recheck judges (on ``judge_tile`` tiles,
    without the motion prior), exceeds the forward poses' by more than the fraction
    ``retro_margin``: before the switch the two headings explain the frames about equally
    (else the recheck would have turned sooner), and the backward track's continuity with
    the turned pose is the evidence (``heading_retracks`` in ``summary.json``).
    The loop then holds each pose back that many frames before it yields it
    (:func:`.loop.stream_poses`).

    ``retro_after``: which corrections have the frames before them re-tracked so:
    ``"heading"`` (a heading switch, as above), ``"limbs"`` (a limb swap,
    :func:`.heading.recheck_limb_sides`: the backward track runs with the heading and limb
    rechecks off and stops where the forward track's swapped limbs already lie on the sides
    the backward track's do) and ``"recovery"`` (a lost track found again,
    :func:`.judge.judge_frame`: rechecks off, stops where the two tracks agree, mean joint
    distance under 5 cm). Each re-track is judged by the same energy rule
    (``retracks`` in ``summary.json``, with its ``kind``). All three by default since
    2026-11-27 (dev, paired with ``("heading",)``: +1.5 points, none lost more than 5, 9 %
    more candidates; README, "The frames before a limb swap or a recovery").

    ``retro_take``: what of a backward track the rule above refuses may still replace the
    forward poses. ``"all"``: nothing (all or nothing). ``"prefix"``: the frames from the
    correction back to where the backward track's energy less the forward's, summed from the
    correction, is lowest, when that sum is below zero -- the frames next to the correction
    where the backward track explains the image better than the forward one, no margin
    (:func:`.retrack.best_prefix`): a backward track that holds the person for twenty frames
    and then loses them in a turn gives those twenty. One that follows a wrong correction
    scores worse from its first frame and gives none. Default since 2026-11-27 (dev: cartwheel seed
    1 30 -> 55 %, no other sequence changed by more than 0.3 points; README, "The frames
    before a correction: given up, or taken in part"). A re-track's ``taken`` is true when
    any frame was taken, ``frames_taken`` says how many.

    ``retro_give_up``: a backward track whose energy, less the forward's times ``1 +
    retro_margin`` and summed from the correction, is above zero and has not reached a new
    minimum for that many frames is stopped there and refused (0 = never;
    :func:`.retrack.gave_up`, ``stopped: "worse"`` in ``retracks``; ``retro_take`` may still
    take the frames next to the correction): it has lost the person or follows a wrong
    correction, and the rest of its window is work for nothing. Default 5 since 2026-11-27
    (dev: no sequence changed, 22 % fewer frames re-tracked).

    ``retro_stop``: which earlier corrections a backward track stops at (it always stops at
    the start). ``"any"``: the frame after any earlier correction whose frames were
    re-tracked. ``"rank"``: only one of its own kind or of a kind before it in
    :data:`.retrack.CORRECTION_ORDER` (heading, recovery, limbs): a heading switch's backward
    track goes on past a limb swap or a recovery (those corrected the limbs or found the
    person again, with the heading the forward track had, which the switch now says was
    wrong), a recovery's past a limb swap; a limb swap's stops at any. Where it goes on, the
    energy rule judges the frames past the earlier correction as any others. ``"rank"`` is
    the default since 2026-11-29 (``"any"`` before): a recovery found by the recogniser's
    proposals after the track had followed a cartwheel 180 degrees out of phase (an
    upside-down star explains the silhouette as well as an upright one with the arms raised)
    re-tracked only the frames after a limb swap that the wrong track itself had made; with
    ``"rank"`` it re-tracks them all (dev probe, the cartwheel leaving the image: seeds 1 and
    3 55.7 -> 75.9 and 61.9 -> 80.0 %; on the 42 dev wide sequences it changes two, 90_05
    seeds 1 and 2, -2.9 and +0.8; paired over the 45 +0.8 points, none lost more than 5,
    3 % more candidates; README, "A heading switch's re-track past an earlier limb swap or
    recovery"). Earlier looks: of 70 dev sequences it changed one (90_05 seed 2, 50.5 ->
    50.4 %), none of 12 train-clip sequences; on the test split, where the failure was
    first found (an informed figure), the 8 sequences it changed gained 8.9 points.

    ``retro_revoke``: which heading switches their re-track takes back (:data:`RETRO_REVOKES`,
    :func:`.retrack.revokes`): ``"refused"``, one whose re-track re-tracked frames and took
    none; ``"unsupported"``, one whose backward track did better on no frame next to it,
    even where the whole was within the margin; ``"outscored"``, those and one whose
    backward track's energy summed over all the frames it re-tracked is above the forward
    track's (no margin) and did better on fewer than half of them; ``"never"``. The switch's frame is tracked
    again without the heading recheck, its votes and evidence cleared
    (:func:`.retrack.revoke_switch`; the entry gets ``revoked`` and the ``switch``). A right
    switch is continuous with the frames before it; a lead that was noise is not.
    ``"unsupported"`` by default since 2026-11-28: of the 42 dev wide sequences it changes
    one, walk-back seed 2 (a wrong switch on frame 44, its backward track worse from the
    first frame), 90.4 -> 100 %; the eight other switches on dev had frames done better next
    to them -- five right, two in 90_05 seed 2's fast spin, and 05_20 seed 3's wrong one on
    frame 44, which the image bears out for 13 frames (README, "A switch the frames before
    it do not bear out"). ``"outscored"`` by default since 2026-11-29: that switch (a back
    bend seen from the side, read as a forward bend facing the other way) re-tracked all 44
    frames back to the start, 1 % worse over them, better on 13: taken back, 20.3 -> 76.5 %;
    it changes one more dev sequence, 90_05 seed 2 (a wrong switch in the fast spin, 44.0 ->
    41.2 %; README, "A turn the frames before it bear out only next to it").
    ``"outscored_unless_met"`` by default since 2026-11-29 (later): ``"outscored"``, but a
    switch whose backward track met the forward track's heading (its re-track stopped
    ``"same heading"``: the turn found inside the window) is judged as ``"unsupported"``
    judges it. In a fast spin the frames of the turn are explained badly by either track,
    so their summed energy does not say which way the person ended up facing: 90_05 seed
    2's switch on frame 28 (its backward track met the forward heading on frame 18, better
    on 3 of 9 frames, 3 % worse over them) now stands, 44.8 -> 64.9 %; no other of the 99
    dev tracks of the wide and parity presets has such a revoke, and the shape fit's trial
    (``retro_frames`` 0) and the start check re-track nothing, so none other changes
    (README, "A turn found inside the window").

    ``retro_settle``: that many frames after a start (automatic, after its front/back check,
    or handed on by the shape fit; 0 = off; 12 by default since 2026-11-30, with
    :attr:`~.settings.EnergySettings.prior_huber` 3: dev 42 paired +1.65 points, none lost
    more than 5, off-front parity +3.0; README, "The frames back to a start"), when that
    frame made no correction, the frames back to the start (or to the last correction
    re-tracked since) are tracked again backwards from the track's pose (``retracks`` kind
    ``"settle"``): a start wrong in one limb that the track finds by itself a few frames
    later has no correction to re-track from. It runs back to the start whether or not the two tracks agree on the way (they
    agree next to the frame the track settled on and may differ only near the start), and
    its poses replace the forward ones only where they explain the frames better, with no
    margin (nothing was corrected to vouch for them). It reaches back at most
    ``retro_frames`` frames.
    """

    frames: int = 10
    min_frames: int = 10
    margin: float = 0.1
    start_by: str = "unexplained"
    energy_margin: float = 0.0
    every: int = 4
    recheck_margin: float = 0.05
    votes: int = 2
    twin_passes: int = 1
    evidence_drift: float = 0.01
    evidence_threshold: float = 0.1
    start_twin: str = "swapped"
    search_every: int = 0
    search_margin: float = 0.05
    search_both: bool = True
    twin_starts: tuple = ("turned", "rest")
    twin_swaps: tuple = ("all",)
    limb_every: int = 4
    limb_margin: float = 0.05
    refit_level: int = 0
    twin_climbs: int = 1
    recheck_tile: int = 0
    judge_tile: int = 256
    judge_start: bool = False
    polish_within: float = 0.05
    polish_side: str = "above"
    polish_evidence: str = "separate"
    polish_revoke: str = "unsupported"
    reseat_every: int = 0
    reseat_margin: float = 0.01
    reseat_climbs: int = 1
    reseat_free: float = 0.5
    reseat_free_pixels: int = 5
    reseat_free_gap: float = 0.25
    reseat_free_every: int = 4
    reseat_free_climbed: bool = False
    reseat_hidden: float = 0.01
    retro_frames: int = 50
    retro_margin: float = 0.05
    retro_after: tuple = ("heading", "limbs", "recovery")
    retro_take: str = "prefix"
    retro_give_up: int = 5
    retro_stop: str = "rank"
    retro_revoke: str = "outscored_unless_met"
    retro_settle: int = 12
    margins_over: str = "energy"

    def __post_init__(self):
        _one_of(self, "start_by", START_SCORES)
        _one_of(self, "margins_over", MARGIN_BASES)
        _one_of(self, "polish_side", POLISH_SIDES)
        _one_of(self, "polish_evidence", POLISH_EVIDENCES)
        _one_of(self, "polish_revoke", POLISH_REVOKES)
        _one_of(self, "start_twin", START_TWINS)
        _positive(self, "frames", "min_frames", "margin", "every", "recheck_margin",
                  "evidence_drift", "evidence_threshold", "search_every", "search_margin", "energy_margin",
                  "limb_every", "limb_margin", "refit_level", "twin_climbs", "reseat_every",
                  "reseat_margin", "reseat_free", "reseat_free_pixels", "reseat_free_gap",
                  "reseat_free_every", "reseat_hidden", "retro_frames", "retro_margin", "retro_give_up",
                  "retro_settle", "polish_within", allow_zero=True)
        _positive(self, "votes", "twin_passes", "reseat_climbs")
        _power_of_two(self.recheck_tile, "HeadingSettings.recheck_tile", zero_ok=True)
        _power_of_two(self.judge_tile, "HeadingSettings.judge_tile", zero_ok=True)
        _check(isinstance(self.reseat_free_climbed, bool), "HeadingSettings.reseat_free_climbed "
               f"must be true or false, not {self.reseat_free_climbed!r}")
        _check(isinstance(self.judge_start, bool), f"HeadingSettings.judge_start must be true "
                                                   f"or false, not {self.judge_start!r}")
        object.__setattr__(self, "twin_starts", tuple(self.twin_starts))
        object.__setattr__(self, "twin_swaps", tuple(self.twin_swaps))
        _check(len(self.twin_swaps) > 0 and set(self.twin_swaps) <= set(TWIN_SWAPS),
               f"HeadingSettings.twin_swaps must be a non-empty choice of "
               f"{', '.join(TWIN_SWAPS)}, not {self.twin_swaps!r}")
        object.__setattr__(self, "retro_after", tuple(self.retro_after))
        _check(set(self.retro_after) <= set(RETRO_KINDS),
               f"HeadingSettings.retro_after must be a choice of {', '.join(RETRO_KINDS)}, "
               f"not {self.retro_after!r}")
        _one_of(self, "retro_stop", RETRO_STOPS)
        _one_of(self, "retro_take", RETRO_TAKES)
        _one_of(self, "retro_revoke", RETRO_REVOKES)
        _check(len(self.twin_starts) > 0 and set(self.twin_starts) <= set(TWIN_STARTS),
               f"HeadingSettings.twin_starts must be a non-empty choice of "
               f"{', '.join(TWIN_STARTS)}, not {self.twin_starts!r}")
