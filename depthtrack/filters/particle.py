"""Particle filter with low-variance resampling, MAP and k-means estimates (thesis 3.4, 6, 7.3.1).

Particles are a dict of arrays sharing the first axis (N); the transition and the
measurement model are plugged in as functions:

* ``transition(particles, rng) -> particles`` samples p(x_t | x_{t-1}) (may work in place);
* ``log_likelihood(particles, z) -> (N,)`` gives log p(z | x) up to a constant.

Weights are handled in the log domain, so a sharp likelihood (small sigma) picks
the best particles instead of underflowing to uniform weights.
"""
from __future__ import annotations

import numpy as np
from threadpoolctl import threadpool_limits

from .angles import wrap
from .chunks import run_chunked


def normalise_log_weights(log_weights):
    """``log_weights (N,)`` -> normalised weights (N,) float64 (max-shifted exp)."""
    lw = np.asarray(log_weights, dtype=np.float64)
    finite = np.isfinite(lw)
    if not finite.any():
        return np.full(lw.shape, 1.0 / lw.size)
    w = np.exp(lw - lw[finite].max())
    w[~finite] = 0.0
    return w / w.sum()


def effective_sample_size(weights) -> float:
    """``1 / sum w^2`` of normalised ``weights (N,)``."""
    w = np.asarray(weights, dtype=np.float64)
    return float(1.0 / np.sum(w * w))


def low_variance_resample(weights, rng=None, offset=None):
    """Algorithm 3 (low-variance / systematic resampling).

    One random number ``r`` in [0, 1/M); the m-th draw takes the first particle
    whose cumulative weight reaches ``r + m / M``. Particle i is therefore drawn
    ``floor(M C_i - M r) - floor(M C_{i-1} - M r)`` times (``C`` the cumulative
    weights, up to ties), i.e. ``M w_i`` rounded up or down.

    Parameters
    ----------
    weights : (M,) float
        Normalised (they are renormalised defensively).
    rng : numpy Generator, optional
    offset : float, optional
        ``r`` itself, in [0, 1/M) (for tests).

    Returns
    -------
    (M,) intp ancestor indices, non-decreasing.
    """
    w = np.asarray(weights, dtype=np.float64)
    m = w.size
    cumulative = np.cumsum(w)
    cumulative /= cumulative[-1]
    if offset is None:
        rng = np.random.default_rng() if rng is None else rng
        offset = rng.random() / m
    # Draws u_m = offset + m / M, m = 0 .. M-1; particle i takes those with
    # C_{i-1} < u_m <= C_i, i.e. K_i - K_{i-1} of them with K_i = #{m : u_m <= C_i}.
    reached = np.floor((cumulative - offset) * m) + 1
    np.clip(reached, 0, m, out=reached)
    reached[-1] = m
    counts = np.diff(reached, prepend=0).astype(np.intp)
    return np.repeat(np.arange(m), counts)


def multinomial_resample(weights, rng=None):
    """Algorithm 2's plain resampling: M independent draws. ``(M,) -> (M,) intp``."""
    rng = np.random.default_rng() if rng is None else rng
    w = np.asarray(weights, dtype=np.float64)
    cumulative = np.cumsum(w)
    cumulative /= cumulative[-1]
    return np.minimum(np.searchsorted(cumulative, rng.random(w.size)), w.size - 1)


def gather_particles(particles: dict, indices, out: dict | None = None) -> dict:
    """Rows ``indices`` of every array of ``particles`` (into ``out``'s buffers when given)."""
    result = {}
    for key, value in particles.items():
        if out is not None and key in out and out[key].shape == value.shape:
            np.take(value, indices, axis=0, out=out[key])
            result[key] = out[key]
        else:
            result[key] = np.take(value, indices, axis=0)
    return result


def map_index(log_weights) -> int:
    """Index of the maximum a posteriori particle (highest weight before resampling)."""
    return int(np.argmax(log_weights))


def circular_embedding(angles, circular=True):
    """``angles (N, D)`` -> features where distances respect wrapping: ``(cos, sin)`` of circular
    columns (chord distance), the rest unchanged. ``(N, D + n_circular)`` float32."""
    angles = np.asarray(angles)
    mask = np.ones(angles.shape[1], bool) if circular is True else np.asarray(circular, bool)
    parts = [np.cos(angles[:, mask]), np.sin(angles[:, mask])]
    if (~mask).any():
        parts.append(angles[:, ~mask])
    return np.concatenate(parts, axis=1).astype(np.float32)


def weighted_kmeans(points, weights, k: int, iterations: int = 5, rng=None):
    """Lloyd's k-means on weighted points, k-means++ seeds, in numpy.

    Parameters
    ----------
    points : (U, D) float
    weights : (U,) float, positive
    k : int, <= U
    iterations : int
        Lloyd iterations (bounded: the cost is ``iterations * U * k * D``).

    Returns
    -------
    centres : (k, D) float64
    labels : (U,) int
    """
    # Small products: OpenBLAS's worker threads cost more than they save here.
    with threadpool_limits(1, user_api="blas"):
        return _weighted_kmeans(points, weights, k, iterations, rng)


