"""The held-out benchmark's statistics and report (tools/benchmark.py writes them).

Per sequence the metrics of ``depthtrack eval --json``; per motion and condition the mean
and spread (standard deviation) over the noise seeds; overall the mean over the
motion-condition groups, each weighing the same, and its spread over the seeds (the overall
figure per seed index, then mean and standard deviation of those); per condition the same
over the condition's motions; the report as Markdown.
"""
from __future__ import annotations

import depthtrack  # noqa: F401  (first, before numpy: the same OpenBLAS kernels on every machine)
import numpy as np

#: The metrics aggregated over seeds (``depthtrack eval --json``'s names).
METRICS = ("within_10cm", "mean_error_m", "max_error_m", "marker_mean_error_m", "fps", "wall_fps",
           "back_to_front_fraction", "trunk_twist_error_deg")


def condition_label(c: dict) -> str:
    parts = [c["camera"], f"az {c['azimuth']:g}"]
    if "distance" in c:
        parts.append(f"{c['distance']:g} m")
    if "camera_height" in c:
        parts.append(f"h {c['camera_height']:g} m")
    if "pitch" in c:
        parts.append(f"pitch {c['pitch']:g}")
    return ", ".join(parts)


def _stats(values) -> dict:
    v = np.array([x for x in values if x is not None], float)
    if len(v) == 0:
        return {"mean": None, "std": None, "n": 0}
    return {"mean": float(v.mean()), "std": float(v.std()), "n": int(len(v))}


def by_condition(sequences: list, methods: list) -> list:
    """Per condition and method: the mean over motions of ``within_10cm`` and its spread over
    seeds (the mean over the condition's motions per seed index), and the slowest fps."""
    rows = []
    for label in dict.fromkeys(s["condition_label"] for s in sequences):
        items = [s for s in sequences if s["condition_label"] == label]
        row = {"condition": label, "motions": sorted({s["motion"] for s in items}), "methods": {}}
        for m in methods:
            by_seed = {}
            for s in items:
                by_seed.setdefault(s["seed_index"], []).append(s["metrics"][m]["within_10cm"])
            row["methods"][m] = {"within_10cm": _stats(float(np.mean(v)) for v in by_seed.values()),
                                 "fps_min": min(s["metrics"][m]["fps"] for s in items)}
        rows.append(row)
    return rows


def time_breakdown(sequences: list, methods: list) -> dict:
    """Per method: mean milliseconds per frame of each stage over the kept tracks, the start
    (``init_s``) and the slowest and mean fps; {} without kept tracks."""
    out = {}
    for m in methods:
        ts = [s["timings"][m] for s in sequences if (s.get("timings") or {}).get(m)]
        if not ts:
            continue
        stages = dict.fromkeys(k for t in ts for k in t["per_frame_ms"])
        out[m] = {"per_frame_ms": {k: float(np.mean([t["per_frame_ms"].get(k, 0.0) for t in ts]))
                                   for k in stages},
                  "init_s": float(np.mean([t["init_s"] for t in ts])),
                  "fps_mean": float(np.mean([t["fps"] for t in ts])),
                  "fps_min": float(min(t["fps"] for t in ts)), "tracks": len(ts)}
        by_stage = [t.get("candidates_per_frame_by_stage") for t in ts]
        if all(by_stage):            # tracks made before the count by stage have none
            names = dict.fromkeys(k for b in by_stage for k in b)
            out[m]["candidates_per_frame_by_stage"] = {
                k: float(np.mean([b.get(k, 0.0) for b in by_stage])) for k in names}
    return out


