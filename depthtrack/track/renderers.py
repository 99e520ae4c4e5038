"""The GL renderers one tracker scores with, owned together and released together."""
from __future__ import annotations

import numpy as np


class RendererSet:
    """The candidate renderer, the polish's finer one and the full-frame silhouette renderer.

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

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.release()

    def set_body(self, body) -> None:
        """Score ``body`` from now on (it must share the mesh of the set's body)."""
        self.body = body
        for r in (self.coarse, self.fine):
            if r is not None:
                r.set_body(body)

    def upload(self, frame) -> None:
        """Make ``frame`` (:class:`~.observe.Frame`) the observation every renderer scores against."""
        self.coarse.set_observation(frame.observed, roi=frame.roi)
        if self.fine is not None:
            self.fine.set_observation(frame.observed, roi=frame.roi)

    def silhouette(self, pose) -> np.ndarray:
        """(H, W) bool: where ``pose (48,)`` covers the full camera image (one GL render)."""
        if self._frame is None:
            from ..render import FrameRenderer
            self._frame = FrameRenderer(self.camera)
        return self._frame.render(self.body, np.asarray(pose)) > 0

    def release(self) -> None:
        """Free every GL object of the set (idempotent)."""
        for r in (self.coarse if self._own_coarse else None, self.fine, self._frame):
            if r is not None:
                r.release()
        self.coarse = self.fine = self._frame = None
