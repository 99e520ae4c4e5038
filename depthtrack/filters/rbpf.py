"""Rao-Blackwellised particle filter for a cyclic motion model (Doucet, de Freitas, Murphy & Russell 2000).

The thesis's state splits into a low-dimensional non-linear part, the cycle
state ``s = (c, v)`` (progress and speed), and a high-dimensional part that is
linear-Gaussian given it, the angles and angular velocities ``x (D = 2A)``::

    x_t = F x_{t-1} + (v_{t-1} L)^2 B mu[floor(c_{t-1} L)] + w,   w ~ N(0, Q)
    z_t = H x_t + n,                                              n ~ N(0, R)

(``F = [[I, I], [0, I]]``, ``B = [I/2; I]``, ``H = [I, 0]``, ``mu`` the (L, A)
table of mean training accelerations). Particles carry only ``s``; ``x`` is
marginalised with a Kalman filter (Rao-Blackwellisation: Doucet et al. 2000,
"Rao-Blackwellised particle filtering for dynamic Bayesian networks", UAI;
the weights are the Kalman predictive likelihoods ``N(z_t; H x_pred, S)``, which
is what makes the proposal use the measurement's information on ``x`` exactly
instead of sampling 52 dimensions and starving).

Two choices make a million particles cheap (numpy, no compiled code):

* ``Q`` and ``R`` do not depend on ``s``, so the Kalman covariance, gain and
  innovation covariance are the same for every particle: one 52-dim Riccati
  step per frame, shared.
* The Kalman means are *collapsed per phase cell*: after every step the means
  of the particles whose progress falls in the same cell (one of ``L``) are
  merged into one (their weighted average), as in GPB1/IMM merging of a
  switching Kalman filter (Blom & Bar-Shalom 1988). A particle's mean is
  then ``X[cell]`` and its prediction ``F X[cell] + s B mu[cell]`` is affine in
  the scalar ``s = (v L)^2``, so its log-likelihood is
  ``-(|a|^2 - 2 s <a, b> + s^2 |b|^2) / 2`` in the ``S^-1`` norm with per-cell
  ``a = z - H F X``, ``b = H B mu``: three table look-ups per particle and
  no per-particle 52-vector. The merge is two ``bincount`` calls over
  (new cell, old cell) pairs and an ``(L, L) @ (L, D)`` product.

Without the collapse this is the exact RBPF; with it, the particles still carry
the exact weights of their current step and the phase/speed posterior; the
angles given the phase are the merged Kalman means. With ``mu = 0`` every cell
holds the same mean and the filter reduces exactly to the Kalman filter
(tested).

Measurements may be missing (``None``: occlusion): then the particles and the
Kalman part only predict.
"""
from __future__ import annotations

import numpy as np

from .angles import wrap
from .fastrandom import table_normals
from .particle import effective_sample_size, low_variance_resample


