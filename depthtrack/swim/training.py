"""From training cycles to the cyclic motion model (thesis 2.7, 4.6, 4.8).

Velocities and accelerations are taken per cycle, in each cycle's own continuous
angle representation (with context samples beyond the cycle's ends, so long
masks see real data). The cycles are then mapped onto one representation — the
first cycle's — sample by sample: where a cycle uses the other pole branch
``(-theta, phi + pi)`` for a segment, its theta, theta velocity and theta
acceleration change sign. Means over cycles are then meaningful.
"""
from __future__ import annotations

import numpy as np

from ..filters.angles import circular_mean
from ..motion.cyclic import CyclicMotionModel
from ..motion.derivatives import first_order_filter, velocity_acceleration
from .cycles import TrainingCycles
from .stickfigure import equivalent_branch, nearest_equivalent


def cycle_derivatives(training: TrainingCycles, derivative: str = "taylor3", second_order=None):
    """Aligned angles, velocities and accelerations of the training cycles.

    Parameters
    ----------
    training : TrainingCycles
    derivative : str
        First-order filter name (``d1``, ``d2``, ``taylor2`` .. ``taylor4``); applied twice
        for the acceleration unless ``second_order`` (a mask) is given.

    Returns
    -------
    angles, velocities, accelerations : (n, L, 26) float
        Per reference sample and sample^2, in the first cycle's representation.
    """
    first = first_order_filter(derivative)
    v, a = velocity_acceleration(training.extended, first, second_order, axis=1)
    m = training.margin
    stop = training.extended.shape[1] - m
    angles, v, a = training.extended[:, m:stop], v[:, m:stop].copy(), a[:, m:stop].copy()
    aligned, flipped = equivalent_branch(angles, angles[0][None])
    sign = np.where(flipped, -1.0, 1.0)
    v[..., 0::2] *= sign
    a[..., 0::2] *= sign
    return aligned, v, a


def train_motion_model(training: TrainingCycles, derivative: str = "taylor3", second_order=None,
                       temporal_sigma: float | None = None, jitter: float = 0.0) -> CyclicMotionModel:
    """The thesis's motion model from training cycles.

    ``temporal_sigma`` (cycles per frame^2) defaults to half a percent of the
    reference speed per frame, ``0.005 / L``.
    """
    angles, v, a = cycle_derivatives(training, derivative, second_order)
    L = angles.shape[1]
    mean_angles = nearest_equivalent(circular_mean(angles, axis=0), angles[0])
    if temporal_sigma is None:
        temporal_sigma = 0.005 / L
    return CyclicMotionModel(mean_angles, v.mean(axis=0), a, temporal_sigma=temporal_sigma, jitter=jitter)
