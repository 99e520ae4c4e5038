"""``depthtrack synth``: synthetic time-of-flight depth sequences with ground truth."""
from __future__ import annotations

import argparse
import time

from ..errors import InputError
from .args import FPS, SEED, SUBJECT_HEIGHT, add_force, check_output, number

_EPILOG = """examples:
  depthtrack synth walk.bvh seq_walk --seconds 1 --camera kinect-v2
  depthtrack synth 126_01.bvh seq_swim --units cmu --fps 30 --start 2 --seconds 10
  depthtrack synth --procedural mixed seq_demo --noise none
  depthtrack synth walk.bvh seq_person3 --shape random --shape-seed 3 --clothing loose
  depthtrack synth --procedural wave seq_me --shape my_shape.json --height 1.82
  depthtrack synth --procedural spin seq_spin --camera azure-nfov --azimuth 135 --camera-height 2.2 --pitch 30
  depthtrack synth take.bvh seq_take --joint-map map.json   # map.json: {"l_shoulder": "L_UpArm", ...}

The output is a sequence directory (or a single .npz when OUT ends in .npz) with
ground-truth joints and Plug-in Gait surface markers; sequence.json records every
setting under "synth" (camera placement, noise parameters, seed, source) and, under
"synth.shape", the subject's build (relative scales, segment lengths in metres, clothing):
ground truth for evaluation, never read by the tracker."""


