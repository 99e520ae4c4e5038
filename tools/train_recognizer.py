#!/usr/bin/env python
"""Train the per-pixel body-part recogniser and write ``depthtrack/data/recognizer.npz``.

Training frames are rendered from random poses of the *train* motions of
``depthtrack/data/motion_split.json`` (the clips that load; the others are named and
skipped) and the built-in procedural motions, half of them perturbed within the joint
limits, on bodies 1.50 to 2.00 m tall, seen by the three camera presets (sr4000,
kinect-v2, azure-nfov) from 1.5 to 4.5 m: half upright (any heading, camera pitch and a
little roll), half at a uniformly random 3D orientation (lying, upside down, ...), most
with ToF noise and a wall behind the body (its flying pixels). Each frame gives the
renderer's per-pixel part labels (:func:`depthtrack.synth.part_scenes.render_part_frame`).

Sampled pixels get depth-difference features for a few hundred random offset pairs
(:mod:`depthtrack.detect.features`); scikit-learn grows the trees, each on its own share
of pixels and offsets, and the trees are exported to flat numpy arrays
(:class:`depthtrack.detect.recognizer.PartForest`), checked against scikit-learn, then the
joints' push-back depths are fitted on further training-motion frames.

Evaluation (printed, and stored in the model's ``meta``): per-part precision and recall
over person pixels and the fraction of joints with a proposal within 10 cm, on held-out
renders of the train motions (another seed), on the dev motions, and on the test motions
(reported only, never tuned on).

Usage::

    OMP_NUM_THREADS=1 nice -n 10 .venv/bin/python tools/train_recognizer.py --seed 0 --frames 3000 \
        --extras centroid --trees 4 [--cache /tmp/set.npz] [--eval-frames 120] [--sets held-out,dev]
        [--data ../shared/data] [--out depthtrack/data/recognizer.npz]      # the shipped model
    nice -n 10 .venv/bin/python tools/train_recognizer.py --eval-only   # evaluate the shipped model
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
sys.path.insert(0, str(ROOT / "tools"))

from depthtrack.body import BodyModel  # noqa: E402
from depthtrack.body.rotations import quat_to_matrix, rotation_about  # noqa: E402
from depthtrack.camera import Camera  # noqa: E402
from depthtrack.contract import JOINT_NAMES  # noqa: E402
from depthtrack.detect.features import centroid_features, depth_features, probe_image, sample_offsets  # noqa: E402
from depthtrack.detect.recognizer import PartForest, Trees, default_path, joint_proposals, recognize  # noqa: E402
from depthtrack.detect.recognizer_parts import NUM_PARTS  # noqa: E402
from depthtrack.progress import Progress  # noqa: E402
from depthtrack.synth.noise import ToFNoise  # noqa: E402
from depthtrack.synth.part_scenes import render_part_frame  # noqa: E402
from depthtrack.synth.scene import transform_poses  # noqa: E402
from train_part_classifier import bvh_poses, perturb  # noqa: E402
from recognizer_eval import body_axes, evaluate, print_report  # noqa: E402

CAMERAS = ("sr4000", "kinect-v2", "azure-nfov")
HEIGHTS = (1.50, 1.62, 1.75, 1.87, 2.00)
PROCEDURAL_TRAIN = ("wave", "squat", "turn", "mixed")
SPLIT_PATH = ROOT / "depthtrack" / "data" / "motion_split.json"


def load_motions(names, body, data: Path, fps: float = 6.0):
    """[(name, world poses (F, 48))] of the clips that load; a note for each that does not."""
    out = []
    for name in names:
        try:
            out.append((name, bvh_poses(data / name, body, fps=fps)))
        except Exception as exc:     # noqa: BLE001 -- a clip our reader cannot take yet is skipped, said
            print(f"note: skipped {name}: {str(exc).splitlines()[0][:120]}", file=sys.stderr)
    return out


def motion_sets(body, data: Path):
    """{"train" | "dev" | "test": [(name, world poses)]} from the motion split."""
    from depthtrack.synth.procedural import procedural_motion

    split = json.loads(SPLIT_PATH.read_text())
    sets = {part: load_motions(split[part], body, data) for part in ("train", "dev", "test")}
    sets["train"] += [(f"procedural:{n}", procedural_motion(n, body, fps=6.0)) for n in PROCEDURAL_TRAIN]
    return sets


def random_rotation(rng, upright: bool) -> np.ndarray:
    """(3, 3): any heading with camera pitch and roll when upright, else uniform over SO(3)."""
    if not upright:
        q = rng.normal(size=4)
        return quat_to_matrix(q / np.linalg.norm(q))
    yaw = rotation_about(np.array([0.0, 1.0, 0.0]), rng.uniform(0, 2 * np.pi))
    pitch = rotation_about(np.array([1.0, 0.0, 0.0]), np.radians(rng.uniform(-10, 35)))
    roll = rotation_about(np.array([0.0, 0.0, 1.0]), np.radians(rng.normal(0, 5)))
    return roll @ pitch @ yaw


def place(body, pose, camera, rng, upright: bool, max_depth: float) -> np.ndarray:
    """A world pose rotated and moved into the camera frame so the body is (mostly) in view."""
    p = np.array(pose, float)
    p[:3] = 0.0
    T = np.eye(4)
    T[:3, :3] = random_rotation(rng, upright)
    local = transform_poses(p[None], T)[0]
    pts = np.asarray(body.joint_positions(local))
    lo, hi = pts.min(0) - 0.15, pts.max(0) + 0.15
    # nearest distance at which the joints' box fits the image, then a random distance beyond it
    fit = max((hi[0] - lo[0]) * camera.fx / camera.width, (hi[1] - lo[1]) * camera.fy / camera.height)
    z = np.clip(max(fit - lo[2], rng.uniform(1.5, 4.5)), 1.2, max_depth - hi[2] - 0.3)
    # shift within the room the image leaves (a small share of frames cut at the border)
    slack = np.array([camera.width, camera.height]) / np.array([camera.fx, camera.fy]) * z \
        - (hi[:2] - lo[:2])
    shift = rng.uniform(-0.5, 0.5, 2) * np.maximum(slack, 0) * (1.0 if rng.random() < 0.85 else 1.6)
    centre = (lo[:2] + hi[:2]) / 2
    principal = (np.array([camera.width, camera.height]) / 2 - [camera.cx, camera.cy]) / [camera.fx, camera.fy] * z
    local[:3] = [shift[0] - centre[0] + principal[0], shift[1] - centre[1] + principal[1], z]
    return local


class FrameSource:
    """Random rendered frames with part labels, reproducible from one seed."""

    def __init__(self, motions, seed: int, cameras=CAMERAS, upright_fraction=0.5, perturb_fraction=0.5):
        from depthtrack.render import FrameRenderer

        base = BodyModel.default()
        self.bodies = [base.scaled(height=h) for h in HEIGHTS]
        self.motions = motions
        self.cameras = {c: Camera.preset(c) for c in cameras}
        self.renderers = {c: FrameRenderer(cam) for c, cam in self.cameras.items()}
        self.rng = np.random.default_rng(seed)
        self.upright_fraction = upright_fraction
        self.perturb_fraction = perturb_fraction

    def frame(self):
        """(camera name, Camera, SceneFrame, upright)."""
        rng = self.rng
        name, poses = self.motions[rng.integers(len(self.motions))]
        self.body = body = self.bodies[rng.integers(len(self.bodies))]
        pose = poses[rng.integers(len(poses))]
        if rng.random() < self.perturb_fraction:
            pose = perturb(body, pose, rng, scale=rng.uniform(0.5, 1.5))
        cam_name = list(self.cameras)[rng.integers(len(self.cameras))]
        camera = self.cameras[cam_name]
        noise = ToFNoise.for_camera(cam_name)
        upright = bool(rng.random() < self.upright_fraction)
        local = place(body, pose, camera, rng, upright, noise.max_range)
        frame = render_part_frame(body, local, camera, self.renderers[cam_name],
                                  noise=noise if rng.random() < 0.85 else None, rng=rng,
                                  wall_gap=float(rng.uniform(0.3, 2.0)) if rng.random() < 0.8 else None)
        return cam_name, camera, frame, upright

    def release(self):
        for r in self.renderers.values():
            r.release()


def sample_pixels(labels, mask, count, rng):
    """(n, 2) (row, col) person pixels, rarer parts drawn more often (weight 1/sqrt(count))."""
    rows, cols = np.nonzero(mask & (labels >= 0))
    if not len(rows):
        return np.zeros((0, 2), int)
    lab = labels[rows, cols]
    freq = np.bincount(lab, minlength=NUM_PARTS)[lab].astype(float)
    w = 1.0 / np.sqrt(freq)
    pick = rng.choice(len(rows), size=min(count, len(rows)), replace=False, p=w / w.sum())
    return np.stack([rows[pick], cols[pick]], axis=1)


def person_points(depth, mask, camera, rows, cols):
    """(N, 3) camera-frame points of pixels, and the centre (3,) of all the mask's points."""
    pts = camera.backproject(depth[rows, cols], np.stack([cols, rows], axis=1).astype(float))
    r, c = np.nonzero(mask & (depth > 0))
    centre = camera.backproject(depth[r, c], np.stack([c, r], axis=1).astype(float)).mean(axis=0)
    return pts.astype(np.float32), centre


