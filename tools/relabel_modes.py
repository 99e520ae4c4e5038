"""Name a track's failure mode: which relabelling of its joints lies nearer the truth.

Per frame, the tracked joints (``body.json`` and ``poses.npz`` of a track) are compared
with the sequence's ground truth as they are and relabelled every way a front/back or
sides mistake would leave them: every side exchanged (``turned``: the body facing the
wrong way), every side but the knees' and ankles' (``turned_legs_kept``: facing the wrong
way with the thighs crossed so the legs are right; ``HeadingSettings.twin_swaps``), the
legs' sides only, the arms' sides only. A frame counts for a relabelling when the track is
more than ``--off`` metres off on average and the relabelling is nearer by the fraction
``--nearer`` at least. A frame that is that far off, for which no relabelling counts, and
whose trunk is turned 45 to 135 degrees from the true one
(:func:`depthtrack.body.facing.facing_error_deg`) counts as ``quarter_turned``: seen in
profile where the person faces the camera, or the reverse -- a mistake no exchange of sides
mends.

    .venv/bin/python tools/relabel_modes.py SEQ TRACK [SEQ TRACK ...] [--json OUT]

SEQ: a synthesized sequence with ground truth; TRACK: its track directory (``--tracks-out``
of ``depthtrack eval``, ``NAME/hc+ep``).
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
from depthtrack.body.facing import facing_error_deg  # noqa: E402
from depthtrack.contract import JOINT_NAMES  # noqa: E402
from depthtrack.errors import InputError  # noqa: E402
from depthtrack.io import open_sequence  # noqa: E402
from depthtrack.track.twins import ARMS_SWAPPED, LEGS_SWAPPED, TWIN_ORDERS  # noqa: E402

#: Relabelling name -> contract joint order (index j of the relabelled joints holds the
#: tracked joint that would be j's under that mistake).
RELABELLINGS = {"turned": TWIN_ORDERS["all"], "turned_legs_kept": TWIN_ORDERS["all_but_legs"],
                "legs": LEGS_SWAPPED, "arms": ARMS_SWAPPED}


def relabel_errors(tracked, truth):
    """``{name: (F,)}``: the mean joint distance (m) per frame of ``tracked (F, 15, 3)`` against
    ``truth (F, 15, 3)``, as tracked (``"as_tracked"``) and under each of :data:`RELABELLINGS`."""
    tracked, truth = np.asarray(tracked), np.asarray(truth)
    out = {"as_tracked": np.linalg.norm(tracked - truth, axis=2).mean(axis=1)}
    for name, order in RELABELLINGS.items():
        out[name] = np.linalg.norm(tracked[:, order] - truth, axis=2).mean(axis=1)
    return out


def modes(errors, off: float, nearer: float, facing_deg=None):
    """``{name: frames}``: per relabelling, the frames where the track is more than ``off`` m
    off and that relabelling is the nearest, nearer by the fraction ``nearer`` at least; with
    ``facing_deg (F,)`` (:func:`facing_error_deg`) also ``"quarter_turned"``: the frames that
    far off, no relabelling's, whose trunk is turned 45 to 135 degrees from the truth's."""
    names = list(RELABELLINGS)
    stack = np.stack([errors[n] for n in names])                    # (R, F)
    best = np.argmin(stack, axis=0)
    asis = errors["as_tracked"]
    hit = (asis > off) & (stack[best, np.arange(len(asis))] < (1.0 - nearer) * asis)
    out = {n: [int(f) for f in np.flatnonzero(hit & (best == k))] for k, n in enumerate(names)}
    if facing_deg is not None:
        deg = np.nan_to_num(np.asarray(facing_deg, dtype=np.float64), nan=0.0)
        quarter = (asis > off) & ~hit & (deg > 45.0) & (deg <= 135.0)
        out["quarter_turned"] = [int(f) for f in np.flatnonzero(quarter)]
    return out


def track_joints(seq_dir: pathlib.Path, track_dir: pathlib.Path):
    """``(tracked (F, 15, 3), truth (F, 15, 3))`` over the frames both have."""
    seq = open_sequence(seq_dir)
    if seq.joints is None:
        raise InputError(seq_dir, "no ground-truth joints (groundtruth/joints.csv)")
    body = BodyModel.from_json(track_dir / "body.json")
    poses = np.load(track_dir / "poses.npz")["poses"]
    n = min(len(poses), len(seq.joints))
    tracked = np.asarray(body.joint_positions(poses[:n])).reshape(n, len(JOINT_NAMES), 3)
    return tracked, np.asarray(seq.joints[:n])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter,
                                     epilog="example:\n  .venv/bin/python tools/relabel_modes.py "
                                            "OUT/dev/sequences/01_08_c3_s3 "
                                            "OUT/dev/tracks/01_08_c3_s3/hc+ep")
    parser.add_argument("pairs", nargs="+", type=pathlib.Path, metavar="SEQ TRACK",
                        help="sequence directories with ground truth, each followed by its track")
    parser.add_argument("--off", type=float, default=0.08, help="metres off on average (0.08)")
    parser.add_argument("--nearer", type=float, default=0.4, help="fraction nearer (0.4)")
    parser.add_argument("--json", type=pathlib.Path, help="write the frames per mode here")
    args = parser.parse_args(argv)
    if len(args.pairs) % 2:
        parser.error("give each sequence with its track: SEQ TRACK [SEQ TRACK ...]")
    report, totals = {}, {n: 0 for n in [*RELABELLINGS, "quarter_turned"]}
    try:
        for seq_dir, track_dir in zip(args.pairs[::2], args.pairs[1::2]):
            tracked, truth = track_joints(seq_dir, track_dir)
            found = modes(relabel_errors(tracked, truth), args.off, args.nearer,
                          facing_error_deg(tracked, truth))
            report[str(track_dir)] = {"frames": len(tracked), **found}
            for n, frames in found.items():
                totals[n] += len(frames)
            counts = ", ".join(f"{n} {len(f)}" for n, f in found.items() if f) or "none"
            print(f"{seq_dir.name}: {len(tracked)} frames; {counts}")
    except (InputError, OSError, KeyError, ValueError) as err:
        print(f"relabel_modes: {err}", file=sys.stderr)
        return 2
    print("all: " + ", ".join(f"{n} {k}" for n, k in totals.items()))
    if args.json:
        args.json.write_text(json.dumps({"tracks": report, "totals": totals}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
