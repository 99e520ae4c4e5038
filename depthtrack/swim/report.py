"""The thesis's experiments as one evaluation: runs, metrics, Markdown tables and plots.

Experiments (thesis 7.3.2; figure numbers refer to the thesis):

* ``particles``: error against the number of particles for each sigma, truth
  initialisation, MAP and k-means estimates of the same runs (Figures 7.9, 7.11);
* ``random``: random initialisation, error against particles at sigma 0.1
  (Figure 7.12) and, with the most particles, against larger sigmas (Figure 7.13);
* ``ukf``: the unscented Kalman filter with the same motion model (thesis 8.2);
* ``baseline``: the measurements themselves used as the estimate;
* ``tuned`` and ``gaps``: the filters with estimated noise and the occlusion
  gaps (:mod:`depthtrack.swim.estimation`).
"""
from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from ..io.atomic import atomic_path
from .estimation import NEW_FILTERS, gap_experiment, markdown_new, tuned_runs
from .experiment import (SwimSetup, frame_errors, measurements, run_particle_filter, run_ukf, summarise)
from .tuning import estimate_measurement_noise


def _run_record(kind, filter_name, init, sigma, n_particles, result, window, estimators):
    rec = {"experiment": kind, "filter": filter_name, "init": init, "sigma": sigma,
           "particles": n_particles, "seconds": round(result["seconds"], 3), "estimators": {}}
    for name, est in result["estimates"].items():
        if estimators is not None and name not in estimators and name != "mean":
            continue
        sq, joint = frame_errors(est, window)
        rec["estimators"][name] = dict(summarise(sq, joint), per_frame=[round(float(x), 5) for x in sq])
    if "ess" in result:
        rec["mean_ess"] = float(np.mean(result["ess"]))
    rec["phase_error"] = float(np.mean(np.abs(((result["phase"] - window.phase[1:]) + 0.5) % 1.0 - 0.5)))
    if result.get("kmeans"):
        rec["kmeans"] = result["kmeans"]
    return rec


