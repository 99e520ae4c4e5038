"""Limbs a kept track holds over free space, each judged by the ground truth.

For every frame of a track, the track's pose is rendered at the camera's resolution and
``depthtrack.track.reseat.free_space_limbs`` lists the limbs whose forearm and hand (shin
and foot) the camera sees through: at least ``--share`` of their pixels with a reading
read more than ``--gap`` metres behind them (and at least ``--pixels`` of them). Printed:
how often a listed limb's end joint (wrist, ankle) is more than ``--far`` from the truth
(the trigger's precision), how many of the limb-frames that far off it lists (its
recall), and with ``--frames`` each listed limb-frame. Nothing is tracked; how the
free-space re-seat (``heading.reseat_free``) was named (README, "A limb over free space").
With ``--hidden SHARE`` the limbs listed are those tracked hidden instead
(``depthtrack.track.reach.hidden_limbs``: forearm and hand, or shin and foot, on fewer than
that share of the person's pixels, the person segmented by ``segment_foreground``;
``heading.reseat_hidden``, README "A limb tracked hidden").

    .venv/bin/python tools/free_space_limbs.py SEQ TRACK [SEQ TRACK ...] [--share 0.5] [--hidden 0.01] [--frames]
"""
from __future__ import annotations

import argparse
import pathlib
import sys

import numpy as np

REPO = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "tools"))

from depthtrack.contract import JOINT_INDEX  # noqa: E402
from depthtrack.errors import InputError  # noqa: E402
from depthtrack.track.heading_settings import HeadingSettings  # noqa: E402
from depthtrack.track.reach import LIMBS, hidden_limbs  # noqa: E402
from depthtrack.track.reseat import free_space_limbs  # noqa: E402
from track_replay import read_track  # noqa: E402


def limb_frames(seq, body, poses, share: float, pixels: int, gap: float, hidden=None):
    """``[(frame, limb, listed, end error (m))]`` for every frame with a pose and every limb;
    listed over free space, or with ``hidden`` (a share) tracked hidden."""
    from depthtrack.detect import segment_foreground
    from depthtrack.render import FrameRenderer

    rows = []
    with FrameRenderer(seq.camera) as renderer:
        for f in range(len(poses)):
            if not np.isfinite(poses[f]).all():
                continue
            labels = renderer.render_labels(body, poses[f])
            if hidden is not None:
                mask = segment_foreground(seq.depth(f), seq.camera).mask
                listed = hidden_limbs(labels, mask, body.joint_names,
                                      int(np.ceil(hidden * np.count_nonzero(mask))))
            else:
                listed = {name for name, _ in free_space_limbs(
                    renderer.render(body, poses[f]), labels, seq.depth(f), body.joint_names,
                    share, pixels, gap)}
            joints = body.joint_positions(poses[f])
            for limb, (_, _, end) in LIMBS.items():
                k = JOINT_INDEX[end]
                rows.append((f, limb, limb in listed, float(np.linalg.norm(joints[k] - seq.joints[f][k]))))
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter,
                                     epilog="example:\n  tools/free_space_limbs.py OUT/dev/sequences/"
                                            "124_01_c2_s2 OUT/dev/tracks/124_01_c2_s2/hc+ep --frames")
    parser.add_argument("pairs", nargs="+", type=pathlib.Path, metavar="SEQ TRACK",
                        help="sequence directories with ground truth, each followed by its track")
    h = HeadingSettings()                # the tracker's defaults, one place
    parser.add_argument("--share", type=float, default=h.reseat_free, help="HeadingSettings.reseat_free")
    parser.add_argument("--pixels", type=int, default=h.reseat_free_pixels,
                        help="HeadingSettings.reseat_free_pixels")
    parser.add_argument("--gap", type=float, default=h.reseat_free_gap,
                        help="HeadingSettings.reseat_free_gap (m)")
    parser.add_argument("--hidden", type=float, metavar="SHARE",
                        help="list the limbs tracked hidden at this share instead (heading.reseat_hidden)")
    parser.add_argument("--far", type=float, default=0.15, help="an end joint this far off (m) is wrong")
    parser.add_argument("--frames", action="store_true", help="print every listed limb-frame")
    args = parser.parse_args(argv)
    try:
        if len(args.pairs) % 2:
            raise InputError(None, "give each sequence directory followed by its track directory")
        rows = []
        for seq_dir, track_dir in zip(args.pairs[::2], args.pairs[1::2]):
            seq, body, poses = read_track(seq_dir, track_dir, [])
            for f, limb, listed, err in limb_frames(seq, body, poses, args.share, args.pixels, args.gap,
                                                    args.hidden):
                rows.append((seq_dir.name, f, limb, listed, err))
                if listed and args.frames:
                    print(f"{seq_dir.name} frame {f:3d} {limb}: end joint {100 * err:5.1f} cm off")
    except (InputError, OSError, KeyError) as exc:
        print(f"free_space_limbs: {exc}", file=sys.stderr)
        return 2
    listed = np.array([r[3] for r in rows], dtype=bool)
    far = np.array([r[4] > args.far for r in rows], dtype=bool)
    print(f"{len(rows)} limb-frames, {far.mean():.1%} with the end joint over {100 * args.far:.0f} cm off; "
          f"listed {'hidden' if args.hidden is not None else 'over free space'}: "
          f"{listed.sum()} ({listed.mean():.1%}), of them that far off "
          f"{far[listed].mean() if listed.any() else float('nan'):.0%} (precision); "
          f"of those that far off, listed {listed[far].mean() if far.any() else float('nan'):.0%} (recall)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
