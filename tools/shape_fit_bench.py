"""How well the shape fit recovers random people's segment lengths from tracked frames.

For each person ``k`` (``--shape random --shape-seed k``, optionally clothed), a held-out
test motion (``depthtrack/data/motion_split.json``, cycled) is synthesized with ToF noise
(SR4000 and Kinect v2 alternately); the tracker ("hc", the template body at the sequence's
height, automatic initialisation) tracks the first ``--frames`` frames; four of them
(spread evenly) with the tracker's segmentation and poses go to
:func:`depthtrack.track.shape_fit.fit_shape` -- what a tracker does after its first
frames. Printed: per person the median and worst segment-length error of the template and
of the fitted body, and the median over everybody. No figure here is tuned on test.

    PYTHONPATH=. python tools/shape_fit_bench.py ../shared/data OUT_DIR [--people 10]
        [--clothing none|tight|loose] [--frames 16] [--json]

``--tracked`` (issue 11's first goal): per person ``k`` the motion's busiest ``--seconds``
(tools/benchmark.py's ``busiest_window``; ``--start S`` for a fixed start) is synthesized
twice with the same camera, height and noise seed -- once with the template's build
(``--shape average``) and once as the random person -- and tracked ("hc+ep", height from
``sequence.json``) as ``--bodies`` says (:data:`BODIES`: average, template, fitted,
oracle). Printed: joints within 10 cm per person and body, mean and s.d. over people, the
median |segment-length error| of each body written; ``OUT_DIR/rows.jsonl`` gets each
person's row as it is done.

    PYTHONPATH=. python tools/shape_fit_bench.py ../shared/data OUT_DIR --tracked
        --split dev --people 4 --first-person 100 [--bodies average,template,fitted,oracle]
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import depthtrack  # noqa: F401  (first, before numpy: the same OpenBLAS kernels on every machine)
import numpy as np

from depthtrack.body import BodyModel
from depthtrack.body.shape import LENGTH_FIELDS, length_errors
from depthtrack.io.sequence import open_sequence
from depthtrack.synth.generate import synthesize_bvh
from depthtrack.synth.subject import make_subject
from depthtrack.track.shape_fit import fit_shape
from depthtrack.track.tracker import Tracker

CAMERAS = ("sr4000", "kinect-v2")


def track_first_frames(seq, body, frames):
    """Poses, masks, floor planes and depths of the first ``frames`` frames tracked with "hc"."""
    from depthtrack.detect import segment_foreground

    depths = [seq.depth(i) for i in range(min(frames, len(seq)))]
    with Tracker(body, seq.camera, method="hc", fps=seq.fps) as tracker:
        poses = [tracker.init(depths[0])] + [tracker.step(d) for d in depths[1:]]
    fgs = [segment_foreground(d, seq.camera) for d in depths]
    return np.array(poses), [f.mask for f in fgs], [f.floor_plane for f in fgs], depths


#: What ``--tracked`` tracks, per person (``--bodies``): "average" = the same motion, camera,
#: height and noise seed synthesized with the template's build (``--shape average``) and
#: tracked by default; "template" = the random person tracked by default (no shape fit);
#: "fitted" = the random person with the tracker's shape fit (``--shape-fit on``);
#: "oracle" = the random person tracked with its true body (``synth.shape``, unclothed).
BODIES = ("average", "template", "fitted", "oracle")


def clip_start(motion, seconds, start):
    """``start`` (s), or the busiest ``seconds`` of the motion (tools/benchmark.py) when None."""
    if start is not None:
        return float(start)
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from benchmark import busiest_window

    return busiest_window("bvh", str(motion), seconds)


def track_scores(seq, result, body, truth):
    """Joints within 10 cm, mean joint error, the body's segment-length errors and the
    front/back switches of one track."""
    from depthtrack.evaluate.metrics import fraction_within, point_errors

    err = point_errors(result.joints, seq.joints)
    return {"within_10cm": round(fraction_within(err), 4),
            "mean_error_m": round(float(np.nanmean(np.where(np.isinf(err), np.nan, err))), 4),
            "segment_errors_m": length_errors(body.segment_lengths(), truth),
            "heading_switches": len(result.info.get("heading_switches") or [])}


def true_body(seq):
    """The synthetic person's own body (``sequence.json`` ``synth.shape``: height and scales;
    the skin without clothing), as the tracker would hold it."""
    from depthtrack.body.shape import BodyShape

    shape = BodyShape.from_dict(seq.meta["synth"]["shape"]["scales"])
    return BodyModel.default(height=seq.subject_height, shape=shape)


def track_with(seq, name):
    """``(result, body, shape_fit_s)``: ``seq`` tracked "hc+ep" as ``name`` of :data:`BODIES` says."""
    import dataclasses

    from depthtrack.track import TrackerSettings, run_tracking

    base = TrackerSettings()
    if name == "oracle":        # run_tracking's tracking, with the person's own body
        body = true_body(seq)
        with Tracker(body, seq.camera, method="hc+ep", fps=seq.fps, settings=base) as tracker:
            return tracker.track_sequence(seq), body, 0.0
    settings = base.replace(shape=dataclasses.replace(base.shape, enabled=name == "fitted"))
    result, body, summary = run_tracking(seq, settings=settings)
    return result, body, summary["timings"]["shape_fit_s"]


def run_tracked(k, motion, camera, out_dir, clothing, seconds, start=None, bodies=BODIES):
    """Person ``k`` tracked as each of ``bodies`` says (:data:`BODIES`); one row of scores."""
    start = clip_start(motion, seconds, start)
    person, info = make_subject(None, "random", k, clothing)
    row = {"person": k, "motion": Path(motion).name, "camera": camera,
           "height_m": info["height_m"], "start_s": start}
    builds = {"average" if name == "average" else "random" for name in bodies}
    seqs = {}
    for build in sorted(builds):
        body, subject = (make_subject(info["height_m"], "average", k, "none") if build == "average"
                         else (person, info))
        seq_dir = out_dir / f"person{k:02d}" / build
        synthesize_bvh(motion, seq_dir, fps=25.0, start=start, seconds=seconds, camera=camera,
                       noise="tof", seed=k, body=body, subject=subject)
        seqs[build] = open_sequence(seq_dir)
    row["frames"] = len(next(iter(seqs.values())))
    truth = info["segment_lengths_m"]
    for name in bodies:
        seq = seqs["average" if name == "average" else "random"]
        t = time.perf_counter()
        result, body, fit_s = track_with(seq, name)
        row[name] = {**track_scores(seq, result, body, seq.meta["synth"]["shape"]["segment_lengths_m"]
                                    if name == "average" else truth),
                     "shape_fit_s": fit_s, "seconds": round(time.perf_counter() - t, 1)}
    return row


def summarise_tracked(rows, bodies):
    """Mean and s.d. over people of joints within 10 cm, median |segment error| per body."""
    out = {}
    for name in bodies:
        w = np.array([r[name]["within_10cm"] for r in rows])
        out[name] = {"within_10cm_mean": round(float(np.mean(w)), 4),
                     "within_10cm_sd": round(float(np.std(w, ddof=1)) if len(w) > 1 else 0.0, 4),
                     "segment_error_median_m": round(float(np.median(np.abs(
                         [v for r in rows for v in r[name]["segment_errors_m"].values()]))), 4)}
    return out


def each_person(args, motions, run_one):
    """``(k, row)`` for people ``--first-person`` on, ``run_one(k, motion)`` each; the motions
    cycle from the first person's, and one our BVH reader cannot map is skipped (and said so)."""
    from depthtrack.errors import InputError

    m = args.first_person
    for k in range(args.first_person, args.first_person + args.people):
        while True:
            motion = motions[m % len(motions)]
            m += 1
            try:
                yield k, run_one(k, motion)
                break
            except InputError as exc:
                print(f"skipped {motion.name}: {exc}", file=sys.stderr)