def make_training_set(source, n_frames, offsets, per_frame, quiet):
    """Sampled pixels: features (N, K) float16, parts (N,), points (N, 3), frame index (N,);
    per frame: true body axes (F, 3, 3) and the person's centre (F, 3)."""
    X, y, P, fid, axes, centres = [], [], [], [], [], []
    with Progress(n_frames, "training frames", quiet=quiet) as progress:
        for _ in range(n_frames):
            _, camera, frame, _ = source.frame()
            px = sample_pixels(frame.labels, frame.mask, per_frame, source.rng)
            if len(px):
                image = probe_image(frame.depth, frame.mask)
                X.append(depth_features(image, px, offsets, camera.fx, camera.fy).astype(np.float16))
                y.append(frame.labels[px[:, 0], px[:, 1]])
                pts, centre = person_points(frame.depth, frame.mask, camera, px[:, 0], px[:, 1])
                P.append(pts)
                fid.append(np.full(len(px), len(axes)))
                axes.append(body_axes(source.body, frame.pose))
                centres.append(centre)
            progress.update()
    return dict(X=np.vstack(X), y=np.concatenate(y), P=np.vstack(P), frame=np.concatenate(fid),
                axes=np.array(axes), centres=np.array(centres))


def cached_training_set(args, source, offsets):
    """:func:`make_training_set`, or the same set read back from ``--cache`` when it was made
    with the same seed, frames, pixels, offsets and upright share (tree settings are then
    cheap to vary; the frames themselves are what takes minutes)."""
    key = json.dumps({"seed": args.seed, "frames": args.frames, "pixels": args.pixels,
                      "candidates": args.candidates, "radius": args.radius, "upright": args.upright,
                      "train": [n for n, _ in source.motions]})
    if args.cache is not None and args.cache.exists():
        with np.load(args.cache, allow_pickle=False) as z:
            if str(z["key"]) == key:
                print(f"training set read from {args.cache}", file=sys.stderr)
                return {k: z[k] for k in ("X", "y", "P", "frame", "axes", "centres")}
        print(f"note: {args.cache} was made with other settings; making the set again", file=sys.stderr)
    data = make_training_set(source, args.frames, offsets, args.pixels, args.quiet)
    if args.cache is not None:
        from depthtrack.io.atomic import atomic_path

        with atomic_path(args.cache) as tmp:
            with open(tmp, "wb") as fh:
                np.savez(fh, key=key, **data)
    return data


