"""The heading recheck replayed on a kept track, its judged lead before and after polishing.

On each frame ``F`` given (default every ``HeadingSettings.every``-th, as the recheck runs),
as ``heading.recheck_heading`` does it: the track's pose and its swapped twin are climbed on
the frame by the energy without the motion prior on the tracker's tiles, then judged on the
judge's tiles (``HeadingSettings.judge_tile``); then both are polished there
(``rechecks.close_call_polish``, what ``HeadingSettings.polish_within`` does to a close call)
and judged again. Printed per frame: the twin's lead per foreground pixel before and after
the polish (positive = the twin explains the frame better), and the share of each pose's
joints within 10 cm of the truth; then how many frames the twin led, before and after.
README, "A close front/back call, polished".

    .venv/bin/python tools/heading_polish.py SEQ TRACK [F,F,...] [--json OUT.json]

``SEQ``: a synthesized sequence with ``groundtruth/joints.csv``; ``TRACK``: a track of it
(``depthtrack track`` / ``eval --tracks-out``: ``body.json``, ``poses.npz``).
"""
from __future__ import annotations

import json
import pathlib
import sys

REPO = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "tools"))
import depthtrack  # noqa: E402,F401  (before numpy: the same OpenBLAS kernels on every machine)
import numpy as np  # noqa: E402

from depthtrack.errors import InputError  # noqa: E402
from depthtrack.track import TrackerSettings  # noqa: E402
from depthtrack.track.rechecks import close_call_polish, recheck_twins  # noqa: E402
from depthtrack.track.search import climb  # noqa: E402
from depthtrack.track.tracker import Tracker  # noqa: E402
from track_replay import frame_energy, parse_frames, read_track, track_parser  # noqa: E402


def within(body, pose, truth) -> float:
    """Share of ``pose (48,)``'s joints within 10 cm of ``truth (15, 3)``."""
    return float(np.mean(np.linalg.norm(body.joint_positions(pose) - truth, axis=1) < 0.10))


def main(argv=None) -> int:
    parser = track_parser(__doc__, "tools/heading_polish.py OUT/dev/sequences/105_05_c3_s2 "
                                   "OUT/dev/tracks/105_05_c3_s2/hc+ep")
    parser.add_argument("frames", nargs="?", default=None,
                        help="comma-separated frames (>= 1); default every recheck frame")
    parser.add_argument("--json", type=pathlib.Path, default=None,
                        help="also write the rows as JSON here")
    args = parser.parse_args(argv)
    settings = TrackerSettings()
    h = settings.heading
    try:
        given = None if args.frames is None else parse_frames(args.frames)
        seq, body, poses = read_track(args.seq, args.track, given or [])
        frames = given or list(range(h.every, len(poses), h.every))
    except (InputError, OSError, KeyError) as exc:
        print(f"heading_polish: {exc}", file=sys.stderr)
        return 2
    rows = []
    with Tracker(body, seq.camera, method="hc+ep", fps=seq.fps, settings=settings) as tr:
        polish = close_call_polish(tr)
        for f in frames:
            frame, energy = frame_energy(tr, seq, poses, f)
            bare = energy.on(tr.renderers.at_tile(h.recheck_tile))
            pixels = max(float(np.count_nonzero(frame.foreground.mask)), 1.0)

            def refit(pose):
                return climb(bare, tr.climbers.start, pose, tr.recorder, passes=h.twin_passes,
                             level_offset=h.refit_level)
            kept, _ = refit(poses[f])
            twin = min((refit(t) for t in recheck_twins(body, settings, bare, poses[f])),
                       key=lambda fit: float(fit[1]))[0]
            ek, et = tr.judge_energy()(np.stack([kept, twin]))
            (pk, pt), (pek, pet) = polish(np.stack([kept, twin]))
            truth = seq.joints[f]
            row = {"frame": f, "lead": round(float(ek - et) / pixels, 4),
                   "lead_polished": round(float(pek - pet) / pixels, 4),
                   "within_10cm_kept": within(body, kept, truth), "within_10cm_twin": within(body, twin, truth),
                   "within_10cm_twin_polished": within(body, pt, truth)}
            rows.append(row)
            print(f"frame {f:3d}: twin's lead per pixel {row['lead']:+.4f}, polished "
                  f"{row['lead_polished']:+.4f}; within 10 cm: kept {row['within_10cm_kept']:.2f}, "
                  f"twin {row['within_10cm_twin']:.2f}, polished twin {row['within_10cm_twin_polished']:.2f}",
                  flush=True)
    led = sum(r["lead"] > 0 for r in rows)
    led_polished = sum(r["lead_polished"] > 0 for r in rows)
    print(f"the twin led on {led} of {len(rows)} frames, polished on {led_polished}")
    if args.json is not None:
        args.json.write_text(json.dumps({"frames": rows, "led": led, "led_polished": led_polished},
                                        indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
