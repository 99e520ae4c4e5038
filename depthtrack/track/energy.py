"""The MAP energy of candidate poses against one observation (the tracker's score).

MAP energy of a candidate pose ``x`` with velocity ``v = x (-) x_{t-1}``::

    E(x) = w * A * mean_tile_cost(x) + 0.5 * sum(((v - v_pred) / sigma)^2)
                                     + 0.5 * sum((x_joints / pose_prior_std)^2)

``mean_tile_cost`` is :meth:`TileRenderer.costs` (smoothed or pixel likelihood, each pixel's
cost a negative log-likelihood), ``A`` the ROI's area in camera pixels, so ``A * mean`` is
the negative log-likelihood summed over the camera pixels the tile covers, and
``w = likelihood_weight`` (1 = pixels independent, as in the paper's model); the second term
is ``-log p(v_t | v_{t-1})`` of :class:`~depthtrack.motion.prior.ConstantVelocityPrior` (only
while tracking: :meth:`Energy.with_prior`); the third a weak pose prior on the joint
rotations (:attr:`EnergySettings.pose_prior_std`, our addition for hidden limbs).

An :class:`Energy` is immutable: the mode of a search (with or without the motion prior,
the coarse or the fine renderer) is a different Energy, never a switched flag.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np


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
    prior : ConstantVelocityPrior or None
        With ``previous (48,)`` and ``v_pred (48,)``: the motion-prior term; None = off.
    """

    renderer: object
    weight: float
    smoothed: bool
    recorder: object
    pose_prior_std: float = 1.0
    prior: object = None
    previous: np.ndarray | None = None
    v_pred: np.ndarray | None = None

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
        if self.pose_prior_std > 0:
            e = e + 0.5 * np.sum((poses[:, 6:] / self.pose_prior_std) ** 2, axis=1)
        return e

    def one(self, pose) -> float:
        """Energy of one pose ``(48,)``."""
        return float(self(np.asarray(pose)[None])[0])
