"""``BodyModel``: skeleton + skinned mesh + body dimensions, posed in batches."""
from __future__ import annotations

import functools
import json
from importlib import resources
from pathlib import Path

import numpy as np

from ..contract import JOINT_NAMES
from .mesh import SkinnedMesh, linear_blend_skinning
from .shape import BodyShape, read_json_source, segment_lengths, shaped_offsets, surface_maps
from .skeleton import (CONTRACT_SOURCE, DOF, JOINTS, JOINT_ID, LOWER, NUM_JOINTS, PARENTS,
                       POSE_NAMES, UPPER, as_batch, children_of, forward_kinematics)

#: Level-of-detail names of the shipped default mesh and their files in depthtrack/data/meshes/.
DEFAULT_MESH_FILES = {"full": "body_full.glb", "decimated": "body_decimated.glb",
                      "coarse": "body_coarse.glb"}

#: ``format`` of a body description (:meth:`BodyModel.to_json`, a track's ``body.json``).
BODY_FORMAT = "depthtrack-body/1"

#: Keys accepted in ``segment_scale``: a joint name stretches the bone that ends at that
#: joint (``"l_knee"``: the left thigh); ``"head"`` stretches neck-to-head-centre.
SEGMENT_KEYS = tuple(JOINTS[1:]) + ("head",)


def default_mesh_path(lod="full") -> Path:
    """Path of the shipped default body mesh for ``lod`` ("full", "decimated" or "coarse":
    about 6,000, 1,000 and 500 triangles, ``tools/make_body_mesh.py``)."""
    if lod not in DEFAULT_MESH_FILES:
        raise ValueError(f"mesh must be one of {sorted(DEFAULT_MESH_FILES)}, got {lod!r}")
    return Path(str(resources.files("depthtrack") / "data" / "meshes" / DEFAULT_MESH_FILES[lod]))


@functools.lru_cache(maxsize=8)
def _load_cached(path: str):
    from .gltf import load_skinned_gltf
    return load_skinned_gltf(path)


