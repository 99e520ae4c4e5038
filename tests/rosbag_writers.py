"""Write depth frames into ROS 1 / ROS 2 bags with rosbags' writers (test helper)."""
from __future__ import annotations

from pathlib import Path

import numpy as np


#: compressed_depth_image_transport's defaults for 32FC1 (quantisation 100, range 10 m).
QUANT_A, DEPTH_MAX = 100.0, 10.0
QUANT_B = 1.0 - QUANT_A / DEPTH_MAX


def _compressed_depth(typestore, header, data, encoding):
    """A "compressedDepth png" CompressedImage as compressed_depth_image_transport writes it."""
    import struct

    import cv2

    if encoding == "16UC1":
        png_input = data.astype(np.uint16)
    else:  # quantised inverse depth, 0 = no reading
        z = data.astype(np.float64)
        ok = np.isfinite(z) & (z > 0)
        png_input = np.zeros(z.shape, np.uint16)
        png_input[ok] = np.rint(QUANT_A / z[ok] + QUANT_B).astype(np.uint16)
    ok, png = cv2.imencode(".png", png_input)
    assert ok
    payload = struct.pack("<iff", 0, QUANT_A, QUANT_B) + png.tobytes()
    Compressed = typestore.types["sensor_msgs/msg/CompressedImage"]
    return Compressed(header=header, format=f"{encoding}; compressedDepth png",
                      data=np.frombuffer(payload, dtype=np.uint8))


def _messages(typestore, frames, camera, encoding, frame_id="depth_optical_frame", t0_ns=1_700_000_000_000_000_000,
              fps=25.0, compressed=False):
    Image = typestore.types["sensor_msgs/msg/Image"]
    Info = typestore.types["sensor_msgs/msg/CameraInfo"]
    Header = typestore.types["std_msgs/msg/Header"]
    Time = typestore.types["builtin_interfaces/msg/Time"]
    RoI = typestore.types["sensor_msgs/msg/RegionOfInterest"]
    ros1 = "seq" in Header.__dataclass_fields__
    h, w = camera.shape
    for i, frame in enumerate(frames):
        t = t0_ns + int(round(i * 1e9 / fps))
        stamp = Time(sec=t // 1_000_000_000, nanosec=t % 1_000_000_000)
        header = Header(seq=i, stamp=stamp, frame_id=frame_id) if ros1 else Header(stamp=stamp, frame_id=frame_id)
        if encoding == "16UC1":
            data = np.asarray(frame, dtype="<u2")
        else:
            data = np.asarray(frame, dtype="<f4")
        if compressed:
            image = _compressed_depth(typestore, header, data, encoding)
        else:
            image = Image(header=header, height=h, width=w, encoding=encoding, is_bigendian=0,
                          step=w * data.itemsize, data=np.frombuffer(data.tobytes(), dtype=np.uint8))
        k = np.array([camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1], float)
        p = np.array([camera.fx, 0, camera.cx, 0, 0, camera.fy, camera.cy, 0, 0, 0, 1, 0], float)
        fields = dict(header=header, height=h, width=w, distortion_model="plumb_bob",
                      binning_x=0, binning_y=0,
                      roi=RoI(x_offset=0, y_offset=0, height=0, width=0, do_rectify=False))
        if ros1:
            info = Info(D=np.zeros(5), K=k, R=np.eye(3).ravel(), P=p, **fields)
        else:
            info = Info(d=np.zeros(5), k=k, r=np.eye(3).ravel(), p=p, **fields)
        yield t, image, info


def write_ros1_bag(path, frames, camera, encoding="16UC1", topic="/camera/depth/image_raw",
                   info_topic="/camera/depth/camera_info", extra_image_topics=(), compressed=False):
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC)
    with Writer(Path(path)) as writer:
        kind = "sensor_msgs/msg/CompressedImage" if compressed else "sensor_msgs/msg/Image"
        c_img = writer.add_connection(topic, kind, typestore=ts)
        c_info = writer.add_connection(info_topic, "sensor_msgs/msg/CameraInfo", typestore=ts)
        extra = [writer.add_connection(t, "sensor_msgs/msg/Image", typestore=ts) for t in extra_image_topics]
        for t, image, info in _messages(ts, frames, camera, encoding, compressed=compressed):
            writer.write(c_img, t, ts.serialize_ros1(image, kind))
            writer.write(c_info, t, ts.serialize_ros1(info, "sensor_msgs/msg/CameraInfo"))
            for c in extra:
                plain = next(_messages(ts, [frames[0]], camera, encoding))[1]
                writer.write(c, t, ts.serialize_ros1(plain, "sensor_msgs/msg/Image"))
    return Path(path)


def write_ros2_bag(path, frames, camera, encoding="32FC1", topic="/camera/depth/image_rect_raw",
                   info_topic="/camera/depth/camera_info", storage="mcap"):
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(Path(path), version=9, storage_plugin=plugin) as writer:
        c_img = writer.add_connection(topic, "sensor_msgs/msg/Image", typestore=ts)
        c_info = writer.add_connection(info_topic, "sensor_msgs/msg/CameraInfo", typestore=ts)
        for t, image, info in _messages(ts, frames, camera, encoding):
            writer.write(c_img, t, ts.serialize_cdr(image, "sensor_msgs/msg/Image"))
            writer.write(c_info, t, ts.serialize_cdr(info, "sensor_msgs/msg/CameraInfo"))
    return Path(path)