def register(subparsers) -> None:
    from ..camera import CAMERA_PRESETS
    from ..synth.procedural import PROCEDURAL_MOTIONS

    p = subparsers.add_parser(
        "synth", help="make a synthetic ToF depth sequence from a BVH or a built-in motion",
        description="Render the default body, posed by a BVH motion (retargeted) or a built-in\n"
                    "motion, in a room with a floor and a back wall, add time-of-flight noise,\n"
                    "and write a depth sequence with ground truth.",
        epilog=_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("motion", nargs="?", metavar="MOTION.bvh", help="the BVH motion (not with --procedural)")
    p.add_argument("out", nargs="?", metavar="OUT", help="output sequence directory, or a .npz file")
    p.add_argument("--procedural", metavar="NAME", choices=sorted(PROCEDURAL_MOTIONS),
                   help=f"use a built-in motion instead of a BVH: {', '.join(PROCEDURAL_MOTIONS)}")
    p.add_argument("--fps", type=FPS, default=25.0, help="output frame rate (default 25)")
    p.add_argument("--start", type=number(0, 1e6), default=0.0, metavar="S", help="seconds into the motion to start")
    p.add_argument("--seconds", type=number(0, 86400, lo_open=True), default=None, metavar="T", help="length to render (default: all)")
    p.add_argument("--camera", choices=sorted(CAMERA_PRESETS), default="sr4000",
                   help="camera intrinsics preset (default sr4000, 176 x 144)")
    p.add_argument("--distance", type=number(0, 100, lo_open=True), default=None, metavar="M",
                   help="horizontal camera-subject distance in metres (default: the smallest "
                        "from 2.5 m in 0.25 m steps that keeps the whole body in view and range, "
                        "or for a motion that travels further, the one that sees most of the body)")
    p.add_argument("--azimuth", type=number(-360, 360), default=0.0, metavar="DEG",
                   help="turn the camera about the subject from straight in front (degrees)")
    p.add_argument("--camera-height", type=number(0, 20, lo_open=True), default=None, metavar="M",
                   help="camera height above the floor (default 0.72 x subject height, chest)")
    p.add_argument("--height", type=SUBJECT_HEIGHT, default=None, metavar="M",
                   help="subject height (default 1.75, or the height --shape random draws)")
    p.add_argument("--shape", default="average", metavar="average|random|FILE.json",
                   help="the subject's proportions: average (the default body), random (a "
                        "plausible adult drawn with --shape-seed, height 1.50-2.00 m), or a JSON "
                        "file of relative scales such as {\"thigh\": 1.05, \"torso_girth\": 1.2} "
                        "(fields: depthtrack.body.shape) or a track's body.json")
    p.add_argument("--shape-seed", type=SEED, default=None, metavar="N",
                   help="seed of --shape random and of loose clothing (default 0)")
    p.add_argument("--clothing", choices=("none", "tight", "loose"), default="none",
                   help="clothing over trunk and legs: tight (5 mm) or loose (1-4 cm offset "
                        "surface); default none")
    p.add_argument("--pitch", type=number(-89, 89), default=None, metavar="DEG",
                   help="camera tilt down from horizontal in degrees, negative = up (default: aimed "
                        "at the middle of the body)")
    p.add_argument("--noise", choices=("tof", "none"), default="tof", help="noise model (default tof)")
    p.add_argument("--seed", type=SEED, default=0, help="noise random seed (default 0)")
    p.add_argument("--units", default=None,
                   help="BVH units: metres per unit or cmu, m, cm, mm, inch (default: inferred, reported)")
    p.add_argument("--joint-map", default=None, metavar="MAP.json",
                   help='BVH joints the reader does not recognise by name: a JSON object {"our joint": '
                        '"file joint"} with our joint names (head, neck, pelvis, l_shoulder, l_elbow, '
                        'l_wrist, l_hip, l_knee, l_ankle, r_...); the rest are found as usual')
    p.add_argument("--keep-leading-jump", action="store_true",
                   help="keep the frames a BVH motion teleports out of at its start (by default "
                        "they are dropped: CMU files open with a calibration T-pose)")
    p.add_argument("--quiet", action="store_true", help="no progress or summary output")
    add_force(p, "OUT")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..synth.generate import synthesize_bvh, synthesize_procedural

    paths = [p for p in (args.motion, args.out) if p is not None]
    if args.procedural:
        if len(paths) != 1:
            raise InputError(None, "with --procedural NAME give only OUT")
        out = paths[0]
    else:
        if len(paths) != 2:
            raise InputError(None, "give MOTION.bvh and OUT (or --procedural NAME OUT)")
        motion, out = paths
    args.out = out                                  # ranges were checked by argparse
    check_output(args, "out", inputs=[None if args.procedural else motion], option="OUT",
                 kind="file" if str(out).lower().endswith(".npz") else "dir")
    from ..synth.subject import make_subject

    body, subject = make_subject(args.height, args.shape, args.shape_seed, args.clothing)
    common = dict(fps=args.fps, start=args.start, seconds=args.seconds, camera=args.camera,
                  distance=args.distance, azimuth=args.azimuth, height=body.height,
                  noise=args.noise, seed=args.seed, camera_height=args.camera_height, quiet=args.quiet,
                  body=body, subject=subject, pitch=args.pitch)
    t0 = time.perf_counter()
    if args.procedural:
        synth = synthesize_procedural(args.procedural, out, **common)
    else:
        synth = synthesize_bvh(motion, out, units=args.units, joint_map=args.joint_map,
                               skip_leading_jump=not args.keep_leading_jump, **common)
    if not args.quiet:
        place = synth["placement"]
        source = synth["source"]
        units = f"; BVH units {source['units_source']}" if source.get("kind") == "bvh" else ""
        print(f"wrote {out}: camera {synth['camera_preset']} at {place['distance_m']:.2f} m, "
              f"{place['frames_in_view'] * 100:.0f}% of frames fully in view "
              f"({place['body_visible'] * 100:.0f}% of the body seen), noise "
              f"{synth['noise']['model']}, {time.perf_counter() - t0:.1f} s{units}")
        if source.get("skipped_leading_frames"):
            print(f"dropped the first {source['skipped_leading_frames']} BVH frame(s): "
                  f"{source['skipped_because']} (--keep-leading-jump keeps them)")
    return 0
