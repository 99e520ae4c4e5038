"""Rao-Blackwellised particle filter for a cyclic motion model (Doucet, de Freitas, Murphy & Russell 2000).

The state splits into a low-dimensional non-linear part, the cycle state
``s = (c, v)`` (progress and speed), and a high-dimensional part that is
linear-Gaussian given it, the angles and angular velocities ``x = [theta, omega]``
(D = 2A). The linear part is the *deviation* from the mean cycle: with
``g(s) = [m(c), d(c) v L]`` (mean pose and mean velocity of the training cycles
at progress c, velocity per frame at speed v),

    x_t = g(s_t) + Phi (x_{t-1} - g(s_{t-1})) + w,   w ~ N(0, Q),   Phi = rho [[I, I], [0, I]]
    z_t = H x_t + n,                                 n ~ N(0, R),   H = [I, 0]

i.e. the deviation moves at constant velocity and decays by ``rho`` per frame
(rho = 1: no decay; then ``m(c_t) - m(c_{t-1}) - d v L`` is the thesis's
``a dt^2 / 2`` and the model is the thesis's mean motion). The cycle state
follows the thesis's temporal model (``c += v + a_t / 2``, ``v += a_t``).

Particles carry only ``s``; ``x`` is marginalised with a Kalman filter
(Rao-Blackwellisation, Doucet et al. 2000, "Rao-Blackwellised particle
filtering for dynamic Bayesian networks", UAI). The particles move first (the
prior proposal for ``s``, a 2-D state that does not starve) and are weighted by
the Kalman predictive likelihood ``N(z_t; H x_pred, S)``, which carries the
measurement's information on all 52 linear dimensions exactly.

Two choices make a million particles cheap (numpy, no compiled code):

* ``Q`` and ``R`` do not depend on ``s``: the Kalman covariance, gain and
  innovation covariance are shared (one 52-dim Riccati step per frame).
* The Kalman means are *collapsed per phase cell* (``cells`` cells of the cycle):
  after every step the means of the particles in the same cell are merged
  (their weighted average), as in GPB1/IMM merging for switching Kalman
  filters (Blom & Bar-Shalom 1988). A particle's innovation is then
  ``P[new] - Q[old] + v_old B[old]`` with per-cell vectors, its log-likelihood a
  quadratic in ``v_old`` whose coefficients are per (new cell, old cell) pair
  tables (``cells^2`` entries, from ``cells x A`` matrix products): three table
  look-ups per particle, no per-particle 52-vector. The merge is three
  ``bincount`` calls and ``(cells, cells) @ (cells, D)`` products.

Without the collapse this would be the exact RBPF; the particles keep exact
weights for their step and the phase/speed posterior, the angles given the
cell are the merged Kalman means. With ``m = d = 0`` every cell holds the same
mean and the filter is exactly the Kalman filter (tested).

Measurements may be missing (``None``: occlusion): the filter then predicts.
"""
from __future__ import annotations

import numpy as np

from .angles import wrap
from .fastrandom import table_normals
from .particle import low_variance_resample


def periodic_interp(table, phase):
    """``table (L, A)`` sampled at progress ``i / L``, linearly interpolated at ``phase (...,)``
    (periodic; differences wrapped, so angle tables may cross +-pi) -> ``(..., A)``."""
    table = np.asarray(table, dtype=float)
    L = len(table)
    u = np.mod(np.asarray(phase, dtype=float), 1.0) * L
    i = np.floor(u).astype(int) % L
    w = (u - np.floor(u))[..., None]
    return table[i] + w * wrap(table[(i + 1) % L] - table[i])


def periodic_table(table, cells: int):
    """``table (L, A)`` at the centres ``(j + 1/2) / cells`` of ``cells`` phase cells -> ``(cells, A)``."""
    return periodic_interp(table, (np.arange(cells) + 0.5) / cells)


