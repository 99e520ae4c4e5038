"""Particle filter pieces against closed forms: resampler counts, Kalman filter, k-means estimate."""
import numpy as np
import pytest

from depthtrack.filters.kalman import KalmanFilter
from depthtrack.filters.particle import (
    ParticleFilter, effective_sample_size, kmeans_estimate, low_variance_resample, map_index,
    normalise_log_weights)


def test_low_variance_counts_match_closed_form():
    rng = np.random.default_rng(0)
    for m in (1, 7, 100, 5000):
        w = rng.random(m) ** 4
        w /= w.sum()
        r = rng.random() / m
        idx = low_variance_resample(w, offset=r)
        counts = np.bincount(idx, minlength=m)
        cumulative = np.cumsum(w)
        expected = np.diff(np.concatenate([[0], np.clip(np.floor((cumulative - r) * m) + 1, 0, m)]))
        expected[-1] = m - expected[:-1].sum()
        np.testing.assert_array_equal(counts, expected)
        # low variance: every particle is drawn floor(M w) or ceil(M w) times
        assert np.all(counts >= np.floor(m * w) - 1e-9) and np.all(counts <= np.ceil(m * w) + 1e-9)
        assert np.all(np.diff(idx) >= 0)


def test_low_variance_algorithm_3_loop():
    # the thesis's pseudo code, literally, on a small example
    w = np.array([0.1, 0.5, 0.05, 0.35])
    m = len(w)
    r = 0.13 / m
    out, c, i = [], w[0], 0
    for k in range(m):
        u = r + k / m
        while u > c:
            i += 1
            c += w[i]
        out.append(i)
    np.testing.assert_array_equal(low_variance_resample(w, offset=r), out)


def test_weights_in_log_domain_do_not_underflow():
    lw = np.array([-1e4, -1e4 - 1.0, -2e4])
    w = normalise_log_weights(lw)
    assert w.sum() == pytest.approx(1.0)
    assert w[0] / w[1] == pytest.approx(np.e)
    assert map_index(lw) == 0
    assert effective_sample_size(np.full(10, 0.1)) == pytest.approx(10)


def test_particle_filter_matches_kalman_filter_on_a_linear_gaussian_model():
    q, r, steps, n = 0.2 ** 2, 0.5 ** 2, 25, 40000
    rng = np.random.default_rng(3)
    truth = np.cumsum(rng.normal(0, np.sqrt(q), steps))
    zs = truth + rng.normal(0, np.sqrt(r), steps)
    kf = KalmanFilter(x=[0.0], P=[[1.0]], F=[[1.0]], H=[[1.0]], Q=[[q]], R=[[r]])

    def transition(p, g):
        return {"x": p["x"] + np.sqrt(q) * g.standard_normal(p["x"].shape)}

    def loglik(p, z):
        return -0.5 * (p["x"][:, 0] - z) ** 2 / r

    pf = ParticleFilter({"x": rng.normal(0, 1, (n, 1))}, transition, loglik, np.random.default_rng(4))
    for z in zs:
        kf.predict()
        kf.update([z])
        pf.step(z)
        x = pf.weighted["x"][:, 0]
        mean = np.dot(pf.weights, x)
        var = np.dot(pf.weights, (x - mean) ** 2)
        sd = np.sqrt(kf.P[0, 0])
        assert abs(mean - kf.x[0]) < 0.05 * sd
        assert var == pytest.approx(kf.P[0, 0], rel=0.08)


def test_kmeans_estimate_picks_the_densest_cluster_and_wraps():
    rng = np.random.default_rng(5)
    dense = np.column_stack([rng.normal(np.pi - 0.01, 0.02, 700), rng.normal(1.0, 0.02, 700)])
    dense[:, 0] = (dense[:, 0] + np.pi) % (2 * np.pi) - np.pi        # straddles +-pi
    sparse = np.column_stack([rng.uniform(-2, 2, 300), rng.uniform(-2, 2, 300)])
    pts = np.vstack([dense, sparse])
    centre, info = kmeans_estimate(pts, fraction=0.01, rng=rng)
    assert info["k"] == 10
    d0 = (centre[0] - (np.pi - 0.01) + np.pi) % (2 * np.pi) - np.pi
    assert abs(d0) < 0.05 and abs(centre[1] - 1.0) < 0.05
    # multiplicities: a point drawn 600 times out of 1000 wins
    pts2 = np.array([[0.0, 0.0], [2.0, 2.0], [2.1, 2.0]])
    centre2, info2 = kmeans_estimate(pts2, 0.01, counts=np.array([200, 600, 200]), rng=rng)
    assert info2["clustered"] == 1000
    assert centre2[0] > 1.9


def test_kmeans_subsample_keeps_cluster_size():
    rng = np.random.default_rng(6)
    pts = rng.normal(0, 1, (50000, 3))
    centre, info = kmeans_estimate(pts, 0.01, max_points=3000, iterations=3, rng=rng)
    assert info["clustered"] == 3000 and info["k"] == 30
