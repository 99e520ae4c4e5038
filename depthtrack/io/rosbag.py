"""ROS 1 bags (RealSense ``.bag`` files among them) and ROS 2 bags (``.db3`` or ``.mcap``
directories), read with ``rosbags`` (pure Python, no ROS installation).

Depth is a ``sensor_msgs/Image`` topic per REP 118: ``16UC1`` (or ``mono16``) in
millimetres by default, 0 = no reading, or ``32FC1`` in metres, NaN = no reading; or a
``sensor_msgs/CompressedImage`` from ``compressed_depth_image_transport``
(``"16UC1; compressedDepth png"``, or ``32FC1`` as quantised inverse depth; the RVL
variant is refused). The topic is found automatically: of the image topics whose first
message holds depth, the only one; among several, the only one named like depth, then
the only uncompressed one; otherwise ``topic`` names it, and an ambiguous bag is refused
with the candidates listed.

Intrinsics come from the ``sensor_msgs/CameraInfo`` topic that shares the longest path
prefix with the depth topic (RealSense: ``.../Depth_0/image/data`` pairs with
``.../Depth_0/info/camera_info``); ``camera_info`` names it, ``intrinsics`` replaces it.
The camera model's distortion is not applied (ROS depth topics are normally rectified);
it is kept in ``meta["source"]["distortion"]``.

16-bit units: ``depth_units`` when given, else a RealSense bag's recorded ``Depth Units``
option (``/device_0/sensor_*/option/Depth Units/value``), else 1 mm (REP 118).
Timestamps are the bag's record times, in seconds from the first depth message.
"""
from __future__ import annotations

import contextlib
import struct
import tempfile
from pathlib import Path

import numpy as np

from ..camera import Camera
from ..errors import InputError
from .arrays import RecordingSequence
from .registry import Reader, fps_from_timestamps, parse_intrinsics
from .validation import finite_positive as positive

IMAGE = "sensor_msgs/msg/Image"
COMPRESSED = "sensor_msgs/msg/CompressedImage"
CAMERA_INFO = "sensor_msgs/msg/CameraInfo"
#: Image encodings we read as depth, and their numpy types (little-endian; swapped per message).
DEPTH_ENCODINGS = {"16UC1": "<u2", "mono16": "<u2", "32FC1": "<f4"}
_BAG_MAGIC = b"#ROSBAG V2.0"
_MCAP_MAGIC = b"\x89MCAP0\r\n"


@contextlib.contextmanager
def open_bag(path: Path):
    """An open ``rosbags`` AnyReader over the bag at ``path`` (closed on leaving the block)."""
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    named = path
    with contextlib.ExitStack() as stack:
        if path.is_file() and path.suffix.lower() != ".bag":
            # AnyReader tells ROS 1 from ROS 2 by the ".bag" suffix alone; a ROS 1 bag under
            # another name (found by its content) is read through a link that has it.
            tmp = stack.enter_context(tempfile.TemporaryDirectory(prefix="depthtrack-bag-"))
            link = Path(tmp) / "recording.bag"
            link.symlink_to(path.resolve())
            path = link
        try:
            # ROS 2 bags written without message definitions need a default type store.
            reader = AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE))
            stack.enter_context(reader)
        except Exception as exc:  # rosbags raises its own error types for damaged bags
            raise InputError(named, f"cannot read the bag ({exc})") from None
        try:
            yield reader
        except InputError:
            raise
        except Exception as exc:  # a damaged message: rosbags' errors, struct and value errors
            raise InputError(named, f"cannot read the bag ({type(exc).__name__}: {exc})") from None


def _first(reader, connections):
    for conn, _, raw in reader.messages(connections=connections):
        return reader.deserialize(raw, conn.msgtype)
    return None


def _field(msg, *names):
    for n in names:
        if hasattr(msg, n):
            return getattr(msg, n)
    raise AttributeError(names[0])


def depth_encoding(msg):
    """The depth encoding of an Image or compressedDepth CompressedImage message, else None."""
    if hasattr(msg, "encoding"):
        return msg.encoding if msg.encoding in DEPTH_ENCODINGS else None
    fmt = str(getattr(msg, "format", ""))
    encoding = fmt.split(";")[0].strip()
    if "compresseddepth" in fmt.lower() and encoding in ("16UC1", "32FC1"):
        return encoding
    return None


