"""How well each score of the start's front/back check picks the heading, on sequences with
ground truth (:func:`depthtrack.track.heading.settle_heading`).

For each sequence: the automatic start on the first frame with a person, then the start pose
and its turned twin each tracked through the next ``HeadingSettings.frames`` frames, as the
check does; per hypothesis both scores (mean unexplained share, mean energy without the
motion prior per foreground pixel) and the fraction of joints within 10 cm of the truth over
those frames. Then, per rule, how often the kept hypothesis was clearly worse (by
``--clear`` of joints within 10 cm) than the other.

    .venv/bin/python tools/start_check_bench.py SEQ [SEQ ...] [--method hc+ep] [--frames N] [--json OUT.jsonl]

The sequences: any with ground truth, e.g. ``tools/benchmark.py --split dev --wide
--keep-tracks``'s ``OUT/dev/sequences/*``. Tracked without the shape fit.
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

from depthtrack.body import BodyModel  # noqa: E402
from depthtrack.io import open_sequence  # noqa: E402
from depthtrack.track import TrackerSettings  # noqa: E402
from depthtrack.track.tracker import Tracker  # noqa: E402

#: Rules: name -> (score key, margin as a fraction).
RULES = {"unexplained, margin 0.10": ("unexplained", 0.10),
         "unexplained, margin 0.05": ("unexplained", 0.05),
         "unexplained, margin 0": ("unexplained", 0.0),
         "energy, margin 0": ("energy", 0.0)}


def start_both_ways(tracker, seq, follow: int):
    """The automatic start on the first frame of ``seq`` with a person and at least
    ``follow`` frames after it, as the tracker's loop makes it (without the wait for the
    whole person): ``(frame index, start state, {"initial": pose (48,), "turned": pose (48,)
    or None})``, the start pose and its turned twin (:meth:`Tracker.turned_start`); None
    when no such frame has a person."""
    for i in range(len(seq) - follow):
        depth = seq.depth(i)
        fg = tracker.segmenter(depth, tracker.camera)
        if tracker.person_present(fg):
            break
    else:
        return None
    state, frame, _ = tracker.start(tracker.state, depth, foreground=fg)
    return i, state, {"initial": state.pose, "turned": tracker.turned_start(frame)(state.pose)}


def start_hypotheses(path, method: str = "hc+ep", frames: int | None = None) -> dict | None:
    """Both hypotheses of the start check on one sequence: ``{"name", "frame", "initial",
    "turned"}``, each hypothesis ``{"unexplained", "energy", "within_10cm"}`` (None when
    its track was dropped); None when no frame has a person or too few frames follow.
    ``frames``: track each through this many frames instead of the check's own
    (``HeadingSettings.frames``), to see whether a longer check would decide better."""
    seq = open_sequence(path)
    body = BodyModel.default(height=seq.subject_height or 1.75)
    settings = TrackerSettings(shape={"enabled": False})
    K = int(frames) if frames else settings.heading.frames
    with Tracker(body, seq.camera, fps=seq.fps, settings=settings, method=method) as t:
        started = start_both_ways(t, seq, K)
        if started is None:
            return None
        i, state, starts = started
        ahead = [seq.depth(i + 1 + k) for k in range(K)]
        truth = seq.joints[i + 1:i + 1 + K]
        out = {"name": pathlib.Path(path).name, "frame": i}
        for kind, pose in starts.items():
            got = t.track_through(state.replace(pose=pose), ahead)
            if got is None:
                out[kind] = None
                continue
            joints = np.array([body.joint_positions(p) for p in got[1]])
            within = float(np.mean(np.linalg.norm(joints - truth, axis=2) < 0.1))
            out[kind] = {**got[2], "within_10cm": within}
    return out


def rule_failures(results, clear: float = 0.2) -> dict:
    """Per rule of :data:`RULES`: the sequences where the kept hypothesis had at least
    ``clear`` fewer joints within 10 cm than the other."""
    out = {}
    for rule, (key, margin) in RULES.items():
        wrong = []
        for r in results:
            a, b = r.get("initial"), r.get("turned")
            if a is None or b is None:
                continue
            kept, other = (b, a) if b[key] < (1.0 - margin) * a[key] else (a, b)
            if other["within_10cm"] - kept["within_10cm"] >= clear:
                wrong.append(r["name"])
        out[rule] = wrong
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter,
                                     epilog="example:\n  .venv/bin/python tools/start_check_bench.py "
                                            "OUT/dev/sequences/* --json starts.jsonl")
    parser.add_argument("sequences", nargs="+")
    parser.add_argument("--method", default="hc+ep", choices=["hc", "hc+ep"])
    parser.add_argument("--clear", type=float, default=0.2,
                        help="a kept heading counts as wrong when the other had this much more "
                             "of the joints within 10 cm (default 0.2)")
    parser.add_argument("--json", help="also write each sequence's result, a JSON line each")
    parser.add_argument("--frames", type=int, default=None,
                        help="track each hypothesis through this many frames (default: the "
                             "check's own, HeadingSettings.frames)")
    args = parser.parse_args(argv)
    results = []
    for n, path in enumerate(args.sequences, 1):
        r = start_hypotheses(path, args.method, args.frames)
        if r is None:
            print(f"[{n}/{len(args.sequences)}] {path}: no start", flush=True)
            continue
        results.append(r)
        print(f"[{n}/{len(args.sequences)}] {r['name']}: " + ", ".join(
            f"{k} {'dropped' if r[k] is None else '%.0f%% within 10 cm' % (100 * r[k]['within_10cm'])}"
            for k in ("initial", "turned")), flush=True)
    if args.json:
        pathlib.Path(args.json).write_text("".join(json.dumps(r) + "\n" for r in results),
                                           encoding="utf-8")
    for rule, wrong in rule_failures(results, args.clear).items():
        print(f"{rule}: kept the clearly worse heading on {len(wrong)} of {len(results)}"
              + (f" ({', '.join(wrong)})" if wrong else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
