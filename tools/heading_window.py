"""Both front/back hypotheses of an automatic start, tracked far past the check's ten frames.

The automatic start on the first frame with a person (``depthtrack.track.Tracker.start``),
then the start pose and its twin (``Tracker.turned_start``) each tracked through the next
``--frames`` frames (as many as the sequence has) as the start check does; per window of ten frames, each hypothesis's mean unexplained share and energy
without the motion prior (the check's two scores; ratio turned / initial, below 1 favours
the twin) and its fraction of joints within 10 cm of the ground truth.

    .venv/bin/python tools/heading_window.py SEQ [--frames 49]

Tracked with the template body at the sequence's height, without the shape fit.
"""
from __future__ import annotations

import argparse
import pathlib
import sys

REPO = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "tools"))
import depthtrack  # noqa: E402,F401  (before numpy: the same OpenBLAS kernels on every machine)
import numpy as np  # noqa: E402

from depthtrack.body import BodyModel  # noqa: E402
from depthtrack.io import open_sequence  # noqa: E402
from depthtrack.track import TrackerSettings  # noqa: E402
from depthtrack.track.tracker import Tracker  # noqa: E402
from start_check_bench import start_both_ways  # noqa: E402


def hypotheses(path, frames: int):
    """``{"initial" | "turned": (share (K,), energy (K,), within_10cm (K,))}`` per frame
    after the start (:func:`start_check_bench.start_both_ways`), or None without a start."""
    seq = open_sequence(path)
    body = BodyModel.default(height=seq.subject_height or 1.75)
    with Tracker(body, seq.camera, fps=seq.fps,
                 settings=TrackerSettings(shape={"enabled": False})) as t:
        started = start_both_ways(t, seq, 1)
        if started is None:
            return None
        i, state, starts = started
        out = {}
        for kind, pose in starts.items():
            s, rows = state.replace(pose=pose), []
            for k in range(i + 1, min(i + 1 + frames, len(seq))):
                s, x, energy = t._advance(s, seq.depth(k), score=True)
                if x is None:
                    break
                err = np.linalg.norm(np.asarray(body.joint_positions(x)) - seq.joints[k], axis=1)
                # energy: the frame's scores (Tracker._advance); the check's is "energy"
                rows.append((s.log[-1]["cost"], energy["energy"], np.mean(err < 0.1)))
            out[kind] = np.array(rows).reshape(-1, 3).T
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("sequence")
    parser.add_argument("--frames", type=int, default=49,
                        help="frames after the start (default 49)")
    args = parser.parse_args(argv)
    if open_sequence(args.sequence).joints is None:
        print(f"heading_window: {args.sequence}: no ground truth (groundtruth/joints.csv)",
              file=sys.stderr)
        return 2
    h = hypotheses(args.sequence, args.frames)
    if h is None:
        print(f"heading_window: {args.sequence}: no frame with a person", file=sys.stderr)
        return 2
    n = min(len(h["initial"][0]), len(h["turned"][0]))
    for a, b in [(a, min(a + 10, n)) for a in range(0, n, 10)] + [(0, n)]:
        (ua, ea, wa), (ub, eb, wb) = ([v[a:b] for v in h[k]] for k in ("initial", "turned"))
        print(f"frames {a + 1}-{b}: share ratio {ub.mean() / ua.mean():.3f}, energy ratio "
              f"{eb.mean() / ea.mean():.3f}; within 10 cm initial {wa.mean():.2f}, "
              f"turned {wb.mean():.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