def _decode_compressed_depth(msg) -> np.ndarray:
    # compressed_depth_image_transport: a 12-byte header (int32 format, float32 depthParam[2])
    # then a 16-bit PNG: millimetres for 16UC1; for 32FC1 the quantised inverse depth
    # v = A / z + B, so z = A / (v - B), v = 0 = no reading.
    import cv2

    fmt = str(msg.format)
    if "rvl" in fmt.lower():
        raise ValueError(f"compressedDepth RVL images are not supported ({fmt!r}); republish as png")
    data = np.asarray(msg.data, dtype=np.uint8)
    if data.size <= 12:
        raise ValueError("compressedDepth message too short")
    _, quant_a, quant_b = struct.unpack("<iff", data[:12].tobytes())
    image = cv2.imdecode(data[12:], cv2.IMREAD_UNCHANGED)
    if image is None or image.dtype != np.uint16 or image.ndim != 2:
        raise ValueError("compressedDepth data is not a 16-bit single-channel PNG")
    if fmt.split(";")[0].strip() == "16UC1":
        return image
    with np.errstate(divide="ignore"):
        depth = np.float32(quant_a) / (image.astype(np.float32) - np.float32(quant_b))
    depth[image == 0] = np.nan
    return depth


def image_to_array(msg) -> np.ndarray:
    """(H, W) uint16 raw or float32 metres from a depth ``sensor_msgs/Image`` or a
    ``compressedDepth`` ``sensor_msgs/CompressedImage`` message."""
    if not hasattr(msg, "encoding"):
        return _decode_compressed_depth(msg)
    encoding = msg.encoding
    dtype = np.dtype(DEPTH_ENCODINGS[encoding])
    if msg.is_bigendian:
        dtype = dtype.newbyteorder(">")
    h, w, step = int(msg.height), int(msg.width), int(msg.step)
    data = np.asarray(msg.data, dtype=np.uint8)
    if step < w * dtype.itemsize or data.size < h * step:
        raise ValueError(f"image data holds {data.size} bytes, {h} rows of {step} expected")
    rows = data[:h * step].reshape(h, step)[:, :w * dtype.itemsize]
    frame = np.ascontiguousarray(rows).view(dtype).reshape(h, w)
    return frame.astype(np.uint16 if dtype.kind == "u" else np.float32)


def _common_prefix(a: str, b: str) -> int:
    n = 0
    for x, y in zip(a.strip("/").split("/"), b.strip("/").split("/")):
        if x != y:
            break
        n += 1
    return n


class RosbagSequence(RecordingSequence):
    """Depth frames of one image topic of a ROS 1 or ROS 2 bag (read in batches)."""

    def __init__(self, path, topic, stamps_ns, encoding, camera, fps, depth_scale, meta):
        t = (np.asarray(stamps_ns, dtype=np.int64) - stamps_ns[0]) / 1e9
        super().__init__(path, camera, fps, depth_scale, t, meta)
        self.topic = topic
        self.encoding = encoding
        self._stamps = np.asarray(stamps_ns, dtype=np.int64)

    def _read(self, start, stop):
        # Messages sharing a record time are told apart by their order.
        skip = int(np.count_nonzero(self._stamps[:start] == self._stamps[start]))
        frames = []
        with open_bag(self.path) as reader:
            conns = [c for c in reader.connections if c.topic == self.topic]
            for conn, _, raw in reader.messages(connections=conns, start=int(self._stamps[start]),
                                                stop=int(self._stamps[stop - 1]) + 1):
                if skip:
                    skip -= 1
                    continue
                msg = reader.deserialize(raw, conn.msgtype)
                if depth_encoding(msg) != self.encoding:
                    raise InputError(self.path, f"topic {self.topic} changes encoding from "
                                                f"{self.encoding} at frame {start + len(frames)}")
                frame = image_to_array(msg)
                if frame.shape != self.camera.shape:
                    raise InputError(self.path, f"topic {self.topic}: frame {start + len(frames)} is "
                                                f"{frame.shape[1]} x {frame.shape[0]}, the first is "
                                                f"{self.camera.width} x {self.camera.height}")
                frames.append(frame)
                if len(frames) == stop - start:
                    break
        if len(frames) != stop - start:
            raise InputError(self.path, f"topic {self.topic}: frames {start}..{stop - 1} could not be read back")
        return frames