def main_tracked(args, motions):
    bodies = [b for b in BODIES if b in args.bodies.split(",")]
    rows = []
    for k, row in each_person(args, motions, lambda k, motion: run_tracked(
            k, motion, CAMERAS[k % 2], args.out, args.clothing, args.seconds, args.start, bodies)):
        rows.append(row)
        args.out.mkdir(parents=True, exist_ok=True)     # each person's row as it comes (long runs)
        with open(args.out / "rows.jsonl", "a", encoding="utf-8") as f:
            f.write(json.dumps(row) + "\n")
        print(f"person {k:2d} {row['motion']:12s} {row['camera']:9s} h {row['height_m']:.2f} m "
              f"from {row['start_s']:.2f} s: within 10 cm "
              + ", ".join(f"{n} {row[n]['within_10cm']:.1%}" for n in bodies)
              + ("; fitted segment error median "
                 f"{100 * np.median(np.abs(list(row['fitted']['segment_errors_m'].values()))):.1f} cm"
                 if "fitted" in bodies else ""), file=sys.stderr, flush=True)
    summary = {"people": len(rows), "split": args.split, "clothing": args.clothing,
               "seconds": args.seconds, "bodies": bodies, **summarise_tracked(rows, bodies),
               "rows": rows}
    if args.json:
        print(json.dumps(summary, indent=1))
    else:
        for name in bodies:
            print(f"{name}: joints within 10 cm {summary[name]['within_10cm_mean']:.1%} +- "
                  f"{summary[name]['within_10cm_sd']:.1%} (mean +- s.d. over people), median "
                  f"|segment length error| {100 * summary[name]['segment_error_median_m']:.1f} cm")


