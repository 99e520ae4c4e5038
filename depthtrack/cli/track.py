"""``depthtrack track``: fit the body model to every frame of a depth sequence."""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from ..errors import InputError

_EPILOG = """methods (the ToF paper's experiments):
  hc      model-based hill climbing only
  ep      evidence propagation from part detections only (no hill climbing; a baseline)
  hc+ep   hill climbing, then detections propagated and refined (default)

examples:
  depthtrack track seq_walk -o track_walk
  depthtrack track seq_walk -o track_walk --method hc --likelihood pixel --overlay walk.mp4

OUT gets joints.csv, poses.npz, track.bvh and summary.json (method, settings, body height
and where it came from, timings per stage, frames per second). The body height is read
from sequence.json (subject.height_m), or else fitted to the first frame with a person by
the likelihood (a few seconds). After the automatic start, the pose and its twin facing
the other way are both tracked for ten frames and the better kept (a depth image barely
tells front from back). Frames without a person (an empty room, the subject gone) get no
pose; tracking starts again when someone appears."""

OVERLAY_SUFFIXES = (".mp4", ".gif")


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "track", help="track a depth sequence (hill climbing + evidence propagation)",
        description="Track the body through a depth sequence: automatic initialisation on the\n"
                    "first frame, then per frame the MAP pose under the motion prior.",
        epilog=_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("sequence", metavar="SEQ", help="depth sequence directory or .npz")
    p.add_argument("-o", "--out", required=True, metavar="OUT", help="output track directory")
    p.add_argument("--method", choices=("hc", "ep", "hc+ep"), default="hc+ep",
                   help="search method (default hc+ep)")
    p.add_argument("--likelihood", choices=("smoothed", "pixel"), default="smoothed",
                   help="the paper's smoothed likelihood (default) or the plain pixel-wise one")
    p.add_argument("--overlay", metavar="VIDEO", default=None,
                   help="also write an overlay video of the track (.mp4 or .gif)")
    p.add_argument("--init-from-groundtruth", action="store_true",
                   help="ABLATION ONLY: start from a pose fitted to the ground-truth joints of "
                        "frame 0 instead of the automatic initialisation (recorded in summary.json)")
    p.add_argument("--quiet", action="store_true", help="no progress or summary output")
    p.set_defaults(func=run)


def _check_out(out: Path) -> None:
    if out.exists() and not out.is_dir():
        raise InputError(out, "exists and is not a directory")
    if out.is_dir() and any(out.iterdir()) and not (out / "summary.json").is_file():
        raise InputError(out, "is a non-empty directory that is not a track output; "
                              "choose a new directory")


def run(args) -> int:
    from ..io.sequence import open_sequence
    from ..progress import Progress
    from ..track import run_tracking

    out = Path(args.out)
    _check_out(out)
    overlay = Path(args.overlay) if args.overlay else None
    if overlay is not None and overlay.suffix.lower() not in OVERLAY_SUFFIXES:
        raise InputError(overlay, "overlay must end in .mp4 or .gif")
    seq = open_sequence(args.sequence)
    t0 = time.perf_counter()
    with Progress(len(seq), "frames", quiet=args.quiet) as progress:
        result, body, summary = run_tracking(seq, method=args.method, likelihood=args.likelihood,
                                             init_from_groundtruth=args.init_from_groundtruth,
                                             progress=progress)
    from ..io.track_output import write_track

    summary["sequence"] = str(seq.path)
    write_track(out, result.joints, result.poses, body.pose_names, body, seq.fps, summary)
    if overlay is not None:
        from ..evaluate.overlay import write_overlay

        written = write_overlay(overlay, seq, result.poses, body)
        summary["overlay"] = str(written)
    if not args.quiet:
        t = summary["timings"]
        print(f"tracked {len(seq)} frames with {args.method} ({args.likelihood} likelihood) in "
              f"{time.perf_counter() - t0:.1f} s: {t['fps']:.2f} frames/s "
              f"({t['fps_excluding_init']:.2f} after initialisation) -> {out}", file=sys.stderr)
        if overlay is not None:
            print(f"overlay: {summary['overlay']}", file=sys.stderr)
    return 0
