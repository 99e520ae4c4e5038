"""Unscented Kalman filter (Julier/Uhlmann, van der Merwe's scaled sigma points), filterpy-style.

The thesis (7.3.3, 8.2) proposes putting its motion model into a Kalman filter;
the model is non-linear in the phase c (the reference acceleration is looked up
at c) and in the speed (scaled by (v / v_ref)^2), so the unscented transform is
used. Angles wrap: residuals and means go through ``residual_x`` / ``residual_z``
and ``mean_x`` / ``mean_z`` hooks.
"""
from __future__ import annotations

import numpy as np
from scipy.linalg import cholesky


class MerweScaledSigmaPoints:
    """2n + 1 sigma points ``x +- columns of sqrt((n + lambda) P)``.

    Parameters
    ----------
    n : int
    alpha, beta, kappa : float
        Spread (small alpha: points near the mean), prior knowledge (2 for Gaussians), extra scaling.
    """

    def __init__(self, n: int, alpha: float = 1e-3, beta: float = 2.0, kappa: float = 0.0):
        self.n, self.alpha, self.beta, self.kappa = n, alpha, beta, kappa
        lam = alpha ** 2 * (n + kappa) - n
        self.lam = lam
        self.Wc = np.full(2 * n + 1, 0.5 / (n + lam))
        self.Wm = self.Wc.copy()
        self.Wm[0] = lam / (n + lam)
        self.Wc[0] = lam / (n + lam) + (1 - alpha ** 2 + beta)

    def sigma_points(self, x, P, add=None):
        """``x (n,)``, ``P (n, n)`` -> ``(2n + 1, n)`` sigma points (``add(x, dx)`` adds offsets)."""
        n = self.n
        P = 0.5 * (P + P.T)
        try:
            U = cholesky((n + self.lam) * P)          # upper: U^T U = (n + lam) P
        except np.linalg.LinAlgError:
            w, V = np.linalg.eigh((n + self.lam) * P)
            U = (V * np.sqrt(np.clip(w, 0, None))).T
        add = (lambda a, b: a + b) if add is None else add
        sig = np.empty((2 * n + 1, n))
        sig[0] = x
        for k in range(n):
            sig[k + 1] = add(x, U[k])
            sig[n + k + 1] = add(x, -U[k])
        return sig


def unscented_transform(sigmas, Wm, Wc, noise_cov=None, mean_fn=None, residual_fn=None):
    """Mean and covariance of transformed sigma points ``(2n + 1, m)``.

    ``mean_fn(sigmas, Wm) -> (m,)`` and ``residual_fn(a, b) -> a - b`` handle wrapping.
    Returns ``mean (m,)``, ``cov (m, m)``.
    """
    mean = np.dot(Wm, sigmas) if mean_fn is None else mean_fn(sigmas, Wm)
    d = sigmas - mean if residual_fn is None else residual_fn(sigmas, mean)
    cov = (d * Wc[:, None]).T @ d
    if noise_cov is not None:
        cov = cov + noise_cov
    return mean, cov


class UnscentedKalmanFilter:
    """UKF with additive process and measurement noise.

    Parameters
    ----------
    x : (n,) float
    P : (n, n) float
    fx : callable(sigmas (2n+1, n)) -> (2n+1, n)
        Process model applied to all sigma points at once.
    hx : callable(sigmas (2n+1, n)) -> (2n+1, m)
        Measurement model.
    Q : (n, n) float or callable(x) -> (n, n)
        Process noise (a callable is evaluated at the posterior mean before predicting).
    R : (m, m) float
    points : MerweScaledSigmaPoints, optional
    residual_x, residual_z : callable(a, b) -> a - b
    mean_x, mean_z : callable(sigmas, Wm) -> mean
    align_z : callable(z, z_pred) -> z
        Re-expresses a measurement next to the prediction (angle branches).

    Attributes
    ----------
    x, P : posterior; ``x_prior``, ``P_prior`` after :meth:`predict`; ``S``, ``K``, ``y`` of the last update.
    C : (n, n) cross-covariance of the state before and after the last :meth:`predict`
        (what :func:`depthtrack.filters.smoother.rts_smooth` needs).
    """

    def __init__(self, x, P, fx, hx, Q, R, points=None, residual_x=None, residual_z=None,
                 mean_x=None, mean_z=None, align_z=None):
        self.x = np.asarray(x, dtype=float).copy()
        self.P = np.asarray(P, dtype=float).copy()
        self.fx, self.hx, self.Q, self.R = fx, hx, Q, np.asarray(R, dtype=float)
        n = len(self.x)
        self.points = MerweScaledSigmaPoints(n) if points is None else points
        self.residual_x = residual_x or (lambda a, b: a - b)
        self.residual_z = residual_z or (lambda a, b: a - b)
        self.mean_x, self.mean_z, self.align_z = mean_x, mean_z, align_z
        self.x_prior, self.P_prior = self.x.copy(), self.P.copy()
        self.sigmas_f = None
        self.S = self.K = self.y = None
        self.C = None

    def _add_x(self, x, dx):
        return x + dx

    def predict(self):
        Q = self.Q(self.x) if callable(self.Q) else self.Q
        x_before = self.x
        sig = self.points.sigma_points(self.x, self.P, self._add_x)
        self.sigmas_f = self.fx(sig)
        self.x, self.P = unscented_transform(self.sigmas_f, self.points.Wm, self.points.Wc, Q,
                                             self.mean_x, self.residual_x)
        # Cross-covariance of the previous and the predicted state, for the unscented RTS smoother.
        d0 = self.residual_x(sig, x_before)
        d1 = self.residual_x(self.sigmas_f, self.x)
        self.C = (d0 * self.points.Wc[:, None]).T @ d1
        self.x_prior, self.P_prior = self.x.copy(), self.P.copy()
        return self.x

    def update(self, z, R=None):
        R = self.R if R is None else np.asarray(R, dtype=float)
        # Fresh sigma points of the prior (which includes Q): exact for linear models,
        # unlike reusing the propagated points that never saw the process noise.
        self.sigmas_f = self.points.sigma_points(self.x, self.P, self._add_x)
        sig_z = self.hx(self.sigmas_f)
        z_pred, S = unscented_transform(sig_z, self.points.Wm, self.points.Wc, R, self.mean_z, self.residual_z)
        z = np.asarray(z, dtype=float)
        if self.align_z is not None:
            z = self.align_z(z, z_pred)
        dx = self.residual_x(self.sigmas_f, self.x)
        dz = self.residual_z(sig_z, z_pred)
        Pxz = (dx * self.points.Wc[:, None]).T @ dz
        K = np.linalg.solve(S.T, Pxz.T).T
        self.y = self.residual_z(z[None], z_pred[None])[0]
        self.x = self.x + K @ self.y
        self.P = self.P - K @ S @ K.T
        self.P = 0.5 * (self.P + self.P.T)
        self.S, self.K = S, K
        return self.x
