#!/usr/bin/env python
"""Train the head / hand / foot patch classifier and write ``depthtrack/data/part_classifier.npz``.

Training data are synthetic depth frames made the way ``depthtrack synth`` makes them
(body in a room with floor and back wall, ToF noise on most frames), from

* mocap clips in ``../shared/data`` retargeted onto the default body
  (``depthtrack.io.bvh.read_bvh`` + ``depthtrack.motion.retarget``) and the built-in
  procedural motions,
* random perturbations of those poses within the joint limits,

seen from random directions, distances, camera heights and rolls, with bodies of
different heights. Every geodesic extremum that :func:`depthtrack.detect.geodesic_extrema`
finds on the segmented person (:func:`depthtrack.detect.segment_foreground`) is labelled
from the renderer's bone-label image (:func:`depthtrack.synth.part_scenes.extremum_truth`).

Held-out evaluation is by *motion*: the test frames come from motions never used in
training (``punch.bvh`` and ``jump.bvh``; ``turn`` when the mocap folder is absent). The
script prints per-class precision and recall of the labels (an extremum counts as
labelled ``c`` when class ``c`` has probability >= 0.5, as ``detect_parts`` reports it),
the part-level recall (frames where a visible part got a correct detection within
0.15 m), and the position error against the tracker's part centres.

Usage::

    .venv/bin/python tools/train_part_classifier.py [--train-frames 1100] [--test-frames 360]
        [--seed 0] [--data ../shared/data] [--out depthtrack/data/part_classifier.npz] [--quiet]
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import depthtrack  # noqa: F401  (first, before numpy: the same OpenBLAS kernels on every machine)
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from depthtrack.body import BodyModel  # noqa: E402
from depthtrack.camera import Camera  # noqa: E402
from depthtrack.detect.classifier import CLASSES, DEFAULT_PATH, FEATURE_NAMES, PartClassifier, \
    extremum_features  # noqa: E402
from depthtrack.detect.geodesic import geodesic_extrema  # noqa: E402
from depthtrack.synth.part_scenes import extremum_truth, render_scene_frames  # noqa: E402
from depthtrack.detect.segment import segment_foreground  # noqa: E402
from depthtrack.progress import Progress  # noqa: E402
from depthtrack.synth.noise import ToFNoise  # noqa: E402

TRAIN_BVH = ("motions/walk.bvh", "motions/run.bvh", "cmu/126_01.bvh")
TEST_BVH = ("motions/punch.bvh", "motions/jump.bvh")
TRAIN_PROCEDURAL = ("wave", "squat", "turn")
HEIGHTS = (1.55, 1.65, 1.75, 1.85, 1.95)
EXTREMA = 7
#: Detected part classes -> indices into the tracker's PartModel (head, l_hand, r_hand, l_foot, r_foot).
PART_SLOTS = {"head": [0], "hand": [1, 2], "foot": [3, 4]}
MATCH_RADIUS = 0.15


def bvh_poses(path, body, fps=30.0):
    """World-frame poses (F, 48) of a BVH clip on ``body``, resampled to ``fps``."""
    from depthtrack.io.bvh import read_bvh
    from depthtrack.motion.retarget import canonical_axes, resample_poses, retarget, subject_height

    motion = read_bvh(path)
    to_world = np.eye(4)
    to_world[:3, :3] = canonical_axes(motion)
    poses = retarget(motion, body, world_to_camera=to_world,
                     scale=float(body.height) / subject_height(motion, body))
    return resample_poses(poses, motion.fps, fps)


def motion_sets(body, data: Path):
    """{"train": [(name, poses)], "test": [(name, poses)]} world-frame pose sequences."""
    from depthtrack.synth.procedural import procedural_motion

    train = [(name, procedural_motion(name, body, fps=10.0)) for name in TRAIN_PROCEDURAL]
    test = []
    if data.is_dir() and all((data / p).is_file() for p in TRAIN_BVH + TEST_BVH):
        train += [(Path(p).stem, bvh_poses(data / p, body, fps=10.0 if "cmu" in p else 30.0))
                  for p in TRAIN_BVH]
        test += [(Path(p).stem, bvh_poses(data / p, body)) for p in TEST_BVH]
    else:
        print(f"note: {data} not found; training on procedural motions only, testing on 'turn'",
              file=sys.stderr)
        test = [train.pop(2)]
    return {"train": train, "test": test}


def perturb(body, pose, rng, scale):
    """Random joint-angle perturbation of a world-frame pose, clipped to the joint limits."""
    out = pose.copy()
    sigma = np.full(body.dof, 0.15) * scale
    for name in ("shoulder", "elbow", "hip", "knee"):
        idx = [i for i, n in enumerate(body.pose_names) if name in n]
        sigma[idx] = 0.45 * scale
    sigma[:6] = 0.0
    out += rng.normal(0.0, 1.0, body.dof) * sigma
    return np.asarray(body.clip(out[None]))[0]


def sample_frames(motions, n_frames, rng, bodies, camera, renderer, perturb_fraction=0.6, quiet=False,
                  label="frames"):
    """Render ``n_frames`` random views; return features, true labels, and data to fit positions."""
    from depthtrack.track.evidence import PartModel

    parts = {id(b): PartModel.from_body(b) for b in bodies}
    noise = ToFNoise.for_camera("sr4000")
    X, y, centres, dirs, targets, frame_of = [], [], [], [], [], []
    visible = []        # per frame: {class: [(part position (3,))...]} of parts present in the image
    per_frame = []
    segmentation = []
    with Progress(n_frames, label, quiet=quiet) as progress:
        for f in range(n_frames):
            name, poses = motions[rng.integers(len(motions))]
            body = bodies[rng.integers(len(bodies))]
            pose = poses[rng.integers(len(poses))]
            if rng.random() < perturb_fraction:
                pose = perturb(body, pose, rng, scale=rng.uniform(0.5, 1.5))
            frame = render_scene_frames(
                body, pose[None], camera, renderer=renderer,
                noise=noise if rng.random() < 0.85 else None, rng=rng,
                distance=None if rng.random() < 0.5 else float(rng.uniform(2.5, 4.0)),
                azimuth=float(rng.uniform(0, 360)), camera_height=float(rng.uniform(0.8, 1.7)),
                roll_deg=float(rng.normal(0, 3.0)), labels=True)[0]
            fg = segment_foreground(frame.depth, camera)
            readable = frame.readable_mask()
            seg = {"iou": float((fg.mask & readable).sum() / max(1, (fg.mask | readable).sum())),
                   "floor_deg": float("nan"), "floor_m": float("nan")}
            if fg.floor_plane is not None:
                seg["floor_deg"] = float(np.degrees(np.arccos(np.clip(
                    fg.floor_plane[:3] @ frame.floor_plane[:3], -1, 1))))
                seg["floor_m"] = float(abs(fg.floor_plane[3] - frame.floor_plane[3]))
            segmentation.append(seg)
            ex = geodesic_extrema(fg, camera, count=EXTREMA)
            progress.update()
            if len(ex) == 0:
                continue
            feats = extremum_features(frame.depth, camera, ex, fg)
            truth = extremum_truth(frame.labels, ex.pixels, body.joint_names)
            part_pos = parts[id(body)].positions(body, frame.pose[None])[0]          # (5, 3)
            X.append(feats)
            y.append(truth)
            centres.append(ex.centres)
            dirs.append(ex.directions)
            tg = np.full((len(ex), 3), np.nan)
            for i, c in enumerate(truth):
                if c in PART_SLOTS:
                    cand = part_pos[PART_SLOTS[c]]
                    tg[i] = cand[np.argmin(np.linalg.norm(cand - ex.centres[i], axis=1))]
            targets.append(tg)
            frame_of.append(np.full(len(ex), len(per_frame)))
            # parts that show in the image (some body pixels of their bones are visible)
            seen = {c: part_pos[PART_SLOTS[c]][[bool(np.any(np.isin(frame.labels, [
                list(body.joint_names).index(b)]))) for b in bones]]
                for c, bones in {"head": ("neck",), "hand": ("l_wrist", "r_wrist"),
                                 "foot": ("l_ankle", "r_ankle")}.items()}
            per_frame.append({"motion": name, "seen": seen})
    return dict(X=np.vstack(X), y=np.concatenate(y), centres=np.vstack(centres), dirs=np.vstack(dirs),
                targets=np.vstack(targets), frame=np.concatenate(frame_of), frames=per_frame,
                segmentation=segmentation)


def fit_position_offsets(data, y_index):
    """Per class: metres along the extremum direction from cap centre to the part's surface centre."""
    offsets = np.zeros(len(CLASSES))
    for c, name in enumerate(CLASSES):
        sel = (y_index == c) & np.all(np.isfinite(data["targets"]), axis=1)
        if name != "other" and sel.sum() > 10:
            along = np.sum((data["targets"][sel] - data["centres"][sel]) * data["dirs"][sel], axis=1)
            offsets[c] = float(np.median(along))
    return offsets


