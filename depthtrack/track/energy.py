"""The MAP energy of candidate poses against one observation (the tracker's score).

MAP energy of a candidate pose ``x`` with velocity ``v = x (-) x_{t-1}``::

    E(x) = w * A * mean_tile_cost(x) + 0.5 * sum(((v - v_pred) / sigma)^2)
                                     + 0.5 * sum((x_joints / std_joints)^2)
                                     + 0.5 * (spine_twist(x) / twist_std)^2

``mean_tile_cost`` is :meth:`TileRenderer.costs` (smoothed or pixel likelihood, each pixel's
cost a negative log-likelihood), ``A`` the ROI's area in camera pixels, so ``A * mean`` is
the negative log-likelihood summed over the camera pixels the tile covers, and
``w = likelihood_weight`` (1 = pixels independent, as in the paper's model); the second term
is ``-log p(v_t | v_{t-1})`` of :class:`~depthtrack.motion.prior.ConstantVelocityPrior` (only
while tracking: :meth:`Energy.with_prior`); the third a weak pose prior on the joint
rotations (``std_joints``: :attr:`EnergySettings.pose_prior_std`, our addition for hidden
limbs, and :attr:`EnergySettings.hidden_prior_std` on the joints of the limbs the frame's
predicted pose shows hidden: :meth:`Energy.with_hidden`, :func:`pose_prior`; with
:attr:`EnergySettings.limb_prior` the limbs' root and middle joints are scored by the
learned :mod:`.limb_prior` instead); the fourth
a prior on the trunk's twist (:func:`spine_twist`, :attr:`EnergySettings.twist_std`, also
ours): the likelihood barely sees which way the pelvis points under a chest and legs that
it does see, and a turning track left its pelvis 30 to 70 degrees behind the chest, the hip
joints 10 to 20 cm off, where a person twists a few degrees. The prior alone is outweighed
by the motion prior; the search's untwist moves (:attr:`SearchSettings.untwist`) give it
a step that turns the pelvis back at once.

An :class:`Energy` is immutable: the mode of a search (with or without the motion prior,
the coarse or the fine renderer) is a different Energy, never a switched flag.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..body.skeleton import JOINT_ID
from ..likelihood import fixed_and_empty_costs

#: Parameters of the spine's rotation vector in a pose (the chest against the pelvis),
#: from the skeleton's joint order (joint j's rotation is ``3 + 3j .. 5 + 3j``).
SPINE_ROTATION = slice(3 + 3 * JOINT_ID["spine"], 6 + 3 * JOINT_ID["spine"])


def pose_prior(poses, std: float, hidden_joints=(), hidden_std: float = 0.0,
               dropped_joints=()) -> np.ndarray:
    """``(N,)`` the pose prior ``0.5 * sum((x_j / std_j)^2)`` over the joint rotations
    ``x_j`` of ``poses (N, 48)`` (parameters 6..47; the root's translation and rotation are
    free), ``std_j`` = ``std`` except on the joints listed in ``hidden_joints`` (indices into
    the skeleton's joints, >= 1), where it is ``hidden_std``. A std of 0 drops its terms;
    so do ``dropped_joints`` (those another term scores: :mod:`.limb_prior`), unless hidden."""
    poses = np.atleast_2d(np.asarray(poses, dtype=np.float64))
    joints = poses[:, 6:].reshape(len(poses), -1, 3)                  # (N, 14, 3): joints 1..14
    precision = np.full(joints.shape[1], 0.0 if std <= 0 else 1.0 / std ** 2)
    if dropped_joints:
        precision[np.asarray(dropped_joints, dtype=np.int64) - 1] = 0.0
    if hidden_joints:
        precision[np.asarray(hidden_joints, dtype=np.int64) - 1] = (
            0.0 if hidden_std <= 0 else 1.0 / hidden_std ** 2)
    return 0.5 * np.einsum("nj,j->n", np.sum(joints ** 2, axis=2), precision)


def spine_twist(poses) -> np.ndarray:
    """``(N,)`` twist (rad) of the chest against the pelvis about the trunk's long axis.

    The twist of the swing-twist decomposition of the spine's rotation about the model's
    vertical axis (``ry``, :mod:`depthtrack.body.skeleton`): with the rotation's quaternion
    ``(w, x, y, z)``, ``2 atan2(y, w)``, wrapped to (-pi, pi]. Unlike the rotation vector's
    ``ry`` component it does not change when the chest also bends.

    Parameters
    ----------
    poses : (N, 48) or (48,) float
    """
    r = np.atleast_2d(np.asarray(poses, dtype=np.float64))[:, SPINE_ROTATION]
    angle = np.linalg.norm(r, axis=1)
    half = 0.5 * angle
    # sin(half) / angle * r_y without dividing by a zero angle
    sinc = np.where(angle > 1e-12, np.sin(half) / np.maximum(angle, 1e-12), 0.5)
    twist = 2.0 * np.arctan2(sinc * r[:, 1], np.cos(half))
    return (twist + np.pi) % (2.0 * np.pi) - np.pi


@dataclass(frozen=True)
class Energy:
    """``(N, 48) -> (N,)`` MAP energy (module docstring).

    Attributes
    ----------
    renderer : TileRenderer
        Holds the observation (uploaded by :func:`~.observe.upload`).
    weight : float
        ``w * A``.
    smoothed : bool
    recorder : Recorder
    pose_prior_std : float
    twist_std : float
        Standard deviation (rad) of the trunk-twist prior (0 = off).
    hidden_joints : tuple of int
        Joints (skeleton indices) whose rotations take ``hidden_prior_std`` instead of
        ``pose_prior_std`` (:meth:`with_hidden`); empty = none.
    hidden_prior_std : float
    limb_prior : LimbPrior or None
        The learned limb prior (:class:`.limb_prior.LimbPrior`): scores the rotations of
        its ``joints`` in place of the Gaussian; None = off.
    prior : ConstantVelocityPrior or None
        With ``previous (48,)`` and ``v_pred (48,)``: the motion-prior term; None = off.
    """

    renderer: object
    weight: float
    smoothed: bool
    recorder: object
    pose_prior_std: float = 1.0
    twist_std: float = 0.0
    prior: object = None
    previous: np.ndarray | None = None
    v_pred: np.ndarray | None = None
    hidden_joints: tuple = ()
    hidden_prior_std: float = 0.0
    limb_prior: object = None

    def with_limb_prior(self, limb_prior) -> "Energy":
        """The same energy with the learned limb prior (:mod:`.limb_prior`) on its joints."""
        return dataclasses.replace(self, limb_prior=limb_prior)

    def with_hidden(self, joints, std: float) -> "Energy":
        """The same energy with the pose prior's std ``std`` on the rotations of ``joints``
        (skeleton indices): the limbs a frame shows hidden (:attr:`EnergySettings.
        hidden_prior_std`)."""
        return dataclasses.replace(self, hidden_joints=tuple(int(j) for j in joints),
                                   hidden_prior_std=float(std))

    def with_prior(self, prior, previous, v_pred) -> "Energy":
        return dataclasses.replace(self, prior=prior, previous=previous, v_pred=v_pred)

    def without_prior(self) -> "Energy":
        return dataclasses.replace(self, prior=None, previous=None, v_pred=None)

    def on(self, renderer) -> "Energy":
        """The same energy scored by another renderer (the polish's finer tiles)."""
        return dataclasses.replace(self, renderer=renderer)

    def likelihood_costs(self, poses) -> np.ndarray:
        """(N,) mean tile costs of ``poses (N, 48)`` against the current observation."""
        with self.recorder.timed("render"):
            c = self.renderer.costs(np.asarray(poses, dtype=np.float64), smoothed=self.smoothed)
        self.recorder.count("candidates", len(c))
        self.recorder.count("render_calls")
        return c

    def likelihood(self, pose) -> float:
        """The likelihood term alone of one pose ``(48,)``."""
        return self.weight * float(self.likelihood_costs(np.asarray(pose)[None])[0])

    def __call__(self, poses) -> np.ndarray:
        poses = np.atleast_2d(poses)
        e = self.weight * self.likelihood_costs(poses)
        if self.prior is not None:
            e = e + self.prior.penalty(poses, self.previous, self.v_pred)
        learned = self.limb_prior
        if self.pose_prior_std > 0 or self.hidden_joints:
            e = e + pose_prior(poses, self.pose_prior_std, self.hidden_joints,
                               self.hidden_prior_std, learned.joints if learned else ())
        if learned is not None:
            e = e + learned.cost(poses)
        if self.twist_std > 0:
            e = e + 0.5 * (spine_twist(poses) / self.twist_std) ** 2
        return e

    def one(self, pose) -> float:
        """Energy of one pose ``(48,)``."""
        return float(self(np.asarray(pose)[None])[0])


def _bounds(energy):
    """``(fixed, empty)`` mean tile costs of the observation ``energy``'s renderer holds
    (:func:`fixed_and_empty_costs`)."""
    r = energy.renderer
    return fixed_and_empty_costs(r.observed_tile, r.params, r.background_tile)


def unexplained(energy, pose) -> float:
    """Share of the observation's cost that ``pose (48,)`` leaves unexplained, against the
    observation held by ``energy``'s renderer: ``(c(x) - c_fixed) / (c_empty - c_fixed)``
    (:mod:`.judge`; about 0.1 - 0.3 on a good fit, near 1 when lost)."""
    c = float(energy.likelihood_costs(np.asarray(pose)[None])[0])
    fixed, empty = _bounds(energy)
    return (c - fixed) / max(empty - fixed, 1e-9)


def fixed_energy(energy) -> float:
    """The part of ``energy``'s value that every pose pays on the observation its renderer
    holds: ``weight`` times the tile's no-reading share (:func:`fixed_and_empty_costs`;
    pixels of the ROI outside the image, or without a reading). A person near the image's
    edge puts a large share of the ROI outside it (dev probe: a frontal cartwheel on SR4000,
    36 % of a frame's energy), so a margin taken as a fraction of the whole energy asks more
    of a candidate there than in mid-image."""
    fixed, _ = _bounds(energy)
    return float(energy.weight * fixed)


def margin_floor(energy, margins_over: str) -> float:
    """The floor the rechecks' relative margins are taken over
    (:attr:`~.heading_settings.HeadingSettings.margins_over`): :func:`fixed_energy` of
    ``energy`` with ``"explainable"``, else 0 (a fraction of the whole energy)."""
    return fixed_energy(energy) if margins_over == "explainable" else 0.0


def relative_lead(e_kept, e_new, floor: float = 0.0) -> float:
    """How much lower ``e_new`` is than ``e_kept``, as a fraction of ``e_kept - floor``
    (``floor``: :func:`fixed_energy`, or 0 for a fraction of the whole energy); > 0 when
    ``e_new`` is lower. The rechecks' relative margins (limb sides, reach, reseat) compare
    this with their margin."""
    return (float(e_kept) - float(e_new)) / max(abs(float(e_kept) - floor), 1e-9)
