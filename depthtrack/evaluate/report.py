"""Evaluation reports: metrics.json, a Markdown table, per-frame errors and plots.

Plots are drawn on bare :class:`matplotlib.figure.Figure` objects with the Agg canvas
(no pyplot, no display), and each plotting function returns its figure so callers and
tests can inspect the bars and lines.

Report directory (written as a whole, atomically)::

    REPORT/metrics.json          {"sequences": {NAME: {METHOD: M}}, "overall": {METHOD: M}}
    REPORT/report.md             tables of the same figures, and the plots
    REPORT/errors.csv            sequence,method,frame,mean_error_m,max_error_m,marker_mean_error_m,marker_max_error_m,
                                 silhouette_iou,unexplained_fraction,median_depth_residual_m
    REPORT/error_over_time.png   per sequence: mean (solid) and worst-joint (dashed) error per frame, per method
    REPORT/fit_over_time.png     per sequence: silhouette IoU (solid) and unexplained share (dashed) per frame
    REPORT/joint_errors.png      mean error of each contract joint, per method
    REPORT/methods.png           the paper's results figure: methods side by side per sequence
"""
from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ..contract import JOINT_NAMES
from ..io.atomic import atomic_path
from . import metrics

#: Fixed colours per method so every plot agrees.
METHOD_COLOURS = {"hc": "tab:blue", "ep": "tab:orange", "hc+ep": "tab:green"}
_EXTRA_COLOURS = ("tab:red", "tab:purple", "tab:brown", "tab:pink", "tab:olive", "tab:cyan")

PLOT_FILES = ("error_over_time.png", "joint_errors.png", "methods.png", "fit_over_time.png")


def method_colour(method: str, methods) -> str:
    if method in METHOD_COLOURS:
        return METHOD_COLOURS[method]
    others = [m for m in methods if m not in METHOD_COLOURS]
    return _EXTRA_COLOURS[others.index(method) % len(_EXTRA_COLOURS)] if method in others else "black"


def _errors_for_plot(result):
    """(F, N) errors to plot for a result and their label: joints when known, else markers."""
    if np.isfinite(result.joint_errors).any() or result.marker_errors is None:
        return result.joint_errors, "joint"
    return result.marker_errors, "marker"


def _new_figure(width, height) -> Figure:
    fig = Figure(figsize=(width, height), dpi=100, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


# ------------------------------------------------------------------ plots
def plot_error_over_time(evaluation) -> Figure:
    """One panel per sequence: per-frame error of each method.

    Solid lines are the mean error over the known joints of each frame, dashed lines the
    worst joint's error (the paper's "average" and "max" traces), so each panel holds
    ``2 * methods`` lines.

    Returns
    -------
    matplotlib.figure.Figure with one axis per sequence.
    """
    sequences, methods = evaluation.sequences, evaluation.methods
    fig = _new_figure(8, 2.4 * len(sequences) + 0.6)
    axes = fig.subplots(len(sequences), 1, squeeze=False)[:, 0]
    for ax, name in zip(axes, sequences):
        kind = "joint"
        for method in methods:
            r = evaluation.get(name, method)
            if r is None:
                continue
            err, kind = _errors_for_plot(r)
            frames = np.arange(len(err))
            colour = method_colour(method, methods)
            ax.plot(frames, 100 * metrics.per_frame_mean(err), color=colour, lw=1.5,
                    label=f"{method} average")
            ax.plot(frames, 100 * metrics.per_frame_max(err), color=colour, lw=1.0, ls="--",
                    label=f"{method} max")
        ax.set_title(name, fontsize=10)
        ax.set_ylabel(f"{kind} error (cm)")
        ax.set_ylim(bottom=0)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, ncol=min(3, 2 * len(methods)), loc="upper left")
    axes[-1].set_xlabel("frame")
    return fig


def plot_fit_over_time(evaluation) -> Figure:
    """One panel per sequence: how well each method's fitted body explains the depth per frame.

    Solid lines: silhouette IoU; dashed: the share of the person's pixels left unexplained
    (:mod:`depthtrack.evaluate.fit`); so each panel holds ``2 * methods`` lines (a method
    without fit figures draws empty lines). Needs no ground truth.
    """
    sequences, methods = evaluation.sequences, evaluation.methods
    fig = _new_figure(8, 2.4 * len(sequences) + 0.6)
    axes = fig.subplots(len(sequences), 1, squeeze=False)[:, 0]
    for ax, name in zip(axes, sequences):
        for method in methods:
            r = evaluation.get(name, method)
            if r is None:
                continue
            fit = r.fit if r.fit is not None else np.full((len(r.joints), 3), np.nan)
            frames = np.arange(len(fit))
            colour = method_colour(method, methods)
            ax.plot(frames, fit[:, 0], color=colour, lw=1.5, label=f"{method} IoU")
            ax.plot(frames, fit[:, 1], color=colour, lw=1.0, ls="--", label=f"{method} unexplained")
        ax.set_title(name, fontsize=10)
        ax.set_ylabel("fraction")
        ax.set_ylim(0, 1)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, ncol=min(3, 2 * len(methods)), loc="center left")
    axes[-1].set_xlabel("frame")
    return fig


