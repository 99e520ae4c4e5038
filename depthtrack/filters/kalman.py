"""Linear Kalman filter (the closed-form reference for the particle and unscented filters)."""
from __future__ import annotations

import numpy as np


def kf_predict(x, P, F, Q, u=None):
    """``x (n,)``, ``P (n, n)`` -> prior ``F x + u``, ``F P F^T + Q``."""
    x = F @ x + (0 if u is None else u)
    P = F @ P @ F.T + Q
    return x, P


def kf_update(x, P, z, H, R):
    """Posterior of ``x (n,)``, ``P (n, n)`` given ``z (m,)`` with ``z = H x + N(0, R)``.

    Uses the Joseph form for a symmetric, positive covariance.

    Returns
    -------
    x, P, S (innovation covariance), K (gain)
    """
    y = z - H @ x
    S = H @ P @ H.T + R
    K = np.linalg.solve(S.T, (P @ H.T).T).T
    x = x + K @ y
    I_KH = np.eye(len(x)) - K @ H
    P = I_KH @ P @ I_KH.T + K @ R @ K.T
    return x, P, S, K


class KalmanFilter:
    """Linear-Gaussian filter: ``x' = F x + u + N(0, Q)``, ``z = H x + N(0, R)``.

    Attributes mirror filterpy: ``x``, ``P`` (posterior), ``x_prior``, ``P_prior``,
    ``x_post``, ``P_post``, ``S``, ``K``.
    """

    def __init__(self, x, P, F, H, Q, R):
        self.x = np.asarray(x, dtype=float)
        self.P = np.asarray(P, dtype=float)
        self.F, self.H = np.asarray(F, float), np.asarray(H, float)
        self.Q, self.R = np.asarray(Q, float), np.asarray(R, float)
        self.x_prior, self.P_prior = self.x.copy(), self.P.copy()
        self.x_post, self.P_post = self.x.copy(), self.P.copy()
        self.S = self.K = None

    def predict(self, u=None):
        self.x, self.P = kf_predict(self.x, self.P, self.F, self.Q, u)
        self.x_prior, self.P_prior = self.x.copy(), self.P.copy()
        return self.x

    def update(self, z):
        self.x, self.P, self.S, self.K = kf_update(self.x, self.P, np.asarray(z, float), self.H, self.R)
        self.x_post, self.P_post = self.x.copy(), self.P.copy()
        return self.x
