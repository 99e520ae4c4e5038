"""tools/make_body_mesh.py rebuilds a closed, skinned, loadable body (coarse grid, for speed)."""

import numpy as np
import pytest
import trimesh

pytest.importorskip("skimage")
pytest.importorskip("fast_simplification")

from depthtrack.body import BodyModel  # noqa: E402
from tool_module import load_tool  # noqa: E402


def test_tool_builds_closed_skinned_meshes(tmp_path):
    tool = load_tool("make_body_mesh")
    results = tool.build(voxel=0.015, full_faces=3000, decimated_faces=800, smooth_iterations=5,
                         out_dir=tmp_path, coarse_faces=400)
    wanted = {"full": 3000, "decimated": 800, "coarse": 400}
    assert set(results) == set(wanted)
    for label, (path, n_vertices, n_faces, size) in results.items():
        body = BodyModel.from_gltf(path)
        m = trimesh.Trimesh(body.mesh.vertices, body.faces, process=False)
        assert m.is_watertight and m.volume > 0
        assert abs(n_faces - wanted[label]) < 20
        np.testing.assert_allclose(body.mesh.weights.sum(1), 1.0, atol=1e-6)
        # the tool scales the full mesh to exactly 1.75 m and both levels share its skeleton
        assert abs(np.ptp(body.mesh.vertices[:, 1]) - 1.75) < (1e-4 if label == "full" else 0.02)
        np.testing.assert_allclose(body.offsets, BodyModel.from_gltf(results["full"][0]).offsets, atol=1e-6)