class CycleRBPF:
    """Rao-Blackwellised particle filter over ``(c, v)`` with a shared, per-cell Kalman part.

    Parameters
    ----------
    mean_angles, mean_velocities : (L, A) float
        Mean pose ``m`` and mean angular velocity ``d`` (rad per reference sample) per reference sample.
    Q : (2A, 2A) float
        Process noise of ``[angles, velocities]`` per frame.
    R : (A, A) float or float
        Measurement noise covariance (a float: ``R * I``).
    x0 : (2A,) float, P0 : (2A, 2A) float
        Initial Kalman mean (next to the first measurement) and covariance.
    phase, speed : (N,) float
        Initial particles (cycles, cycles per frame).
    rho : float
        Decay of the deviation from the mean cycle per frame.
    temporal_sigma : float
        Random-acceleration noise of the cycle state, cycles per frame^2.
    cells : int
        Phase cells of the collapse (default 4 L).
    circular : (A,) bool, optional
        Which angles wrap; default all.
    resample_threshold : float
        Resample when the effective sample size falls below this fraction of N.
    align : callable(table (C, A), reference (A,)) -> (aligned (C, A), sign (C, A)), optional
        Re-expresses the mean-cycle poses next to a reference (the measurement) where angles
        have several equivalent representations (the stick figure's ``(-theta, phi + pi)``);
        ``sign`` flips the matching velocities. Default: wrap each angle next to the reference.

    Attributes
    ----------
    X : (cells, 2A) float64 — Kalman mean of each cell; P : (2A, 2A) — shared covariance;
    phase, speed : (N,) float32; log_w : (N,) float32 normalised log-weights;
    mean_x, map_x : (2A,) estimates of the last step; ess : float.
    """

    def __init__(self, mean_angles, mean_velocities, Q, R, x0, P0, phase, speed, rho: float = 1.0,
                 temporal_sigma: float = 0.0, cells: int | None = None, circular=None,
                 resample_threshold: float = 0.5, rng=None, min_speed: float = 0.0, align=None):
        m = np.asarray(mean_angles, dtype=float)
        self.align = align
        self.L, self.A = m.shape
        A = self.A
        self.C = 4 * self.L if cells is None else int(cells)
        self.m = periodic_table(m, self.C)                              # (C, A) mean pose per cell
        self.d = periodic_table(np.asarray(mean_velocities, float), self.C) * self.L   # per unit speed
        self.rho = float(rho)
        self.Q = np.asarray(Q, dtype=float)
        R = np.asarray(R, dtype=float)
        self.R = R * np.eye(A) if R.ndim == 0 else R
        self.Phi = self.rho * np.block([[np.eye(A), np.eye(A)], [np.zeros((A, A)), np.eye(A)]])
        self.X = np.tile(np.asarray(x0, dtype=float), (self.C, 1))
        self.P = np.asarray(P0, dtype=float).copy()
        self.phase = np.asarray(phase, dtype=np.float32).copy()
        self.speed = np.asarray(speed, dtype=np.float32).copy()
        self.log_w = np.full(len(self.phase), -np.log(len(self.phase)), np.float32)
        self.sigma_t = float(temporal_sigma)
        self.circular = np.ones(A, bool) if circular is None else np.asarray(circular, bool)
        self.threshold = float(resample_threshold)
        self.rng = np.random.default_rng() if rng is None else rng
        self.min_speed = np.float32(min_speed)
        self.ess = float(len(self.phase))
        self.resampled = False
        self.mean_x = np.asarray(x0, dtype=float).copy()
        self.map_x = self.mean_x.copy()
        self.map_phase, self.map_speed = float(self.phase[0]), float(self.speed[0])
        self._cell = self.cells()

    @property
    def n(self) -> int:
        return len(self.phase)

    def cells(self):
        """(N,) int32 phase cell ``floor(c cells)`` of each particle."""
        idx = (self.phase * np.float32(self.C)).astype(np.int32)
        return np.minimum(idx, self.C - 1, out=idx)

    def _wrapped(self, d):
        return np.where(self.circular, wrap(d), d)

    def step(self, z=None):
        """One frame: move the cycle state, weigh by ``z (A,)`` (None: withheld, predict only), merge, resample.

        Returns the posterior mean of ``[angles, velocities]`` (2A,).
        """
        A, C, rho = self.A, self.C, self.rho
        old, v_old = self._cell, self.speed.copy()
        self._move()
        new = self._cell = self.cells()
        key = new * np.int32(C)
        key += old
        ref = self.mean_x[:A] if z is None else np.asarray(z, dtype=float)
        if self.align is None:
            mr, dr = ref + self._wrapped(self.m - ref), self.d       # mean cycle next to the reference
        else:
            mr, sign = self.align(self.m, ref)
            dr = self.d * sign
        # deviation of each cell's mean from the mean cycle (per unit old speed for the velocity part)
        E = self._wrapped(self.X[:, :A] - mr)
        Qo = rho * (E + self.X[:, A:])                 # angle prediction = m[new] + Qo[old] - v_old Bo[old]
        Bo = rho * dr
        Wo = rho * self.X[:, A:]                       # velocity prediction = d[new] v_new + Wo[old] - v_old Bo[old]
        P_pred = self.Phi @ self.P @ self.Phi.T + self.Q
        if z is None:
            lw = self.log_w
            w = np.exp(lw)
            Kt = Kw = np.zeros((A, A))
            Pn = np.zeros((C, A))
            self.P = P_pred
        else:
            S = P_pred[:A, :A] + self.R
            K = np.linalg.solve(S, P_pred[:A]).T                        # (D, A): P H^T S^-1
            Kt, Kw = K[:A], K[A:]
            W = np.linalg.inv(S)
            # innovation y = Pn[new] - Qo[old] + v_old Bo[old]
            Pn = ref - mr                                               # z - m[new], wrapped
            PW, QW, BW = Pn @ W, Qo @ W, Bo @ W
            pp = np.einsum("ij,ij->i", PW, Pn)
            qq = np.einsum("ij,ij->i", QW, Qo)
            bb = np.einsum("ij,ij->i", BW, Bo)
            qb = np.einsum("ij,ij->i", QW, Bo)
            G1 = PW @ Qo.T                                              # (new, old) <P, Q>
            G2 = PW @ Bo.T                                              # (new, old) <P, B>
            t0 = (-0.5 * (pp[:, None] + qq[None, :] - 2 * G1)).astype(np.float32).ravel()
            t1 = (qb[None, :] - G2).astype(np.float32).ravel()
            t2 = (-0.5 * bb).astype(np.float32)
            # log-likelihood t0 + v (t1 + v t2)
            ll = np.take(t2, old)
            ll *= v_old
            ll += np.take(t1, key)
            ll *= v_old
            ll += np.take(t0, key)
            ll += self.log_w
            ll -= ll.max()
            w = np.exp(ll)
            total = w.sum(dtype=np.float64)
            w *= np.float32(1.0 / total)
            ll -= np.float32(np.log(total))
            lw = ll
            IKH = np.eye(2 * A)
            IKH[:, :A] -= K
            self.P = IKH @ P_pred
            self.P = 0.5 * (self.P + self.P.T)
        # merge: weighted sums per new cell (pair sums over old cells)
        M0 = np.bincount(key, weights=w, minlength=C * C).reshape(C, C)
        M1 = np.bincount(key, weights=w * v_old, minlength=C * C).reshape(C, C)
        Vn = np.bincount(new, weights=w * self.speed, minlength=C)
        tot = M0.sum(axis=1)
        sy = tot[:, None] * Pn - M0 @ Qo + M1 @ Bo                      # sum of innovations
        s_pred_t = tot[:, None] * mr + M0 @ Qo - M1 @ Bo                # sum of predicted angles
        s_pred_w = Vn[:, None] * dr + M0 @ Wo - M1 @ Bo
        sum_t = s_pred_t + sy @ Kt.T
        sum_w = s_pred_w + sy @ Kw.T
        live = tot > 0
        self.X[live, :A] = sum_t[live] / tot[live, None]
        self.X[live, A:] = sum_w[live] / tot[live, None]
        self.mean_x = np.concatenate([sum_t.sum(0), sum_w.sum(0)]) / tot.sum()
        best = int(np.argmax(lw))
        nb, ob, vb, vn = new[best], old[best], float(v_old[best]), float(self.speed[best])
        y = Pn[nb] - Qo[ob] + vb * Bo[ob]
        self.map_x = np.concatenate([mr[nb] + Qo[ob] - vb * Bo[ob] + Kt @ y,
                                     vn * dr[nb] + Wo[ob] - vb * Bo[ob] + Kw @ y])
        self.map_phase, self.map_speed = float(self.phase[best]), vn
        self.ess = float(1.0 / np.einsum("i,i->", w, w, dtype=np.float64))
        self.resampled = z is not None and self.ess < self.threshold * self.n
        if self.resampled:
            idx = low_variance_resample(w, self.rng)
            self.phase, self.speed, self._cell = self.phase[idx], self.speed[idx], self._cell[idx]
            lw = np.full(self.n, -np.log(self.n), np.float32)
        self.log_w = lw
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