def aggregate(sequences: list, methods: list) -> tuple:
    """Per (motion, condition) group and overall statistics over seeds."""
    groups = {}
    for s in sequences:
        groups.setdefault((s["motion"], s["condition_label"]), []).append(s)
    rows = []
    for (motion, label), items in groups.items():
        row = {"motion": motion, "condition": label, "seeds": [s["seed"] for s in items], "methods": {}}
        for m in methods:
            row["methods"][m] = {k: _stats(s["metrics"][m].get(k) for s in items) for k in METRICS}
            row["methods"][m]["fps_min"] = min(s["metrics"][m]["fps"] for s in items)
        rows.append(row)
    overall = {}
    for m in methods:
        # Overall per seed index (the mean over groups), then mean and spread over seeds.
        by_seed = {}
        for s in sequences:
            by_seed.setdefault(s["seed_index"], []).append(s["metrics"][m])
        stats = {}
        for k in METRICS:
            known = [[x[k] for x in xs if x.get(k) is not None] for xs in by_seed.values()]
            stats[k] = _stats(float(np.mean(v)) for v in known if v)
        group_means = [r["methods"][m]["within_10cm"]["mean"] for r in rows]
        stats["worst_group_within_10cm"] = min(group_means)
        stats["fps_min"] = min(r["methods"][m]["fps_min"] for r in rows)
        walls = [s["metrics"][m].get("wall_fps") for s in sequences]
        stats["wall_fps_min"] = min(walls) if walls and None not in walls else None
        overall[m] = stats
    return rows, overall


def _wall(o):
    """``wall_fps`` (mean and slowest) of an overall row; "-" for reports made before it."""
    s = o.get("wall_fps") or {}
    if s.get("mean") is None or o.get("wall_fps_min") is None:
        return "-"
    return f"{s['mean']:.2f}, {o['wall_fps_min']:.2f}"


#: A statistic a report made before the metric existed lacks.
_UNKNOWN = {"mean": None, "std": None, "n": 0}


def _deg(s):
    return "-" if s["mean"] is None else f"{s['mean']:.1f} ± {s['std']:.1f}"


def _pct(s):
    return "-" if s["mean"] is None else f"{100 * s['mean']:.0f} ± {100 * s['std']:.0f}%"


def _cm(s):
    return "-" if s["mean"] is None else f"{100 * s['mean']:.1f} ± {100 * s['std']:.1f}"


def machine_renderer():
    """``{"gl_renderer", "gl_version"}`` of this machine's EGL (the one the tracks were drawn
    with: figures move by a few points between rasterisers, README "On a GPU"), or None."""
    from depthtrack.render import GLUnavailableError, gl_info

    try:
        return gl_info()
    except GLUnavailableError:
        return None


def renderer_label(renderer) -> str:
    return "GL renderer unknown" if not renderer else \
        f"GL renderer {renderer['gl_renderer']} ({renderer['gl_version']})"


def software_label(software: dict) -> str:
    """The versions a report's tracks were computed with, one line (figures move between
    installs: README, "Benchmark")."""
    return "Software: " + ", ".join(f"{k} {v}" for k, v in software.items() if v) + "."


def blas_label(blas: dict) -> str:
    """The OpenBLAS kernels a report's tracks were computed with, one line (they follow the
    CPU unless pinned: README, "The same figures on another machine")."""
    kernels = sorted({lib["architecture"] for lib in blas.get("libraries", []) if lib.get("architecture")})
    return f"OpenBLAS kernels: {', '.join(kernels) or 'none loaded'} ({blas.get('pin', 'unknown')})."


