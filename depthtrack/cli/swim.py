"""``depthtrack swim``: the learned cyclic motion model for swimmers (train, evaluate, derivatives, reconstruct)."""
from __future__ import annotations

import argparse
import json
import sys

from ..errors import InputError
from .args import SEED, THREADS, add_force, integer, number

_EPILOG = """examples:
  depthtrack swim evaluate --train ../shared/data/cmu/126_01.bvh --test ../shared/data/cmu/126_01.bvh --report swim-report
  depthtrack swim evaluate --train T.bvh --test T.bvh --particles 1000000 --sigma 0.5 --estimator map \\
      --filter particle --init truth --json
  depthtrack swim evaluate --train T.bvh --test T.bvh --filter rbpf,ukf-tuned,smoother --particles 100000 \\
      --noise 0.1 --gaps 10,30
  depthtrack swim evaluate --train T.bvh --test T.bvh --test-start 566 --filter rbpf,ukf-tuned --particles 100000
  depthtrack swim evaluate --train T.bvh --test T.bvh --filter rbpf,ukf-tuned --process-noise loo --gaps 10
  depthtrack swim train T.bvh -o model.json
  depthtrack swim derivatives T.bvh --report deriv
  depthtrack swim reconstruct markings.csv --lengths lengths.json -o joints.csv"""


def _floats(text, what):
    try:
        values = [float(x) for x in str(text).split(",") if x.strip()]
    except ValueError:
        raise InputError(None, f"{what}: not a comma-separated list of numbers: {text!r}") from None
    if not values:
        raise InputError(None, f"{what}: empty list")
    return values


def _ints(text, what):
    values = _floats(text, what)
    if any(not v >= 1 or v != int(v) or v > 1e9 for v in values):
        raise InputError(None, f"{what}: whole numbers in [1, 1e9] expected: {text!r}")
    return [int(v) for v in values]


def _starts(text):
    """--cycle-starts: whole numbers >= 0, increasing (the take's length is checked on loading)."""
    values = _floats(text, "--cycle-starts")
    if any(not v >= 0 or v != int(v) for v in values) or len(values) < 2 or \
            any(b <= a for a, b in zip(values, values[1:])):
        raise InputError(None, f"--cycle-starts: at least two increasing whole frame numbers >= 0 "
                               f"expected: {text!r}")
    return [int(v) for v in values]


def _choices(text, allowed, what, both=None):
    """Comma-separated choices; ``both`` (documented for two-way options) means ``both``'s pair."""
    values = [x.strip() for x in str(text).split(",") if x.strip()]
    if values == ["both"]:                          # documented: "map, kmeans or both"
        values = list(both or allowed)
    bad = [v for v in values if v not in allowed]
    if bad or not values:
        raise InputError(None, f"unknown {what} {', '.join(bad) or repr(text)} (choose from {', '.join(allowed)})")
    return tuple(values)


#: The first-order derivative filters (depthtrack.motion.derivatives.first_order_filter).
DERIVATIVES = ("d1", "d2", "taylor2", "taylor3", "taylor4")