def run_evaluation(setup: SwimSetup, particles=(100, 1000, 10000, 100000, 1000000), sigmas=(0.05, 0.1, 0.5, 1.0),
                   estimators=("map", "kmeans"), inits=("truth", "random"), filters=("particle", "ukf"),
                   random_sigmas=(0.5, 1.0, 2.0), random_sigma=0.1, noise: float = 0.05, seed: int = 0,
                   threads: int = 1, progress=None, log=None, thesis_particles: int = 100000, gaps=(),
                   rbpf_particles=None, gap_particles: int = 100000):
    """Run the grid of experiments.

    Returns
    -------
    metrics : dict (JSON-ready)
    snapshot : (T, 26) float or None
        MAP estimates of the largest truth-initialised particle run at the sigma
        nearest 0.1 (for the stick-figure snapshots), else the first UKF run's means.
    """
    window = setup.window
    z = measurements(window, noise, np.random.default_rng(seed + 12345))
    runs = []
    started = time.perf_counter()
    snapshot, snapshot_key = None, None

    def say(text):
        if log is not None:
            log(text)

    base_sq, base_joint = frame_errors(z[1:], window)
    baseline = summarise(base_sq, base_joint)
    kmeans_wanted = "kmeans" in estimators
    if "particle" in filters:
        if "truth" in inits:
            for sigma in sigmas:
                for n in particles:
                    r = run_particle_filter(setup.model, window, z, n, sigma, "truth", estimators, seed, threads,
                                            progress=progress)
                    if "map" in r["estimates"]:
                        key = (abs(sigma - 0.1), -n)
                        if snapshot_key is None or key < snapshot_key:
                            snapshot, snapshot_key = r["estimates"]["map"], key
                    runs.append(_run_record("particles", "particle", "truth", sigma, n, r, window, estimators))
                    say(f"particle truth sigma={sigma} N={n}: " + ", ".join(
                        f"{k} {v['error']:.3f}" for k, v in runs[-1]["estimators"].items()) + f" ({r['seconds']:.1f} s)")
        if "random" in inits:
            est = tuple(e for e in estimators if e == "map") or estimators[:1]
            for n in particles:
                r = run_particle_filter(setup.model, window, z, n, random_sigma, "random", est, seed, threads,
                                        progress=progress)
                runs.append(_run_record("random", "particle", "random", random_sigma, n, r, window, est))
                say(f"particle random sigma={random_sigma} N={n}: {runs[-1]['estimators']}"[:120])
            n_max = max(particles)
            for sigma in random_sigmas:
                r = run_particle_filter(setup.model, window, z, n_max, sigma, "random", est, seed, threads,
                                        progress=progress)
                runs.append(_run_record("random_sigma", "particle", "random", sigma, n_max, r, window, est))
                say(f"particle random sigma={sigma} N={n_max}")
    jitter = setup.model.jitter
    if jitter > 0 and "truth" in inits and thesis_particles:
        # The thesis's model exactly (no roughening), for comparison.
        setup.model.jitter = 0.0
        try:
            for sigma in (0.1, 0.5):
                if "particle" in filters:
                    for n in (n for n in particles if n <= thesis_particles):
                        r = run_particle_filter(setup.model, window, z, n, sigma, "truth", ("map",), seed, threads,
                                                progress=progress)
                        runs.append(_run_record("thesis_model", "particle", "truth", sigma, n, r, window, ("map",)))
                        say(f"thesis model (jitter 0) sigma={sigma} N={n}: "
                            f"{runs[-1]['estimators']['map']['error']:.3f}")
                if "ukf" in filters:
                    r = run_ukf(setup.model, window, z, sigma, "truth", seed)
                    runs.append(_run_record("thesis_model", "ukf", "truth", sigma, None, r, window, None))
        finally:
            setup.model.jitter = jitter
    if "ukf" in filters:
        for init in inits:
            for sigma in sorted(set(sigmas) | (set(random_sigmas) if init == "random" else set())):
                r = run_ukf(setup.model, window, z, sigma, init, seed)
                if snapshot is None and init == "truth":
                    snapshot = r["estimates"]["mean"]
                runs.append(_run_record("ukf", "ukf", init, sigma, None, r, window, None))
                say(f"ukf {init} sigma={sigma}: {runs[-1]['estimators']['mean']['error']:.3f}")
    # the filters with estimated noise (Rao-Blackwellised PF, tuned UKF, smoother), then the gaps
    new = tuple(f for f in filters if f in NEW_FILTERS)
    if new:
        runs.extend(tuned_runs(setup, z, new, rbpf_particles or particles, inits, seed, log=say, progress=progress))
    gap_results = []
    if gaps:
        gap_filters = tuple(f for f in filters if f != "particle") or ("ukf-tuned",)
        gap_results = gap_experiment(setup, z, gaps, gap_filters, min(gap_particles, max(rbpf_particles or particles)),
                                     seed=seed, log=say)
    for rec in runs:
        rec["estimators"] = {k: v for k, v in rec["estimators"].items()}
    metrics = {
        "format": "depthtrack-swim-evaluation/1",
        "train": setup.train_path, "test": setup.test_path, "units": setup.units,
        "training_cycles": [{"first_frame": s, "end_frame": e, "side": side} for s, e, side in setup.train_sources],
        "test_window": {"first_frame": window.first_frame, "frames": window.frames, "step": window.step,
                        "fps": window.fps},
        "model": {"reference_length": setup.model.length, "cycles": setup.model.n_cycles,
                  "temporal_sigma": setup.model.temporal_sigma, "jitter": setup.model.jitter},
        "measurement_noise": noise, "seed": seed,
        "error_unit": "rad^2 per frame: squared angle error summed over the 26 angles, mean over frames",
        "baseline_measurement": baseline,
        "measurement_noise_estimate": estimate_measurement_noise(z),
        "process_noise": {"source": "second moment of the model's one-step residuals on the training frames" +
                          (", each cycle under a model trained without it (leave one cycle out)"
                           if setup.process_noise == "loo" else ""),
                          "estimate": setup.process_noise,
                          "residual_frames": setup.residual_count,
                          "velocity_decay": setup.velocity_decay,
                          "rms_angle": None if setup.process_q is None else
                          float(np.sqrt(np.trace(setup.process_q[:26, :26]) / 26)),
                          "rms_velocity": None if setup.process_q is None else
                          float(np.sqrt(np.trace(setup.process_q[26:, 26:]) / 26))},
        "runs": runs,
        "gaps": gap_results,
        "seconds": round(time.perf_counter() - started, 2),
    }
    return metrics, snapshot


# --------------------------------------------------------------------------- tables
def _fmt(x, digits=3):
    return "—" if x is None else f"{x:.{digits}f}"


