"""Many candidate poses rendered at once into tiles of one texture, and scored there.

:class:`TileRenderer` draws N candidate poses of a skinned body in one instanced draw call
per atlas (``gl_InstanceID`` picks the candidate's bone matrices and its tile), each tile
showing the same square region of interest (ROI) of the camera image. A compute pass then
scores every tile against the observed ROI with the sensor model of
:mod:`depthtrack.likelihood` and reduces it to its mean in the same work group, so one
``(N,)`` float array is all that comes back from the GPU.
"""
from __future__ import annotations

import numpy as np

from ..camera import Camera
from ..errors import InputError
from ..likelihood import LikelihoodParams, encode_observation, observation_tile, shader_constants
from .context import compute, gl_context, program

#: Near and far clipping planes of every view (metres).
DEPTH_RANGE = (0.05, 50.0)
#: Most candidates per upload (rows of the bone-matrix texture); larger calls are chunked.
MAX_BATCH = 16384
#: Invocations per work group of the cost pass.
COST_GROUP = 64
#: Pixels of a row scored by one invocation of the cost pass (they share texel fetches).
COST_RUN = 8


def tile_camera(camera: Camera, roi, tile: int) -> Camera:
    """The camera of one tile: ``camera`` restricted to the square ``roi``, scaled to ``tile`` pixels.

    Parameters
    ----------
    camera : Camera
    roi : (u0, v0, size)
        Columns ``u0 .. u0+size-1``, rows ``v0 .. v0+size-1`` of the camera image.
    tile : int

    Returns
    -------
    Camera
        ``tile x tile`` pixels; tile pixel centres lie where :func:`observation_tile` samples.
    """
    u0, v0, size = (float(x) for x in roi)
    s = tile / size
    return Camera(tile, tile, camera.fx * s, camera.fy * s,
                  (camera.cx - u0 + 0.5) * s - 0.5, (camera.cy - v0 + 0.5) * s - 0.5)


def full_roi(camera: Camera):
    """The square ROI ``(u0, v0, size)`` that covers the whole image, centred on it."""
    size = max(camera.width, camera.height)
    return ((camera.width - size) / 2.0, (camera.height - size) / 2.0, float(size))


def _set_view(prog, cam: Camera, grid: int):
    prog["u_intrinsics"].value = (cam.fx, cam.fy, cam.cx, cam.cy)
    prog["u_view_size"].value = (float(cam.width), float(cam.height))
    prog["u_depth_range"].value = DEPTH_RANGE
    prog["u_grid"].value = grid


def is_closed_outward(vertices, faces) -> bool:
    """True when a triangle mesh is watertight with consistent outward (counter-clockwise) winding.

    Only then may back faces be culled: the nearest surface along any ray is a front face.
    """
    import trimesh

    mesh = trimesh.Trimesh(np.asarray(vertices, float), np.asarray(faces), process=False)
    return bool(mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0)


#: GL_CLIP_DISTANCE0: glEnable(GL_CLIP_DISTANCE0 + i) turns on the shader's gl_ClipDistance[i].
GL_CLIP_DISTANCE0 = 0x3000
#: How many clip distances ``project.glsl`` writes (the four edges of a tile).
TILE_CLIP_PLANES = 4


def set_draw_state(ctx, cull_back_faces: bool) -> None:
    """Depth test on, the four tile-edge clip planes on, back faces culled when asked.

    The clip planes (``gl_ClipDistance[0..3]`` in ``project.glsl``) keep every candidate
    inside its own tile. GL applies a clip distance only while its ``GL_CLIP_DISTANCEi`` is
    enabled: Mesa's llvmpipe clipped without it, NVIDIA's driver does not, and there the
    candidates bled into their neighbours' tiles (``tests/test_render_tiles.py`` failed on
    an H200). moderngl's ``enable_only`` leaves capabilities it does not know alone, so the
    planes are enabled directly on every draw.

    Our projection writes image row v to framebuffer row v (no flip), which mirrors the
    image vertically, so outward faces wind clockwise on screen: GL's "front" is culled.
    """
    if cull_back_faces:
        ctx.enable_only(ctx.DEPTH_TEST | ctx.CULL_FACE)
        ctx.cull_face = "front"
    else:
        ctx.enable_only(ctx.DEPTH_TEST)
    for plane in range(TILE_CLIP_PLANES):
        ctx.enable_direct(GL_CLIP_DISTANCE0 + plane)


