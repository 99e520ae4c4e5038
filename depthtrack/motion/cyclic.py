"""The learned cyclic motion model of the swimmer thesis (chapter 4).

State per hypothesis (thesis Figure 4.2, position dropped as in 4.3):

* ``angles`` (A,) — the configuration (26 stick-figure angles), rad;
* ``velocities`` (A,) — angular velocities, rad per frame;
* ``phase`` c in [0, 1) — progress through the reference cycle;
* ``speed`` v — cycles per frame (the reference speed is ``v_ref = 1 / L``).

Transition (equations 4.12, 4.14, 4.19 with dt in frames)::

    a     ~ N(mu_c, Sigma_c) / k^2,  k = v_ref / v       (4.11, 4.16)
    angle = angle + vel dt + a dt^2 / 2
    vel   = vel + a dt
    a_t   ~ N(0, sigma_t^2)                               (4.13)
    c     = c + v dt + a_t dt^2 / 2   (mod 1)
    v     = v + a_t dt

which is the thesis's ``N(K mu, K Sigma K^T)`` angular noise with
``K = (dt^2 / 2, dt)`` and ``L sigma_t^2 L^T`` temporal noise. ``mu_c`` and
``Sigma_c`` are the mean and covariance of the n training cycles' accelerations
at reference sample ``floor(c L)``; ``Sigma_c`` has rank <= n - 1, so a draw is
``mu_c + basis_c^T z`` with ``z ~ N(0, I_n)`` and
``basis_c = (a_c - mu_c) / sqrt(n - 1)`` — exact, and n normals per particle
instead of A.

Particles are a dict of float32 arrays (structure of arrays) and are moved in
place, in chunks of rows that stay in cache, on a few threads (numpy releases
the GIL); each chunk has its own random stream, so results do not depend on the
thread count.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from threadpoolctl import threadpool_limits

from ..filters.angles import wrap, wrap_inplace
from ..filters.chunks import run_chunked
from ..filters.fastrandom import table_normals

PARTICLE_KEYS = ("angles", "velocities", "phase", "speed")


@dataclass
class CyclicMotionModel:
    """Cyclic motion model learned from training cycles of common length L.

    Parameters
    ----------
    mean_angles : (L, A) float
        Mean pose at each reference sample (for initialisation and plots).
    mean_velocities : (L, A) float
        Mean angular velocity per reference sample.
    accelerations : (n, L, A) float
        Training accelerations per reference sample^2 (all cycles in one representation).
    temporal_sigma : float
        Standard deviation of the temporal acceleration a_t, cycles per frame^2.
    dt : float
        Time step in frames (1).
    jitter : float
        Extra isotropic acceleration noise ("roughening"), rad per reference sample^2,
        scaled by 1/k^2 like the learned noise (0 = the thesis's model). Particles
        draw it as random rows of a fresh bank of ``jitter_bank`` Gaussian vectors per step.
    circular : (A,) bool, optional
        Which state angles wrap (all by default).
    """

    mean_angles: np.ndarray
    mean_velocities: np.ndarray
    accelerations: np.ndarray
    temporal_sigma: float = 2e-5
    dt: float = 1.0
    jitter: float = 0.0
    circular: np.ndarray | None = None
    threads: int = 1
    chunk: int = 16384
    jitter_bank: int = 65536
    _cache: dict = field(default_factory=dict, repr=False)

    def __post_init__(self):
        self.mean_angles = np.asarray(self.mean_angles, dtype=float)
        self.mean_velocities = np.asarray(self.mean_velocities, dtype=float)
        self.accelerations = np.asarray(self.accelerations, dtype=float)
        if self.accelerations.ndim != 3 or self.accelerations.shape[1:] != self.mean_angles.shape:
            raise ValueError("accelerations must be (n, L, A) matching mean_angles (L, A)")
        if self.circular is None:
            self.circular = np.ones(self.n_angles, dtype=bool)

    # ------------------------------------------------------------------ sizes
    @property
    def length(self) -> int:
        return self.mean_angles.shape[0]

    @property
    def n_angles(self) -> int:
        return self.mean_angles.shape[1]

    @property
    def n_cycles(self) -> int:
        return self.accelerations.shape[0]

    @property
    def dim(self) -> int:
        """Length of the state vector ``[angles, velocities, phase, speed]``."""
        return 2 * self.n_angles + 2

    @property
    def v_ref(self) -> float:
        return 1.0 / self.length

    @property
    def mean_acceleration(self) -> np.ndarray:
        """(L, A) mean training acceleration mu_c."""
        return self.accelerations.mean(axis=0)

    @property
    def acceleration_basis(self) -> np.ndarray:
        """(L, n, A): ``(a_c - mu_c) / sqrt(n - 1)``; ``basis^T basis`` is the covariance Sigma_c."""
        n = self.n_cycles
        dev = self.accelerations - self.mean_acceleration
        if n < 2:
            return np.zeros((self.length, 1, self.n_angles))
        return np.transpose(dev, (1, 0, 2)) / np.sqrt(n - 1)

    def acceleration_covariance(self, index: int) -> np.ndarray:
        """(A, A) Sigma_c at reference sample ``index`` (plus jitter^2 I)."""
        b = self.acceleration_basis[index]
        return b.T @ b + self.jitter ** 2 * np.eye(self.n_angles)

    def _tables32(self):
        if "tables" not in self._cache:
            basis = self.acceleration_basis
            self._cache["tables"] = (
                np.ascontiguousarray(self.mean_acceleration, dtype=np.float32),
                [np.ascontiguousarray(basis[:, j], dtype=np.float32) for j in range(basis.shape[1])],
            )
        return self._cache["tables"]

    # ------------------------------------------------------------ lookups
    def index(self, phase):
        """Reference sample ``floor(c L) mod L`` of ``phase (...,)`` -> int array."""
        idx = np.floor(np.asarray(phase, dtype=float) * self.length).astype(np.intp)
        return np.mod(idx, self.length)

    def acceleration_scale(self, speed):
        """``1 / k^2 = (v / v_ref)^2`` for ``speed (...,)``."""
        return (np.asarray(speed) * self.length) ** 2

    def interpolated(self, table, phase):
        """Periodic linear interpolation of ``table (L, ...)`` at ``phase`` (scalar)."""
        u = (float(phase) % 1.0) * self.length
        i = int(np.floor(u)) % self.length
        w = u - np.floor(u)
        return (1 - w) * table[i] + w * table[(i + 1) % self.length]

    def interpolated_rows(self, table, phase):
        """Periodic linear interpolation of ``table (L, A)`` at every ``phase (K,)`` -> ``(K, A)``."""
        u = np.mod(np.asarray(phase, dtype=float), 1.0) * self.length
        i = np.floor(u).astype(int) % self.length
        w = (u - np.floor(u))[:, None]
        return (1 - w) * table[i] + w * table[(i + 1) % self.length]

    # ------------------------------------------------------------ particles
    def propagate(self, particles: dict, rng: np.random.Generator, threads: int | None = None,
                  ancestors=None, out: dict | None = None, score=None):
        """Sample the transition for every particle (thesis 6.1).

        Parameters
        ----------
        particles : dict
            ``angles (N, A)``, ``velocities (N, A)``, ``phase (N,)``, ``speed (N,)`` float32.
        rng : numpy Generator
            Seeds the per-chunk streams.
        ancestors : (N,) int, optional
            Resampling indices: new particle i starts from ``particles[ancestors[i]]``
            (the gather is done chunk by chunk, in cache). Without it particles move in place.
        out : dict, optional
            Buffers for the result when ``ancestors`` is given (same shapes as ``particles``).

        score : (z (A,), sigma), optional
            Also evaluate the thesis's Gaussian measurement model in the same pass.

        Returns
        -------
        dict of the new particles; with ``score`` also their log-likelihoods (N,) float32
        ``-|wrap(angles - z)|^2 / (2 sigma^2)``.

        Notes
        -----
        Where the rows of a chunk are ordered by reference sample (the particle
        filter orders its resampled particles so, see ``order_key``), the
        accelerations of each run of equal samples are one small matrix product
        ``z @ basis_c``; otherwise a gather per basis vector. The transition
        noise uses :func:`depthtrack.filters.fastrandom.table_normals`.
        """
        mean32, basis32 = self._tables32()
        stacked = self._stacked_basis32()
        n = len(particles["phase"])
        if ancestors is None:
            src, dst = particles, particles
        else:
            src = particles
            dst = out if out is not None else {k: np.empty_like(v) for k, v in particles.items()}
        L = self.length
        n_basis = len(basis32)
        dt = np.float32(self.dt)
        half_dt2 = np.float32(0.5 * self.dt ** 2)
        sigma_t = np.float32(self.temporal_sigma)
        jitter = np.float32(self.jitter)
        min_speed = np.float32(0.05 * self.v_ref)
        wrap_mask = None if self.circular.all() else np.asarray(self.circular)
        has_noise = self.n_cycles > 1
        base = int(rng.integers(2 ** 63))
        if score is not None:
            z_meas = np.asarray(score[0], dtype=np.float32)
            ll_scale = np.float32(-0.5 / float(score[1]) ** 2)
            loglik = np.empty(n, np.float32)
        # Isotropic jitter ("roughening"): each particle takes a random row of a fresh
        # bank of Gaussian vectors, 1 random integer instead of A normals per particle.
        bank = None
        if jitter > 0:
            bank = jitter * table_normals(rng, (min(self.jitter_bank, max(n, 1)), self.n_angles))

        def work(a, b, i):
            g = np.random.default_rng([base, i])
            m = b - a
            if ancestors is None:
                ang, vv = dst["angles"][a:b], dst["velocities"][a:b]
                c, v = dst["phase"][a:b], dst["speed"][a:b]
            else:
                rows = ancestors[a:b]
                ang = np.take(src["angles"], rows, axis=0, out=dst["angles"][a:b])
                vv = np.take(src["velocities"], rows, axis=0, out=dst["velocities"][a:b])
                c = np.take(src["phase"], rows, out=dst["phase"][a:b])
                v = np.take(src["speed"], rows, out=dst["speed"][a:b])
            idx = (c * np.float32(L)).astype(np.intp)
            np.clip(idx, 0, L - 1, out=idx)
            if has_noise:
                z = table_normals(g, (m, n_basis))
                cuts = np.flatnonzero(idx[1:] != idx[:-1]) + 1
                if np.all(idx[cuts] > idx[cuts - 1]) and len(cuts) < m // 8 + 1:
                    acc = np.empty((m, ang.shape[1]), np.float32)
                    edges = np.concatenate([[0], cuts, [m]])
                    for lo, hi in zip(edges[:-1], edges[1:]):
                        k = idx[lo]
                        np.matmul(z[lo:hi], stacked[k], out=acc[lo:hi])
                        acc[lo:hi] += mean32[k]
                else:
                    acc = np.take(mean32, idx, axis=0)
                    for j, table in enumerate(basis32):
                        acc += z[:, j:j + 1] * np.take(table, idx, axis=0)
            else:
                acc = np.take(mean32, idx, axis=0)
            if bank is not None:
                acc += np.take(bank, g.integers(0, len(bank), m), axis=0)
            scale = v * np.float32(L)
            scale *= scale
            acc *= scale[:, None]
            ang += dt * vv if dt != 1 else vv
            ang += half_dt2 * acc
            vv += dt * acc if dt != 1 else acc
            if score is None:
                if wrap_mask is None:
                    wrap_inplace(ang)
                else:
                    ang[:, wrap_mask] = wrap(ang[:, wrap_mask])
            at = sigma_t * table_normals(g, m)
            c += dt * v + half_dt2 * at
            c -= np.floor(c)
            v += dt * at
            np.maximum(v, min_speed, out=v)
            if score is not None:
                d = ang - z_meas
                if wrap_mask is None:
                    wrap_inplace(d)
                else:
                    d[:, wrap_mask] = wrap(d[:, wrap_mask])
                loglik[a:b] = np.einsum("ij,ij->i", d, d) * ll_scale
                np.add(z_meas, d, out=ang)      # wrapped into [z - pi, z + pi): one add, not a wrap

        # The runs' matrix products are tiny: OpenBLAS's own threads only add wake-up cost.
        with threadpool_limits(1, user_api="blas"):
            run_chunked(n, work, self.chunk, self.threads if threads is None else threads)
        return dst if score is None else (dst, loglik)

    def order_key(self, particles: dict):
        """(N,) reference sample of each particle: the particle filter sorts resampled
        particles by it so :meth:`propagate` can use one matrix product per run."""
        idx = (particles["phase"] * np.float32(self.length)).astype(np.int16)
        return np.clip(idx, 0, self.length - 1, out=idx)

    def _stacked_basis32(self):
        if "stacked" not in self._cache:
            self._cache["stacked"] = np.ascontiguousarray(self.acceleration_basis, dtype=np.float32)
        return self._cache["stacked"]

    def particles_at(self, n: int, angles, velocities, phase, speed, rng=None, angle_spread=0.0,
                     velocity_spread=0.0, phase_spread=0.0, speed_spread=0.0) -> dict:
        """``n`` float32 particles around one state (spreads are Gaussian standard deviations;
        ``speed_spread`` is relative)."""
        rng = np.random.default_rng() if rng is None else rng
        A = self.n_angles
        out = {
            "angles": np.empty((n, A), np.float32), "velocities": np.empty((n, A), np.float32),
            "phase": np.empty(n, np.float32), "speed": np.empty(n, np.float32),
        }
        out["angles"][:] = np.asarray(angles, np.float32)
        out["velocities"][:] = np.asarray(velocities, np.float32)
        out["phase"][:] = np.float32(phase)
        out["speed"][:] = np.float32(speed)
        if angle_spread:
            out["angles"] += np.float32(angle_spread) * table_normals(rng, (n, A))
        if velocity_spread:
            out["velocities"] += np.float32(velocity_spread) * table_normals(rng, (n, A))
        if phase_spread:
            out["phase"] += np.float32(phase_spread) * rng.standard_normal(n, dtype=np.float32)
        if speed_spread:
            out["speed"] *= 1 + np.float32(speed_spread) * rng.standard_normal(n, dtype=np.float32)
        out["phase"] -= np.floor(out["phase"])
        wrap_inplace(out["angles"])
        np.maximum(out["speed"], np.float32(0.05 * self.v_ref), out=out["speed"])
        return out

    def random_particles(self, n: int, rng=None, speed_range=(0.5, 2.0), velocity_scale=0.0,
                         angle_low=None, angle_high=None) -> dict:
        """``n`` particles spread over the state space (thesis 7.3.2's random initialisation).

        Angles uniform in ``[angle_low, angle_high)`` (default ``[-pi, pi)``), angular
        velocities ``N(0, velocity_scale^2)``, phase uniform in [0, 1), speed uniform in
        ``speed_range`` times ``v_ref``.
        """
        rng = np.random.default_rng() if rng is None else rng
        A = self.n_angles
        low = -np.pi if angle_low is None else np.asarray(angle_low)
        high = np.pi if angle_high is None else np.asarray(angle_high)
        ang = (low + (high - low) * rng.random((n, A))).astype(np.float32)
        vel = (velocity_scale * rng.standard_normal((n, A))).astype(np.float32)
        return {
            "angles": ang, "velocities": vel,
            "phase": rng.random(n).astype(np.float32),
            "speed": (self.v_ref * rng.uniform(*speed_range, n)).astype(np.float32),
        }

    # ------------------------------------------------------------ vector form (UKF)
    def split(self, x):
        """``x (..., 2A + 2)`` -> angles, velocities, phase, speed views."""
        A = self.n_angles
        return x[..., :A], x[..., A:2 * A], x[..., 2 * A], x[..., 2 * A + 1]

    def transition(self, x):
        """Deterministic transition with the mean acceleration, for sigma points.

        ``x (K, 2A + 2)`` or ``(2A + 2,)`` -> same shape (float64). The mean
        acceleration is interpolated linearly between reference samples so the
        map is continuous in c.
        """
        x = np.array(x, dtype=float, copy=True)
        squeeze = x.ndim == 1
        x = np.atleast_2d(x)
        ang, vel, c, v = self.split(x)
        mu = self.mean_acceleration
        u = np.mod(c, 1.0) * self.length
        i0 = np.floor(u).astype(int) % self.length
        w = (u - np.floor(u))[:, None]
        acc = ((1 - w) * mu[i0] + w * mu[(i0 + 1) % self.length]) * self.acceleration_scale(v)[:, None]
        dt = self.dt
        ang += vel * dt + 0.5 * dt * dt * acc
        vel += acc * dt
        c += v * dt
        return x[0] if squeeze else x

    def process_noise(self, x) -> np.ndarray:
        """(2A + 2, 2A + 2) covariance of the transition noise at state ``x``.

        ``K Sigma_c K^T / k^4`` for angles and velocities, ``L sigma_t^2 L^T`` for
        phase and speed (equations 4.17, 4.18, 4.20).
        """
        A = self.n_angles
        _, _, c, v = self.split(np.asarray(x, dtype=float))
        b = self.interpolated(self.acceleration_basis, c)
        sigma = (b.T @ b + self.jitter ** 2 * np.eye(A)) * float(self.acceleration_scale(v)) ** 2
        dt = self.dt
        K = np.array([0.5 * dt * dt, dt])
        Q = np.zeros((self.dim, self.dim))
        Q[:2 * A, :2 * A] = np.kron(np.outer(K, K), sigma)
        Q[2 * A:, 2 * A:] = np.outer(K, K) * self.temporal_sigma ** 2
        return Q

    def state_residual(self, a, b):
        """``a - b`` for state vectors with wrapped angles and phase: ``(..., D)``."""
        d = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
        A = self.n_angles
        d[..., :A] = np.where(self.circular, wrap(d[..., :A]), d[..., :A])
        d[..., 2 * A] = wrap(d[..., 2 * A], 1.0)
        return d

    def to_dict(self) -> dict:
        return {"mean_angles": self.mean_angles.tolist(), "mean_velocities": self.mean_velocities.tolist(),
                "accelerations": self.accelerations.tolist(), "temporal_sigma": self.temporal_sigma,
                "dt": self.dt, "jitter": self.jitter, "circular": np.asarray(self.circular).tolist()}

    @classmethod
    def from_dict(cls, d: dict) -> "CyclicMotionModel":
        return cls(np.array(d["mean_angles"]), np.array(d["mean_velocities"]), np.array(d["accelerations"]),
                   float(d["temporal_sigma"]), float(d.get("dt", 1.0)), float(d.get("jitter", 0.0)),
                   np.array(d.get("circular")) if d.get("circular") is not None else None)