def markdown(report: dict) -> str:
    methods = report["methods"]
    out = [f"# Held-out benchmark: {report['split']} split ({report['preset']} preset)", "",
           f"{report['date']}, {report['machine']}, {renderer_label(report.get('renderer'))}, "
           f"commit {report['commit']}; "
           f"{report['seconds']:g} s clips at {report['fps']:g} fps, ToF noise, seeds {report['seeds']}; "
           f"{report['wall_s']:.0f} s wall.", "",
           *([software_label(report["software"]), ""] if report.get("software") else []),
           *([blas_label(report["blas"]), ""] if report.get("blas") else []),
           "Motions: " + ", ".join(f"`{m['name']}` ({m['kind']}, start {m['start_s']:g} s)"
                                   for m in report["motions"]), "",
           *(["**ABLATION: the tracker was told which way each person faces at the start "
              "(`--facing`, read off the ground truth of frame 0).**", ""]
             if report.get("facing_from_truth") else []),
           *([f"**Not the default tracker: `--settings {report['tracker_settings']}`.**", ""]
             if report.get("tracker_settings") else []),
           *([f"**Not the default tracker: `--preset {report['tracker_preset']}`.**", ""]
             if report.get("tracker_preset", "default") != "default" else []),
           "## Overall (each motion-condition group weighs the same; ± = spread over seeds)", "",
           "| method | within 10 cm | mean error (cm) | max error (cm) | marker avg (cm) | fps (mean) | "
           "worst group within 10 cm | slowest sequence fps | fps with the body fits (mean, slowest) | "
           "frames back to front | trunk twist error (deg) |",
           "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for m in methods:
        o = report["overall"][m]
        out.append(f"| {m} | {_pct(o['within_10cm'])} | {_cm(o['mean_error_m'])} | {_cm(o['max_error_m'])} | "
                   f"{_cm(o['marker_mean_error_m'])} | {o['fps']['mean']:.2f} | "
                   f"{100 * o['worst_group_within_10cm']:.0f}% | {o['fps_min']:.2f} | {_wall(o)} | "
                   f"{_pct(o.get('back_to_front_fraction') or _UNKNOWN)} | "
                   f"{_deg(o.get('trunk_twist_error_deg') or _UNKNOWN)} |")
    if report.get("by_condition") and len(report["by_condition"]) > 1:
        out += ["", "## Per condition (mean over the motions; ± = spread over seeds)", "",
                "| condition | " + " | ".join(f"{m} within 10 cm" for m in methods) + " |",
                "|---|" + "---:|" * len(methods)]
        for r in report["by_condition"]:
            out.append(f"| {r['condition']} | " + " | ".join(
                _pct(r["methods"][m]["within_10cm"]) for m in methods) + " |")
    if report.get("time_breakdown"):
        stages = list(dict.fromkeys(k for t in report["time_breakdown"].values()
                                    for k in t["per_frame_ms"]))
        out += ["", "## Where the time goes (mean ms per frame over the kept tracks; start apart)", "",
                "| method | start (s) | " + " | ".join(stages) + " | fps mean | fps slowest |",
                "|---|---:|" + "---:|" * (len(stages) + 2)]
        for m, t in report["time_breakdown"].items():
            out.append(f"| {m} | {t['init_s']:.1f} | " + " | ".join(
                f"{t['per_frame_ms'].get(k, 0.0):.0f}" for k in stages) +
                f" | {t['fps_mean']:.2f} | {t['fps_min']:.2f} |")
        for m, t in report["time_breakdown"].items():
            if t.get("candidates_per_frame_by_stage"):
                out.append(f"\nCandidates scored per frame, {m}: " + ", ".join(
                    f"{k} {v:,.0f}" for k, v in sorted(t["candidates_per_frame_by_stage"].items(),
                                                      key=lambda kv: -kv[1])) + ".")
    out += ["", "## Per motion and condition (mean ± spread over seeds)", "",
            "| motion | condition | method | within 10 cm | mean error (cm) | max error (cm) | slowest fps | "
            "frames back to front |",
            "|---|---|---|---:|---:|---:|---:|---:|"]
    for r in report["groups"]:
        for m in methods:
            g = r["methods"][m]
            out.append(f"| {r['motion']} | {r['condition']} | {m} | {_pct(g['within_10cm'])} | "
                       f"{_cm(g['mean_error_m'])} | {_cm(g['max_error_m'])} | {g['fps_min']:.2f} | "
                       f"{_pct(g.get('back_to_front_fraction') or _UNKNOWN)} |")
    out += ["", "## Per sequence", "",
            "| sequence | method | frames | within 10 cm | mean error (cm) | fps | back to front | body seen |",
            "|---|---|---:|---:|---:|---:|---:|---:|"]
    for s in report["sequences"]:
        seen = (s.get("placement") or {}).get("body_visible")
        for m in methods:
            x = s["metrics"][m]
            b2f = x.get("back_to_front_fraction")
            out.append(f"| {s['name']} | {m} | {x['frames']} | {100 * x['within_10cm']:.0f}% | "
                       f"{100 * x['mean_error_m']:.1f} | {x['fps']:.2f} | "
                       f"{'-' if b2f is None else f'{100 * b2f:.0f}%'} | "
                       f"{'-' if seen is None else f'{100 * seen:.0f}%'} |")
    out += ["", "## Commands", "", "```", report["command"]]
    for s in report["sequences"]:
        out.append(s["synth_command"])
        if s is report["sequences"][-1] or report["sequences"][report["sequences"].index(s) + 1]["eval_command"] \
                != s["eval_command"]:
            out.append(s["eval_command"])
    out += ["```", ""]
    return "\n".join(out)


def paired(base: dict, new: dict, method: str = "hc+ep", metric: str = "within_10cm",
           threshold: float = 0.05) -> dict:
    """Two benchmark reports of the same sequences compared sequence by sequence.

    A setting's effect is the mean of the per-sequence differences ``new - base`` over the
    sequences both reports hold (same names: same motion, condition and noise seed); its
    standard error is their standard deviation over the square root of their number. Which
    attractor a track falls into is decided by small differences, so a few sequences move by
    tens of points either way: ``lost`` and ``gained`` count the sequences that moved by more
    than ``threshold`` (in the metric's units), ``unchanged`` those that did not move at all.

    Parameters
    ----------
    base, new : dict
        ``report.json`` of ``tools/benchmark.py``.
    method : str
    metric : str
        A per-sequence metric of ``depthtrack eval --json`` (``within_10cm``, ...).
    threshold : float

    Returns
    -------
    dict
        ``rows`` (name, base, new, difference; None where a side lacks the metric), ``n``,
        ``mean_difference``, ``standard_error``, ``lost``, ``gained``, ``unchanged``,
        ``only_base`` and ``only_new`` (names in one report alone), and for ``fps`` and
        ``wall_fps`` the mean ratio ``new / base`` (``fps_ratio``, ``wall_fps_ratio``).
    """
    def by_name(report):
        return {s["name"]: s["metrics"].get(method) for s in report["sequences"]}

    b, n = by_name(base), by_name(new)
    names = [k for k in b if k in n]
    rows, diffs, ratios = [], [], {"fps": [], "wall_fps": []}
    for k in names:
        x = None if b[k] is None else b[k].get(metric)
        y = None if n[k] is None else n[k].get(metric)
        d = None if x is None or y is None else float(y) - float(x)
        rows.append({"name": k, "base": x, "new": y, "difference": d})
        if d is not None:
            diffs.append(d)
        for key, values in ratios.items():
            if b[k] and n[k] and b[k].get(key) and n[k].get(key):
                values.append(float(n[k][key]) / float(b[k][key]))
    d = np.array(diffs, float)
    out = {"method": method, "metric": metric, "threshold": threshold, "rows": rows,
           "n": int(len(d)),
           "mean_difference": float(d.mean()) if len(d) else None,
           "standard_error": float(d.std(ddof=1) / np.sqrt(len(d))) if len(d) > 1 else None,
           "lost": int(np.sum(d < -threshold)), "gained": int(np.sum(d > threshold)),
           "unchanged": int(np.sum(d == 0.0)),
           "only_base": [k for k in b if k not in n], "only_new": [k for k in n if k not in b]}
    for key, values in ratios.items():
        out[f"{key}_ratio"] = float(np.mean(values)) if values else None
    return out
