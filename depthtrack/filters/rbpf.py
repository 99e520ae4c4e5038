"""Rao-Blackwellised particle filter for a cyclic motion model (Doucet, de Freitas, Murphy & Russell 2000).

The thesis's state splits into a low-dimensional non-linear part, the cycle
state ``s = (c, v)`` (progress and speed), and a high-dimensional part that is
linear-Gaussian given it, the angles and angular velocities ``x (D = 2A)``::

    theta_t = theta + rho omega + (1 - rho) d(c) r + mu(c) r^2 / 2
    omega_t = rho omega + (1 - rho) d(c) r + mu(c) r^2           (+ w ~ N(0, Q))
    z_t = theta_t + n,  n ~ N(0, R)

with ``r = v L`` (the speed relative to the reference cycle, so ``r^2 = 1/k^2``),
``mu`` and ``d`` the (L, A) tables of mean training acceleration and velocity at
``floor(c L)``, all of the previous frame. With ``rho = 1`` this is the thesis's
model (``a ~ mu / k^2``, equations 4.12-4.19, noise from the data); ``rho < 1``
lets the velocity's deviation from the mean stroke's velocity decay, so
predictions through a gap follow the mean stroke's motion instead of
extrapolating a velocity error (``rho`` is fitted on training frames,
:mod:`depthtrack.swim.tuning`).

Particles carry only ``s``; ``x`` is marginalised with a Kalman filter (Rao-Blackwellisation: Doucet et al. 2000,
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
  then ``X[cell]`` and its prediction ``F X[cell] + s B mu[cell] + r G d[cell]``
  is affine in the scalars ``r`` and ``s = r^2``, so its log-likelihood is a
  quadratic in ``(s, r)`` whose coefficients are per-cell tables (from
  ``a = z - H F X``, ``b = H B mu``, ``g = H G d`` in the ``S^-1`` norm): three
  table look-ups per particle (six when ``rho < 1``) and no per-particle
  52-vector. The merge is ``bincount`` calls over (new cell, old cell) pairs
  and ``(L, L) @ (L, D)`` products.

Without the collapse this is the exact RBPF; with it, the particles still carry
the exact weights of their current step and the phase/speed posterior; the
angles given the phase are the merged Kalman means. With ``mu = d = 0`` every
cell holds the same mean and the filter reduces exactly to the Kalman filter
(tested).

Measurements may be missing (``None``: occlusion): then the particles and the
Kalman part only predict, with ``gap_rho`` (a decay fitted for predicting many
frames ahead may differ from the best one-step model).
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
        Mean acceleration per reference sample^2 (``mu``).
    velocity_table : (L, A) float, optional
        Mean velocity per reference sample (``d``); needed when ``rho < 1``.
    rho : float or (A,) float
        Decay of the velocity's deviation from the mean stroke per frame (1: the thesis's model).
    gap_rho : float or (A,) float, optional
        The decay used on frames without a measurement (default ``rho``): a model fitted for
        predicting many frames ahead can differ from the best one-step model.
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
    input_sign : callable((L, A) angles) -> (L, A) of +-1, optional
        Sign of the mean-stroke input (``mu``, ``d``) for each cell's Kalman mean: angles with
        two representations of one pose (a swimmer's zenith/azimuth pairs) need the learned
        velocity and acceleration negated where the state is in the other branch than the
        tables (:func:`depthtrack.swim.stickfigure.zenith_sign`); default all +1.

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
                 circular=None, resample_threshold: float = 0.5, rng=None, min_speed: float = 0.0,
                 velocity_table=None, rho: float = 1.0, gap_rho=None, input_sign=None):
        mu = np.asarray(accel_table, dtype=float)
        self.L, self.A = mu.shape
        A, D = self.A, 2 * self.A
        self.mu = mu
        self.Q = np.asarray(Q, dtype=float)
        R = np.asarray(R, dtype=float)
        self.R = R * np.eye(A) if R.ndim == 0 else R
        self.Bmu = np.concatenate([0.5 * mu, mu], axis=1)          # (L, D): input per unit s = r^2
        self._d = np.zeros_like(mu) if velocity_table is None else np.asarray(velocity_table, dtype=float)
        self.gap_rho = np.broadcast_to(np.asarray(rho if gap_rho is None else gap_rho, float), (A,)).copy()
        self._rho_measured = np.broadcast_to(np.asarray(rho, float), (A,)).copy()
        self.input_sign = input_sign
        self.set_rho(self._rho_measured)
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

    def set_rho(self, rho):
        """Use velocity decay ``rho`` (scalar or (A,)) from now on (the transition ``F`` and the velocity input)."""
        A = self.A
        self.rho = np.broadcast_to(np.asarray(rho, float), (A,)).copy()
        R = np.diag(self.rho)
        self.F = np.block([[np.eye(A), R], [np.zeros((A, A)), R]])
        self._decays = bool(np.any(self.rho != 1.0))
        self.Gd = np.tile(1 - self.rho, 2) * np.concatenate([self._d, self._d], axis=1)   # (L, D): per unit r

    def _inputs(self):
        """Per-cell inputs ``(Bmu, Gd)`` (L, D), in each cell's branch when ``input_sign`` is given."""
        if self.input_sign is None:
            return self.Bmu, self.Gd
        sign = np.tile(np.asarray(self.input_sign(self.X[:, :self.A]), dtype=float), 2)
        return self.Bmu * sign, self.Gd * sign

    @property
    def n(self) -> int:
        return len(self.phase)

    def cells(self, phase=None):
        """(N,) intp phase cell ``floor(c L)`` of each particle."""
        c = self.phase if phase is None else phase
        # intp, not int32: take and bincount convert other index types first (twice the time)
        idx = (c * np.float32(self.L)).astype(np.intp)
        return np.minimum(idx, self.L - 1, out=idx)

    def step(self, z=None):
        """One frame: weigh by ``z (A,)`` (or only predict when ``z`` is None), merge, move the cycle state.

        Returns the posterior mean of ``[angles, velocities]`` (2A,).
        """
        A, L = self.A, self.L
        want = self.gap_rho if z is None else self._rho_measured
        if not np.array_equal(want, self.rho):
            self.set_rho(want)
        cell = self._cell if self._cell is not None else self.cells()
        r = self.speed * np.float32(L)                                # (N,) speed relative to the reference
        s = r * r                                                     # acceleration scale 1/k^2
        Bmu, Gd = self._inputs()
        FX = self.X @ self.F.T                                        # (L, D)
        P_pred = self.F @ self.P @ self.F.T + self.Q
        self.P_prior = P_pred
        if z is None:
            alpha, beta, gamma = FX, Bmu, Gd                         # prediction = alpha + s beta + r gamma
            lw = self.log_w
            w = np.exp(lw)
            self.P = P_pred
        else:
            z = np.asarray(z, dtype=float)
            S = P_pred[:A, :A] + self.R
            K = np.linalg.solve(S, P_pred[:A]).T                      # (D, A): P H^T S^-1
            W = np.linalg.inv(S)
            # innovation of a particle: a[cell] - s b[cell] - r g[cell]
            a = z - FX[:, :A]
            a = np.where(self.circular, wrap(a), a)                   # z taken next to each cell's prediction
            b, g = Bmu[:, :A], Gd[:, :A]
            aW, bW = a @ W, b @ W

            def dot(u, v):
                return np.einsum("ij,ij->i", u, v)

            # log-likelihood -|a - s b - r g|^2 / 2 = t0 + s (t1 + s t3 + r t4) + r (t2 + r t5)
            tab = np.stack([-0.5 * dot(aW, a), dot(aW, b), dot(aW, g), -0.5 * dot(bW, b), -dot(bW, g),
                            -0.5 * dot(g @ W, g)]).astype(np.float32)
            ll = np.take(tab[3], cell)
            ll *= s
            if self._decays:
                ll += r * np.take(tab[4], cell)
            ll += np.take(tab[1], cell)
            ll *= s
            if self._decays:
                lr = np.take(tab[5], cell)
                lr *= r
                lr += np.take(tab[2], cell)
                lr *= r
                ll += lr
            ll += np.take(tab[0], cell)
            lw = ll
            lw += self.log_w
            lw -= lw.max()
            w = np.exp(lw)
            total = w.sum(dtype=np.float64)
            w *= np.float32(1.0 / total)
            lw -= np.float32(np.log(total))
            # posterior mean = prediction + K (a - s b - r g): alpha + s beta + r gamma
            IKH = np.eye(2 * A)
            IKH[:, :A] -= K                                           # I - K H with H = [I, 0]
            alpha = FX + a @ K.T
            beta = Bmu @ IKH.T
            gamma = Gd @ IKH.T
            self.P = IKH @ P_pred
            self.P = 0.5 * (self.P + self.P.T)
        # every cell's angles next to one reference (the measurement, else the last estimate)
        ref = self.mean_x[:A] if z is None else z
        alpha = alpha.copy()
        alpha[:, :A] = ref + np.where(self.circular, wrap(alpha[:, :A] - ref), alpha[:, :A] - ref)
        best = int(np.argmax(lw))
        cb = cell[best]
        self.map_x = alpha[cb] + float(s[best]) * beta[cb] + float(r[best]) * gamma[cb]
        self.map_phase, self.map_speed = float(self.phase[best]), float(self.speed[best])
        self.ess = float(1.0 / np.einsum("i,i->", w, w, dtype=np.float64))
        # resample (adaptively), then move the cycle state
        self.resampled = z is not None and self.ess < self.threshold * self.n
        if self.resampled:
            # the estimate from the weighted set, before resampling adds noise
            W = [np.bincount(cell, weights=x, minlength=L) for x in (w, w * s, w * r)]
            self.mean_x = (W[0] @ alpha + W[1] @ beta + W[2] @ gamma) / W[0].sum()
            idx = low_variance_resample(w, self.rng)
            cell, s, r = cell[idx], s[idx], r[idx]
            self.phase, self.speed = self.phase[idx], self.speed[idx]
            w = np.full(self.n, 1.0 / self.n, np.float32)
            lw = np.full(self.n, -np.log(self.n), np.float32)
        self.log_w = lw
        self._move()
        new_cell = self._cell = self.cells()
        # collapse: weighted mean of the particles' Kalman means per new cell
        key = new_cell * L
        key += cell
        M0 = np.bincount(key, weights=w, minlength=L * L).reshape(L, L)
        M1 = np.bincount(key, weights=w * s, minlength=L * L).reshape(L, L)
        merged = M0 @ alpha + M1 @ beta
        if self._decays:
            M2 = np.bincount(key, weights=w * r, minlength=L * L).reshape(L, L)
            merged += M2 @ gamma
        if not self.resampled:
            self.mean_x = merged.sum(axis=0) / M0.sum()
        tot = M0.sum(axis=1)
        live = tot > 0
        self.X[live] = merged[live] / tot[live, None]
        return self.mean_x

    def cycle_mean(self):
        """Posterior mean ``(c, v)`` of the frame last stepped: the weighted mean of the particles'
        speeds, and of their phases unwrapped around the best particle's (the particles have already
        moved on by one frame, so their mean phase less their mean speed; the temporal noise has zero
        mean). O(N): for the occasional frame that needs it (a gap's start), not every step."""
        w = np.exp(self.log_w.astype(np.float64))
        w /= w.sum()
        v = float(w @ self.speed)
        d = self.phase.astype(np.float64) - (self.map_phase + self.map_speed)
        d -= np.round(d)
        c = self.map_phase + self.map_speed + float(w @ d) - v
        return c - np.floor(c), v

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
