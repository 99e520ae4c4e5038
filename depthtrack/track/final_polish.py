"""Stage "final polish": each finished pose climbed once more at the camera's own resolution.

The per-frame search scores candidates on 64-pixel tiles and polishes them on 128-pixel
tiles, and its finest steps are 1.5 cm at the pelvis and 0.075 rad at the shoulders (4 cm at
the wrist): fine enough to follow the person, too coarse to lay a limb on its pixels. A body
a few pixels off uncovers a band of the person on one side of each limb and overhangs the
other; on dev bend seed 1 (Kinect v2, every joint within 10 cm) the track's body covered the
person with a silhouette IoU of 0.83 and left 9 % of the person unexplained, where the same
body fitted to the true joints reaches 0.91 to 0.93 and 1 to 2 %.

So once a pose is final -- :func:`.loop.stream_poses` yields it, and no correction can
re-track it any more -- it is climbed again on that frame without the motion prior, on
tiles as fine as the camera's pixels (:func:`final_tile`: a power of two by the ROI's side,
nearest it or the smallest at least it as :attr:`~.settings.PolishSettings.final_tile_round`
says, at most :attr:`~.settings.PolishSettings.final_tile`), from the search's finest
rung down :attr:`~.settings.PolishSettings.final_levels` finer ones (each halves every
step), :attr:`~.settings.PolishSettings.final_passes` times (each climb from that rung again,
on the frame observed around the pose the last climb left; one climb stops long before it
converges). The track itself does not change: the next frame is tracked from the pose the loop
had, so the decisions are the same with or without this stage, and only the poses
reported are finer. Its time and candidates are the ``final`` stage of the timings.
"""
from __future__ import annotations

import math

import numpy as np

from .observe import as_depth, observe
from .loop import stream_poses
from .settings import TILE_ROUNDINGS

#: The smallest tile the final polish uses (pixels): the search's own.
SMALLEST_TILE = 64


def final_tile(roi_size: float, largest: int, smallest: int = SMALLEST_TILE,
               rounding: str = "nearest") -> int:
    """The tile side (pixels) for a square ROI of ``roi_size`` camera pixels, within
    ``[smallest, largest]``: the power of two nearest it in log scale (``rounding``
    ``"nearest"``) or the smallest at least it (``"up"``: no camera pixel shares a tile
    pixel with another, e.g. an SR4000 person of 150 pixels on 256 rather than 128)."""
    if rounding not in TILE_ROUNDINGS:
        raise ValueError(f"rounding must be one of {TILE_ROUNDINGS}, not {rounding!r}")
    if not np.isfinite(roi_size) or roi_size <= 0:
        return int(smallest)
    exponent = math.log2(float(roi_size))
    tile = 2 ** int(math.ceil(exponent) if rounding == "up" else round(exponent))
    return int(min(max(tile, smallest), largest))


class FinalPolish:
    """The final polish of one tracker's poses (module docstring).

    Owns a :class:`~depthtrack.render.TileRenderer` per tile side it has used, released by
    :meth:`delete` (or leaving a ``with`` block).

    Parameters
    ----------
    tracker : Tracker
        Its body, camera, segmenter, settings (:class:`~.settings.PolishSettings`), energy
        and recorder are used; its state is read (the floor plane), never changed.
    """

    def __init__(self, tracker):
        self.tracker = tracker
        self.climber = tracker.climbers.final
        self._renderers = {}

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.delete()

    def delete(self) -> None:
        """Release every renderer made (idempotent)."""
        for r in self._renderers.values():
            r.release()
        self._renderers = {}

    def _renderer(self, tile: int):
        if tile not in self._renderers:
            from ..render import TileRenderer

            t = self.tracker
            self._renderers[tile] = TileRenderer(t.render_body, t.camera, tile=tile)
        return self._renderers[tile]

    def __call__(self, depth, pose, foreground=None):
        """``pose (48,)`` climbed on ``depth (H, W)``: the polished pose, or ``pose`` itself
        where the frame's segmentation finds nobody. ``foreground``: the frame's
        segmentation when the caller has it (else it is segmented here).

        :attr:`~.settings.PolishSettings.final_passes` climbs, each on the frame observed
        around the pose the last one left (the ROI and the region near the body follow it),
        so ``n`` passes are the one-pass polish applied ``n`` times; a climb that moves
        nothing ends them."""
        t = self.tracker
        pose = np.asarray(pose, dtype=np.float64).copy()
        with t.recorder.timed("final"):
            depth = as_depth(depth, t.camera)
            if foreground is None:
                foreground = t.segmenter(depth, t.camera)
            if not np.any(foreground.mask):
                return pose
            for _ in range(t.settings.polish.final_passes):
                climbed = self._climb(depth, foreground, pose)
                if np.array_equal(climbed, pose):
                    break
                pose = climbed
        return pose

    def _climb(self, depth, foreground, pose):
        """One climb of ``pose (48,)`` on the frame observed around it."""
        t = self.tracker
        s = t.settings
        frame, _ = observe(depth, foreground, t.camera, s, floor=t.state.floor,
                           predicted_joints=np.asarray(t.body.joint_positions(pose)),
                           predicted_silhouette=t.renderers.silhouette(pose))
        renderer = self._renderer(final_tile(frame.roi[2], s.polish.final_tile,
                                             rounding=s.polish.final_tile_round))
        renderer.set_observation(frame.observed, roi=frame.roi)
        energy = t._energy(frame, hidden_of=pose).on(renderer)
        return self.climber.climb(pose, energy, level_offset=s.search.levels - 1).pose


def final_polished(tracker, frames, init_pose=None):
    """:func:`.loop.stream_poses`, each pose final-polished (:class:`FinalPolish`) on its
    own frame as it is yielded; yields ``(index, pose (48,) or None)`` in order.

    The frames not yet yielded are kept (at most the loop's re-track window and look-ahead),
    and so is each one's first segmentation: the final polish, and a re-track that tracks
    the frame again, reuse it instead of segmenting the same depth again (the loop hands
    the tracker's segmenter the very array read; the segmentation is a pure function of
    it). The tracker's segmenter is its own again when the stream ends.
    """
    depths, foregrounds, index_of = {}, {}, {}
    segment = tracker.segmenter

    def remembering(depth, camera):
        k = index_of.get(id(depth))
        if k is None or depths.get(k) is not depth:
            return segment(depth, camera)
        if k not in foregrounds:
            foregrounds[k] = segment(depth, camera)
        return foregrounds[k]

    def read():
        for k, depth in enumerate(frames):
            depth = as_depth(depth, tracker.camera)
            depths[k] = depth
            index_of[id(depth)] = k
            yield depth
    tracker.segmenter = remembering
    try:
        with FinalPolish(tracker) as polish:
            for i, x in stream_poses(tracker, read(), init_pose):
                depth = depths.pop(i, None)
                if depth is not None:
                    index_of.pop(id(depth), None)
                foreground = foregrounds.pop(i, None)
                if x is not None and depth is not None:
                    x = polish(depth, x, foreground)
                yield i, x
    finally:
        tracker.segmenter = segment
