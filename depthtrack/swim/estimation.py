"""Experiments for the filters that beat the measurements, and for occlusion gaps: runs, JSON, Markdown.

* ``tuned_runs``: the Rao-Blackwellised particle filter (``rbpf``, for each
  particle count), the UKF with estimated noise (``ukf-tuned``) and its RTS
  smoother (``smoother``), against the same measurements as the thesis's filters.
* ``gap_experiment``: for each gap length K, measurements withheld on the
  schedule of :func:`depthtrack.swim.gaps.gap_mask`; the filters predict through
  the gaps; errors inside and after the gaps, overall and per quarter of the
  stroke cycle, for the filters and the baselines (hold, constant velocity,
  linear interpolation). Inside the gaps ``rbpf`` and ``ukf-tuned`` predict on
  the sphere of segment directions (:mod:`depthtrack.swim.sphere`);
  ``rbpf-angles`` and ``ukf-tuned-angles`` are the same runs' own predictions
  in angles (the model before), for comparison.
"""
from __future__ import annotations

import numpy as np

from .experiment import SwimSetup, frame_errors, run_ukf, summarise
from .gaps import gap_baselines, gap_errors, gap_mask, gap_runs, withhold
from .tracking import run_rbpf, run_ukf_tuned
from .tuning import estimate_measurement_noise

NEW_FILTERS = ("rbpf", "ukf-tuned", "smoother")


def _record(filter_name, init, n_particles, result, window, r_sigma):
    rec = {"experiment": "tuned", "filter": filter_name, "init": init, "sigma": round(r_sigma, 5),
           "sigma_source": "estimated from the measurements (third differences)",
           "particles": n_particles, "seconds": round(result["seconds"], 3), "estimators": {}}
    for name, est in result["estimates"].items():
        sq, joint = frame_errors(est, window)
        rec["estimators"][name] = dict(summarise(sq, joint), per_frame=[round(float(x), 5) for x in sq])
    if "ess" in result:
        rec["mean_ess"] = float(np.mean(result["ess"]))
    rec["phase_error"] = float(np.mean(np.abs(((result["phase"] - window.phase[1:]) + 0.5) % 1.0 - 0.5)))
    return rec


def tuned_runs(setup: SwimSetup, z, filters, particles, inits=("truth",), seed: int = 0, log=None,
               progress=None) -> list:
    """Runs of the new filters on measurements ``z (T + 1, A)`` (JSON records like the thesis runs)."""
    if setup.process_q is None:
        return []
    window, model = setup.window, setup.model
    r_sigma = estimate_measurement_noise(z)
    runs = []
    for init in inits:
        if "rbpf" in filters:
            for n in particles:
                r = run_rbpf(model, window, z, n, setup.process_q, r_sigma, init, seed, progress=progress,
                             gap_rho=setup.velocity_decay)
                runs.append(_record("rbpf", init, n, r, window, r_sigma))
                if log:
                    log(f"rbpf {init} N={n}: mean {runs[-1]['estimators']['mean']['error']:.4f} "
                        f"({r['seconds']:.1f} s)")
        if "ukf-tuned" in filters or "smoother" in filters:
            r = run_ukf_tuned(model, window, z, setup.process_q, r_sigma, init, seed, smooth="smoother" in filters,
                              gap_rho=setup.velocity_decay)
            if "ukf-tuned" in filters:
                runs.append(_record("ukf-tuned", init, None, r, window, r_sigma))
            if "smoother" in filters:
                runs.append(_record("smoother", init, None, r["smoothed"], window, r_sigma))
            if log:
                log(f"ukf-tuned/smoother {init}: " + ", ".join(
                    f"{x['filter']} {x['estimators']['mean']['error']:.4f}" for x in runs[-2:]))
    return runs