def _weighted_kmeans(points, weights, k, iterations, rng):
    rng = np.random.default_rng() if rng is None else rng
    x = np.asarray(points, dtype=np.float64)
    w = np.asarray(weights, dtype=np.float64)
    u = len(x)
    sq = np.einsum("ij,ij->i", x, x)
    centres = np.empty((k, x.shape[1]))
    centres[0] = x[rng.choice(u, p=w / w.sum())]
    d2 = np.maximum(sq - 2 * x @ centres[0] + centres[0] @ centres[0], 0)
    for i in range(1, k):
        p = w * d2
        total = p.sum()
        pick = rng.choice(u, p=p / total) if total > 0 else rng.integers(u)
        centres[i] = x[pick]
        d2 = np.minimum(d2, np.maximum(sq - 2 * x @ centres[i] + centres[i] @ centres[i], 0))
    labels = np.zeros(u, dtype=np.intp)
    for _ in range(max(1, iterations)):
        dist = sq[:, None] - 2 * x @ centres.T + np.einsum("ij,ij->i", centres, centres)[None]
        labels = np.argmin(dist, axis=1)
        mass = np.bincount(labels, weights=w, minlength=k)
        onehot = np.zeros((u, k))
        onehot[np.arange(u), labels] = w
        sums = onehot.T @ x
        filled = mass > 0
        centres[filled] = sums[filled] / mass[filled, None]
    dist = sq[:, None] - 2 * x @ centres.T + np.einsum("ij,ij->i", centres, centres)[None]
    return centres, np.argmin(dist, axis=1)


def kmeans_estimate(points, fraction: float = 0.01, counts=None, circular=True, max_points: int = 5000,
                    iterations: int = 5, rng=None):
    """Thesis 7.3.1: the centre of the most populated k-means cluster, k = ``fraction`` of the particles.

    The particle set is the multiset ``points`` with multiplicities ``counts``
    (after resampling many particles are copies; pass the distinct ancestors and
    how often each was drawn). Costs are bounded: ``max_points`` particles are
    drawn from the multiset (all of them when there are fewer), k is ``fraction``
    of the drawn ones — so clusters keep the expected size ``1 / fraction``
    (100 members) — and :func:`weighted_kmeans` runs ``iterations`` Lloyd
    iterations from k-means++ seeds on the distinct drawn points weighted by
    their multiplicity (k is capped at the number of distinct points). Angles are
    clustered on the circle, in ``(cos, sin)`` coordinates; the centre goes back
    through ``atan2`` (the circular mean of the members).

    Parameters
    ----------
    points : (U, D) float
    fraction : float
    counts : (U,) int, optional
        Multiplicities (default 1 each).
    circular : bool or (D,) bool
    max_points : int
    iterations : int
    rng : numpy Generator

    Returns
    -------
    centre : (D,) float64
    info : dict
        ``k``, ``clustered`` (particles drawn), ``distinct``, ``largest`` (weight of the chosen cluster).
    """
    rng = np.random.default_rng() if rng is None else rng
    points = np.asarray(points)
    u, dim = points.shape
    counts = np.ones(u, dtype=np.int64) if counts is None else np.asarray(counts, dtype=np.int64)
    total = int(counts.sum())
    if total > max_points:
        drawn = np.bincount(rng.choice(u, max_points, p=counts / total), minlength=u)
    else:
        drawn = counts
    keep = np.flatnonzero(drawn)
    sample, weight = points[keep], drawn[keep].astype(np.float64)
    n_drawn = int(weight.sum())
    k = max(1, min(int(round(fraction * n_drawn)), len(sample)))
    mask = np.ones(dim, bool) if circular is True else np.asarray(circular, bool)
    if k == 1:
        labels = np.zeros(len(sample), int)
    else:
        _, labels = weighted_kmeans(circular_embedding(sample, mask), weight, k, iterations, rng)
    sizes = np.bincount(labels, weights=weight, minlength=k)
    best = int(np.argmax(sizes))
    members = sample[labels == best].astype(np.float64)
    w = weight[labels == best]
    centre = (members * w[:, None]).sum(0) / w.sum()
    if mask.any():
        centre[mask] = np.arctan2((np.sin(members[:, mask]) * w[:, None]).sum(0),
                                  (np.cos(members[:, mask]) * w[:, None]).sum(0))
    return centre, {"k": k, "clustered": n_drawn, "distinct": len(sample), "largest": float(sizes[best])}


def gaussian_angle_log_likelihood(angles, z, sigma: float, threads: int = 2, chunk: int = 16384):
    """The thesis's measurement model: an isotropic Gaussian over the (wrapped) angle error.

    ``log p(z | x) = -|wrap(x - z)|^2 / (2 sigma^2)`` (constant dropped).

    Parameters
    ----------
    angles : (N, A) float32
    z : (A,) float
    sigma : float

    Returns
    -------
    (N,) float32
    """
    angles = np.asarray(angles)
    z = np.asarray(z, dtype=angles.dtype)
    out = np.empty(len(angles), dtype=np.float32)
    k = np.float32(-0.5 / sigma ** 2)

    def work(a, b, _):
        d = angles[a:b] - z
        d = wrap(d)
        out[a:b] = np.einsum("ij,ij->i", d, d) * k

    run_chunked(len(angles), work, chunk, threads)
    return out


