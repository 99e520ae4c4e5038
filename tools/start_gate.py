"""The automatic start of each sequence's shape-fit trial, replayed on frame 0: the bend gate.

For every SEQ, the global search runs as the trial's start runs it (the template body at
the sequence's height, ``hc+ep``, frame 0) with the given settings, and one JSON line says
how much of the observation the best straight finalist leaves unexplained, the angle neck -
pelvis - knees' midpoint (degrees) of the recogniser's most confident proposals on frame 0
(``hip_angle``; the knees' midpoint is side-free), whether the bent bodies were searched
(``StartSettings.bend_gate``, ``bend_hip_angle``), which body won, the finalists' scores
and, where the sequence has ground truth, the start's mean joint error (cm) and share of
joints within 10 cm. ``--cue`` adds the same angle of the true joints
(``hip_angle_true``) and repeats the proposals' as ``hip_angle_proposals`` (its name before
the tracker used it). A start that waits for the whole person (the person not complete on
frame 0) cannot be replayed so: its line says ``"failed"``.

    .venv/bin/python tools/start_gate.py SEQ [SEQ ...] [--settings JSON] [--cue]

Example (README, "Bent bodies"): the train down dog opens the gate, an upright start does not.
"""
from __future__ import annotations

import argparse
import json
import pathlib
import sys

import numpy as np

REPO = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from depthtrack.body import BodyModel  # noqa: E402
from depthtrack.contract import JOINT_INDEX  # noqa: E402
from depthtrack.errors import InputError  # noqa: E402
from depthtrack.io import open_sequence  # noqa: E402
from depthtrack.track import TrackerSettings  # noqa: E402
from depthtrack.track.proposals import hip_angle  # noqa: E402
from depthtrack.track.tracker import Tracker  # noqa: E402


def start_line(path: pathlib.Path, settings: TrackerSettings, cue: bool = False) -> dict:
    """The replayed start of sequence ``path`` as one JSON-able dict (see the module docstring)."""
    seq = open_sequence(path)
    body = BodyModel.default(height=seq.subject_height or 1.75)
    with Tracker(body, seq.camera, method="hc+ep", fps=seq.fps, settings=settings) as tracker:
        try:
            tracker.init(seq.depth(0))
        except InputError as exc:
            return {"seq": path.name, "failed": str(exc)}
        info = tracker.describe()["initialisation"]
        joints = np.asarray(tracker.body.joint_positions(tracker.pose))
    gate = info.get("bend_gate") or {}
    line = {"seq": path.name, "unexplained": gate.get("unexplained"),
            "hip_angle": gate.get("hip_angle"),
            "searched": gate.get("searched"), "chosen_bend": info.get("chosen_bend"),
            "straight": [f["score"] for f in info["finalists"] if "bend" not in f],
            "bent": [[f["bend"], f["score"]] for f in info["finalists"] if "bend" in f]}
    if seq.joints is not None:
        err = np.linalg.norm(joints - seq.joints[0], axis=1)
        line.update(error_cm=round(100 * float(err.mean()), 1),
                    within_10cm=round(float((err < 0.1).mean()), 3))
    if cue:
        line["hip_angle_proposals"] = gate.get("hip_angle")
    if cue and seq.joints is not None:
        t = seq.joints[0]
        line["hip_angle_true"] = round(float(hip_angle(*(t[JOINT_INDEX[n]] for n in
                                                         ("neck", "pelvis", "l_knee", "r_knee")))))
    return line


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     epilog="example: .venv/bin/python tools/start_gate.py "
                                            "OUT/dev/sequences/05_20_c1_s1",
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("seqs", nargs="+", type=pathlib.Path, metavar="SEQ",
                        help="synthesized sequence directories")
    parser.add_argument("--settings", default="{}",
                        help='tracker settings as JSON, e.g. \'{"start": {"bend_gate": 1.0}}\'')
    parser.add_argument("--cue", action="store_true",
                        help="also the hip angle of the true joints")
    args = parser.parse_args(argv)
    try:
        settings = TrackerSettings().updated(json.loads(args.settings))
    except (json.JSONDecodeError, InputError, TypeError, ValueError) as exc:
        print(f"start_gate: --settings: {exc}", file=sys.stderr)
        return 2
    for path in args.seqs:
        try:
            line = start_line(path, settings, cue=args.cue)
        except (InputError, OSError) as exc:
            print(f"start_gate: {exc}", file=sys.stderr)
            return 2
        print(json.dumps(line), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