def per_joint_means(evaluation, method):
    """``(15,)`` mean error of each contract joint for ``method``, averaged over sequences."""
    rows = [metrics.per_point_mean(r.joint_errors) for r in evaluation.results if r.method == method]
    rows = np.array(rows) if rows else np.full((1, len(JOINT_NAMES)), np.nan)
    known = np.isfinite(rows)
    counts = known.sum(axis=0)
    return np.where(counts > 0, np.where(known, rows, 0).sum(axis=0) / np.maximum(counts, 1), np.nan)


def plot_joint_errors(evaluation) -> Figure:
    """Grouped bars: the mean error of each of the 15 contract joints, one bar per method.

    Per joint, the mean over frames in each sequence, then over sequences. Holds
    ``15 * methods`` bars (a joint never known gets a zero-height bar).
    """
    methods = evaluation.methods
    fig = _new_figure(10, 4)
    ax = fig.subplots()
    x = np.arange(len(JOINT_NAMES))
    width = 0.8 / len(methods)
    for k, method in enumerate(methods):
        values = 100 * per_joint_means(evaluation, method)
        ax.bar(x + (k - (len(methods) - 1) / 2) * width, np.nan_to_num(values), width,
               color=method_colour(method, methods), label=method)
    ax.set_xticks(x, JOINT_NAMES, rotation=45, ha="right")
    ax.set_ylabel("mean joint error (cm)")
    ax.set_title("error per joint (averaged over sequences)")
    ax.grid(axis="y", alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0))
    return fig


def _sequence_error(result, use_markers):
    err = result.marker_errors if use_markers else result.joint_errors
    per_frame = metrics.per_frame_mean(err)
    known = per_frame[np.isfinite(per_frame)]
    if not len(known):
        return np.nan, np.nan
    return float(known.mean()), float(known.std())


def plot_methods(evaluation) -> Figure:
    """The paper's results figure: the methods side by side for each sequence.

    Top panel: grouped bars, one group per sequence and one bar per method, the average
    error with the standard deviation over frames as error bars. The paper's metric (the
    markers' average error) is used when every result has markers, the mean joint error
    otherwise. Sequences are sorted from the highest to the lowest error (averaged over
    methods), as the paper sorts from most to least complex.
    Bottom panel (when both ``hc`` and ``hc+ep`` ran): the error of hc+ep minus that of hc
    per sequence (negative = the combined tracker is better).

    Returns
    -------
    Figure; its first axis holds ``sequences * methods`` bars, the second (if any) ``sequences``.
    """
    sequences, methods = evaluation.sequences, evaluation.methods
    use_markers = all(r.marker_errors is not None for r in evaluation.results)
    table = {(s, m): _sequence_error(evaluation.get(s, m), use_markers) if evaluation.get(s, m) else (np.nan, np.nan)
             for s in sequences for m in methods}

    def hardest_first(name):
        known = [table[name, m][0] for m in methods if np.isfinite(table[name, m][0])]
        return -float(np.mean(known)) if known else 0.0

    order = sorted(sequences, key=hardest_first)
    compare = "hc" in methods and "hc+ep" in methods
    fig = _new_figure(max(6, 1.2 * len(sequences) * max(1, len(methods) / 2) + 2), 6.5 if compare else 4)
    axes = fig.subplots(2 if compare else 1, 1, squeeze=False)[:, 0]
    x = np.arange(len(order))
    width = 0.8 / len(methods)
    ax = axes[0]
    for k, method in enumerate(methods):
        mean = np.array([table[s, method][0] for s in order])
        std = np.array([table[s, method][1] for s in order])
        ax.bar(x + (k - (len(methods) - 1) / 2) * width, 100 * np.nan_to_num(mean), width,
               yerr=100 * np.nan_to_num(std), capsize=3, color=method_colour(method, methods), label=method)
    what = "marker" if use_markers else "joint"
    ax.set_ylabel(f"average {what} error (cm)")
    ax.set_title("tracking error per sequence (sorted by error; bars: mean, whiskers: s.d. over frames)",
                 fontsize=9)
    ax.set_xticks(x, order, rotation=20, ha="right")
    ax.grid(axis="y", alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0))
    if compare:
        ax = axes[1]
        diff = np.array([table[s, "hc+ep"][0] - table[s, "hc"][0] for s in order])
        diff = 100 * np.nan_to_num(diff)
        ax.bar(x, diff, 0.6, color=np.where(diff <= 0, "tab:green", "tab:red"))
        ax.axhline(0, color="black", lw=0.8)
        ax.set_ylabel("hc+ep - hc (cm)")
        ax.set_title("error difference of the combined tracker w.r.t. hill climbing (below 0: better)",
                     fontsize=9)
        ax.set_xticks(x, order, rotation=20, ha="right")
        ax.grid(axis="y", alpha=0.3)
    return fig


