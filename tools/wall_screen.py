"""Which sequences can ``observe.wall_background`` change? For each frame, the readings on the
plane of a wall the segmentation dropped that lie near the person (within ``--near`` pixels
of the mask) and inside a depth band wider than the tracker's (the mask's 2nd percentile less
``depth_band``, to the farther of its 98th percentile and the true joints' farthest, when
known, plus ``depth_band + --extra``). A sequence with no such reading on any frame is
tracked the same with the option on or off; the others must be tracked to be judged.

Prints one line per sequence (``--json``: one object per line): the name, the frames with
such readings, and the first few ``(frame, pixels)``.
"""
from __future__ import annotations

import argparse
import json
import pathlib
import sys

REPO = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
import depthtrack  # noqa: E402,F401  (before numpy: the same OpenBLAS kernels on every machine)
import cv2  # noqa: E402
import numpy as np  # noqa: E402

from depthtrack.detect import segment_foreground  # noqa: E402
from depthtrack.detect.segment import inlier_distance  # noqa: E402
from depthtrack.errors import InputError  # noqa: E402
from depthtrack.io import open_sequence  # noqa: E402
from depthtrack.track import TrackerSettings  # noqa: E402
from depthtrack.track.observation import on_planes  # noqa: E402


def wall_readings(depth, camera, joints=None, near: int = 21, extra: float = 0.1,
                  depth_band: float = TrackerSettings().observe.depth_band):
    """Pixels ``(H, W) bool`` of one frame on a dropped wall's plane, near the person and inside
    the widened band (all False when the segmentation found no wall or no person).

    Parameters
    ----------
    depth : (H, W) float
    camera : Camera
    joints : (J, 3) float or None
        True joints (camera frame) of the frame: the tracker's band reaches its predicted joints.
    near : int
        Side (pixels) of the square that dilates the person's mask.
    extra : float
        Metres added to the far side of the band.
    """
    depth = np.asarray(depth, dtype=np.float64)
    fg = segment_foreground(depth, camera)
    none = np.zeros(depth.shape, bool)
    z = depth[fg.mask]
    z = z[z > 0]
    if fg.wall_planes is None or len(z) <= 10:
        return none
    lo, hi = np.percentile(z, [2.0, 98.0])
    if joints is not None and np.isfinite(joints).any():
        hi = max(hi, float(np.nanmax(joints[:, 2])))
    wall = on_planes(camera.backproject(depth), fg.wall_planes, inlier_distance(depth))
    close = cv2.dilate(fg.mask.astype(np.uint8), np.ones((near, near), np.uint8)) > 0
    return ((depth > 0) & wall & ~fg.mask & close
            & (depth >= lo - depth_band) & (depth <= hi + depth_band + extra))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="example:\n  .venv/bin/python tools/wall_screen.py OUT/dev/sequences/*/")
    parser.add_argument("sequences", nargs="+", type=pathlib.Path, help="sequence directories")
    parser.add_argument("--near", type=int, default=21, help="mask dilation, pixels (default 21)")
    parser.add_argument("--extra", type=float, default=0.1,
                        help="metres added to the band's far side (default 0.1)")
    parser.add_argument("--json", action="store_true", help="one JSON object per line")
    args = parser.parse_args(argv)
    for path in args.sequences:
        try:
            seq = open_sequence(path)
        except (InputError, OSError) as exc:
            print(f"wall_screen: {path}: {exc}", file=sys.stderr)
            return 2
        hits = []
        for f in range(len(seq)):
            joints = None if seq.joints is None else seq.joints[f]
            n = int(wall_readings(seq.depth(f), seq.camera, joints, args.near, args.extra).sum())
            if n:
                hits.append((f, n))
        name = path.resolve().name
        if args.json:
            print(json.dumps({"sequence": name, "frames": len(hits), "hits": hits}), flush=True)
        else:
            print(f"{name} {len(hits)} {hits[:6]}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