class CycleRBPF:
    """Rao-Blackwellised particle filter over ``(c, v)`` with a shared, per-cell Kalman part.

    Parameters
    ----------
    accel_table : (L, A) float
        Mean acceleration per reference sample and reference sample^2 (``mu``).
    Q : (2A, 2A) float
        Process noise of ``[angles, velocities]`` per frame.
    R : (A, A) float or float
        Measurement noise covariance (a float: ``R * I``).
    x0 : (2A,) float, P0 : (2A, 2A) float
        Initial Kalman mean and covariance.
    phase, speed : (N,) float
        Initial particles (cycles, cycles per frame).
    temporal_sigma : float
        Random-acceleration noise of the cycle state, cycles per frame^2.
    circular : (A,) bool, optional
        Which angles wrap (innovations and merges); default all.
    resample_threshold : float
        Resample when the effective sample size falls below this fraction of N.
    rng : numpy Generator

    Attributes
    ----------
    X : (L, 2A) float64
        Kalman mean of each phase cell.
    P : (2A, 2A) float64
        Shared Kalman covariance (posterior after :meth:`step`).
    phase, speed : (N,) float32
    log_w : (N,) float64
        Normalised log-weights.
    """

    def __init__(self, accel_table, Q, R, x0, P0, phase, speed, temporal_sigma: float = 0.0,
                 circular=None, resample_threshold: float = 0.5, rng=None, min_speed: float = 0.0):
        mu = np.asarray(accel_table, dtype=float)
        self.L, self.A = mu.shape
        A, D = self.A, 2 * self.A
        self.mu = mu
        self.Q = np.asarray(Q, dtype=float)
        R = np.asarray(R, dtype=float)
        self.R = R * np.eye(A) if R.ndim == 0 else R
        self.F = np.block([[np.eye(A), np.eye(A)], [np.zeros((A, A)), np.eye(A)]])
        self.Bmu = np.concatenate([0.5 * mu, mu], axis=1)          # (L, D): B mu per cell
        self.X = np.tile(np.asarray(x0, dtype=float), (self.L, 1))
        self.P = np.asarray(P0, dtype=float).copy()
        self.phase = np.asarray(phase, dtype=np.float32).copy()
        self.speed = np.asarray(speed, dtype=np.float32).copy()
        self.log_w = np.full(len(self.phase), -np.log(len(self.phase)))
        self.sigma_t = float(temporal_sigma)
        self.circular = np.ones(A, bool) if circular is None else np.asarray(circular, bool)
        self.threshold = float(resample_threshold)
        self.rng = np.random.default_rng() if rng is None else rng
        self.min_speed = np.float32(min_speed)
        self.ess = float(len(self.phase))
        self.resampled = False
        self.map_x = self.X[0].copy()
        self.mean_x = self.X[0].copy()
        self.map_phase = float(self.phase[0])
        self.map_speed = float(self.speed[0])
        self.P_prior = self.P.copy()
        self.x_prior_mean = self.mean_x.copy()

    @property
    def n(self) -> int:
        return len(self.phase)

    def cells(self, phase=None):
        """(N,) int phase cell ``floor(c L)`` of each particle."""
        c = self.phase if phase is None else phase
        idx = (c * np.float32(self.L)).astype(np.intp)
        return np.clip(idx, 0, self.L - 1, out=idx)

    def _wrap_angles(self, d):
        A = self.A
        d[..., :A] = np.where(self.circular, wrap(d[..., :A]), d[..., :A])
        return d

    def step(self, z=None):
        """One frame: weigh by ``z (A,)`` (or only predict when ``z`` is None), merge, move the cycle state.

        Returns the posterior mean of ``[angles, velocities]`` (2A,).
        """
        A, L = self.A, self.L
        cell = self.cells()
        s = (self.speed * np.float32(L)) ** 2                         # (N,) acceleration scale 1/k^2
        FX = self.X @ self.F.T                                        # (L, D)
        P_pred = self.F @ self.P @ self.F.T + self.Q
        self.P_prior = P_pred
        if z is None:
            alpha, beta = FX, self.Bmu                               # prediction = alpha + s beta
            lw = self.log_w
            self.P = P_pred
        else:
            z = np.asarray(z, dtype=float)
            S = P_pred[:A, :A] + self.R
            K = np.linalg.solve(S, P_pred[:A]).T                      # (D, A): P H^T S^-1
            W = np.linalg.inv(S)
            # innovation of a particle: a[cell] - s b[cell]
            a = z - FX[:, :A]
            a = np.where(self.circular, wrap(a), a)                   # z taken next to each cell's prediction
            b = self.Bmu[:, :A]
            aW = a @ W
            aa = np.einsum("ij,ij->i", aW, a)
            ab = np.einsum("ij,ij->i", aW, b)
            bb = np.einsum("ij,ij->i", b @ W, b)
            tab = np.stack([aa, ab, bb]).astype(np.float32)           # (3, L)
            sc = s.astype(np.float32)
            ll = tab[0][cell] - 2 * sc * tab[1][cell] + sc * sc * tab[2][cell]
            lw = self.log_w + (-0.5 * ll).astype(np.float64)
            # posterior mean = prediction + K (a - s b): alpha + s beta
            IKH = np.eye(2 * A)
            IKH[:, :A] -= K                                           # I - K H with H = [I, 0]
            alpha = FX + a @ K.T
            beta = self.Bmu @ IKH.T
            self.P = IKH @ P_pred
            self.P = 0.5 * (self.P + self.P.T)
        if z is not None:
            top = lw.max()
            w = np.exp(lw - top)
            total = w.sum()
            w /= total
            lw = lw - (top + np.log(total))
        else:
            w = np.exp(lw)
        # every cell's angles next to one reference (the measurement, else the last estimate)
        ref = self.mean_x[:A] if z is None else z
        alpha = alpha.copy()
        alpha[:, :A] = ref + np.where(self.circular, wrap(alpha[:, :A] - ref), alpha[:, :A] - ref)
        # estimates: weighted mean and the best particle
        W0 = np.bincount(cell, weights=w, minlength=L)
        W1 = np.bincount(cell, weights=w * s, minlength=L)
        self.mean_x = (W0 @ alpha + W1 @ beta) / max(W0.sum(), 1e-300)
        best = int(np.argmax(lw))
        self.map_x = alpha[cell[best]] + s[best] * beta[cell[best]]
        self.map_phase, self.map_speed = float(self.phase[best]), float(self.speed[best])
        self.ess = effective_sample_size(w)
        # resample (adaptively), then move the cycle state
        self.resampled = z is not None and self.ess < self.threshold * self.n
        if self.resampled:
            idx = low_variance_resample(w, self.rng)
            cell, s = cell[idx], s[idx]
            self.phase, self.speed = self.phase[idx], self.speed[idx]
            w = np.full(self.n, 1.0 / self.n)
            lw = np.log(w)
        self.log_w = lw
        self._move()
        new_cell = self.cells()
        # collapse: weighted mean of the particles' Kalman means per new cell
        key = new_cell * L + cell
        M0 = np.bincount(key, weights=w, minlength=L * L).reshape(L, L)
        M1 = np.bincount(key, weights=w * s, minlength=L * L).reshape(L, L)
        tot = M0.sum(axis=1)
        merged = M0 @ alpha + M1 @ beta
        live = tot > 0
        self.X[live] = merged[live] / tot[live, None]
        return self.mean_x

    def _move(self):
        """The thesis's temporal model: ``c += v + a_t / 2``, ``v += a_t``, ``a_t ~ N(0, sigma_t^2)``."""
        if self.sigma_t > 0:
            at = np.float32(self.sigma_t) * table_normals(self.rng, self.n)
            self.phase += self.speed + np.float32(0.5) * at
            self.speed += at
        else:
            self.phase += self.speed
        self.phase -= np.floor(self.phase)
        np.maximum(self.speed, self.min_speed, out=self.speed)
