"""ToF noise model: measured statistics match the parameters."""
import numpy as np
import pytest

from depthtrack.synth.noise import ToFNoise, apply_tof_noise, edge_mask


def test_gaussian_noise_grows_with_depth():
    params = ToFNoise(dropout=0.0, depth_scale=0.0, flying_probability=0.0)
    rng = np.random.default_rng(0)
    for z in (1.0, 2.5, 4.0):
        out = apply_tof_noise(np.full((300, 300), z), params, rng)
        sigma = params.sigma_base + params.sigma_quadratic * z * z
        assert out.mean() == pytest.approx(z, abs=3 * sigma / 300)
        # std of 90,000 samples: relative standard error 0.24 %
        assert out.std() == pytest.approx(sigma, rel=0.015)


def test_dropout_range_and_quantisation():
    params = ToFNoise(dropout=0.05, max_range=3.0, min_range=0.5, flying_probability=0.0)
    rng = np.random.default_rng(1)
    depth = np.full((200, 200), 2.0)
    depth[:, :50] = 3.5              # beyond the range
    depth[:, 50:60] = 0.3            # too near
    depth[:10] = 0.0                 # nothing there
    out = apply_tof_noise(depth, params, rng)
    assert np.all(out[:, :60] == 0) and np.all(out[:10] == 0)
    body = out[10:, 60:]
    lost = np.mean(body == 0)
    n = body.size
    assert abs(lost - 0.05) < 4 * np.sqrt(0.05 * 0.95 / n)
    raw = out / params.depth_scale
    np.testing.assert_allclose(raw, np.rint(raw), atol=1e-3)     # multiples of depth_scale


def test_flying_pixels_lie_between_the_surfaces():
    params = ToFNoise(sigma_base=0.0, sigma_quadratic=0.0, dropout=0.0, flying_probability=0.6,
                      depth_scale=0.0)
    rng = np.random.default_rng(2)
    depth = np.full((400, 400), 3.0)
    depth[:, :200] = 2.0             # a vertical step edge at column 200
    depth[:, 300:] = 3.05            # a small step: below the threshold
    edge, other = edge_mask(depth, params.flying_threshold)
    assert edge[:, [199, 200]].all() and edge.sum() == 2 * 400
    np.testing.assert_allclose(other[:, 199], 3.0)
    out = apply_tof_noise(depth, params, rng)
    changed = out != depth.astype(np.float32)
    assert not changed[~edge].any()
    mixed = out[changed]
    assert np.all((mixed > 2.0) & (mixed < 3.0))
    assert changed[edge].mean() == pytest.approx(0.6, abs=4 * np.sqrt(0.24 / 800))
    assert np.mean(mixed) == pytest.approx(2.5, abs=0.05)   # a ~ U(0, 1)


def test_seeded_and_documented():
    params = ToFNoise.for_camera("azure-nfov")
    assert (params.min_range, params.max_range) == (0.5, 3.86)
    depth = np.full((20, 20), 2.0)
    a = params.apply(depth, np.random.default_rng(5))
    b = params.apply(depth, np.random.default_rng(5))
    np.testing.assert_array_equal(a, b)
    assert ToFNoise.from_dict(params.to_dict()) == params
    assert params.to_dict()["model"] == "tof"
