"""Where a track leaves the person unexplained: along the body's outline, or away from it.

For each frame of a kept track the fitted body is rendered at the track's poses (as
``depthtrack eval`` scores the fit, :mod:`depthtrack.evaluate.fit`), and the person's
unexplained pixels are split by :func:`depthtrack.evaluate.fit.unexplained_parts`: not
covered or covered more than 10 cm off, each within two pixels of the body's outline (a
limb laid a pixel or two beside its person) or away from it (a limb elsewhere, a body too
thin). For a synthetic sequence the same is printed for the true body at the true poses
(rebuilt from ``sequence.json``, :func:`depthtrack.synth.generate.rendered_poses`; the
BVH file looked for in ``--motions``) and for the track's body at the true poses: what
the pose costs, against what the body's shape costs. Shares are of the person's pixels
with a reading, summed over the frames (README, "Final polish, climbed again")::

    .venv/bin/python tools/unexplained_where.py SEQ TRACK [--motions ../shared/data/cmu-extra] [--json OUT]
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

from depthtrack.errors import InputError  # noqa: E402
from depthtrack.evaluate.fit import PART_KEYS, frame_fit, person_masks, unexplained_parts  # noqa: E402
from depthtrack.io import open_sequence, read_track  # noqa: E402
from depthtrack.io.atomic import write_text_atomic  # noqa: E402


def parts_of(seq, masks, body, poses, renderer) -> dict:
    """Shares of :data:`PART_KEYS` and ``unexplained`` (their first four summed) and
    ``silhouette_iou`` (mean over frames) for ``poses (F, D)`` of ``body`` on ``seq``;
    frames without a person or a pose are left out."""
    counts = np.zeros(len(PART_KEYS) + 1, np.int64)
    ious = []
    for i in range(len(seq)):
        if not masks[i].any() or not np.all(np.isfinite(poses[i])):
            continue
        depth, rendered = seq.depth(i), renderer.render(body, poses[i])
        counts += unexplained_parts(masks[i], depth, rendered)
        ious.append(frame_fit(masks[i], depth, rendered)[0])
    n = max(int(counts[0]), 1)
    out = {k: float(c) / n for k, c in zip(PART_KEYS, counts[1:])}
    out["unexplained"] = float(counts[1:5].sum()) / n
    out["silhouette_iou"] = float(np.mean(ious)) if ious else None
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0],
        epilog="example: .venv/bin/python tools/unexplained_where.py OUT/dev/sequences/03_01_c1_s1 "
               "OUT/dev/tracks/03_01_c1_s1/hc+ep --motions ../shared/data/cmu-extra")
    parser.add_argument("seq", type=pathlib.Path, help="the sequence directory")
    parser.add_argument("track", type=pathlib.Path, help="a track output of it (body.json, poses.npz)")
    parser.add_argument("--motions", type=pathlib.Path, default=None,
                        help="folder of the BVH file a synthetic sequence was made from")
    parser.add_argument("--json", type=pathlib.Path, help="write the shares here")
    args = parser.parse_args(argv)
    try:
        from depthtrack.body import BodyModel
        from depthtrack.synth.generate import rendered_poses

        seq = open_sequence(args.seq)
        track = read_track(args.track)
        body_path = args.track / "body.json"
        if not body_path.is_file():
            raise InputError(body_path, "missing (the track's fitted body)")
        body = BodyModel.from_json(body_path)
        meta_path = args.seq / "sequence.json"
        meta = json.loads(meta_path.read_text()) if meta_path.is_file() else {}
        truth = rendered_poses(meta, args.motions) if "synth" in meta else None
    except (InputError, OSError, ValueError) as exc:
        print(f"unexplained_where: {exc}", file=sys.stderr)
        return 2
    except (KeyError, TypeError) as exc:
        print(f"unexplained_where: {args.seq / 'sequence.json'}: not a synthetic sequence's "
              f"synth block ({exc!r} missing or malformed)", file=sys.stderr)
        return 2
    from depthtrack.render import FrameRenderer

    masks = person_masks(seq)
    rows = {}
    with FrameRenderer(seq.camera) as renderer:
        rows["track's body, track's poses"] = parts_of(seq, masks, body, track.poses, renderer)
        if truth is not None:
            true_body, true_poses = truth
            rows["true body, true poses"] = parts_of(seq, masks, true_body, true_poses, renderer)
            rows["track's body, true poses"] = parts_of(seq, masks, body, true_poses, renderer)
    for name, r in rows.items():
        print(f"{name:28s} IoU {r['silhouette_iou']:.3f}  unexplained {100 * r['unexplained']:4.1f} % = "
              f"uncovered near outline {100 * r['uncovered_near_outline']:.1f} + away "
              f"{100 * r['uncovered_inside']:.1f}, off near outline {100 * r['off_near_outline']:.1f} "
              f"+ away {100 * r['off_inside']:.1f}; body off the person "
              f"{100 * r['body_off_person']:.1f} %")
    if args.json:
        write_text_atomic(args.json, json.dumps({"sequence": str(args.seq), "track": str(args.track),
                                                 "shares": rows}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