def export_trees(trees, feature_sets, n_offsets, classes=None) -> Trees:
    """Flatten scikit-learn trees into :class:`Trees`: a tree's feature i is its offset pair
    ``feature_set[i]``, or extra input ``i - len(feature_set)`` (numbered ``n_offsets + e``)."""
    feature, threshold, left, right, roots, leaves = [], [], [], [], [], []
    base = n_leaves = 0
    for tree, fset in zip(trees, feature_sets):
        t = tree.tree_
        is_leaf = t.children_left < 0
        leaf_row = np.cumsum(is_leaf) - 1 + n_leaves
        if classes is not None:
            value = t.value[:, 0, :]
            full = np.zeros((t.node_count, classes))
            full[:, tree.classes_] = value / np.maximum(value.sum(1, keepdims=True), 1e-12)
        else:
            full = t.value[:, :, 0]
        leaves.append(full[is_leaf])
        f = np.maximum(t.feature, 0)
        mapped = np.where(f < len(fset), fset[np.minimum(f, len(fset) - 1)], n_offsets + f - len(fset))
        feature.append(np.where(is_leaf, 0, mapped))
        threshold.append(np.where(is_leaf, 0.0, t.threshold))
        left.append(np.where(is_leaf, -1, t.children_left + base))
        right.append(np.where(is_leaf, leaf_row, t.children_right + base))
        roots.append(base)
        base += t.node_count
        n_leaves += int(is_leaf.sum())
    return Trees(np.concatenate(feature), np.concatenate(threshold), np.concatenate(left),
                 np.concatenate(right), np.array(roots), np.vstack(leaves))


