"""Who is filmed: the synthetic subject's height, body shape and clothing.

``depthtrack synth --shape average|random|FILE.json [--shape-seed N] [--clothing none|tight|loose]``
builds its body with :func:`make_subject`. The shape (:class:`~depthtrack.body.shape.BodyShape`)
moves joints and surface alike; clothing only changes the surface the camera sees (the
skeleton, the ground truth, stays the person's):

* ``tight``: a 5 mm layer over the trunk and legs;
* ``loose``: an offset surface over the trunk and legs, 1 to 4 cm along the vertex normals,
  the amount a smooth random field over the mesh (seeded by the shape seed), so a shirt
  and trousers stand off the body unevenly as cloth does.

Offsets are faded in over the skin weights of the trunk and leg joints, so the surface
stays continuous where they meet the arms, neck and feet.
"""
from __future__ import annotations

import numpy as np

from ..errors import InputError

SHAPE_CHOICES = ("average", "random")
CLOTHING = ("none", "tight", "loose")
#: Offset of tight clothing (m).
TIGHT_OFFSET = 0.005
#: Range of the offset of loose clothing (m).
LOOSE_OFFSET = (0.01, 0.04)
#: Joints whose surface the clothing covers: trunk and legs (shirt and trousers).
CLOTHED_JOINTS = ("pelvis", "spine", "l_hip", "l_knee", "r_hip", "r_knee")


def mesh_neighbours(faces, n_vertices):
    """Sparse row-normalised vertex adjacency ``(V, V)`` of a triangle mesh (for smoothing)."""
    from scipy import sparse

    f = np.asarray(faces, np.int64)
    a = np.concatenate([f[:, 0], f[:, 1], f[:, 2], f[:, 1], f[:, 2], f[:, 0]])
    b = np.concatenate([f[:, 1], f[:, 2], f[:, 0], f[:, 0], f[:, 1], f[:, 2]])
    adj = sparse.csr_matrix((np.ones(len(a)), (a, b)), shape=(n_vertices, n_vertices))
    adj.data[:] = 1.0
    deg = np.asarray(adj.sum(axis=1)).ravel()
    return sparse.diags(1.0 / np.maximum(deg, 1.0)) @ adj


def smooth_field(values, neighbours, iterations: int):
    """``values (V,)`` averaged with their mesh neighbours ``iterations`` times (half-and-half steps)."""
    v = np.asarray(values, float)
    for _ in range(iterations):
        v = 0.5 * v + 0.5 * (neighbours @ v)
    return v


def clothing_offsets(mesh, clothing: str, seed: int = 0):
    """Per-vertex outward offset (m, at the mesh's own size) of ``clothing``: ``(V,)`` float.

    Parameters
    ----------
    mesh : SkinnedMesh
    clothing : {"none", "tight", "loose"}
    seed : int
        Seeds the loose clothing's random field.
    """
    from ..body.skeleton import JOINT_ID

    if clothing not in CLOTHING:
        raise InputError(None, f"unknown clothing {clothing!r}; choose from {', '.join(CLOTHING)}")
    n = mesh.num_vertices
    if clothing == "none":
        return np.zeros(n)
    covered = np.isin(mesh.joints, [JOINT_ID[j] for j in CLOTHED_JOINTS])
    region = np.sum(np.where(covered, mesh.weights, 0.0), axis=1)        # 1 inside, 0 outside
    nb = mesh_neighbours(mesh.faces, n)
    region = np.clip(smooth_field(region, nb, 4), 0.0, 1.0)
    if clothing == "tight":
        return TIGHT_OFFSET * region
    rng = np.random.default_rng(int(seed) + 7919)
    field = smooth_field(rng.random(n), nb, 60)
    lo, hi = np.percentile(field, [2, 98])
    field = np.clip((field - lo) / max(hi - lo, 1e-9), 0.0, 1.0)
    return (LOOSE_OFFSET[0] + (LOOSE_OFFSET[1] - LOOSE_OFFSET[0]) * field) * region


