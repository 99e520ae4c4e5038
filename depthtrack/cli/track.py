"""``depthtrack track``: fit the body model to every frame of a depth sequence."""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from ..errors import InputError
from .reader_options import add_reader_options, reader_options
from .args import add_force, check_output

_EPILOG = """methods (the ToF paper's experiments):
  hc      model-based hill climbing only
  ep      evidence propagation from part detections only (no hill climbing; a baseline)
  hc+ep   hill climbing, then detections propagated and refined (default)

examples:
  depthtrack track seq_walk -o track_walk
  depthtrack track seq_walk -o track_walk --method hc --likelihood pixel --overlay walk.mp4
  depthtrack track seq_walk -o track_walk --shape-fit off      # keep the template's proportions
  depthtrack track seq_walk -o track_walk --settings '{"heading": {"every": 8}}'
  depthtrack track seq_walk -o track_walk --preset fast   # short clips about twice as fast, a few points less accurate
  depthtrack track seq_walk -o track_walk --facing away   # the person starts with their back to us
  depthtrack track recording.mkv -o track_kinect
  depthtrack track realsense.bag -o track_rs --topic /device_0/sensor_0/Depth_0/image/data

SEQ is any readable recording: a sequence directory or .npz, an Azure Kinect / Femto .mkv,
a ROS 1 .bag, a ROS 2 bag directory, a TUM RGB-D folder (see "reading recordings").
  depthtrack track seq_walk -o track_walk --export glb,c3d,json --smooth savgol:9

OUT gets joints.csv, poses.npz, track.bvh, body.json (the fitted body: height, shape,
segment lengths; depthtrack.BodyModel.from_json reads it) and summary.json (method,
settings, body height and where it came from, the shape fit, timings per stage, frames per
second). The body height is read from sequence.json (subject.height_m), or else fitted to
the first frame with a person by the likelihood (a few seconds). Then the person's
proportions and girth are fitted to four of the first 16 frames, tracked with the
template, and the whole sequence is tracked with the fitted body (--shape-fit off keeps
the template's proportions; see the README, "Body shape"). After the automatic start, the
pose and its twin facing the other way are both tracked for ten frames and the better kept
(a depth image barely tells front from back); when that was a close call, summary.json's
heading_check says "ambiguous": true and the command says so: if the track then faces the
wrong way, --facing camera (or away) tells the tracker which way the person faces at the
start. Frames without a person (an empty room, the subject gone) get no pose; tracking
starts again when someone appears. --export also writes OUT/exports/ (track.glb,
track.c3d, joints.json, ...; see `depthtrack export --help`)."""

OVERLAY_SUFFIXES = (".mp4", ".gif")


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "track", help="track a depth sequence (hill climbing + evidence propagation)",
        description="Track the body through a depth sequence: automatic initialisation on the\n"
                    "first frame, then per frame the MAP pose under the motion prior.",
        epilog=_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("sequence", metavar="SEQ",
                   help="depth sequence directory or .npz, or any readable recording")
    p.add_argument("-o", "--out", required=True, metavar="OUT", help="output track directory")
    p.add_argument("--method", choices=("hc", "ep", "hc+ep"), default="hc+ep",
                   help="search method (default hc+ep)")
    p.add_argument("--likelihood", choices=("smoothed", "pixel"), default="smoothed",
                   help="the paper's smoothed likelihood (default) or the plain pixel-wise one")
    p.add_argument("--overlay", metavar="VIDEO", default=None,
                   help="also write an overlay video of the track (.mp4 or .gif)")
    p.add_argument("--init-from-groundtruth", action="store_true",
                   help="ABLATION ONLY: start from a pose fitted to the ground-truth joints of "
                        "frame 0 instead of the automatic initialisation (recorded in summary.json)")
    p.add_argument("--shape-fit", choices=("on", "off"), default=None,
                   help="on (default): fit the body's shape (segment lengths, widths, girth) to "
                        "the first 16 frames before tracking; off: the template's proportions")
    p.add_argument("--facing", choices=("auto", "camera", "away"), default=None,
                   help="which way the person faces at the start, when you know: camera or away "
                        "(no front/back guess), or auto (default: the tracker decides)")
    p.add_argument("--settings", metavar="JSON", default=None,
                   help="tracker settings, a file or JSON text: an object of setting groups as summary.json's "
                        "\"settings\" holds them (only the fields to change, e.g. "
                        "{\"heading\": {\"every\": 8}}), or a track's summary.json itself")
    add_preset_option(p)
    from .export import add_export_options
    add_export_options(p, "--export", "also write these formats into OUT/exports/: glb, gltf, c3d, json, "
                                      "bvh, csv (comma-separated; see `depthtrack export`)")
    p.add_argument("--quiet", action="store_true", help="no progress or summary output")
    add_reader_options(p)
    add_force(p, "OUT")
    p.set_defaults(func=run)


