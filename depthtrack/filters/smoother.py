"""Rauch-Tung-Striebel smoothing, linear and unscented (offline use of a forward filter's output).

Rauch, Tung & Striebel 1965 for the linear case; the unscented RTS smoother of
Särkkä 2008 ("Unscented Rauch-Tung-Striebel smoother", IEEE TAC 53(3)) for the
UKF: the smoother gain is ``G_t = C_{t+1} (P^-_{t+1})^-1`` with ``C_{t+1}`` the
cross-covariance of ``x_t`` and ``x_{t+1}`` from the prediction's sigma points
(for a linear model ``C = P_t F^T`` and both coincide).
"""
from __future__ import annotations

import numpy as np


def rts_smooth(xs, Ps, xs_prior, Ps_prior, Cs, residual=None):
    """Backward pass over a forward filter's results.

    Parameters
    ----------
    xs, Ps : (T, n), (T, n, n)
        Filtered means and covariances of frames 0 .. T-1.
    xs_prior, Ps_prior : (T, n), (T, n, n)
        Predicted means and covariances of frames 0 .. T-1 (row 0 unused).
    Cs : (T, n, n)
        ``Cs[t]`` the cross-covariance of ``x_{t-1}`` and the prediction of ``x_t``
        (``P_{t-1} F^T`` for a linear model; row 0 unused).
    residual : callable(a, b) -> a - b, optional
        State difference with wrapping.

    Returns
    -------
    (T, n) smoothed means, (T, n, n) smoothed covariances.
    """
    res = residual or (lambda a, b: np.asarray(a) - np.asarray(b))
    xs = np.asarray(xs, dtype=float)
    T = len(xs)
    xs_s = xs.copy()
    Ps_s = np.array(Ps, dtype=float)
    for t in range(T - 2, -1, -1):
        G = np.linalg.solve(Ps_prior[t + 1].T, np.asarray(Cs[t + 1]).T).T     # C P^-1
        xs_s[t] = xs[t] + G @ res(xs_s[t + 1], xs_prior[t + 1])
        Ps_s[t] = Ps[t] + G @ (Ps_s[t + 1] - Ps_prior[t + 1]) @ G.T
        Ps_s[t] = 0.5 * (Ps_s[t] + Ps_s[t].T)
    return xs_s, Ps_s
