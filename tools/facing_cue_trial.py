#!/usr/bin/env python
"""Trial (not used by the tracker): can a learned classifier tell from one depth frame
whether the person faces the camera or away?

The front/back check after a start and the rechecks while tracking compare how well two
fitted bodies explain the depth, and on some starts both explain it within a few percent
(README, "Front or back"). This asks whether the silhouette itself carries the answer in a
form a learned model picks up: upright frames rendered as the recogniser's training frames
are (:class:`train_recognizer.FrameSource`: train motions, perturbed poses, bodies 1.50 to
2.00 m, the three cameras, ToF noise, a wall behind), each person cropped to a 2:1 box,
depth relative to the person's median (clipped to +-0.6 m, background far), resized to
32 x 64; the label is whether the pelvis's forward axis points toward the camera. Every
crop also trains mirrored left-right (that does not change the facing). A scikit-learn
histogram gradient-boosting classifier is fitted; at test time a crop and its mirror are
averaged.

Reported: accuracy on held-out renders of the train motions (another seed) and of the dev
motions, over all frames and over frames whose facing is clear (the forward axis within
60 degrees of the line of sight), and with ``--sequences`` per benchmark sequence (the
tracker's own segmentation): accuracy on clear frames, and whether the mean over the
first ten frames gets the first ten frames' facing right.

Usage::

    nice .venv/bin/python tools/facing_cue_trial.py [--frames 20000] [--eval-frames 1500]
        [--sequences OUT/dev/sequences/*] [--data ../shared/data]
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import depthtrack  # noqa: F401  (first, before numpy: the same OpenBLAS kernels on every machine)
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tools"))

from depthtrack.progress import Progress  # noqa: E402

CROP_ROWS, CROP_COLS, CLIP_M = 64, 32, 0.6


def person_crop(depth, mask):
    """(64, 32) float32 depth relative to the person's median in a 2:1 box around ``mask``
    (``depth (H, W)``, ``mask (H, W) bool``); None with fewer than 30 person pixels."""
    import cv2

    rows, cols = np.nonzero(mask)
    if len(rows) < 30:
        return None
    rel = np.where(mask, np.clip(depth - np.median(depth[mask]), -CLIP_M, CLIP_M), CLIP_M)
    r0, r1, c0, c1 = rows.min(), rows.max() + 1, cols.min(), cols.max() + 1
    side = max(r1 - r0, 2 * (c1 - c0))
    canvas = np.full((side, side // 2), CLIP_M, np.float32)
    oy, ox = (side - (r1 - r0)) // 2, (side // 2 - (c1 - c0)) // 2
    canvas[oy:oy + r1 - r0, ox:ox + c1 - c0] = rel[r0:r1, c0:c1]
    return cv2.resize(canvas, (CROP_COLS, CROP_ROWS), interpolation=cv2.INTER_AREA)


def rendered_set(motions, n_frames: int, seed: int, label: str):
    """``(crops (N, 64, 32), forward_z (N,))``: upright rendered frames; ``forward_z`` < 0
    faces the camera (the camera looks along +z)."""
    from recognizer_eval import body_axes
    from train_recognizer import FrameSource

    source = FrameSource(motions, seed, upright_fraction=1.0)
    crops, forward = [], []
    try:
        with Progress(n_frames, f"{label} frames") as progress:
            for _ in range(n_frames):
                _, _, frame, _ = source.frame()
                crop = person_crop(frame.depth, frame.mask)
                if crop is not None:
                    crops.append(crop)
                    forward.append(body_axes(source.body, frame.pose)[2, 0])
                progress.update()
    finally:
        source.release()
    return np.array(crops), np.array(forward)


def facing_probability(model, crops) -> np.ndarray:
    """(N,) probability of facing the camera, a crop and its mirror averaged."""
    flat = crops.reshape(len(crops), -1)
    mirrored = crops[:, :, ::-1].reshape(len(crops), -1)
    return (model.predict_proba(flat)[:, 1] + model.predict_proba(mirrored)[:, 1]) / 2


def score_sequence(model, path) -> dict:
    """Per-frame accuracy on clear frames and the first ten frames' verdict on one sequence."""
    from benchmark import truth_facing_cosines
    from depthtrack.detect import segment_foreground
    from depthtrack.io import open_sequence

    seq = open_sequence(path)
    cos = truth_facing_cosines(seq)
    p = np.full(len(seq), np.nan)
    for i in range(len(seq)):
        depth = seq.depth(i)
        crop = person_crop(depth, segment_foreground(depth, seq.camera).mask)
        if crop is not None:
            p[i] = facing_probability(model, crop[None])[0]
    clear = np.isfinite(p) & (np.abs(cos) > 0.5)
    first = np.nanmean(p[:10])
    return {"name": Path(path).name, "clear_accuracy": float(np.mean((p[clear] > 0.5) == (cos[clear] > 0))),
            "first10_p": float(first), "first10_cos": float(np.mean(cos[:10])),
            "first10_right": bool((first > 0.5) == (np.mean(cos[:10]) > 0))}


def main(argv=None) -> int:
    from sklearn.ensemble import HistGradientBoostingClassifier

    from depthtrack.body import BodyModel
    from train_recognizer import motion_sets

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--frames", type=int, default=20000, help="training frames (default 20000)")
    ap.add_argument("--eval-frames", type=int, default=1500, help="frames per evaluation set")
    ap.add_argument("--sequences", nargs="*", default=[], help="benchmark sequences with ground truth")
    ap.add_argument("--data", type=Path, default=ROOT.parent / "shared" / "data")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)

    sets = motion_sets(BodyModel.default(), args.data)
    X, fz = rendered_set(sets["train"], args.frames, args.seed, "training")
    X, fz = np.concatenate([X, X[:, :, ::-1]]), np.concatenate([fz, fz])
    model = HistGradientBoostingClassifier(max_iter=600, max_leaf_nodes=63, random_state=args.seed)
    model.fit(X.reshape(len(X), -1), (fz < 0).astype(int))
    for label, motions, seed in (("held-out renders", sets["train"], args.seed + 9),
                                 ("dev renders", sets["dev"], args.seed + 5)):
        Xe, fe = rendered_set(motions, args.eval_frames, seed, label)
        right = (facing_probability(model, Xe) > 0.5) == (fe < 0)
        clear = np.abs(fe) > 0.5
        print(f"{label}: {right.mean():.3f} of frames right, {right[clear].mean():.3f} of clear frames "
              f"({clear.sum()} of {len(fe)})")
    rows = [score_sequence(model, path) for path in args.sequences]
    for r in rows:
        print(f"{r['name']:18s} clear frames right {r['clear_accuracy']:.2f}; first ten frames: "
              f"p(faces camera) {r['first10_p']:.2f}, truth cosine {r['first10_cos']:+.2f} -> "
              f"{'right' if r['first10_right'] else 'WRONG'}")
    if rows:
        print(f"mean over sequences: clear frames right {np.nanmean([r['clear_accuracy'] for r in rows]):.3f}; "
              f"first ten frames right on {sum(r['first10_right'] for r in rows)} of {len(rows)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
