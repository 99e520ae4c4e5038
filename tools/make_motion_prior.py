#!/usr/bin/env python
"""Measure the tracker's acceleration prior from motion capture; write depthtrack/data/motion_prior.json.

Usage::

    .venv/bin/python tools/make_motion_prior.py [BVH or DIR ...] [-o depthtrack/data/motion_prior.json]
        [--analysis-fps 30] [--data ../shared/data] [--joint-map MAP.json]

Default inputs: the ``train`` clips of the motion split, ``depthtrack/data/motion_split.json``
(paths relative to ``--data``, default ``../shared/data``): a prior is fitted on train
motions only, never on the dev or test ones. The shipped prior
(``depthtrack/data/motion_prior.json``, its ``clips`` list) was made from the four DeepMimic
clips and the CMU back stroke, all train clips; it is not regenerated when the split grows.
Each clip is read with :func:`depthtrack.io.bvh.read_bvh` (any naming convention, or
``--joint-map``), retargeted onto
the default body (:func:`depthtrack.motion.retarget.retarget`), resampled to the analysis
rate (rotations slerped; a leading T-pose calibration frame is dropped), and its relative velocities ``v_t`` (see
:mod:`depthtrack.motion.prior`) differenced: ``alpha = (v_t - v_{t-1}) * fps^2``.
Per pose parameter the file stores the root mean square of ``alpha`` pooled over every
frame of every clip (the maximum-likelihood standard deviation of a zero-mean Gaussian)
and its 95th percentile of ``|alpha|``, in m/s^2 (pelvis translation) or rad/s^2.

The default analysis rate, 30 Hz, is the native rate of most clips and divides the 60
and 120 Hz ones exactly, so no clip is interpolated between its samples.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
import depthtrack  # noqa: E402,F401  (before numpy: the same OpenBLAS kernels on every machine)
import numpy as np  # noqa: E402

from depthtrack.body.model import BodyModel  # noqa: E402
from depthtrack.io.atomic import write_text_atomic  # noqa: E402
from depthtrack.io.bvh import read_bvh  # noqa: E402
from depthtrack.motion.prior import accelerations_of, velocities_of  # noqa: E402
from depthtrack.motion.retarget import resample_poses, retarget  # noqa: E402

#: The train / dev / test split of the mocap clips.
SPLIT = REPO / "depthtrack" / "data" / "motion_split.json"

#: Floor on a stored deviation, so a parameter that never moves in the data keeps a usable prior.
MIN_ACCEL_STD = 1.0


def train_clips(data_dir, split_path=SPLIT):
    """Paths of the motion split's train clips under ``data_dir``."""
    split = json.loads(Path(split_path).read_text(encoding="utf-8"))
    return [Path(data_dir) / rel for rel in split["train"]]


def present_train_clips(data_dir, split_path=SPLIT):
    """:func:`train_clips`, each checked to be there; raises :class:`FileNotFoundError`
    naming every one that is not ("train clips not found: ...")."""
    files = train_clips(data_dir, split_path)
    missing = [str(f) for f in files if not f.is_file()]
    if missing:
        raise FileNotFoundError(f"train clips not found: {', '.join(missing)}")
    return files


def clip_poses(path, body, analysis_fps, joint_map=None):
    """``(poses (K, 48), motion, dropped)``: one BVH clip retargeted onto ``body`` and
    resampled to ``analysis_fps``, its leading T-pose jump (``dropped`` frames) left out."""
    motion = read_bvh(path, joint_map=joint_map)
    poses = retarget(motion, body)
    dropped = motion.leading_jump()
    return resample_poses(poses[dropped:], motion.fps, analysis_fps), motion, dropped


def clip_accelerations(path, body, analysis_fps, joint_map=None):
    """(K, 48) accelerations of one BVH clip at ``analysis_fps``, and a description of it."""
    poses, motion, dropped = clip_poses(path, body, analysis_fps, joint_map)
    acc = accelerations_of(poses, analysis_fps)
    info = {"file": Path(path).name, "source_fps": round(motion.fps, 3), "frames": int(len(poses)),
            "units_m": motion.units_m, "units_source": motion.units_source,
            "dropped_leading_frames": int(dropped)}
    return acc, info


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("inputs", nargs="*",
                        help="BVH files or directories (default: the train clips of "
                             "depthtrack/data/motion_split.json under --data)")
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data"),
                        help="where the split's clips are (default ../shared/data)")
    parser.add_argument("--joint-map", default=None, metavar="MAP.json",
                        help='{"our joint": "file joint"} for skeletons whose names are not recognised')
    parser.add_argument("-o", "--output", default=str(REPO / "depthtrack" / "data" / "motion_prior.json"))
    parser.add_argument("--analysis-fps", type=float, default=30.0)
    args = parser.parse_args(argv)

    try:
        files = [] if args.inputs else present_train_clips(args.data)
    except FileNotFoundError as exc:
        print(f"make_motion_prior: {exc}", file=sys.stderr)
        return 2
    for item in args.inputs:
        p = Path(item)
        files += sorted(p.rglob("*.bvh")) if p.is_dir() else [p]
    if not files:
        print("make_motion_prior: no BVH files found", file=sys.stderr)
        return 2
    body = BodyModel.default()
    accs, clips = [], []
    for f in files:
        acc, info = clip_accelerations(f, body, args.analysis_fps, args.joint_map)
        accs.append(acc)
        clips.append(info)
        print(f"{f.name}: {info['frames']} frames at {args.analysis_fps:g} Hz "
              f"(source {info['source_fps']} Hz, units {info['units_m']:.5f} m)")
    all_acc = np.concatenate(accs)
    rms = np.sqrt(np.mean(all_acc ** 2, axis=0))
    p95 = np.percentile(np.abs(all_acc), 95, axis=0)
    names = list(body.pose_names)
    data = {
        "format": "depthtrack-motion-prior/1",
        "made_by": "tools/make_motion_prior.py",
        "statistic": "accel_std = RMS of (v_t - v_{t-1}) * fps^2 over all frames of all clips "
                     f"(floored at {MIN_ACCEL_STD}); accel_p95 = 95th percentile of its magnitude",
        "units": "pelvis_t*: m/s^2; rotations: rad/s^2 (relative, local-frame velocities)",
        "scaling": "per-frame velocity-change std = accel_std / fps^2 (see depthtrack.motion.prior)",
        "analysis_fps": args.analysis_fps,
        "clips": clips,
        "samples": int(len(all_acc)),
        "pose_names": names,
        "accel_std": {n: round(float(max(v, MIN_ACCEL_STD)), 4) for n, v in zip(names, rms)},
        "accel_p95": {n: round(float(v), 4) for n, v in zip(names, p95)},
    }
    write_text_atomic(args.output, json.dumps(data, indent=1) + "\n")
    print(f"wrote {args.output} from {len(clips)} clips, {len(all_acc)} samples")
    for n, v in zip(names, rms):
        print(f"  {n:14s} {v:9.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