class BodyModel:
    """An articulated, skinned human body: 15 ball joints, 48 pose parameters.

    The pose layout, frame and joint conventions are in :mod:`depthtrack.body.skeleton`.
    Inputs are ``(N, D)`` or ``(D,)`` pose arrays; outputs drop the N axis for ``(D,)``.

    Parameters
    ----------
    mesh : SkinnedMesh
        The surface and its skin, bound at the zero pose of the *unscaled* skeleton.
    offsets : (J, 3) float
        Bone offsets of the unscaled skeleton (joint position minus parent's at the zero pose).
    head_offset : (3,) float
        Head centre in the neck's frame (unscaled).
    scale : float
        Uniform scale applied to bones and surface.
    segment_scale : dict {str: float}
        Per-bone stretch (see :data:`SEGMENT_KEYS`), applied on top of ``scale``.
    lods : dict {str: SkinnedMesh or path}
        Other meshes bound to the same skeleton, for :meth:`with_mesh`.
    shape : BodyShape or None
        Relative proportions (:mod:`depthtrack.body.shape`), applied before ``scale`` and
        ``segment_scale``; None = the mesh's own.

    Scaling: a bone ending at joint c is stretched by ``f_c`` and the surface that the
    parent joint j moves is stretched by ``f_c`` along that bone's rest direction, via a
    per-joint linear map ``S_j = scale * (I + sum_c (f_c - 1) d_c d_c^T)`` applied in the
    joint's bind frame: ``skin_matrices = world @ S @ inverse_bind``. The mesh vertex
    buffer is the same for every scaled copy; ``rest_vertices`` gives the scaled shape.
    Stretching a bone whose parent has several children (``spine``, ``l_hip`` under the
    pelvis; ``neck``, shoulders under the spine) also stretches the parent's other
    vertices along that direction -- an approximation at the few centimetres around the
    parent joint. A ``shape`` adds its per-joint maps ``L_j``
    (:func:`~depthtrack.body.shape.surface_maps`): ``S_j = scale * stretch_j @ L_j`` and
    bone offsets ``L_parent @ base_offset`` (before the stretch).
    """

    def __init__(self, mesh: SkinnedMesh, offsets, head_offset, scale=1.0, segment_scale=None,
                 lods=None, mesh_name="full", height_mesh=None, shape=None):
        offsets = np.asarray(offsets, dtype=np.float64)
        if offsets.shape != (NUM_JOINTS, 3):
            raise ValueError(f"offsets must be ({NUM_JOINTS}, 3)")
        if mesh.inverse_bind.shape != (NUM_JOINTS, 4, 4):
            raise ValueError(f"mesh.inverse_bind must be ({NUM_JOINTS}, 4, 4)")
        if not (np.isfinite(scale) and scale > 0):
            raise ValueError("scale must be a positive number")
        seg = dict(segment_scale or {})
        for key, f in seg.items():
            if key not in SEGMENT_KEYS:
                raise ValueError(f"unknown segment {key!r}; expected one of {SEGMENT_KEYS}")
            if not (np.isfinite(f) and f > 0):
                raise ValueError(f"segment scale for {key!r} must be positive, got {f}")
        self.mesh = mesh
        self.mesh_name = mesh_name
        self.base_offsets = offsets.copy()
        self.base_head_offset = np.asarray(head_offset, dtype=np.float64).copy()
        self.scale = float(scale)
        self.segment_scale = seg
        if shape is not None and not isinstance(shape, BodyShape):
            raise ValueError(f"shape must be a BodyShape, got {type(shape).__name__}")
        self.shape = shape or BodyShape()
        self._lods = dict(lods or {})
        self._lods.setdefault(mesh_name, mesh)

        factors = np.ones(NUM_JOINTS)
        for key, f in seg.items():
            if key != "head":
                factors[JOINT_ID[key]] = f
        maps = surface_maps(self.shape, self.base_offsets, self.base_head_offset)
        shaped, shaped_head = shaped_offsets(maps, self.base_offsets, self.base_head_offset, PARENTS)
        self.offsets = self.scale * factors[:, None] * shaped
        self.head_offset = self.scale * seg.get("head", 1.0) * shaped_head
        self.bone_scale = self._scale_matrices(factors, seg.get("head", 1.0), shaped, shaped_head, maps)
        self._scaled_inverse_bind = self.bone_scale @ mesh.inverse_bind
        self._rest_vertices = None
        # the mesh whose extent defines `height`, shared by all levels of detail so
        # that a full and a decimated body of the same height have the same skeleton
        self._height_mesh = mesh if height_mesh is None else height_mesh

    # ------------------------------------------------------------------ construction
    @classmethod
    def default(cls, height=1.75, mesh="full", shape=None):
        """The shipped default body scaled to ``height`` metres, with ``mesh`` "full", "decimated"
        or "coarse".

        ``shape``: a :class:`~depthtrack.body.shape.BodyShape` (relative proportions); the
        body is then scaled so that its standing height is still ``height``.
        """
        loaded = _load_cached(str(default_mesh_path("full")))
        lods = {name: default_mesh_path(name) for name in DEFAULT_MESH_FILES}
        lods["full"] = loaded.mesh
        body = cls(loaded.mesh, loaded.offsets, loaded.head_offset, lods=lods, mesh_name="full",
                   shape=shape)
        body = body.scaled(height=height)
        return body if mesh == "full" else body.with_mesh(mesh)

    @classmethod
    def from_gltf(cls, path, height=None):
        """A body from a rigged glTF/glb file whose joints map onto ours (see :mod:`.gltf`).

        The file's bind pose becomes this body's zero pose. ``height`` (metres) rescales it;
        ``None`` keeps the file's size.
        """
        from .gltf import load_skinned_gltf
        loaded = load_skinned_gltf(path)
        body = cls(loaded.mesh, loaded.offsets, loaded.head_offset, mesh_name="file",
                   lods={"file": loaded.mesh})
        return body if height is None else body.scaled(height=height)

    def _copy(self, mesh=None, scale=None, segment_scale=None, mesh_name=None, shape=None):
        return BodyModel(self.mesh if mesh is None else mesh, self.base_offsets, self.base_head_offset,
                         scale=self.scale if scale is None else scale,
                         segment_scale=self.segment_scale if segment_scale is None else segment_scale,
                         lods=self._lods, mesh_name=self.mesh_name if mesh_name is None else mesh_name,
                         height_mesh=self._height_mesh, shape=self.shape if shape is None else shape)

    def shaped(self, shape, height=None):
        """A copy with another :class:`~depthtrack.body.shape.BodyShape` (None = average).

        ``height`` None keeps the uniform scale (so a longer thigh makes the body taller);
        a number rescales the shaped body to that standing height (metres).
        """
        body = self._copy(shape=BodyShape() if shape is None else shape)
        return body if height is None else body.scaled(height=height)

    def scaled(self, height=None, segment_scale=None):
        """A copy with other body dimensions.

        Parameters
        ----------
        height : float or None
            Standing height in metres (top of head to sole at the zero pose, segment
            stretch included); ``None`` keeps the current uniform scale.
        segment_scale : dict {segment: factor} or None
            Replaces the per-bone stretch; ``None`` keeps the current one.
        """
        seg = self.segment_scale if segment_scale is None else dict(segment_scale)
        if height is None:
            return self._copy(segment_scale=seg)
        height = float(height)
        if not (np.isfinite(height) and height > 0):
            raise ValueError(f"height must be a positive number of metres, got {height}")
        unit = self._copy(scale=1.0, segment_scale=seg)
        return self._copy(scale=height / unit.height, segment_scale=seg)

    def with_mesh(self, mesh):
        """A copy with another mesh of the same skeleton: "full", "decimated", "coarse" or a
        SkinnedMesh."""
        if isinstance(mesh, SkinnedMesh):
            return self._copy(mesh=mesh, mesh_name=mesh.name)
        if mesh not in self._lods:
            raise ValueError(f"no mesh {mesh!r} for this body; have {sorted(self._lods)}")
        found = self._lods[mesh]
        if not isinstance(found, SkinnedMesh):
            found = _load_cached(str(found)).mesh
            self._lods[mesh] = found
        return self._copy(mesh=found, mesh_name=mesh)

    def _scale_matrices(self, factors, head_factor, offsets, head_offset, maps):
        """Per-joint bind-frame stretch ``S (J, 4, 4)``: ``scale * stretch @ L`` (class docstring),
        ``offsets (J, 3)``, ``head_offset (3,)`` the shaped ones, ``maps (J, 3, 3)`` the shape's."""
        kids = children_of(PARENTS)
        S = np.zeros((NUM_JOINTS, 4, 4))
        for j in range(NUM_JOINTS):
            lin = np.eye(3)
            stretches = [(offsets[c], factors[c]) for c in kids[j]]
            if j == JOINT_ID["neck"]:
                stretches.append((head_offset, head_factor))
            bind_rot = self.mesh.inverse_bind[j, :3, :3]
            for vec, f in stretches:
                n = np.linalg.norm(vec)
                if f != 1.0 and n > 0:
                    d = bind_rot @ (vec / n)
                    lin = lin + (f - 1.0) * np.outer(d, d)
            # the shape's map is given in the model frame: move it into the joint's bind frame
            lin = lin @ (bind_rot @ maps[j] @ bind_rot.T)
            S[j, :3, :3] = self.scale * lin
            S[j, 3, 3] = 1.0
        return S

    # ------------------------------------------------------------------ description
    joint_names = JOINTS
    parents = PARENTS
    pose_names = POSE_NAMES
    lower = LOWER
    upper = UPPER
    dof = DOF

    @property
    def faces(self):
        """``(F, 3) int32`` triangles of the current mesh."""
        return self.mesh.faces

    @property
    def rest_vertices(self):
        """``(V, 3)`` float64 surface of this (scaled) body at the zero pose."""
        if self._rest_vertices is None:
            self._rest_vertices = self.posed_vertices(np.zeros(DOF))
        return self._rest_vertices

    @property
    def reference_mesh(self):
        """The mesh that defines :attr:`height` (the full one for the default body)."""
        return self._height_mesh

    def segment_lengths(self) -> dict:
        """Segment lengths in metres (:func:`depthtrack.body.shape.segment_lengths`)."""
        return segment_lengths(self)

    def to_dict(self) -> dict:
        """What rebuilds this body (:meth:`from_json`) and what it measures; JSON-serialisable."""
        return {"format": BODY_FORMAT, "mesh": self.mesh_name, "height_m": round(self.height, 5),
                "scale": self.scale, "shape": self.shape.to_dict(),
                "segment_scale": {k: float(v) for k, v in self.segment_scale.items()},
                "segment_lengths_m": self.segment_lengths()}

    def to_json(self) -> str:
        """:meth:`to_dict` as JSON text (a track's ``body.json``)."""
        return json.dumps(self.to_dict(), indent=1) + "\n"

    @classmethod
    def from_json(cls, source):
        """Rebuild a default-mesh body from ``body.json`` (a path) or its text / dict.

        Raises
        ------
        InputError
            Unreadable file, wrong format, a body not built on the shipped default mesh.
        """
        from ..errors import InputError

        data, path = read_json_source(source if isinstance(source, (dict, Path)) else str(source), "body")
        if not isinstance(data, dict) or data.get("format") != BODY_FORMAT:
            raise InputError(path, f"not a body file (expected \"format\": \"{BODY_FORMAT}\")")
        mesh = data.get("mesh", "full")
        if mesh not in DEFAULT_MESH_FILES:
            raise InputError(path, f"the body was built on mesh {mesh!r}; only the shipped meshes "
                                   f"({', '.join(DEFAULT_MESH_FILES)}) can be rebuilt")
        shape = BodyShape.from_dict(data.get("shape") or {}, path)
        seg = data.get("segment_scale") or {}
        scale = data.get("scale")
        try:
            body = cls.default(mesh="full")._copy(shape=shape, segment_scale=seg, scale=1.0)
            if isinstance(scale, (int, float)) and scale > 0:
                body = body._copy(scale=float(scale))
            else:
                body = body.scaled(height=float(data["height_m"]))
        except (KeyError, TypeError, ValueError) as exc:
            raise InputError(path, f"bad body description: {exc}") from None
        return body if mesh == "full" else body.with_mesh(mesh)

    @property
    def height(self):
        """Standing height in metres: vertical extent of the surface at the zero pose.

        Measured on the body's reference mesh (the full one for the default body), so
        every level of detail of one body reports the same height.
        """
        m = self._height_mesh
        skin = forward_kinematics(np.zeros((1, DOF)), self.offsets, PARENTS) @ (self.bone_scale @ m.inverse_bind)
        y = linear_blend_skinning(m.vertices, m.joints, m.weights, skin)[0, :, 1]
        return float(y.max() - y.min())

    def clip(self, poses):
        """Poses with every parameter clipped to ``[lower, upper]``; same shape as ``poses``."""
        return np.clip(np.asarray(poses, dtype=np.float64), LOWER, UPPER)

    def default_pose(self, position=(0.0, 0.0, 0.0)):
        """The zero (A-) pose with the pelvis at ``position (3,)`` (camera frame, metres): ``(D,)``."""
        pose = np.zeros(DOF)
        pose[0:3] = position
        return pose

    # ------------------------------------------------------------------ posing
    def world_transforms(self, poses):
        """``(N, J, 4, 4)`` float64 joint-to-world transforms."""
        p, single = as_batch(poses)
        out = forward_kinematics(p, self.offsets, PARENTS)
        return out[0] if single else out

    def skin_matrices(self, poses):
        """``(N, J, 4, 4)`` float32 ``world @ scale @ inverse_bind``: bind-pose model frame to world."""
        p, single = as_batch(poses)
        out = (forward_kinematics(p, self.offsets, PARENTS) @ self._scaled_inverse_bind).astype(np.float32)
        return out[0] if single else out

    def joint_positions(self, poses):
        """``(N, 15, 3)`` float64 positions of the contract joints (``JOINT_NAMES`` order)."""
        p, single = as_batch(poses)
        world = forward_kinematics(p, self.offsets, PARENTS)
        out = world[:, np.maximum(CONTRACT_SOURCE, 0)][:, :, :3, 3].copy()
        neck = world[:, JOINT_ID["neck"]]
        out[:, JOINT_NAMES.index("head")] = neck[:, :3, :3] @ self.head_offset + neck[:, :3, 3]
        return out[0] if single else out

    def posed_vertices(self, poses):
        """``(N, V, 3)`` float64 linear-blend skinning of the mesh with :meth:`skin_matrices`.

        This is the numpy reference of what the GPU renders: the same float32 matrices,
        applied in float64.
        """
        p, single = as_batch(poses)
        skin = self.skin_matrices(p)
        out = linear_blend_skinning(self.mesh.vertices, self.mesh.joints, self.mesh.weights, skin)
        return out[0] if single else out

    def __repr__(self):
        shaped = "" if self.shape.is_average else ", shaped"
        return (f"BodyModel(height={self.height:.3f} m{shaped}, mesh={self.mesh_name!r}: "
                f"{self.mesh.num_vertices} vertices, {self.mesh.num_faces} faces)")
