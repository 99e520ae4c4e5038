#!/usr/bin/env python
"""Score the body-part recogniser on rendered frames: per-part precision and recall, side
tallies, and per-joint proposal accuracy (used by ``tools/train_recognizer.py``).

``evaluate(forest, source, n_frames, quiet, label)`` renders ``n_frames`` from a frame
source (``train_recognizer.FrameSource``), labels them and proposes joints, and returns a
dict of figures; ``print_report(results)`` prints them as tables.
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import depthtrack  # noqa: F401  (first, before numpy: the same OpenBLAS kernels on every machine)
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from depthtrack.contract import JOINT_NAMES  # noqa: E402
from depthtrack.detect.features import probe_image  # noqa: E402
from depthtrack.detect.recognizer import joint_proposals, recognize  # noqa: E402
from depthtrack.detect.recognizer_parts import BODY_PARTS, NUM_PARTS, mirror_parts  # noqa: E402
from depthtrack.progress import Progress  # noqa: E402


def body_axes(body, pose) -> np.ndarray:
    """(3, 3) columns ``forward, up, left`` of the pelvis (camera frame): where the body faces."""
    R = np.asarray(body.world_transforms(pose))[0, :3, :3]
    forward, up = R @ [0.0, 0.0, -1.0], R @ [0.0, -1.0, 0.0]
    return np.column_stack([forward, up, np.cross(up, forward)])


def evaluate(forest, source, n_frames, quiet, label):
    """Per-part precision/recall over person pixels, pixel accuracy, joints with a proposal within 10 cm."""
    confusion = np.zeros((NUM_PARTS, NUM_PARTS), np.int64)
    facing = np.zeros((2, 2))        # rows: upright, any orientation; forward estimate within 90 deg, frames
    side_axis = np.zeros((2, 2))     # rows: upright, any orientation; side stage's left axis within 90 deg, frames
    tally = np.zeros(3)              # upright frames: tally sign right, sided accuracy within 0.3-0.7, frames
    side = np.zeros((2, 2))          # rows: upright, any orientation; sided pixels on the true side, all sided
    sides = np.array([n[:2] for n in BODY_PARTS])
    sided = np.isin(sides, ["l_", "r_"])
    hit_any = np.zeros((2, len(JOINT_NAMES)))       # rows: upright, any orientation
    hit_top = np.zeros((2, len(JOINT_NAMES)))
    frames = np.zeros(2)
    per_camera = {}
    timing = {}                      # camera -> [(recognize s, proposals s)] per frame
    with Progress(n_frames, label, quiet=quiet) as progress:
        for _ in range(n_frames):
            cam_name, camera, frame, upright = source.frame()
            rows, cols = np.nonzero(frame.mask)
            if not len(rows):           # the body left the image or the sensor's range
                progress.update()
                continue
            axes = forest.orientation(probe_image(frame.depth, frame.mask), rows, cols, camera.fx, camera.fy)
            truth = body_axes(source.body, frame.pose)
            if forest.orient is not None:
                facing[0 if upright else 1] += [axes[0] @ truth[:, 0] > 0, 1]
            if forest.side is not None:
                est = forest.side_axis(probe_image(frame.depth, frame.mask), rows, cols, camera.fx, camera.fy)
                side_axis[0 if upright else 1] += [est @ truth[:2, 2] > 0, 1]
            t_start = time.perf_counter()
            labels, probs = recognize(frame.depth, frame.mask, camera, forest=forest, orientation=axes)
            t_labels = time.perf_counter()
            sel = frame.mask & (frame.labels >= 0) & (labels >= 0)
            np.add.at(confusion, (frame.labels[sel], labels[sel]), 1)
            t, g = frame.labels[sel], labels[sel]
            both = sided[t] & sided[g]
            side[0 if upright else 1] += [np.sum(sides[t[both]] == sides[g[both]]), both.sum()]
            if upright and both.any():
                # would one left/right decision per frame help? the forest's own tally of its
                # sides against image x, and how mixed the frame's sided labels are
                r_, c_ = np.nonzero(sel)
                dx = c_ - c_.mean()
                p_side = probs[r_, c_][:, sided]
                lr = np.where(sides[sided] == "l_", 1.0, -1.0)
                truth_sign = np.sum((np.where(sides[t] == "l_", 1.0, -1.0) * dx)[sided[t]])
                tally[0] += np.sign((p_side @ lr) @ dx) == np.sign(truth_sign)
                acc = np.mean(sides[t[both]] == sides[g[both]])
                tally[1] += 0.3 <= acc <= 0.7
                tally[2] += 1
            prop = joint_proposals(frame.depth, probs, camera, k=3, forest=forest)
            timing.setdefault(cam_name, []).append([t_labels - t_start, time.perf_counter() - t_labels])
            dist = np.linalg.norm(prop.positions - frame.joints[:, None], axis=2)
            any_hit = np.nanmin(np.where(np.isfinite(dist), dist, np.inf), axis=1) < 0.10
            row = 0 if upright else 1
            hit_any[row] += any_hit
            hit_top[row] += np.nan_to_num(dist[:, 0], nan=np.inf) < 0.10
            frames[row] += 1
            c = per_camera.setdefault(cam_name, [0, 0.0])
            c[0] += 1
            c[1] += any_hit.mean()
            progress.update()
    tp = np.diag(confusion).astype(float)
    precision = tp / np.maximum(confusion.sum(0), 1)
    recall = tp / np.maximum(confusion.sum(1), 1)
    total = np.maximum(frames, 1)[:, None]
    twin = mirror_parts()
    side_free = (np.trace(confusion) + sum(confusion[i, twin[i]] for i in range(NUM_PARTS) if twin[i] != i))
    return {"frames": int(n_frames), "pixel_accuracy": float(tp.sum() / max(confusion.sum(), 1)),
            "side_free_pixel_accuracy": float(side_free / max(confusion.sum(), 1)),
            "precision": dict(zip(BODY_PARTS, precision.round(4).tolist())),
            "recall": dict(zip(BODY_PARTS, recall.round(4).tolist())),
            "facing_correct_upright": float(facing[0, 0] / facing[0, 1]) if facing[0, 1] else None,
            "facing_correct_rotated": float(facing[1, 0] / facing[1, 1]) if facing[1, 1] else None,
            "side_axis_correct_upright": float(side_axis[0, 0] / side_axis[0, 1]) if side_axis[0, 1] else None,
            "side_axis_correct_rotated": float(side_axis[1, 0] / side_axis[1, 1]) if side_axis[1, 1] else None,
            "frame_side_tally_correct_upright": float(tally[0] / max(tally[2], 1)),
            "frames_side_mixed_upright": float(tally[1] / max(tally[2], 1)),
            "left_right_correct_upright": float(side[0, 0] / max(side[0, 1], 1)),
            "left_right_correct_rotated": float(side[1, 0] / max(side[1, 1], 1)),
            "joint_within_10cm_any_of_3": float(hit_any.sum() / (frames.sum() * len(JOINT_NAMES))),
            "joint_within_10cm_top1": float(hit_top.sum() / (frames.sum() * len(JOINT_NAMES))),
            "upright_within_10cm_any_of_3": float(hit_any[0].sum() / (total[0, 0] * len(JOINT_NAMES))),
            "rotated_within_10cm_any_of_3": float(hit_any[1].sum() / (total[1, 0] * len(JOINT_NAMES))),
            "per_joint_within_10cm_any_of_3": dict(zip(JOINT_NAMES, (hit_any.sum(0) / frames.sum()).round(3).tolist())),
            "per_camera_within_10cm_any_of_3": {k: round(float(v[1] / v[0]), 4) for k, v in per_camera.items()},
            "median_ms_recognize_proposals": {k: np.round(1000 * np.median(v, axis=0), 1).tolist()
                                              for k, v in timing.items()}}


def print_report(results):
    names = list(results)
    print("\nper-part precision / recall over person pixels:")
    print(f"{'part':14}" + "".join(f" {n + ' P':>12} {n + ' R':>12}" for n in names))
    for part in BODY_PARTS:
        print(f"{part:14}" + "".join(f" {results[n]['precision'][part]:12.3f} {results[n]['recall'][part]:12.3f}"
                                     for n in names))
    keys = ("facing_correct_upright", "facing_correct_rotated") if results[names[0]]["facing_correct_upright"] \
        is not None else ()
    if results[names[0]]["side_axis_correct_upright"] is not None:
        keys = (*keys, "side_axis_correct_upright", "side_axis_correct_rotated")
    for key in ("pixel_accuracy", "side_free_pixel_accuracy", *keys, "left_right_correct_upright",
                "left_right_correct_rotated", "frame_side_tally_correct_upright", "frames_side_mixed_upright",
                "joint_within_10cm_any_of_3", "joint_within_10cm_top1",
                "upright_within_10cm_any_of_3", "rotated_within_10cm_any_of_3"):
        print(f"{key:32}" + "".join(f" {results[n][key]:10.3f} ({n})" for n in names))
    print("per joint, a proposal (of 3) within 10 cm:")
    for j in JOINT_NAMES:
        print(f"  {j:12}" + "".join(f" {results[n]['per_joint_within_10cm_any_of_3'][j]:8.3f}" for n in names))
    for n in names:
        print(f"per camera ({n}): {results[n]['per_camera_within_10cm_any_of_3']}; median ms per frame "
              f"(recognize, proposals; one core): {results[n]['median_ms_recognize_proposals']}")


