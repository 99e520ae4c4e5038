"""How much a coarser candidate mesh changes the scores: the costs of candidate poses on a
kept track's frames, rendered with each shipped level of detail, against the full mesh's.

On every ``--every``-th frame of the track the tracked pose and 63 perturbations of it
(0.06 rad on every joint, 1.5 cm on the pelvis) are scored on that frame's observation as
the tracker saw it (``track_replay.frame_energy``) at the tracker's tile side. Printed per
mesh: the Spearman rank correlation of its costs with the full mesh's (mean over frames),
the mean cost difference in units of the candidates' spread, and how often its lowest
candidate is the full mesh's. The tracker ranks candidates, so the rank correlation is
what a level of detail must keep.

    .venv/bin/python tools/render_mesh_check.py SEQ TRACK [--every 4]
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
from depthtrack.render import TileRenderer  # noqa: E402
from depthtrack.track import TrackerSettings  # noqa: E402
from depthtrack.track.settings import RENDER_MESHES  # noqa: E402
from depthtrack.track.tracker import Tracker  # noqa: E402
from track_replay import frame_energy, read_track, track_parser  # noqa: E402

MESHES = ("full",) + tuple(m for m in RENDER_MESHES if m != "full")


def main(argv=None) -> int:
    from scipy.stats import spearmanr

    parser = track_parser(__doc__, "tools/render_mesh_check.py OUT/dev/sequences/13_14_c0_s1 "
                                   "OUT/dev/tracks/13_14_c0_s1/hc+ep")
    parser.add_argument("--every", type=int, default=4, help="frame step (default 4)")
    args = parser.parse_args(argv)
    try:
        seq, body, poses = read_track(args.seq, args.track, [1])
    except (InputError, OSError, KeyError) as exc:
        print(f"render_mesh_check: {exc}", file=sys.stderr)
        return 2
    rng = np.random.default_rng(0)
    rank = {m: [] for m in MESHES}
    gap = {m: [] for m in MESHES}
    same_best = dict.fromkeys(MESHES, 0)
    settings = TrackerSettings()
    with Tracker(body, seq.camera, method="hc", fps=seq.fps, settings=settings) as tracker:
        renderers = {m: TileRenderer(body.with_mesh(m), seq.camera, tile=settings.observe.tile)
                     for m in MESHES}
        try:
            frames = range(2, len(poses), max(1, args.every))
            for f in frames:
                frame, _ = frame_energy(tracker, seq, poses, f)
                candidates = np.repeat(poses[f][None], 64, axis=0)
                candidates[1:, 3:] += rng.normal(0.0, 0.06, (63, candidates.shape[1] - 3))
                candidates[1:, :3] += rng.normal(0.0, 0.015, (63, 3))
                candidates = body.clip(candidates)
                costs = {}
                for m, r in renderers.items():
                    r.set_observation(frame.observed, roi=frame.roi)
                    costs[m] = r.costs(candidates)
                spread = float(np.std(costs["full"]))
                for m in MESHES:
                    rank[m].append(spearmanr(costs["full"], costs[m])[0])
                    gap[m].append(float(np.mean(np.abs(costs[m] - costs["full"]))) / spread)
                    same_best[m] += int(np.argmin(costs[m]) == np.argmin(costs["full"]))
        finally:
            for r in renderers.values():
                r.release()
    n = len(rank["full"])
    print(f"{n} frames of {args.track}, 64 candidates each, tile {settings.observe.tile}")
    print(f"{'mesh':10s} {'triangles':>9s} {'rank corr.':>10s} {'cost gap':>9s} {'same best':>9s}")
    for m in MESHES:
        print(f"{m:10s} {body.with_mesh(m).mesh.num_faces:9d} {np.mean(rank[m]):10.4f} "
              f"{np.mean(gap[m]):9.3f} {same_best[m]:>5d}/{n}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
