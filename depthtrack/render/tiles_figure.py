"""A PNG mosaic of rendered candidate tiles with their costs, the best one highlighted."""
from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..io.atomic import atomic_path


def write_tiles_figure(path, depths, costs, observed, title: str | None = None,
                       max_tiles: int = 64) -> None:
    """Write a mosaic: the observed tile, then every candidate tile with its cost printed on it.

    Parameters
    ----------
    path : str or Path
        Output PNG (written atomically).
    depths : (N, t, t) float
        Rendered camera z per candidate (0 = nothing drawn), e.g. ``TileRenderer.render_depth``.
    costs : (N,) float
        Cost per candidate (lower is better), e.g. ``TileRenderer.costs``; the lowest is
        framed in green and its cost printed in bold.
    observed : (t, t) float
        The observed tile (0 = no reading, inf = background), e.g. ``TileRenderer.observed_tile``.
    title : str, optional
    max_tiles : int
        Show at most this many candidates (the best ones, in their original order).
    """
    import matplotlib
    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    depths = np.asarray(depths, dtype=float)
    costs = np.asarray(costs, dtype=float).ravel()
    observed = np.asarray(observed, dtype=float)
    if depths.ndim != 3 or depths.shape[1] != depths.shape[2] or len(costs) != len(depths) \
            or observed.shape != depths.shape[1:]:
        raise InputError(path, f"need depths (N, t, t), costs (N,), observed (t, t); got "
                               f"{depths.shape}, {costs.shape}, {observed.shape}")
    best = int(np.argmin(costs))
    shown = np.sort(np.argsort(costs, kind="stable")[:max_tiles])
    valid = [d[d > 0] for d in (*depths[shown], observed[np.isfinite(observed)])]
    values = np.concatenate([v for v in valid if v.size]) if any(v.size for v in valid) else np.ones(1)
    lo, hi = np.percentile(values, [1, 99]) if values.size else (0.0, 1.0)
    if hi <= lo:
        hi = lo + 1.0

    panels = 1 + len(shown)
    cols = int(np.ceil(np.sqrt(panels)))
    rows = int(np.ceil(panels / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(1.9 * cols, 2.0 * rows + (0.4 if title else 0)),
                             squeeze=False)
    cmap = matplotlib.colormaps["viridis"].with_extremes(bad="white")

    def show(ax, image, label, **text):
        ax.imshow(np.ma.masked_where(~(np.isfinite(image) & (image > 0)), image), cmap=cmap,
                  vmin=lo, vmax=hi, interpolation="nearest")
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_title(label, fontsize=8, **text)

    show(axes[0, 0], observed, "observed")
    for k, index in enumerate(shown, start=1):
        ax = axes.flat[k]
        is_best = index == best
        show(ax, depths[index], f"#{index}  cost {costs[index]:.4f}",
             fontweight="bold" if is_best else "normal", color="green" if is_best else "black")
        if is_best:
            t = depths.shape[1]
            ax.add_patch(Rectangle((-0.5, -0.5), t, t, fill=False, edgecolor="limegreen", linewidth=4))
    for ax in axes.flat[panels:]:
        ax.axis("off")
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=100, format="png")
    plt.close(fig)
