"""Foreground segmentation against rendered frames with known person masks and floor planes."""
from pathlib import Path

import numpy as np
import pytest

from depthtrack.camera import Camera
from depthtrack.detect import fit_floor, segment_foreground
from depthtrack.errors import InputError

import detect_frames as F


def iou(a, b):
    return (a & b).sum() / (a | b).sum()


@pytest.mark.parametrize("name", ["a_pose", "t_pose", "reach"])
def test_mask_matches_rendered_person_with_floor_and_wall(name):
    f = F.frame(name)
    fg = segment_foreground(f.depth, F.camera())
    assert iou(fg.mask, f.mask) >= 0.95
    # points and pixels describe exactly the mask
    assert len(fg.points) == fg.mask.sum() == len(fg.pixels)
    u, v = fg.pixels.T
    assert fg.mask[v, u].all()
    np.testing.assert_allclose(fg.points[:, 2], f.depth[v, u], atol=1e-6)


def test_mask_on_noisy_frame_matches_pixels_that_still_read_the_person():
    noisy = F.frame("t_pose", noisy=True, seed=3)
    fg = segment_foreground(noisy.depth, F.camera())
    # Flying pixels on the silhouette read somewhere between the body and the wall:
    # the known mask is the body's pixels whose reading stayed within 5 cm of the body.
    readable = noisy.readable_mask(0.05)
    assert readable.sum() < 0.95 * noisy.mask.sum()          # the noise did corrupt the silhouette
    assert iou(fg.mask, readable) >= 0.93
    assert (fg.mask & ~noisy.mask).sum() <= 0.03 * noisy.mask.sum()


@pytest.mark.parametrize("roll", [0.0, 8.0])
def test_floor_plane_recovered_within_one_degree_and_one_cm(roll):
    f = F.frame("a_pose", noisy=True, roll_deg=roll, seed=1)
    plane = segment_foreground(f.depth, F.camera()).floor_plane
    assert plane is not None
    angle = np.degrees(np.arccos(np.clip(plane[:3] @ f.floor_plane[:3], -1, 1)))
    assert angle < 1.0
    assert abs(plane[3] - f.floor_plane[3]) < 0.01
    # the camera is 1.26 m (0.72 x 1.75 m) above the floor: the origin's height is that
    assert plane[3] == pytest.approx(0.72 * 1.75, abs=0.01)


def test_fit_floor_on_exact_plane_is_exact_and_rejects_walls():
    rng = np.random.default_rng(0)
    n = np.array([0.0, -np.cos(0.3), -np.sin(0.3)])          # floor seen by a camera pitched down
    xy = rng.uniform(-2, 2, size=(3000, 2))
    base = np.array([0.0, 1.2, 3.0])
    e1 = np.array([1.0, 0.0, 0.0])
    e2 = np.cross(n, e1)
    floor = base + xy[:, :1] * e1 + xy[:, 1:] * e2
    # the wall stops 0.4 m above where it would meet the floor (no crease in the inlier band)
    wall = np.column_stack([rng.uniform(-2, 2, 4000), rng.uniform(-1.5, 0.2, 4000), np.full(4000, 5.0)])
    plane = fit_floor(np.vstack([floor, wall]))
    np.testing.assert_allclose(plane[:3], n, atol=1e-6)
    assert plane[3] == pytest.approx(-n @ base, abs=1e-6)
    assert fit_floor(wall) is None                              # a wall is never the floor


def test_person_without_scenery_is_every_reading():
    from depthtrack.synth.part_scenes import render_scene_frames

    f = render_scene_frames(F.body(), F.pose()[None], F.camera(), scenery=False)[0]
    fg = segment_foreground(f.depth, F.camera())
    assert fg.floor_plane is None
    assert iou(fg.mask, f.depth > 0) >= 0.99


def test_empty_frame_gives_empty_foreground():
    cam = F.camera()
    fg = segment_foreground(np.zeros(cam.shape), cam)
    assert fg.mask.shape == cam.shape and not fg.mask.any()
    assert fg.points.shape == (0, 3) and fg.pixels.shape == (0, 2)


@pytest.mark.parametrize("bad, message", [
    (np.full((144, 176), np.nan), "NaN"),
    (np.zeros((100, 176)), "camera is 176 x 144"),
    (np.zeros((144, 176, 2)), "2-D"),
    (-np.ones((144, 176)), "negative"),
])
def test_bad_depth_raises_input_error(bad, message):
    with pytest.raises(InputError, match=message):
        segment_foreground(bad, Camera.preset("sr4000"))


def test_flying_pixels_are_the_mixed_readings_across_an_edge():
    from depthtrack.detect.graph import flying_pixels

    z = np.full((5, 9), 3.0)
    z[:, 5:] = 4.0                      # a 1 m step between columns 4 and 5
    z[2, 4] = 3.5                       # one mixed reading half way across it
    z[:, 0] = 3.0 + 0.05 * np.arange(5)  # a slanted but continuous column
    z[4, 7] = 3.0                       # a 1-pixel post in front of the far surface
    fly = flying_pixels(z, z > 0, fx=220.0)
    assert fly[2, 4]
    assert fly.sum() == 1


@pytest.mark.skipif(not (Path(__file__).resolve().parents[2] / "shared" / "data" / "motions" / "jump.bvh").exists(),
                    reason="shared motion data absent")
def test_person_near_the_back_wall_is_not_lost_in_it(tmp_path):
    # The jump clip as `make benchmark` makes it: at the top of the jump (frame 11) the body
    # joined the back wall through noisy pixels and the whole surface was taken for a wall.
    from depthtrack.io import open_sequence
    from depthtrack.synth.generate import synthesize_bvh
    from depthtrack.track.observation import visible_area

    path = Path(__file__).resolve().parents[2] / "shared" / "data" / "motions" / "jump.bvh"
    synthesize_bvh(path, tmp_path / "jump", camera="sr4000", noise="tof", fps=25.0)
    seq = open_sequence(tmp_path / "jump")
    areas = [visible_area(segment_foreground(seq.depth(i), seq.camera), seq.camera) for i in range(len(seq))]
    assert min(areas) > 0.25