def markdown_tables(metrics: dict) -> str:
    """The report's Markdown: one table per experiment."""
    runs = metrics["runs"]
    out = []
    out.append(f"Train `{metrics['train']}` ({len(metrics['training_cycles'])} cycles), test `{metrics['test']}` "
               f"frames {metrics['test_window']['first_frame']}.. step {metrics['test_window']['step']} "
               f"({metrics['test_window']['frames']} frames at {metrics['test_window']['fps']:.0f} Hz), "
               f"measurement noise {metrics['measurement_noise']} rad, jitter {metrics['model']['jitter']}.")
    out.append(f"Error: {metrics['error_unit']}. Measurements alone: "
               f"{metrics['baseline_measurement']['error']:.3f} "
               f"({metrics['baseline_measurement']['rms_deg']:.1f} deg RMS, "
               f"{metrics['baseline_measurement']['joint_error_cm']:.1f} cm).")
    for est, title in (("map", "MAP estimate"), ("kmeans", "k-means estimate (k = 1 % of the particles)")):
        rows = [r for r in runs if r["experiment"] == "particles" and est in r["estimators"]]
        if not rows:
            continue
        sigmas = sorted({r["sigma"] for r in rows})
        counts = sorted({r["particles"] for r in rows})
        out.append(f"\n### Particle filter, truth initialisation, {title}\n")
        out.append("| particles | " + " | ".join(f"σ = {s}" for s in sigmas) + " | seconds (σ = {}) |".format(sigmas[-1]))
        out.append("|---:|" + "---:|" * (len(sigmas) + 1))
        for n in counts:
            cells = []
            secs = None
            for s in sigmas:
                r = next((r for r in rows if r["particles"] == n and r["sigma"] == s), None)
                cells.append(_fmt(r["estimators"][est]["error"]) if r else "—")
                if r and s == sigmas[-1]:
                    secs = r["seconds"]
            out.append(f"| {n:,} | " + " | ".join(cells) + f" | {_fmt(secs, 1)} |")
    rows = [r for r in runs if r["experiment"] in ("random", "random_sigma")]
    if rows:
        out.append("\n### Particle filter, random initialisation (MAP)\n")
        out.append("| particles | σ | error | RMS (deg) | joints (cm) | seconds |")
        out.append("|---:|---:|---:|---:|---:|---:|")
        for r in rows:
            e = next(iter(r["estimators"].values()))
            out.append(f"| {r['particles']:,} | {r['sigma']} | {_fmt(e['error'])} | {_fmt(e['rms_deg'], 1)} | "
                       f"{_fmt(e['joint_error_cm'], 1)} | {_fmt(r['seconds'], 1)} |")
    rows = [r for r in runs if r["experiment"] == "thesis_model"]
    if rows:
        out.append("\n### The thesis's model without roughening (jitter 0), truth initialisation\n")
        out.append("| filter | particles | σ | error | RMS (deg) | joints (cm) |")
        out.append("|---|---:|---:|---:|---:|---:|")
        for r in rows:
            e = next(iter(r["estimators"].values()))
            n = "—" if r["particles"] is None else f"{r['particles']:,}"
            out.append(f"| {r['filter']} | {n} | {r['sigma']} | {_fmt(e['error'])} | {_fmt(e['rms_deg'], 1)} | "
                       f"{_fmt(e['joint_error_cm'], 1)} |")
    rows = [r for r in runs if r["filter"] == "ukf" and r["experiment"] == "ukf"]
    if rows:
        out.append("\n### Unscented Kalman filter (same motion model)\n")
        out.append("| init | σ | error | RMS (deg) | joints (cm) | seconds |")
        out.append("|---|---:|---:|---:|---:|---:|")
        for r in rows:
            e = r["estimators"]["mean"]
            out.append(f"| {r['init']} | {r['sigma']} | {_fmt(e['error'])} | {_fmt(e['rms_deg'], 1)} | "
                       f"{_fmt(e['joint_error_cm'], 1)} | {_fmt(r['seconds'], 2)} |")
    return "\n".join(out) + "\n" + markdown_new(metrics)