def fit_trees(make, X, target, n_trees, candidates, rng, extras=None, label="tree"):
    """Grow ``n_trees`` scikit-learn trees, each on 60 % of the pixels and 70 % of the offset pairs."""
    trees, fsets = [], []
    share = max(1, int(0.7 * candidates))
    for t in range(n_trees):
        fset = np.sort(rng.choice(candidates, share, replace=False))
        rows = rng.random(len(target)) < 0.6
        inputs = X[rows][:, fset].astype(np.float32)
        if extras is not None:
            inputs = np.hstack([inputs, extras[rows]])
        tree = make(int(rng.integers(1 << 31)))
        tree.fit(inputs, target[rows])
        del inputs
        trees.append(tree)
        fsets.append(fset)
        print(f"{label} {t + 1}/{n_trees}: {tree.tree_.node_count} nodes, depth {tree.get_depth()}", file=sys.stderr)
    return trees, fsets


def orientation_errors(forest, source, n_frames, quiet) -> np.ndarray:
    """(n, 3, 3) rotations ``R_est R_true^T`` of the frame-level axes estimate on fresh frames."""
    out = []
    with Progress(n_frames, "orientation frames", quiet=quiet) as progress:
        for _ in range(n_frames):
            _, camera, frame, _ = source.frame()
            rows, cols = np.nonzero(frame.mask)
            if len(rows):
                f, u = forest.orientation(probe_image(frame.depth, frame.mask), rows, cols, camera.fx, camera.fy)
                est = np.column_stack([f, u, np.cross(u, f)])
                out.append(est @ body_axes(source.body, frame.pose).T)
            progress.update()
    return np.array(out)


def noisy_extras(data, errors, rng) -> np.ndarray:
    """(N, 8) body-frame inputs of the training pixels, each frame's true axes turned by an
    orientation error drawn from those measured (so the part trees learn how far to trust it)."""
    from depthtrack.detect.features import body_frame_features

    out = np.empty((len(data["y"]), 8), np.float32)
    for i, (axes, centre) in enumerate(zip(data["axes"], data["centres"])):
        E = errors[rng.integers(len(errors))]
        sel = data["frame"] == i
        out[sel] = body_frame_features(data["P"][sel], centre, E @ axes[:, 0], E @ axes[:, 1])
    return out