def gap_experiment(setup: SwimSetup, z, lengths, filters=("ukf", "rbpf", "ukf-tuned", "smoother"),
                   particles: int = 100000, ukf_sigma: float = 0.1, seed: int = 0, log=None,
                   first: int = 20, spacing: int = 40, after: int = 10, cv_window: int = 5) -> list:
    """Errors inside and after gaps of each length in ``lengths`` (see module docstring).

    Returns a list of dicts: ``length``, ``gaps`` ([start, stop) test frames), ``methods``
    {name: :func:`depthtrack.swim.gaps.gap_errors` dict}, ``ratio_cv`` {filter: constant-velocity
    error inside the gaps / the filter's}.
    """
    window, model = setup.window, setup.model
    out = []
    phase = window.phase[1:]
    for k in lengths:
        mask = gap_mask(window.frames, k, first, spacing)
        zg = withhold(z, mask)
        methods = {}
        def errors(est):
            sq, joint = frame_errors(est, window)
            return gap_errors(sq, mask, phase, after, joint=joint)

        for name, est in gap_baselines(z, mask, cv_window).items():
            methods[name] = errors(est[1:])
        r_sigma = estimate_measurement_noise(zg)
        if "ukf" in filters:
            r = run_ukf(model, window, zg, ukf_sigma, "truth", seed)
            methods["ukf"] = errors(r["estimates"]["mean"])
        if "rbpf" in filters and setup.process_q is not None:
            r = run_rbpf(model, window, zg, particles, setup.process_q, r_sigma, "truth", seed,
                         gap_rho=setup.velocity_decay)
            methods["rbpf"] = errors(r["estimates"]["mean"])
            methods["rbpf-angles"] = errors(r.get("filter_estimates", r["estimates"])["mean"])
        if ("ukf-tuned" in filters or "smoother" in filters) and setup.process_q is not None:
            r = run_ukf_tuned(model, window, zg, setup.process_q, r_sigma, "truth", seed, gap_rho=setup.velocity_decay)
            methods["ukf-tuned"] = errors(r["estimates"]["mean"])
            methods["ukf-tuned-angles"] = errors(r.get("filter_estimates", r["estimates"])["mean"])
            methods["smoother"] = errors(r["smoothed"]["estimates"]["mean"])
        cv = methods["constant_velocity"]["inside"]
        cv_cm = methods["constant_velocity"]["inside_cm"]
        ratio = {name: (None if not m["inside"] else round(cv / m["inside"], 3))
                 for name, m in methods.items() if name in ("ukf", "rbpf", "ukf-tuned", "smoother", "rbpf-angles",
                                                                "ukf-tuned-angles")}
        ratio_cm = {name: (None if not m["inside_cm"] else round(cv_cm / m["inside_cm"], 3))
                    for name, m in methods.items() if name in ratio}
        out.append({"length": int(k), "first": first, "spacing": spacing, "after": after, "cv_window": cv_window,
                    "rbpf_particles": particles, "ukf_sigma": ukf_sigma, "gap_prediction": "sphere",
                    "gaps": [[int(a), int(b)] for a, b in gap_runs(mask)], "methods": methods, "ratio_cv": ratio,
                    "ratio_cv_cm": ratio_cm})
        if log:
            log(f"gaps of {k}: " + ", ".join(f"{n} {m['inside']:.3f}" for n, m in methods.items()
                                            if m["inside"] is not None))
    return out


def _fmt(x, digits=3):
    return "—" if x is None else f"{x:.{digits}f}"


def markdown_new(metrics: dict) -> str:
    """Markdown tables of the tuned filters and the gap experiment (empty when neither ran)."""
    out = []
    rows = [r for r in metrics["runs"] if r["experiment"] == "tuned"]
    base = metrics["baseline_measurement"]["error"]
    if rows:
        sig = rows[0]["sigma"]
        out.append(f"\n### Filters with estimated noise (measurement noise estimated {sig} rad; "
                   f"measurements alone {base:.4f})\n")
        out.append("| filter | init | particles | mean | MAP | joints (cm) | vs measurements | seconds |")
        out.append("|---|---|---:|---:|---:|---:|---:|---:|")
        for r in rows:
            e = r["estimators"]["mean"]
            m = r["estimators"].get("map", {}).get("error")
            n = "—" if r["particles"] is None else f"{r['particles']:,}"
            out.append(f"| {r['filter']} | {r['init']} | {n} | {_fmt(e['error'], 4)} | {_fmt(m, 4)} | "
                       f"{_fmt(e['joint_error_cm'], 1)} | {e['error'] / base:.2f}x | {_fmt(r['seconds'], 2)} |")
    for g in metrics.get("gaps", []):
        out.append(f"\n### Gaps of {g['length']} frames (test frames {g['gaps']}); error inside the gaps, "
                   f"in the {g['after']} frames after, per quarter of the cycle inside\n")
        out.append("| method | inside | after | inside, c in [0, .25) | [.25, .5) | [.5, .75) | [.75, 1) | "
                   "CV / method | inside (cm) | CV / method (cm) |")
        out.append("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
        for name, m in g["methods"].items():
            ratio, ratio_cm = g["ratio_cv"].get(name), g.get("ratio_cv_cm", {}).get(name)
            out.append(f"| {name} | {_fmt(m['inside'])} | {_fmt(m['after'])} | " +
                       " | ".join(_fmt(x) for x in m["inside_per_phase"]) + f" | {_fmt(ratio, 1)} | "
                       f"{_fmt(m.get('inside_cm'), 1)} | {_fmt(ratio_cm, 1)} |")
    return "\n".join(out) + ("\n" if out else "")
