"""FrameRenderer: full-resolution depth and part labels against a CPU ray cast."""
from functools import lru_cache

import numpy as np
import pytest

from depthtrack.body import BodyModel
from depthtrack.camera import Camera
from depthtrack.errors import InputError
from depthtrack.render import FrameRenderer
from depthtrack.render.raycast import raycast_depth

CAMERA = Camera.preset("sr4000")
FLOOR = (np.array([[-4, 0.95, 0.5], [4, 0.95, 0.5], [4, 0.95, 9], [-4, 0.95, 9]], float),
         np.array([[0, 1, 2], [0, 2, 3]]))
WALL = (np.array([[-4, -4, 4.5], [4, -4, 4.5], [4, 0.95, 4.5], [-4, 0.95, 4.5]], float),
        np.array([[0, 1, 2], [0, 2, 3]]))


@lru_cache(maxsize=None)
def body():
    return BodyModel.default(mesh="decimated")


def pose(seed):
    rng = np.random.default_rng(seed)
    p = body().default_pose(position=(0.1, 0.0, 2.6))
    p[3:] += rng.normal(0.0, 0.2, len(p) - 3)
    return p


def planes_depth(meshes):
    """(H, W) z of the nearest hit on a few big triangles, Moller-Trumbore over all rays (0 = none)."""
    rays = CAMERA.rays().reshape(-1, 3)
    best = np.full(len(rays), np.inf)
    for vertices, faces in meshes:
        for a, b, c in vertices[faces]:
            e1, e2 = b - a, c - a
            pvec = np.cross(rays, e2)
            det = pvec @ e1
            qvec = np.cross(-a, e1)           # ray origin (0, 0, 0) minus a, cross e1
            with np.errstate(divide="ignore", invalid="ignore"):
                u = (pvec @ -a) / det
                v = (rays @ qvec) / det
                t = (qvec @ e2) / det
                hit = (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
            best = np.where(hit & (t < best), t, best)
    return np.where(np.isfinite(best), best, 0.0).reshape(CAMERA.shape)


@pytest.mark.parametrize("seed", [0, 1])
def test_frame_depth_with_floor_and_wall_matches_ray_cast(seed):
    p = pose(seed)
    depth = FrameRenderer(CAMERA).render(body(), p, extra_meshes=[FLOOR, WALL])
    body_depth = raycast_depth(body().posed_vertices(p), body().faces, CAMERA)
    ref = planes_depth([FLOOR, WALL])
    ref = np.where((body_depth > 0) & ((body_depth < ref) | (ref == 0)), body_depth, ref)
    assert depth.shape == CAMERA.shape and depth.dtype == np.float32
    hit = ref > 0
    assert hit.mean() > 0.5          # wall and floor fill most of the view
    assert np.mean(np.abs(depth[hit] - ref[hit]) < 0.005) >= 0.99
    assert np.mean((depth > 0) != hit) < 0.002
    # the floor is where the plane is: rows below the horizon hit it at z = fy * 0.95 / (v - cy)
    row = CAMERA.height - 1
    np.testing.assert_allclose(depth[row, 5], CAMERA.fy * 0.95 / (row - CAMERA.cy), rtol=1e-5)


def test_labels_name_the_dominant_skinning_joint_of_the_surface_hit():
    p = pose(2)
    # a floor high enough to hide the feet: occluded body pixels must be labelled background
    floor = (FLOOR[0] - [0, 0.15, 0], FLOOR[1])
    labels = FrameRenderer(CAMERA).render_labels(body(), p, extra_meshes=[floor, WALL])
    vertices, faces = body().posed_vertices(p), body().faces
    depth, face = raycast_depth(vertices, faces, CAMERA, return_faces=True)
    scenery = planes_depth([floor, WALL])
    assert labels.dtype == np.int16 and labels.shape == CAMERA.shape
    on_body = (face >= 0) & ((scenery == 0) | (depth < scenery - 0.005))
    occluded = (face >= 0) & (scenery > 0) & (scenery < depth - 0.005)
    assert np.all(labels[face < 0] == -1)
    assert occluded.sum() > 10 and np.mean(labels[occluded] == -1) >= 0.97
    # reference: the joint with the largest barycentric-interpolated weight at the hit point
    mesh = body().mesh
    per_vertex = np.zeros((len(mesh.vertices), len(body().joint_names)))
    np.add.at(per_vertex, (np.arange(len(mesh.vertices))[:, None], mesh.joints), mesh.weights)
    v, u = np.nonzero(on_body)
    hits = np.stack([(u - CAMERA.cx) / CAMERA.fx, (v - CAMERA.cy) / CAMERA.fy,
                     np.ones_like(u, float)], -1) * depth[v, u, None]
    tri = vertices[faces[face[v, u]]]
    import trimesh
    bary = trimesh.triangles.points_to_barycentric(tri, hits)
    weights = np.einsum("nk,nkj->nj", bary, per_vertex[faces[face[v, u]]])
    expected = np.argmax(weights, axis=1)
    agree = labels[v, u] == expected
    assert on_body.sum() > 300
    assert agree.mean() >= 0.97
    assert set(np.unique(labels[on_body])) >= {0, 1, 2}


def test_bad_extra_mesh_is_rejected():
    with pytest.raises(InputError):
        FrameRenderer(CAMERA).render(body(), pose(0), extra_meshes=[(np.zeros((3, 2)), [[0, 1, 2]])])
