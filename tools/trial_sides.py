"""The shape fit's trial, frame by frame, against the ground truth: which way it faced.

Runs the trial the shape fit runs (``height.fit_body_shape``: the template at the
subject's height, the settings of ``height.trial_settings``, the first
``ShapeSettings.frames`` frames, its automatic start and front/back check included) and
prints, per frame, the trunk's facing error against the truth (degrees) and whether the
legs' or the arms' sides are exchanged (``body.facing``), with the trial's heading switches
and limb swaps. The trial tracks without re-tracks, so a frame before a correction keeps the
sides it was tracked with: this shows whether the correction was right, and so what
``ShapeSettings.carry_back`` would do to the fit frames and the re-track's first pose.

    .venv/bin/python tools/trial_sides.py SEQ [SEQ ...] [--settings JSON] [--json OUT.json]
"""
from __future__ import annotations

import argparse
import itertools
import json
import pathlib
import sys

REPO = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
import depthtrack  # noqa: E402,F401  (before numpy: the same OpenBLAS kernels on every machine)
import numpy as np  # noqa: E402

from depthtrack.body.facing import facing_error_deg, sides_exchanged  # noqa: E402
from depthtrack.errors import InputError  # noqa: E402
from depthtrack.io import open_sequence  # noqa: E402
from depthtrack.track import TrackerSettings  # noqa: E402
from depthtrack.track.twins import LIMB_SWAPS  # noqa: E402
from depthtrack.track.height import body_for_sequence, trial_settings  # noqa: E402
from depthtrack.track.tracker import Tracker  # noqa: E402


def trial_sides(seq, settings) -> dict:
    """``{"frames", "facing_error_deg", "legs_exchanged", "arms_exchanged",
    "heading_switches", "limb_swaps"}`` of ``seq``'s shape-fit trial (per frame with a pose)."""
    body, _ = body_for_sequence(seq, settings=settings)
    s = trial_settings(settings)
    with Tracker(body, seq.camera, method="hc+ep", fps=seq.fps, settings=s) as tracker:
        stream = tracker.stream(seq.depth(i) for i in range(len(seq)))
        try:
            trial = list(itertools.islice(stream, s.shape.frames))
        finally:
            stream.close()
        described = tracker.describe()
    frames = [i for i, x in trial if x is not None]
    joints = np.asarray(body.joint_positions(np.stack([x for _, x in trial if x is not None])))
    truth = np.asarray(seq.joints)[frames]
    return {"frames": frames,
            "facing_error_deg": [round(float(v), 1) for v in facing_error_deg(joints, truth)],
            **{f"{limb}_exchanged": [bool(v) for v in sides_exchanged(joints, truth, order)]
               for limb, order in LIMB_SWAPS.items()},
            "heading_switches": [e["index"] for e in described["heading_switches"]],
            "limb_swaps": [[e["index"], e["limbs"]] for e in described["limb_swaps"]]}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter,
                                     epilog="example:\n  tools/trial_sides.py "
                                            "OUT/dev/sequences/02_03_c1_s1 --json trial.json")
    parser.add_argument("seqs", nargs="+", type=pathlib.Path, help="sequence directories with ground truth")
    parser.add_argument("--settings", default="{}", help="tracker settings (JSON), as for depthtrack track")
    parser.add_argument("--json", type=pathlib.Path, help="also write the frames' figures here")
    args = parser.parse_args(argv)
    try:
        settings = TrackerSettings().updated(json.loads(args.settings))
        seqs = [open_sequence(p) for p in args.seqs]
        for p, seq in zip(args.seqs, seqs):
            if seq.joints is None:
                raise InputError(p, "no ground truth (groundtruth/joints.csv)")
    except (InputError, OSError, ValueError) as exc:
        print(f"trial_sides: {exc}", file=sys.stderr)
        return 2
    out = {}
    for p, seq in zip(args.seqs, seqs):
        r = out[str(p)] = trial_sides(seq, settings)
        mark = {i: "H" for i in r["heading_switches"]} | {i: k[0].upper() for i, k in r["limb_swaps"]}
        print(f"{p.name}: heading switches {r['heading_switches']}, limb swaps {r['limb_swaps']}")
        print("  frame   " + " ".join(f"{i:>3d}{mark.get(i, ' ')}" for i in r["frames"]))
        print("  facing  " + " ".join(f"{v:>4.0f}" for v in r["facing_error_deg"]))
        for limb in LIMB_SWAPS:
            print(f"  {limb:7s} " + " ".join("   X" if v else "   ." for v in r[f"{limb}_exchanged"]),
                  flush=True)
    if args.json:
        args.json.write_text(json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
