"""Evaluation against ground truth: metrics, batch runs, reports with plots, overlays, the demo.

* :mod:`.metrics` -- pure error functions over arrays (NaN = unknown);
* :mod:`.markers` -- the mocap markers' places on a fitted body;
* :mod:`.runs` -- track or read tracks of sequences with several methods and score them;
* :mod:`.report` -- metrics.json, report.md, errors.csv and matplotlib (Agg) plots;
* :mod:`.overlay` -- MP4/GIF videos of depth + fitted silhouette + skeleton;
* :mod:`.demo` -- the end-to-end demo on the built-in procedural motion.

The plotting, video and demo modules load on first use (matplotlib and OpenCV are slow
to import), so ``import depthtrack.evaluate`` stays cheap.
"""
from . import metrics
from .metrics import (average_marker_error, fraction_within, joint_errors, marker_errors,
                      max_marker_error, mean_error, mean_max_error)
from .runs import METHODS, Evaluation, MethodResult, evaluate

_LAZY = {
    "write_report": "report", "plot_methods": "report", "plot_error_over_time": "report",
    "plot_joint_errors": "report", "write_overlay": "overlay", "overlay_frames": "overlay",
    "run_demo": "demo", "marker_positions": "markers",
}


def __getattr__(name):
    if name in _LAZY:
        import importlib

        module = importlib.import_module(f"{__name__}.{_LAZY[name]}")
        return getattr(module, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["metrics", "joint_errors", "mean_error", "mean_max_error", "fraction_within",
           "marker_errors", "average_marker_error", "max_marker_error", "METHODS", "Evaluation",
           "MethodResult", "evaluate", *_LAZY]
