#!/usr/bin/env python
"""Speed of the swimmer filters: a million particles for 200 frames, wall time and peak memory.

    PYTHONPATH=. python tools/bench_swim_filters.py [BVH] [--particles 1000000] [--frames 200]
        [--filter rbpf|particle] [--repeat 3]

Trains on the cycles of BVH (default ../shared/data/cmu/126_01.bvh) that end before the test
window, as ``depthtrack swim evaluate`` does, and tracks the window with measurements of
0.05 rad noise. Prints one JSON line per run: filtering wall seconds and the process's CPU
seconds (best of --repeat; the filters run on one thread, so the CPU time is the wall time
on an idle core), the error, the process's peak resident memory (ru_maxrss) and the
machine's load average, since this 2-core machine is shared and timings move with its load.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import sys
import time

import depthtrack  # noqa: F401  (first, before numpy: the same OpenBLAS kernels on every machine)
import numpy as np


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("bvh", nargs="?", default="../shared/data/cmu/126_01.bvh")
    p.add_argument("--particles", type=int, default=1_000_000)
    p.add_argument("--frames", type=int, default=200)
    p.add_argument("--filter", choices=("rbpf", "particle"), default="rbpf")
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--noise", type=float, default=0.05)
    args = p.parse_args(argv)
    if not os.path.isfile(args.bvh):
        print(f"bench_swim_filters: {args.bvh}: no such BVH file", file=sys.stderr)
        return 2
    from depthtrack.swim.experiment import frame_errors, measurements, prepare, run_particle_filter, summarise
    from depthtrack.swim.tracking import run_rbpf
    from depthtrack.swim.tuning import estimate_measurement_noise

    setup = prepare(args.bvh, args.bvh, frames=args.frames)
    setup.model.jitter = 0.1
    z = measurements(setup.window, args.noise, np.random.default_rng(12345))
    best, err = None, None
    for k in range(args.repeat):
        start, cpu = time.perf_counter(), time.process_time()
        if args.filter == "rbpf":
            r = run_rbpf(setup.model, setup.window, z, args.particles, setup.process_q,
                         estimate_measurement_noise(z), seed=k)
            est = r["estimates"]["mean"]
        else:
            r = run_particle_filter(setup.model, setup.window, z, args.particles, 0.5, "truth", ("map",), seed=k)
            est = r["estimates"]["map"]
        wall, cpu = time.perf_counter() - start, time.process_time() - cpu
        err = summarise(*frame_errors(est, setup.window))["error"]
        best = wall if best is None else min(best, wall)
        best_cpu = cpu if k == 0 else min(best_cpu, cpu)
        print(json.dumps({"filter": args.filter, "particles": args.particles, "frames": args.frames, "run": k,
                          "seconds": round(wall, 2), "cpu_seconds": round(cpu, 2), "error": round(err, 4),
                          "load_average": os.getloadavg()[0]}), flush=True)
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(json.dumps({"filter": args.filter, "particles": args.particles, "frames": args.frames,
                      "best_seconds": round(best, 2), "best_cpu_seconds": round(best_cpu, 2), "peak_rss_mb": round(peak_mb), "error": round(err, 4),
                      "cpus": os.cpu_count()}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