def fit_side(X, data, args, rng):
    """The side stage: two regression trees, one per half of the frames (odd, even), for the
    camera x, y of the subject's left axis at each pixel. Each training frame's estimate
    (mean over its pixels) comes from the tree that did not see it, so the part trees learn
    how far to trust it; at run time both trees are averaged.

    Returns
    -------
    Trees, (F, 2) float32 out-of-fold estimate per training frame
    """
    from sklearn.tree import DecisionTreeRegressor

    frame = data["frame"]
    F = len(data["axes"])
    target = data["axes"][frame][:, :2, 2].astype(np.float32)
    est, trees, fsets = np.zeros((F, 2)), [], []
    count = np.maximum(np.bincount(frame, minlength=F), 1)
    for fold in (0, 1):
        fset = np.sort(rng.choice(args.candidates, max(1, int(0.7 * args.candidates)), replace=False))
        rows = frame % 2 == fold
        tree = DecisionTreeRegressor(max_depth=args.side_depth, min_samples_leaf=50, max_features=args.max_features,
                                     random_state=int(rng.integers(1 << 31)))
        tree.fit(X[rows][:, fset].astype(np.float32), target[rows])
        pred = tree.predict(X[~rows][:, fset].astype(np.float32))
        for c in (0, 1):
            est[:, c] += np.bincount(frame[~rows], weights=pred[:, c], minlength=F)
        trees.append(tree)
        fsets.append(fset)
        print(f"side tree {fold + 1}/2: {tree.tree_.node_count} nodes", file=sys.stderr)
    est /= count[:, None]
    truth = data["axes"][:, :2, 2]
    flat = np.abs(truth[:, 0]) > 0.7
    print(f"side stage, out of fold: left axis on the right side of the image in "
          f"{np.mean((est * truth).sum(1) > 0):.1%} of training frames ({np.mean((est * truth).sum(1)[flat] > 0):.1%} "
          f"where it lies along the image's x)", file=sys.stderr)
    return export_trees(trees, fsets, args.candidates), est.astype(np.float32)


def frame_extras(forest, image, rows, cols, points, fx, fy):
    """(N, E) the per-pixel extra inputs the part trees of ``forest`` split on (none: E = 0)."""
    from depthtrack.detect.features import body_frame_features, side_features

    if forest.orient is not None:
        return body_frame_features(points, points.mean(axis=0), *forest.orientation(image, rows, cols, fx, fy))
    if forest.extras == "none":
        return np.zeros((len(rows), 0), np.float32)
    ext = centroid_features(points, points.mean(axis=0))
    if forest.side is not None:
        ext = np.hstack([ext, side_features(ext, forest.side_axis(image, rows, cols, fx, fy))])
    return ext


def check_export(forest, trees, fsets, offsets, source):
    """The numpy traversal must reproduce scikit-learn's probabilities on a fresh frame."""
    _, camera, frame, _ = source.frame()
    rows, cols = np.nonzero(frame.mask & (frame.depth > 0))
    image = probe_image(frame.depth, frame.mask)
    X = depth_features(image, np.stack([rows, cols], 1), offsets, camera.fx, camera.fy)
    pts, _ = person_points(frame.depth, frame.mask, camera, rows, cols)
    axes = forest.orientation(image, rows, cols, camera.fx, camera.fy)
    extras = frame_extras(forest, image, rows, cols, pts, camera.fx, camera.fy)
    ref = np.zeros((len(rows), NUM_PARTS))
    for tree, fset in zip(trees, fsets):
        ref[:, tree.classes_] += tree.predict_proba(np.hstack([X[:, fset], extras])) / len(trees)
    mine, _ = forest.predict(image, rows, cols, pts, camera.fx, camera.fy, axes)
    agree = float(np.mean(np.abs(mine - ref).max(1) < 1e-3))
    if agree < 0.999:
        raise RuntimeError(f"exported forest agrees with scikit-learn on only {agree:.1%} of pixels")


