"""The end-to-end demo: synthesize, track, evaluate, draw — on the built-in procedural motion.

Nothing outside the package is needed (no mocap files): the sequence is made by
:func:`depthtrack.synth.generate.synthesize_procedural` with the SR4000 camera and the
time-of-flight noise model, then tracked with each requested method through
:mod:`depthtrack.evaluate.runs`, scored against its own ground truth, reported with
plots, drawn as an overlay video, and the candidate renderer is shown by its tile figure.

Output directory (written as a whole, atomically)::

    OUT/wave/            the synthetic depth sequence with ground truth (named after the motion)
    OUT/tiles.png        rendered candidate tiles against an observation
    OUT/track/           the hc+ep track (joints.csv, poses.npz, track.bvh, summary.json)
    OUT/report/          metrics.json, report.md, errors.csv, plots
    OUT/overlay.mp4      depth + fitted silhouette + skeleton, per frame
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..io.atomic import atomic_path

#: The demo's motion, camera, noise and length (seconds at 25 fps).
DEMO_MOTION = "wave"
DEMO_SECONDS = 2.4
DEMO_FPS = 25.0
DEMO_METHODS = ("hc+ep", "hc", "ep")
#: Candidate tiles in the tile figure, and the spread of their perturbation (radians, metres).
TILE_CANDIDATES = 16
TILE_ROTATION_STD = 0.2
TILE_TRANSLATION_STD = 0.05


def perturbed_candidates(pose, n: int, rng, rotation_std: float = TILE_ROTATION_STD,
                         translation_std: float = TILE_TRANSLATION_STD):
    """``(n, D)`` candidates around ``pose (D,)``: the first is ``pose`` itself, the others add
    Gaussian noise to every rotation (radians) and to the root translation (metres)."""
    pose = np.asarray(pose, dtype=np.float64)
    candidates = np.tile(pose, (n, 1))
    noise = rng.normal(0.0, rotation_std, (n - 1, pose.size))
    noise[:, :3] = rng.normal(0.0, translation_std, (n - 1, 3))
    candidates[1:] += noise
    return candidates


def demo_pose(body, fps: float = DEMO_FPS):
    """``(D,)`` a pose of the demo motion (mid-wave, arm up) standing 3 m in front of the camera."""
    from ..synth.procedural import procedural_motion

    motion = procedural_motion("wave", body, fps)
    pose = motion[len(motion) // 4].copy()
    pose[:3] += (0.0, 0.1, 3.0)          # model frame: y down, facing the camera along -z
    return pose


def write_demo_tiles(path, body, camera, rng, wall_m: float = 4.5):
    """The renderer's tile figure: candidates perturbed around :func:`demo_pose`, each rendered
    by :class:`~depthtrack.render.TileRenderer` and scored (smoothed likelihood) against an
    observation rendered from one of them in front of a wall, drawn by
    :func:`depthtrack.render.tiles_figure.write_tiles_figure`.

    Returns
    -------
    observed_index : int
        The candidate the observation was rendered from.
    best_index : int
        The candidate with the lowest cost (the observed one, when the likelihood works).
    """
    from ..render import FrameRenderer, TileRenderer
    from ..render.tiles_figure import write_tiles_figure
    from ..track.observation import square_roi

    candidates = perturbed_candidates(demo_pose(body), TILE_CANDIDATES, rng)
    observed_index = 1 + int(rng.integers(TILE_CANDIDATES - 1))
    frame = FrameRenderer(camera)
    try:
        observation = frame.render(body, candidates[observed_index])
    finally:
        frame.release()
    roi = square_roi(observation > 0, margin=0.15)
    wall = np.full(camera.shape, wall_m, np.float32)
    observation = np.where(observation > 0, observation, wall)
    tiles = TileRenderer(body.with_mesh("decimated"), camera, tile=64)
    try:
        tiles.set_observation(observation, roi=roi, background=wall)
        costs = tiles.costs(candidates, smoothed=True)
        depths = tiles.render_depth(candidates)
        observed = tiles.observed_tile
    finally:
        tiles.release()
    best_index = int(np.argmin(costs))
    write_tiles_figure(path, depths, costs, observed,
                       title=f"{TILE_CANDIDATES} candidates, observation rendered from #{observed_index}")
    return observed_index, best_index


@dataclass
class DemoOutputs:
    """Where the demo put things.

    Attributes
    ----------
    out : Path
        The output directory.
    items : dict {name: (path relative to ``out``, description)}
    notes : list of str
        Anything the user should know (e.g. a GIF instead of an MP4).
    seconds : float
        Wall-clock time of the whole demo.
    """

    out: Path
    items: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)
    seconds: float = 0.0


def run_demo(out_dir, seconds: float = DEMO_SECONDS, methods=DEMO_METHODS, quiet: bool = True,
             log=None) -> DemoOutputs:
    """Run the whole pipeline into ``out_dir`` (replaced as a whole when it succeeds).

    Parameters
    ----------
    out_dir : path-like
    seconds : float
        Length of the synthetic sequence.
    methods : sequence of str
        Tracking methods to evaluate; the first one's track is written and drawn.
    quiet : bool
        No progress meters.
    log : callable(str) or None
        Receives a line as each stage finishes.

    Returns
    -------
    DemoOutputs
    """
    from ..body import BodyModel
    from ..io.sequence import open_sequence
    from ..io.track_output import write_track
    from ..synth.generate import synthesize_procedural
    from .overlay import write_overlay
    from .report import write_report
    from .runs import evaluate

    log = log or (lambda line: None)
    out_dir = Path(out_dir)
    start = time.perf_counter()
    result = DemoOutputs(out_dir)
    rng = np.random.default_rng(2010)
    with atomic_path(out_dir) as tmp:
        tmp = Path(tmp)
        tmp.mkdir()
        seq_dir = tmp / DEMO_MOTION
        synthesize_procedural(DEMO_MOTION, seq_dir, fps=DEMO_FPS, seconds=seconds, camera="sr4000",
                              noise="tof", quiet=True)
        seq = open_sequence(seq_dir)
        body = BodyModel.default(height=seq.subject_height or 1.75)
        result.items["sequence"] = (DEMO_MOTION, f"procedural {DEMO_MOTION!r}, SR4000 176 x 144, ToF "
                                                f"noise, {len(seq)} frames at {seq.fps:g} fps")
        log(f"synthesized {len(seq)} frames ({time.perf_counter() - start:.1f} s)")

        observed, best = write_demo_tiles(tmp / "tiles.png", body, seq.camera, rng)
        result.items["tiles"] = ("tiles.png", f"{TILE_CANDIDATES} perturbed candidates against an "
                                 f"observation rendered from #{observed}; lowest cost: #{best}")
        log(f"tile figure ({time.perf_counter() - start:.1f} s)")

        evaluation = evaluate([seq_dir], methods=methods, quiet=quiet,
                              log=lambda line: log(f"tracked {line}"))
        write_report(evaluation, tmp / "report")
        result.items["report"] = ("report/report.md", "with metrics.json, errors.csv and plots; "
                                  + ", ".join(methods))
        main = evaluation.results[0]
        summary = dict(main.track_summary, sequence=str(out_dir / DEMO_MOTION))
        write_track(tmp / "track", main.joints, main.poses, main.body.pose_names, main.body, seq.fps,
                    summary)
        result.items["track"] = ("track", main.method)
        overlay = write_overlay(tmp / "overlay.mp4", seq, main.poses, main.body)
        result.items["overlay"] = (overlay.name, f"depth, {main.method} silhouette and skeleton")
        if overlay.suffix != ".mp4":
            result.notes.append("this OpenCV cannot encode MP4; the overlay is a GIF")
        log(f"report and overlay ({time.perf_counter() - start:.1f} s)")
    result.seconds = time.perf_counter() - start
    return result


__all__ = ["run_demo", "DemoOutputs", "perturbed_candidates", "write_demo_tiles", "demo_pose",
           "DEMO_MOTION", "DEMO_SECONDS", "DEMO_METHODS"]
