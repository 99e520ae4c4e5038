"""Section 7.1's derivative-filter comparison as a table and a plot (cf. thesis Figure 7.1)."""
from __future__ import annotations

import json
from pathlib import Path

from ..io.atomic import atomic_path


def derivative_table(rows) -> str:
    """Markdown table of :func:`depthtrack.motion.derivatives.compare_derivative_filters` rows."""
    lines = ["| filter (velocity; acceleration) | E (eq. 7.2, rad²) | E per angle-sample |", "|---|---:|---:|"]
    for r in rows:
        acc = "same, twice" if r["second_order"] is None else "2nd-order mask"
        lines.append(f"| {r['name']} ({acc}) | {r['error']:.4g} | {r['error_per_sample']:.3g} |")
    return "\n".join(lines) + "\n"


def write_derivative_report(rows, directory, n_cycles: int, length: int, smooth: float) -> list:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    directory = Path(directory)
    with atomic_path(directory) as tmp:
        tmp = Path(tmp)
        tmp.mkdir(parents=True)
        (tmp / "derivatives.json").write_text(json.dumps(rows, indent=1))
        (tmp / "derivatives.md").write_text(
            f"# Derivative filters on {n_cycles} training cycles (L = {length}, smoothing {smooth})\n\n"
            + derivative_table(rows))
        fig, ax = plt.subplots(figsize=(7, 4))
        names = [r["name"] for r in rows]
        ax.barh(range(len(rows)), [r["error"] for r in rows], color="tab:blue")
        ax.set_yticks(range(len(rows)), names, fontsize=7)
        ax.set_xscale("log")
        ax.set_xlabel("E = 1/2 sum (p - p_hat)^2  (rad²)")
        ax.set_title("Derivative filters (cf. thesis Fig. 7.1)")
        fig.tight_layout()
        fig.savefig(tmp / "fig7_1_derivatives.png", dpi=110)
        plt.close(fig)
    return ["derivatives.json", "derivatives.md", "fig7_1_derivatives.png"]