def fit_push_back(forest, source, n_frames, quiet) -> np.ndarray:
    """(15,) median camera-z from a joint's best surface mode (within 30 cm) to the true joint."""
    forest.push_back = np.zeros(len(JOINT_NAMES), np.float32)
    dz = [[] for _ in JOINT_NAMES]
    with Progress(n_frames, "push-back frames", quiet=quiet) as progress:
        for _ in range(n_frames):
            _, camera, frame, _ = source.frame()
            _, probs = recognize(frame.depth, frame.mask, camera, forest=forest)
            prop = joint_proposals(frame.depth, probs, camera, k=1, forest=forest)
            for j in range(len(JOINT_NAMES)):
                p = prop.positions[j, 0]
                if np.isfinite(p[0]) and np.linalg.norm(p - frame.joints[j]) < 0.3:
                    dz[j].append(frame.joints[j, 2] - p[2])
            progress.update()
    return np.array([np.median(d) if len(d) else 0.0 for d in dz], np.float32)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog="example: nice -n 10 .venv/bin/python tools/train_recognizer.py --seed 0 --frames 3000 --extras centroid --trees 4")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--frames", type=int, default=1800, help="training frames (default 1800)")
    ap.add_argument("--pixels", type=int, default=400, help="sampled pixels per training frame")
    ap.add_argument("--candidates", type=int, default=500, help="random offset pairs (default 500)")
    ap.add_argument("--radius", type=float, default=0.75, help="largest probe offset, metres (default 0.75)")
    ap.add_argument("--trees", type=int, default=3)
    ap.add_argument("--max-depth", type=int, default=22)
    ap.add_argument("--upright", type=float, default=0.6, help="share of upright training frames (default 0.6)")
    ap.add_argument("--max-features", type=int, default=40, help="offset pairs tried per split")
    ap.add_argument("--min-leaf", type=int, default=10, help="fewest training pixels per leaf")
    ap.add_argument("--extras", choices=("none", "centroid", "centroid+side"), default="none",
                    help="per-pixel inputs besides the offset pairs: centroid = offset from the person's centre (m); "
                         "centroid+side = also a side stage's frame estimate of where the subject's left is")
    ap.add_argument("--side-depth", type=int, default=16, help="depth of the side stage's trees")
    ap.add_argument("--orientation", action="store_true",
                    help="add the (experimental) first stage that estimates the body's axes")
    ap.add_argument("--calib-frames", type=int, default=100, help="frames for the push-back fit")
    ap.add_argument("--eval-frames", type=int, default=120, help="frames per evaluation set")
    ap.add_argument("--data", type=Path, default=ROOT.parent / "shared" / "data")
    ap.add_argument("--out", type=Path, default=default_path())
    ap.add_argument("--cache", type=Path, default=None,
                    help="keep the rendered training set in this .npz and reuse it when the frame settings match")
    ap.add_argument("--sets", default="held-out,dev,test",
                    help="evaluation sets, comma-separated (default held-out,dev,test; tune without test)")
    ap.add_argument("--eval-only", action="store_true", help="evaluate the model at --out, train nothing")
    ap.add_argument("--quiet", action="store_true")
    args = ap.parse_args(argv)

    t0 = time.perf_counter()
    sets = motion_sets(BodyModel.default(), args.data)
    print("train motions: " + ", ".join(n for n, _ in sets["train"]))
    print("dev motions: " + ", ".join(n for n, _ in sets["dev"]) + "; test motions: "
          + ", ".join(n for n, _ in sets["test"]))
    if args.eval_only:
        forest = PartForest.load(args.out)
    else:
        from sklearn.tree import DecisionTreeClassifier, DecisionTreeRegressor

        rng = np.random.default_rng(args.seed)
        offsets = sample_offsets(args.candidates, rng, radius=args.radius)
        source = FrameSource(sets["train"], args.seed, upright_fraction=args.upright)
        data = cached_training_set(args, source, offsets)
        X, y = data["X"], data["y"]
        t_data = time.perf_counter() - t0
        forest = PartForest(offsets, None, Trees(np.zeros(1), np.zeros(1), [-1], [0], [0], np.ones((1, NUM_PARTS))),
                            np.zeros(len(JOINT_NAMES)))
        extras, angle = None, np.array([np.nan])
        if args.extras != "none":
            extras = centroid_features(data["P"], data["centres"][data["frame"]])
            forest.meta["extras"] = args.extras
        if args.extras == "centroid+side":
            forest.side, side_est = fit_side(X, data, args, rng)
            s = side_est[data["frame"]]
            extras = np.hstack([extras, s, (extras[:, :2] * s).sum(1, keepdims=True)]).astype(np.float32)
        if args.orientation:
            # stage 1: the body's axes per pixel (regression), one estimate per frame at run time
            target = np.concatenate([data["axes"][data["frame"], :, 0], data["axes"][data["frame"], :, 1]], axis=1)
            o_trees, o_sets = fit_trees(lambda seed: DecisionTreeRegressor(
                max_depth=18, min_samples_leaf=20, max_features=args.max_features, random_state=seed),
                X, target, 2, args.candidates, rng, label="orientation tree")
            forest.orient = export_trees(o_trees, o_sets, args.candidates)
            errors = orientation_errors(forest, source, args.calib_frames, args.quiet)
            angle = np.degrees(np.arccos(np.clip((np.trace(errors, axis1=1, axis2=2) - 1) / 2, -1, 1)))
            print(f"orientation error on {len(errors)} fresh frames: median {np.median(angle):.0f} deg, "
                  f"under 45 deg {np.mean(angle < 45):.0%}", file=sys.stderr)
            extras = noisy_extras(data, errors, rng)
        # the part trees: offset pairs (and after stage 1 the body-frame inputs, with realistic axis errors)
        trees, fsets = fit_trees(lambda seed: DecisionTreeClassifier(
            max_depth=args.max_depth, min_samples_leaf=args.min_leaf, max_features=args.max_features,
            random_state=seed), X, y, args.trees, args.candidates, rng, extras=extras, label="part tree")
        forest.parts = export_trees(trees, fsets, args.candidates, classes=NUM_PARTS)
        source.release()
        # fresh train-motion frames of their own seed, so a run from --cache fits the same push-back
        source = FrameSource(sets["train"], args.seed + 500, upright_fraction=args.upright)
        check_export(forest, trees, fsets, offsets, source)
        del X, extras, data
        forest.push_back = fit_push_back(forest, source, args.calib_frames, args.quiet)
        source.release()
        forest.meta = {**forest.meta, "trained_by": "tools/train_recognizer.py", "seed": args.seed, "frames": args.frames,
                       "pixels_per_frame": args.pixels, "candidates": args.candidates, "trees": args.trees,
                       "max_depth": args.max_depth, "samples": int(len(y)), "radius": args.radius,
                       "upright": args.upright, "max_features": args.max_features, "min_leaf": args.min_leaf,
                       "orientation_stage": bool(args.orientation), "side_depth": args.side_depth if args.extras == "centroid+side" else None,
                       "orientation_error_median_deg": round(float(np.median(angle)), 1) if args.orientation else None,
                       "train_motions": [n for n, _ in sets["train"]], "train_seconds": round(time.perf_counter() - t0)}
        forest.save(args.out)        # evaluate what ships: float16 offsets and thresholds, uint8 leaves
        meta, forest = forest.meta, PartForest.load(args.out)
        forest.meta = meta
        print(f"data {t_data:.0f} s ({len(y)} pixels), trained in {time.perf_counter() - t0:.0f} s; "
              f"push-back (m): {dict(zip(JOINT_NAMES, forest.push_back.round(3).tolist()))}")
    results = {}
    for name, motions, seed in (("held-out", sets["train"], args.seed + 1000), ("dev", sets["dev"], args.seed + 2000),
                                ("test", sets["test"], args.seed + 3000)):
        if motions and name in args.sets.split(","):
            src = FrameSource(motions, seed)
            results[name] = evaluate(forest, src, args.eval_frames, args.quiet, f"{name} frames")
            src.release()
    print_report(results)
    if not args.eval_only:
        forest.meta["evaluation"] = results
        forest.meta["eval_frames"] = args.eval_frames
        forest.save(args.out)
        print(f"wrote {args.out} ({args.out.stat().st_size / 1024:.0f} KiB) in {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    from depthtrack.errors import InputError

    try:
        sys.exit(main())
    except InputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)