# --------------------------------------------------------------------------- plots
def write_plots(metrics: dict, directory: Path, setup: SwimSetup | None = None) -> list:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    written = []
    runs = metrics["runs"]

    def save(fig, name):
        fig.tight_layout()
        fig.savefig(directory / name, dpi=110)
        plt.close(fig)
        written.append(name)

    for est, name, title in (("map", "fig7_9a_particles_map.png", "MAP (cf. thesis Fig. 7.9a / 7.11)"),
                             ("kmeans", "fig7_9b_particles_kmeans.png", "k-means (cf. thesis Fig. 7.9b)")):
        rows = [r for r in runs if r["experiment"] == "particles" and est in r["estimators"]]
        if not rows:
            continue
        fig, ax = plt.subplots(figsize=(6, 4))
        for s in sorted({r["sigma"] for r in rows}):
            rs = sorted((r for r in rows if r["sigma"] == s), key=lambda r: r["particles"])
            ax.plot([r["particles"] for r in rs], [r["estimators"][est]["error"] for r in rs], "o-", label=f"σ = {s}")
        ukf = [r for r in runs if r["experiment"] == "ukf" and r["init"] == "truth"]
        for r in ukf:
            if r["sigma"] == 0.1:
                ax.axhline(r["estimators"]["mean"]["error"], color="k", ls="--", lw=1, label="UKF σ = 0.1")
        ax.axhline(metrics["baseline_measurement"]["error"], color="gray", ls=":", lw=1, label="measurement")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("particles")
        ax.set_ylabel("squared angle error per frame (rad²)")
        ax.set_title(title)
        ax.legend(fontsize=8)
        save(fig, name)
    rows = [r for r in runs if r["experiment"] == "random"]
    if rows:
        fig, ax = plt.subplots(figsize=(6, 4))
        truth = [r for r in runs if r["experiment"] == "particles" and r["sigma"] == rows[0]["sigma"]
                 and "map" in r["estimators"]]
        ax.plot([r["particles"] for r in rows], [next(iter(r["estimators"].values()))["error"] for r in rows],
                "o-", label=f"random init, σ = {rows[0]['sigma']}")
        if truth:
            truth = sorted(truth, key=lambda r: r["particles"])
            ax.plot([r["particles"] for r in truth], [r["estimators"]["map"]["error"] for r in truth], "s--",
                    label=f"truth init, σ = {rows[0]['sigma']}")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("particles")
        ax.set_ylabel("squared angle error per frame (rad²)")
        ax.set_title("Random initialisation (cf. thesis Fig. 7.12)")
        ax.legend(fontsize=8)
        save(fig, "fig7_12_random_init.png")
    rows = [r for r in runs if r["experiment"] == "random_sigma"]
    if rows:
        fig, ax = plt.subplots(figsize=(6, 4))
        for r in rows:
            e = next(iter(r["estimators"].values()))
            ax.plot(np.arange(1, len(e["per_frame"]) + 1), e["per_frame"], label=f"σ = {r['sigma']}")
        ax.set_yscale("log")
        ax.set_xlabel("frame")
        ax.set_ylabel("squared angle error (rad²)")
        ax.set_title(f"Random initialisation, {rows[0]['particles']:,} particles (cf. Fig. 7.13)")
        ax.legend(fontsize=8)
        save(fig, "fig7_13_random_sigma.png")
    # error over time: best particle run against the UKF
    pf = [r for r in runs if r["experiment"] == "particles" and "map" in r["estimators"]]
    ukf = [r for r in runs if r["experiment"] == "ukf" and r["init"] == "truth"]
    if pf or ukf:
        fig, ax = plt.subplots(figsize=(7, 4))
        if pf:
            n_max = max(r["particles"] for r in pf)
            for r in (r for r in pf if r["particles"] == n_max):
                ax.plot(r["estimators"]["map"]["per_frame"], lw=1, label=f"PF {n_max:,} σ = {r['sigma']}")
        for r in ukf:
            ax.plot(r["estimators"]["mean"]["per_frame"], lw=1, ls="--", label=f"UKF σ = {r['sigma']}")
        ax.set_yscale("log")
        ax.set_xlabel("frame")
        ax.set_ylabel("squared angle error (rad²)")
        ax.set_title("Error over the test window")
        ax.legend(fontsize=7, ncol=2)
        save(fig, "error_over_time.png")
    return written


def write_snapshots(setup: SwimSetup, estimates, directory: Path, frames=(3, 40), name="fig7_10_snapshots.png"):
    """True (green) and predicted (red) stick figures at a few frames, side view (cf. thesis Fig. 7.10)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .stickfigure import SWIM_PARENTS, angles_to_joints

    w = setup.window
    fig, axes = plt.subplots(1, len(frames), figsize=(4 * len(frames), 3.2))
    for ax, f in zip(np.atleast_1d(axes), frames):
        f = min(f, len(estimates))
        truth = angles_to_joints(w.angles[f], w.lengths)
        est = angles_to_joints(estimates[f - 1], w.lengths)
        for joints, colour in ((truth, "green"), (est, "red")):
            for j in range(1, 14):
                p = SWIM_PARENTS[j]
                ax.plot([joints[p, 2], joints[j, 2]], [joints[p, 1], joints[j, 1]], color=colour, lw=2)
        ax.set_aspect("equal")
        ax.set_title(f"frame {f}")
        ax.set_xlabel("z (m)")
        ax.set_ylabel("y (m, up)")
    fig.tight_layout()
    fig.savefig(directory / name, dpi=110)
    plt.close(fig)
    return name


def write_report(metrics: dict, directory, setup: SwimSetup | None = None, snapshot_estimates=None) -> list:
    """metrics.json, results.md and the plots into ``directory`` (replaced atomically)."""
    directory = Path(directory)
    with atomic_path(directory) as tmp:
        tmp = Path(tmp)
        tmp.mkdir(parents=True)
        (tmp / "metrics.json").write_text(json.dumps(metrics, indent=1))
        (tmp / "results.md").write_text("# Swimmer motion model: evaluation\n\n" + markdown_tables(metrics))
        written = ["metrics.json", "results.md"] + write_plots(metrics, tmp, setup)
        if setup is not None and snapshot_estimates is not None:
            written.append(write_snapshots(setup, snapshot_estimates, tmp))
    return written
