"""Where the error through a gap comes from: the model itself, or the filter's state when the gap starts.

For each gap of the schedule of :func:`depthtrack.swim.gaps.gap_mask` the tuned
UKF (:func:`depthtrack.swim.tracking.run_ukf_tuned`, every frame measured) gives
its state at the last measured frame; the motion model with the gap's velocity
decay then predicts the gap's frames from that state, and from the same state
with the true phase and speed, and also the true angles or the true velocities
(central differences of the truth), or all of them, with the model in angles and (``sphere``
rows) integrated on the sphere of segment directions (:mod:`depthtrack.swim.sphere`, what the
filters predict gaps with). The differences split the in-gap error
into the model's own part and the part of each state component. Also the error
by position inside the gap, of constant velocity and of the filter run with
the gap withheld, the error per segment inside the gaps, and how often each
segment of the (continuous) truth is the other representation of the mean
stroke's pose (:func:`depthtrack.swim.stickfigure.zenith_sign`).

Run: ``python -m depthtrack.swim.gap_diagnosis --train B --test B [--test-start 566]
[--noise 0.05] [--gaps 10,30]`` (JSON on stdout; a few seconds).
"""
from __future__ import annotations

import argparse
import json
import sys

import numpy as np

from ..errors import InputError
from ..filters.angles import wrap
from .experiment import frame_errors, measurements, prepare
from .gaps import gap_baselines, gap_mask, gap_runs, withhold
from .stickfigure import (SEGMENTS, angle_error_sq, continue_angles, equivalent_branch,
                          nearest_equivalent)
from .sphere import sphere_transition
from .tracking import decaying_transition, run_ukf_tuned
from .tuning import estimate_measurement_noise


def predict_gaps(fx, starts, runs):
    """Angles predicted through each gap: ``fx`` applied to ``starts[i] (D,)`` (the state at frame
    ``a - 1``) for the gap ``runs[i] = (a, b)``; returns a list of ``(b - a, D)`` states."""
    out = []
    for x, (a, b) in zip(starts, runs):
        xs, x = [], np.array(x, dtype=float)
        for _ in range(b - a):
            x = fx(x)[0]
            xs.append(x.copy())
        out.append(np.array(xs))
    return out


def diagnose(setup, z, length: int, first: int = 20, spacing: int = 40) -> dict:
    """In-gap errors (rad^2 per frame) of the model's predictions from the filter's and the true state.

    ``z (T + 1, A)``: the measurements. Returns a dict (see module docstring).
    """
    model, window = setup.model, setup.window
    A = model.n_angles
    mask = gap_mask(window.frames, length, first, spacing)
    runs = gap_runs(mask)
    r_sigma = estimate_measurement_noise(z)
    states = run_ukf_tuned(model, window, z, setup.process_q, r_sigma, smooth=False)["states"]   # frames 1..T
    truth = window.angles
    fx = decaying_transition(model, setup.velocity_decay)
    fx_sphere = sphere_transition(model, setup.velocity_decay)

    def error(starts, fx=fx):
        pred = predict_gaps(fx, starts, runs)
        sq = [np.sum(wrap(nearest_equivalent(p[:, :A], truth[a:b]) - truth[a:b]) ** 2, axis=1)
              for p, (a, b) in zip(pred, runs)]
        return float(np.mean(np.concatenate(sq)))

    filt = [states[a - 2] for a, _ in runs]
    # the truth in each filter state's representation, velocities by central differences
    true_th = [continue_angles(truth[a - 2:a + 1], reference=s[:A]) for s, (a, _) in zip(filt, runs)]
    true_x = [np.concatenate([t[1], 0.5 * (t[2] - t[0]), [window.phase[a - 1], window.speed[a - 1]]])
              for t, (a, _) in zip(true_th, runs)]

    def mix(angles_from, velocities_from, cycle_from):
        return [np.concatenate([u[:A], w[A:2 * A], c[2 * A:]]) for u, w, c in zip(angles_from, velocities_from, cycle_from)]

    variants = {"filter state": (filt, filt, filt),
                "filter state, true phase and speed": (filt, filt, true_x),
                "filter angles, true velocities, phase and speed": (filt, true_x, true_x),
                "true angles, phase and speed, filter velocities": (true_x, filt, true_x),
                "true state": (true_x, true_x, true_x)}
    out = {"length": length, "gaps": [[int(a), int(b)] for a, b in runs], "velocity_decay": setup.velocity_decay,
           "model_from": {name: error(mix(*src)) for name, src in variants.items()}}
    for name in ("filter state", "true state"):
        out["model_from"][name + ", sphere"] = error(mix(*variants[name]), fx_sphere)
    # error by position in the gap: constant velocity and the filter run with the gaps withheld (its
    # estimates in the gaps: the roll-out on the sphere)
    zg = withhold(z, mask)
    run = run_ukf_tuned(model, window, zg, setup.process_q, estimate_measurement_noise(zg), smooth=False,
                        gap_rho=setup.velocity_decay)
    for name, est in (("constant_velocity", gap_baselines(z, mask)["constant_velocity"][1:]),
                      ("ukf-tuned", run["estimates"]["mean"])):
        sq = frame_errors(est, window)[0]
        pos = np.full((len(runs), length), np.nan)
        for i, (a, b) in enumerate(runs):
            pos[i, :b - a] = sq[a - 1:b - 1]
        out.setdefault("by_position", {})[name] = [round(float(x), 4) for x in np.nanmean(pos, axis=0)]
        inside = mask[1:]
        per_segment = angle_error_sq(est[inside], truth[1:][inside]).mean(axis=0)
        out.setdefault("per_segment", {})[name] = {n: round(float(x), 4) for n, x in zip(SEGMENTS, per_segment)}
    # how often the continuous truth is the other representation of the mean stroke's pose, per segment
    mean_pose = model.interpolated_rows(model.mean_angles, window.phase)
    _, flipped = equivalent_branch(continue_angles(truth, reference=mean_pose[0]), mean_pose)
    out["other_branch_fraction"] = {n: round(float(x), 3) for n, x in zip(SEGMENTS, flipped.mean(axis=0))}
    return out


def main(argv=None):
    p = argparse.ArgumentParser(prog="python -m depthtrack.swim.gap_diagnosis", description=__doc__.split("\n")[0])
    p.add_argument("--train", required=True)
    p.add_argument("--test", required=True)
    p.add_argument("--test-start", type=int, default=None)
    p.add_argument("--noise", type=float, default=0.05)
    p.add_argument("--gaps", default="10,30")
    p.add_argument("--seed", type=int, default=0)
    args = p.parse_args(argv)
    try:
        setup = prepare(args.train, args.test, test_start=args.test_start)
    except InputError as exc:                     # one line naming the file, exit status 2
        print(f"error: {exc}", file=sys.stderr)
        raise SystemExit(2) from None
    z = measurements(setup.window, args.noise, np.random.default_rng(args.seed + 12345))
    print(json.dumps([diagnose(setup, z, int(k)) for k in args.gaps.split(",")], indent=1))


if __name__ == "__main__":
    main()
