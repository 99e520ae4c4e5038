"""``depthtrack eval``: track sequences with several methods and score them against ground truth."""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from ..errors import InputError
from .reader_options import add_reader_options, reader_options
from .args import add_force, check_output
from .track import add_preset_option


_EPILOG = """examples:
  depthtrack eval seqs/walk seqs/run --methods hc,hc+ep --report eval-report
  depthtrack eval seqs/walk --likelihood pixel --json > walk.json
  depthtrack eval seqs/walk seqs/walk --track out/walk_hc out/walk_hcep --json
  depthtrack eval my_recording --track out/my_recording     # no ground truth: fit figures only
  depthtrack eval seqs/* --workers 2 --json > all.json          # 2 processes on this machine
  depthtrack eval seqs/* --dask local --workers 4                # a Dask LocalCluster
  depthtrack eval /lab/seqs/* --dask tcp://scheduler:8786 --tracks-out /lab/tracks

Overall figures average the sequences, each weighing the same (frames: the total).
Results go to stdout (a table, or JSON with --json); progress to stderr.

Batches: one task per sequence (all its methods), run in order here (default), in
--workers N spawned processes, or on a Dask cluster (--dask ADDRESS, or --dask local for
a LocalCluster of --workers processes, default 2); the figures are the same every way
(fps aside). A sequence that fails is reported (stderr, and "failed" in --json) and the
others go on. Exit status: 0 all done; 2 bad input (nothing run, or a sequence that could
not be read: the rest still reported); 1 a sequence crashed (a bug or a lost worker)."""


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "eval",
        help="score tracking methods against ground truth, and by how well the body explains the depth",
        description="Track each sequence with each method (or read existing track outputs with "
                    "--track) and score the result against the sequence's ground truth: mean "
                    "joint error, the worst joint's error averaged over frames, the fraction of "
                    "joints within 10 cm, the paper's average and maximum marker errors (when the "
                    "sequence has markers), the share of frames tracked back to front (the trunk "
                    "facing away from the true one), the error of the trunk's twist (shoulders "
                    "against hips, degrees) and frames per second; per sequence and averaged over "
                    "sequences (each sequence weighing the same). Every sequence, with or without "
                    "ground truth, also gets fit figures: silhouette IoU of the person's foreground "
                    "and the fitted body's render, the share of the person's pixels left "
                    "unexplained and the median depth residual (accuracy fields are null without "
                    "ground truth); synthetic sequences made with --shape also get the fitted "
                    "body's segment-length errors (from the track's body.json when it has one).",
        epilog=_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("sequences", nargs="+", metavar="SEQ",
                   help="sequence directory (or .npz, or any readable recording); ground-truth "
                        "joints and/or markers give the accuracy figures")
    p.add_argument("--methods", default=None,
                   help="comma-separated tracking methods from hc, ep, hc+ep (default: all three; "
                        "not with --track)")
    p.add_argument("--likelihood", choices=("smoothed", "pixel"), default="smoothed",
                   help="likelihood the tracker scores candidates with (default smoothed)")
    p.add_argument("--track", nargs="+", metavar="DIR", default=None,
                   help="score existing track outputs instead of tracking: one per SEQ, in order "
                        "(repeat a SEQ to score several tracks of it); the method name comes from "
                        "each track's summary.json")
    p.add_argument("--report", metavar="DIR", default=None,
                   help="write metrics.json, report.md, errors.csv and plots into DIR (replaced)")
    p.add_argument("--json", action="store_true",
                   help='print only {"sequences": {NAME: {METHOD: M}}, "overall": {METHOD: M}} to stdout '
                        '(plus "failed": {NAME: WHY} when a sequence failed)')
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="track N sequences at once in spawned processes (with --dask local: its "
                        "worker processes, default 2)")
    p.add_argument("--dask", metavar="ADDRESS", default=None,
                   help="run one task per sequence on a Dask cluster: a scheduler address "
                        "(tcp://HOST:8786) or 'local' for a LocalCluster on this machine")
    p.add_argument("--tracks-out", metavar="DIR", default=None,
                   help="also write each track to DIR/SEQUENCE/METHOD/ (as `depthtrack track` does)")
    p.add_argument("--facing", choices=("auto", "camera", "away"), default=None,
                   help="which way the person faces at the start of every sequence, when you "
                        "know (see depthtrack track --help)")
    p.add_argument("--settings", metavar="JSON", default=None,
                   help="tracker settings for every sequence, as for depthtrack track")
    add_preset_option(p)
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    add_reader_options(p)
    add_force(p, "the --report directory")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..evaluate.report import format_text_table, write_report
    from ..evaluate.runs import METHODS, evaluate, print_line

    if args.track is not None and args.methods is not None:
        raise InputError(None, "--methods and --track exclude each other (a track's method is in "
                               "its summary.json)")
    check_output(args, "report", inputs=[*args.sequences, *(args.track or ())])
    methods = METHODS if args.methods is None else args.methods.split(",")
    if args.workers is not None and args.workers < 1:
        raise InputError(None, f"--workers must be at least 1, not {args.workers}")
    if args.tracks_out is not None and Path(args.tracks_out).exists() and not Path(args.tracks_out).is_dir():
        raise InputError(args.tracks_out, "exists and is not a directory")
    executor = "dask" if args.dask else ("workers" if args.workers else "serial")
    settings = None
    if args.settings is not None or args.facing is not None or args.preset is not None:
        if args.track is not None:
            raise InputError(None, "--settings, --preset and --facing apply to tracking, not to --track")
        from .track import tracker_settings
        settings = tracker_settings(args)
    evaluation = evaluate(args.sequences, methods=methods, likelihood=args.likelihood,
                          track_dirs=args.track, quiet=args.quiet, open_options=reader_options(args),
                          log=None if args.quiet else print_line, executor=executor,
                          workers=args.workers, dask_address=args.dask, tracks_out=args.tracks_out,
                          keep_going=True, settings=settings)
    for failure in evaluation.failures:
        print(f"depthtrack eval: {failure.message}" if failure.bad_input
              else f"depthtrack eval: {failure.path}: {failure.message}", file=sys.stderr)
        if failure.detail and not args.quiet:
            print(failure.detail.rstrip(), file=sys.stderr)
    if not evaluation.results:
        return 2 if all(f.bad_input for f in evaluation.failures) else 1
    data = evaluation.to_dict()
    written = write_report(evaluation, args.report) if args.report else None
    if args.json:
        sys.stdout.write(json.dumps(data, indent=1) + "\n")
    else:
        sys.stdout.write(format_text_table(evaluation, data))
    if written and not args.quiet:
        print(f"report: {args.report}/report.md (metrics.json, errors.csv, "
              f"{', '.join(n for n in written if n.endswith('.png'))})", file=sys.stderr)
    if evaluation.failures:
        return 2 if all(f.bad_input for f in evaluation.failures) else 1
    return 0