def evaluate(model, data, min_score=0.5):
    """Per-class precision / recall over extrema, part-level recall, position errors (dict)."""
    p = model.predict_proba(data["X"])
    k = np.argmax(p, axis=1)
    pred = np.array(CLASSES, dtype=object)[k]
    pred[p[np.arange(len(k)), k] < min_score] = "other"
    truth = data["y"]
    positions = data["centres"] + model.position_offset[k][:, None] * data["dirs"]
    out = {}
    for c in CLASSES[:3]:
        tp = int(np.sum((pred == c) & (truth == c)))
        n_pred = int(np.sum(pred == c))
        n_true = int(np.sum(truth == c))
        err = np.linalg.norm(positions - data["targets"], axis=1)[(pred == c) & (truth == c)]
        # part level: visible parts with a detection of their class within MATCH_RADIUS
        hits = total = 0
        for f, info in enumerate(data["frames"]):
            mine = (data["frame"] == f) & (pred == c)
            for part in info["seen"][c]:
                total += 1
                hits += bool(np.any(np.linalg.norm(positions[mine] - part, axis=1) < MATCH_RADIUS))
        out[c] = {"precision": tp / n_pred if n_pred else float("nan"),
                  "recall": tp / n_true if n_true else float("nan"),
                  "extrema": n_true, "detections": n_pred,
                  "part_recall": hits / total if total else float("nan"), "parts": total,
                  "median_position_error_m": float(np.median(err)) if len(err) else float("nan")}
    out["accuracy"] = float(np.mean(pred == truth))
    return out


