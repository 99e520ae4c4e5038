"""The final polish on a kept track: its figures before and after, without tracking again.

The final polish (``depthtrack.track.final_polish``) changes no decision of a track, only
the poses reported, so a track kept from a run without it (``--settings '{"polish":
{"final_tile": 0}}'``, or an older commit's) gives, polished pose by pose, the very poses a
run with it reports. Printed (and written with ``--json``): within 10 cm, mean joint error,
silhouette IoU, unexplained share and median depth residual of the track as kept and as
polished, and the polish's seconds and candidates per frame. How the default's dev and test
figures for it were measured (README, "Final polish"). Since ``final_passes`` passes are the
one-pass polish applied that many times, a track kept with ``n`` passes polished with
``--settings '{"polish": {"final_passes": k}}'`` gives what ``n + k`` passes report (README,
"Final polish, climbed again").

    .venv/bin/python tools/final_polish_tracks.py SEQ TRACK [--json OUT.json] [--settings JSON]
"""
from __future__ import annotations

import json
import pathlib
import sys
import time

REPO = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "tools"))
import depthtrack  # noqa: E402,F401  (before numpy: the same OpenBLAS kernels on every machine)
import numpy as np  # noqa: E402

from depthtrack.errors import InputError  # noqa: E402
from depthtrack.io.atomic import write_text_atomic  # noqa: E402
from depthtrack.evaluate.runs import score  # noqa: E402
from depthtrack.track import TrackerSettings  # noqa: E402
from depthtrack.track.final_polish import FinalPolish  # noqa: E402
from depthtrack.track.tracker import Tracker  # noqa: E402
from track_replay import read_track, track_parser  # noqa: E402


#: The figures printed and written, as ``depthtrack eval --json`` names them.
KEYS = ("within_10cm", "mean_error_m", "silhouette_iou", "unexplained_fraction",
        "median_depth_residual_m")


def figures(seq, body, poses) -> dict:
    """:data:`KEYS` of ``poses (F, 48)``, scored as ``depthtrack eval`` scores a track."""
    joints = np.asarray(body.joint_positions(poses))
    summary = score("track", "hc+ep", seq, joints, poses=poses, body=body).summary
    return {k: summary[k] for k in KEYS}


def main(argv=None) -> int:
    parser = track_parser(__doc__, "tools/final_polish_tracks.py OUT/dev/sequences/bend_c1_s1 "
                                   "OUT/dev/tracks/bend_c1_s1/hc+ep --json bend.json")
    parser.add_argument("--json", type=pathlib.Path, help="write the figures here")
    parser.add_argument("--settings", default="{}",
                        help="tracker settings laid over the defaults (JSON), e.g. "
                             "'{\"polish\": {\"final_tile\": 128}}'")
    args = parser.parse_args(argv)
    try:
        seq, body, poses = read_track(args.seq, args.track, [])
        settings = TrackerSettings().updated(json.loads(args.settings))
    except (InputError, OSError, KeyError, ValueError) as exc:
        print(f"final_polish_tracks: {exc}", file=sys.stderr)
        return 2
    polished = poses.copy()
    with Tracker(body, seq.camera, settings=settings, fps=seq.fps) as tracker:
        t0 = time.perf_counter()
        with FinalPolish(tracker) as polish:
            for i in range(len(seq)):
                if np.all(np.isfinite(poses[i])):
                    polished[i] = polish(seq.depth(i), poses[i])
        seconds = time.perf_counter() - t0
        candidates = tracker.recorder.counts["candidates"]
    out = {"sequence": str(args.seq), "track": str(args.track),
           "seconds_per_frame": seconds / len(seq), "candidates_per_frame": candidates / len(seq),
           "before": figures(seq, body, poses), "after": figures(seq, body, polished)}
    for when in ("before", "after"):
        f = out[when]
        print(f"{when:6s} within 10 cm {f['within_10cm'] * 100:5.1f} %  mean error "
              f"{f['mean_error_m'] * 100:5.2f} cm  IoU {f['silhouette_iou']:.3f}  unexplained "
              f"{f['unexplained_fraction'] * 100:4.1f} %  residual "
              f"{f['median_depth_residual_m'] * 100:.2f} cm")
    print(f"{out['seconds_per_frame']:.2f} s and {out['candidates_per_frame']:.0f} candidates a frame")
    if args.json:
        write_text_atomic(args.json, json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
