#!/usr/bin/env python
"""The held-out tracking benchmark: synthesize sequences from one split's motions, track, report.

Usage::

    .venv/bin/python tools/benchmark.py --split dev  [--quick | --wide] [--out benchmark-output]
    .venv/bin/python tools/benchmark.py --split test [--quick | --wide]

For every motion of the split (the mocap clips of ``depthtrack/data/motion_split.json``
under ``--data``, and the procedural motions of
``depthtrack.synth.procedural.PROCEDURAL_SPLIT``) and every viewing condition (camera,
azimuth, distance, camera height and pitch) it synthesizes one sequence per noise seed
with ``depthtrack synth`` (ToF noise, 25 fps, the window of ``--seconds`` in which the
motion moves most), tracks and scores it with ``depthtrack eval`` (``--methods``), and
writes ``OUT/SPLIT/report.md`` and ``OUT/SPLIT/report.json``: per sequence, per motion
and condition the mean and spread (standard deviation) over the seeds, and overall (the
mean over motion-condition groups, each weighing the same, and its spread over the seeds),
with every command line that made them.

Presets: ``--wide`` takes every motion of the split, each under one of the quick
preset's three conditions in turn, three seeds, 2 s clips, ``hc+ep``: every motion seen,
in about 40 minutes per split on two idle cores. ``--parity`` takes the quick preset's
three motions under every condition of :data:`CONDITIONS_PARITY` (the three cameras from
the front, SR4000 from 90, 180 and 270 degrees), ``hc+ep`` and ``hc``, and adds a table per
condition and method (mean over the motions): camera and azimuth parity, ``hc+ep`` against
``hc``. ``--quick`` takes three motions of the split (two mocap clips and one procedural
motion), one condition each (SR4000 from the front, Kinect v2 from 120 degrees, Azure
NFOV from 240 degrees), three seeds, 2 s clips and ``hc+ep`` only: a few minutes on two
cores. The full preset (default) takes every motion of the split under six conditions
(the three cameras from all round, a high camera looking down, a far one), three seeds,
4 s clips, ``hc+ep`` and ``hc``. Held out means held out: tune on dev; a setting changed
after looking at a test figure turns that figure into a dev figure.
"""
from __future__ import annotations

import argparse
import concurrent.futures
import datetime
import json
import os
import shlex
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
import depthtrack  # noqa: E402,F401  (before numpy: the same OpenBLAS kernels on every machine)
import numpy as np  # noqa: E402

from depthtrack.environment import blas_kernels, software_versions  # noqa: E402
from depthtrack.io.atomic import write_text_atomic  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from benchmark_report import (aggregate, by_condition, condition_label, machine_renderer,  # noqa: E402
                              markdown, time_breakdown)
from depthtrack.track.settings import PRESETS as TRACKER_PRESETS  # noqa: E402

SPLIT_FILE = REPO / "depthtrack" / "data" / "motion_split.json"
FPS = 25.0

#: Viewing conditions: camera preset, azimuth (deg), and optional distance (m), camera
#: height (m) and pitch (deg, down); None = the synthesizer's default placement.
CONDITIONS_FULL = [
    {"camera": "sr4000", "azimuth": 0},
    {"camera": "kinect-v2", "azimuth": 90},
    {"camera": "azure-nfov", "azimuth": 180},
    {"camera": "sr4000", "azimuth": 270},
    {"camera": "kinect-v2", "azimuth": 45, "camera_height": 2.2, "pitch": 20},
    {"camera": "azure-nfov", "azimuth": 315, "distance": 4.0},
]
CONDITIONS_QUICK = [
    {"camera": "sr4000", "azimuth": 0},
    {"camera": "kinect-v2", "azimuth": 120},
    {"camera": "azure-nfov", "azimuth": 240},
]
#: The parity preset: each motion under every camera from the front, and SR4000 from all
#: round (the goals: the other cameras at least as accurate as SR4000; every azimuth within
#: 5 points of the frontal view).
CONDITIONS_PARITY = [
    {"camera": "sr4000", "azimuth": 0},
    {"camera": "kinect-v2", "azimuth": 0},
    {"camera": "azure-nfov", "azimuth": 0},
    {"camera": "sr4000", "azimuth": 90},
    {"camera": "sr4000", "azimuth": 180},
    {"camera": "sr4000", "azimuth": 270},
]
PRESETS = {
    "full": {"seconds": 4.0, "seeds": 3, "methods": "hc+ep,hc", "clips": None},
    "parity": {"seconds": 2.0, "seeds": 3, "methods": "hc+ep,hc", "clips": 3},
    "quick": {"seconds": 2.0, "seeds": 3, "methods": "hc+ep", "clips": 3},
    "wide": {"seconds": 2.0, "seeds": 3, "methods": "hc+ep", "clips": None},
}