def segmentation_summary(data) -> dict:
    """IoU of the segmented person with the truly-read person pixels, and floor-plane errors."""
    iou = np.array([s["iou"] for s in data["segmentation"]])
    deg = np.array([s["floor_deg"] for s in data["segmentation"]])
    off = np.array([s["floor_m"] for s in data["segmentation"]])
    found = np.isfinite(deg)
    return {"iou_median": float(np.median(iou)), "iou_p5": float(np.percentile(iou, 5)),
            "floor_found": float(np.mean(found)),
            "floor_deg_median": float(np.median(deg[found])) if found.any() else float("nan"),
            "floor_deg_p95": float(np.percentile(deg[found], 95)) if found.any() else float("nan"),
            "floor_m_median": float(np.median(off[found])) if found.any() else float("nan"),
            "floor_m_p95": float(np.percentile(off[found], 95)) if found.any() else float("nan")}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--train-frames", type=int, default=1100)
    ap.add_argument("--test-frames", type=int, default=360)
    ap.add_argument("--trees", type=int, default=40)
    ap.add_argument("--max-depth", type=int, default=14)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--data", type=Path, default=ROOT.parent / "shared" / "data")
    ap.add_argument("--out", type=Path, default=DEFAULT_PATH)
    ap.add_argument("--quiet", action="store_true")
    args = ap.parse_args(argv)
    from sklearn.ensemble import RandomForestClassifier

    from depthtrack.render import FrameRenderer

    t0 = time.perf_counter()
    camera = Camera.preset("sr4000")
    renderer = FrameRenderer(camera)
    base = BodyModel.default()
    bodies = [base.scaled(height=h) for h in HEIGHTS]
    motions = motion_sets(base, args.data)
    train = sample_frames(motions["train"], args.train_frames, np.random.default_rng(args.seed), bodies,
                          camera, renderer, quiet=args.quiet, label="train frames")
    test = sample_frames(motions["test"], args.test_frames, np.random.default_rng(args.seed + 1000), bodies,
                         camera, renderer, quiet=args.quiet, label="test frames")
    t_data = time.perf_counter() - t0
    y_index = np.array([CLASSES.index(c) for c in train["y"]])
    forest = RandomForestClassifier(n_estimators=args.trees, max_depth=args.max_depth, min_samples_leaf=2,
                                    class_weight="balanced_subsample", n_jobs=2, random_state=args.seed)
    forest.fit(train["X"], y_index)
    offsets = fit_position_offsets(train, y_index)
    model = PartClassifier.from_sklearn(forest, position_offset=offsets)
    # the numpy evaluation must reproduce scikit-learn's
    assert np.allclose(model.predict_proba(test["X"]), forest.predict_proba(test["X"]), atol=2e-3)
    result = evaluate(model, test)
    result["segmentation"] = seg = segmentation_summary(test)
    train_counts = {c: int(np.sum(train["y"] == c)) for c in CLASSES}
    model.meta = {"trained_by": "tools/train_part_classifier.py", "seed": args.seed,
                  "train_frames": args.train_frames, "test_frames": args.test_frames,
                  "train_motions": [n for n, _ in motions["train"]],
                  "test_motions": [n for n, _ in motions["test"]], "train_extrema": train_counts,
                  "held_out": result, "features": len(FEATURE_NAMES)}
    # leaves hold the class probabilities; float16 storage keeps the file small
    model.save(args.out)
    seconds = time.perf_counter() - t0
    print(f"train: {args.train_frames} frames from {', '.join(n for n, _ in motions['train'])} "
          f"(+ random perturbations); extrema per class {train_counts}")
    print(f"held-out test: {args.test_frames} frames from {', '.join(n for n, _ in motions['test'])}")
    print(f"{'class':6} {'precision':>9} {'recall':>7} {'extrema':>8} {'part recall':>12} {'pos err (m)':>12}")
    for c in CLASSES[:3]:
        r = result[c]
        print(f"{c:6} {r['precision']:9.3f} {r['recall']:7.3f} {r['extrema']:8d} "
              f"{r['part_recall']:12.3f} {r['median_position_error_m']:12.3f}")
    print(f"accuracy over all extrema (4 classes): {result['accuracy']:.3f}")
    print(f"segmentation on the test frames: IoU with the person pixels that read true (within 5 cm) "
          f"median {seg['iou_median']:.3f}, 5th percentile {seg['iou_p5']:.3f}; floor found in "
          f"{seg['floor_found']:.0%} of frames, error median {seg['floor_deg_median']:.2f} deg / "
          f"{100 * seg['floor_m_median']:.1f} cm, 95th percentile {seg['floor_deg_p95']:.2f} deg / "
          f"{100 * seg['floor_m_p95']:.1f} cm")
    print(f"position offsets along the direction (m): "
          f"{dict(zip(CLASSES, np.round(offsets, 3).tolist()))}")
    print(f"wrote {args.out} ({args.out.stat().st_size / 1024:.0f} KiB); data {t_data:.0f} s, "
          f"total {seconds:.0f} s")
    print(json.dumps(result, indent=None, default=float))
    return 0


if __name__ == "__main__":
    sys.exit(main())
