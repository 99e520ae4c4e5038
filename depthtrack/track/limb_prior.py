"""A learned prior on each limb's pose: a Gaussian mixture over the train motions' limbs,
floored by the broad Gaussian it replaces.

The energy's pose prior (:func:`.energy.pose_prior`) is a zero-mean Gaussian of std
``pose_prior_std`` (1 rad) on every joint rotation: it keeps a hidden limb from drifting
anywhere, but it knows nothing of where people hold their limbs. A side view's far arm,
hidden behind the body, was tracked across the chest where the true one hung at the side
(README, "Figures: parity preset on the test split"); a stronger Gaussian (0.5) pulled it
back, and made every raised visible arm pay too (README, "A stronger pose prior").

Here each limb's six numbers ``x`` (root and middle joint rotation vectors,
:data:`.reseat.LIMB_SLOTS`; a right limb mirrored onto the left, :data:`.reseat.MIRROR`) pay::

    cost(x) = -log((1 - floor) * g(x) + floor * n(x)) + log n(0)

``g`` the mixture fitted to the train clips' frames (``tools/make_limb_prior.py``, shipped as
``depthtrack/data/limb_prior.npz``), ``n = N(0, std^2 I)`` the broad Gaussian
(``std = pose_prior_std``). With ``floor = 1`` the cost is that Gaussian's,
``0.5 |x|^2 / std^2``, exactly; with any floor it is at most that plus ``log(1 / floor)``
(``floor * n(x)`` alone bounds the sum), so a limb where no train motion went -- a kick,
a cartwheel -- pays at most that constant more than before, while a limb where people
hold theirs pays less: the prior prefers the common pose only where the image does not
decide.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from pathlib import Path

import numpy as np

from ..body.skeleton import JOINT_ID
from .reach import LIMBS
from .reseat import LIMB_SLOTS, MIRROR

#: The limb kinds and their limbs (the mixture of a kind serves both sides).
KINDS = {"arm": ("l_arm", "r_arm"), "leg": ("l_leg", "r_leg")}
#: The joints whose rotations the prior scores (skeleton indices): each limb's root and
#: middle joint.
PRIOR_JOINTS = tuple(sorted(JOINT_ID[j] for limbs in KINDS.values() for limb in limbs
                            for j in LIMBS[limb][:2]))


def prior_path() -> Path:
    """The shipped mixtures, ``depthtrack/data/limb_prior.npz``."""
    return Path(str(resources.files("depthtrack") / "data" / "limb_prior.npz"))


@dataclass(frozen=True)
class Mixture:
    """A Gaussian mixture over ``D``-vectors.

    Attributes
    ----------
    weights : (K,) float
        Summing to 1.
    means : (K, D) float
    covariances : (K, D, D) float
        Symmetric positive definite.
    """

    weights: np.ndarray
    means: np.ndarray
    covariances: np.ndarray

    def __post_init__(self):
        # factored once: the energy asks for the density of every candidate batch
        object.__setattr__(self, "cholesky", np.linalg.cholesky(self.covariances))

    def log_density(self, x) -> np.ndarray:
        """``(N,)`` ``log g(x)`` of ``x (N, D)``."""
        return mixture_log_density(x, self.weights, self.means, self.cholesky)


def mixture_log_density(x, weights, means, cholesky) -> np.ndarray:
    """``(N,)`` log density of the Gaussian mixture (``weights (K,)``, ``means (K, D)``, the
    covariances' lower Cholesky factors ``cholesky (K, D, D)``) at ``x (N, D)``."""
    x = np.atleast_2d(np.asarray(x, dtype=np.float64))
    chol = np.asarray(cholesky, dtype=np.float64)                            # (K, D, D)
    d = x[None, :, :] - means[:, None, :]                                    # (K, N, D)
    z = np.linalg.solve(chol[:, None], d[..., None])[..., 0]                 # (K, N, D)
    log_det = 2.0 * np.sum(np.log(np.diagonal(chol, axis1=1, axis2=2)), axis=1)   # (K,)
    dim = x.shape[1]
    log_comp = -0.5 * (np.sum(z * z, axis=2) + log_det[:, None] + dim * np.log(2 * np.pi))
    return np.logaddexp.reduce(np.log(weights)[:, None] + log_comp, axis=0)


def floored_cost(x, mixture: Mixture, std: float, floor: float) -> np.ndarray:
    """``(N,)`` the module docstring's ``cost`` of ``x (N, D)``: the mixture floored by
    ``N(0, std^2 I)`` with weight ``floor`` (0 < floor <= 1), relative to that Gaussian's
    density at zero."""
    x = np.atleast_2d(np.asarray(x, dtype=np.float64))
    broad = -0.5 * np.sum(x * x, axis=1) / std ** 2          # log n(x) - log n(0)
    if floor >= 1.0:
        return -broad
    # log g(x) - log n(0): n(0) = (2 pi std^2)^(-D/2)
    learned = mixture.log_density(x) + 0.5 * x.shape[1] * np.log(2 * np.pi * std ** 2)
    return -np.logaddexp(np.log1p(-floor) + learned, np.log(floor) + broad)


@dataclass(frozen=True)
class LimbPrior:
    """The learned prior of every limb, as the energy asks for it.

    Attributes
    ----------
    mixtures : dict
        ``{"arm": Mixture, "leg": Mixture}`` over left-limb six-vectors.
    std : float
        The broad Gaussian's std (:attr:`EnergySettings.pose_prior_std`).
    floor : float
        :attr:`EnergySettings.limb_prior_floor`.
    weight : float
        :attr:`EnergySettings.limb_prior_weight`: how far from the Gaussian toward the
        learned cost (0 = the Gaussian, 1 = the learned).
    """

    mixtures: dict
    std: float
    floor: float
    weight: float = 1.0

    @property
    def joints(self) -> tuple:
        """:data:`PRIOR_JOINTS`: the energy's Gaussian leaves them to this prior."""
        return PRIOR_JOINTS

    def cost(self, poses) -> np.ndarray:
        """``(N,)`` the summed cost of the four limbs of ``poses (N, 48)``."""
        return limb_prior_cost(poses, self.mixtures, self.std, self.floor, self.weight)


def limb_prior_cost(poses, mixtures: dict, std: float, floor: float,
                    weight: float = 1.0) -> np.ndarray:
    """``(N,)`` :func:`floored_cost` summed over the four limbs of ``poses (N, 48)`` (a right
    limb mirrored onto the left); with ``weight`` w, ``gauss + w * (cost - gauss)`` per limb
    (``gauss = 0.5 |x|^2 / std^2``), at most ``gauss + w * log(1 / floor)``."""
    poses = np.atleast_2d(np.asarray(poses, dtype=np.float64))
    total = np.zeros(len(poses))
    for kind, (left, right) in KINDS.items():
        both = np.concatenate([poses[:, LIMB_SLOTS[left]], poses[:, LIMB_SLOTS[right]] * MIRROR])
        c = floored_cost(both, mixtures[kind], std, floor)
        if weight != 1.0:
            gauss = 0.5 * np.sum(both * both, axis=1) / std ** 2
            c = gauss + weight * (c - gauss)
        total += c[:len(poses)] + c[len(poses):]
    return total


@lru_cache(maxsize=4)
def load_mixtures(path=None) -> dict:
    """``{"arm": Mixture, "leg": Mixture}`` from an ``.npz`` of
    ``tools/make_limb_prior.py`` (read once per path)."""
    with np.load(path or prior_path()) as data:
        return {kind: Mixture(np.array(data[f"{kind}_weights"], dtype=np.float64),
                              np.array(data[f"{kind}_means"], dtype=np.float64),
                              np.array(data[f"{kind}_covariances"], dtype=np.float64))
                for kind in KINDS}