def _pick_topic(path, reader, images: dict, topic):
    """The depth topic: ``topic``, else the only image topic holding depth; among several,
    the only one named like depth, else the only uncompressed one; else refused."""
    if topic is not None:
        if topic not in images:
            listed = ", ".join(sorted(images)) or "none"
            raise InputError(path, f"no image topic {topic!r} (image topics: {listed})")
        return topic
    if not images:
        raise InputError(path, "no sensor_msgs/Image or CompressedImage topic in the bag")
    depth = []
    for t, conns in images.items():
        msg = _first(reader, conns)
        if msg is not None and depth_encoding(msg) is not None:
            depth.append(t)
    if not depth:
        raise InputError(path, f"no depth image topic (16UC1, 32FC1 or compressedDepth) among "
                               f"{', '.join(sorted(images))}")
    for prefer in (lambda t: "depth" in t.lower(), lambda t: images[t][0].msgtype == IMAGE):
        if len(depth) == 1:
            break
        depth = [t for t in depth if prefer(t)] or depth
    if len(depth) == 1:
        return depth[0]
    raise InputError(path, f"several depth topics, choose one with --topic: {', '.join(sorted(depth))}")


def _pick_camera_info(path, infos: dict, topic, camera_info):
    if camera_info is not None:
        if camera_info not in infos:
            listed = ", ".join(sorted(infos)) or "none"
            raise InputError(path, f"no sensor_msgs/CameraInfo topic {camera_info!r} (camera info topics: {listed})")
        return camera_info
    if not infos:
        return None
    scored = sorted(infos, key=lambda t: -_common_prefix(t, topic))
    best = _common_prefix(scored[0], topic)
    tied = [t for t in scored if _common_prefix(t, topic) == best]
    if len(tied) > 1:
        raise InputError(path, f"several camera info topics fit {topic}, choose one with camera_info= "
                               f"or give --intrinsics: {', '.join(tied)}")
    return scored[0]


def _camera_from_info(path, msg, width, height) -> Camera:
    k = np.asarray(_field(msg, "k", "K"), dtype=float)
    if k.size != 9 or k[0] <= 0 or k[4] <= 0:
        raise InputError(path, "the camera info holds no intrinsics (K is zero): give --intrinsics")
    fx, fy, cx, cy = k[0], k[4], k[2], k[5]
    info_w, info_h = int(msg.width), int(msg.height)
    if info_w and info_h and (info_w, info_h) != (width, height):
        # The camera info describes the full sensor and the image is scaled (binning):
        # the intrinsics scale with it.
        sx, sy = width / info_w, height / info_h
        fx, cx, fy, cy = fx * sx, (cx + 0.5) * sx - 0.5, fy * sy, (cy + 0.5) * sy - 0.5
    return Camera(width=width, height=height, fx=fx, fy=fy, cx=cx, cy=cy)


def _realsense_depth_units(reader, topic):
    """The ``Depth Units`` option a RealSense bag records for the depth sensor, or None."""
    sensor = "/".join(topic.split("/")[:3])  # /device_0/sensor_N
    for conn in reader.connections:
        name = conn.topic
        if name.startswith(sensor + "/option/") and "depth units" in name.lower() and name.endswith("/value"):
            msg = _first(reader, [conn])
            if msg is not None and hasattr(msg, "data") and float(msg.data) > 0:
                return float(msg.data)
    return None


def _stamps(reader, connections) -> np.ndarray:
    """(F,) int64 record times (ns) of the messages on ``connections``, in order."""
    try:
        # ROS 1: the bag's own index has them, so opening does not read every frame.
        times = [entry.time for c in connections for entry in c.owner.indexes[c.id]]
    except (AttributeError, KeyError, TypeError):
        times = [t for _, t, _ in reader.messages(connections=connections)]
    return np.array(sorted(times), dtype=np.int64)


