"""``depthtrack demo``: the whole pipeline on the built-in procedural sample."""
from __future__ import annotations

import sys

from ..errors import InputError
from .args import add_force, check_output, number


def register(subparsers) -> None:
    from ..evaluate.demo import DEMO_METHODS, DEMO_MOTION, DEMO_SECONDS

    p = subparsers.add_parser(
        "demo", help="synthesize, track, evaluate and draw the built-in sample (a few minutes)",
        description=f"Run the whole pipeline on the built-in procedural motion {DEMO_MOTION!r}: "
                    "synthesize a depth sequence (SR4000 camera, time-of-flight noise, 25 fps) with "
                    "ground truth, draw the candidate renderer's tile figure, track the sequence with "
                    "each method, evaluate against the ground truth (report with plots), and write an "
                    "overlay video of the first method's track. Needs no data files.",
        )
    p.add_argument("--out", required=True, metavar="DIR", help="output directory (replaced)")
    p.add_argument("--seconds", type=number(0, 60, lo_open=True), default=DEMO_SECONDS, help=f"length of the sequence in seconds (default {DEMO_SECONDS})")
    p.add_argument("--methods", default=",".join(DEMO_METHODS),
                   help=f"comma-separated methods from hc, ep, hc+ep; the first one is drawn "
                        f"(default {','.join(DEMO_METHODS)})")
    p.add_argument("--quiet", action="store_true", help="print only where the outputs are")
    add_force(p, "DIR")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..evaluate.demo import run_demo
    from ..evaluate.runs import check_methods

    if not (args.seconds > 0 and args.seconds <= 60):
        raise InputError(None, "--seconds must be between 0 and 60")
    methods = check_methods(args.methods.split(","))
    check_output(args, "out")

    def log(line):
        if not args.quiet:
            print(line, file=sys.stderr, flush=True)

    outputs = run_demo(args.out, seconds=args.seconds, methods=methods, quiet=args.quiet, log=log)
    print(f"demo finished in {outputs.seconds:.0f} s; outputs in {outputs.out}/:")
    width = max(len(k) for k in outputs.items) if outputs.items else 0
    for key, (where, what) in outputs.items.items():
        print(f"  {key:<{width}}  {outputs.out / where}  ({what})")
    for note in outputs.notes:
        print(f"  note: {note}")
    return 0
