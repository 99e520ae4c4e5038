"""Front or back, scored at several tile sides: a kept track's pose against its twin facing
the other way and against a pose fitted to the true joints.

On each frame ``F`` given, as the front/back recheck does it (``heading.recheck_heading``):
the track's pose and its swapped twins (``HeadingSettings.twin_starts``) are climbed on the
frame by the energy without the motion prior, on the tracker's tiles, and the lower twin
competes; a pose fitted to the true joints is climbed alike. Each is then scored on tiles of
64, 128 and 256 pixels: printed, the twin's and the truth fit's energy relative to the
track's (negative = lower, the better explanation) and each one's unexplained share. A lead
the recheck's margins do not see on the tracker's tiles may show on finer ones
(``HeadingSettings.judge_tile``; README, "Front or back at a finer tile").

    .venv/bin/python tools/heading_tiles.py SEQ TRACK F[,F...]

``SEQ``: a synthesized sequence with ``groundtruth/joints.csv``; ``TRACK``: a track of it
(``depthtrack track`` / ``eval --tracks-out``: ``body.json``, ``poses.npz``).
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
from depthtrack.track.twins import facing_direction, fit_joints, limb_swapped_twins  # noqa: E402
from depthtrack.track.rechecks import heading_twins  # noqa: E402
from depthtrack.track.energy import unexplained  # noqa: E402
from depthtrack.track.search import climb  # noqa: E402
from depthtrack.track.tracker import Tracker  # noqa: E402
from track_replay import frame_energy, parse_frames, read_track, track_parser  # noqa: E402

TILES = (64, 128, 256)


def main(argv=None) -> int:
    parser = track_parser(__doc__, "tools/heading_tiles.py OUT/dev/sequences/overhead_c2_s1 "
                                   "OUT/dev/tracks/overhead_c2_s1/hc+ep 5,15,25,35,45")
    parser.add_argument("frames", help="comma-separated frames (>= 1)")
    parser.add_argument("--limbs", action="store_true",
                        help="the twins with the legs' or the arms' sides exchanged "
                             "(twins.limb_swapped_twins, the limbs' recheck) instead of the "
                             "front/back twin")
    args = parser.parse_args(argv)
    try:
        seq, body, poses = read_track(args.seq, args.track, parse_frames(args.frames))
    except (InputError, OSError, KeyError) as exc:
        print(f"heading_tiles: {exc}", file=sys.stderr)
        return 2
    settings = TrackerSettings()
    with Tracker(body, seq.camera, method="hc+ep", fps=seq.fps, settings=settings) as tr:
        for f in parse_frames(args.frames):
            truth = seq.joints[f]
            _, energy = frame_energy(tr, seq, poses, f)

            def climbed(pose):
                return climb(energy, tr.climbers.start, pose, tr.recorder)[0]

            kept = climbed(poses[f])
            twins = ([t for _, t in limb_swapped_twins(body, kept)] if args.limbs
                     else heading_twins(body, settings, kept))
            twin = min((climbed(t) for t in twins), key=energy.one)
            fitted = climbed(fit_joints(body, truth, kept))

            def error(pose):
                return 100 * np.linalg.norm(body.joint_positions(pose) - truth, axis=1).mean()

            print(f"frame {f}: mean joint error (cm) track {error(kept):.0f}, twin "
                  f"{error(twin):.0f}, truth fit {error(fitted):.0f}; the twin faces the track's "
                  f"way by {facing_direction(twin) @ facing_direction(kept):+.2f} (cosine)")
            for tile in TILES:
                e = energy.on(tr.renderers.at_tile(tile))
                ek, et, ef = e(np.stack([kept, twin, fitted]))
                print(f"  {tile:3d} px tiles: twin {et / ek - 1:+.3f}, truth fit {ef / ek - 1:+.3f}"
                      f" of the track's energy; unexplained track {unexplained(e, kept):.3f}, "
                      f"twin {unexplained(e, twin):.3f}, truth fit {unexplained(e, fitted):.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