class ParticleFilter:
    """Bootstrap particle filter (thesis Algorithm 2 with Algorithm 3's resampler).

    Parameters
    ----------
    particles : dict of (N, ...) arrays
    transition : callable(particles, rng) -> particles
        With ``fused_resampling``: ``transition(particles, rng, ancestors=..., out=...)``
        must start new particle i from ``particles[ancestors[i]]`` and write into ``out``.
    log_likelihood : callable(particles, z) -> (N,)
    rng : numpy Generator, optional
    resampler : callable(weights, rng) -> indices
        :func:`low_variance_resample` (default) or :func:`multinomial_resample`.
    order_key : callable(particles) -> (N,) int, optional
        Resampled particles are ordered by the key of their ancestor (stable), so a
        transition can batch particles that share a key.
    fused_resampling : bool
        Leave the gather to the transition (one pass over memory instead of two).
    transition_and_score : callable, optional
        Move and weigh in one pass (see :meth:`step`).

    Attributes
    ----------
    particles : dict
        The current set. After :meth:`update` it is the resampled posterior, except
        with ``fused_resampling``, where it stays the weighted set until the next
        :meth:`predict` (use :meth:`resampled` for the posterior).
    weighted : dict
        The particles the last update weighted (before resampling).
    log_weights : (N,) float
        Log-likelihoods of the last update, before resampling.
    weights : (N,) float64
        Their normalised weights.
    map_particle : dict
        The highest-weight particle of the last update (before resampling).
    ess : float
        Effective sample size before the last resampling.
    ancestors : (N,) intp
        Which weighted particle each resampled particle copies.
    """

    def __init__(self, particles: dict, transition, log_likelihood, rng=None, resampler=low_variance_resample,
                 order_key=None, fused_resampling: bool = False, transition_and_score=None):
        self.particles = particles
        self.transition = transition
        self.log_likelihood = log_likelihood
        self.rng = np.random.default_rng() if rng is None else rng
        self.resampler = resampler
        self.order_key = order_key
        self.fused = fused_resampling
        self.transition_and_score = transition_and_score
        self.log_weights = None
        self.weights = None
        self.map_particle = None
        self.weighted = None
        self.ess = float(self.n)
        self.ancestors = None
        self._pending = None
        self._spare = None

    @property
    def n(self) -> int:
        return len(next(iter(self.particles.values())))

    def predict(self):
        """Move every particle through the transition (the prior for the next update)."""
        if self._pending is not None:
            spare = self._spare
            new = self.transition(self.particles, self.rng, ancestors=self._pending, out=spare)
            self._spare, self.particles, self._pending = self.particles, new, None
        else:
            self.particles = self.transition(self.particles, self.rng)
        return self.particles

    def update(self, z):
        """Weight by ``log_likelihood(particles, z)``, remember the MAP particle, resample."""
        return self._weigh_and_resample(self.log_likelihood(self.particles, z))

    def _weigh_and_resample(self, lw):
        self.log_weights = lw
        self.weights = normalise_log_weights(lw)
        self.ess = effective_sample_size(self.weights)
        best = map_index(lw)
        self.map_particle = {k: np.array(v[best]) for k, v in self.particles.items()}
        idx = self.resampler(self.weights, self.rng)
        if self.order_key is not None:
            keys = np.asarray(self.order_key(self.particles))[idx]
            idx = idx[np.argsort(keys, kind="stable")]
        self.ancestors = idx
        self.weighted = self.particles
        if self.fused:
            self._pending = idx
            if self._spare is None:
                self._spare = {k: np.empty_like(v) for k, v in self.particles.items()}
            return self.particles
        new = gather_particles(self.particles, idx, self._spare)
        self._spare = self.particles          # reuse the old buffers next time
        self.particles = new
        return self.particles

    def resampled(self) -> dict:
        """The posterior particle set of the last update (gathered when still pending)."""
        if self._pending is None:
            return self.particles
        return gather_particles(self.particles, self._pending)

    def distinct_posterior(self, key):
        """Distinct particles of the last update and how often each was drawn:
        ``(U, ...)`` values of ``key`` before resampling, ``(U,)`` counts."""
        distinct, counts = np.unique(self.ancestors, return_counts=True)
        return self.weighted[key][distinct], counts

    def step(self, z):
        """Predict and update with measurement ``z``.

        With ``transition_and_score`` the move and the likelihood are one pass:
        ``transition_and_score(particles, rng, z, ancestors=..., out=...) -> (particles, log_likelihoods)``.
        """
        if self.transition_and_score is None:
            self.predict()
            return self.update(z)
        if self._pending is not None:
            new, lw = self.transition_and_score(self.particles, self.rng, z, ancestors=self._pending,
                                                out=self._spare)
            self._spare, self.particles, self._pending = self.particles, new, None
        else:
            self.particles, lw = self.transition_and_score(self.particles, self.rng, z)
        return self._weigh_and_resample(lw)