def clothed_mesh(mesh, clothing: str, seed: int = 0, scale: float = 1.0):
    """``mesh`` with its vertices moved out along their normals by :func:`clothing_offsets`
    (divided by ``scale``, the body's uniform scale, so the offsets are metres on the
    scaled body); the same mesh when ``clothing`` is "none"."""
    from ..body.mesh import SkinnedMesh

    offsets = clothing_offsets(mesh, clothing, seed) / float(scale)
    if not np.any(offsets):
        return mesh
    normals = mesh.vertex_normals()
    vertices = mesh.vertices + offsets[:, None] * normals
    return SkinnedMesh(vertices, mesh.faces, mesh.joints, mesh.weights, mesh.inverse_bind,
                       name=f"{mesh.name}+{clothing}-clothing")


def load_shape(choice, seed=None):
    """``(height_m or None, BodyShape, description dict)`` for ``--shape``.

    ``average``: the default proportions; ``random``: :func:`~depthtrack.body.shape.random_person`
    with ``seed`` (default 0), whose height is used unless one is given; a path: a JSON file
    with the shape fields (or a ``body.json`` / object with a ``shape`` block; its
    ``height_m`` is used unless one is given).
    """
    import json
    from pathlib import Path

    from ..body.shape import BodyShape, random_person

    if choice in (None, "average"):
        return None, BodyShape(), {"source": "average"}
    if choice == "random":
        seed = 0 if seed is None else int(seed)
        height, shape = random_person(seed)
        return height, shape, {"source": "random", "seed": seed}
    path = Path(choice)
    if not path.is_file():
        raise InputError(path, "--shape must be average, random or a JSON file of shape fields "
                               "(no such file)")
    shape = BodyShape.from_json(path)
    height = None
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        h = data.get("height_m") if isinstance(data, dict) else None
        height = float(h) if isinstance(h, (int, float)) and 0.5 < h < 3.0 else None
    except (OSError, ValueError):
        pass
    return height, shape, {"source": "file", "file": path.name}


def make_subject(height=None, shape="average", shape_seed=None, clothing="none", mesh="full"):
    """The synthetic subject: ``(body, description)``.

    Parameters
    ----------
    height : float or None
        Standing height (m); None = the shape's (random / file) or 1.75.
    shape : "average", "random", a JSON path, or a BodyShape
    shape_seed : int or None
        Seed of ``random`` (and of the loose clothing's field); default 0.
    clothing : {"none", "tight", "loose"}

    Returns
    -------
    body : BodyModel
        Built with the shape, at the height, with the clothed surface.
    description : dict
        For ``sequence.json`` ``synth.shape``: source, seed, height, relative scales, segment
        lengths (m) and clothing -- the ground truth of the subject's build.
    """
    from ..body import BodyModel
    from ..body.shape import BodyShape

    if clothing not in CLOTHING:
        raise InputError(None, f"unknown clothing {clothing!r}; choose from {', '.join(CLOTHING)}")
    if isinstance(shape, BodyShape):
        drawn_height, body_shape, info = None, shape, {"source": "given"}
    else:
        drawn_height, body_shape, info = load_shape(shape, shape_seed)
    h = float(height) if height is not None else (drawn_height or 1.75)
    if not (np.isfinite(h) and h > 0):
        raise InputError(None, f"height must be a positive number of metres, got {h}")
    body = BodyModel.default(height=h, mesh=mesh, shape=body_shape)
    seed = 0 if shape_seed is None else int(shape_seed)
    if clothing != "none":
        body = body.with_mesh(clothed_mesh(body.mesh, clothing, seed, body.scale))
    description = {**info, "height_m": round(float(body.height), 4),
                   "scales": body_shape.to_dict(),
                   "segment_lengths_m": body.segment_lengths(),
                   "clothing": {"kind": clothing,
                                **({"offset_m": TIGHT_OFFSET} if clothing == "tight" else {}),
                                **({"offset_range_m": list(LOOSE_OFFSET), "seed": seed}
                                   if clothing == "loose" else {}),
                                **({"covers": list(CLOTHED_JOINTS)} if clothing != "none" else {})}}
    return body, description


__all__ = ["SHAPE_CHOICES", "CLOTHING", "make_subject", "load_shape", "clothed_mesh",
           "clothing_offsets", "mesh_neighbours", "smooth_field"]