def skinned_vertex_buffer(ctx, mesh):
    """Interleaved (position 3f, joints 4i, weights 4f) vertex buffer and index buffer of a SkinnedMesh."""
    v = np.ascontiguousarray(mesh.vertices, np.float32)
    j = np.ascontiguousarray(mesh.joints, np.int32)
    w = np.ascontiguousarray(mesh.weights, np.float32)
    if not (len(v) == len(j) == len(w)) or j.shape[1] != 4 or w.shape[1] != 4:
        raise InputError(None, "skinned mesh needs vertices (V,3), joints (V,4), weights (V,4)")
    interleaved = np.empty(len(v), dtype=[("p", "f4", 3), ("j", "i4", 4), ("w", "f4", 4)])
    interleaved["p"], interleaved["j"], interleaved["w"] = v, j, w
    vbo = ctx.buffer(interleaved.tobytes())
    ibo = ctx.buffer(np.ascontiguousarray(mesh.faces, np.int32).tobytes())
    return vbo, ibo


class TileRenderer:
    """Render and score N candidate poses of ``body`` in tiles of one texture.

    Parameters
    ----------
    body : BodyModel
        Anything with ``mesh`` (a SkinnedMesh) and ``skin_matrices(poses) -> (N, J, 4, 4)``.
    camera : Camera
        The depth camera whose image the observation comes from.
    tile : int
        Tile side in pixels, a power of two (4 .. 1024; 32 to 128 are typical).
    params : LikelihoodParams, optional
        Sensor-model parameters of :meth:`costs`.
    max_atlas : int
        Largest atlas side in pixels; a batch that does not fit is drawn in several passes.

    Attributes
    ----------
    tile_camera : Camera
        The view of one tile (the camera restricted to the ROI, mapped onto the tile).
    roi : (u0, v0, size)
        The current region of interest in camera pixels.
    """

    def __init__(self, body, camera: Camera, tile: int = 64, params: LikelihoodParams | None = None,
                 max_atlas: int = 1024):
        if tile < 4 or tile > 1024 or tile & (tile - 1):
            raise InputError(None, f"tile size must be a power of two in 4..1024, got {tile}")
        self.ctx = ctx = gl_context()
        self.body = body
        self.camera = camera
        self.tile = int(tile)
        self.params = params or LikelihoodParams()
        self.max_grid = max(1, int(max_atlas) // self.tile)
        self.max_grid = 1 << (self.max_grid.bit_length() - 1)
        self.joint_count = int(np.asarray(body.mesh.inverse_bind).shape[0])

        self._prog = program("skin_depth.vert", "depth.frag")
        # culling halves the triangles llvmpipe sets up; only safe for closed meshes
        self.cull_back_faces = is_closed_outward(body.mesh.vertices, body.mesh.faces)
        vbo, ibo = skinned_vertex_buffer(ctx, body.mesh)
        self._vao = ctx.vertex_array(self._prog, [(vbo, "3f 4i 4f", "in_position", "in_joints",
                                                   "in_weights")], index_buffer=ibo,
                                     index_element_size=4)
        self._buffers = [vbo, ibo]
        side = self.max_grid * self.tile
        self._atlas = ctx.texture((side, side), 1, dtype="f4")
        self._atlas.filter = (ctx.NEAREST, ctx.NEAREST)
        self._depth = ctx.depth_renderbuffer((side, side))
        self._fbo = ctx.framebuffer(color_attachments=[self._atlas], depth_attachment=self._depth)
        self._observed = ctx.texture((self.tile, self.tile), 2, dtype="f4")
        self._observed.filter = (ctx.NEAREST, ctx.NEAREST)
        self._bones = None          # RGBA32F texture (4 J, capacity), grown on demand
        self._costs = ctx.buffer(reserve=64 * 4)
        self._cost_pass = {}
        self.roi = None
        self.tile_camera = None
        self.observed_tile = None
        self.background_tile = None
        self.set_roi(full_roi(camera))

    # ------------------------------------------------------------------ observation / ROI
    def set_roi(self, roi) -> None:
        """Point every tile at the square ``roi`` = (u0, v0, size) in camera pixels."""
        roi = tuple(float(x) for x in roi)
        if len(roi) != 3 or not np.all(np.isfinite(roi)) or roi[2] <= 0:
            raise InputError(None, f"roi must be (u0, v0, size) with size > 0, got {roi}")
        self.roi = roi
        self.tile_camera = tile_camera(self.camera, roi, self.tile)

    def set_observation(self, depth, roi=None, background=None) -> None:
        """Upload the observed frame, resampled once into the tile grid of ``roi``.

        Parameters
        ----------
        depth : (H, W) float
            Observed camera z, metres; 0 = no reading; inf or >= params.max_depth = background.
        roi : (u0, v0, size), optional
            Square region of interest in camera pixels; None = the whole image (centred square).
        background : (H, W) float, optional
            Depth of the static scene (0 = unknown): observed pixels at that depth cost nothing
            where the model is absent (see :mod:`depthtrack.likelihood`).
        """
        depth = np.asarray(depth, dtype=np.float32)
        if depth.shape != self.camera.shape:
            raise InputError(None, f"observed depth is {depth.shape[1]} x {depth.shape[0]}, "
                                   f"camera is {self.camera.width} x {self.camera.height}")
        self.set_roi(full_roi(self.camera) if roi is None else roi)
        self.observed_tile = observation_tile(depth, self.roi, self.tile)
        self.background_tile = None if background is None else \
            observation_tile(np.asarray(background, np.float32), self.roi, self.tile)
        encoded = encode_observation(self.observed_tile, self.params, self.background_tile)
        self._observed.write(np.ascontiguousarray(encoded).tobytes())

    # ------------------------------------------------------------------ rendering
    def _upload_bones(self, poses) -> int:
        poses = np.asarray(poses, dtype=np.float64)
        if poses.ndim != 2:
            raise InputError(None, f"poses must be (N, D), got shape {poses.shape}")
        n = len(poses)
        mats = np.ascontiguousarray(self.body.skin_matrices(poses), dtype=np.float32)
        if self._bones is None or self._bones.height < n:
            if self._bones is not None:
                self._bones.release()
            capacity = min(MAX_BATCH, max(n, 256, 0 if self._bones is None else 2 * self._bones.height))
            self._bones = self.ctx.texture((4 * self.joint_count, capacity), 4, dtype="f4")
            self._bones.filter = (self.ctx.NEAREST, self.ctx.NEAREST)
        self._bones.write(mats.tobytes(), viewport=(0, 0, 4 * self.joint_count, n))
        self._bones.use(3)
        return n

    def _passes(self, n: int):
        """(first candidate, count, grid) of each atlas pass for a batch of n candidates."""
        per_pass = self.max_grid * self.max_grid
        for first in range(0, n, per_pass):
            count = min(per_pass, n - first)
            grid = 1
            while grid * grid < count:
                grid *= 2
            yield first, count, grid

    def _draw(self, first: int, count: int, grid: int) -> None:
        side = grid * self.tile
        self._fbo.use()
        self._fbo.viewport = (0, 0, side, side)
        self._fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0, viewport=(0, 0, side, side))
        set_draw_state(self.ctx, self.cull_back_faces)
        # programs are shared between renderers: set this renderer's view every pass
        _set_view(self._prog, self.tile_camera, grid)
        self._prog["u_first"].value = first
        self._vao.render(instances=count)

    def render_depth(self, poses) -> np.ndarray:
        """Camera z of each candidate in the current ROI.

        Parameters
        ----------
        poses : (N, D) float

        Returns
        -------
        depth : (N, tile, tile) float32, 0 where nothing is drawn
        """
        poses = np.asarray(poses, dtype=np.float64)
        if poses.ndim == 2 and len(poses) == 0:
            return np.zeros((0, self.tile, self.tile), np.float32)
        if poses.ndim == 2 and len(poses) > MAX_BATCH:
            return np.concatenate([self.render_depth(poses[i:i + MAX_BATCH])
                                   for i in range(0, len(poses), MAX_BATCH)])
        n = self._upload_bones(poses)
        t = self.tile
        out = np.empty((n, t, t), np.float32)
        for first, count, grid in self._passes(n):
            self._draw(first, count, grid)
            side = grid * t
            atlas = np.frombuffer(self._fbo.read(viewport=(0, 0, side, side), components=1,
                                                 dtype="f4"), np.float32)
            tiles = atlas.reshape(grid, t, grid, t).transpose(0, 2, 1, 3).reshape(-1, t, t)
            out[first:first + count] = tiles[:count]
        return out

    def _cost_program(self, smoothed: bool):
        key = bool(smoothed)
        if key not in self._cost_pass:
            self._cost_pass[key] = compute("tile_cost.comp", {
                "TILE": self.tile, "SMOOTHED": int(key), "GROUP": COST_GROUP,
                "RUN": min(COST_RUN, self.tile), **shader_constants(self.params)})
        return self._cost_pass[key]

    def costs(self, poses, observed_depth=None, smoothed: bool = True, roi=None) -> np.ndarray:
        """Mean per-pixel cost of each candidate against the observation (lower is better).

        Parameters
        ----------
        poses : (N, D) float
        observed_depth : (H, W) float, optional
            Passed to :meth:`set_observation` (with ``roi``) first when given.
        smoothed : bool
            Smoothed likelihood (True) or the pixel-wise sensor cost (False).
        roi : (u0, v0, size), optional
            Only with ``observed_depth``: the ROI to resample it into (None = whole image).

        Returns
        -------
        costs : (N,) float64
        """
        if observed_depth is not None:
            self.set_observation(observed_depth, roi)
        if self.observed_tile is None:
            raise InputError(None, "TileRenderer.costs needs an observation: call "
                                   "set_observation(depth) first or pass observed_depth")
        poses = np.asarray(poses, dtype=np.float64)
        if poses.ndim == 2 and len(poses) == 0:
            return np.zeros(0)
        if poses.ndim == 2 and len(poses) > MAX_BATCH:
            return np.concatenate([self.costs(poses[i:i + MAX_BATCH], smoothed=smoothed)
                                   for i in range(0, len(poses), MAX_BATCH)])
        n = self._upload_bones(poses)
        if n * 4 > self._costs.size:
            self._costs.orphan(max(n * 4, 2 * self._costs.size))
        prog = self._cost_program(smoothed)
        self._costs.bind_to_storage_buffer(1)
        for first, count, grid in self._passes(n):
            self._draw(first, count, grid)
            self._atlas.use(0)
            self._observed.use(1)
            prog["u_first"].value = first
            prog["u_grid"].value = grid
            prog.run(group_x=count)
        self.ctx.memory_barrier()
        return np.frombuffer(self._costs.read(size=n * 4), np.float32).astype(np.float64)

    def set_body(self, body) -> None:
        """Render ``body`` from now on; it must have the same mesh (e.g. the same body at
        another height: scaling lives in the skin matrices, the vertex buffer is shared)."""
        if body.mesh is not self.body.mesh and not (
                np.array_equal(body.mesh.vertices, self.body.mesh.vertices)
                and np.array_equal(body.mesh.faces, self.body.mesh.faces)
                and np.array_equal(body.mesh.joints, self.body.mesh.joints)
                and np.array_equal(body.mesh.weights, self.body.mesh.weights)):
            raise ValueError("set_body needs a body with the renderer's mesh")
        self.body = body

    def release(self) -> None:
        """Free the GL objects of this renderer (the shared context and programs stay).

        Idempotent; the renderer is unusable afterwards. ``with TileRenderer(...) as r:``
        releases on leaving the block.
        """
        for obj in [self._vao, *self._buffers, self._fbo, self._atlas, self._depth,
                    self._observed, self._bones, self._costs]:
            if obj is not None:
                obj.release()
        self._vao = self._fbo = self._atlas = self._depth = None
        self._observed = self._bones = self._costs = None
        self._buffers = []

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.release()
