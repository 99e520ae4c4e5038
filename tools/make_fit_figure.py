"""The README's fit-figure picture: what a good and a bad fit look like on a depth frame.

A random person (``--shape random --shape-seed 3``, loose clothing) is rendered noise-free
by an SR4000 at 4.6 m in four frames of the built-in wave and squat motions; the default
(template) body of the same height at the true poses is compared with the body whose
shape :func:`depthtrack.track.shape_fit.fit_shape` fitted to those four frames.
Writes ``docs/fit_figures.png`` and prints the figures of each panel::

    PYTHONPATH=. python tools/make_fit_figure.py [OUT.png]
"""
from __future__ import annotations

import sys
from pathlib import Path

import depthtrack  # noqa: F401  (first, before numpy: the same OpenBLAS kernels on every machine)
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from depthtrack.body import BodyModel
from depthtrack.camera import Camera
from depthtrack.evaluate.fit import frame_fit
from depthtrack.render import FrameRenderer
from depthtrack.synth.procedural import procedural_motion
from depthtrack.synth.subject import make_subject
from depthtrack.track.shape_fit import fit_shape


def colour_fit(person, depth, rendered, tolerance=0.10):
    """RGB image: explained person pixels green, unexplained red, body off the person blue."""
    model = rendered > 0
    explained = person & model & (np.abs(depth - rendered) <= tolerance) & (depth > 0)
    img = np.full(person.shape + (3,), 0.12)
    img[person] = (0.55, 0.55, 0.55)
    img[person & ~explained] = (0.85, 0.15, 0.1)
    img[explained] = (0.2, 0.7, 0.3)
    img[model & ~person] = (0.2, 0.4, 0.95)
    return img


def main(out="docs/fit_figures.png"):
    camera = Camera.preset("sr4000")
    person, info = make_subject(None, "random", 3, "loose")
    template = BodyModel.default(person.height)
    wave = procedural_motion("wave", template, 25.0)
    squat = procedural_motion("squat", template, 25.0)
    poses = np.stack([wave[25], wave[60], squat[50], squat[90]])
    poses[:, 2] += 4.6
    r = FrameRenderer(camera)
    try:
        depths = [r.render(person, p) for p in poses]
        masks = [d > 0 for d in depths]
        fit = fit_shape(template, camera, depths, masks, poses, tile=128)
        shown = 0
        panels = [("observed depth (random person, loose clothing)", None, None)]
        for name, body, pose in (("template body", template, poses[shown]),
                                 ("fitted shape", fit.body, fit.poses[shown])):
            rendered = r.render(body, pose)
            figures = [frame_fit(masks[k], depths[k], r.render(body, p))
                       for k, p in enumerate(poses if body is template else fit.poses)]
            iou, unexplained, residual = np.mean(figures, axis=0)
            print(f"{name}: IoU {iou:.3f}, unexplained {unexplained:.1%}, "
                  f"median residual {100 * residual:.1f} cm (mean over the 4 frames)")
            panels.append((f"{name}: IoU {iou:.2f}, unexplained {unexplained:.0%}", body, rendered))
    finally:
        r.release()
    fig = Figure(figsize=(9, 3.6), dpi=90, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, 3)
    m = masks[shown]
    rows, cols = np.nonzero(m)
    crop = (slice(max(rows.min() - 8, 0), rows.max() + 8), slice(max(cols.min() - 20, 0), cols.max() + 20))
    for ax, (title, body, rendered) in zip(axes, panels):
        if rendered is None:
            d = np.where(depths[shown] > 0, depths[shown], np.nan)
            ax.imshow(d[crop], cmap="viridis_r")
        else:
            ax.imshow(colour_fit(m, depths[shown], rendered)[crop], interpolation="nearest")
        ax.set_title(title, fontsize=8)
        ax.set_axis_off()
    fig.suptitle("green: explained person pixels, red: unexplained, blue: body where the person "
                 "is not", fontsize=8)
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out)
    print(f"wrote {out}")


if __name__ == "__main__":
    main(*sys.argv[1:2])
