"""Build the default skinned body meshes shipped in depthtrack/data/meshes/.

    .venv/bin/python tools/make_body_mesh.py [--voxel 0.005] [--full 6000] [--decimated 1000]
                                             [--coarse 500]

Polygonises the implicit body of :mod:`depthtrack.body.anthropometry` (a smooth
union of capsules and ellipsoids on Winter's proportions for a 1.75 m adult) with
marching cubes, smooths it (Taubin, volume preserving), decimates it with quadric
edge collapse to three levels of detail (full; decimated, the tracker's candidates;
coarse, a cheaper candidate mesh: ``ObserveSettings.render_mesh``), computes the skinning
weights (distance to the bones, top 4 normalised) and writes glTF 2.0 skins. Every mesh is
checked to be closed, consistently oriented and single-shelled before writing.

Needs the tool extras: ``pip install -e '.[tools]'`` (scikit-image, fast-simplification).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import depthtrack  # noqa: F401  (first, before numpy: the same OpenBLAS kernels on every machine)
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from depthtrack.body.anthropometry import (REFERENCE_HEIGHT, body_sdf,  # noqa: E402
                                           raw_skin_weights, rest_joint_positions, top_influences)
from depthtrack.body.gltf import write_skinned_gltf  # noqa: E402
from depthtrack.body.mesh import SkinnedMesh  # noqa: E402
from depthtrack.body.skeleton import NUM_JOINTS  # noqa: E402

OUT_DIR = ROOT / "depthtrack" / "data" / "meshes"


def polygonise(voxel):
    """Marching cubes of the body SDF on a regular grid: (vertices (n, 3), faces (m, 3))."""
    from skimage.measure import marching_cubes

    lo = np.array([-0.55, -0.45 * REFERENCE_HEIGHT - 0.05, -0.30])
    hi = np.array([0.55, 0.56 * REFERENCE_HEIGHT + 0.05, 0.30])
    shape = np.ceil((hi - lo) / voxel).astype(int) + 1
    axes = [lo[i] + voxel * np.arange(shape[i]) for i in range(3)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    values = np.empty(len(grid))
    chunk = 400_000
    for s in range(0, len(grid), chunk):
        values[s:s + chunk] = body_sdf(grid[s:s + chunk])
    verts, faces, _, _ = marching_cubes(values.reshape(shape), level=0.0, spacing=(voxel,) * 3)
    return verts + lo, faces


def clean(vertices, faces):
    """Largest connected shell, merged, consistently wound with outward normals."""
    import trimesh

    mesh = trimesh.Trimesh(vertices, faces, process=True)
    parts = mesh.split(only_watertight=False)
    mesh = max(parts, key=lambda m: len(m.faces))
    trimesh.repair.fix_normals(mesh)
    return mesh


def decimate(mesh, target_faces):
    import fast_simplification
    import trimesh

    reduction = 1.0 - target_faces / len(mesh.faces)
    v, f = fast_simplification.simplify(np.asarray(mesh.vertices, np.float32),
                                        np.asarray(mesh.faces, np.int32), target_reduction=reduction)
    out = trimesh.Trimesh(v, f, process=True)
    trimesh.repair.fix_normals(out)
    return out


def diffuse_weights(mesh, weights, iterations):
    """Smooth per-vertex weights ``(n, J)`` over the surface: ``w <- (w + mean of neighbours) / 2``.

    Diffusion over ``iterations`` steps of edge length e spreads a weight step over
    about ``e * sqrt(iterations)``, which turns the distance-based weights into
    smooth blends around the joints without crossing gaps between limbs.
    """
    import scipy.sparse as sp

    n = len(mesh.vertices)
    e = np.asarray(mesh.edges_unique)
    adj = sp.coo_matrix((np.ones(2 * len(e)), (np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]])),
                        shape=(n, n)).tocsr()
    step = sp.diags(1.0 / np.asarray(adj.sum(1)).ravel()) @ adj
    w = np.asarray(weights, dtype=np.float64)
    for _ in range(iterations):
        w = 0.5 * w + 0.5 * (step @ w)
    return w / w.sum(1, keepdims=True)


def check(mesh, label):
    problems = []
    if not mesh.is_watertight:
        problems.append("not watertight")
    if not mesh.is_winding_consistent:
        problems.append("inconsistent winding")
    if mesh.volume <= 0:
        problems.append("inward normals")
    if mesh.body_count != 1:
        problems.append(f"{mesh.body_count} shells")
    if problems:
        raise SystemExit(f"{label} mesh: " + ", ".join(problems))


def build(voxel=0.005, full_faces=6000, decimated_faces=1000, smooth_iterations=20, out_dir=OUT_DIR,
          blend_width=0.025, coarse_faces=500):
    import trimesh

    from scipy.spatial import cKDTree

    verts, faces = polygonise(voxel)
    dense = clean(verts, faces)
    trimesh.smoothing.filter_taubin(dense, lamb=0.5, nu=-0.53, iterations=smooth_iterations)
    blend_iterations = int(round((blend_width / voxel) ** 2))
    dense_weights = diffuse_weights(dense, raw_skin_weights(dense.vertices), blend_iterations)
    nearest = cKDTree(dense.vertices)
    joints, head = rest_joint_positions()
    meshes = {label: decimate(dense, target)
              for label, target in (("full", full_faces), ("decimated", decimated_faces),
                                            ("coarse", coarse_faces))}
    # Smoothing and the finite grid shave a few millimetres off the head and soles; scale
    # both levels (and the skeleton) about the pelvis so the full mesh is exactly
    # REFERENCE_HEIGHT tall and BodyModel.default(1.75) needs no further scale.
    extent = np.ptp(meshes["full"].vertices[:, 1])
    factor = REFERENCE_HEIGHT / extent
    joints, head = joints * factor, head * factor
    results = {}
    for label, m in meshes.items():
        check(m, label)
        _, idx = nearest.query(m.vertices)  # weights come from the dense surface, before scaling
        jidx, w = top_influences(dense_weights[idx])
        m.vertices = m.vertices * factor
        inverse_bind = np.tile(np.eye(4), (NUM_JOINTS, 1, 1))
        inverse_bind[:, :3, 3] = -joints
        skinned = SkinnedMesh(m.vertices, m.faces, jidx, w, inverse_bind, name=f"default-{label}")
        path = Path(out_dir) / f"body_{label}.glb"
        write_skinned_gltf(path, skinned, joints, head)
        results[label] = (path, len(m.vertices), len(m.faces), path.stat().st_size)
    return results


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--voxel", type=float, default=0.005, help="marching-cubes cell size in metres")
    ap.add_argument("--full", type=int, default=6000, help="triangles of the full mesh")
    ap.add_argument("--decimated", type=int, default=1000, help="triangles of the decimated mesh")
    ap.add_argument("--coarse", type=int, default=500, help="triangles of the coarse mesh")
    ap.add_argument("--smooth", type=int, default=20, help="Taubin smoothing iterations")
    ap.add_argument("--out", type=Path, default=OUT_DIR, help="output folder")
    args = ap.parse_args(argv)
    for label, (path, nv, nf, size) in build(args.voxel, args.full, args.decimated, args.smooth,
                                             args.out, coarse_faces=args.coarse).items():
        print(f"{label}: {path.relative_to(ROOT) if path.is_relative_to(ROOT) else path}: "
              f"{nv} vertices, {nf} triangles, {size / 1024:.0f} KiB")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
