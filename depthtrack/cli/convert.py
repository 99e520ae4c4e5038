"""``depthtrack convert``: write any readable recording as a depthtrack sequence."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..errors import InputError
from .args import add_force, check_output
from .reader_options import READER_HELP, add_reader_options, reader_options

_EPILOG = READER_HELP + """

examples:
  depthtrack convert recording.mkv seq_kinect
  depthtrack convert realsense.bag seq_rs --depth-units 0.0001
  depthtrack convert ros2_bag/ seq_ros --topic /camera/depth/image_rect_raw
  depthtrack convert rgbd_dataset_freiburg1_xyz seq_tum
  depthtrack convert my_tum_folder seq_tum --intrinsics 525,525,319.5,239.5
  depthtrack convert seq_dir seq.npz          # directory <-> single file

OUT is a sequence directory (or OUT.npz), written atomically: frames as 16-bit PNGs in the
recording's own units (1 mm for 32FC1 metres), sequence.json with the camera, the frame
rate and a "source" block (reader, input, options, per-frame timestamps)."""


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "convert", help="convert a recording (.mkv, ROS bag, TUM folder, ...) to a depth sequence",
        description="Read a depth recording with the reader its suffix or content calls for, and "
                    "write it as a depthtrack sequence directory (or .npz).",
        epilog=_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("input", metavar="INPUT", help="recording: file or directory")
    p.add_argument("out", metavar="OUT", help="output sequence directory (or .npz file)")
    add_reader_options(p)
    p.add_argument("--quiet", action="store_true", help="no progress or summary output")
    add_force(p, "OUT")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..io.convert import convert_sequence
    from ..io.registry import open_sequence
    from ..progress import Progress

    inp, out = Path(args.input), Path(args.out)
    options = reader_options(args)
    check_output(args, "out", inputs=[inp], option="OUT",
                 kind="file" if out.suffix.lower() == ".npz" else "dir")
    seq = open_sequence(inp, **options)
    with Progress(len(seq), "frames", quiet=args.quiet) as progress:
        convert_sequence(seq, out, options=options, progress=progress)
    if not args.quiet:
        c = seq.camera
        print(f"converted {len(seq)} frames ({c.width} x {c.height}, fx {c.fx:.2f} fy {c.fy:.2f} "
              f"cx {c.cx:.2f} cy {c.cy:.2f}, {seq.fps:g} fps, {seq.depth_scale:g} m per unit) "
              f"read by {getattr(seq, 'reader', '?')} -> {out}", file=sys.stderr)
    return 0
