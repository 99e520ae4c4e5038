"""Where a kept track's joints miss, joint by joint, and whether the camera saw them.

For each sequence with ground truth and its track (``OUT/SEQUENCE/METHOD/``, as ``depthtrack
eval --tracks-out`` keeps it): within 10 cm per joint, the share of frames each true joint
was hidden from the camera (``depthtrack.evaluate.joint_view.hidden_joints``: the depth at
its pixel reads more than 8 cm in front of it), each elbow's mean offset from its shoulder
in the chest's frame (forward, outward, up; true and tracked, over the frames the true
elbow was hidden), and the limb-frames with an arm point deeper than 2 cm in the trunk
(``trunk_penetration``), tracked and true. Nothing is tracked. How the side views' miss on
the parity preset was named: the far arm, hidden, tracked across the chest (README,
"Figures: parity preset on the test split").

    .venv/bin/python tools/joint_errors.py SEQ TRACK [SEQ TRACK ...] [--worst 4] [--json OUT.json]
"""
from __future__ import annotations

import argparse
import json
import pathlib
import sys

REPO = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
import depthtrack  # noqa: E402,F401  (before numpy: the same OpenBLAS kernels on every machine)
import numpy as np  # noqa: E402

from depthtrack.contract import JOINT_NAMES  # noqa: E402
from depthtrack.errors import InputError  # noqa: E402
from depthtrack.evaluate.joint_view import elbow_offsets, hidden_joints, trunk_penetration  # noqa: E402
from depthtrack.evaluate.metrics import fraction_within, joint_errors  # noqa: E402
from depthtrack.io.atomic import write_text_atomic  # noqa: E402
from depthtrack.io.sequence import open_sequence  # noqa: E402
from depthtrack.io.track_output import read_track  # noqa: E402

#: An arm point this deep in the trunk (m) counts as passing through it.
PENETRATION_M = 0.02


def track_view(seq_dir, track_dir) -> dict:
    """The figures of one track (module docstring), as plain numbers."""
    seq = open_sequence(seq_dir)
    if seq.joints is None:
        raise InputError(seq_dir, "no ground-truth joints (groundtruth/joints.csv)")
    tracked = np.asarray(read_track(track_dir).joints, dtype=np.float64)
    n = min(len(tracked), len(seq.joints))
    truth = np.asarray(seq.joints, dtype=np.float64)[:n]
    tracked = tracked[:n]
    # as ``depthtrack eval`` scores them: a frame the tracker gave no pose is a miss
    err = joint_errors(tracked, truth)                                      # (F, 15)
    hidden = np.array([hidden_joints(seq.depth(f), seq.camera, truth[f]) for f in range(n)])
    ok = np.all(np.isfinite(tracked), axis=(1, 2))                          # frames with a pose
    elbows = {}
    for side in "lr":
        seen = hidden[:, JOINT_NAMES.index(f"{side}_elbow")] & ok
        if seen.any():
            elbows[side] = {"frames_hidden": int(seen.sum()),
                            "true_m": np.round(elbow_offsets(truth[seen], side).mean(0), 3).tolist(),
                            "tracked_m": np.round(elbow_offsets(tracked[seen], side).mean(0), 3).tolist()}
    return {"sequence": str(seq_dir), "track": str(track_dir), "frames": int(n),
            "within_10cm": fraction_within(err),
            "joints": {name: {"within_10cm": round(fraction_within(err[:, j]), 3),
                              "hidden_share": round(float(hidden[:, j].mean()), 3)}
                       for j, name in enumerate(JOINT_NAMES)},
            "elbows_when_hidden": elbows,
            "arms_in_trunk": {"tracked": int((trunk_penetration(tracked[ok]) > PENETRATION_M).sum()),
                              "true": int((trunk_penetration(truth) > PENETRATION_M).sum()),
                              "limb_frames": int(2 * n)}}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter,
                                     epilog="example:\n  .venv/bin/python tools/joint_errors.py "
                                            "OUT/dev/sequences/01_08_c3_s2 OUT/dev/tracks/01_08_c3_s2/hc+ep")
    parser.add_argument("pairs", nargs="+", metavar="SEQ TRACK",
                        help="a sequence directory, then its track directory (repeatable)")
    parser.add_argument("--worst", type=int, default=4, help="joints printed per track, worst first (default 4)")
    parser.add_argument("--json", metavar="OUT.json", default=None, help="also write every figure as JSON")
    args = parser.parse_args(argv)
    try:
        if len(args.pairs) % 2:
            raise InputError(None, "give each sequence directory followed by its track directory")
        if args.worst < 0:
            raise InputError(None, f"--worst must be 0 or more, not {args.worst}")
        rows = [track_view(pathlib.Path(s), pathlib.Path(t))
                for s, t in zip(args.pairs[::2], args.pairs[1::2])]
    except (InputError, OSError, KeyError, ValueError) as exc:
        print(f"joint_errors: {exc}", file=sys.stderr)
        return 2
    for r in rows:
        worst = sorted(r["joints"].items(), key=lambda kv: kv[1]["within_10cm"])[:args.worst]
        print(f"{pathlib.Path(r['sequence']).name}: {100 * r['within_10cm']:.1f} % within 10 cm; worst "
              + ", ".join(f"{k} {100 * v['within_10cm']:.0f} % (hidden {100 * v['hidden_share']:.0f} %)"
                          for k, v in worst))
        for side, e in r["elbows_when_hidden"].items():
            t, p = (np.round(100 * np.asarray(e[k])).astype(int).tolist() for k in ("true_m", "tracked_m"))
            print(f"  {side} elbow hidden on {e['frames_hidden']} frames; from the shoulder "
                  f"(forward, outward, up) cm: true {t}, tracked {p}")
        a = r["arms_in_trunk"]
        print(f"  arm in the trunk (> {100 * PENETRATION_M:.0f} cm): tracked {a['tracked']}, "
              f"true {a['true']} of {a['limb_frames']} limb-frames")
    if args.json:
        write_text_atomic(pathlib.Path(args.json), json.dumps(rows, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
