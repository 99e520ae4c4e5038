"""Long-recording check: memory and GL objects stay flat while a long sequence is tracked.

Synthesizes a procedural sequence of ``--frames`` frames (default 10,000) at 25 fps with
time-of-flight noise (the built-in "mixed" motion played forwards and backwards, so it
never jumps), tracks it with ``hc+ep`` as ``depthtrack track`` does, writes the track,
and reports the resident memory (VmRSS) and the number of live moderngl objects every
``--every`` frames. Frames are read from disk one at a time (the directory form loads
lazily), so memory must not grow with the length: the check passes when RSS grows by
less than ``--max-growth-mb`` (default 50) after frame ``--warmup`` (default 100) and
the GL object count is the same at every sample after it.

Per-frame results the tracker keeps (a 48-float pose, 15 joints and a small log entry
per frame) grow by about 1 KB per frame: 10 MB for 10,000 frames, inside the limit.

Usage::

    python tools/long_run.py                       # 10,000 frames (about 40 min at 4 fps here)
    python tools/long_run.py --frames 1000 --json  # the figures reported in the README

Exit status 0 when both checks pass, 1 otherwise.
"""
from __future__ import annotations

import argparse
import gc
import json
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import depthtrack  # noqa: E402,F401  (before numpy: the same OpenBLAS kernels on every machine)
import numpy as np  # noqa: E402


def rss_mb() -> float:
    """Resident set size of this process in MB (Linux /proc)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024.0
    return float("nan")


def live_gl_objects() -> int:
    """moderngl objects alive (not released) in this process."""
    import moderngl

    kinds = tuple(getattr(moderngl, n) for n in ("Buffer", "Texture", "Texture3D", "TextureArray",
                                                  "TextureCube", "Framebuffer", "Renderbuffer",
                                                  "VertexArray", "Program", "ComputeShader", "Query",
                                                  "Sampler", "Scope") if hasattr(moderngl, n))
    count = 0
    for obj in gc.get_objects():
        if isinstance(obj, kinds) and type(getattr(obj, "mglo", None)).__name__ != "InvalidObject":
            count += 1
    return count


class Monitor:
    """Stands in for :class:`depthtrack.progress.Progress`: samples memory and GL objects."""

    def __init__(self, total: int, every: int, quiet: bool):
        self.total, self.every, self.quiet = total, every, quiet
        self.done = 0
        self.samples = []
        self.t0 = time.perf_counter()

    def update(self, n: int = 1) -> None:
        before = self.done
        self.done += n
        if self.done // self.every > before // self.every or self.done == self.total:
            sample = {"frame": self.done, "rss_mb": round(rss_mb(), 1), "gl_objects": live_gl_objects(),
                      "seconds": round(time.perf_counter() - self.t0, 1)}
            self.samples.append(sample)
            if not self.quiet:
                print(f"frame {sample['frame']:6d}  RSS {sample['rss_mb']:7.1f} MB  GL objects "
                      f"{sample['gl_objects']:4d}  {sample['seconds']:7.1f} s", file=sys.stderr, flush=True)


def long_poses(body, frames: int, fps: float) -> np.ndarray:
    """(frames, 48) poses: the "mixed" motion forwards, backwards, forwards... (no jumps)."""
    from depthtrack.synth.procedural import procedural_motion

    once = procedural_motion("mixed", body, fps)
    loop = np.concatenate([once, once[-2:0:-1]])
    reps = -(-frames // len(loop))
    return np.tile(loop, (reps, 1))[:frames]


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                epilog="example: python tools/long_run.py --frames 1000 --json")
    p.add_argument("--frames", type=int, default=10000, help="sequence length (default 10000)")
    p.add_argument("--fps", type=float, default=25.0, help="frame rate (default 25)")
    p.add_argument("--method", default="hc+ep", choices=("hc", "ep", "hc+ep"))
    p.add_argument("--every", type=int, default=100, help="sample every N frames (default 100)")
    p.add_argument("--warmup", type=int, default=100, help="frames before the baseline sample (default 100)")
    p.add_argument("--max-growth-mb", type=float, default=50.0)
    p.add_argument("--workdir", default=None, help="where the sequence goes (default: a temporary directory)")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.add_argument("--quiet", action="store_true")
    args = p.parse_args(argv)
    if args.frames < 2 * args.warmup:
        p.error(f"--frames must be at least {2 * args.warmup}")

    from depthtrack.body import BodyModel
    from depthtrack.io.sequence import open_sequence
    from depthtrack.io.track_output import write_track
    from depthtrack.synth.generate import synthesize
    from depthtrack.track.tracker import run_tracking

    with tempfile.TemporaryDirectory(dir=args.workdir) as work:
        work = Path(work)
        body = BodyModel.default(height=1.75, mesh="full")
        t0 = time.perf_counter()
        synthesize(work / "seq", body, long_poses(body, args.frames, args.fps), args.fps, noise="tof",
                   source={"kind": "procedural", "name": "mixed (looped)"}, quiet=args.quiet)
        synth_s = time.perf_counter() - t0
        seq = open_sequence(work / "seq")
        gc.collect()
        start_rss = rss_mb()
        monitor = Monitor(len(seq), args.every, args.quiet)
        result, tracked_body, summary = run_tracking(seq, method=args.method, progress=monitor)
        write_track(work / "track", result.joints, result.poses, tracked_body.pose_names, tracked_body,
                    seq.fps, summary)
        end_rss = rss_mb()

    after = [s for s in monitor.samples if s["frame"] >= args.warmup]
    base = after[0]
    growth = max(s["rss_mb"] for s in after) - base["rss_mb"]
    gl_counts = sorted({s["gl_objects"] for s in after})
    report = {"frames": args.frames, "fps": args.fps, "method": args.method, "synth_seconds": round(synth_s, 1),
              "tracking_fps": summary["timings"]["fps"], "rss_before_tracking_mb": round(start_rss, 1),
              "rss_at_warmup_mb": base["rss_mb"], "rss_max_after_warmup_mb": max(s["rss_mb"] for s in after),
              "rss_growth_after_warmup_mb": round(growth, 1), "rss_after_writing_mb": round(end_rss, 1),
              "gl_objects_after_warmup": gl_counts, "samples": monitor.samples,
              "memory_flat": growth < args.max_growth_mb, "gl_objects_constant": len(gl_counts) == 1}
    if args.json:
        print(json.dumps(report, indent=1))
    else:
        print(f"{args.frames} frames at {args.fps:g} fps, {args.method}: {report['tracking_fps']:.2f} frames/s; "
              f"RSS {base['rss_mb']:.0f} MB at frame {base['frame']}, growth after it "
              f"{growth:.1f} MB (limit {args.max_growth_mb:g}); live GL objects {gl_counts}")
    return 0 if report["memory_flat"] and report["gl_objects_constant"] else 1


if __name__ == "__main__":
    sys.exit(main())