def _common_training(p):
    p.add_argument("--length", type=integer(10, 10000), default=100,
                   help="reference cycle length L, 10 to 10000 (default 100)")
    p.add_argument("--smooth", type=number(0, 100), default=2.0,
                   help="Gaussian smoothing width of the resampled cycles, in reference samples (default 2)")
    p.add_argument("--derivative", default="taylor3", choices=DERIVATIVES, metavar="NAME",
                   help="first-order derivative filter: d1, d2, taylor2, taylor3, taylor4 (default taylor3)")
    p.add_argument("--cycle-starts", default=None,
                   help="manual cycle-start frames of the training take, comma-separated (overrides detection)")
    p.add_argument("--units", default=None, help="BVH units (metres per unit, or cmu/cm/m/inch); default inferred")
    p.add_argument("--stroke", default="back", choices=("back", "freestyle", "breast", "butterfly", "auto"),
                   help="stroke, for the cycle detection: back and freestyle by the upper arm pointing up, "
                        "the others (and auto) by periodicity of the angles (default back)")
    p.add_argument("--joint-map", default=None, metavar="MAP.json",
                   help='BVH joints the reader does not recognise by name: {"our joint": "file joint"}, '
                        'our joints as in the sequence contract (l_shoulder, l_elbow, ...)')


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "swim", help="learned cyclic motion model for swimmers (thesis): train, evaluate, derivatives, reconstruct",
        description="The swimmer thesis's 14-joint stick figure, its cyclic motion model learned from "
                    "stroke cycles, the particle filter and an unscented Kalman filter, evaluated as in "
                    "the thesis on motion capture.",
        epilog=_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="swim_command", metavar="SUBCOMMAND")
    p.set_defaults(func=lambda args: (p.print_help(), 2)[1])

    e = sub.add_parser(
        "evaluate", help="train on early cycles, track later ones, report errors (thesis 7.3)",
        description="Train the motion model on back-stroke cycles of --train, predict --frames frames of "
                    "--test (the later part of the same take when both are the same file: training only "
                    "uses cycles that end before the test window) with the particle filter and/or the "
                    "unscented Kalman filter, the measurement being the true pose plus noise, and report "
                    "the squared angle error per frame.",
        epilog=_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    e.add_argument("--train", required=True, metavar="BVH", help="take with the training cycles")
    e.add_argument("--test", required=True, metavar="BVH", help="take to track (may be the same file)")
    e.add_argument("--particles", default="100,1000,10000,100000,1000000",
                   help="particle counts, comma-separated (default 100,...,1000000)")
    e.add_argument("--sigma", default="0.05,0.1,0.5,1.0",
                   help="standard deviations (rad) of the Gaussian measurement model (default 0.05,0.1,0.5,1.0)")
    e.add_argument("--random-sigma", default="0.5,1.0,2.0",
                   help="larger sigmas for random initialisation with the most particles (thesis Fig. 7.13)")
    e.add_argument("--frames", type=integer(1, 1000000), default=200, help="frames to predict (default 200)")
    e.add_argument("--step", type=integer(1, 1000), default=2,
                   help="use every STEP-th frame of the test take (default 2: 60 Hz from 120 Hz mocap)")
    e.add_argument("--estimator", default="map,kmeans", help="map, kmeans or both (default both)")
    e.add_argument("--init", default="truth,random", help="truth, random or both (default both)")
    e.add_argument("--filter", default="particle,ukf",
                   help="comma-separated: particle and ukf (the thesis's, with the --sigma grid), rbpf (the "
                        "Rao-Blackwellised particle filter on the cycle state, for each --particles count), "
                        "ukf-tuned (the UKF with noise estimated from the training frames and the measurements), "
                        "smoother (its RTS smoother, offline); both = particle,ukf (the default)")
    e.add_argument("--gaps", default=None, metavar="K,...",
                   help="also withhold the measurements for stretches of K frames (every K + 40 frames from "
                        "test frame 20) and report the errors inside and after the gaps, per stroke phase, "
                        "against holding the last measurement, constant-velocity extrapolation and linear "
                        "interpolation (e.g. 10,30)")
    e.add_argument("--process-noise", choices=("training", "loo"), default="training",
                   help="process noise of rbpf, ukf-tuned and smoother: the model's one-step residuals on the "
                        "training cycles (training, the default) or on each training cycle under a model "
                        "trained without it (loo: leave one cycle out; larger, as on unseen frames)")
    e.add_argument("--test-start", type=integer(0, 10**9), default=None, metavar="FRAME",
                   help="first frame of the test window in the test take (default: the latest cycle start "
                        "that leaves room); with the same take, training skips the cycles overlapping it")

    e.add_argument("--noise", type=number(0, 10), default=0.05,
                   help="standard deviation (rad) of the noise added to the true angles to make the "
                        "measurements (default 0.05; 0 = the exact truth as in the thesis)")
    e.add_argument("--jitter", type=number(0, 100), default=0.1,
                   help="isotropic acceleration noise added to the learned one, rad per reference "
                        "sample^2 (default 0.1; 0 = the thesis's model exactly)")
    e.add_argument("--thesis-model-particles", type=integer(0, 10**9), default=100000,
                   help="also run the thesis's model without jitter (sigma 0.1 and 0.5) for particle "
                        "counts up to this (default 100000; 0 = skip)")
    e.add_argument("--temporal-sigma", type=number(0, 10, lo_open=True), default=None,
                   help="standard deviation of the temporal acceleration, cycles per frame^2 (default 0.005/L)")
    e.add_argument("--threads", type=THREADS, default=1,
                   help="worker threads for the particles (default 1: on this 2-vCPU machine a second "
                        "thread measured slower)")
    e.add_argument("--seed", type=SEED, default=0, help="random seed (default 0)")
    e.add_argument("--report", metavar="DIR", default=None,
                   help="write metrics.json, results.md and plots into DIR (replaced)")
    e.add_argument("--json", action="store_true", help="print the metrics as JSON to stdout")
    e.add_argument("--quiet", action="store_true", help="no progress on stderr")
    add_force(e, "the --report directory")
    _common_training(e)
    e.set_defaults(func=run_evaluate)

    t = sub.add_parser("train", help="learn the cyclic motion model from a BVH take and save it as JSON",
                       description="Cycle segmentation, spline resampling, smoothing and derivatives "
                                   "(thesis 2.7, 4.8); writes the model (mean angles, velocities, "
                                   "accelerations of every cycle) as JSON.")
    t.add_argument("bvh", metavar="BVH")
    t.add_argument("-o", "--output", required=True, metavar="JSON")
    t.add_argument("--last-frame", type=integer(0, 10**9), default=None, help="only cycles ending at or before this frame")
    _common_training(t)
    t.set_defaults(func=run_train)

    d = sub.add_parser("derivatives", help="compare derivative filters on training cycles (thesis 7.1)",
                       description="Equations 7.1 and 7.2: extrapolate each angle with the velocity and "
                                   "acceleration of each derivative filter and sum the squared errors.")
    d.add_argument("bvh", metavar="BVH")
    d.add_argument("--report", metavar="DIR", default=None, help="write derivatives.md, .json and a plot")
    d.add_argument("--json", action="store_true", help="print the table as JSON")
    add_force(d, "the --report directory")
    _common_training(d)
    d.set_defaults(func=run_derivatives)

    r = sub.add_parser("reconstruct", help="3D stick figure from 2D joint markings (thesis 2.4-2.6)",
                       description="Read a markings CSV (frame,joint,u,v,view; see depthtrack.swim.markings) and "
                                   "reconstruct the 14 joints in 3D: Taylor's scaled orthographic method "
                                   "for one view, the pseudo-inverse scale for two views.")
    r.add_argument("markings", metavar="CSV")
    r.add_argument("--lengths", required=True, metavar="JSON",
                   help='segment lengths {"l_knee": 0.41, ...} (child joint names) or a list of 13')
    r.add_argument("--stroke", choices=("back", "freestyle", "breast", "butterfly"), default="back")
    r.add_argument("-o", "--output", required=True, metavar="CSV", help="frame,joint,x,y,z")
    r.set_defaults(func=run_reconstruct)


def _check_out(args, attr, inputs, kind, command):
    from .args import check_output
    check_output(args, attr, inputs=inputs, kind=kind, command=command,
                 option="-o" if attr == "output" else None)


def _progress(args, total):
    from ..progress import Progress
    return Progress(total, "frames", quiet=args.quiet)


def run_evaluate(args) -> int:
    from .. import swim  # noqa: F401  (import errors surface here, not at parse time)
    from ..swim.experiment import prepare
    from ..swim.report import markdown_tables, run_evaluation, write_report

    particles = _ints(args.particles, "--particles")
    sigmas = _floats(args.sigma, "--sigma")
    random_sigmas = _floats(args.random_sigma, "--random-sigma")
    estimators = _choices(args.estimator, ("map", "kmeans"), "estimator")
    inits = _choices(args.init, ("truth", "random"), "initialisation")
    filters = _choices(args.filter, ("particle", "ukf", "rbpf", "ukf-tuned", "smoother"), "filter",
                       both=("particle", "ukf"))
    gaps = _ints(args.gaps, "--gaps") if args.gaps else ()
    if any(not (0 < s <= 100) for s in sigmas + random_sigmas):
        raise InputError(None, "--sigma and --random-sigma must be in (0, 100] rad")
    starts = _starts(args.cycle_starts) if args.cycle_starts else None
    _check_out(args, "report", [args.train, args.test], "dir", "swim evaluate")
    setup = prepare(args.train, args.test, frames=args.frames, step=args.step, length=args.length,
                    smooth_sigma=args.smooth, derivative=args.derivative, temporal_sigma=args.temporal_sigma,
                    train_starts=starts, units=args.units, test_start=args.test_start, stroke=args.stroke,
                    joint_map=args.joint_map, process_noise=args.process_noise)
    setup.model.jitter = args.jitter
    log = None if (args.quiet or args.json) else (lambda text: print(text, file=sys.stderr))
    metrics, snapshot = run_evaluation(setup, particles, sigmas, estimators, inits, filters, random_sigmas,
                                       noise=args.noise, seed=args.seed, threads=args.threads, log=log,
                                       thesis_particles=args.thesis_model_particles, gaps=gaps)
    if args.report:
        write_report(metrics, args.report, setup, snapshot)
    if args.json:
        sys.stdout.write(json.dumps(metrics) + "\n")
    else:
        sys.stdout.write(markdown_tables(metrics))
    return 0


def run_train(args) -> int:
    from ..io.atomic import write_text_atomic
    from ..swim.cycles import build_training_cycles
    from ..swim.mocap import load_swim_mocap
    from ..swim.stickfigure import ANGLE_NAMES
    from ..swim.training import train_motion_model

    starts = _starts(args.cycle_starts) if args.cycle_starts else None
    _check_out(args, "output", [args.bvh], "file", "swim train")
    mocap = load_swim_mocap(args.bvh, args.units, args.joint_map)
    training = build_training_cycles(mocap.joints, mocap.fps, starts=starts, length=args.length,
                                     smooth_sigma=args.smooth, last_frame=args.last_frame, stroke=args.stroke)
    model = train_motion_model(training, args.derivative)
    data = {"format": "depthtrack-swim-model/1", "source": str(args.bvh), "angle_names": list(ANGLE_NAMES),
            "cycles": [{"first_frame": s, "end_frame": e, "side": side} for s, e, side in training.sources],
            "derivative": args.derivative, "smooth": args.smooth, **model.to_dict()}
    write_text_atomic(args.output, json.dumps(data))
    print(f"{len(training)} cycles, L = {model.length}: {args.output}", file=sys.stderr)
    return 0


def run_derivatives(args) -> int:
    from ..motion.derivatives import compare_derivative_filters
    from ..swim.cycles import build_training_cycles
    from ..swim.mocap import load_swim_mocap
    from ..swim.derivative_report import derivative_table, write_derivative_report

    starts = _starts(args.cycle_starts) if args.cycle_starts else None
    _check_out(args, "report", [args.bvh], "dir", "swim derivatives")
    mocap = load_swim_mocap(args.bvh, args.units, args.joint_map)
    training = build_training_cycles(mocap.joints, mocap.fps, starts=starts, length=args.length,
                                     smooth_sigma=args.smooth, stroke=args.stroke)
    rows = compare_derivative_filters(training.cycles)
    if args.report:
        write_derivative_report(rows, args.report, len(training), args.length, args.smooth)
    if args.json:
        sys.stdout.write(json.dumps(rows) + "\n")
    else:
        sys.stdout.write(derivative_table(rows))
    return 0


def run_reconstruct(args) -> int:
    from ..swim.markings import read_lengths, read_markings, reconstruct_markings, write_joints_csv

    _check_out(args, "output", [args.markings, args.lengths], "file", "swim reconstruct")
    markings = read_markings(args.markings)
    lengths = read_lengths(args.lengths)
    try:
        joints, info = reconstruct_markings(markings, lengths, stroke=args.stroke)
    except InputError as exc:                   # the markings' content is at fault: name the file
        if exc.path is not None:
            raise
        raise InputError(args.markings, exc.problem) from None
    write_joints_csv(args.output, joints, markings.frames)
    print(f"{len(joints)} frames reconstructed ({info}): {args.output}", file=sys.stderr)
    return 0