def figure_png(fig: Figure) -> bytes:
    """PNG bytes of a figure."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    return buf.getvalue()


# ------------------------------------------------------------------ text
def _cm(value):
    return "n/a" if value is None else f"{100 * value:.1f}"


def _pct(value):
    return "n/a" if value is None else f"{100 * value:.0f}%"


def _fps(value):
    return "n/a" if value is None else f"{value:.2f}"


def _frac(value, digits=2):
    return "n/a" if value is None else f"{value:.{digits}f}"


def fit_markdown_table(rows) -> str:
    """Markdown table of the fit figures of ``rows``: iterable of (label, method, M)."""
    lines = ["| sequence | method | silhouette IoU | unexplained | median depth residual (cm) | "
             "segment length error (cm) |",
             "|---|---|---:|---:|---:|---:|"]
    for label, method, m in rows:
        lines.append(f"| {label} | {method} | {_frac(m.get('silhouette_iou'))} | "
                     f"{_pct(m.get('unexplained_fraction'))} | {_cm(m.get('median_depth_residual_m'))} | "
                     f"{_cm(m.get('segment_length_error_m'))} |")
    return "\n".join(lines) + "\n"


def markdown_table(rows) -> str:
    """Markdown table of ``rows``: iterable of (label, method, M)."""
    lines = ["| sequence | method | frames | mean error (cm) | max error (cm) | within 10 cm | "
             "marker avg (cm) | marker max (cm) | fps | back to front |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for label, method, m in rows:
        lines.append(f"| {label} | {method} | {m['frames']} | {_cm(m['mean_error_m'])} | "
                     f"{_cm(m['max_error_m'])} | {_pct(m['within_10cm'])} | "
                     f"{_cm(m['marker_mean_error_m'])} | {_cm(m['marker_max_error_m'])} | {_fps(m['fps'])} | "
                     f"{_pct(m.get('back_to_front_fraction'))} |")
    return "\n".join(lines) + "\n"


def format_markdown(evaluation, data=None) -> str:
    """The report's Markdown text."""
    data = data or evaluation.to_dict()
    rows = [(name, method, m) for name, per in data["sequences"].items() for method, m in per.items()]
    overall = [(f"**all ({len(data['sequences'])})**", method, m) for method, m in data["overall"].items()]
    likelihood = evaluation.likelihood or "as recorded in the tracks"
    return "\n".join([
        "# depthtrack evaluation",
        "",
        f"Sequences: {len(data['sequences'])}; methods: {', '.join(evaluation.methods)}; "
        f"likelihood: {likelihood}.",
        "",
        markdown_table(rows + overall),
        "Definitions: *mean error* is the mean distance of the 15 contract joints to the ground "
        "truth over all known (frame, joint) pairs; *max error* is the worst joint's error in each "
        "frame, averaged over frames; *within 10 cm* is the fraction of known joints closer than "
        f"{100 * metrics.WITHIN_THRESHOLD_M:.0f} cm; *marker avg / max* are the paper's metrics "
        "(per frame the mean / largest distance between the visible mocap markers and the same "
        "markers on the fitted mesh, averaged over frames; n/a without markers); *fps* is frames "
        "tracked per second of wall-clock time; *back to front* is the share of frames whose "
        "tracked trunk faces away from the true one (the left-to-right axis of hips and "
        "shoulders against the truth's: the body seen from the wrong side). The *all* rows "
        "average the sequences, each "
        "sequence weighing the same (frames: the total).",
        "",
        "## Fit to the depth (no ground truth needed)",
        "",
        fit_markdown_table(rows + overall),
        "*silhouette IoU*: overlap of the person's foreground (the tracker's segmentation) and "
        "the fitted body's render, mean over frames (1 = exact); *unexplained*: share of the "
        "person's pixels that the body does not cover within 10 cm of their depth, mean over "
        "frames; *median depth residual*: median |observed - rendered| where both exist "
        "(median over frames); *segment length error*: median over segments of |fitted - true| "
        "length, only for synthetic sequences made with a shape (`synth.shape`). A good fit of "
        "a real person: IoU at least 0.85 and at most 8 % unexplained.",
        "",
        "## Plots",
        "",
        "![methods per sequence](methods.png)",
        "",
        "![error over time](error_over_time.png)",
        "",
        "![error per joint](joint_errors.png)",
        "",
        "![fit over time](fit_over_time.png)",
        "",
        "Per-frame errors: `errors.csv`.",
        "",
    ])


