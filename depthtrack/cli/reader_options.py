"""The options that say how to read a recording, shared by ``convert``, ``track`` and ``eval``."""
from __future__ import annotations

READER_HELP = """inputs (chosen by suffix or content; see the README, "Recordings"):
  SEQ/ or SEQ.npz            depthtrack sequence
  REC.mkv                    Azure Kinect / Orbbec Femto recording (DEPTH track, calibration.json)
  REC.bag                    ROS 1 bag, RealSense .bag included (sensor_msgs/Image 16UC1 or 32FC1)
  BAG/                       ROS 2 bag directory (.db3 or .mcap with metadata.yaml)
  TUM/                       TUM RGB-D folder (depth.txt + depth/*.png; needs --intrinsics
                             unless the folder name says freiburg1/2/3)"""


def add_reader_options(parser) -> None:
    """Add --topic, --camera-info, --intrinsics, --depth-units, --fps, --undistort, --reader."""
    g = parser.add_argument_group("reading recordings")
    g.add_argument("--topic", metavar="TOPIC", default=None,
                   help="ROS bags: the depth image topic (needed when the bag has several)")
    g.add_argument("--camera-info", metavar="TOPIC", default=None,
                   help="ROS bags: the CameraInfo topic (default: the one nearest the depth topic)")
    g.add_argument("--intrinsics", metavar="FX,FY,CX,CY|PRESET", default=None,
                   help="camera intrinsics in pixels, or a preset (freiburg1, freiburg2, freiburg3, "
                        "tum-ros-default, sr4000, kinect-v2, azure-nfov); replaces the recorded ones")
    g.add_argument("--depth-units", metavar="M", type=float, default=None,
                   help="metres per raw 16-bit depth unit (default: the recording's, e.g. 0.001 "
                        "for ROS 16UC1 and Azure Kinect, 0.0002 for TUM)")
    g.add_argument("--fps", metavar="F", type=float, default=None,
                   help="frames per second (default: from the recording's timestamps)")
    g.add_argument("--undistort", choices=("auto", "on", "off"), default=None,
                   help=".mkv: resample onto the pinhole camera (auto: wide-FOV modes only)")
    g.add_argument("--reader", metavar="NAME", default=None,
                   help="force a reader by name (azure-kinect-mkv, ros1-bag, ros2-bag, tum-rgbd, "
                        "depthtrack-directory, depthtrack-npz, or a plugin's)")


def reader_options(args) -> dict:
    """The options given on the command line, as ``open_sequence`` keywords (unset ones left out)."""
    undistort = {"auto": "auto", "on": True, "off": False}.get(getattr(args, "undistort", None))
    options = {"topic": args.topic, "camera_info": args.camera_info, "intrinsics": args.intrinsics,
               "depth_units": args.depth_units, "fps": args.fps, "undistort": undistort,
               "reader": args.reader}
    return {k: v for k, v in options.items() if v is not None}
