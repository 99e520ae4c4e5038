"""Full-resolution views of one pose with static scenery: depth and part-label images.

Used by the synthesizer (depth frames of a body in a room) and the detector's training
(per-pixel labels of which bone is seen). Same projection and skinning shaders as
:class:`~depthtrack.render.tiles.TileRenderer`, with a single view covering the image.
"""
from __future__ import annotations

import numpy as np

from ..camera import Camera
from ..errors import InputError
from .context import gl_context, program
from .tiles import _set_view, is_closed_outward, set_draw_state, skinned_vertex_buffer

#: Most joints a label image can tell apart (four vec4 varyings of weights).
MAX_LABEL_JOINTS = 16


def _triangles(mesh):
    """(vertices (V, 3) float32, faces (F, 3) int32) of a trimesh, a (V, F) pair or anything with both."""
    if isinstance(mesh, (tuple, list)) and len(mesh) == 2:
        vertices, faces = mesh
    else:
        vertices, faces = getattr(mesh, "vertices", None), getattr(mesh, "faces", None)
    vertices = np.asarray(vertices, np.float32)
    faces = np.asarray(faces, np.int32)
    if vertices.ndim != 2 or vertices.shape[1] != 3 or faces.ndim != 2 or faces.shape[1] != 3 \
            or (faces.size and (faces.min() < 0 or faces.max() >= len(vertices))):
        raise InputError(None, "extra meshes must be triangle meshes: vertices (V, 3), "
                               "faces (F, 3) indexing them")
    return vertices, faces


class FrameRenderer:
    """Render one body pose plus static meshes at the camera's full resolution.

    Parameters
    ----------
    camera : Camera

    Notes
    -----
    Rendered values are camera-frame z at the pixel centres (0 = nothing drawn), matching a
    ray cast through ``camera.rays()``. Static meshes are given in the camera frame.
    """

    def __init__(self, camera: Camera):
        self.ctx = ctx = gl_context()
        self.camera = camera
        size = (camera.width, camera.height)
        self._target = ctx.texture(size, 1, dtype="f4")
        self._depth = ctx.depth_renderbuffer(size)
        self._fbo = ctx.framebuffer(color_attachments=[self._target], depth_attachment=self._depth)
        self._programs = {
            "skin_depth": program("skin_depth.vert", "depth.frag"),
            "skin_labels": program("skin_labels.vert", "labels.frag"),
            "static_depth": program("static.vert", "depth.frag"),
            "static_labels": program("static.vert", "background.frag"),
        }
        self._bodies = {}   # id(mesh) -> (mesh, {program name: vao}, buffers)
        self._bones = None

    def _body_vaos(self, body):
        key = id(body.mesh)
        if key not in self._bodies:
            vbo, ibo = skinned_vertex_buffer(self.ctx, body.mesh)
            vaos = {name: self.ctx.vertex_array(
                        self._programs[name],
                        [(vbo, "3f 4i 4f", "in_position", "in_joints", "in_weights")],
                        index_buffer=ibo, index_element_size=4)
                    for name in ("skin_depth", "skin_labels")}
            cull = is_closed_outward(body.mesh.vertices, body.mesh.faces)
            self._bodies[key] = (body.mesh, vaos, (vbo, ibo), cull)
        return self._bodies[key]

    def _upload_pose(self, body, pose):
        pose = np.asarray(pose, dtype=np.float64)
        if pose.ndim != 1:
            raise InputError(None, f"pose must be (D,), got shape {pose.shape}")
        mats = np.ascontiguousarray(body.skin_matrices(pose[None]), np.float32)[0]
        width = 4 * len(mats)
        if self._bones is None or self._bones.width != width:
            if self._bones is not None:
                self._bones.release()
            self._bones = self.ctx.texture((width, 1), 4, dtype="f4")
            self._bones.filter = (self.ctx.NEAREST, self.ctx.NEAREST)
        self._bones.write(mats.tobytes())
        self._bones.use(3)
        return len(mats)

    def _render(self, body, pose, extra_meshes, labels: bool) -> np.ndarray:
        joints = self._upload_pose(body, pose)
        if labels and joints > MAX_LABEL_JOINTS:
            raise InputError(None, f"label images support at most {MAX_LABEL_JOINTS} joints, "
                                   f"the body has {joints}")
        kind = "labels" if labels else "depth"
        self._fbo.use()
        self._fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
        _, vaos, _, cull = self._body_vaos(body)
        set_draw_state(self.ctx, cull)
        for name in (f"skin_{kind}", f"static_{kind}"):
            _set_view(self._programs[name], self.camera, 1)
        skinned = self._programs[f"skin_{kind}"]
        if "u_first" in skinned:
            skinned["u_first"].value = 0
        vaos[f"skin_{kind}"].render()
        set_draw_state(self.ctx, False)         # scenery may be open or wound either way
        for mesh in extra_meshes:
            vertices, faces = _triangles(mesh)
            if not len(faces):
                continue
            vbo = self.ctx.buffer(vertices.tobytes())
            ibo = self.ctx.buffer(faces.tobytes())
            vao = self.ctx.vertex_array(self._programs[f"static_{kind}"], [(vbo, "3f", "in_position")],
                                        index_buffer=ibo, index_element_size=4)
            vao.render()
            for obj in (vao, vbo, ibo):
                obj.release()
        data = self._fbo.read(components=1, dtype="f4")
        return np.frombuffer(data, np.float32).reshape(self.camera.height, self.camera.width).copy()

    def render(self, body, pose, extra_meshes=()) -> np.ndarray:
        """Depth image of ``body`` in ``pose`` with ``extra_meshes`` drawn too.

        Parameters
        ----------
        body : BodyModel
        pose : (D,) float
        extra_meshes : sequence of trimesh.Trimesh or (vertices (V, 3), faces (F, 3))
            Static scenery in the camera frame (floor, walls).

        Returns
        -------
        depth : (H, W) float32
            Camera z in metres, 0 where nothing is drawn.
        """
        return self._render(body, pose, extra_meshes, labels=False)

    def render_labels(self, body, pose, extra_meshes=()) -> np.ndarray:
        """Which joint's bone dominates the visible body surface at each pixel.

        Parameters
        ----------
        body : BodyModel
        pose : (D,) float
        extra_meshes : as :meth:`render`; they occlude the body and are labelled background.

        Returns
        -------
        labels : (H, W) int16
            Index into ``body.joint_names`` of the joint with the largest interpolated skinning
            weight at the visible surface point (the bone from that joint to its child);
            -1 for background and scenery.
        """
        values = self._render(body, pose, extra_meshes, labels=True)
        return (np.rint(values).astype(np.int16) - 1)

    def release(self) -> None:
        """Free this renderer's GL objects (the shared context and programs stay); idempotent.

        ``with FrameRenderer(camera) as r:`` releases on leaving the block.
        """
        for _, vaos, buffers, _ in self._bodies.values():
            for obj in (*vaos.values(), *buffers):
                obj.release()
        self._bodies.clear()
        for obj in (self._fbo, self._target, self._depth, self._bones):
            if obj is not None:
                obj.release()
        self._fbo = self._target = self._depth = self._bones = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.release()
