"""TileRenderer: GL depth against a CPU ray cast, GL costs against the numpy reference."""
from functools import lru_cache

import numpy as np
import pytest

from depthtrack.body import BodyModel
from depthtrack.camera import Camera
from depthtrack.likelihood import LikelihoodParams, encode_observation, tile_costs
from depthtrack.render import FrameRenderer, TileRenderer
from depthtrack.render.raycast import raycast_depth

CAMERA = Camera.preset("sr4000")
ROI = (38, 6, 112)           # a square around the default body at 2.6 m


@lru_cache(maxsize=None)
def body():
    return BodyModel.default(mesh="decimated")


@lru_cache(maxsize=None)
def renderer(tile=64, max_atlas=1024):
    return TileRenderer(body(), CAMERA, tile=tile, max_atlas=max_atlas)


def candidate_poses(n, seed=0, sigma=0.15, position=(0.0, 0.0, 2.6)):
    """(n, 48) the default pose with joint angles and position perturbed; row 0 unperturbed."""
    rng = np.random.default_rng(seed)
    poses = np.repeat(body().default_pose(position=position)[None], n, axis=0)
    poses[1:, 3:] += rng.normal(0.0, sigma, (n - 1, poses.shape[1] - 3))
    poses[1:, :3] += rng.normal(0.0, 0.03, (n - 1, 3))
    return poses


def segmented_observation(pose, holes_seed=None):
    """Depth frame of the body at ``pose``: inf (background) off the body, optional no-reading holes."""
    depth = FrameRenderer(CAMERA).render(body(), pose).astype(np.float32)
    depth[depth == 0] = np.inf
    if holes_seed is not None:
        rng = np.random.default_rng(holes_seed)
        depth[rng.random(depth.shape) < 0.05] = 0.0
    return depth


def test_tile_depth_matches_ray_cast_at_pixel_centres():
    r = renderer()
    r.set_roi(ROI)
    poses = candidate_poses(3, seed=1)
    depth = r.render_depth(poses)
    assert depth.shape == (3, 64, 64) and depth.dtype == np.float32
    for pose, gl in zip(poses, depth):
        ref = raycast_depth(body().posed_vertices(pose), body().faces, r.tile_camera)
        inside = ref > 0
        assert inside.sum() > 300
        assert np.mean(np.abs(gl[inside] - ref[inside]) < 0.005) >= 0.99
        assert np.mean((gl > 0) != inside) < 0.005


def test_tile_camera_is_the_roi_scaled_onto_the_tile():
    r = renderer()
    r.set_roi((10, 20, 128))
    cam = r.tile_camera
    # a camera pixel centre maps to the tile point (u - u0 + 0.5) * s - 0.5, s = 64 / 128
    point = np.array([0.3, -0.2, 2.0])
    u, v = CAMERA.project(point)
    np.testing.assert_allclose(cam.project(point), [(u - 10 + 0.5) / 2 - 0.5, (v - 20 + 0.5) / 2 - 0.5])


@pytest.mark.parametrize("smoothed", [True, False])
def test_gl_costs_equal_numpy_costs_of_the_gl_rendered_tiles(smoothed):
    r = renderer()
    poses = candidate_poses(20, seed=2, sigma=0.2)
    observed = segmented_observation(poses[0] + np.r_[0.02, 0.0, 0.03, np.zeros(45)], holes_seed=3)
    r.set_observation(observed, roi=ROI)
    gl = r.costs(poses, smoothed=smoothed)
    ref = tile_costs(r.render_depth(poses), r.observed_tile, r.params, smoothed=smoothed)
    assert gl.shape == (20,) and gl.dtype == np.float64
    np.testing.assert_allclose(gl, ref, rtol=1e-4)
    assert np.ptp(ref) > 0.01      # the candidates really differ


def test_gl_costs_with_scene_background_equal_numpy():
    params = LikelihoodParams(depth_scale=0.15, neighbor_penalty=0.04, no_reading_cost=0.3)
    r = TileRenderer(body(), CAMERA, tile=32, params=params)
    poses = candidate_poses(6, seed=4)
    scene = np.full(CAMERA.shape, 3.5, np.float32)           # a wall behind the subject
    observed = FrameRenderer(CAMERA).render(body(), poses[0], extra_meshes=[
        ([[-5, -5, 3.5], [5, -5, 3.5], [5, 5, 3.5], [-5, 5, 3.5]], [[0, 1, 2], [0, 2, 3]])])
    r.set_observation(observed, roi=ROI, background=scene)
    for smoothed in (True, False):
        ref = tile_costs(r.render_depth(poses), r.observed_tile, params, smoothed=smoothed,
                         background=r.background_tile)
        np.testing.assert_allclose(r.costs(poses, smoothed=smoothed), ref, rtol=1e-4)


def test_cost_is_lowest_at_the_pose_the_observation_was_rendered_from():
    r = renderer()
    poses = candidate_poses(40, seed=5, sigma=0.08)
    truth = 17
    observed = segmented_observation(poses[truth], holes_seed=6)
    for smoothed in (True, False):
        costs = r.costs(poses, observed_depth=observed, smoothed=smoothed, roi=ROI)
        assert np.argmin(costs) == truth
        assert np.sort(costs)[1] > costs[truth] + 1e-3


def assert_depths_agree(a, b):
    """Renders of the same poses at other tile positions: within 1 mm, 99.9 % within 0.1 mm."""
    diff = np.abs(a - b)
    assert diff.max() < 1e-3
    assert np.mean(diff < 1e-4) >= 0.999


