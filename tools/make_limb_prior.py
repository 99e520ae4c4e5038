#!/usr/bin/env python
"""Fit the learned limb prior (Gaussian mixtures of arm and leg poses); write
depthtrack/data/limb_prior.npz.

Usage::

    .venv/bin/python tools/make_limb_prior.py [-o depthtrack/data/limb_prior.npz]
        [--data ../shared/data] [--components 8] [--fps 10] [--seed 0]

The samples are those of ``tools/make_limb_poses.py``: every frame of the ``train`` clips of
``depthtrack/data/motion_split.json`` (never dev or test), retargeted onto the default body
at ``--fps``, each arm's shoulder and elbow and each leg's hip and knee rotation vectors, a
right limb mirrored onto the left, clipped to the joint limits. scikit-learn's
``GaussianMixture`` (full covariances, ``reg_covar`` 1e-3 rad^2 so that a rotation the train
motions never vary -- a knee's twist -- keeps a std of about 2 degrees, seeded) fits each
kind. It prints the mean log density per frame on the train samples and on the ``dev`` clips'
(held out), for the components asked and its neighbours, so the choice of ``--components``
can be read off dev. :mod:`depthtrack.track.limb_prior` reads the file.
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "tools"))
import depthtrack  # noqa: E402,F401  (before numpy: the same OpenBLAS kernels on every machine)
import numpy as np  # noqa: E402

from depthtrack.body.model import BodyModel  # noqa: E402
from make_limb_poses import samples_of, train_run, write_npz  # noqa: E402
from make_motion_prior import SPLIT  # noqa: E402


def dev_clips(data_dir) -> list:
    """The split's dev clips that are present under ``data_dir`` (for the held-out figure
    only; a BVH clip missing there is left out of it)."""
    split = json.loads(Path(SPLIT).read_text(encoding="utf-8"))
    return [p for p in (Path(data_dir) / rel for rel in split["dev"]) if p.is_file()]


def main(argv=None) -> int:
    run = train_run(argv, __doc__.split("\n\n")[0], "limb_prior.npz", ("--components", 8))
    if run is None:
        return 2
    args, files, train = run
    from sklearn.mixture import GaussianMixture

    dev_files = dev_clips(args.data)
    dev = samples_of(dev_files, BodyModel.default(), args.fps) if dev_files else None
    print(f"train: {len(files)} clips, {len(train['arm'])} limb samples a kind; "
          f"dev: {len(dev_files)} clips" + (f", {len(dev['arm'])}" if dev else ""))
    out = {}
    for kind, data in train.items():
        for k in sorted({max(1, args.components // 2), args.components, 2 * args.components}):
            gmm = GaussianMixture(k, covariance_type="full", reg_covar=1e-3,
                                  random_state=args.seed, n_init=2).fit(data)
            held = f", dev {gmm.score(dev[kind]):.2f}" if dev else ""
            print(f"{kind}, {k} components: mean log density train {gmm.score(data):.2f}{held}")
            if k == args.components:
                out[kind] = gmm
    write_npz(args.output, {f"{kind}_{field}": getattr(g, f"{field}_") for kind, g in out.items()
                            for field in ("weights", "means", "covariances")}, files,
              "Gaussian mixtures of left-limb (shoulder, elbow) and (hip, knee) rotation "
              "vectors over the train clips' frames; made by tools/make_limb_prior.py")
    return 0


if __name__ == "__main__":
    sys.exit(main())