def split_motions(split: str, data: Path) -> list:
    """``[(name, kind, source)]``: the split's mocap clips (kind "bvh") and procedural motions."""
    from depthtrack.synth.procedural import PROCEDURAL_SPLIT

    table = json.loads(SPLIT_FILE.read_text(encoding="utf-8"))
    if split not in table:
        raise SystemExit(f"benchmark: unknown split {split!r}; {SPLIT_FILE.name} has train, dev, test")
    out = [(Path(rel).stem, "bvh", str(data / rel)) for rel in table[split]]
    out += [(name, "procedural", name) for name in PROCEDURAL_SPLIT.get(split, [])]
    return out


def quick_subset(motions: list, n: int) -> list:
    """``n`` motions spread over the list: ``n - 1`` mocap clips and one procedural motion."""
    bvh = [m for m in motions if m[1] == "bvh"]
    proc = [m for m in motions if m[1] == "procedural"]
    k = max(1, n - (1 if proc else 0))
    picked = [bvh[i] for i in np.linspace(0, len(bvh) - 1, min(k, len(bvh))).round().astype(int)] if bvh else []
    return picked + proc[:n - len(picked)]


def motion_conditions(name: str, places: dict, conditions: list, one_each: bool) -> list:
    """The conditions a motion is run under: quick and wide, one, in turn by the motion's
    place (``places[name]``: its index in the split, or in the quick preset's subset); the
    full and parity presets, every one."""
    return [conditions[places[name] % len(conditions)]] if one_each else list(conditions)


def busiest_window(kind: str, source: str, seconds: float) -> float:
    """Start (s, after any calibration frames synth drops) of the ``seconds`` in which the joints move most.

    Chosen from the motion alone (joint speeds), never from tracking results.
    """
    if kind == "bvh":
        from depthtrack.io.bvh import read_bvh

        motion = read_bvh(source)
        skip = motion.leading_jump()
        step = max(1, int(round(motion.fps / 10.0)))
        joints = motion.contract_joint_positions()[skip::step]
        rate = motion.fps / step
    else:
        from depthtrack.body import BodyModel
        from depthtrack.synth.procedural import procedural_motion

        body = BodyModel.default(mesh="decimated")
        rate = 10.0
        joints = body.joint_positions(procedural_motion(source, body, rate))
    speed = np.linalg.norm(np.diff(joints, axis=0), axis=-1).sum(axis=1)        # (F - 1,)
    width = max(1, int(round(seconds * rate)))
    if len(speed) <= width:
        return 0.0
    sums = np.convolve(speed, np.ones(width), mode="valid")
    return round(float(np.argmax(sums)) / rate, 2)


def synth_command(kind, source, out, start, seconds, condition, seed) -> list:
    cmd = ["depthtrack", "synth"]
    cmd += [shown(source), shown(out)] if kind == "bvh" else ["--procedural", source, shown(out)]
    cmd += ["--fps", f"{FPS:g}", "--start", f"{start:g}", "--seconds", f"{seconds:g}",
            "--camera", condition["camera"], "--azimuth", f"{condition['azimuth']:g}"]
    for key, flag in (("distance", "--distance"), ("camera_height", "--camera-height"), ("pitch", "--pitch")):
        if key in condition:
            cmd += [flag, f"{condition[key]:g}"]
    return cmd + ["--noise", "tof", "--seed", str(seed), "--quiet"]


def synth_placement(path) -> dict:
    """The camera placement ``depthtrack synth`` chose (``sequence.json``'s ``synth.placement``):
    distance, how many frames hold the whole body in view and how much of the body is seen."""
    meta = json.loads((Path(path) / "sequence.json").read_text(encoding="utf-8"))
    place = meta.get("synth", {}).get("placement", {})
    return {k: place.get(k) for k in ("distance_m", "frames_in_view", "body_visible")}