def test_tiles_never_bleed_into_their_neighbours():
    r = renderer(tile=32)
    r.set_observation(segmented_observation(candidate_poses(1)[0]), roi=ROI)
    # bodies straddling every edge of the ROI, close to the camera, and one fully outside
    shifts = [(-0.9, 0, 0), (0.9, 0, 0), (0, -1.2, 0), (0, 1.2, 0), (0, 0, -1.4),
              (-0.6, -0.8, -0.5), (0.6, 0.8, -0.5), (3.0, 0, 0), (0, 0, 0)]
    poses = candidate_poses(len(shifts), seed=7, sigma=0.3)
    poses[:, :3] += np.array(shifts)
    together = r.render_depth(poses)
    alone = np.stack([r.render_depth(p[None])[0] for p in poses])
    # same pixels drawn (a bleed covers whole strips of a neighbour's tile: 16 % of the
    # pixels where the tile-edge clip planes were off on NVIDIA's driver); depths equal up
    # to the float rounding of the per-tile placement, which on a GPU can pick the other
    # triangle at a seam (0.1 mm at one pixel in 9,216 on an H200)
    np.testing.assert_array_equal(together > 0, alone > 0)
    assert_depths_agree(together, alone)
    assert (together[:7] > 0).any(axis=(1, 2)).all() and not together[7].any()
    costs_alone = np.array([r.costs(p[None])[0] for p in poses])
    np.testing.assert_allclose(r.costs(poses), costs_alone, rtol=1e-4)


def test_batches_larger_than_the_atlas_are_split():
    r = renderer(tile=32, max_atlas=64)       # 4 tiles per pass
    poses = candidate_poses(11, seed=8)
    observed = segmented_observation(poses[3])
    costs = r.costs(poses, observed_depth=observed, roi=ROI)
    depth = r.render_depth(poses)
    one_pass = renderer(tile=32)
    one_pass.set_roi(ROI)
    reference = one_pass.render_depth(poses)
    np.testing.assert_array_equal(depth > 0, reference > 0)
    assert_depths_agree(depth, reference)
    np.testing.assert_allclose(costs, tile_costs(depth, r.observed_tile, r.params), rtol=1e-4)


@pytest.mark.parametrize("tile", [16, 64, 128])
def test_reduction_is_the_exact_mean(tile):
    # with the model out of view every pixel costs its precomputed model-absent value, which
    # a random observation against a random scene depth makes arbitrary in [0, 1]
    rng = np.random.default_rng(tile)
    observed = rng.uniform(1.0, 3.0, CAMERA.shape).astype(np.float32)
    scene = rng.uniform(1.0, 3.0, CAMERA.shape).astype(np.float32)
    r = TileRenderer(body(), CAMERA, tile=tile)
    r.set_observation(observed, roi=(0, 0, 144), background=scene)
    expected = encode_observation(r.observed_tile, r.params, r.background_tile)[..., 1].mean(dtype=np.float64)
    behind = candidate_poses(3, position=(0.0, 0.0, -3.0))
    for smoothed in (True, False):
        np.testing.assert_allclose(r.costs(behind, smoothed=smoothed), expected, rtol=1e-5)


def test_gl_edge_rules_no_reading_and_background():
    r = renderer()
    poses = candidate_poses(5, seed=9)
    no_reading = np.zeros(CAMERA.shape, np.float32)
    np.testing.assert_allclose(r.costs(poses, observed_depth=no_reading, roi=ROI),
                               r.params.no_reading_cost, rtol=1e-6)
    background = np.full(CAMERA.shape, np.inf, np.float32)
    drawn = r.render_depth(poses) > 0
    # pixel-wise: every drawn pixel over observed background costs silhouette_cost
    np.testing.assert_allclose(r.costs(poses, observed_depth=background, roi=ROI, smoothed=False),
                               drawn.mean(axis=(1, 2)) * r.params.silhouette_cost, rtol=1e-5)
    # smoothed: a drawn pixel with an undrawn neighbour (cost 0 there) pays only the penalty
    padded = np.pad(drawn, [(0, 0), (1, 1), (1, 1)], constant_values=True)
    interior = np.ones_like(drawn)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            interior &= padded[:, 1 + dy:65 + dy, 1 + dx:65 + dx]
    expected = (interior * r.params.silhouette_cost
                + (drawn & ~interior) * r.params.neighbor_penalty).mean(axis=(1, 2))
    np.testing.assert_allclose(r.costs(poses, smoothed=True), expected, rtol=1e-5)


def test_costs_need_an_observation_and_matching_shapes():
    from depthtrack.errors import InputError
    r = TileRenderer(body(), CAMERA, tile=16)
    with pytest.raises(InputError):
        r.costs(candidate_poses(2))
    with pytest.raises(InputError):
        r.set_observation(np.zeros((10, 10), np.float32))
    with pytest.raises(InputError):
        TileRenderer(body(), CAMERA, tile=48)


def test_missing_egl_gives_one_line_with_what_to_install(monkeypatch):
    import moderngl
    from depthtrack.render import context

    def fail(**kwargs):
        raise Exception("libEGL.so: cannot open shared object file")

    monkeypatch.setattr(context, "_CONTEXT", None)
    monkeypatch.setattr(moderngl, "create_standalone_context", fail)
    with pytest.raises(context.GLUnavailableError) as err:
        context.gl_context()
    message = str(err.value)
    assert "\n" not in message
    assert "apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri" in message
