"""``depthtrack export``: write an existing track in formats other tools read."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..errors import InputError

_EPILOG = """formats (comma-separated; files are written into DIR, default TRACK_DIR/exports):
  glb    track.glb    glTF 2.0 binary: the fitted skinned body and its animation, y up, metres
  gltf   track.gltf   the same as glTF JSON with the buffer embedded
  c3d    track.c3d    39 Plug-in Gait markers of the fitted body and the 15 joints, z up, mm
  json   joints.json  per-frame joints {frame, time, joints {name: [x,y,z] or null}}, camera frame
  bvh    track.bvh    skeleton with a T-pose rest pose, y or z up (--up), metres
  csv    joints.csv   frame,joint,x,y,z, camera frame, metres

Smoothing (--smooth) filters a copy: the files get a "_smoothed" suffix (track_smoothed.glb)
and the track in TRACK_DIR is never changed. Frames without a pose stay unknown where the
format can say so (C3D residual -1, JSON null, CSV rows left out) and hold the last pose in
glTF and BVH animations.

examples:
  depthtrack export track_walk --format glb,c3d,json
  depthtrack export track_walk --format bvh --up z -o for_blender
  depthtrack export track_walk --format glb,c3d --smooth savgol:9"""


def add_export_options(p, formats_flag: str, formats_help: str, formats_default=None) -> None:
    """The options ``export`` and ``track --export`` share: formats, --smooth, --up."""
    from ..motion.smoothing import SMOOTH_HELP

    p.add_argument(formats_flag, dest="formats", metavar="FORMATS", default=formats_default,
                   help=formats_help)
    p.add_argument("--smooth", default="none", metavar="SPEC", help=SMOOTH_HELP)
    p.add_argument("--up", choices=("y", "z"), default="y",
                   help="up axis of the exported BVH (default y; glTF is always y up, C3D z up)")


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "export", help="write a track as glTF/GLB, C3D, JSON, BVH or CSV for other tools",
        description="Export an existing track directory (from `depthtrack track`) without "
                    "tracking again.",
        epilog=_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("track", metavar="TRACK_DIR", help="a track directory (poses.npz, joints.csv, ...)")
    add_export_options(p, "--format", "comma-separated formats: glb, gltf, c3d, json, bvh, csv "
                                      "(default glb,c3d,json)", "glb,c3d,json")
    p.add_argument("-o", "--out", metavar="DIR", default=None,
                   help="directory for the files (default TRACK_DIR/exports)")
    p.add_argument("--quiet", action="store_true", help="print nothing")
    p.set_defaults(func=run)


def export_track_outputs(out_dir, body, poses, joints, fps, formats, smooth="none", up="y") -> dict:
    """Smooth (when asked) and write the exports; returns ``{format: path}``.

    Raw exports take the track's own joints; smoothed ones take joints of the smoothed poses.
    """
    from ..export.registry import parse_formats, write_exports
    from ..motion.smoothing import parse_smoothing, smooth_poses

    formats = parse_formats(formats)
    smoothing = parse_smoothing(smooth)
    if smoothing.active:
        return write_exports(out_dir, body, smooth_poses(poses, smoothing, fps), fps, formats,
                             joints=None, up=up, suffix="_smoothed")
    return write_exports(out_dir, body, poses, fps, formats, joints=joints, up=up)


def run(args) -> int:
    from ..evaluate.runs import body_for_track_dir
    from ..export.registry import parse_formats
    from ..io.track_output import read_track
    from ..motion.smoothing import parse_smoothing

    formats = parse_formats(args.formats)          # check every option before reading anything
    parse_smoothing(args.smooth)
    track = read_track(args.track)
    if track.poses.shape[1] != 48:
        raise InputError(Path(args.track) / "poses.npz", "poses are not of the default body model (48 values)")
    out = Path(args.out) if args.out else Path(args.track) / "exports"
    if out.resolve() == Path(args.track).resolve():
        # the exports' names (track.bvh, joints.csv) are the track's own files
        raise InputError(out, "is the track itself; export into another directory (default TRACK_DIR/exports)")
    if out.exists() and not out.is_dir():
        raise InputError(out, "exists and is not a directory")
    body = body_for_track_dir(args.track, track)      # the fitted shape when the track has body.json
    written = export_track_outputs(out, body, track.poses, track.joints, track.fps, formats,
                                   args.smooth, args.up)
    if not args.quiet:
        for fmt, path in written.items():
            print(f"{fmt}: {path}", file=sys.stderr)
    return 0
