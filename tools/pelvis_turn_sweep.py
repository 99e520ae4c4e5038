"""What the likelihood and the motion prior each say of turning a tracked pelvis: on frame
``F`` of a kept track, the tracked pose with its pelvis turned about its own vertical axis
by -60 .. +60 degrees, alone (the chest and the thighs kept where they are, as the search's
untwist moves turn it) and with the whole body; per angle the change of the energy without
the motion prior and of the motion prior's penalty against the tracked pose.

The prediction is the tracker's: ``damping`` times the velocity between frames ``F - 2``
and ``F - 1`` of the track; ``--huber K`` scores the prior with Huber's loss
(``energy.prior_huber``).

    .venv/bin/python tools/pelvis_turn_sweep.py SEQ TRACK F [--huber K]
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
from depthtrack.motion.prior import ConstantVelocityPrior, apply_velocity, pose_velocity  # noqa: E402
from depthtrack.track import TrackerSettings  # noqa: E402
from depthtrack.track.hill_climb import SPINE, default_blocks  # noqa: E402
from depthtrack.track.tracker import Tracker  # noqa: E402
from track_replay import frame_energy, read_track, track_parser  # noqa: E402

ANGLES_DEG = np.arange(-60, 61, 10)


def main(argv=None) -> int:
    parser = track_parser(__doc__, "tools/pelvis_turn_sweep.py OUT/dev/sequences/90_05_c0_s2 "
                                   "OUT/dev/tracks/90_05_c0_s2/hc+ep 12")
    parser.add_argument("frame", type=int, help="the frame (>= 2)")
    parser.add_argument("--huber", type=float, default=0.0, help="Huber's k (default 0: Gaussian)")
    args = parser.parse_args(argv)
    try:
        if args.frame < 2:
            raise InputError(args.track, "the frame must be 2 or later (the prediction needs two)")
        seq, body, poses = read_track(args.seq, args.track, [args.frame])
    except (InputError, OSError, KeyError) as exc:
        print(f"pelvis_turn_sweep: {exc}", file=sys.stderr)
        return 2
    f = args.frame
    settings = TrackerSettings()
    prior = ConstantVelocityPrior.load(fps=seq.fps, damping=settings.energy.damping,
                                       huber=args.huber)
    pelvis = next(g for block in default_blocks() for g in block if g.name == "pelvis")
    angles = np.radians(ANGLES_DEG)
    turns = np.zeros((len(angles), body.dof))
    turns[:, pelvis.params[1]] = angles
    v_pred = prior.predict_velocity(pose_velocity(poses[f - 2], poses[f - 1]))
    zero = int(np.flatnonzero(ANGLES_DEG == 0)[0])
    with Tracker(body, seq.camera, method="hc", fps=seq.fps, settings=settings) as tracker:
        _, energy = frame_energy(tracker, seq, poses, f)
        x = poses[f]
        print(f"frame {f}: change against the tracked pose, likelihood / prior "
              f"({'Huber k = ' + str(args.huber) if args.huber else 'Gaussian'})")
        for name, kept in (("pelvis alone", pelvis.compensate + (SPINE,)), ("whole body", ())):
            deltas = pelvis.compensated(turns, kept, x) if kept else turns
            candidates = body.clip(apply_velocity(x, deltas))
            likelihood = energy(candidates)
            penalty = prior.penalty(candidates, poses[f - 1], v_pred)
            print(f"{name:13s}" + " ".join(
                f"{a:+d}: {likelihood[i] - likelihood[zero]:+.0f} / {penalty[i] - penalty[zero]:+.0f}"
                for i, a in enumerate(ANGLES_DEG)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
