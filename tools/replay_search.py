"""A recovery's global search replayed on one frame of a kept track, against the truth.

The search runs as ``judge.recover`` runs it on frame ``F``: on that frame's observation,
preferring the heading and body axis of the track's pose on frame ``F - 1``, with the
track's own body (``body.json``), by the energy without the motion prior. Printed for the
track's pose on ``F - 1`` and on ``F``, the search's result, and a pose fitted to the true
joints (then climbed): energy, unexplained share, facing against the previous pose (cosine),
share of joints within 10 cm and mean joint error. A search result whose energy is above the
truth fit's is a failure of the search, not of the likelihood.

    .venv/bin/python tools/replay_search.py SEQ TRACK F [--legs] [--bends]

``SEQ``: a synthesized sequence with ``groundtruth/joints.csv``; ``TRACK``: a track of it
(``depthtrack track`` / ``eval --tracks-out``: ``body.json``, ``poses.npz``); ``--legs``:
the search also tries raised legs (``StartSettings.legs``); ``--bends``: bodies bent at the
hips (``StartSettings.bends``). Example (README, "Lost and found"): dev 90_05 seed 1, frame
40.
"""
from __future__ import annotations

import pathlib
import sys

REPO = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "tools"))
import depthtrack  # noqa: E402,F401  (before numpy: the same OpenBLAS kernels on every machine)
import numpy as np  # noqa: E402

from depthtrack.errors import InputError  # noqa: E402
from depthtrack.track import TrackerSettings  # noqa: E402
from depthtrack.track.twins import facing_direction, fit_joints, long_axis  # noqa: E402
from depthtrack.track.energy import unexplained  # noqa: E402
from depthtrack.track.search import climb  # noqa: E402
from depthtrack.track.start import global_search  # noqa: E402
from depthtrack.track.tracker import Tracker  # noqa: E402
from track_replay import frame_energy, read_track, track_parser  # noqa: E402


def main(argv=None) -> int:
    parser = track_parser(__doc__, "tools/replay_search.py OUT/dev/sequences/90_05_c0_s1 "
                                   "OUT/dev/tracks/90_05_c0_s1/hc+ep 40 --legs")
    parser.add_argument("frame", type=int, help="the frame to replay (>= 1)")
    parser.add_argument("--legs", action="store_true", help="also try raised legs")
    parser.add_argument("--bends", action="store_true", help="also try bodies bent at the hips")
    args = parser.parse_args(argv)
    try:
        seq, body, poses = read_track(args.seq, args.track, [args.frame])
    except (InputError, OSError, KeyError) as exc:
        print(f"replay_search: {exc}", file=sys.stderr)
        return 2
    f = args.frame
    truth = seq.joints[f]
    previous = poses[f - 1]
    with Tracker(body, seq.camera, method="hc+ep", fps=seq.fps, settings=TrackerSettings()) as tr:
        frame, energy = frame_energy(tr, seq, poses, f)
        found, _, info = global_search(tr, energy, frame, heading=facing_direction(previous),
                                       body_axis=long_axis(previous), legs=args.legs,
                                       bends=args.bends)
        fitted = fit_joints(body, truth, previous)
        climbed, _ = climb(energy, tr.climbers.start, fitted, tr.recorder)

        def line(name, pose):
            err = np.linalg.norm(body.joint_positions(pose) - truth, axis=1)
            print(f"{name:22s} energy {energy.one(pose):9.1f}  unexplained "
                  f"{unexplained(energy, pose):.3f}  facing vs previous "
                  f"{facing_direction(pose) @ facing_direction(previous):+.2f}  within 10 cm "
                  f"{np.mean(err < 0.1):.2f}  mean error {100 * err.mean():.0f} cm")

        line(f"frame {f - 1}'s pose", previous)
        line(f"frame {f}'s tracked pose", poses[f])
        tried = (" with legs" if args.legs else "") + (" with bends" if args.bends else "")
        line("search" + tried, found)
        line("truth fit", fitted)
        line("truth fit, climbed", climbed)
        print("finalists:", ", ".join(f"{d['from']} {d['energy']}" for d in info["finalists"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
