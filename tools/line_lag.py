"""How far a track's turn lags the body's, part by part: per frame, the signed angle in the
ground plane between the tracked and the true left-to-right line of the hips, the
shoulders and the ankles, and the tracked and true trunk twist.

A track whose hips fall behind while its shoulders and ankles keep up has a pelvis that
lags the turn (README, the 90_05 paragraph under "Benchmark"); all three behind, a body
that turns too slowly; all three near 180 degrees, a body back to front.

    .venv/bin/python tools/line_lag.py SEQ TRACK

``SEQ``: a sequence with ``groundtruth/joints.csv``; ``TRACK``: a track of it
(``depthtrack track`` / ``eval --tracks-out``). The ground plane is the camera's x-z plane
(the synthesized cameras are level).
"""
from __future__ import annotations

import argparse
import pathlib
import sys

REPO = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
import depthtrack  # noqa: E402,F401  (before numpy: the same OpenBLAS kernels on every machine)
import numpy as np  # noqa: E402

from depthtrack.contract import JOINT_INDEX  # noqa: E402
from depthtrack.errors import InputError  # noqa: E402
from depthtrack.evaluate.metrics import trunk_twist  # noqa: E402
from depthtrack.filters.angles import wrap  # noqa: E402
from depthtrack.io import open_sequence  # noqa: E402
from depthtrack.io.track_output import read_track  # noqa: E402

LINES = {"hips": ("l_hip", "r_hip"), "shoulders": ("l_shoulder", "r_shoulder"),
         "ankles": ("l_ankle", "r_ankle")}


def line_heading(joints, left: str, right: str) -> np.ndarray:
    """``(F,)`` heading (degrees) of the left-to-right line of ``joints (F, 15, 3)`` in the
    camera's x-z plane."""
    v = joints[:, JOINT_INDEX[right]] - joints[:, JOINT_INDEX[left]]
    return np.degrees(np.arctan2(v[:, 2], v[:, 0]))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     epilog="example:\n  tools/line_lag.py OUT/dev/sequences/"
                                            "90_05_c0_s2 OUT/dev/tracks/90_05_c0_s2/hc+ep",
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("seq", type=pathlib.Path, help="sequence directory with ground truth")
    parser.add_argument("track", type=pathlib.Path, help="track directory")
    args = parser.parse_args(argv)
    try:
        truth = open_sequence(args.seq).joints
        if truth is None:
            raise InputError(args.seq, "no ground-truth joints (groundtruth/joints.csv)")
        tracked = read_track(args.track).joints
    except (InputError, OSError) as exc:
        print(f"line_lag: {exc}", file=sys.stderr)
        return 2
    n = min(len(truth), len(tracked))
    truth, tracked = np.asarray(truth[:n], float), np.asarray(tracked[:n], float)
    lag = {k: wrap(line_heading(tracked, *lr) - line_heading(truth, *lr), 360.0)
           for k, lr in LINES.items()}
    turn = wrap(np.diff(line_heading(truth, *LINES["hips"]), prepend=np.nan), 360.0)
    twist_t, twist_true = trunk_twist(tracked), trunk_twist(truth)
    print("frame  true hips' turn  lag: hips shoulders ankles  twist: tracked true  (degrees)")
    for f in range(n):
        print(f"{f:5d} {turn[f]:+16.0f} {lag['hips'][f]:+11.0f} {lag['shoulders'][f]:+10.0f} "
              f"{lag['ankles'][f]:+7.0f} {twist_t[f]:+15.0f} {twist_true[f]:+5.0f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