def format_errors_csv(evaluation) -> str:
    """Per-frame errors of every (sequence, method) as CSV text."""
    out = ["sequence,method,frame,mean_error_m,max_error_m,marker_mean_error_m,marker_max_error_m,"
           "silhouette_iou,unexplained_fraction,median_depth_residual_m"]

    def cell(v):
        return "" if not np.isfinite(v) else f"{v:.6f}"

    for r in evaluation.results:
        mean, worst = metrics.per_frame_mean(r.joint_errors), metrics.per_frame_max(r.joint_errors)
        if r.marker_errors is not None:
            mmean, mworst = metrics.per_frame_mean(r.marker_errors), metrics.per_frame_max(r.marker_errors)
        else:
            mmean = mworst = np.full(len(mean), np.nan)
        fit = r.fit if r.fit is not None else np.full((len(mean), 3), np.nan)
        for f in range(len(mean)):
            out.append(f"{r.sequence},{r.method},{f},{cell(mean[f])},{cell(worst[f])},"
                       f"{cell(mmean[f])},{cell(mworst[f])},{cell(fit[f, 0])},{cell(fit[f, 1])},"
                       f"{cell(fit[f, 2])}")
    return "\n".join(out) + "\n"


def format_text_table(evaluation, data=None) -> str:
    """A plain-text table for the terminal."""
    data = data or evaluation.to_dict()
    header = f"{'sequence':<20} {'method':<7} {'frames':>6} {'mean cm':>8} {'max cm':>8} {'<10cm':>6} " \
             f"{'mk avg':>7} {'mk max':>7} {'fps':>7} {'IoU':>5} {'unexpl':>6}"
    lines = [header, "-" * len(header)]

    def row(label, method, m):
        return (f"{label:<20} {method:<7} {m['frames']:>6} {_cm(m['mean_error_m']):>8} "
                f"{_cm(m['max_error_m']):>8} {_pct(m['within_10cm']):>6} {_cm(m['marker_mean_error_m']):>7} "
                f"{_cm(m['marker_max_error_m']):>7} {_fps(m['fps']):>7} "
                f"{_frac(m.get('silhouette_iou')):>5} {_pct(m.get('unexplained_fraction')):>6}")

    for name, per in data["sequences"].items():
        for method, m in per.items():
            lines.append(row(name[:20], method, m))
    for method, m in data["overall"].items():
        lines.append(row("ALL (seq. mean)", method, m))
    return "\n".join(lines) + "\n"


def write_report(evaluation, out_dir) -> dict:
    """Write the report directory atomically (replacing ``out_dir`` as a whole).

    Returns
    -------
    dict {file name: pathlib.Path} of the files written (under ``out_dir``).
    """
    out_dir = Path(out_dir)
    data = evaluation.to_dict()
    figures = {"error_over_time.png": plot_error_over_time(evaluation),
               "joint_errors.png": plot_joint_errors(evaluation),
               "methods.png": plot_methods(evaluation),
               "fit_over_time.png": plot_fit_over_time(evaluation)}
    files = {
        "metrics.json": json.dumps(data, indent=1) + "\n",
        "report.md": format_markdown(evaluation, data),
        "errors.csv": format_errors_csv(evaluation),
    }
    with atomic_path(out_dir) as tmp:
        tmp = Path(tmp)
        tmp.mkdir()
        for name, text in files.items():
            (tmp / name).write_text(text, encoding="utf-8")
        for name, fig in figures.items():
            (tmp / name).write_bytes(figure_png(fig))
    return {name: out_dir / name for name in (*files, *figures)}


__all__ = ["plot_error_over_time", "plot_joint_errors", "plot_methods", "plot_fit_over_time",
           "fit_markdown_table", "per_joint_means",
           "figure_png", "markdown_table", "format_markdown", "format_errors_csv",
           "format_text_table", "write_report", "PLOT_FILES", "METHOD_COLOURS"]
