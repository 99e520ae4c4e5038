"""The automatic start of each sequence's shape-fit trial, replayed: the bend gate.

For every SEQ, the global search runs as the trial's start runs it (the template body at the
sequence's height, ``hc+ep``, on the frame the start takes: the first with a person, or
where the person enters the view a later one with enough of them,
``StartSettings.complete_fraction``) with the given settings, and one JSON line says which
frame (``frame``), how much of the observation the best straight finalist leaves
unexplained, the angle neck - pelvis - knees' midpoint (degrees) of the recogniser's most
confident proposals on that frame (``hip_angle``; the knees' midpoint is side-free), whether
the bent bodies were searched (``StartSettings.bend_gate``, ``bend_hip_angle``), which body
won (``chosen_from``: the grid or the recogniser's proposals), the finalists' scores and,
where the sequence has ground truth, the start's mean joint error (cm) and share of joints
within 10 cm. Where the grid's best, heard by ``StartSettings.grid_heard``, won, ``displaced``
says the same of the start it displaced (where it came from, its score; the start differs
from ``grid_heard`` "never"'s exactly on those lines). ``--cue`` adds the same angle of the true
joints (``hip_angle_true``) and repeats the proposals' as ``hip_angle_proposals`` (its name
before the tracker used it). A sequence with nobody on any frame is not replayed: its line
says ``"failed"``.

    .venv/bin/python tools/start_gate.py SEQ [SEQ ...] [--settings JSON] [--cue]

Example (README, "Bent bodies"): the train down dog opens the gate, an upright start does not.
With ``--settings '{"start": {"grid_heard": "start"}}'`` it is the screen of README, "The
displaced start checked too".
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
from depthtrack.contract import JOINT_INDEX  # noqa: E402
from depthtrack.errors import InputError  # noqa: E402
from depthtrack.io import open_sequence  # noqa: E402
from depthtrack.track import TrackerSettings  # noqa: E402
from depthtrack.track.loop import first_complete  # noqa: E402
from depthtrack.track.observation import cut_by_border, visible_area  # noqa: E402
from depthtrack.track.proposals import hip_angle  # noqa: E402
from depthtrack.track.tracker import Tracker  # noqa: E402


def start_frame(tracker, seq):
    """``(k, foreground)``: the frame the tracker's automatic start takes and its
    segmentation -- the first frame with a person, or where the person enters the view the
    first frame after it with enough of them (:attr:`StartSettings.complete_fraction`,
    ``complete_uncut``, :func:`~depthtrack.track.loop.first_complete`, as the loop takes
    them); ``(None, None)`` where no frame has a person."""
    g = tracker.settings.start
    segmented = (tracker.segmenter(seq.depth(i), seq.camera) for i in range(len(seq)))
    first, fg = next(((i, f) for i, f in enumerate(segmented) if tracker.person_present(f)),
                     (None, None))
    if first is None:
        return None, None
    end = min(len(seq), first + 1 + (g.complete_frames if g.complete_fraction > 0 else 0))
    foregrounds = [fg] + [tracker.segmenter(seq.depth(i), seq.camera) for i in range(first + 1, end)]
    k = first_complete([visible_area(f, seq.camera) for f in foregrounds], g.complete_fraction,
                       [cut_by_border(f.mask) for f in foregrounds] if g.complete_uncut else None)
    return first + k, foregrounds[k]


def start_line(path: pathlib.Path, settings: TrackerSettings, cue: bool = False) -> dict:
    """The replayed start of sequence ``path`` as one JSON-able dict (see the module docstring)."""
    seq = open_sequence(path)
    body = BodyModel.default(height=seq.subject_height or 1.75)
    with Tracker(body, seq.camera, method="hc+ep", fps=seq.fps, settings=settings) as tracker:
        k, fg = start_frame(tracker, seq)
        if k is None:
            return {"seq": path.name, "failed": "no person on any frame"}
        try:
            tracker.init(seq.depth(k), foreground=fg)
        except InputError as exc:
            return {"seq": path.name, "failed": str(exc)}
        info = tracker.describe()["initialisation"]
        joints = np.asarray(tracker.body.joint_positions(tracker.pose))
        displaced = info.get("displaced")
        if displaced is not None:
            displaced_joints = np.asarray(tracker.body.joint_positions(np.array(displaced["pose"])))
    gate = info.get("bend_gate") or {}
    line = {"seq": path.name, "frame": k, "unexplained": gate.get("unexplained"),
            "hip_angle": gate.get("hip_angle"),
            "searched": gate.get("searched"), "chosen_bend": info.get("chosen_bend"),
            "chosen_from": info.get("chosen_from"),
            "straight": [f["score"] for f in info["finalists"] if "bend" not in f],
            "bent": [[f["bend"], f["score"]] for f in info["finalists"] if "bend" in f]}
    if displaced is not None:
        line["displaced"] = {"from": displaced["from"], "score": displaced["score"]}
    if seq.joints is not None:
        line.update(_accuracy(joints, seq.joints[k]))
        if displaced is not None:
            line["displaced"].update(_accuracy(displaced_joints, seq.joints[k]))
    if cue:
        line["hip_angle_proposals"] = gate.get("hip_angle")
    if cue and seq.joints is not None:
        t = seq.joints[k]
        line["hip_angle_true"] = round(float(hip_angle(*(t[JOINT_INDEX[n]] for n in
                                                         ("neck", "pelvis", "l_knee", "r_knee")))))
    return line


def _accuracy(joints, truth) -> dict:
    """``{"error_cm", "within_10cm"}`` of ``joints (15, 3)`` against ``truth (15, 3)``."""
    err = np.linalg.norm(joints - truth, axis=1)
    return {"error_cm": round(100 * float(err.mean()), 1),
            "within_10cm": round(float((err < 0.1).mean()), 3)}


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