def shown(path) -> str:
    """A path as the report shows it: relative to the repository root (where the commands run) when near."""
    rel = os.path.relpath(path, REPO)
    return str(path) if rel.startswith(os.path.join("..", "..")) else rel


def run_depthtrack(cmd: list) -> str:
    """Run a ``depthtrack ...`` command line with this checkout's package; returns stdout."""
    env = dict(os.environ, PYTHONPATH=str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    done = subprocess.run([sys.executable, "-m", "depthtrack", *cmd[1:]], cwd=REPO, env=env,
                          capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"benchmark: {shlex.join(cmd)} failed ({done.returncode}): {done.stderr.strip()[-500:]}")
    return done.stdout


def track_timings(folder: Path):
    """A kept track's ``timings`` from its ``summary.json`` (None when unreadable)."""
    try:
        return json.loads((folder / "summary.json").read_text(encoding="utf-8"))["timings"]
    except (OSError, ValueError, KeyError):
        return None


def facing_from_truth(path) -> str:
    """``"camera"`` or ``"away"``: which way the person of the sequence at ``path`` faces on
    frame 0, from its ground-truth joints, by the rule of ``--facing``
    (:func:`depthtrack.track.start.wrong_side`): the pelvis's forward direction and the
    direction from the pelvis to the camera, both flattened onto the floor. Only for the
    ``--facing-from-truth`` ablation: what a user who looked at the recording would tell
    the tracker.

    The floor's normal is the world's up seen by the synthesizer's camera
    (``synth.placement.world_to_camera`` in ``sequence.json``; the camera's -y without
    it). Measuring against the trunk's axis instead, as this did at first, reads a person
    bent over on frame 0 at random (the trunk's axis is then nearly horizontal).
    """
    from depthtrack.io import open_sequence

    return "camera" if truth_facing_cosines(open_sequence(path))[0] > 0 else "away"


def truth_facing_cosines(seq) -> np.ndarray:
    """(F,) cosine between the pelvis's forward direction and the direction from the pelvis
    to the camera, both flattened onto the floor, per frame of ``seq``'s ground-truth joints
    (the rule of :func:`facing_from_truth`; positive = facing the camera)."""
    from depthtrack.contract import JOINT_INDEX as J

    j = np.asarray(seq.joints, dtype=np.float64)                     # (F, 15, 3)
    placement = (seq.meta.get("synth") or {}).get("placement") or {}
    if "world_to_camera" in placement:
        up = -np.asarray(placement["world_to_camera"], dtype=np.float64)[:3, 1]   # world y is down
    else:
        up = np.array([0.0, -1.0, 0.0])
    up /= np.linalg.norm(up)
    across = j[:, J["l_hip"]] - j[:, J["r_hip"]]
    forward = np.cross(across, up)                 # left x up: the way the pelvis faces
    to_camera = -j[:, J["pelvis"]]
    forward -= (forward @ up)[:, None] * up
    to_camera -= (to_camera @ up)[:, None] * up
    return np.sum(forward * to_camera, axis=1) / (np.linalg.norm(forward, axis=1)
                                                  * np.linalg.norm(to_camera, axis=1))


def noise_seeds(count: int, first: int = 1) -> list:
    """The noise seeds of a run: ``count`` of them from ``first`` on (``--seeds``,
    ``--first-seed``). Dev settings are chosen on seeds 1-3; seeds past them say how much of
    a dev figure is the seeds (README, "Dev at noise seeds 4 and 5")."""
    return list(range(first, first + count))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter,
                                     epilog="examples:\n  tools/benchmark.py --split dev --quick\n"
                                            "  tools/benchmark.py --split dev --wide --first-seed 4 "
                                            "--seeds 2 --jobs 2\n"
                                            "  tools/benchmark.py --split test --out benchmark-output")
    parser.add_argument("--split", default="test", help="dev or test (or train) (default test)")
    parser.add_argument("--quick", action="store_true", help="the quick preset (minutes; see above)")
    parser.add_argument("--wide", action="store_true",
                        help="every motion of the split, one condition each (see above)")
    parser.add_argument("--parity", action="store_true",
                        help="cameras and azimuths compared on a few motions, hc+ep and hc (see above)")
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data"),
                        help="where the split's mocap clips are (default ../shared/data)")
    parser.add_argument("--out", default="benchmark-output", help="output folder (default benchmark-output)")
    parser.add_argument("--seconds", type=float, default=None, help="clip length (preset: 4, quick 2)")
    parser.add_argument("--seeds", type=int, default=None, help="noise seeds per condition (preset 3)")
    parser.add_argument("--first-seed", type=int, default=1,
                        help="the first noise seed (default 1; the seeds are FIRST, FIRST+1, ...): "
                             "fresh seeds give a dev figure the settings were not tuned on, "
                             "e.g. --first-seed 4 --seeds 2")
    parser.add_argument("--methods", default=None, help="tracking methods (preset hc+ep,hc; quick hc+ep)")
    parser.add_argument("--motions", default=None, help="comma-separated motion names of the split to run")
    parser.add_argument("--jobs", type=int, default=1,
                        help="motion-condition groups run at once (default 1; frame rates are "
                             "then shared-machine figures)")
    parser.add_argument("--facing-from-truth", action="store_true",
                        help="ABLATION: tell the tracker which way the person faces at the start "
                             "(depthtrack eval --facing, read off the ground truth of frame 0), as "
                             "a user who looked at the recording would; the report says so")
    parser.add_argument("--settings", metavar="JSON", default=None,
                        help="tracker settings for every sequence (depthtrack eval --settings: "
                             "a JSON object or file), to measure a setting on dev; the report "
                             "keeps them and says the tracker was not the default")
    parser.add_argument("--tracker-preset", choices=tuple(TRACKER_PRESETS), default=None,
                        help="tracker preset for every sequence (depthtrack eval --preset: default, "
                             "fast); the report keeps it and, for any but default, says so")
    parser.add_argument("--keep-tracks", action="store_true",
                        help="also keep every track (OUT/SPLIT/tracks/SEQUENCE/METHOD/), to look at the failures")
    args = parser.parse_args(argv)

    if args.quick + args.wide + args.parity > 1:
        print("benchmark: choose one of --quick, --wide and --parity", file=sys.stderr)
        return 2
    preset_name = ("quick" if args.quick else "wide" if args.wide else "parity" if args.parity
                   else "full")
    one_each = args.quick or args.wide
    preset = dict(PRESETS[preset_name])
    seconds = args.seconds or preset["seconds"]
    n_seeds = args.seeds or preset["seeds"]
    methods = (args.methods or preset["methods"]).split(",")
    if n_seeds < 1 or seconds <= 0 or args.jobs < 1:
        print("benchmark: --seeds, --seconds and --jobs must be positive", file=sys.stderr)
        return 2
    if args.first_seed < 0:
        print(f"benchmark: --first-seed must be 0 or more, not {args.first_seed}", file=sys.stderr)
        return 2
    data = Path(args.data).resolve()
    motions = split_motions(args.split, data)
    missing = [src for _, kind, src in motions if kind == "bvh" and not Path(src).is_file()]
    if missing:
        print(f"benchmark: motion clips not found: {', '.join(missing)}", file=sys.stderr)
        return 2
    # each motion's place in turn for the one-condition presets: its place in the split, so
    # that --motions picks out the very sequences of the whole preset
    places = {m[0]: k for k, m in enumerate(motions)}
    if args.motions:
        wanted = args.motions.split(",")
        motions = [m for m in motions if m[0] in wanted]
    elif preset["clips"]:
        motions = quick_subset(motions, preset["clips"])
        places = {m[0]: k for k, m in enumerate(motions)}
    conditions = (CONDITIONS_QUICK if one_each else CONDITIONS_PARITY if args.parity
                  else CONDITIONS_FULL)
    out = Path(args.out).resolve() / args.split
    seq_dir = out / "sequences"
    seeds = noise_seeds(n_seeds, args.first_seed)
    command = "tools/benchmark.py " + shlex.join(argv if argv is not None else sys.argv[1:])

    t0 = time.perf_counter()
    plan = []
    for name, kind, source in motions:
        start = busiest_window(kind, source, seconds)
        plan.append((name, kind, source, start, motion_conditions(name, places, conditions, one_each)))
    total = sum(len(p[4]) for p in plan) * len(seeds)

    def run_group(name, kind, source, start, cond):
        """One motion under one condition: a synth per seed, one eval for the seeds together
        (fewer process starts). Returns the group's sequence records."""
        group = []
        for s_index, seed in enumerate(seeds):
            seq_name = f"{name}_c{conditions.index(cond)}_s{seed}"
            path = seq_dir / seq_name
            synth = synth_command(kind, source, path, start, seconds, cond, seed)
            run_depthtrack(synth)
            group.append((seq_name, path, synth, seed, s_index))
        evaluate = ["depthtrack", "eval", *[shown(g[1]) for g in group], "--methods", ",".join(methods),
                    "--json", "--quiet"]
        facing = facing_from_truth(group[0][1]) if args.facing_from_truth else None
        if facing is not None:
            evaluate += ["--facing", facing]
        if args.settings is not None:
            evaluate += ["--settings", args.settings]
        if args.tracker_preset is not None:
            evaluate += ["--preset", args.tracker_preset]
        if args.keep_tracks:
            evaluate += ["--tracks-out", shown(out / "tracks"), "--force"]
        result = json.loads(run_depthtrack(evaluate))["sequences"]
        records = [{"name": seq_name, "motion": name, "kind": kind, "source": source,
                    "condition": cond, "condition_label": condition_label(cond),
                    "seed": seed, "seed_index": s_index, "start_s": start,
                    "synth_command": shlex.join(synth), "eval_command": shlex.join(evaluate),
                    "facing_given": facing, "placement": synth_placement(path),
                    "metrics": {m: result[seq_name][m] for m in methods}}
                   for seq_name, path, synth, seed, s_index in group]
        if args.keep_tracks:
            for r in records:
                r["timings"] = {m: track_timings(out / "tracks" / r["name"] / m) for m in methods}
        return records

    tasks = [(name, kind, source, start, cond) for name, kind, source, start, conds in plan for cond in conds]
    results, done = {}, 0
    # --jobs groups at once, each in its own processes; the report keeps the plan's order
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        futures = {pool.submit(run_group, *t): k for k, t in enumerate(tasks)}
        for future in concurrent.futures.as_completed(futures):
            results[futures[future]] = records = future.result()
            for r in records:
                done += 1
                print(f"[{done}/{total}] {r['name']}: " + ", ".join(
                    f"{m} {100 * r['metrics'][m]['within_10cm']:.0f}% within 10 cm, "
                    f"{r['metrics'][m]['fps']:.2f} fps ({r['metrics'][m].get('wall_fps') or 0:.2f} with the body fits)"
                    for m in methods), file=sys.stderr, flush=True)
    sequences = [r for k in sorted(results) for r in results[k]]
    groups, overall = aggregate(sequences, methods)
    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=REPO, capture_output=True,
                                text=True).stdout.strip() or "unknown"
    except OSError:
        commit = "unknown"
    report = {
        "format": "depthtrack-benchmark/1", "split": args.split, "preset": preset_name,
        "command": command, "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "machine": f"{os.cpu_count()} CPUs", "renderer": machine_renderer(),
        "software": software_versions(),
        # the parent's kernels; each track's summary.json has its own (the same when pinned)
        "blas": blas_kernels(),
        "commit": commit, "seconds": seconds, "fps": FPS,
        "seeds": seeds, "methods": methods, "wall_s": time.perf_counter() - t0, "jobs": args.jobs,
        "facing_from_truth": bool(args.facing_from_truth),
        "tracker_settings": args.settings,
        "tracker_preset": args.tracker_preset or "default",
        "motions": [{"name": n, "kind": k, "source": s, "start_s": st} for n, k, s, st, _ in plan],
        "conditions": conditions, "sequences": sequences, "groups": groups, "overall": overall,
        "by_condition": by_condition(sequences, methods),
        "time_breakdown": time_breakdown(sequences, methods),
    }
    write_text_atomic(out / "report.json", json.dumps(report, indent=1) + "\n")
    write_text_atomic(out / "report.md", markdown(report))
    print(f"benchmark: {out / 'report.md'}, {out / 'report.json'}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
