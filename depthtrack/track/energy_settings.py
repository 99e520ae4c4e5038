"""The energy's settings (:class:`EnergySettings`): the motion prior's damping and loss, the
likelihood's weight, and the priors on the pose (:mod:`.energy`); re-exported by
:mod:`.settings` with the other groups."""
from __future__ import annotations

from dataclasses import dataclass

from .setting_checks import check as _check
from .setting_checks import positive as _positive


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
        prior on (the trap of ``"shown"``). 0.5 on the far arm on dev (2026-12-02), not
        adopted: +1.7 points on the 9 SR4000 parity tracks from 90 degrees, -0.9 on the 9
        from 270, one of them -10.8 (the far arm tracked raised sideways, a basin the climb
        does not leave; the true arm scores lower there, the hanging one does not; README,
        "The prior on the far side of a side view").
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
