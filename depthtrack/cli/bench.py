"""``depthtrack bench``: candidates per second of the tiled GPU likelihood."""
from __future__ import annotations

import argparse
import json

from ..errors import InputError
from .args import integer, number


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "bench", help="measure candidate poses scored per second by the tiled GL renderer",
        description="Score batches of candidate poses of the default body against an observed "
                    "depth frame (skinning, instanced render, smoothed cost, reduction, "
                    "read-back) and print candidates per second per tile size and batch size, "
                    "with the GL renderer in use and the mesh size.",
        epilog="examples:\n  depthtrack bench\n  depthtrack bench --quick --json\n"
               "  depthtrack bench --mesh full --tiles 64 --batches 256 1024\n"
               "  depthtrack bench --mesh coarse --tiles 64 --batches 16 64\n"
               "  depthtrack bench --mesh DIR/body_decimated.glb --tiles 64 --batches 16 64",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--mesh", default="decimated", metavar="MESH",
                   help="body mesh to render: decimated (default, ~1000 triangles, the "
                        "tracker's), coarse (~500), full (~6000), or a skinned .glb of the "
                        "default skeleton (e.g. from tools/make_body_mesh.py --out DIR)")
    p.add_argument("--tiles", type=integer(4, 1024), nargs="+", default=None, metavar="T",
                   help="tile sizes in pixels, powers of two (default 32 64 128)")
    p.add_argument("--batches", type=integer(1, 65536), nargs="+", default=None, metavar="N",
                   help="candidates per call (default 16 64 256 1024)")
    p.add_argument("--pixel", action="store_true",
                   help="time the pixel-wise cost instead of the smoothed likelihood")
    p.add_argument("--seconds", type=number(0, 3600, lo_open=True), default=None, metavar="S",
                   help="timing per cell (default 0.5; 0.1 with --quick)")
    p.add_argument("--quick", action="store_true",
                   help="short run: batches 16 64 256 and 0.1 s per cell")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.add_argument("--quiet", action="store_true", help="no progress meter")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..progress import Progress
    from ..render.benchmark import BATCHES, TILES, benchmark_tiles, format_report

    tiles = tuple(args.tiles or TILES)
    batches = tuple(args.batches or (BATCHES[:3] if args.quick else BATCHES))
    for t in tiles:
        if t < 4 or t > 1024 or t & (t - 1):
            raise InputError(None, f"--tiles: {t} is not a power of two in 4..1024")
    if any(b < 1 for b in batches):
        raise InputError(None, "--batches must be positive")
    seconds = args.seconds if args.seconds is not None else (0.1 if args.quick else 0.5)
    progress = Progress(len(tiles) * len(batches), "cells", quiet=args.quiet or args.json)
    try:
        report = benchmark_tiles(mesh=args.mesh, tiles=tiles, batches=batches, seconds=seconds,
                                 smoothed=not args.pixel, progress=progress)
    finally:
        progress.close()
    print(json.dumps(report, indent=2) if args.json else format_report(report))
    return 0