def open_rosbag(path, topic=None, camera_info=None, intrinsics=None, depth_units=None, fps=None):
    """Open the depth topic of a ROS 1 ``.bag`` or a ROS 2 bag directory (module docstring)."""
    path = Path(path)
    if path.is_file() and path.suffix.lower() != ".bag" and not _is_ros1(path, _head(path)):
        if not (path.parent / "metadata.yaml").is_file():
            raise InputError(path, "a ROS 2 bag file is read with its bag directory's metadata.yaml, "
                                   "which is not beside it")
        path = path.parent
    with open_bag(path) as reader:
        images, infos = {}, {}
        for conn in reader.connections:
            if conn.msgtype in (IMAGE, COMPRESSED):
                images.setdefault(conn.topic, []).append(conn)
            elif conn.msgtype == CAMERA_INFO:
                infos.setdefault(conn.topic, []).append(conn)
        topic = _pick_topic(path, reader, images, topic)
        first = _first(reader, images[topic])
        if first is None:
            raise InputError(path, f"topic {topic} has no messages")
        encoding = depth_encoding(first)
        if encoding is None:
            what = getattr(first, "encoding", None) or getattr(first, "format", "?")
            raise InputError(path, f"topic {topic} is {what}, not depth "
                                   f"({', '.join(DEPTH_ENCODINGS)} or compressedDepth)")
        height, width = image_to_array(first).shape
        source = {"format": "rosbag", "input": str(path), "topic": topic, "encoding": encoding,
                  "compressed": not hasattr(first, "encoding"), "frame_id": str(first.header.frame_id)}
        info_topic = _pick_camera_info(path, infos, topic, camera_info)
        if intrinsics is not None:
            camera = parse_intrinsics(intrinsics, width, height, path)
            source["intrinsics_from"] = "given"
        elif info_topic is None:
            raise InputError(path, f"no sensor_msgs/CameraInfo for {topic}: give --intrinsics fx,fy,cx,cy")
        else:
            info = _first(reader, infos[info_topic])
            if info is None:
                raise InputError(path, f"camera info topic {info_topic} has no messages")
            camera = _camera_from_info(path, info, width, height)
            source["camera_info"] = info_topic
            source["distortion_model"] = str(info.distortion_model)
            source["distortion"] = [float(d) for d in _field(info, "d", "D")]
        if encoding == "32FC1":
            if depth_units is not None:
                raise InputError(path, f"topic {topic} is 32FC1 (metres): --depth-units applies to 16-bit depth only")
            scale = 0.001  # the quantum raw_depth and convert use
        elif depth_units is not None:
            scale = positive(depth_units, "depth units", path)
        else:
            scale = _realsense_depth_units(reader, topic) or 0.001
        source["depth_units"] = scale if encoding != "32FC1" else None
        stamps = _stamps(reader, images[topic])
    t = (stamps - stamps[0]) / 1e9
    rate = positive(fps, "fps", path) if fps is not None else fps_from_timestamps(t, 30.0)
    source["start_time"] = float(stamps[0]) / 1e9
    return RosbagSequence(path, topic, stamps, encoding, camera, rate, scale, {"source": source})


def _head(path: Path) -> bytes:
    with open(path, "rb") as f:
        return f.read(len(_BAG_MAGIC))


def _is_ros1(path, head) -> bool:
    return head.startswith(_BAG_MAGIC)


def _is_ros2(path, head) -> bool:
    if path.is_dir():
        return (path / "metadata.yaml").is_file() and any(
            p.suffix in (".db3", ".mcap") for p in path.iterdir())
    # A bare .mcap is claimed too, so that its error says what is missing.
    return head.startswith(_MCAP_MAGIC) or (
        head.startswith(b"SQLite format 3\0") and (path.parent / "metadata.yaml").is_file())


_OPTIONS = ("topic", "camera_info", "intrinsics", "depth_units", "fps")
READERS = {
    "ros1-bag": Reader("ros1-bag", open_rosbag, suffixes=(".bag",), sniff=_is_ros1, options=_OPTIONS,
                       description="ROS 1 .bag (RealSense included), sensor_msgs/Image depth"),
    "ros2-bag": Reader("ros2-bag", open_rosbag, suffixes=(".db3", ".mcap"), sniff=_is_ros2,
                       options=_OPTIONS,
                       description="ROS 2 bag directory (.db3 or .mcap + metadata.yaml)"),
}
