"""The numpy sensor model and smoothed likelihood against closed forms (no OpenGL)."""
import numpy as np
import pytest

from depthtrack.errors import InputError
from depthtrack.likelihood import (LikelihoodParams, encode_observation, observation_tile,
                                   pixel_costs, smoothed_costs, smoothstep, tile_costs)

P = LikelihoodParams(depth_scale=0.1, neighbor_penalty=0.025, silhouette_cost=1.0,
                     missing_cost=0.9, no_reading_cost=0.5, max_depth=8.0)


def test_smoothstep_is_the_glsl_cubic():
    x = np.array([-1.0, 0.0, 0.25, 0.5, 1.0, 3.0])
    np.testing.assert_allclose(smoothstep(x), [0, 0, 0.25**2 * 2.5, 0.5, 1, 1])


def test_pixel_cost_is_smoothstep_of_scaled_difference():
    observed = np.full((4, 4), 2.0)
    rendered = np.full((4, 4), 2.03)
    expected = 0.3**2 * (3 - 2 * 0.3)
    np.testing.assert_allclose(pixel_costs(rendered, observed, P), expected, rtol=1e-5)
    np.testing.assert_allclose(pixel_costs(np.full((4, 4), 2.5), observed, P), 1.0)


def test_edge_rules_for_no_reading_background_and_absent_model():
    # one row per case: observed value, rendered value, expected cost
    cases = [
        (0.0, 2.0, P.no_reading_cost),      # no reading, model drawn
        (0.0, 0.0, P.no_reading_cost),      # no reading, model absent
        (np.inf, 2.0, P.silhouette_cost),   # background (segmented), model drawn
        (9.0, 2.0, P.silhouette_cost),      # beyond max_depth counts as background
        (np.inf, 0.0, 0.0),                 # background explained by the scene
        (9.0, 0.0, 0.0),
        (2.0, 0.0, P.missing_cost),         # foreground, model absent, no scene depth
        (2.0, 2.0, 0.0),
    ]
    observed = np.array([[c[0] for c in cases]])
    rendered = np.array([[c[1] for c in cases]])
    np.testing.assert_allclose(pixel_costs(rendered, observed, P)[0], [c[2] for c in cases],
                               atol=1e-7)


def test_known_scene_depth_explains_observation_where_model_is_absent():
    observed = np.array([[3.0, 3.0, 2.0]])
    scene = np.array([[3.0, 0.0, 3.0]])     # scene depth known, unknown, known but far
    rendered = np.zeros((1, 3))
    np.testing.assert_allclose(pixel_costs(rendered, observed, P, background=scene)[0],
                               [0.0, P.missing_cost, 1.0], atol=1e-7)


def test_smoothed_cost_pays_the_penalty_for_a_one_pixel_shift():
    rng = np.random.default_rng(0)
    observed = np.zeros((8, 8))
    observed[2:6, 2:6] = 2.0 + rng.uniform(0, 0.5, (4, 4))
    rendered = np.roll(observed, 1, axis=1)     # the model one pixel to the right
    smooth = smoothed_costs(rendered, observed, P)
    pixel = pixel_costs(rendered, observed, P)
    assert np.all(smooth <= pixel + 1e-12)
    # every observed foreground pixel finds its own depth one pixel away
    np.testing.assert_allclose(smooth[2:6, 2:6], P.neighbor_penalty, atol=1e-6)


def test_smoothed_cost_ignores_neighbours_outside_the_tile():
    observed = np.array([[2.0, 2.0]])
    rendered = np.array([[2.5, 2.0]])
    # pixel 0 can use pixel 1 (penalty); nothing beyond the border helps
    np.testing.assert_allclose(smoothed_costs(rendered, observed, P)[0],
                               [P.neighbor_penalty, 0.0], atol=1e-7)


def test_tile_costs_are_means_over_pixels_batched():
    rng = np.random.default_rng(1)
    observed = rng.uniform(1, 3, (6, 6))
    rendered = rng.uniform(1, 3, (5, 6, 6)) * (rng.random((5, 6, 6)) > 0.3)
    got = tile_costs(rendered, observed, P, smoothed=False)
    want = [pixel_costs(r, observed, P).mean() for r in rendered]
    np.testing.assert_allclose(got, want)
    assert got.shape == (5,)


def test_observation_tile_is_nearest_sampling_at_tile_pixel_centres():
    depth = np.arange(10 * 12, dtype=np.float32).reshape(10, 12)
    # ROI 4 pixels wide mapped onto 2 tile pixels: centres at camera 2.5 -> 3 and 4.5 -> 5
    tile = observation_tile(depth, (2, 1, 4), 2)
    np.testing.assert_array_equal(tile, depth[np.ix_([2, 4], [3, 5])])
    # same size: identity crop; outside the image: no reading
    np.testing.assert_array_equal(observation_tile(depth, (3, 2, 4), 4), depth[2:6, 3:7])
    out = observation_tile(depth, (-2, -2, 4), 4)
    assert np.all(out[:2] == 0) and np.all(out[:, :2] == 0)
    np.testing.assert_array_equal(out[2:, 2:], depth[:2, :2])


def test_encoding_marks_no_reading_and_background():
    enc = encode_observation(np.array([[0.0, np.inf, 2.0, np.nan, -1.0]]), P)
    np.testing.assert_allclose(enc[0, :, 0], [0.0, -1.0, 2.0, 0.0, 0.0])
    np.testing.assert_allclose(enc[0, :, 1], [P.no_reading_cost, 0.0, P.missing_cost,
                                              P.no_reading_cost, P.no_reading_cost])


def test_invalid_parameters_are_rejected():
    with pytest.raises(InputError):
        LikelihoodParams(depth_scale=0.0)
    with pytest.raises(InputError):
        LikelihoodParams(neighbor_penalty=-1.0)


def test_one_sensor_model_table_feeds_the_shader_and_the_unexplained_bounds():
    from depthtrack.likelihood import (BACKGROUND, BACKGROUND_CODE, NO_READING, SENSOR_MODEL,
                                       LikelihoodParams, fixed_and_empty_costs, sensor_cost,
                                       shader_constants, tile_costs)
    from depthtrack.render.context import shader_source

    params = LikelihoodParams(silhouette_cost=0.8, no_reading_cost=0.3)
    consts = shader_constants(params)
    assert float(consts["SILHOUETTE_COST"]) == sensor_cost(params, "background", "drawn") == 0.8
    assert float(consts["NO_READING_COST"]) == 0.3
    assert float(consts["BACKGROUND_CODE"]) == BACKGROUND_CODE
    assert set(SENSOR_MODEL) == {"no_reading", "background", "reading"}
    source = shader_source("tile_cost.comp")
    for name in consts:                                   # the shader reads every constant
        assert name in source
    assert "u_depth_scale" not in source and "0.025" not in source
    rng = np.random.default_rng(3)
    observed = rng.uniform(1.0, 3.0, (16, 16))
    observed[:4] = NO_READING
    observed[-3:] = BACKGROUND
    fixed, empty = fixed_and_empty_costs(observed, params)
    nothing = np.zeros((1, 16, 16))
    assert empty == pytest.approx(tile_costs(nothing, observed, params, smoothed=True)[0])
    assert empty == pytest.approx(tile_costs(nothing, observed, params, smoothed=False)[0])
    assert fixed == pytest.approx(0.3 * 64 / 256)
    assert empty == pytest.approx(fixed + 1.0 * (256 - 64 - 48) / 256)