def run_person(k, motion, camera, out_dir, clothing, frames, fit_frames=4, prior_weight=1.0,
               tile=None, rounds=2, max_iterations=40, fit_scale=True):
    person, info = make_subject(None, "random", k, clothing)
    seq_dir = out_dir / f"person{k:02d}"
    synthesize_bvh(motion, seq_dir, fps=25.0, start=1.0, seconds=frames / 25.0 + 0.2,
                   camera=camera, noise="tof", seed=k, body=person, subject=info)
    seq = open_sequence(seq_dir)
    template = BodyModel.default(height=seq.subject_height)
    poses, masks, planes, depths = track_first_frames(seq, template, frames)
    pick = np.unique(np.linspace(0, len(poses) - 1, fit_frames).round().astype(int))
    t = time.perf_counter()
    fit = fit_shape(template, seq.camera, [depths[i] for i in pick], [masks[i] for i in pick],
                    poses[pick], [planes[i] for i in pick], prior_weight=prior_weight, tile=tile,
                    rounds=rounds, max_iterations=max_iterations, fit_scale=fit_scale)
    seconds = time.perf_counter() - t
    truth = info["segment_lengths_m"]
    from depthtrack.evaluate.fit import frame_fit
    from depthtrack.render import FrameRenderer

    r = FrameRenderer(seq.camera)
    try:
        figures = {name: np.mean([frame_fit(masks[i], depths[i], r.render(b, p))
                                  for i, p in zip(pick, ps)], axis=0).round(4).tolist()
                   for name, b, ps in (("template", template, poses[pick]),
                                       ("fitted", fit.body, fit.poses))}
    finally:
        r.release()
    before = length_errors(template.segment_lengths(), truth)
    after = length_errors(fit.body.segment_lengths(), truth)
    row = {"person": k, "motion": Path(motion).name, "camera": camera, "height_m": info["height_m"],
           "template_errors_m": before, "fitted_errors_m": after, "fit_seconds": round(seconds, 1),
           "tile": fit.tile, "frames_used": pick.tolist(),
           "fit_figures": figures}
    return row


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("data", type=Path)
    ap.add_argument("out", type=Path)
    ap.add_argument("--people", type=int, default=10)
    ap.add_argument("--clothing", default="none", choices=("none", "tight", "loose"))
    ap.add_argument("--frames", type=int, default=16)
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--split", default="test", choices=("train", "dev", "test"),
                    help="motions of depthtrack/data/motion_split.json (tune on dev, report test)")
    ap.add_argument("--fit-frames", type=int, default=4, help="frames given to the shape fit")
    ap.add_argument("--prior-weight", type=float, default=30.0, help="fit_shape's prior_weight")
    ap.add_argument("--tile", type=int, default=0, help="fit_shape's tile (0 = auto, 1:1 pixels)")
    ap.add_argument("--rounds", type=int, default=2, help="fit_shape's rounds")
    ap.add_argument("--max-iterations", type=int, default=40, help="fit_shape's max_iterations")
    ap.add_argument("--keep-height", action="store_true",
                    help="fit_scale=False: keep the sequence's height, as the tracker does when given")
    ap.add_argument("--tracked", action="store_true",
                    help="track each clip ('hc+ep') as --bodies says and compare joints within 10 cm")
    ap.add_argument("--bodies", default=",".join(BODIES),
                    help="with --tracked, comma-separated: average (the template's build filmed the "
                         "same way), template (the random person, no shape fit), fitted (shape fit "
                         "on), oracle (tracked with the person's true body)")
    ap.add_argument("--start", type=float, default=None,
                    help="clip start (s) with --tracked; default the motion's busiest --seconds")
    ap.add_argument("--seconds", type=float, default=2.0, help="clip length with --tracked")
    ap.add_argument("--first-person", type=int, default=0, help="first shape seed with --tracked")
    args = ap.parse_args(argv)
    split = json.loads((Path(__file__).resolve().parents[1] / "depthtrack" / "data"
                        / "motion_split.json").read_text())
    motions = [args.data / m for m in split[args.split]]
    if args.tracked:
        return main_tracked(args, motions)
    rows = []
    for k, row in each_person(args, motions, lambda k, motion: run_person(
            k, motion, CAMERAS[k % 2], args.out, args.clothing, args.frames, args.fit_frames,
            args.prior_weight, args.tile or None, args.rounds, args.max_iterations,
            not args.keep_height)):
        rows.append(row)
        b = np.abs(list(row["template_errors_m"].values()))
        a = np.abs(list(row["fitted_errors_m"].values()))
        print(f"person {k:2d} {row['motion']:12s} {row['camera']:9s} h {row['height_m']:.2f} m: "
              f"template median {100 * np.median(b):.1f} cm (worst {100 * b.max():.1f}), fitted "
              f"median {100 * np.median(a):.1f} cm (worst {100 * a.max():.1f}), "
              f"{row['fit_seconds']:.0f} s, tile {row['tile']}; IoU / unexplained template "
              f"{row['fit_figures']['template'][0]:.3f} / {row['fit_figures']['template'][1]:.1%}, "
              f"fitted {row['fit_figures']['fitted'][0]:.3f} / {row['fit_figures']['fitted'][1]:.1%}",
              file=sys.stderr, flush=True)
    allb = np.abs([r["template_errors_m"][s] for r in rows for s in LENGTH_FIELDS])
    alla = np.abs([r["fitted_errors_m"][s] for r in rows for s in LENGTH_FIELDS])
    per_segment = {s: round(float(np.median(np.abs([r["fitted_errors_m"][s] for r in rows]))), 4)
                   for s in LENGTH_FIELDS}
    summary = {"people": len(rows), "clothing": args.clothing, "split": args.split,
               "fit_frames": args.fit_frames, "prior_weight": args.prior_weight,
               "template_median_error_m": round(float(np.median(allb)), 4),
               "fitted_median_error_m": round(float(np.median(alla)), 4),
               "fitted_per_segment_median_m": per_segment,
               "fit_figures_mean": {n: np.mean([r["fit_figures"][n] for r in rows], axis=0).round(4).tolist()
                                    for n in ("template", "fitted")},
               "rows": rows}
    if args.json:
        print(json.dumps(summary, indent=1))
    else:
        print(f"median |segment length error| over {len(rows)} people x {len(LENGTH_FIELDS)} "
              f"segments: template {100 * summary['template_median_error_m']:.1f} cm, fitted "
              f"{100 * summary['fitted_median_error_m']:.1f} cm")
        print("fitted, per segment (cm): " + ", ".join(f"{s} {100 * v:.1f}" for s, v in per_segment.items()))
        for n, (iou, unexplained, residual) in summary["fit_figures_mean"].items():
            print(f"{n}: silhouette IoU {iou:.3f}, unexplained {unexplained:.1%}, median depth "
                  f"residual {100 * residual:.1f} cm (mean over people of the 4 fitted frames)")


if __name__ == "__main__":
    main()
