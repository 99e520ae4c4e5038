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
from .particle import low_variance_resample


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
    log_w : (N,) float32
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
        self.log_w = np.full(len(self.phase), -np.log(len(self.phase)), np.float32)
        self._cell = None
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
        idx = (c * np.float32(self.L)).astype(np.int32)
        return np.minimum(idx, self.L - 1, out=idx)

    def step(self, z=None):
        """One frame: weigh by ``z (A,)`` (or only predict when ``z`` is None), merge, move the cycle state.

        Returns the posterior mean of ``[angles, velocities]`` (2A,).
        """
        A, L = self.A, self.L
        cell = self._cell if self._cell is not None else self.cells()
        s = self.speed * np.float32(L)
        s *= s                                                        # (N,) acceleration scale 1/k^2
        FX = self.X @ self.F.T                                        # (L, D)
        P_pred = self.F @ self.P @ self.F.T + self.Q
        self.P_prior = P_pred
        if z is None:
            alpha, beta = FX, self.Bmu                               # prediction = alpha + s beta
            lw = self.log_w
            w = np.exp(lw)
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
            tab = np.stack([-0.5 * np.einsum("ij,ij->i", aW, a), np.einsum("ij,ij->i", aW, b),
                            -0.5 * np.einsum("ij,ij->i", b @ W, b)]).astype(np.float32)   # (3, L)
            # log-likelihood -(aa - 2 s ab + s^2 bb) / 2, as t0 + s (t1 + s t2)
            ll = np.take(tab[2], cell)
            ll *= s
            ll += np.take(tab[1], cell)
            ll *= s
            ll += np.take(tab[0], cell)
            lw = ll
            lw += self.log_w
            lw -= lw.max()
            w = np.exp(lw)
            total = w.sum(dtype=np.float64)
            w *= np.float32(1.0 / total)
            lw -= np.float32(np.log(total))
            # posterior mean = prediction + K (a - s b): alpha + s beta
            IKH = np.eye(2 * A)
            IKH[:, :A] -= K                                           # I - K H with H = [I, 0]
            alpha = FX + a @ K.T
            beta = self.Bmu @ IKH.T
            self.P = IKH @ P_pred
            self.P = 0.5 * (self.P + self.P.T)
        # every cell's angles next to one reference (the measurement, else the last estimate)
        ref = self.mean_x[:A] if z is None else z
        alpha = alpha.copy()
        alpha[:, :A] = ref + np.where(self.circular, wrap(alpha[:, :A] - ref), alpha[:, :A] - ref)
        best = int(np.argmax(lw))
        self.map_x = alpha[cell[best]] + float(s[best]) * beta[cell[best]]
        self.map_phase, self.map_speed = float(self.phase[best]), float(self.speed[best])
        self.ess = float(1.0 / np.einsum("i,i->", w, w, dtype=np.float64))
        ws = w * s
        # resample (adaptively), then move the cycle state
        self.resampled = z is not None and self.ess < self.threshold * self.n
        if self.resampled:
            # the estimate from the weighted set, before resampling adds noise
            W0 = np.bincount(cell, weights=w, minlength=L)
            W1 = np.bincount(cell, weights=ws, minlength=L)
            self.mean_x = (W0 @ alpha + W1 @ beta) / W0.sum()
            idx = low_variance_resample(w, self.rng)
            cell, s = cell[idx], s[idx]
            self.phase, self.speed = self.phase[idx], self.speed[idx]
            w = np.full(self.n, 1.0 / self.n, np.float32)
            ws = w * s
            lw = np.full(self.n, -np.log(self.n), np.float32)
        self.log_w = lw
        self._move()
        new_cell = self._cell = self.cells()
        # collapse: weighted mean of the particles' Kalman means per new cell
        key = new_cell * np.int32(L)
        key += cell
        M0 = np.bincount(key, weights=w, minlength=L * L).reshape(L, L)
        M1 = np.bincount(key, weights=ws, minlength=L * L).reshape(L, L)
        if not self.resampled:
            self.mean_x = (M0.sum(axis=0) @ alpha + M1.sum(axis=0) @ beta) / M0.sum()
        tot = M0.sum(axis=1)
        merged = M0 @ alpha + M1 @ beta
        live = tot > 0
        self.X[live] = merged[live] / tot[live, None]
        return self.mean_x

    def _move(self):
        """The thesis's temporal model: ``c += v + a_t / 2``, ``v += a_t``, ``a_t ~ N(0, sigma_t^2)``."""
        if self.sigma_t > 0:
            at = np.float32(self.sigma_t) * table_normals(self.rng, self.n)
            self.speed += at
            np.maximum(self.speed, self.min_speed, out=self.speed)
            at *= np.float32(0.5)
            self.phase += self.speed
            self.phase -= at
        else:
            self.phase += self.speed
        self.phase -= np.floor(self.phase)
