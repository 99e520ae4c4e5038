"""The GL renderers one tracker scores with, owned together and released together."""
from __future__ import annotations

import numpy as np


class RendererSet:
    """The candidate renderer, the polish's finer one, the rechecks' renderers at other tile
    sides (made when first asked for: :meth:`at_tile`) and the full-frame silhouette renderer.

    One owner releases them (:meth:`release`, or ``with``). Bodies that share a mesh (the
    default body at any height) share a set: :meth:`set_body`; so the height fit scores
    every height with the same GL objects.

    Parameters
    ----------
    body : BodyModel
        The render body (the decimated mesh).
    camera : Camera
    tile : int
    fine_tile : int
        0 or equal to ``tile``: no fine renderer.
    coarse : TileRenderer, optional
        A candidate renderer of the caller's (then ``tile`` is its tile); it stays the
        caller's to release.
    """

    def __init__(self, body, camera, tile: int, fine_tile: int = 0, coarse=None):
        from ..render import TileRenderer

        self.camera = camera
        self.body = body
        self._own_coarse = coarse is None
        self.coarse = TileRenderer(body, camera, tile=tile) if coarse is None else coarse
        tile = self.coarse.tile
        self.fine = None
        try:
            if fine_tile and fine_tile != tile:
                self.fine = TileRenderer(body, camera, tile=fine_tile)
        except BaseException:
            if self._own_coarse:
                self.coarse.release()
            raise
        self._frame = None
        self._others = {}           # tile side -> TileRenderer made by at_tile
        self._uploaded = None       # the last frame uploaded, for a renderer made later

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.release()

    def set_body(self, body) -> None:
        """Score ``body`` from now on (it must share the mesh of the set's body)."""
        self.body = body
        for r in (self.coarse, self.fine, *self._others.values()):
            if r is not None:
                r.set_body(body)

    def upload(self, frame) -> None:
        """Make ``frame`` (:class:`~.observe.Frame`) the observation every renderer scores against."""
        self._uploaded = frame
        for r in (self.coarse, self.fine, *self._others.values()):
            if r is not None:
                r.set_observation(frame.observed, roi=frame.roi)

    @property
    def uploaded(self):
        """The :class:`~.observe.Frame` uploaded last (None before the first)."""
        return self._uploaded

    def at_tile(self, tile: int):
        """The candidate renderer at ``tile`` pixels (0 = :attr:`coarse`), scoring the last
        uploaded frame; made on the first call and owned by the set."""
        if not tile or tile == self.coarse.tile:
            return self.coarse
        if self.fine is not None and tile == self.fine.tile:
            return self.fine
        if tile not in self._others:
            from ..render import TileRenderer

            renderer = TileRenderer(self.body, self.camera, tile=tile)
            if self._uploaded is not None:
                renderer.set_observation(self._uploaded.observed, roi=self._uploaded.roi)
            self._others[tile] = renderer
        return self._others[tile]

    def silhouette(self, pose) -> np.ndarray:
        """(H, W) bool: where ``pose (48,)`` covers the full camera image (one GL render)."""
        return self.depth(pose) > 0

    def depth(self, pose) -> np.ndarray:
        """(H, W) float: camera z of ``pose (48,)`` over the full image, 0 where it is not (one GL render)."""
        return self._full_frame().render(self.body, np.asarray(pose))

    def labels(self, pose) -> np.ndarray:
        """(H, W) int16: the joint (index into the body's ``joint_names``) whose bone shows
        at each pixel of the full image, -1 where none (one GL render)."""
        return self._full_frame().render_labels(self.body, np.asarray(pose))

    def _full_frame(self):
        """The full-image renderer, made on first use and owned by the set."""
        if self._frame is None:
            from ..render import FrameRenderer
            self._frame = FrameRenderer(self.camera)
        return self._frame

    def release(self) -> None:
        """Free every GL object of the set (idempotent)."""
        for r in (self.coarse if self._own_coarse else None, self.fine, self._frame,
                  *self._others.values()):
            if r is not None:
                r.release()
        self.coarse = self.fine = self._frame = None
        self._others = {}
        self._uploaded = None
