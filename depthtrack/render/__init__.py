"""OpenGL rendering: the shared EGL context, the tiled candidate renderer, full frames.

``from depthtrack.render import TileRenderer, FrameRenderer, gl_context``

* :func:`gl_context` -- the process-wide moderngl context (EGL; GPU or Mesa llvmpipe).
* :class:`TileRenderer` ``(body, camera, tile=64)`` -- N candidate poses rendered in one
  instanced pass into tiles of one atlas texture, scored against an observed depth frame
  by the robust / smoothed likelihood of :mod:`depthtrack.likelihood` in a compute pass
  that also reduces each tile to its mean: ``set_observation(depth, roi)``,
  ``costs(poses) -> (N,)``, ``render_depth(poses) -> (N, tile, tile)``, ``tile_camera``.
* :class:`FrameRenderer` ``(camera)`` -- one pose at full resolution with static scenery:
  ``render(body, pose, extra_meshes) -> (H, W)`` depth, ``render_labels`` part labels.
* :func:`~depthtrack.render.tiles_figure.write_tiles_figure` -- PNG mosaic of tiles + costs.
* :func:`~depthtrack.render.raycast.raycast_depth` -- the CPU ray-cast reference.

Shaders live in ``depthtrack/shaders/`` (package data).
"""
from .context import GLUnavailableError, gl_context, gl_info, gl_renderer
from .frame import FrameRenderer
from .tiles import TileRenderer, full_roi, tile_camera

__all__ = ["GLUnavailableError", "gl_context", "gl_info", "gl_renderer", "TileRenderer", "FrameRenderer",
           "full_roi", "tile_camera"]
