#!/usr/bin/env python
"""Cluster the train motions' arm and leg poses; write depthtrack/data/limb_poses.npz.

Usage::

    .venv/bin/python tools/make_limb_poses.py [-o depthtrack/data/limb_poses.npz]
        [--data ../shared/data] [--clusters 32] [--fps 10] [--seed 0]

The inputs are the ``train`` clips of ``depthtrack/data/motion_split.json`` (never dev or
test), each read with :func:`depthtrack.io.bvh.read_bvh`, retargeted onto the default body
and resampled to ``--fps``. Per frame, each arm gives its shoulder and elbow rotation
vectors and each leg its hip and knee ones (six numbers, the parent-relative rotations of
the pose vector); a right limb is mirrored onto the left (``(rx, ry, rz) -> (rx, -ry,
-rz)``, the sagittal mirror the body's joint limits follow), so both sides share one set.
k-means (``scipy.cluster.vq.kmeans2``, seeded) reduces each set to ``4 * --clusters``
centres, largest first, and farthest-point sampling of where each centre puts the limb's
middle and end joints keeps ``--clusters`` of them spread over the reachable space, which :mod:`depthtrack.track.reseat` puts on a tracked body's limb to look for a basin the
hill climbing cannot reach from where the limb is.
"""
from __future__ import annotations

import argparse
import io
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "tools"))
import depthtrack  # noqa: E402,F401  (before numpy: the same OpenBLAS kernels on every machine)
import numpy as np  # noqa: E402
from scipy.cluster.vq import kmeans2  # noqa: E402

from depthtrack.body.model import BodyModel  # noqa: E402
from depthtrack.body.skeleton import LOWER, UPPER  # noqa: E402
from depthtrack.contract import JOINT_NAMES  # noqa: E402
from depthtrack.io.atomic import write_bytes_atomic  # noqa: E402
from depthtrack.track.reseat import LIMB_SLOTS, MIRROR  # noqa: E402
from make_motion_prior import clip_poses, present_train_clips  # noqa: E402


def limb_samples(poses):
    """``{"arm": (2F, 6), "leg": (2F, 6)}``: every frame's left limbs and mirrored right ones,
    clipped to the joint limits."""
    out = {}
    for kind in ("arm", "leg"):
        slots = LIMB_SLOTS[f"l_{kind}"]
        left = poses[:, slots]
        right = poses[:, LIMB_SLOTS[f"r_{kind}"]] * MIRROR
        # within the body's joint limits, as the tracker would clip them
        out[kind] = np.clip(np.concatenate([left, right]), LOWER[slots], UPPER[slots])
    return out


def limb_points(body, kind, values):
    """``(K, 6)`` where a left limb set to each of ``values (K, 6)`` puts its middle and end
    joints (elbow and wrist, or knee and ankle), relative to its root joint, trunk upright."""
    poses = np.zeros((len(values), body.dof))
    poses[:, LIMB_SLOTS[f"l_{kind}"]] = values
    joints = np.asarray(body.joint_positions(poses))
    names = list(JOINT_NAMES)
    root, mid, end = (("l_shoulder", "l_elbow", "l_wrist") if kind == "arm"
                      else ("l_hip", "l_knee", "l_ankle"))
    r = joints[:, names.index(root)]
    return np.concatenate([joints[:, names.index(mid)] - r, joints[:, names.index(end)] - r], axis=1)


def spread(points, k):
    """Indices of ``k`` of ``points (N, D)`` by farthest-point sampling from the first (the
    largest cluster): the library covers where limbs go, not only where they mostly are."""
    picked = [0]
    dist = np.linalg.norm(points - points[0], axis=1)
    while len(picked) < min(k, len(points)):
        i = int(np.argmax(dist))
        picked.append(i)
        dist = np.minimum(dist, np.linalg.norm(points - points[i], axis=1))
    return np.array(picked)


def train_run(argv, description: str, output: str, extra):
    """``(args, files, samples)`` for this tool or ``make_limb_prior.py``: ``argv`` parsed
    (:func:`tool_arguments`), the train clips under ``--data`` and their limb samples
    (:func:`samples_of`); None when a train clip is missing (the line naming them printed,
    prefixed by the tool's name)."""
    args = tool_arguments(argv, description, output, extra)
    try:
        files = present_train_clips(args.data)
    except FileNotFoundError as exc:
        print(f"make_{Path(output).stem}: {exc}", file=sys.stderr)
        return None
    return args, files, samples_of(files, BodyModel.default(), args.fps, verbose=True)


def tool_arguments(argv, description: str, output: str, extra):
    """The arguments this tool and ``make_limb_prior.py`` share: ``--data``, ``-o`` (default
    ``depthtrack/data/OUTPUT``), ``--fps``, ``--seed``, and ``extra`` (``(flag, default)``,
    an int), parsed from ``argv``."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data"))
    parser.add_argument("-o", "--output", default=str(REPO / "depthtrack" / "data" / output))
    parser.add_argument("--fps", type=float, default=10.0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(extra[0], type=int, default=extra[1])
    return parser.parse_args(argv)


def samples_of(files, body, fps, verbose: bool = False) -> dict:
    """``{"arm": (M, 6), "leg": (M, 6)}``: :func:`limb_samples` of every frame of the BVH
    ``files``, retargeted onto ``body`` at ``fps``."""
    samples = {"arm": [], "leg": []}
    for f in files:
        poses, _, _ = clip_poses(f, body, fps)
        for kind, s in limb_samples(poses).items():
            samples[kind].append(s)
        if verbose:
            print(f"{f.name}: {len(poses)} frames at {fps:g} Hz")
    return {kind: np.concatenate(parts) for kind, parts in samples.items()}


def write_npz(path, arrays: dict, files, about: str) -> None:
    """``arrays`` with the train ``files``' names and ``about``, written atomically."""
    buf = io.BytesIO()
    np.savez(buf, **arrays, clips=np.array([f.name for f in files]), about=np.array(about))
    write_bytes_atomic(path, buf.getvalue())
    print(f"wrote {path}")


def main(argv=None) -> int:
    run = train_run(argv, __doc__.split("\n\n")[0], "limb_poses.npz", ("--clusters", 32))
    if run is None:
        return 2
    args, files, samples = run
    body = BodyModel.default()
    rng = np.random.default_rng(args.seed)
    out = {}
    for kind, data in samples.items():
        centres, labels = kmeans2(data, 4 * args.clusters, minit="++", seed=rng)
        counts = np.bincount(labels, minlength=len(centres))
        centres = centres[counts > 0]
        picked = spread(limb_points(body, kind, centres), args.clusters)
        out[kind] = centres[picked]
        print(f"{kind}: {len(data)} samples -> {len(centres)} clusters -> {len(picked)} spread")
    write_npz(args.output, {"arm": out["arm"], "leg": out["leg"]}, files,
              "left-limb (shoulder, elbow) and (hip, knee) rotation vectors: "
              "k-means centres of the train clips' frames, spread by farthest-"
              "point sampling of the limb's joints; made by tools/make_limb_poses.py")
    return 0


if __name__ == "__main__":
    sys.exit(main())