def _add_overlay(out, overlay, seq, poses, body, summary) -> None:
    """Write the overlay after the (complete) track; only then does summary.json name it.

    A failed overlay leaves the track complete and consistent: its summary.json names
    no overlay, and the one-line error says the track is there.
    """
    from ..evaluate.overlay import write_overlay
    from ..io.atomic import describe_os_error, write_text_atomic
    from ..io.track_output import summary_json_text

    try:
        written = write_overlay(overlay, seq, poses, body)
    except OSError as exc:
        raise InputError(overlay, f"overlay not written ({describe_os_error(exc)}); the track in "
                                  f"{out} is complete") from None
    summary["overlay"] = str(written)
    written_summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    written_summary["overlay"] = str(written)
    write_text_atomic(out / "summary.json", summary_json_text(written_summary))


def add_preset_option(p) -> None:
    """``--preset``: the named starting point of the tracker settings (track and eval)."""
    from ..track.settings import PRESETS

    p.add_argument("--preset", choices=tuple(PRESETS), default=None,
                   help="tracker settings to start from: default (the most accurate) or fast "
                        "(a few points less accurate; a 2-s clip about twice as fast, mostly "
                        "by leaving out the shape fit, each frame 3 to 20 %% faster: no shape "
                        "fit, one search pass, no polish nor final polish, rechecks half as often; README, "
                        "\"Speed\"); --settings, --shape-fit and --facing then change it")


def tracker_settings(args):
    """The tracker settings the options ask for (``--preset``, then ``--settings`` over it,
    then ``--shape-fit`` and ``--facing``)."""
    import dataclasses

    from ..body.shape import read_json_source
    from ..track.settings import preset

    s = preset(getattr(args, "preset", None) or "default")
    given = getattr(args, "settings", None)
    if given is not None:
        data, path = read_json_source(given, "tracker settings")
        if isinstance(data, dict) and isinstance(data.get("settings"), dict):
            data = data["settings"]                     # a track's summary.json
        if not isinstance(data, dict):
            raise InputError(path, "tracker settings must be a JSON object of setting groups")
        try:
            s = s.updated(data)         # groups (fields named), and the flat names summary.json keeps
        except InputError as exc:
            raise InputError(path, exc.problem) from None
    if getattr(args, "shape_fit", None) is not None:
        s = s.replace(shape=dataclasses.replace(s.shape, enabled=args.shape_fit == "on"))
    if getattr(args, "facing", None) is not None:
        s = s.replace(start=dataclasses.replace(s.start, facing=args.facing))
    return s


def run(args) -> int:
    from ..io.sequence import open_sequence
    from ..progress import Progress
    from ..track import run_tracking

    out = Path(args.out)
    check_output(args, "out", inputs=[args.sequence], option="-o")
    overlay = Path(args.overlay) if args.overlay else None
    if overlay is not None and overlay.suffix.lower() not in OVERLAY_SUFFIXES:
        raise InputError(overlay, "overlay must end in .mp4 or .gif")
    if getattr(args, "formats", None):                 # check export options before tracking
        from ..export.registry import parse_formats
        from ..motion.smoothing import parse_smoothing
        parse_formats(args.formats)
        parse_smoothing(args.smooth)
    elif (args.smooth != "none" or args.up != "y") and not args.quiet:
        print("note: --smooth and --up apply to --export files, and no --export was given",
              file=sys.stderr)
    check_output(args, "overlay", inputs=[args.sequence, args.out], kind="file")
    seq = open_sequence(args.sequence, **reader_options(args))
    t0 = time.perf_counter()
    with Progress(len(seq), "frames", quiet=args.quiet) as progress:
        result, body, summary = run_tracking(seq, method=args.method, likelihood=args.likelihood,
                                             init_from_groundtruth=args.init_from_groundtruth,
                                             progress=progress, settings=tracker_settings(args))
    from ..io.track_output import write_track

    summary["sequence"] = str(seq.path)
    write_track(out, result.joints, result.poses, body.pose_names, body, seq.fps, summary)
    if overlay is not None:
        _add_overlay(out, overlay, seq, result.poses, body, summary)
    if getattr(args, "formats", None):
        from .export import export_track_outputs

        exported = export_track_outputs(out / "exports", body, result.poses, result.joints, seq.fps,
                                        args.formats, args.smooth, args.up)
        if not args.quiet:
            print("exports: " + ", ".join(str(p) for p in exported.values()), file=sys.stderr)
    if not args.quiet:
        t = summary["timings"]
        print(f"tracked {len(seq)} frames with {args.method} ({args.likelihood} likelihood) in "
              f"{time.perf_counter() - t0:.1f} s: {t['fps']:.2f} frames/s "
              f"({t['fps_excluding_init']:.2f} after initialisation) -> {out}", file=sys.stderr)
        if overlay is not None:
            print(f"overlay: {summary['overlay']}", file=sys.stderr)
        details = summary.get("initialisation_details") or {}
        check = (details.get("heading_check")
                 or (details.get("trial_start") or {}).get("heading_check") or {})
        if check.get("ambiguous"):
            print(f"note: front or back was a close call at the start (kept the "
                  f"{check['kept']} heading); if the track faces the wrong way, rerun with "
                  f"--facing camera or --facing away", file=sys.stderr)
    return 0
