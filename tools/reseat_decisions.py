"""The re-seat recheck's decisions on a kept track, each judged by the ground truth.

On every ``--every``-th frame of a track, the re-seat (``reseat.recheck_reseat``) runs as
the tracker runs it: the track's pose climbed without the motion prior on the recheck's
tiles, each limb set to every pose of the limb library, the lowest of each limb climbed
over that limb. Printed per frame: the best re-seated limb's energy lead over the climbed
pose (positive = lower energy), and the mean joint error of both. The summary counts, for
leads over each margin, how often the re-seat would have made the frame's error better or
worse by more than 2 cm: how good the decision is, apart from where the track goes next
(one changed frame changes every frame after it, and a benchmark's paired differences
mostly measure that).

With ``--hidden SHARE`` only the frames with a limb tracked hidden (``heading.reseat_hidden``
= SHARE: its forearm and hand, or shin and foot, on fewer than that share of the person's
pixels) are tried, and only those limbs re-seated, as the tracker's hidden-limb re-seat does.
With ``--side DEG`` only the frames whose tracked trunk the camera sees from the side (within
DEG degrees) are tried, and only the far side's limbs re-seated
(:func:`depthtrack.track.reach.far_side_limbs`, as ``energy.hidden_prior_gate`` "side" lists
them; ``--arms``: the far arm only).

    .venv/bin/python tools/reseat_decisions.py SEQ TRACK [--every 4] [--hidden 0.01 | --side 45 [--arms]] [--json OUT.json]
"""
from __future__ import annotations

import json
import pathlib
import sys

REPO = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "tools"))
import depthtrack  # noqa: E402,F401  (before numpy: the same OpenBLAS kernels on every machine)
import numpy as np  # noqa: E402

from depthtrack.errors import InputError  # noqa: E402
from depthtrack.track import TrackerSettings  # noqa: E402
from depthtrack.track.reach import far_side_limbs  # noqa: E402
from depthtrack.track.rechecks import tracked_hidden  # noqa: E402
from depthtrack.track.reseat import best_reseat, limb_climber, limb_library  # noqa: E402
from depthtrack.track.search import climb  # noqa: E402
from depthtrack.track.tracker import Tracker  # noqa: E402
from track_replay import frame_energy, read_track, track_parser  # noqa: E402

MARGINS = (0.0, 0.005, 0.01, 0.02, 0.03, 0.05)
#: A frame's mean joint error counts as changed beyond this (metres).
CHANGED = 0.02


def main(argv=None) -> int:
    parser = track_parser(__doc__, "tools/reseat_decisions.py OUT/dev/sequences/90_05_c0_s2 "
                                   "OUT/dev/tracks/90_05_c0_s2/hc+ep --every 4")
    parser.add_argument("--every", type=int, default=4, help="every that many frames (from 4)")
    parser.add_argument("--hidden", type=float, metavar="SHARE",
                        help="only limbs tracked hidden at this share (heading.reseat_hidden)")
    parser.add_argument("--side", type=float, metavar="DEG",
                        help="only the far side's limbs of a trunk seen within DEG of a side view")
    parser.add_argument("--arms", action="store_true", help="with --side: the far arm only")
    parser.add_argument("--json", type=pathlib.Path, help="also write the decisions here")
    args = parser.parse_args(argv)
    try:
        if args.every < 1:
            raise InputError(None, f"--every must be at least 1, not {args.every}")
        if args.hidden is not None and not 0 < args.hidden < 1:
            raise InputError(None, f"--hidden must be a share between 0 and 1, not {args.hidden}")
        if args.side is not None and not 0 <= args.side <= 90:
            raise InputError(None, f"--side must be 0 to 90 degrees, not {args.side}")
        if args.arms and args.side is None:
            raise InputError(None, "--arms narrows --side: give --side DEG too")
        if args.side is not None and args.hidden is not None:
            raise InputError(None, "--side and --hidden choose the limbs two ways: give one")
        seq, body, poses = read_track(args.seq, args.track, [1])
        frames = list(range(args.every, len(poses), args.every))
    except (InputError, OSError, KeyError) as exc:
        print(f"reseat_decisions: {exc}", file=sys.stderr)
        return 2
    settings = TrackerSettings(heading={"reseat_hidden": args.hidden or 0.0})
    library = limb_library()
    rows = []
    with Tracker(body, seq.camera, method="hc+ep", fps=seq.fps, settings=settings) as tr:
        start = tr.climbers.start

        def error(pose, f):
            return float(np.linalg.norm(body.joint_positions(pose) - seq.joints[f], axis=1).mean())

        for f in frames:
            if not np.isfinite(poses[f]).all():
                continue
            frame, energy = frame_energy(tr, seq, poses, f)
            limbs = None
            if args.hidden is not None:
                limbs = sorted(tracked_hidden(tr, frame, tr.renderers.labels(poses[f])))
                if not limbs:
                    continue
            if args.side is not None:
                limbs = sorted(limb for limb in far_side_limbs(body.joint_positions(poses[f]), args.side)
                               if not args.arms or limb.endswith("_arm"))
                if not limbs:
                    continue
            base, e_base = climb(energy, start, poses[f], tr.recorder)
            name, y, e_y = best_reseat(base, energy, limb_climber(energy, start, tr.recorder),
                                       library, clip=body.clip, limbs=limbs)
            row = {"frame": f, "limb": name, "lead": (e_base - e_y) / abs(e_base),
                   "error_m": error(base, f), "error_reseated_m": error(y, f)}
            rows.append(row)
            print(f"frame {f:3d}: {name} lead {100 * row['lead']:+5.1f} %, mean joint error "
                  f"{100 * row['error_m']:4.1f} -> {100 * row['error_reseated_m']:4.1f} cm", flush=True)
    for m in MARGINS:
        taken = [r for r in rows if r["lead"] > m]
        better = sum(r["error_reseated_m"] < r["error_m"] - CHANGED for r in taken)
        worse = sum(r["error_reseated_m"] > r["error_m"] + CHANGED for r in taken)
        print(f"margin {m:.3f}: taken on {len(taken)} of {len(rows)} frames, better by > 2 cm "
              f"{better}, worse by > 2 cm {worse}")
    if args.json:
        args.json.write_text(json.dumps({"sequence": str(args.seq), "track": str(args.track),
                                         "rows": rows}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
