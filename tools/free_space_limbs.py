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
``heading.reseat_hidden``, README "A limb tracked hidden"). With ``--hidden`` and
``--prior``, each listed limb is also set where a prior would put it, the rest of the pose
kept: a Gaussian over the 42 joint rotations of the train motions' poses (the train clips
of ``depthtrack/data/motion_split.json`` under ``--data``, retargeted and resampled to 30
Hz as ``tools/make_motion_prior.py`` does), its mean for the limb's two rotations given the
rest of the tracked pose, and its plain mean; printed, the end joint's mean error as
tracked and at each (README, "Figures: parity preset, the default with the hidden
re-seat").

    .venv/bin/python tools/free_space_limbs.py SEQ TRACK [SEQ TRACK ...] [--share 0.5] [--hidden 0.01 [--prior]] [--frames]
"""
from __future__ import annotations

import argparse
import pathlib
import sys

REPO = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "tools"))
import depthtrack  # noqa: E402,F401  (before numpy: the same OpenBLAS kernels on every machine)
import numpy as np  # noqa: E402

from depthtrack.body.skeleton import JOINT_ID  # noqa: E402
from depthtrack.contract import JOINT_INDEX  # noqa: E402
from depthtrack.errors import InputError  # noqa: E402
from depthtrack.track.heading_settings import HeadingSettings  # noqa: E402
from depthtrack.track.reach import LIMBS, hidden_limbs, share_in_pixels  # noqa: E402
from depthtrack.track.reseat import free_space_limbs  # noqa: E402
from track_replay import read_track  # noqa: E402


def limb_parameters(limb) -> np.ndarray:
    """``(6,)`` indices into a pose ``(48,)`` of ``limb``'s root and middle joint rotations
    (shoulder and elbow, hip and knee; joint ``j`` rotates by ``3 + 3j .. 5 + 3j``)."""
    root, mid, _ = LIMBS[limb]
    return np.concatenate([np.arange(3 + 3 * JOINT_ID[j], 6 + 3 * JOINT_ID[j]) for j in (root, mid)])


def rotation_gaussian(poses):
    """``(mean (42,), covariance (42, 42))`` of the joint rotations ``poses[:, 6:]`` of
    ``poses (N, 48)`` (a ridge of 1e-4 rad^2 keeps it invertible)."""
    r = np.asarray(poses, dtype=np.float64)[:, 6:]
    return r.mean(axis=0), np.cov(r.T) + 1e-4 * np.eye(r.shape[1])


def conditional_mean(mean, cov, values, free) -> np.ndarray:
    """The Gaussian ``(mean (D,), cov (D, D))``'s mean of the entries ``free`` given the
    others at ``values (D,)``: ``mu_f + S_fo S_oo^-1 (x_o - mu_o)``."""
    free = np.asarray(free)
    rest = np.setdiff1d(np.arange(len(values)), free)
    return mean[free] + cov[np.ix_(free, rest)] @ np.linalg.solve(cov[np.ix_(rest, rest)],
                                                                  values[rest] - mean[rest])


def prior_substitutes(mean, cov):
    """``(pose (48,), limb) -> [pose (48,), ...]``: the pose with ``limb``'s two rotations at
    the Gaussian's conditional mean given the rest, and at its plain mean."""
    def substitutes(pose, limb):
        free = limb_parameters(limb) - 6
        out = []
        for values in (conditional_mean(mean, cov, pose[6:], free), mean[free]):
            y = np.array(pose, dtype=np.float64)
            y[free + 6] = values
            out.append(y)
        return out
    return substitutes


def train_rotation_gaussian(data_dir):
    """:func:`rotation_gaussian` of the train clips' poses at 30 Hz on the default body."""
    from depthtrack.body import BodyModel
    from make_motion_prior import clip_poses, present_train_clips

    body = BodyModel.default()
    files = present_train_clips(data_dir)   # FileNotFoundError names the missing ones
    return rotation_gaussian(np.concatenate([clip_poses(f, body, 30.0)[0] for f in files]))


def limb_frames(seq, body, poses, share: float, pixels: int, gap: float, hidden=None,
                substitutes=None):
    """``[(frame, limb, listed, end error (m), substitutes' end errors (m))]`` for every frame
    with a pose and every limb; listed over free space, or with ``hidden`` (a share) tracked
    hidden; ``substitutes`` (``(pose, limb) -> poses``, e.g. :func:`prior_substitutes`) gives
    each listed limb's other poses, whose end errors come last (empty where not listed)."""
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
                listed = hidden_limbs(labels, mask, body.joint_names, share_in_pixels(mask, hidden))
            else:
                listed = {name for name, _ in free_space_limbs(
                    renderer.render(body, poses[f]), labels, seq.depth(f), body.joint_names,
                    share, pixels, gap)}
            joints = body.joint_positions(poses[f])
            for limb, (_, _, end) in LIMBS.items():
                k = JOINT_INDEX[end]
                others = ()
                if substitutes is not None and limb in listed:
                    others = tuple(float(np.linalg.norm(body.joint_positions(y)[k] - seq.joints[f][k]))
                                   for y in substitutes(poses[f], limb))
                rows.append((f, limb, limb in listed, float(np.linalg.norm(joints[k] - seq.joints[f][k])),
                             others))
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
    parser.add_argument("--prior", action="store_true",
                        help="with --hidden: also each listed limb at the train poses' Gaussian "
                             "(its conditional mean given the rest of the pose, and its mean)")
    parser.add_argument("--data", type=pathlib.Path, default=REPO.parent / "shared" / "data",
                        help="where the train clips of the motion split are (--prior)")
    parser.add_argument("--far", type=float, default=0.15, help="an end joint this far off (m) is wrong")
    parser.add_argument("--frames", action="store_true", help="print every listed limb-frame")
    args = parser.parse_args(argv)
    try:
        if len(args.pairs) % 2:
            raise InputError(None, "give each sequence directory followed by its track directory")
        if args.prior and args.hidden is None:
            raise InputError(None, "--prior asks where a prior puts the limbs listed hidden: give --hidden")
        substitutes = prior_substitutes(*train_rotation_gaussian(args.data)) if args.prior else None
        rows = []
        for seq_dir, track_dir in zip(args.pairs[::2], args.pairs[1::2]):
            seq, body, poses = read_track(seq_dir, track_dir, [])
            for f, limb, listed, err, others in limb_frames(seq, body, poses, args.share, args.pixels,
                                                            args.gap, args.hidden, substitutes):
                rows.append((seq_dir.name, f, limb, listed, err, others))
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
    if substitutes is not None and listed.any():
        errors = np.array([[r[4], *r[5]] for r in rows if r[3]])
        print(f"listed limbs' end joint, mean error: as tracked {100 * errors[:, 0].mean():.1f} cm, "
              f"at the train Gaussian's conditional mean {100 * errors[:, 1].mean():.1f} cm, "
              f"at its mean {100 * errors[:, 2].mean():.1f} cm")
    return 0


if __name__ == "__main__":
    sys.exit(main())
